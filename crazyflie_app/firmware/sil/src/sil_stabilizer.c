/* The 1 kHz loop of the firmware, in the order stabilizer.c's stabilizerTask and estimator_kalman.c's
 * kalmanTask run it, around the firmware's own functions: commanderGetSetpoint, supervisorUpdate /
 * supervisorOverrideSetpoint, controllerPid, powerDistribution / powerDistributionCap, and the Kalman core's
 * predict, process noise, flow / ToF / distance updates, finalize, bounds check and externalize.
 *
 * The loop itself is written here because the firmware's versions are FreeRTOS tasks bound to the sensor
 * interrupt and semaphores; what it calls is the firmware. Per tick t: the plant moves 1 ms under the motor
 * ratios set at t-1, the sensors sample it, the stabilizer runs on the estimate the Kalman task externalized
 * at t-1 (as estimatorKalman() copies it), then the Kalman task consumes this tick's measurements. */
#include <string.h>

#include "axis3fSubSampler.h"
#include "commander.h"
#include "controller.h"
#include "crtp_commander_high_level.h"
#define DEBUG_MODULE "STAB"
#include "debug.h"
#include "estimator.h"
#include "controller_pid.h"
#include "kalman_core.h"
#include "kalman_supervisor.h"
#include "log.h"
#include "mm_distance.h"
#include "mm_flow.h"
#include "mm_tof.h"
#include "motors.h"
#include "outlierFilterLighthouse.h"
#include "param.h"
#include "physicalConstants.h"
#include "power_distribution.h"
#include "quatcompress.h"
#include "statsCnt.h"
#include "stabilizer_types.h"
#include "supervisor.h"
#include "supervisor_state_machine.h"

#include "sil_api.h"
#include "sil_plant.h"
#include "sil_sensors.h"
#include "sil_shim.h"

#define TICK_S 0.001
#define PREDICTION_UPDATE_INTERVAL_MS 10
#define ONE_SECOND 1000  /* estimator_kalman.c: its rate counters' averaging interval */  /* estimator_kalman.c: 1000 / PREDICT_RATE */

static sil_config_t config;
static sil_body_t body;
static sil_sensors_t sensors;
static sil_random_t windRng;
static sil_state_t *truthOut;
static sil_state_t *estimateOut;
static sil_status_t *statusOut;
static int64_t currentTick;

/* stabilizer.c */
static stabilizerStep_t stabilizerStep;
static sensorData_t sensorData;
static state_t state;
static setpoint_t setpoint;
static setpoint_t tempSetpoint;  /* the high-level commander's setpoint, before the commander takes it */
static control_t control;
static motors_thrust_uncapped_t motorThrustUncapped;
static motors_thrust_uncapped_t motorThrustBatCompUncapped;
static motors_thrust_pwm_t motorPwm;
static float supplyVoltage;
static StateEstimatorType estimatorType;  /* stabilizer.estimator: what runs (the emulation has Kalman only) */
static ControllerType controllerType;     /* stabilizer.controller: what runs (the emulation has PID only) */
static STATS_CNT_RATE_DEFINE(stabilizerRate, 500);
static uint32_t inToOutLatency;           /* the loop has no sensor interrupt to measure from: 0 */
static void compressState(void);          /* stabilizer.c's, in sil_loop_tables.inc */
static void compressSetpoint(void);

/* estimator_kalman.c */
static kalmanCoreData_t coreData;
static kalmanCoreParams_t coreParams;
static Axis3fSubSampler_t accSubSampler;
static Axis3fSubSampler_t gyroSubSampler;
static Axis3f accLatest;
static Axis3f gyroLatest;
static state_t taskEstimatorState;
static uint32_t nextPredictionMs;
bool resetEstimation;  /* kalman.resetEstimation: the next Kalman step re-initialises the filter */
static bool robustTwr;
static bool robustTdoa;
static OutlierFilterLhState_t sweepOutlierFilterState;  /* no Lighthouse deck here: logged as the firmware's */
static STATS_CNT_RATE_DEFINE(updateCounter, ONE_SECOND);
static STATS_CNT_RATE_DEFINE(predictionCounter, ONE_SECOND);
static STATS_CNT_RATE_DEFINE(finalizeCounter, ONE_SECOND);

/* this tick's measurements, in the order the drivers queued them */
static flowMeasurement_t flowQueued;
static tofMeasurement_t tofQueued;
static distanceMeasurement_t distanceQueued;
static bool flowPending, tofPending, distancePending;

static void estimatorKalmanInit(uint32_t nowMs) {
  axis3fSubSamplerInit(&accSubSampler, GRAVITY_MAGNITUDE);
  axis3fSubSamplerInit(&gyroSubSampler, DEG_TO_RAD);
  kalmanCoreInit(&coreData, &coreParams, nowMs);
  nextPredictionMs = nowMs;
}

static void sampleSensors(uint32_t tick) {
  silSensorsImu(&sensors, &config, &body, &sensorData);
  axis3fSubSamplerAccumulate(&accSubSampler, &sensorData.acc);
  axis3fSubSamplerAccumulate(&gyroSubSampler, &sensorData.gyro);
  accLatest = sensorData.acc;
  gyroLatest = sensorData.gyro;
  flowPending = silSensorsFlow(&sensors, &config, &body, tick, &flowQueued);
  tofPending = silSensorsTof(&sensors, &config, &body, tick, &tofQueued);
  distancePending = false;
  if (config.positioning == SIL_POSITIONING_UWB && tick % SIL_TWR_PERIOD_MS == 0) {
    const int result = silSensorsTwr(&sensors, &config, &body, &distanceQueued);
    distancePending = result > 0;
    statusOut->uwb_rejected += result < 0;
  }
}

/* stabilizer.c controlMotors(), with its batteryCompensation() low-pass on the supply voltage */
static void controlMotors(void) {
  powerDistribution(&control, &motorThrustUncapped);
  supplyVoltage += 0.01f * ((float)body.battery_v - supplyVoltage);
  for (int motor = 0; motor < STABILIZER_NR_OF_MOTORS; motor++) {
    motorThrustBatCompUncapped.list[motor] =
      motorsCompensateBatteryVoltage(motor, motorThrustUncapped.list[motor], supplyVoltage);
  }
  powerDistributionCap(&motorThrustBatCompUncapped, &motorPwm);
  for (int motor = 0; motor < STABILIZER_NR_OF_MOTORS; motor++) {
    motorsSetRatio(motor, motorPwm.list[motor]);
  }
}

/* stabilizer.c updateStateEstimatorAndControllerTypes(), for the one estimator and one controller compiled
 * here: a client asking for another one is told so on the console and the variable reads what runs, as the
 * firmware's does after stateEstimatorSwitchTo() / controllerInit() */
static void updateStateEstimatorAndControllerTypes(void) {
  if (estimatorType != StateEstimatorTypeKalman) {
    DEBUG_PRINT("estimator %d is not in the emulated firmware: the Kalman filter (2) runs\n", (int)estimatorType);
    estimatorType = StateEstimatorTypeKalman;
  }
  if (controllerType != ControllerTypePID) {
    if (controllerType == ControllerTypeAutoSelect) {
      controllerPidInit();  /* auto selects the PID controller, re-initialised as controllerInit() does */
    } else {
      DEBUG_PRINT("controller %d is not in the emulated firmware: the PID controller (1) runs\n", (int)controllerType);
    }
    controllerType = ControllerTypePID;
  }
}

static void stabilizerStepOnce(void) {
  updateStateEstimatorAndControllerTypes();
  state = taskEstimatorState;  /* estimatorKalman(): the state the task externalized last */
  const bool canFly = supervisorCanFly();
  crtpCommanderBlock(!canFly);
  if (canFly && crtpCommanderHighLevelGetSetpoint(&tempSetpoint, &state, stabilizerStep)) {
    commanderSetSetpoint(&tempSetpoint, COMMANDER_PRIORITY_HIGHLEVEL);
  }
  commanderGetSetpoint(&setpoint, &state);
  if (!canFly) {
    memset(&setpoint, 0, sizeof(setpoint));
  }
  supervisorUpdate(&sensorData, &setpoint, stabilizerStep);
  supervisorOverrideSetpoint(&setpoint);
  controllerPid(&control, &setpoint, &sensorData, &state, stabilizerStep);
  if (supervisorAreMotorsAllowedToRun()) {
    controlMotors();
  } else {
    motorsStop();
  }
  compressState();
  compressSetpoint();
  stabilizerStep++;
  STATS_CNT_RATE_EVENT(&stabilizerRate);
}

static void kalmanTaskOnce(uint32_t nowMs) {
  if (resetEstimation) {
    estimatorKalmanInit(nowMs);
    resetEstimation = false;
  }
  const bool quadIsFlying = supervisorIsFlying();
  if (nowMs >= nextPredictionMs) {
    axis3fSubSamplerFinalize(&accSubSampler);
    axis3fSubSamplerFinalize(&gyroSubSampler);
    kalmanCorePredict(&coreData, &coreParams, &accSubSampler.subSample, &gyroSubSampler.subSample, nowMs,
                      quadIsFlying);
    nextPredictionMs = nowMs + PREDICTION_UPDATE_INTERVAL_MS;
    STATS_CNT_RATE_EVENT(&predictionCounter);
  }
  kalmanCoreAddProcessNoise(&coreData, &coreParams, nowMs);
  if (distancePending) {
    kalmanCoreUpdateWithDistance(&coreData, &distanceQueued);
    statusOut->uwb_updates++;
  }
  if (tofPending) {
    kalmanCoreUpdateWithTof(&coreData, &tofQueued);
    statusOut->tof_updates++;
  }
  if (flowPending) {
    kalmanCoreUpdateWithFlow(&coreData, &flowQueued, &gyroLatest);
    statusOut->flow_updates++;
  }
  if (kalmanCoreFinalize(&coreData)) {
    STATS_CNT_RATE_EVENT(&finalizeCounter);
  }
  if (!kalmanSupervisorIsStateWithinBounds(&coreData)) {
    resetEstimation = true;
    statusOut->estimator_resets++;
  }
  kalmanCoreExternalizeState(&coreData, &taskEstimatorState, &accLatest);
  STATS_CNT_RATE_EVENT(&updateCounter);
}

static void publish(uint32_t tick) {
  truthOut->x = body.position[0];
  truthOut->y = body.position[1];
  truthOut->z = body.position[2];
  truthOut->vx = body.velocity[0];
  truthOut->vy = body.velocity[1];
  truthOut->vz = body.velocity[2];
  silPlantEuler(&body, &truthOut->roll, &truthOut->pitch, &truthOut->yaw);
  estimateOut->x = state.position.x;
  estimateOut->y = state.position.y;
  estimateOut->z = state.position.z;
  estimateOut->vx = state.velocity.x;
  estimateOut->vy = state.velocity.y;
  estimateOut->vz = state.velocity.z;
  estimateOut->yaw = state.attitude.yaw;
  estimateOut->roll = state.attitude.roll;
  estimateOut->pitch = state.attitude.pitch;
  statusOut->tick = tick;
  statusOut->console_pending = silShimConsolePending();
  statusOut->supervisor_state = silSupervisorState();
  statusOut->armed = supervisorIsArmed();
  statusOut->crashed = body.crashed;
  statusOut->battery_v = body.battery_v;
  statusOut->thrust_n = 0.0;
  for (int i = 0; i < 4; i++) {
    statusOut->motor_ratio[i] = body.motor_command[i];
    statusOut->thrust_n += body.thrust[i];
  }
}

static void runTick(uint32_t tick) {
  silShimSetTick(tick);
  double ratio[4];
  for (int i = 0; i < 4; i++) {
    ratio[i] = motorsGetRatio(i) / 65535.0;
  }
  silPlantSetMotors(&body, ratio);
  silPlantStep(&body, &config, &windRng, TICK_S);
  sampleSensors(tick);
  stabilizerStepOnce();
  kalmanTaskOnce(tick);
  publish(tick);
}

/* The LOG/PARAM groups of stabilizer.c and estimator_kalman.c, and the compression code their
 * stateEstimateZ / ctrltargetZ groups log, generated from the firmware source by build.py: they name this
 * loop's variables, which carry the firmware's names. */
#include "sil_loop_tables.inc"

/* -- the host interface (sil_api.h) -------------------------------------------------------------------- */

int sil_api_version(void) { return SIL_API_VERSION; }

int sil_state_size(void) { return (int)sizeof(sil_state_t); }

int sil_boot(const sil_config_t *c, sil_state_t *truth, sil_state_t *estimate, sil_status_t *status) {
  config = *c;
  truthOut = truth;
  estimateOut = estimate;
  statusOut = status;
  memset(statusOut, 0, sizeof(*statusOut));
  silShimSetTick(0);
  silPlantInit(&body, &config);
  silSensorsInit(&sensors, &config);
  silRandomInit(&windRng, config.seed, 5);
  stabilizerStep = 1;
  supplyVoltage = (float)config.battery_full_v;
  commanderInit();
  controllerPidInit();
  powerDistributionInit();
  kalmanCoreDefaultParams(&coreParams);
  coreParams.initialX = (float)config.start[0];
  coreParams.initialY = (float)config.start[1];
  coreParams.initialZ = (float)config.start[2];
  coreParams.initialYaw = (float)(config.start_yaw_deg * DEG_TO_RAD);
  estimatorType = StateEstimatorTypeKalman;  /* the Flow deck requires it (estimator selection at boot) */
  controllerType = ControllerTypePID;
  resetEstimation = false;
  estimatorKalmanInit(0);
  kalmanCoreExternalizeState(&coreData, &taskEstimatorState, &accLatest);
  state = taskEstimatorState;
  currentTick = -1;
  publish(0);
  return 0;
}

void sil_advance_to(uint32_t tick) {
  while (currentTick < (int64_t)tick) {
    currentTick++;
    runTick((uint32_t)currentTick);
  }
}

static void toFirmwareSetpoint(const sil_setpoint_t *in, setpoint_t *out) {
  setpoint_t sp;
  memset(&sp, 0, sizeof(sp));
  sp.mode.x = (stab_mode_t)in->mode_x;
  sp.mode.y = (stab_mode_t)in->mode_y;
  sp.mode.z = (stab_mode_t)in->mode_z;
  sp.mode.roll = (stab_mode_t)in->mode_roll;
  sp.mode.pitch = (stab_mode_t)in->mode_pitch;
  sp.mode.yaw = (stab_mode_t)in->mode_yaw;
  sp.position.x = (float)in->position[0];
  sp.position.y = (float)in->position[1];
  sp.position.z = (float)in->position[2];
  sp.velocity.x = (float)in->velocity[0];
  sp.velocity.y = (float)in->velocity[1];
  sp.velocity.z = (float)in->velocity[2];
  sp.attitude.roll = (float)in->attitude[0];
  sp.attitude.pitch = (float)in->attitude[1];
  sp.attitude.yaw = (float)in->attitude[2];
  sp.attitudeRate.roll = (float)in->attitude_rate[0];
  sp.attitudeRate.pitch = (float)in->attitude_rate[1];
  sp.attitudeRate.yaw = (float)in->attitude_rate[2];
  sp.thrust = (float)in->thrust;
  sp.velocity_body = in->velocity_body != 0;
  *out = sp;
}

int sil_commander_set_setpoint(const sil_setpoint_t *in, int priority) {
  setpoint_t sp;
  toFirmwareSetpoint(in, &sp);
  const int accepted = priority >= commanderGetActivePriority();
  commanderSetSetpoint(&sp, priority);
  return accepted;
}

void sil_commander_relax_priority(void) { commanderRelaxPriority(); }

uint32_t sil_commander_get_inactivity_time(void) { return commanderGetInactivityTime(); }

int sil_commander_get_active_priority(void) { return commanderGetActivePriority(); }

int sil_supervisor_request_arming(int do_arm) {
  const int taken = supervisorRequestArming(do_arm != 0);
  statusOut->armed = supervisorIsArmed();
  return taken;
}

int sil_supervisor_info_bitfield(void) { return supervisorGetInfoBitfield(); }

const char *sil_supervisor_state_name(int s) { return supervisorGetStateName((supervisorState_t)s); }

int sil_console_read(char *buffer, int size) {
  const int length = silShimConsoleRead(buffer, size);
  statusOut->console_pending = silShimConsolePending();
  return length;
}

void sil_probe_controller_init(void) {
  controllerPidInit();
  powerDistributionInit();
}

void sil_probe_controller(const sil_setpoint_t *in, const sil_state_t *estimate, const double gyro[3], uint32_t step,
                          double out[8]) {
  setpoint_t sp;
  toFirmwareSetpoint(in, &sp);
  state_t st;
  memset(&st, 0, sizeof(st));
  st.position.x = (float)estimate->x;
  st.position.y = (float)estimate->y;
  st.position.z = (float)estimate->z;
  st.velocity.x = (float)estimate->vx;
  st.velocity.y = (float)estimate->vy;
  st.velocity.z = (float)estimate->vz;
  st.attitude.roll = (float)estimate->roll;
  st.attitude.pitch = (float)estimate->pitch;
  st.attitude.yaw = (float)estimate->yaw;
  sensorData_t sensors;
  memset(&sensors, 0, sizeof(sensors));
  sensors.gyro.x = (float)gyro[0];
  sensors.gyro.y = (float)gyro[1];
  sensors.gyro.z = (float)gyro[2];
  control_t c;
  memset(&c, 0, sizeof(c));
  controllerPid(&c, &sp, &sensors, &st, step);
  motors_thrust_uncapped_t uncapped;
  motors_thrust_pwm_t pwm;
  powerDistribution(&c, &uncapped);
  powerDistributionCap(&uncapped, &pwm);
  out[0] = c.thrust;
  out[1] = c.roll;
  out[2] = c.pitch;
  out[3] = c.yaw;
  for (int i = 0; i < 4; i++) {
    out[4 + i] = pwm.list[i];
  }
}
