/*
 * The parameters' defaults: NavigationParams of crazyflie_app/app/nav_types.py (the app's PARAM table).
 */
#include <string.h>

#include "nav_internal.h"

void navParamsDefaults(NavParams* p) {
  memset(p, 0, sizeof(*p));
  p->altitude_m = 1.25;
  p->takeoff_tolerance_m = 0.05;
  p->takeoff_settle_ms = 1000;
  p->land_height_m = 0.5;
  p->land_final_m = 0.15;
  p->land_step_ms = 3000;
  p->arrival_min_speed = 0.02;
  p->cruise_speed = 0.10;
  p->waypoint_tolerance_m = 0.03;
  p->lookahead_m = 0.15;
  p->approach_speed = 0.10;
  p->servo_gain = 0.8;
  p->capture_radius_px = 40.0;
  p->settle_radius_px = 6.0;
  p->settle_dwell_ms = 600;
  p->settle_speed = 0.02;
  p->settle_relax = 1.0;
  p->settle_grace_ms = 8000;
  p->servo_integral = 0.3;
  p->servo_integral_band = 3.0;
  p->recovery_distance_m = 0.7;
  p->lost_timeout_ms = 1500;
  p->recovery_timeout_ms = 15000;
  p->target_timeout_ms = 60000;
  p->recovery_speed = 0.10;
  p->return_tolerance_m = 0.05;
  p->merge_radius_m = 0.45;
  p->duplicate_radius_m = 0.25;
  p->crown_size_m = 0.35;
  p->column_factor = 1.5;
  p->row_spacing_m = 0.0;
  p->anchor_min_trees = 0;
  p->anchor_gain = 0.5;
  p->min_hits = 2;
  p->tree_capacity = 32;
  p->visited_capacity = 64;
  p->cam_width_px = 352;
  p->cam_height_px = 288;
  p->cam_scale = 0.0031;
  p->cam_offset_x_m = 0.0;
  p->cam_offset_y_m = 0.0;
  p->cam_latency_ms = 50;
  p->kf_measurement_std_px = 3.0;
  p->kf_accel_psd = 400.0;
  p->link_hold_ms = 1000;
  p->link_land_ms = 10000;
  p->camera_wait_ms = 20000;
  p->frame_capacity = 64;
  p->start = 1;
}

/* A client may write any value into a PARAM: camScale and camWidth are taken at the nearest value the model can
 * divide by (nav_types.py: CAM_SCALE_MIN, CAM_WIDTH_MIN_PX), so a write of 0 gives wrong geometry, not inf. */
#define CAM_SCALE_MIN 1e-4
#define CAM_WIDTH_MIN_PX 1

double navFocalPx(const NavParams* p) {
  const double scale = p->cam_scale > CAM_SCALE_MIN ? p->cam_scale : CAM_SCALE_MIN;
  const int32_t width = p->cam_width_px > CAM_WIDTH_MIN_PX ? p->cam_width_px : CAM_WIDTH_MIN_PX;
  return (1.0 / scale) * (double)width / 352.0;
}
