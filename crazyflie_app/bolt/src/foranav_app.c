/*
 * ForaNav flight app for the Crazyflie Bolt: the thin firmware adapter around the pure navigation core
 * (nav_core.c, nav_kalman.c, nav_trees.c, nav_serial.c), the C twin of crazyflie_app/navigation.py.
 *
 * appMain waits for the system, checks the decks (deck.bcFlow2 required, deck.bcLoco advised), resolves the
 * stateEstimate log ids once, waits 3 s, waits for the camera (app.camWaitMs, else NO_CAMERA: never armed),
 * requests arming (the Bolt requires it: CONFIG_MOTORS_REQUIRE_ARMING), then every 10 ms reads the estimate, steps the core and sends its setpoint with
 * commanderSetSetpoint(..., COMMANDER_PRIORITY_EXTRX). The camera task reads the JeVois' text lines from
 * UART2 (115200 baud; the driver's receive buffer holds 200 bytes, so it is drained every 10 ms) and feeds
 * them to the core's line assembler and parser. The two tasks share the core under a mutex.
 *
 * PARAM_GROUP(app) and LOG_GROUP(app) have the names, types and units of the Python app's tables
 * (tests/crazyflie_app/bolt/test_build.py checks it); the console lines are the Python app's (navFormatEvent).
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "FreeRTOS.h"
#include "semphr.h"
#include "task.h"

#include "app.h"
#include "commander.h"
#include "log.h"
#include "param.h"
#include "static_mem.h"
#include "supervisor.h"
#include "uart2.h"

#define DEBUG_MODULE "FORANAV"
#include "debug.h"

#include "foranav_path.h"
#include "nav_core.h"

#define BOOT_DELAY_MS 2000         /* Navigation.c: wait 2 s, then check the decks */
#define PRE_TAKEOFF_DELAY_MS 3000  /* ... and 3 s more before take-off */
#define APP_PERIOD_MS 10           /* the main loop */
#define CAMERA_PERIOD_MS 10        /* UART2 polling: 200 bytes hold 17 ms of 115200 baud */
#define CAMERA_WAIT_POLL_MS 10     /* pre-flight camera check */
#define CAMERA_TASK_PRI 1
#define CAMERA_TASK_STACKSIZE 800 /* words: the frame path (association, events) needs ~2 kB */
#define UART2_BAUDRATE 115200
#define UART_CHUNK 64
#define LOG_VARID_INVALID 0xffffu
#define EVENT_LINE_LENGTH 160

static NavCore core;
static NavCameraInput camera;
static SemaphoreHandle_t coreMutex;
static StaticSemaphore_t coreMutexBuffer;
static logVarId_t estimateIds[6];
static bool estimateReady;
static setpoint_t setpoint;
STATIC_MEM_TASK_ALLOC(foranavCameraTask, CAMERA_TASK_STACKSIZE);

/* PARAM variables (firmware types; copied into the core's double params every tick) */
static struct {
  float altitude;
  float takeoffTol;
  uint16_t takeoffSettle;
  float landHeight;
  float landFinal;
  uint16_t landStep;
  float cruiseSpeed;
  float arrivalSpeed;
  float wpTolerance;
  float lookahead;
  float approachSpeed;
  float servoGain;
  float captureRadius;
  float settleRadius;
  uint16_t settleDwell;
  float settleSpeed;
  float settleRelax;
  uint16_t settleGrace;
  float servoKi;
  float servoKiBand;
  float recoveryDist;
  uint16_t lostTimeout;
  uint32_t recoveryTimeout;
  uint32_t targetTimeout;
  uint16_t linkHoldMs;
  uint16_t linkLandMs;
  uint16_t camWaitMs;
  uint8_t frameCap;
  float recoverySpeed;
  float returnTol;
  float mergeRadius;
  float dupRadius;
  float crownSize;
  float columnFactor;
  uint8_t minHits;
  uint8_t treeCapacity;
  uint16_t visitedCap;
  uint16_t camWidth;
  uint16_t camHeight;
  float camScale;
  float camOffsetX;
  float camOffsetY;
  uint16_t camLatency;
  float kfMeasStd;
  float kfAccelPsd;
} appParams;

static void paramsToCore(NavParams* p) {
  p->altitude_m = (double)appParams.altitude;
  p->takeoff_tolerance_m = (double)appParams.takeoffTol;
  p->takeoff_settle_ms = (int32_t)appParams.takeoffSettle;
  p->land_height_m = (double)appParams.landHeight;
  p->land_final_m = (double)appParams.landFinal;
  p->land_step_ms = (int32_t)appParams.landStep;
  p->cruise_speed = (double)appParams.cruiseSpeed;
  p->arrival_min_speed = (double)appParams.arrivalSpeed;
  p->waypoint_tolerance_m = (double)appParams.wpTolerance;
  p->lookahead_m = (double)appParams.lookahead;
  p->approach_speed = (double)appParams.approachSpeed;
  p->servo_gain = (double)appParams.servoGain;
  p->capture_radius_px = (double)appParams.captureRadius;
  p->settle_radius_px = (double)appParams.settleRadius;
  p->settle_dwell_ms = (int32_t)appParams.settleDwell;
  p->settle_speed = (double)appParams.settleSpeed;
  p->settle_relax = (double)appParams.settleRelax;
  p->settle_grace_ms = (int32_t)appParams.settleGrace;
  p->servo_integral = (double)appParams.servoKi;
  p->servo_integral_band = (double)appParams.servoKiBand;
  p->recovery_distance_m = (double)appParams.recoveryDist;
  p->lost_timeout_ms = (int32_t)appParams.lostTimeout;
  p->recovery_timeout_ms = (int32_t)appParams.recoveryTimeout;
  p->target_timeout_ms = (int32_t)appParams.targetTimeout;
  p->link_hold_ms = (int32_t)appParams.linkHoldMs;
  p->link_land_ms = (int32_t)appParams.linkLandMs;
  p->camera_wait_ms = (int32_t)appParams.camWaitMs;
  p->frame_capacity = (int32_t)appParams.frameCap;
  p->recovery_speed = (double)appParams.recoverySpeed;
  p->return_tolerance_m = (double)appParams.returnTol;
  p->merge_radius_m = (double)appParams.mergeRadius;
  p->duplicate_radius_m = (double)appParams.dupRadius;
  p->crown_size_m = (double)appParams.crownSize;
  p->column_factor = (double)appParams.columnFactor;
  p->min_hits = (int32_t)appParams.minHits;
  p->tree_capacity = (int32_t)appParams.treeCapacity;
  p->visited_capacity = (int32_t)appParams.visitedCap;
  p->cam_width_px = (int32_t)appParams.camWidth;
  p->cam_height_px = (int32_t)appParams.camHeight;
  p->cam_scale = (double)appParams.camScale;
  p->cam_offset_x_m = (double)appParams.camOffsetX;
  p->cam_offset_y_m = (double)appParams.camOffsetY;
  p->cam_latency_ms = (int32_t)appParams.camLatency;
  p->kf_measurement_std_px = (double)appParams.kfMeasStd;
  p->kf_accel_psd = (double)appParams.kfAccelPsd;
}

static void paramsFromCore(const NavParams* p) {
  appParams.altitude = (float)p->altitude_m;
  appParams.takeoffTol = (float)p->takeoff_tolerance_m;
  appParams.takeoffSettle = (uint16_t)p->takeoff_settle_ms;
  appParams.landHeight = (float)p->land_height_m;
  appParams.landFinal = (float)p->land_final_m;
  appParams.landStep = (uint16_t)p->land_step_ms;
  appParams.cruiseSpeed = (float)p->cruise_speed;
  appParams.arrivalSpeed = (float)p->arrival_min_speed;
  appParams.wpTolerance = (float)p->waypoint_tolerance_m;
  appParams.lookahead = (float)p->lookahead_m;
  appParams.approachSpeed = (float)p->approach_speed;
  appParams.servoGain = (float)p->servo_gain;
  appParams.captureRadius = (float)p->capture_radius_px;
  appParams.settleRadius = (float)p->settle_radius_px;
  appParams.settleDwell = (uint16_t)p->settle_dwell_ms;
  appParams.settleSpeed = (float)p->settle_speed;
  appParams.settleRelax = (float)p->settle_relax;
  appParams.settleGrace = (uint16_t)p->settle_grace_ms;
  appParams.servoKi = (float)p->servo_integral;
  appParams.servoKiBand = (float)p->servo_integral_band;
  appParams.recoveryDist = (float)p->recovery_distance_m;
  appParams.lostTimeout = (uint16_t)p->lost_timeout_ms;
  appParams.recoveryTimeout = (uint32_t)p->recovery_timeout_ms;
  appParams.targetTimeout = (uint32_t)p->target_timeout_ms;
  appParams.linkHoldMs = (uint16_t)p->link_hold_ms;
  appParams.linkLandMs = (uint16_t)p->link_land_ms;
  appParams.camWaitMs = (uint16_t)p->camera_wait_ms;
  appParams.frameCap = (uint8_t)p->frame_capacity;
  appParams.recoverySpeed = (float)p->recovery_speed;
  appParams.returnTol = (float)p->return_tolerance_m;
  appParams.mergeRadius = (float)p->merge_radius_m;
  appParams.dupRadius = (float)p->duplicate_radius_m;
  appParams.crownSize = (float)p->crown_size_m;
  appParams.columnFactor = (float)p->column_factor;
  appParams.minHits = (uint8_t)p->min_hits;
  appParams.treeCapacity = (uint8_t)p->tree_capacity;
  appParams.visitedCap = (uint16_t)p->visited_capacity;
  appParams.camWidth = (uint16_t)p->cam_width_px;
  appParams.camHeight = (uint16_t)p->cam_height_px;
  appParams.camScale = (float)p->cam_scale;
  appParams.camOffsetX = (float)p->cam_offset_x_m;
  appParams.camOffsetY = (float)p->cam_offset_y_m;
  appParams.camLatency = (uint16_t)p->cam_latency_ms;
  appParams.kfMeasStd = (float)p->kf_measurement_std_px;
  appParams.kfAccelPsd = (float)p->kf_accel_psd;
}

/* LOG variables, refreshed every tick */
static struct {
  uint8_t phase;
  uint16_t targetId;
  float targetX;
  float targetY;
  float errU;
  float errV;
  uint8_t captured;
  uint8_t numTrees;
  uint16_t numVisited;
  uint8_t waypoint;
  uint16_t reached;
  uint16_t recoveries;
  uint16_t abandoned;
  uint32_t detections;
  uint32_t outOfColumn;
  uint16_t evicted;
  uint16_t unstored;
  uint32_t duplicates;
  uint32_t frameOverflow;
  uint16_t forgotten;
  uint32_t linkDropped;
  uint16_t linkOpens;
  uint8_t linkLost;
  uint16_t linkLosses;
} appLog;

static void setHoverSetpoint(setpoint_t* sp, float vx, float vy, float z, float yaw) {
  sp->mode.x = modeVelocity;
  sp->mode.y = modeVelocity;
  sp->mode.z = modeAbs;
  sp->mode.yaw = modeAbs;
  sp->velocity.x = vx;
  sp->velocity.y = vy;
  sp->position.z = z;
  sp->attitude.yaw = yaw;
  sp->velocity_body = true;
}

static NavPose readPose(void) {
  NavPose p;
  p.x = logGetFloat(estimateIds[0]);
  p.y = logGetFloat(estimateIds[1]);
  p.z = logGetFloat(estimateIds[2]);
  p.yaw_deg = logGetFloat(estimateIds[3]);
  p.vx = logGetFloat(estimateIds[4]);
  p.vy = logGetFloat(estimateIds[5]);
  return p;
}

static void printEvents(void) {
  NavEvent event;
  char line[EVENT_LINE_LENGTH];
  while (navCoreDrainEvents(&core, &event, 1) == 1) {
    navFormatEvent(&event, line, sizeof(line));
    DEBUG_PRINT("%s\n", line);
  }
}

static void refreshLog(void) {
  const NavTree* target = navCoreTarget(&core);
  appLog.phase = (uint8_t)core.phase;
  appLog.targetId = (uint16_t)core.target_id;
  appLog.targetX = target != NULL ? (float)target->x : NAN; /* as the Python app: no target, no position */
  appLog.targetY = target != NULL ? (float)target->y : NAN;
  appLog.errU = (float)core.pixel_error[0];
  appLog.errV = (float)core.pixel_error[1];
  appLog.captured = core.captured ? 1 : 0;
  appLog.numTrees = (uint8_t)core.memory.num_trees;
  appLog.numVisited = (uint16_t)core.memory.num_visited;
  appLog.waypoint = (uint8_t)core.waypoint_index;
  appLog.reached = (uint16_t)core.counters.reached;
  appLog.recoveries = (uint16_t)core.counters.recoveries;
  appLog.abandoned = (uint16_t)core.counters.abandoned;
  appLog.detections = core.counters.detections;
  appLog.outOfColumn = core.counters.out_of_column;
  appLog.evicted = (uint16_t)core.memory.evicted;
  appLog.unstored = (uint16_t)core.memory.unstored;
  appLog.duplicates = core.counters.duplicates;
  appLog.frameOverflow = camera.frame_overflow;
  appLog.forgotten = (uint16_t)core.memory.visited_forgotten;
  appLog.linkDropped = camera.assembler.dropped;
  appLog.linkOpens = 1;
  appLog.linkLost = core.link_lost ? 1 : 0;
  appLog.linkLosses = (uint16_t)core.counters.link_losses;
}

/* The camera task: drain UART2 every 10 ms into the core's camera input. */
static void cameraTask(void* arg) {
  (void)arg;
  uint8_t buffer[UART_CHUNK];
  for (;;) {
    xSemaphoreTake(coreMutex, portMAX_DELAY);
    const int32_t now = (int32_t)xTaskGetTickCount();
    const NavPose pose = estimateReady ? readPose() : (NavPose){0};
    int received;
    /* timeout 1 tick: with 0 the driver returns nothing at all */
    while ((received = uart2GetDataWithTimeout(sizeof(buffer), buffer, M2T(1))) > 0) {
      size_t used = 0;
      while (used < (size_t)received) {
        bool frameDone = false;
        used += navCameraInputFeed(&camera, &core, buffer + used, (size_t)received - used, now, &pose,
                                   estimateReady, &frameDone);
      }
    }
    navCameraInputEndBatch(&camera, &core, now, &pose, estimateReady);
    printEvents();
    xSemaphoreGive(coreMutex);
    vTaskDelay(M2T(CAMERA_PERIOD_MS));
  }
}

void appMain(void) {
  static const double pathXy[] = FORANAV_PATH_XY;
  NavParams params;
  navParamsDefaults(&params);
  params.altitude_m = FORANAV_ALTITUDE_M;
  paramsFromCore(&params);
  if (!navCoreInit(&core, &params, pathXy, FORANAV_PATH_WAYPOINTS)) {
    DEBUG_PRINT("foranav_path.h: 2 to %d waypoints needed, aborting\n", NAV_MAX_WAYPOINTS);
    return;
  }
  navCameraInputInit(&camera, FORANAV_TARGET_LABEL);
  coreMutex = xSemaphoreCreateMutexStatic(&coreMutexBuffer);
  uart2Init(UART2_BAUDRATE);
  STATIC_MEM_TASK_CREATE(foranavCameraTask, cameraTask, "FORANAV_CAM", NULL, CAMERA_TASK_PRI);

  DEBUG_PRINT("ForaNav app started, waiting for the system\n");
  vTaskDelay(M2T(BOOT_DELAY_MS));
  const paramVarId_t flowId = paramGetVarId("deck", "bcFlow2");
  const paramVarId_t locoId = paramGetVarId("deck", "bcLoco");
  if (!PARAM_VARID_IS_VALID(flowId) || !paramGetUint(flowId)) {
    DEBUG_PRINT("No flow deck installed, aborting\n");
    xSemaphoreTake(coreMutex, portMAX_DELAY);
    navCoreAbortNoDeck(&core, (int32_t)xTaskGetTickCount());
    printEvents();
    xSemaphoreGive(coreMutex);
    return; /* the app task parks */
  }
  if (!PARAM_VARID_IS_VALID(locoId) || !paramGetUint(locoId)) {
    DEBUG_PRINT("No Loco deck: flying on Flow dead reckoning, expect drift\n");
  }
  static const char* const names[6] = {"x", "y", "z", "yaw", "vx", "vy"};
  for (int i = 0; i < 6; i++) {
    estimateIds[i] = logGetVarId("stateEstimate", names[i]);
    if (estimateIds[i] == LOG_VARID_INVALID) {
      DEBUG_PRINT("stateEstimate not available, aborting\n");
      return;
    }
  }
  xSemaphoreTake(coreMutex, portMAX_DELAY);
  estimateReady = true;
  xSemaphoreGive(coreMutex);
  vTaskDelay(M2T(PRE_TAKEOFF_DELAY_MS));
  /* a camera never heard is a camera lost: flying the path blind would "complete" nothing */
  for (int32_t waited = 0;; waited += CAMERA_WAIT_POLL_MS) {
    xSemaphoreTake(coreMutex, portMAX_DELAY);
    paramsToCore(&core.params);
    const bool alive = navCameraInputAlive(&camera, &core.params, (int32_t)xTaskGetTickCount());
    const bool give_up = !alive && waited >= core.params.camera_wait_ms;
    if (give_up) {
      char seconds[16];
      navFormatFixed(seconds, sizeof(seconds), (double)core.params.camera_wait_ms / 1000.0, 1);
      DEBUG_PRINT("No camera heard for %s s, not taking off\n", seconds);
      navCoreAbortNoCamera(&core, (int32_t)xTaskGetTickCount());
      printEvents();
    }
    xSemaphoreGive(coreMutex);
    if (alive) {
      break;
    }
    if (give_up) {
      return; /* never armed: the Bolt stays on the ground */
    }
    if (waited == 0) {
      DEBUG_PRINT("Waiting for the camera\n");
    }
    vTaskDelay(M2T(CAMERA_WAIT_POLL_MS));
  }
  /* the last check passed. The Bolt requires arming: until armed, the supervisor replaces every setpoint by
   * the null one */
  if (!supervisorRequestArming(true)) {
    DEBUG_PRINT("Arming refused by the supervisor, aborting\n");
    return;
  }
  DEBUG_PRINT("Armed\n");
  xSemaphoreTake(coreMutex, portMAX_DELAY);
  navCoreStart(&core, (int32_t)xTaskGetTickCount());
  printEvents();
  xSemaphoreGive(coreMutex);
  for (;;) {
    xSemaphoreTake(coreMutex, portMAX_DELAY);
    paramsToCore(&core.params); /* PARAM writes from the client take effect on the next tick */
    const NavPose pose = readPose();
    const NavCommand command = navCoreStep(&core, (int32_t)xTaskGetTickCount(), &pose);
    if (command.kind == NAV_CMD_HOVER) {
      setHoverSetpoint(&setpoint, (float)command.vx, (float)command.vy, (float)command.z, 0.0f);
    } else {
      memset(&setpoint, 0, sizeof(setpoint)); /* null setpoint: motors off */
    }
    commanderSetSetpoint(&setpoint, COMMANDER_PRIORITY_EXTRX);
    refreshLog();
    printEvents();
    xSemaphoreGive(coreMutex);
    vTaskDelay(M2T(APP_PERIOD_MS));
  }
}

PARAM_GROUP_START(app)
/**
 * @brief flight height above ground (paper: 1.25 m) (m)
 */
PARAM_ADD(PARAM_FLOAT, altitude, &appParams.altitude)
/**
 * @brief height error that counts as at altitude (m)
 */
PARAM_ADD(PARAM_FLOAT, takeoffTol, &appParams.takeoffTol)
/**
 * @brief time at altitude before the path starts (ms)
 */
PARAM_ADD(PARAM_UINT16, takeoffSettle, &appParams.takeoffSettle)
/**
 * @brief first landing step height (Navigation.c: 0.5 m) (m)
 */
PARAM_ADD(PARAM_FLOAT, landHeight, &appParams.landHeight)
/**
 * @brief second landing step height (Navigation.c: 0.15 m) (m)
 */
PARAM_ADD(PARAM_FLOAT, landFinal, &appParams.landFinal)
/**
 * @brief duration of each landing step (Navigation.c: 3 s) (ms)
 */
PARAM_ADD(PARAM_UINT16, landStep, &appParams.landStep)
/**
 * @brief speed along the path F (paper: <= 0.1 m/s) (m/s)
 */
PARAM_ADD(PARAM_FLOAT, cruiseSpeed, &appParams.cruiseSpeed)
/**
 * @brief slowest speed of the follow law near a waypoint (it slows down as 1/s x distance) (m/s)
 */
PARAM_ADD(PARAM_FLOAT, arrivalSpeed, &appParams.arrivalSpeed)
/**
 * @brief distance at which a waypoint counts as reached (Navigation.c: 0.03 m) (m)
 */
PARAM_ADD(PARAM_FLOAT, wpTolerance, &appParams.wpTolerance)
/**
 * @brief carrot distance ahead on the path segment (m)
 */
PARAM_ADD(PARAM_FLOAT, lookahead, &appParams.lookahead)
/**
 * @brief visual-servo speed limit (paper: 0.1) (m/s)
 */
PARAM_ADD(PARAM_FLOAT, approachSpeed, &appParams.approachSpeed)
/**
 * @brief visual-servo velocity per metre of image offset (1/s)
 */
PARAM_ADD(PARAM_FLOAT, servoGain, &appParams.servoGain)
/**
 * @brief tau: offset at which the tree counts as nearly centred (paper / Navigation.c: 40 px) (px)
 */
PARAM_ADD(PARAM_FLOAT, captureRadius, &appParams.captureRadius)
/**
 * @brief reached: filtered offset below this (6 px ~ 2.3 cm at 1.25 m) ... (px)
 */
PARAM_ADD(PARAM_FLOAT, settleRadius, &appParams.settleRadius)
/**
 * @brief ... held this long ... (ms)
 */
PARAM_ADD(PARAM_UINT16, settleDwell, &appParams.settleDwell)
/**
 * @brief ... while the MAV is slower than this (m/s)
 */
PARAM_ADD(PARAM_FLOAT, settleSpeed, &appParams.settleSpeed)
/**
 * @brief growth of settleRadius (and settleSpeed) per second captured beyond settleGrace, up to captureRadius (px/s)
 */
PARAM_ADD(PARAM_FLOAT, settleRelax, &appParams.settleRelax)
/**
 * @brief captured time before settleRelax starts (ms)
 */
PARAM_ADD(PARAM_UINT16, settleGrace, &appParams.settleGrace)
/**
 * @brief integral gain of the visual servo, active only when held near but off the centre (wind) (1/s^2)
 */
PARAM_ADD(PARAM_FLOAT, servoKi, &appParams.servoKi)
/**
 * @brief the servo integrates only inside this many settle radii (-)
 */
PARAM_ADD(PARAM_FLOAT, servoKiBand, &appParams.servoKiBand)
/**
 * @brief delta: MAV-to-s_t distance that starts recovery (Navigation.c: 0.7 m) (m)
 */
PARAM_ADD(PARAM_FLOAT, recoveryDist, &appParams.recoveryDist)
/**
 * @brief target unseen this long during the approach: recovery (ms)
 */
PARAM_ADD(PARAM_UINT16, lostTimeout, &appParams.lostTimeout)
/**
 * @brief recovery gives up (tree abandoned) after this long (ms)
 */
PARAM_ADD(PARAM_UINT32, recoveryTimeout, &appParams.recoveryTimeout)
/**
 * @brief a target not reached this long after it was selected is abandoned (ms)
 */
PARAM_ADD(PARAM_UINT32, targetTimeout, &appParams.targetTimeout)
/**
 * @brief camera link silent this long in flight: hold position until frames come back (ms)
 */
PARAM_ADD(PARAM_UINT16, linkHoldMs, &appParams.linkHoldMs)
/**
 * @brief camera link silent this long: land (ms)
 */
PARAM_ADD(PARAM_UINT16, linkLandMs, &appParams.linkLandMs)
/**
 * @brief before take-off: no camera line heard within linkHoldMs for this long -> NO_CAMERA, stay on the ground (0: no check) (ms)
 */
PARAM_ADD(PARAM_UINT16, camWaitMs, &appParams.camWaitMs)
/**
 * @brief detections kept per frame; more before the frame's MARK STOP are dropped (LOG frameOverflow) (-)
 */
PARAM_ADD(PARAM_UINT8, frameCap, &appParams.frameCap)
/**
 * @brief speed when re-approaching s_t (m/s)
 */
PARAM_ADD(PARAM_FLOAT, recoverySpeed, &appParams.recoverySpeed)
/**
 * @brief cross-track error that ends RETURN_TO_PATH (m)
 */
PARAM_ADD(PARAM_FLOAT, returnTol, &appParams.returnTol)
/**
 * @brief detections this close to a stored tree are the same tree (Navigation.c: 0.45 m) (m)
 */
PARAM_ADD(PARAM_FLOAT, mergeRadius, &appParams.mergeRadius)
/**
 * @brief detections of one frame this close are one crown seen twice and merged (trees stand >= a crown apart) (m)
 */
PARAM_ADD(PARAM_FLOAT, dupRadius, &appParams.dupRadius)
/**
 * @brief crown size of a mature tree (planting column) (m)
 */
PARAM_ADD(PARAM_FLOAT, crownSize, &appParams.crownSize)
/**
 * @brief planting column half-width in crown sizes (paper: 1.5) (-)
 */
PARAM_ADD(PARAM_FLOAT, columnFactor, &appParams.columnFactor)
/**
 * @brief detections before a tree may become the target (-)
 */
PARAM_ADD(PARAM_UINT8, minHits, &appParams.minHits)
/**
 * @brief capacity of T_d (overflow evicts, counted) (-)
 */
PARAM_ADD(PARAM_UINT8, treeCapacity, &appParams.treeCapacity)
/**
 * @brief capacity of the visited list (counted) (-)
 */
PARAM_ADD(PARAM_UINT16, visitedCap, &appParams.visitedCap)
/**
 * @brief camera frame width (JeVois 352x288 mode) (px)
 */
PARAM_ADD(PARAM_UINT16, camWidth, &appParams.camWidth)
/**
 * @brief camera frame height (px)
 */
PARAM_ADD(PARAM_UINT16, camHeight, &appParams.camHeight)
/**
 * @brief ground size of a pixel per metre of height at 352 px width (0.0031) (m/px/m)
 */
PARAM_ADD(PARAM_FLOAT, camScale, &appParams.camScale)
/**
 * @brief camera mount, body forward (default 0) (m)
 */
PARAM_ADD(PARAM_FLOAT, camOffsetX, &appParams.camOffsetX)
/**
 * @brief camera mount, body left (default 0) (m)
 */
PARAM_ADD(PARAM_FLOAT, camOffsetY, &appParams.camOffsetY)
/**
 * @brief capture-to-reception latency of a frame (ms)
 */
PARAM_ADD(PARAM_UINT16, camLatency, &appParams.camLatency)
/**
 * @brief Kalman filter: detection noise std (px)
 */
PARAM_ADD(PARAM_FLOAT, kfMeasStd, &appParams.kfMeasStd)
/**
 * @brief Kalman filter: white-acceleration spectral density of the image motion (px^2/s^3)
 */
PARAM_ADD(PARAM_FLOAT, kfAccelPsd, &appParams.kfAccelPsd)
PARAM_GROUP_STOP(app)

LOG_GROUP_START(app)
/**
 * @brief app phase (navigation_core.PHASE_NAMES) (-)
 */
LOG_ADD(LOG_UINT8, phase, &appLog.phase)
/**
 * @brief id of the target tree t* (0: none) (-)
 */
LOG_ADD(LOG_UINT16, targetId, &appLog.targetId)
/**
 * @brief stored position s_t of the target (m)
 */
LOG_ADD(LOG_FLOAT, targetX, &appLog.targetX)
/**
 * @brief stored position s_t of the target (m)
 */
LOG_ADD(LOG_FLOAT, targetY, &appLog.targetY)
/**
 * @brief filtered image offset e_p, column (px)
 */
LOG_ADD(LOG_FLOAT, errU, &appLog.errU)
/**
 * @brief filtered image offset e_p, row (px)
 */
LOG_ADD(LOG_FLOAT, errV, &appLog.errV)
/**
 * @brief 1 while e_p < captureRadius (-)
 */
LOG_ADD(LOG_UINT8, captured, &appLog.captured)
/**
 * @brief trees in T_d (-)
 */
LOG_ADD(LOG_UINT8, numTrees, &appLog.numTrees)
/**
 * @brief entries in the visited list (-)
 */
LOG_ADD(LOG_UINT16, numVisited, &appLog.numVisited)
/**
 * @brief index of the waypoint being flown to (-)
 */
LOG_ADD(LOG_UINT8, waypoint, &appLog.waypoint)
/**
 * @brief trees reached (-)
 */
LOG_ADD(LOG_UINT16, reached, &appLog.reached)
/**
 * @brief recoveries started (-)
 */
LOG_ADD(LOG_UINT16, recoveries, &appLog.recoveries)
/**
 * @brief trees given up after a failed recovery (-)
 */
LOG_ADD(LOG_UINT16, abandoned, &appLog.abandoned)
/**
 * @brief detections received (-)
 */
LOG_ADD(LOG_UINT32, detections, &appLog.detections)
/**
 * @brief detections outside the planting column (-)
 */
LOG_ADD(LOG_UINT32, outOfColumn, &appLog.outOfColumn)
/**
 * @brief trees evicted from a full T_d (-)
 */
LOG_ADD(LOG_UINT16, evicted, &appLog.evicted)
/**
 * @brief new trees not stored: T_d full of trees of the same frame (-)
 */
LOG_ADD(LOG_UINT16, unstored, &appLog.unstored)
/**
 * @brief detections merged with another of the same frame (-)
 */
LOG_ADD(LOG_UINT32, duplicates, &appLog.duplicates)
/**
 * @brief detections dropped beyond frameCap in a frame (-)
 */
LOG_ADD(LOG_UINT32, frameOverflow, &appLog.frameOverflow)
/**
 * @brief visited entries forgotten from a full list (-)
 */
LOG_ADD(LOG_UINT16, forgotten, &appLog.forgotten)
/**
 * @brief serial lines dropped for length (-)
 */
LOG_ADD(LOG_UINT32, linkDropped, &appLog.linkDropped)
/**
 * @brief times the serial port was (re)opened (-)
 */
LOG_ADD(LOG_UINT16, linkOpens, &appLog.linkOpens)
/**
 * @brief 1 while holding position for a silent camera link (-)
 */
LOG_ADD(LOG_UINT8, linkLost, &appLog.linkLost)
/**
 * @brief times the camera link went silent in flight (-)
 */
LOG_ADD(LOG_UINT16, linkLosses, &appLog.linkLosses)
LOG_GROUP_STOP(app)
