/* Sensor models: what the Bolt's drivers hand the estimator, sampled from the rigid body.
 *
 *   IMU (BMI088)     1 kHz; specific force and body rates + white noise + a residual bias, then the
 *                    driver's second-order low-pass (gyro 80 Hz, acc 30 Hz: sensors_bmi088_bmp3xx.c), with
 *                    the firmware's own lpf2p filter code
 *   PMW3901 flow     100 Hz; counts in the sensor's units (10x pixels, mm_flow.c's FLOW_RESOLUTION) over its
 *                    42 degree field of view and 35 pixels; low texture and low light lower its quality:
 *                    frames without the motion flag, counts that under-read, more noise (flowdeck_v1v2.c
 *                    drops frames without motion and counts past its outlier limit)
 *   VL53L1x ToF      40 Hz (zranger2.c's 25 ms); range limit, noise, the driver's std model
 *   Loco deck TWR    100 Hz round robin over the anchors; Gaussian noise and NLOS ranges that are too long,
 *                    then lpsTwrTag.c's outlier filter (32-range history, 4 sigma)
 */
#pragma once
#include <stdbool.h>

#include "filter.h"
#include "sil_api.h"
#include "sil_plant.h"
#include "sil_random.h"
#include "stabilizer_types.h"

#define SIL_TWR_HISTORY 32

typedef struct {
  sil_random_t imu_rng, flow_rng, tof_rng, uwb_rng;
  double gyro_bias_dps[3];
  double acc_bias_g[3];
  lpf2pData gyro_lpf[3];
  lpf2pData acc_lpf[3];
  uint32_t last_flow_tick;
  double flow_residual[2];      /* motion below one count, kept by the sensor for the next read */
  int next_anchor;
  float twr_history[SIL_NR_OF_ANCHORS][SIL_TWR_HISTORY];
  int twr_count[SIL_NR_OF_ANCHORS];
  int twr_pointer[SIL_NR_OF_ANCHORS];
} sil_sensors_t;

void silSensorsInit(sil_sensors_t *sensors, const sil_config_t *config);
/* The filtered IMU sample of this tick into data->acc (g) and data->gyro (deg/s). */
void silSensorsImu(sil_sensors_t *sensors, const sil_config_t *config, const sil_body_t *body, sensorData_t *data);
bool silSensorsFlow(sil_sensors_t *sensors, const sil_config_t *config, const sil_body_t *body, uint32_t tick,
                    flowMeasurement_t *flow);
bool silSensorsTof(sil_sensors_t *sensors, const sil_config_t *config, const sil_body_t *body, uint32_t tick,
                   tofMeasurement_t *tof);
/* returns 1 with a range that passed the driver's filter, -1 with one it dropped, 0 when none was due */
int silSensorsTwr(sil_sensors_t *sensors, const sil_config_t *config, const sil_body_t *body,
                  distanceMeasurement_t *distance);

#define SIL_FLOW_PERIOD_MS 10
#define SIL_TOF_PERIOD_MS 25
#define SIL_TWR_PERIOD_MS 10
