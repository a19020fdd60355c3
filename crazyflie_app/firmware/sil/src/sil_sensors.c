#include "sil_sensors.h"

#include <math.h>
#include <string.h>

/* the firmware's sensor constants (the drivers named in sil_sensors.h) */
#define GYRO_LPF_CUTOFF_HZ 80
#define ACC_LPF_CUTOFF_HZ 30
#define IMU_RATE_HZ 1000
#define FLOW_PIXELS 35.0
#define FLOW_THETA_PIX 0.71674       /* 2 sin(42 deg / 2) */
#define FLOW_RESOLUTION 0.10         /* counts are 10x pixels */
#define FLOW_OUTLIER_LIMIT 100       /* flowdeck_v1v2.c OULIER_LIMIT */
#define FLOW_STD_FIXED 2.0f          /* flowdeck_v1v2.c flowStdFixed */
#define FLOW_MIN_HEIGHT_M 0.08       /* below this the sensor is out of focus: no motion flag */
#define TOF_EXP_POINT_A 2.5f         /* zranger2.c noise model */
#define TOF_EXP_STD_A 0.0025f
#define TOF_EXP_POINT_B 4.0f
#define TOF_EXP_STD_B 0.2f
#define TOF_OUTLIER_LIMIT_M 5.0f     /* zranger2.c RANGE_OUTLIER_LIMIT */
#define TOF_OUT_OF_RANGE_M 8.19f     /* what the sensor reports past its range */
#define TWR_STD_M 0.25f              /* lpsTwrTag.c */
#define TWR_OUTLIER_SIGMAS 4.0f
#define QUALITY_NO_MOTION 0.35       /* below this quality frames start to lack the motion flag */

void silSensorsInit(sil_sensors_t *s, const sil_config_t *c) {
  memset(s, 0, sizeof(*s));
  silRandomInit(&s->imu_rng, c->seed, 1);
  silRandomInit(&s->flow_rng, c->seed, 2);
  silRandomInit(&s->tof_rng, c->seed, 3);
  silRandomInit(&s->uwb_rng, c->seed, 4);
  for (int i = 0; i < 3; i++) {
    s->gyro_bias_dps[i] = silRandomGauss(&s->imu_rng, c->gyro_bias_dps);
    s->acc_bias_g[i] = silRandomGauss(&s->imu_rng, c->acc_bias_g);
    lpf2pInit(&s->gyro_lpf[i], IMU_RATE_HZ, GYRO_LPF_CUTOFF_HZ);
    lpf2pInit(&s->acc_lpf[i], IMU_RATE_HZ, ACC_LPF_CUTOFF_HZ);
  }
}

static void toBody(const double r[3][3], const double world[3], double body[3]) {
  for (int i = 0; i < 3; i++) {
    body[i] = r[0][i] * world[0] + r[1][i] * world[1] + r[2][i] * world[2];
  }
}

void silSensorsImu(sil_sensors_t *s, const sil_config_t *c, const sil_body_t *body, sensorData_t *data) {
  double r[3][3];
  silPlantRotation(body, r);
  const double specific_world[3] = {body->acceleration[0], body->acceleration[1],
                                    body->acceleration[2] + SIL_GRAVITY};
  double specific[3];
  toBody(r, specific_world, specific);
  float acc[3], gyro[3];
  for (int i = 0; i < 3; i++) {
    const double acc_g = specific[i] / SIL_GRAVITY + s->acc_bias_g[i] + silRandomGauss(&s->imu_rng, c->acc_noise_g);
    const double rate = body->rates[i] * 180.0 / M_PI + s->gyro_bias_dps[i] +
                        silRandomGauss(&s->imu_rng, c->gyro_noise_dps);
    acc[i] = lpf2pApply(&s->acc_lpf[i], (float)acc_g);
    gyro[i] = lpf2pApply(&s->gyro_lpf[i], (float)rate);
  }
  data->acc.x = acc[0]; data->acc.y = acc[1]; data->acc.z = acc[2];
  data->gyro.x = gyro[0]; data->gyro.y = gyro[1]; data->gyro.z = gyro[2];
}

static double flowQuality(const sil_config_t *c) {
  double light = c->light / 0.3;  /* the shutter compensates down to a third of daylight */
  light = light > 1.0 ? 1.0 : light;
  return c->ground_texture * light;
}

bool silSensorsFlow(sil_sensors_t *s, const sil_config_t *c, const sil_body_t *body, uint32_t tick,
                    flowMeasurement_t *flow) {
  if (tick - s->last_flow_tick < SIL_FLOW_PERIOD_MS) {
    return false;
  }
  const float dt = (float)(tick - s->last_flow_tick) / 1000.0f;
  s->last_flow_tick = tick;
  const double quality = flowQuality(c);
  /* draw every random number of the frame up front, so the stream does not depend on the branch taken */
  const double motion_draw = silRandomUniform(&s->flow_rng);
  const double noise_x = silRandomGauss(&s->flow_rng, 1.0), noise_y = silRandomGauss(&s->flow_rng, 1.0);
  double r[3][3];
  silPlantRotation(body, r);
  const double height = body->position[2];
  if (height < FLOW_MIN_HEIGHT_M || r[2][2] < 0.5) {
    return false;
  }
  if (quality < QUALITY_NO_MOTION && motion_draw > quality / QUALITY_NO_MOTION) {
    return false;
  }
  double velocity[3];
  toBody(r, body->velocity, velocity);
  const double scale = dt * FLOW_PIXELS / FLOW_THETA_PIX / FLOW_RESOLUTION;
  const double under_read = quality >= 0.5 ? 1.0 : 0.5 + quality;
  const double noise = c->flow_noise_px * (1.0 + 3.0 * (1.0 - quality));
  /* the sensor accumulates motion in its delta registers: what a read leaves below a count stays for the next */
  /* the sweeps' drift conditions: a scale error (the pixel angle, the lens, the height the sensor assumes)
   * and a bias per frame */
  const double gain = under_read * scale * c->flow_scale;
  const double counts_x = s->flow_residual[0] + gain * (velocity[0] * r[2][2] / height - body->rates[1])
                          + c->flow_bias_counts + noise * noise_x;
  const double counts_y = s->flow_residual[1] + gain * (velocity[1] * r[2][2] / height + body->rates[0])
                          + c->flow_bias_counts + noise * noise_y;
  const long accpx = lround(counts_x), accpy = lround(counts_y);
  s->flow_residual[0] = counts_x - (double)accpx;
  s->flow_residual[1] = counts_y - (double)accpy;
  if (labs(accpx) >= FLOW_OUTLIER_LIMIT || labs(accpy) >= FLOW_OUTLIER_LIMIT) {
    return false;
  }
  flow->dpixelx = (float)accpx;
  flow->dpixely = (float)accpy;
  flow->stdDevX = FLOW_STD_FIXED;
  flow->stdDevY = FLOW_STD_FIXED;
  flow->dt = dt;
  return true;
}

bool silSensorsTof(sil_sensors_t *s, const sil_config_t *c, const sil_body_t *body, uint32_t tick,
                   tofMeasurement_t *tof) {
  if (tick % SIL_TOF_PERIOD_MS != 0) {
    return false;
  }
  const double noise = silRandomGauss(&s->tof_rng, 1.0);
  double r[3][3];
  silPlantRotation(body, r);
  if (r[2][2] < 0.5) {
    return false;
  }
  double range = body->position[2] / r[2][2];
  range = range > c->tof_max_m ? TOF_OUT_OF_RANGE_M : range + c->tof_noise_m * noise;
  range = range < 0.0 ? 0.0 : range;
  const float distance = (float)(lround(range * 1000.0) / 1000.0);  /* the driver reads whole millimetres */
  if (distance >= TOF_OUTLIER_LIMIT_M) {
    return false;
  }
  const float coefficient = logf(TOF_EXP_STD_B / TOF_EXP_STD_A) / (TOF_EXP_POINT_B - TOF_EXP_POINT_A);
  tof->distance = distance;
  tof->stdDev = TOF_EXP_STD_A * (1.0f + expf(coefficient * (distance - TOF_EXP_POINT_A)));
  tof->timestamp = tick;
  return true;
}

static bool twrFilterAccepts(sil_sensors_t *s, int anchor, float range) {
  float *history = s->twr_history[anchor];
  double mean = 0.0, variance = 0.0;
  for (int i = 0; i < SIL_TWR_HISTORY; i++) {
    mean += history[i];
  }
  mean /= SIL_TWR_HISTORY;
  for (int i = 0; i < SIL_TWR_HISTORY; i++) {
    variance += (history[i] - mean) * (history[i] - mean);
  }
  const double std = sqrt(variance / (SIL_TWR_HISTORY - 1));  /* arm_std_f32: sample std */
  history[s->twr_pointer[anchor]] = range;
  s->twr_pointer[anchor] = (s->twr_pointer[anchor] + 1) % SIL_TWR_HISTORY;
  return fabs(mean - range) < TWR_OUTLIER_SIGMAS * std;
}

int silSensorsTwr(sil_sensors_t *s, const sil_config_t *c, const sil_body_t *body,
                  distanceMeasurement_t *distance) {
  const int anchor = s->next_anchor;
  s->next_anchor = (anchor + 1) % SIL_NR_OF_ANCHORS;
  const double noise = silRandomGauss(&s->uwb_rng, c->uwb_noise_m);
  const double nlos_draw = silRandomUniform(&s->uwb_rng);
  const double nlos_extra = 0.2 + silRandomUniform(&s->uwb_rng) * (c->uwb_nlos_max_m - 0.2);
  const double *a = c->anchors[anchor];
  const double dx = body->position[0] - a[0], dy = body->position[1] - a[1], dz = body->position[2] - a[2];
  double range = sqrt(dx * dx + dy * dy + dz * dz) + noise;
  if (nlos_draw < c->uwb_nlos_probability) {
    range += nlos_extra;
  }
  if (!twrFilterAccepts(s, anchor, (float)range)) {
    return -1;
  }
  distance->distance = (float)range;
  distance->x = (float)a[0];
  distance->y = (float)a[1];
  distance->z = (float)a[2];
  distance->anchorId = (uint8_t)anchor;
  distance->stdDev = TWR_STD_M;
  return 1;
}
