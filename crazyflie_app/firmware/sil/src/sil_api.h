/* The software-in-the-loop Crazyflie: the real firmware's commander, supervisor, PID controller, power
 * distribution and Kalman estimator (compiled from the firmware tarball) flying a rigid-body Bolt-sized
 * quadrotor with IMU, flow deck (PMW3901 + VL53L1x) and Loco deck (UWB TWR) sensor models.
 *
 * This header is the whole interface the host sees (crazyflie_app/firmware/sil/stack.py mirrors it with
 * ctypes). One tick is one millisecond, as configTICK_RATE_HZ on the Crazyflie; sil_advance_to(t) runs
 * the 1 kHz stabilizer loop up to and including tick t. Every random choice comes from config.seed. */
#pragma once
#include <stdint.h>

#define SIL_API_VERSION 1
#define SIL_NR_OF_ANCHORS 8

enum { SIL_POSITIONING_FLOW = 0, SIL_POSITIONING_UWB = 1 };
enum { SIL_CRASH_NONE = 0, SIL_CRASH_TUMBLE = 1, SIL_CRASH_GROUND_HIT = 2 };

typedef struct {
  /* airframe */
  double mass_kg;
  double arm_m;                 /* motor distance from the centre */
  double inertia_kg_m2[3];      /* diagonal: roll, pitch, yaw */
  double thrust_max_n;          /* one motor at full command and the reference voltage */
  double torque_per_thrust_m;   /* yaw reaction torque per newton of thrust */
  double motor_tau_s;           /* first-order motor speed lag */
  double drag_n_per_mps[3];     /* linear drag, world x, y, z */
  double angular_drag_nm_per_radps;
  /* battery (2S LiPo) */
  double battery_full_v;
  double battery_empty_v;
  double battery_capacity_mah;
  double battery_resistance_ohm;
  double reference_v;           /* the voltage thrust_max_n is given at */
  double hover_current_a;       /* current drawn at hover thrust */
  /* IMU (BMI088): white noise and a residual bias after the driver's gyro calibration */
  double gyro_noise_dps;
  double gyro_bias_dps;
  double acc_noise_g;
  double acc_bias_g;
  /* flow deck: PMW3901 and VL53L1x */
  double flow_noise_px;         /* std of the counts, in the sensor's units (10x pixels) */
  double flow_scale;            /* counts reported per count of motion (1: exact; the pixel angle's error) */
  double flow_bias_counts;      /* counts added to each frame's x and y (a bias the Kalman filter integrates) */
  double ground_texture;        /* 1 textured ground .. 0 featureless */
  double light;                 /* 1 daylight .. 0 dark */
  double tof_noise_m;
  double tof_max_m;
  /* Loco deck, two-way ranging */
  int32_t positioning;          /* SIL_POSITIONING_FLOW or _UWB */
  double uwb_noise_m;
  double uwb_nlos_probability;
  double uwb_nlos_max_m;        /* NLOS ranges are long by U(0.2, this) */
  double anchors[SIL_NR_OF_ANCHORS][3];
  /* environment */
  double wind_gust_mps2;        /* std of the gust acceleration (Ornstein-Uhlenbeck) */
  double wind_tau_s;
  /* start */
  double start[3];
  double start_yaw_deg;
  uint64_t seed;
} sil_config_t;

/* What the host reads after each tick (written by the stack into memory the host owns). */
typedef struct {
  double x, y, z;               /* m, world */
  double vx, vy, vz;            /* m/s, world */
  double yaw;                   /* deg, counter-clockwise */
  double roll, pitch;           /* deg, as stateEstimate.roll/pitch (pitch in the firmware's legacy sign) */
} sil_state_t;

typedef struct {
  uint32_t tick;
  int32_t supervisor_state;     /* supervisorState_t */
  int32_t armed;
  int32_t crashed;              /* SIL_CRASH_* */
  double battery_v;
  double motor_ratio[4];        /* 0..1, what the motors were set to */
  double thrust_n;              /* total */
  int32_t estimator_resets;     /* kalman state out of bounds, reset */
  int32_t flow_updates;
  int32_t tof_updates;
  int32_t uwb_updates;
  int32_t uwb_rejected;         /* ranges the TWR outlier filter dropped */
  int32_t console_pending;      /* bytes of console text waiting for sil_console_read */
} sil_status_t;

/* A setpoint in the fields of stabilizer_types.h setpoint_t the app layer uses; modes are stab_mode_t. */
typedef struct {
  int32_t mode_x, mode_y, mode_z, mode_roll, mode_pitch, mode_yaw;
  double position[3];
  double velocity[3];
  double attitude[3];           /* roll, pitch, yaw: deg */
  double attitude_rate[3];      /* deg/s */
  double thrust;
  int32_t velocity_body;
} sil_setpoint_t;

int sil_api_version(void);
int sil_state_size(void);
/* Boot a fresh stack at tick 0 (the MAV on the ground at config->start, motors off, not armed). */
int sil_boot(const sil_config_t *config, sil_state_t *truth, sil_state_t *estimate, sil_status_t *status);
void sil_advance_to(uint32_t tick);
/* commanderSetSetpoint at the current tick; returns 1 when the priority let it in */
int sil_commander_set_setpoint(const sil_setpoint_t *setpoint, int priority);
void sil_commander_relax_priority(void);
uint32_t sil_commander_get_inactivity_time(void);
int sil_commander_get_active_priority(void);
int sil_supervisor_request_arming(int do_arm);
const char *sil_supervisor_state_name(int state);
int sil_supervisor_info_bitfield(void);  /* supervisorGetInfoBitfield() */
/* Copy (and forget) the console text printed since the last call; returns its length. */
int sil_console_read(char *buffer, int size);

/* One call of this build's controllerPid + powerDistribution + powerDistributionCap on the given inputs,
 * outside the loop (on a library that is not booted): the tests compare it with the firmware's own cffirmware
 * bindings. out: thrust, roll, pitch, yaw of control_t, then the four capped motor PWM values. */
void sil_probe_controller_init(void);
void sil_probe_controller(const sil_setpoint_t *setpoint, const sil_state_t *state, const double gyro[3],
                          uint32_t step, double out[8]);
