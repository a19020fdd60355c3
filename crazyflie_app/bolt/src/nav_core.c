/*
 * Algorithm 1 as a state machine: the C port of crazyflie_app/app/navigation_core.py (read its docstring for the
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

#include "nav_internal.h"

/* -- init ----------------------------------------------------------------------------------------------- */

bool navCoreInit(NavCore* core, const NavParams* params, const double* xy, int32_t waypoints) {
  memset(core, 0, sizeof(*core));
  if (waypoints < 2 || waypoints > NAV_MAX_WAYPOINTS) {
    return false;
  }
  core->params = *params;
  for (int32_t i = 0; i < waypoints; i++) {
    core->planned[i][0] = core->path[i][0] = xy[2 * i];
    core->planned[i][1] = core->path[i][1] = xy[2 * i + 1];
  }
  core->path_length = waypoints;
  navTreesInit(&core->memory, params->tree_capacity, params->visited_capacity);
  core->phase = NAV_PHASE_BOOT;
  return true;
}

void navCoreStart(NavCore* core, int32_t t_ms) { navEnterPhase(core, NAV_PHASE_TAKEOFF, t_ms); }

void navCoreAbortNoDeck(NavCore* core, int32_t t_ms) { navEnterPhase(core, NAV_PHASE_NO_DECK, t_ms); }

void navCoreAbortNoCamera(NavCore* core, int32_t t_ms) { navEnterPhase(core, NAV_PHASE_NO_CAMERA, t_ms); }

int32_t navCoreDrainEvents(NavCore* core, NavEvent* out, int32_t max_events) {
  const int32_t n = core->num_events < max_events ? core->num_events : max_events;
  memcpy(out, core->events, (size_t)n * sizeof(NavEvent));
  memmove(core->events, core->events + n, (size_t)(core->num_events - n) * sizeof(NavEvent));
  core->num_events -= n;
  return n;
}

/* -- visual approach ------------------------------------------------------------------------------------ */

static bool eligibleTree(const NavCore* core, int32_t index);

/* Re-anchoring on the row as the camera sees it over a reached tree (navigation_core._row_in_view): the reached
 * tree at (x, y), then the column's eligible trees seen within lostTimeout, in T_d order. */
static void reanchorOnRow(NavCore* core, int32_t t_ms, double x, double y) {
  double across, sum;
  if (!navAcrossPlanned(core, x, y, &sum)) {
    return;
  }
  int32_t count = 1;
  for (int32_t i = 0; i < core->memory.num_trees; i++) {
    const NavTree* t = &core->memory.trees[i];
    if (eligibleTree(core, i) && t_ms - t->last_ms <= core->params.lost_timeout_ms &&
        navAcrossPlanned(core, t->x, t->y, &across)) {
      sum += across;
      count++;
    }
  }
  navReanchor(core, sum, count);
}

static NavCommand reached(NavCore* core, int32_t t_ms, const NavPose* pose, const NavTree* tree) {
  double cx, cy;
  navCameraGroundPoint(core, pose, &cx, &cy);
  const int32_t id = tree->id;
  const double tx = tree->x, ty = tree->y;
  navTreesMarkVisited(&core->memory, id, t_ms, pose->x, pose->y, true, false);
  core->counters.reached++;
  NavEvent* e = navPushEvent(core, NAV_EVENT_TREE_REACHED, t_ms, id, cx, cy);
  if (e != NULL) {
    e->a = tx;
    e->b = ty;
  }
  navDropTarget(core);
  navNoteReached(core, cx, cy, t_ms);
  reanchorOnRow(core, t_ms, cx, cy);
  return navAfterTree(core, t_ms, pose);
}

static NavCommand stepApproach(NavCore* core, int32_t t_ms, const NavPose* pose) {
  const NavParams* p = &core->params;
  const NavTree* tree = navCoreTarget(core);
  if (tree == NULL) { /* evicted meanwhile: nothing left to approach */
    navDropTarget(core);
    return navAfterTree(core, t_ms, pose);
  }
  if (t_ms - core->target_since > p->target_timeout_ms) {
    return navAbandonTarget(core, t_ms, pose, tree, false);
  }
  navPredictFilter(core, t_ms);
  double cx, cy;
  navCameraGroundPoint(core, pose, &cx, &cy);
  const double e_d = hypot(tree->x - cx, tree->y - cy);
  if (e_d > p->recovery_distance_m || t_ms - tree->last_ms > p->lost_timeout_ms) {
    navBeginRecovery(core, t_ms, tree, e_d, true);
    return navStepRecovery(core, t_ms, pose);
  }
  const double u = core->filter.x[0], v = core->filter.x[1];
  const double eu = u - (double)p->cam_width_px / 2.0, ev = v - (double)p->cam_height_px / 2.0;
  core->pixel_error[0] = eu;
  core->pixel_error[1] = ev;
  const double error_px = hypot(eu, ev);
  core->captured = error_px < p->capture_radius_px; /* the paper's tau: nearly centred */
  /* the relax clock runs from the first capture of this approach (visual_servo.py says why) */
  if (core->captured && !core->has_captured_since) {
    core->has_captured_since = true;
    core->captured_since = t_ms;
  }
  double radius, speed;
  navSettleThresholds(core, t_ms, &radius, &speed);
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
  navIntegrateServo(core, t_ms, offset, error_px, hypot(pose->vx, pose->vy));
  double vx, vy;
  navServoVelocity(offset[0], offset[1], p->servo_gain, p->approach_speed, core->servo_integral, p->servo_integral,
                   &vx, &vy);
  return navHover(core, vx, vy);
}

/* -- target selection ----------------------------------------------------------------------------------- */

/* A stored tree that may become the target: seen often enough, in the planting column (eligible_trees). */
static bool eligibleTree(const NavCore* core, int32_t index) {
  const NavTree* t = &core->memory.trees[index];
  return t->hits >= core->params.min_hits && navInPlantingColumn(core, t->x, t->y) && !navBehind(core, t->x, t->y, t->first_ms);
}

static bool selectTarget(NavCore* core, int32_t t_ms, const NavPose* pose) {
  const NavParams* p = &core->params;
  const int32_t nearest = navNearest(core, pose, false, eligibleTree);
  if (nearest < 0) {
    return false;
  }
  const NavTree* best = &core->memory.trees[nearest];
  core->target_id = best->id;
  core->target_since = t_ms;
  navPushEvent(core, NAV_EVENT_TARGET_SELECTED, t_ms, best->id, best->x, best->y);
  const NavPose* found = navPoseAt(core, best->last_ms - p->cam_latency_ms);
  const NavPose capture = found != NULL ? *found : *pose;
  if (t_ms - best->last_ms > p->lost_timeout_ms) {
    /* seen earlier but not in view now: go to s_t by memory first (not counted as a recovery) */
    navBeginRecovery(core, t_ms, best, 0.0, false);
    return true;
  }
  double u, v;
  navEgoCorrected(core, best->u, best->v, &capture, pose, &u, &v);
  navStartTracking(core, t_ms, u, v);
  return true;
}

/* -- path following and the control tick ---------------------------------------------------------------- */

static NavCommand stepFollow(NavCore* core, int32_t t_ms, const NavPose* pose) {
  if (selectTarget(core, t_ms, pose)) {
    return core->phase == NAV_PHASE_APPROACH ? stepApproach(core, t_ms, pose) : navStepRecovery(core, t_ms, pose);
  }
  const NavParams* p = &core->params;
  const double* goal = core->path[core->waypoint_index];
  if (navWaypointReached(core, pose)) {
    navAdvanceWaypoint(core);
    NavEvent* e = navPushEvent(core, NAV_EVENT_WAYPOINT, t_ms, 0, 0.0, 0.0);
    if (e != NULL) {
      e->n = core->waypoint_index - 1;
    }
    if (core->waypoint_index >= core->path_length) {
      if (navStartRevisit(core, t_ms, pose)) {
        return navStepRecovery(core, t_ms, pose);
      }
      navEnterPhase(core, NAV_PHASE_LAND, t_ms);
      return navStepLand(core, t_ms);
    }
    goal = core->path[core->waypoint_index];
  }
  if (core->phase == NAV_PHASE_RETURN_TO_PATH && core->waypoint_index > 0) {
    if (navCrossTrack(core, pose) < p->return_tolerance_m) {
      navEnterPhase(core, NAV_PHASE_FOLLOW_PATH, t_ms);
    }
  }
  double wx, wy, bx, by;
  navFollowVelocity(core, pose, goal, &wx, &wy);
  navUnrotate(pose->yaw_deg, wx, wy, &bx, &by);
  return navHover(core, bx, by);
}

NavCommand navCoreStep(NavCore* core, int32_t t_ms, const NavPose* pose) {
  navRecordPose(core, t_ms, pose);
  core->memory.capacity = core->params.tree_capacity; /* PARAMs may change in flight */
  core->memory.visited_capacity = core->params.visited_capacity;
  int32_t evicted[NAV_MAX_TREES];
  const int32_t num_evicted = navTreesEvictToCapacity(&core->memory, pose->x, pose->y, evicted);
  for (int32_t k = 0; k < num_evicted; k++) {
    NavEvent* e = navPushEvent(core, NAV_EVENT_TREE_EVICTED, t_ms, evicted[k], 0.0, 0.0);
    if (e != NULL) {
      e->variant = 1; /* treeCapacity lowered */
    }
    if (evicted[k] == core->target_id) {
      navDropTarget(core);
    }
  }
  NavCommand command;
  if (navWatchLink(core, t_ms, &command)) {
    core->has_last_tick = true;
    core->last_tick = t_ms;
    return command;
  }
  switch (core->phase) {
    case NAV_PHASE_TAKEOFF:
      command = navStepTakeoff(core, t_ms, pose);
      break;
    case NAV_PHASE_FOLLOW_PATH:
    case NAV_PHASE_RETURN_TO_PATH:
      command = stepFollow(core, t_ms, pose);
      break;
    case NAV_PHASE_APPROACH:
      command = stepApproach(core, t_ms, pose);
      break;
    case NAV_PHASE_RECOVERY:
      command = navStepRecovery(core, t_ms, pose);
      break;
    case NAV_PHASE_LAND:
      command = navStepLand(core, t_ms);
      break;
    default: /* BOOT, DONE, NO_DECK, NO_CAMERA */
      command = navNullCommand();
      break;
  }
  core->has_last_tick = true;
  core->last_tick = t_ms;
  return command;
}
