/*
 * Algorithm 1 as a state machine: the C port of crazyflie_app/navigation_core.py (read its docstring for the
 * design; function names here follow its methods). Phases:
 *
 *   BOOT -> TAKEOFF -> FOLLOW_PATH <-> APPROACH <-> RECOVERY
 *                         ^   |            |            | (timeout: tree abandoned)
 *                         |   v            v reached    v
 *                         RETURN_TO_PATH <------------- +
 *   FOLLOW_PATH (last waypoint) -> LAND -> DONE (null setpoints);  NO_DECK: no Flow deck, aborted
 */
#include <math.h>
#include <string.h>
#ifndef NAV_NO_PRINTF_FLOAT
#include <stdio.h>
#endif

#include "nav_core.h"

static const double DEG_TO_RAD = 3.14159265358979323846 / 180.0; /* CPython math.radians */
static const double INITIAL_VELOCITY_STD = 100.0;                 /* px/s, PixelKalmanFilter default */

static const char* const PHASE_NAMES[] = {"BOOT", "TAKEOFF", "FOLLOW_PATH", "APPROACH", "RECOVERY",
                                          "RETURN_TO_PATH", "LAND", "DONE", "NO_DECK", "NO_CAMERA"};
static const char* const EVENT_NAMES[] = {"phase", "tree_added", "tree_evicted", "target_selected",
                                          "tree_reached", "recovery", "approach_by_memory", "reacquired",
                                          "abandoned", "waypoint", "link_lost", "link_restored", "revisit"};

const char* navPhaseName(int32_t phase) {
  return (phase >= 0 && phase <= NAV_PHASE_NO_CAMERA) ? PHASE_NAMES[phase] : "?";
}

const char* navEventKindName(int32_t kind) {
  return (kind >= 0 && kind < NAV_EVENT_KIND_COUNT) ? EVENT_NAMES[kind] : "?";
}

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
}

double navFocalPx(const NavParams* p) {
  return (1.0 / p->cam_scale) * (double)p->cam_width_px / 352.0;
}

static double maxd(double a, double b) { return a > b ? a : b; }
static double mind(double a, double b) { return a < b ? a : b; }

/* -- geometry ------------------------------------------------------------------------------------------- */

static void rotate(double yaw_deg, double bx, double by, double* wx, double* wy) { /* body -> world */
  const double c = cos(yaw_deg * DEG_TO_RAD), s = sin(yaw_deg * DEG_TO_RAD);
  *wx = bx * c - by * s;
  *wy = bx * s + by * c;
}

static void unrotate(double yaw_deg, double wx, double wy, double* bx, double* by) { /* world -> body */
  const double c = cos(yaw_deg * DEG_TO_RAD), s = sin(yaw_deg * DEG_TO_RAD);
  *bx = wx * c + wy * s;
  *by = -wx * s + wy * c;
}

static double distanceToSegment(double px, double py, const double a[2], const double b[2]) {
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  const double length2 = dx * dx + dy * dy;
  const double t = length2 == 0.0 ? 0.0 : maxd(0.0, mind(1.0, ((px - a[0]) * dx + (py - a[1]) * dy) / length2));
  return hypot(px - a[0] - t * dx, py - a[1] - t * dy);
}

static void servoVelocity(double offset_fwd_m, double offset_left_m, double gain, double max_speed,
                          const double integral[2], double integral_gain, double* vx, double* vy) {
  *vx = gain * offset_fwd_m + integral_gain * integral[0];
  *vy = gain * offset_left_m + integral_gain * integral[1];
  const double speed = hypot(*vx, *vy);
  if (speed > max_speed && max_speed > 0.0) {
    *vx = *vx * max_speed / speed;
    *vy = *vy * max_speed / speed;
  }
}

static void cameraGroundPoint(const NavCore* core, const NavPose* pose, double* x, double* y) {
  double ox, oy;
  rotate(pose->yaw_deg, core->params.cam_offset_x_m, core->params.cam_offset_y_m, &ox, &oy);
  *x = pose->x + ox;
  *y = pose->y + oy;
}

static void pixelToWorld(const NavCore* core, double u, double v, const NavPose* pose, double* x, double* y) {
  const NavParams* p = &core->params;
  const double scale = maxd(pose->z, 0.05) / navFocalPx(p);
  const double fwd = ((double)p->cam_height_px / 2.0 - v) * scale, left = ((double)p->cam_width_px / 2.0 - u) * scale;
  double wx, wy, cx, cy;
  rotate(pose->yaw_deg, fwd, left, &wx, &wy);
  cameraGroundPoint(core, pose, &cx, &cy);
  *x = cx + wx;
  *y = cy + wy;
}

static void currentSegment(const NavCore* core, const double** a, const double** b) {
  int32_t k = core->waypoint_index > 1 ? core->waypoint_index : 1;
  k = k < core->path_length - 1 ? k : core->path_length - 1;
  *a = core->path[k - 1];
  *b = core->path[k];
}

static bool inPlantingColumn(const NavCore* core, double x, double y) {
  const double *a, *b;
  currentSegment(core, &a, &b);
  return distanceToSegment(x, y, a, b) <= core->params.column_factor * core->params.crown_size_m;
}

/* The newest recorded pose not later than t_ms (the oldest kept one if none); NULL if none recorded. */
static const NavPose* poseAt(const NavCore* core, int32_t t_ms) {
  const NavPose* best = NULL;
  for (int32_t n = 0; n < core->poses_count; n++) {
    const int32_t index = (core->poses_head - 1 - n + NAV_POSE_HISTORY) % NAV_POSE_HISTORY;
    best = &core->poses[index].pose;
    if (core->poses[index].t_ms <= t_ms) {
      break;
    }
  }
  return best;
}

static void recordPose(NavCore* core, int32_t t_ms, const NavPose* pose) {
  core->poses[core->poses_head].t_ms = t_ms;
  core->poses[core->poses_head].pose = *pose;
  core->poses_head = (core->poses_head + 1) % NAV_POSE_HISTORY;
  if (core->poses_count < NAV_POSE_HISTORY) {
    core->poses_count++;
  }
}

/* -- events and phases ---------------------------------------------------------------------------------- */

static NavEvent* pushEvent(NavCore* core, NavEventKind kind, int32_t t_ms, int32_t tree_id, double x, double y) {
  if (core->num_events >= NAV_MAX_EVENTS) {
    core->events_dropped++;
    return NULL;
  }
  NavEvent* e = &core->events[core->num_events++];
  e->kind = kind;
  e->t_ms = t_ms;
  e->tree_id = tree_id;
  e->x = x;
  e->y = y;
  e->a = e->b = 0.0;
  e->n = e->variant = 0;
  return e;
}

static void enterPhase(NavCore* core, NavPhase phase, int32_t t_ms) {
  if (phase != core->phase) {
    core->phase = phase;
    core->phase_since = t_ms;
    NavEvent* e = pushEvent(core, NAV_EVENT_PHASE, t_ms, core->target_id, 0.0, 0.0);
    if (e != NULL) {
      e->n = (int32_t)phase;
    }
  }
}

static NavCommand hover(const NavCore* core, double vx, double vy) {
  NavCommand c = {NAV_CMD_HOVER, vx, vy, core->params.altitude_m};
  return c;
}

static NavCommand nullCommand(void) {
  NavCommand c = {NAV_CMD_NULL, 0.0, 0.0, 0.0};
  return c;
}

static void dropTarget(NavCore* core) {
  core->target_id = 0;
  core->has_filter = false;
  core->captured = false;
}

/* -- init ----------------------------------------------------------------------------------------------- */

bool navCoreInit(NavCore* core, const NavParams* params, const double* xy, int32_t waypoints) {
  memset(core, 0, sizeof(*core));
  if (waypoints < 2 || waypoints > NAV_MAX_WAYPOINTS) {
    return false;
  }
  core->params = *params;
  for (int32_t i = 0; i < waypoints; i++) {
    core->path[i][0] = xy[2 * i];
    core->path[i][1] = xy[2 * i + 1];
  }
  core->path_length = waypoints;
  navTreesInit(&core->memory, params->tree_capacity, params->visited_capacity);
  core->phase = NAV_PHASE_BOOT;
  return true;
}

void navCoreStart(NavCore* core, int32_t t_ms) { enterPhase(core, NAV_PHASE_TAKEOFF, t_ms); }

void navCoreAbortNoDeck(NavCore* core, int32_t t_ms) { enterPhase(core, NAV_PHASE_NO_DECK, t_ms); }

void navCoreAbortNoCamera(NavCore* core, int32_t t_ms) { enterPhase(core, NAV_PHASE_NO_CAMERA, t_ms); }

const NavTree* navCoreTarget(const NavCore* core) {
  return core->target_id ? navTreesGet((NavTreeMemory*)&core->memory, core->target_id) : NULL;
}

int32_t navCoreDrainEvents(NavCore* core, NavEvent* out, int32_t max_events) {
  const int32_t n = core->num_events < max_events ? core->num_events : max_events;
  memcpy(out, core->events, (size_t)n * sizeof(NavEvent));
  memmove(core->events, core->events + n, (size_t)(core->num_events - n) * sizeof(NavEvent));
  core->num_events -= n;
  return n;
}

/* -- tracking ------------------------------------------------------------------------------------------- */

/* The measured pixel moved to where the tree appears now, given the MAV's motion since capture. */
static void egoCorrected(const NavCore* core, double u, double v, const NavPose* capture, const NavPose* now,
                         double* cu, double* cv) {
  double fwd, left;
  unrotate(now->yaw_deg, now->x - capture->x, now->y - capture->y, &fwd, &left);
  const double scale = navFocalPx(&core->params) / maxd(now->z, 0.05);
  *cu = u + left * scale;
  *cv = v + fwd * scale;
}

static void startTracking(NavCore* core, int32_t t_ms, double u, double v) {
  const NavParams* p = &core->params;
  navKalmanInit(&core->filter, u, v, p->kf_measurement_std_px, p->kf_accel_psd, INITIAL_VELOCITY_STD);
  core->has_filter = true;
  core->filter_t_ms = t_ms;
  core->has_settle_since = false;
  core->has_captured_since = false;
  core->servo_integral[0] = core->servo_integral[1] = 0.0;
  core->has_recovery_since = false;
  enterPhase(core, NAV_PHASE_APPROACH, t_ms);
}

static void predictFilter(NavCore* core, int32_t t_ms) {
  if (t_ms > core->filter_t_ms) {
    navKalmanPredict(&core->filter, (double)(t_ms - core->filter_t_ms) / 1000.0); /* real time, s */
    core->filter_t_ms = t_ms;
  }
}

static void measureTarget(NavCore* core, int32_t t_ms, const NavDetection* det, const NavPose* capture,
                          const NavPose* now) {
  double u, v;
  egoCorrected(core, det->u, det->v, capture, now, &u, &v);
  if (core->phase == NAV_PHASE_RECOVERY) {
    pushEvent(core, NAV_EVENT_REACQUIRED, t_ms, core->target_id, 0.0, 0.0);
    startTracking(core, t_ms, u, v);
    return;
  }
  if (!core->has_filter) {
    return;
  }
  predictFilter(core, t_ms);
  navKalmanUpdate(&core->filter, u, v);
}

/* -- camera input --------------------------------------------------------------------------------------- */

void navCoreOnFrameMark(NavCore* core, int32_t t_ms) {
  core->has_last_frame_ms = true;
  core->last_frame_ms = t_ms;
}

/* Detections of one frame closer than radius on the ground are one tree seen twice (overlapping detector
 * windows on one big crown): greedy in line order, each joins the first kept one within the radius (running
 * mean of pixel and ground position) or is kept (navigation_core.merge_duplicates). */
static int32_t mergeDuplicates(NavCore* core, const NavDetection* detections, int32_t count, double radius) {
  int32_t kept = 0;
  for (int32_t i = 0; i < count; i++) {
    const double x = core->last_frame_points[i][0], y = core->last_frame_points[i][1];
    int32_t k = 0;
    for (; k < kept; k++) {
      const double ox = core->merged_points[k][0], oy = core->merged_points[k][1];
      if (hypot(x - ox, y - oy) < radius) {
        const int32_t n = core->merged_counts[k] + 1;
        const NavDetection other = core->merged[k];
        core->merged[k].u = other.u + (detections[i].u - other.u) / (double)n;
        core->merged[k].v = other.v + (detections[i].v - other.v) / (double)n;
        core->merged_points[k][0] = ox + (x - ox) / (double)n;
        core->merged_points[k][1] = oy + (y - oy) / (double)n;
        core->merged_counts[k] = n;
        break;
      }
    }
    if (k == kept) {
      core->merged[kept] = detections[i];
      core->merged_points[kept][0] = x;
      core->merged_points[kept][1] = y;
      core->merged_counts[kept] = 1;
      kept++;
    }
    core->owner[i] = k;
  }
  return kept;
}

/* One de-duplicated detection of a frame -> the id of its tree (0: ignored). */
static int32_t takeDetection(NavCore* core, int32_t t_ms, int32_t k, int32_t* num_protected, const NavPose* capture,
                             const NavPose* pose_now) {
  const NavDetection* det = &core->merged[k];
  const double wx = core->merged_points[k][0], wy = core->merged_points[k][1];
  int32_t tree_id = core->assignment[k].id;
  if (core->assignment[k].kind == 2) {
    core->counters.on_visited++;
    return tree_id;
  }
  if (core->assignment[k].kind == 0) {
    if (!inPlantingColumn(core, wx, wy)) {
      core->counters.out_of_column++;
      return 0;
    }
    int32_t evicted[NAV_MAX_TREES];
    int32_t num_evicted = 0;
    tree_id = navTreesAdd(&core->memory, wx, wy, t_ms, det->u, det->v, pose_now->x, pose_now->y, core->protected_ids,
                          *num_protected, evicted, &num_evicted);
    for (int32_t e = 0; e < num_evicted; e++) {
      pushEvent(core, NAV_EVENT_TREE_EVICTED, t_ms, evicted[e], 0.0, 0.0);
      if (evicted[e] == core->target_id) {
        dropTarget(core);
      }
    }
    if (tree_id == 0) {
      return 0; /* T_d full of trees seen in this very frame: counted in memory.unstored */
    }
    core->protected_ids[(*num_protected)++] = tree_id; /* a later new tree of this frame must not evict it */
    pushEvent(core, NAV_EVENT_TREE_ADDED, t_ms, tree_id, wx, wy);
  } else {
    navTreesUpdate(&core->memory, tree_id, wx, wy, t_ms, det->u, det->v);
  }
  if (tree_id == core->target_id) {
    measureTarget(core, t_ms, det, capture, pose_now);
  }
  return tree_id;
}

int32_t navCoreOnFrame(NavCore* core, int32_t t_ms, const NavDetection* detections, int32_t count,
                       const NavPose* pose_now) {
  const NavParams* p = &core->params;
  if (count > NAV_MAX_FRAME_DETECTIONS) {
    count = NAV_MAX_FRAME_DETECTIONS;
  }
  const NavPose* found = poseAt(core, t_ms - p->cam_latency_ms);
  const NavPose capture = found != NULL ? *found : *pose_now;
  for (int32_t i = 0; i < count; i++) {
    pixelToWorld(core, detections[i].u, detections[i].v, &capture, &core->last_frame_points[i][0],
                 &core->last_frame_points[i][1]);
  }
  core->num_last_frame_points = count;
  const int32_t kept = mergeDuplicates(core, detections, count, p->duplicate_radius_m);
  core->counters.duplicates += (uint32_t)(count - kept);
  navTreesAssociate(&core->memory, (const double (*)[2])core->merged_points, kept, p->merge_radius_m,
                    core->assignment);
  int32_t num_protected = 0;
  for (int32_t k = 0; k < kept; k++) {
    if (core->assignment[k].kind == 1) {
      core->protected_ids[num_protected++] = core->assignment[k].id;
    }
  }
  for (int32_t k = 0; k < kept; k++) {
    core->merged_ids[k] = takeDetection(core, t_ms, k, &num_protected, &capture, pose_now);
  }
  core->counters.detections += (uint32_t)count;
  for (int32_t i = 0; i < count; i++) {
    core->last_frame_ids[i] = core->merged_ids[core->owner[i]];
  }
  return count;
}

/* -- control tick --------------------------------------------------------------------------------------- */

static NavCommand stepLand(NavCore* core, int32_t t_ms) {
  const NavParams* p = &core->params;
  const int32_t elapsed = t_ms - core->phase_since;
  if (elapsed < p->land_step_ms) {
    NavCommand c = {NAV_CMD_HOVER, 0.0, 0.0, p->land_height_m};
    return c;
  }
  if (elapsed < 2 * p->land_step_ms) {
    NavCommand c = {NAV_CMD_HOVER, 0.0, 0.0, p->land_final_m};
    return c;
  }
  enterPhase(core, NAV_PHASE_DONE, t_ms);
  return nullCommand();
}

/* Hold while the camera link is silent in flight, land when it stays silent; false: not holding. */
static bool watchLink(NavCore* core, int32_t t_ms, NavCommand* command) {
  const bool flying = core->phase == NAV_PHASE_FOLLOW_PATH || core->phase == NAV_PHASE_RETURN_TO_PATH ||
                      core->phase == NAV_PHASE_APPROACH || core->phase == NAV_PHASE_RECOVERY;
  if (!core->has_last_frame_ms || !flying) {
    return false;
  }
  const int32_t silent_ms = t_ms - core->last_frame_ms;
  const NavParams* p = &core->params;
  if (silent_ms > p->link_land_ms) {
    core->link_lost = false;
    core->link_aborted = true;
    NavEvent* e = pushEvent(core, NAV_EVENT_LINK_LOST, t_ms, 0, 0.0, 0.0);
    if (e != NULL) {
      e->a = (double)silent_ms / 1e3;
      e->variant = 1;
    }
    dropTarget(core);
    enterPhase(core, NAV_PHASE_LAND, t_ms);
    *command = stepLand(core, t_ms);
    return true;
  }
  if (silent_ms > p->link_hold_ms) {
    if (!core->link_lost) {
      core->link_lost = true;
      core->counters.link_losses++;
      pushEvent(core, NAV_EVENT_LINK_LOST, t_ms, 0, 0.0, 0.0);
    }
    *command = hover(core, 0.0, 0.0);
    return true;
  }
  if (core->link_lost) {
    core->link_lost = false;
    NavEvent* e = pushEvent(core, NAV_EVENT_LINK_RESTORED, t_ms, 0, 0.0, 0.0);
    if (e != NULL) {
      e->a = (double)silent_ms / 1e3;
    }
  }
  return false;
}

static NavCommand stepTakeoff(NavCore* core, int32_t t_ms, const NavPose* pose) {
  const NavParams* p = &core->params;
  if (fabs(pose->z - p->altitude_m) > p->takeoff_tolerance_m) {
    core->has_settle_since = false;
  } else if (!core->has_settle_since) {
    core->has_settle_since = true;
    core->settle_since = t_ms;
  } else if (t_ms - core->settle_since >= p->takeoff_settle_ms) {
    core->has_settle_since = false;
    enterPhase(core, NAV_PHASE_FOLLOW_PATH, t_ms);
  }
  return hover(core, 0.0, 0.0);
}

/* -- recovery ------------------------------------------------------------------------------------------- */

static NavCommand afterTree(NavCore* core, int32_t t_ms, const NavPose* pose);

/* Give the target up. unseen: recovery timed out without seeing it again (hidden); such a tree is flagged for
 * one more try before landing, unless this already was that try. */
static NavCommand abandonTarget(NavCore* core, int32_t t_ms, const NavPose* pose, const NavTree* tree, bool unseen) {
  if (tree != NULL) {
    const int32_t id = tree->id;
    const double x = tree->x, y = tree->y;
    const bool revisit = unseen && !core->revisiting;
    navTreesMarkVisited(&core->memory, id, t_ms, pose->x, pose->y, false, revisit);
    core->counters.abandoned++;
    NavEvent* e = pushEvent(core, NAV_EVENT_ABANDONED, t_ms, id, x, y);
    if (e != NULL) {
      e->variant = revisit ? 1 : 0;
    }
  }
  dropTarget(core);
  return afterTree(core, t_ms, pose);
}

static NavCommand stepRecovery(NavCore* core, int32_t t_ms, const NavPose* pose) {
  const NavParams* p = &core->params;
  const NavTree* tree = navCoreTarget(core);
  double cx, cy;
  cameraGroundPoint(core, pose, &cx, &cy);
  const double ex = tree != NULL ? tree->x - cx : 0.0, ey = tree != NULL ? tree->y - cy : 0.0;
  const double distance = hypot(ex, ey);
  if (core->revisiting && !core->revisit_arrived && tree != NULL) {
    /* going back: the recovery and target clocks start once the MAV is over s_t */
    core->revisit_arrived = distance <= p->return_tolerance_m;
    core->recovery_since = core->target_since = t_ms;
  }
  if (tree == NULL || t_ms - core->target_since > p->target_timeout_ms) {
    return abandonTarget(core, t_ms, pose, tree, false);
  }
  if (t_ms - core->recovery_since > p->recovery_timeout_ms) {
    return abandonTarget(core, t_ms, pose, tree, true);
  }
  const double speed = mind(p->recovery_speed, p->servo_gain * distance);
  if (distance < 1e-9) {
    return hover(core, 0.0, 0.0);
  }
  double bx, by;
  unrotate(pose->yaw_deg, ex / distance * speed, ey / distance * speed, &bx, &by);
  return hover(core, bx, by);
}

static void beginRecovery(NavCore* core, int32_t t_ms, const NavTree* tree, double e_d, bool counted) {
  core->counters.recoveries += counted ? 1u : 0u;
  core->has_recovery_since = true;
  core->recovery_since = t_ms;
  core->has_filter = false;
  NavEvent* e = pushEvent(core, counted ? NAV_EVENT_RECOVERY : NAV_EVENT_APPROACH_BY_MEMORY, t_ms, tree->id,
                          tree->x, tree->y);
  if (e != NULL) {
    e->variant = e_d > core->params.recovery_distance_m ? 1 : 0;
    e->a = e_d;
    e->n = t_ms - tree->last_ms;
  }
  enterPhase(core, NAV_PHASE_RECOVERY, t_ms);
}

/* Go back once for the nearest tree abandoned while hidden (flagged in the visited list): restore it into
 * T_d as the target and fly to s_t by memory. False if there is none. */
static bool startRevisit(NavCore* core, int32_t t_ms, const NavPose* pose) {
  const NavParams* p = &core->params;
  double cx, cy;
  cameraGroundPoint(core, pose, &cx, &cy);
  const NavVisited* best = NULL;
  double best_d = 0.0;
  for (int32_t i = 0; i < core->memory.num_visited; i++) {
    const NavVisited* e = &core->memory.visited[i];
    if (!e->revisit) {
      continue;
    }
    const double d = hypot(e->x - cx, e->y - cy);
    if (best == NULL || d < best_d || (d == best_d && e->id < best->id)) {
      best = e;
      best_d = d;
    }
  }
  if (best == NULL) {
    return false;
  }
  int32_t evicted[NAV_MAX_TREES];
  int32_t num_evicted = 0;
  const NavTree* tree = navTreesRestore(&core->memory, best->id, p->min_hits, (double)p->cam_width_px / 2.0,
                                        (double)p->cam_height_px / 2.0, pose->x, pose->y, evicted, &num_evicted);
  for (int32_t k = 0; k < num_evicted; k++) {
    pushEvent(core, NAV_EVENT_TREE_EVICTED, t_ms, evicted[k], 0.0, 0.0);
  }
  core->revisiting = true;
  core->revisit_arrived = false;
  core->target_id = tree->id;
  core->target_since = t_ms;
  pushEvent(core, NAV_EVENT_REVISIT, t_ms, tree->id, tree->x, tree->y);
  beginRecovery(core, t_ms, tree, 0.0, false);
  return true;
}

/* A target is done (reached, abandoned or evicted): back to the path, or, while going back for abandoned trees
 * after the last waypoint, on to the next one or to landing. */
static NavCommand afterTree(NavCore* core, int32_t t_ms, const NavPose* pose) {
  if (!core->revisiting) {
    enterPhase(core, NAV_PHASE_RETURN_TO_PATH, t_ms);
    return hover(core, 0.0, 0.0);
  }
  core->revisiting = false;
  if (startRevisit(core, t_ms, pose)) {
    return hover(core, 0.0, 0.0);
  }
  enterPhase(core, NAV_PHASE_LAND, t_ms);
  return stepLand(core, t_ms);
}

/* -- visual approach ------------------------------------------------------------------------------------ */

static void settleThresholds(const NavCore* core, int32_t t_ms, double* radius, double* speed) {
  const NavParams* p = &core->params;
  if (!core->has_captured_since) {
    *radius = p->settle_radius_px;
    *speed = p->settle_speed;
    return;
  }
  const double relax_s = maxd(0.0, (double)(t_ms - core->captured_since - p->settle_grace_ms) / 1000.0);
  *radius = mind(p->settle_radius_px + p->settle_relax * relax_s, p->capture_radius_px);
  *speed = p->settle_speed * *radius / maxd(p->settle_radius_px, 1e-9);
}

static void integrateServo(NavCore* core, int32_t t_ms, const double offset[2], double error_px, double speed) {
  const NavParams* p = &core->params;
  if (error_px > p->servo_integral_band * p->settle_radius_px || p->servo_integral <= 0.0) {
    core->servo_integral[0] = core->servo_integral[1] = 0.0;
    return;
  }
  if (speed >= p->settle_speed) {
    return; /* still moving: hold the integral */
  }
  const double dt = !core->has_last_tick ? 0.0 : maxd(0.0, (double)(t_ms - core->last_tick) / 1000.0);
  double ix = core->servo_integral[0] + offset[0] * dt, iy = core->servo_integral[1] + offset[1] * dt;
  const double limit = 0.5 * p->approach_speed / p->servo_integral;
  const double norm = hypot(ix, iy);
  if (norm > limit) {
    ix = ix * limit / norm;
    iy = iy * limit / norm;
  }
  core->servo_integral[0] = ix;
  core->servo_integral[1] = iy;
}

static NavCommand reached(NavCore* core, int32_t t_ms, const NavPose* pose, const NavTree* tree) {
  double cx, cy;
  cameraGroundPoint(core, pose, &cx, &cy);
  const int32_t id = tree->id;
  const double tx = tree->x, ty = tree->y;
  navTreesMarkVisited(&core->memory, id, t_ms, pose->x, pose->y, true, false);
  core->counters.reached++;
  NavEvent* e = pushEvent(core, NAV_EVENT_TREE_REACHED, t_ms, id, cx, cy);
  if (e != NULL) {
    e->a = tx;
    e->b = ty;
  }
  dropTarget(core);
  return afterTree(core, t_ms, pose);
}

static NavCommand stepApproach(NavCore* core, int32_t t_ms, const NavPose* pose) {
  const NavParams* p = &core->params;
  const NavTree* tree = navCoreTarget(core);
  if (tree == NULL) { /* evicted meanwhile: nothing left to approach */
    dropTarget(core);
    return afterTree(core, t_ms, pose);
  }
  if (t_ms - core->target_since > p->target_timeout_ms) {
    return abandonTarget(core, t_ms, pose, tree, false);
  }
  predictFilter(core, t_ms);
  double cx, cy;
  cameraGroundPoint(core, pose, &cx, &cy);
  const double e_d = hypot(tree->x - cx, tree->y - cy);
  if (e_d > p->recovery_distance_m || t_ms - tree->last_ms > p->lost_timeout_ms) {
    beginRecovery(core, t_ms, tree, e_d, true);
    return stepRecovery(core, t_ms, pose);
  }
  const double u = core->filter.x[0], v = core->filter.x[1];
  const double eu = u - (double)p->cam_width_px / 2.0, ev = v - (double)p->cam_height_px / 2.0;
  core->pixel_error[0] = eu;
  core->pixel_error[1] = ev;
  const double error_px = hypot(eu, ev);
  core->captured = error_px < p->capture_radius_px; /* the paper's tau: nearly centred */
  if (!core->captured) {
    core->has_captured_since = false;
  } else if (!core->has_captured_since) {
    core->has_captured_since = true;
    core->captured_since = t_ms;
  }
  double radius, speed;
  settleThresholds(core, t_ms, &radius, &speed);
  if (core->captured && error_px < radius && hypot(pose->vx, pose->vy) < speed) {
    if (!core->has_settle_since) {
      core->has_settle_since = true;
      core->settle_since = t_ms;
    }
    if (t_ms - core->settle_since >= p->settle_dwell_ms) {
      return reached(core, t_ms, pose, tree);
    }
  } else {
    core->has_settle_since = false;
  }
  const double scale = maxd(pose->z, 0.05) / navFocalPx(p);
  const double offset[2] = {-ev * scale, -eu * scale}; /* metres forward, left */
  integrateServo(core, t_ms, offset, error_px, hypot(pose->vx, pose->vy));
  double vx, vy;
  servoVelocity(offset[0], offset[1], p->servo_gain, p->approach_speed, core->servo_integral, p->servo_integral,
                &vx, &vy);
  return hover(core, vx, vy);
}

/* -- target selection ----------------------------------------------------------------------------------- */

static bool selectTarget(NavCore* core, int32_t t_ms, const NavPose* pose) {
  const NavParams* p = &core->params;
  double cx, cy;
  cameraGroundPoint(core, pose, &cx, &cy);
  const NavTree* best = NULL;
  double best_d = 0.0;
  for (int32_t i = 0; i < core->memory.num_trees; i++) {
    const NavTree* t = &core->memory.trees[i];
    if (t->hits < p->min_hits || !inPlantingColumn(core, t->x, t->y)) {
      continue;
    }
    const double d = hypot(t->x - cx, t->y - cy);
    if (best == NULL || d < best_d || (d == best_d && t->id < best->id)) {
      best = t;
      best_d = d;
    }
  }
  if (best == NULL) {
    return false;
  }
  core->target_id = best->id;
  core->target_since = t_ms;
  pushEvent(core, NAV_EVENT_TARGET_SELECTED, t_ms, best->id, best->x, best->y);
  const NavPose* found = poseAt(core, best->last_ms - p->cam_latency_ms);
  const NavPose capture = found != NULL ? *found : *pose;
  if (t_ms - best->last_ms > p->lost_timeout_ms) {
    /* seen earlier but not in view now: go to s_t by memory first (not counted as a recovery) */
    beginRecovery(core, t_ms, best, 0.0, false);
    return true;
  }
  double u, v;
  egoCorrected(core, best->u, best->v, &capture, pose, &u, &v);
  startTracking(core, t_ms, u, v);
  return true;
}

/* -- path following ------------------------------------------------------------------------------------- */

static bool waypointReached(const NavCore* core, const NavPose* pose) {
  const double* goal = core->path[core->waypoint_index];
  if (hypot(goal[0] - pose->x, goal[1] - pose->y) < core->params.waypoint_tolerance_m) {
    return true;
  }
  if (core->waypoint_index == 0) {
    return false;
  }
  const double* a = core->path[core->waypoint_index - 1];
  const double dx = goal[0] - a[0], dy = goal[1] - a[1];
  return (pose->x - goal[0]) * dx + (pose->y - goal[1]) * dy >= 0.0;
}

static void followVelocity(const NavCore* core, const NavPose* pose, const double* goal, double* wx, double* wy) {
  const NavParams* p = &core->params;
  double carrot[2];
  if (core->waypoint_index == 0) {
    carrot[0] = goal[0];
    carrot[1] = goal[1];
  } else {
    const double* a = core->path[core->waypoint_index - 1];
    const double dx = goal[0] - a[0], dy = goal[1] - a[1];
    double length = hypot(dx, dy);
    if (length == 0.0) {
      length = 1e-9;
    }
    const double along = ((pose->x - a[0]) * dx + (pose->y - a[1]) * dy) / length;
    const double s = mind(maxd(along, 0.0) + p->lookahead_m, length) / length;
    carrot[0] = a[0] + s * dx;
    carrot[1] = a[1] + s * dy;
  }
  const double ex = carrot[0] - pose->x, ey = carrot[1] - pose->y;
  const double distance = hypot(ex, ey);
  if (distance < 1e-9) {
    *wx = *wy = 0.0;
    return;
  }
  const double to_goal = hypot(goal[0] - pose->x, goal[1] - pose->y);
  const double speed = mind(p->cruise_speed, maxd(p->arrival_min_speed, to_goal));
  *wx = ex / distance * speed;
  *wy = ey / distance * speed;
}

static NavCommand stepFollow(NavCore* core, int32_t t_ms, const NavPose* pose) {
  if (selectTarget(core, t_ms, pose)) {
    return core->phase == NAV_PHASE_APPROACH ? stepApproach(core, t_ms, pose) : stepRecovery(core, t_ms, pose);
  }
  const NavParams* p = &core->params;
  const double* goal = core->path[core->waypoint_index];
  if (waypointReached(core, pose)) {
    core->waypoint_index++;
    NavEvent* e = pushEvent(core, NAV_EVENT_WAYPOINT, t_ms, 0, 0.0, 0.0);
    if (e != NULL) {
      e->n = core->waypoint_index - 1;
    }
    if (core->waypoint_index >= core->path_length) {
      if (startRevisit(core, t_ms, pose)) {
        return stepRecovery(core, t_ms, pose);
      }
      enterPhase(core, NAV_PHASE_LAND, t_ms);
      return stepLand(core, t_ms);
    }
    goal = core->path[core->waypoint_index];
  }
  if (core->phase == NAV_PHASE_RETURN_TO_PATH && core->waypoint_index > 0) {
    const double *a, *b;
    currentSegment(core, &a, &b);
    if (distanceToSegment(pose->x, pose->y, a, b) < p->return_tolerance_m) {
      enterPhase(core, NAV_PHASE_FOLLOW_PATH, t_ms);
    }
  }
  double wx, wy, bx, by;
  followVelocity(core, pose, goal, &wx, &wy);
  unrotate(pose->yaw_deg, wx, wy, &bx, &by);
  return hover(core, bx, by);
}

NavCommand navCoreStep(NavCore* core, int32_t t_ms, const NavPose* pose) {
  recordPose(core, t_ms, pose);
  core->memory.capacity = core->params.tree_capacity; /* PARAMs may change in flight */
  core->memory.visited_capacity = core->params.visited_capacity;
  int32_t evicted[NAV_MAX_TREES];
  const int32_t num_evicted = navTreesEvictToCapacity(&core->memory, pose->x, pose->y, evicted);
  for (int32_t k = 0; k < num_evicted; k++) {
    NavEvent* e = pushEvent(core, NAV_EVENT_TREE_EVICTED, t_ms, evicted[k], 0.0, 0.0);
    if (e != NULL) {
      e->variant = 1; /* treeCapacity lowered */
    }
    if (evicted[k] == core->target_id) {
      dropTarget(core);
    }
  }
  NavCommand command;
  if (watchLink(core, t_ms, &command)) {
    core->has_last_tick = true;
    core->last_tick = t_ms;
    return command;
  }
  switch (core->phase) {
    case NAV_PHASE_TAKEOFF:
      command = stepTakeoff(core, t_ms, pose);
      break;
    case NAV_PHASE_FOLLOW_PATH:
    case NAV_PHASE_RETURN_TO_PATH:
      command = stepFollow(core, t_ms, pose);
      break;
    case NAV_PHASE_APPROACH:
      command = stepApproach(core, t_ms, pose);
      break;
    case NAV_PHASE_RECOVERY:
      command = stepRecovery(core, t_ms, pose);
      break;
    case NAV_PHASE_LAND:
      command = stepLand(core, t_ms);
      break;
    default: /* BOOT, DONE, NO_DECK, NO_CAMERA */
      command = nullCommand();
      break;
  }
  core->has_last_tick = true;
  core->last_tick = t_ms;
  return command;
}

/* -- console lines -------------------------------------------------------------------------------------- */

/* Decimal digits of value >= 0 into out (no libc: the Bolt build links no stdio). Returns the length. */
static size_t formatUnsigned(char* out, size_t size, unsigned long value, int min_digits) {
  char digits[24];
  int n = 0;
  do {
    digits[n++] = (char)('0' + value % 10u);
    value /= 10u;
  } while (value > 0u && n < (int)sizeof(digits));
  while (n < min_digits && n < (int)sizeof(digits)) {
    digits[n++] = '0';
  }
  size_t k = 0;
  while (n > 0 && k + 1 < size) {
    out[k++] = digits[--n];
  }
  if (size > 0) {
    out[k] = '\0';
  }
  return k;
}

int navFormatFixed(char* out, size_t size, double value, int decimals) {
#ifndef NAV_NO_PRINTF_FLOAT
  return snprintf(out, size, "%.*f", decimals, value); /* correctly rounded, as Python's '%.3f' */
#else
  unsigned long scale = 1u;
  for (int i = 0; i < decimals; i++) {
    scale *= 10u;
  }
  const double magnitude = fabs(value) * (double)scale;
  if (!(magnitude < 4.0e9)) {
    return (int)formatUnsigned(out, size, 0u, 1); /* out of range for the console: never a real value */
  }
  /* Correctly rounded like printf: the sign of (exact |value| x scale) - (whole + 1/2) is exact with fma
   * (0.0005 is a little above the half: "0.001"); an exact half goes to even (1.25 -> "1.2"). */
  const double a = fabs(value), sc = (double)scale;
  double whole = floor(magnitude);
  if (fma(a, sc, -whole) < 0.0) {
    whole -= 1.0; /* the rounded product reached an integer the exact one is below */
  }
  const double above_half = fma(a, sc, -(whole + 0.5));
  unsigned long scaled = (unsigned long)whole;
  if (above_half > 0.0 || (above_half == 0.0 && (scaled & 1u))) {
    scaled++;
  }
  size_t n = 0;
  if (value < 0.0 && n + 1 < size) {
    out[n++] = '-';
  }
  n += formatUnsigned(out + n, size - n, scaled / scale, 1);
  if (decimals > 0 && n + 1 < size) {
    out[n++] = '.';
    n += formatUnsigned(out + n, size - n, scaled % scale, decimals);
  }
  out[n < size ? n : size - 1] = '\0';
  return (int)n;
#endif
}

/* Appends with bounds: returns the new length (never past size - 1). */
static size_t append(char* out, size_t size, size_t n, const char* text) {
  while (*text != '\0' && n + 1 < size) {
    out[n++] = *text++;
  }
  out[n < size ? n : size - 1] = '\0';
  return n;
}

static size_t appendFixed(char* out, size_t size, size_t n, double value, int decimals) {
  char number[32];
  navFormatFixed(number, sizeof(number), value, decimals);
  return append(out, size, n, number);
}

static size_t appendInt(char* out, size_t size, size_t n, long value) {
  char number[24];
  size_t k = 0;
  if (value < 0) {
    number[k++] = '-';
  }
  formatUnsigned(number + k, sizeof(number) - k, value < 0 ? 0ul - (unsigned long)value : (unsigned long)value, 1);
  return append(out, size, n, number);
}

int navFormatEventDetail(const NavEvent* e, char* out, size_t size) {
  size_t n = 0;
  out[0] = '\0';
  switch (e->kind) {
    case NAV_EVENT_PHASE:
      n = append(out, size, n, navPhaseName(e->n));
      break;
    case NAV_EVENT_TREE_EVICTED:
      n = append(out, size, n, e->variant ? "treeCapacity lowered" : "T_d full");
      break;
    case NAV_EVENT_ABANDONED:
      n = append(out, size, n, e->variant ? "unseen: will go back once" : "");
      break;
    case NAV_EVENT_REVISIT:
      n = append(out, size, n, "abandoned while hidden");
      break;
    case NAV_EVENT_TREE_REACHED:
      n = append(out, size, n, "s_t ");
      n = appendFixed(out, size, n, e->a, 3);
      n = append(out, size, n, " ");
      n = appendFixed(out, size, n, e->b, 3);
      break;
    case NAV_EVENT_RECOVERY:
    case NAV_EVENT_APPROACH_BY_MEMORY:
      if (e->variant) {
        n = append(out, size, n, "e_d ");
        n = appendFixed(out, size, n, e->a, 2);
        n = append(out, size, n, " m");
      } else {
        n = append(out, size, n, "not seen ");
        n = appendInt(out, size, n, e->n);
        n = append(out, size, n, " ms");
      }
      break;
    case NAV_EVENT_WAYPOINT:
      n = appendInt(out, size, n, e->n);
      break;
    case NAV_EVENT_LINK_LOST:
      if (e->variant) {
        n = append(out, size, n, "camera silent ");
        n = appendFixed(out, size, n, e->a, 1);
        n = append(out, size, n, " s: landing");
      } else {
        n = append(out, size, n, "camera silent: holding position");
      }
      break;
    case NAV_EVENT_LINK_RESTORED:
      n = append(out, size, n, "after ");
      n = appendFixed(out, size, n, e->a, 1);
      n = append(out, size, n, " s");
      break;
    default:
      break;
  }
  return (int)n;
}

int navFormatEvent(const NavEvent* e, char* out, size_t size) {
  char detail[64];
  navFormatEventDetail(e, detail, sizeof(detail));
  size_t n = 0;
  out[0] = '\0';
  if (e->kind == NAV_EVENT_PHASE) {
    n = append(out, size, n, "phase ");
    return (int)append(out, size, n, detail);
  }
  n = append(out, size, n, navEventKindName(e->kind));
  if (e->tree_id) {
    n = append(out, size, n, " tree ");
    n = appendInt(out, size, n, e->tree_id);
  }
  const bool positioned = e->kind == NAV_EVENT_TREE_ADDED || e->kind == NAV_EVENT_TREE_REACHED ||
                          e->kind == NAV_EVENT_TARGET_SELECTED || e->kind == NAV_EVENT_RECOVERY ||
                          e->kind == NAV_EVENT_ABANDONED || e->kind == NAV_EVENT_APPROACH_BY_MEMORY ||
                          e->kind == NAV_EVENT_REVISIT;
  if (positioned) {
    n = append(out, size, n, " at (");
    n = appendFixed(out, size, n, e->x, 3);
    n = append(out, size, n, ", ");
    n = appendFixed(out, size, n, e->y, 3);
    n = append(out, size, n, ")");
  }
  if (detail[0] != '\0') {
    n = append(out, size, n, " ");
    n = append(out, size, n, detail);
  }
  return (int)n;
}
