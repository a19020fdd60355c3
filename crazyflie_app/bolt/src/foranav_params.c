/*
 * The app's PARAM group (PARAM_GROUP(app)): its variables in firmware types, copied into the core's double
 * params every tick (foranavParamsToCore) and set from the core's defaults at start (foranavParamsFromCore).
 * Names, types and units are the Python app's PARAM table (tests/crazyflie_app/bolt/test_c_app.py checks it).
 */
#include <stdint.h>

#include "param.h"

#include "foranav_app.h"

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
  uint8_t start;
  float recoverySpeed;
  float returnTol;
  float mergeRadius;
  float dupRadius;
  float crownSize;
  float columnFactor;
  float rowSpacing;
  uint8_t anchorMin;
  float anchorGain;
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

void foranavParamsToCore(NavParams* p) {
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
  p->start = (int32_t)appParams.start;
  p->recovery_speed = (double)appParams.recoverySpeed;
  p->return_tolerance_m = (double)appParams.returnTol;
  p->merge_radius_m = (double)appParams.mergeRadius;
  p->duplicate_radius_m = (double)appParams.dupRadius;
  p->crown_size_m = (double)appParams.crownSize;
  p->column_factor = (double)appParams.columnFactor;
  p->row_spacing_m = (double)appParams.rowSpacing;
  p->anchor_min_trees = (int32_t)appParams.anchorMin;
  p->anchor_gain = (double)appParams.anchorGain;
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

void foranavParamsFromCore(const NavParams* p) {
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
  appParams.start = (uint8_t)p->start;
  appParams.recoverySpeed = (float)p->recovery_speed;
  appParams.returnTol = (float)p->return_tolerance_m;
  appParams.mergeRadius = (float)p->merge_radius_m;
  appParams.dupRadius = (float)p->duplicate_radius_m;
  appParams.crownSize = (float)p->crown_size_m;
  appParams.columnFactor = (float)p->column_factor;
  appParams.rowSpacing = (float)p->row_spacing_m;
  appParams.anchorMin = (uint8_t)p->anchor_min_trees;
  appParams.anchorGain = (float)p->anchor_gain;
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
 * @brief second landing step: from this height down to the ground (Navigation.c held 0.15 m) (m)
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
 * @brief 0: after its deck checks the app waits on the ground, motors off, until a client writes 1 (then take-off 3 s later); 1 (default): it starts by itself (-)
 */
PARAM_ADD(PARAM_UINT8, start, &appParams.start)
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
 * @brief centre distance of adjacent rows: the column is at most half of it wide (0: not given) (m)
 */
PARAM_ADD(PARAM_FLOAT, rowSpacing, &appParams.rowSpacing)
/**
 * @brief re-anchoring: the row line is corrected at each tree reached from at least this many trees seen (0: off) (-)
 */
PARAM_ADD(PARAM_UINT8, anchorMin, &appParams.anchorMin)
/**
 * @brief re-anchoring: each correction moves the row line this fraction of the way to the trees seen (-)
 */
PARAM_ADD(PARAM_FLOAT, anchorGain, &appParams.anchorGain)
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
