/*
 * Recovery (crazyflie_app/app/recovery.py): flying to s_t by memory when the target is lost, giving it up, and the
 * one revisit of trees abandoned while hidden.
 */
#include <math.h>

#include "nav_internal.h"

/* A target is done (reached, abandoned or evicted): back to the path, or, while going back for abandoned trees
 * after the last waypoint, on to the next one or to landing. */
NavCommand navAfterTree(NavCore* core, int32_t t_ms, const NavPose* pose) {
  if (!core->revisiting) {
    navEnterPhase(core, NAV_PHASE_RETURN_TO_PATH, t_ms);
    return navHover(core, 0.0, 0.0);
  }
  core->revisiting = false;
  if (navStartRevisit(core, t_ms, pose)) {
    return navHover(core, 0.0, 0.0);
  }
  navEnterPhase(core, NAV_PHASE_LAND, t_ms);
  return navStepLand(core, t_ms);
}

/* Give the target up. unseen: recovery timed out without seeing it again (hidden); such a tree is flagged for
 * one more try before landing, unless this already was that try. */
NavCommand navAbandonTarget(NavCore* core, int32_t t_ms, const NavPose* pose, const NavTree* tree, bool unseen) {
  if (tree != NULL) {
    const int32_t id = tree->id;
    const double x = tree->x, y = tree->y;
    const bool revisit = unseen && !core->revisiting;
    navTreesMarkVisited(&core->memory, id, t_ms, pose->x, pose->y, false, revisit);
    core->counters.abandoned++;
    NavEvent* e = navPushEvent(core, NAV_EVENT_ABANDONED, t_ms, id, x, y);
    if (e != NULL) {
      e->variant = revisit ? 1 : 0;
    }
  }
  navDropTarget(core);
  return navAfterTree(core, t_ms, pose);
}

NavCommand navStepRecovery(NavCore* core, int32_t t_ms, const NavPose* pose) {
  const NavParams* p = &core->params;
  const NavTree* tree = navCoreTarget(core);
  double cx, cy;
  navCameraGroundPoint(core, pose, &cx, &cy);
  const double ex = tree != NULL ? tree->x - cx : 0.0, ey = tree != NULL ? tree->y - cy : 0.0;
  const double distance = hypot(ex, ey);
  if (core->revisiting && !core->revisit_arrived && tree != NULL) {
    /* going back: the recovery and target clocks start once the MAV is over s_t */
    core->revisit_arrived = distance <= p->return_tolerance_m;
    core->recovery_since = core->target_since = t_ms;
  }
  if (tree == NULL || t_ms - core->target_since > p->target_timeout_ms) {
    return navAbandonTarget(core, t_ms, pose, tree, false);
  }
  if (t_ms - core->recovery_since > p->recovery_timeout_ms) {
    return navAbandonTarget(core, t_ms, pose, tree, true);
  }
  const double speed = mind(p->recovery_speed, p->servo_gain * distance);
  if (distance < 1e-9) {
    return navHover(core, 0.0, 0.0);
  }
  double bx, by;
  navUnrotate(pose->yaw_deg, ex / distance * speed, ey / distance * speed, &bx, &by);
  return navHover(core, bx, by);
}

void navBeginRecovery(NavCore* core, int32_t t_ms, const NavTree* tree, double e_d, bool counted) {
  core->counters.recoveries += counted ? 1u : 0u;
  core->has_recovery_since = true;
  core->recovery_since = t_ms;
  core->has_filter = false;
  NavEvent* e = navPushEvent(core, counted ? NAV_EVENT_RECOVERY : NAV_EVENT_APPROACH_BY_MEMORY, t_ms, tree->id,
                             tree->x, tree->y);
  if (e != NULL) {
    e->variant = e_d > core->params.recovery_distance_m ? 1 : 0;
    e->a = e_d;
    e->n = t_ms - tree->last_ms;
  }
  navEnterPhase(core, NAV_PHASE_RECOVERY, t_ms);
}

/* Index of the eligible entry of T_d (visited false) or of the visited list nearest to the camera's ground point,
 * a tie to the smaller id (recovery.nearest); -1 if none is eligible. */
int32_t navNearest(const NavCore* core, const NavPose* pose, bool visited, NavEligible eligible) {
  double cx, cy;
  navCameraGroundPoint(core, pose, &cx, &cy);
  const int32_t count = visited ? core->memory.num_visited : core->memory.num_trees;
  int32_t best = -1, best_id = 0;
  double best_d = 0.0;
  for (int32_t i = 0; i < count; i++) {
    if (!eligible(core, i)) {
      continue;
    }
    double x, y;
    const int32_t id = navTreesEntry(&core->memory, visited, i, &x, &y);
    const double d = hypot(x - cx, y - cy);
    if (best < 0 || d < best_d || (d == best_d && id < best_id)) {
      best = i;
      best_id = id;
      best_d = d;
    }
  }
  return best;
}

/* A visited entry flagged for one more try (abandoned while hidden), unless a reached tree lies within
 * app.dupRadius of it (it was that tree). */
static bool flaggedForRevisit(const NavCore* core, int32_t index) {
  return core->memory.visited[index].revisit &&
         !navTreesNearReached(&core->memory, index, core->params.duplicate_radius_m);
}

/* Go back once for the nearest tree abandoned while hidden (flagged in the visited list): restore it into
 * T_d as the target and fly to s_t by memory. False if there is none. */
bool navStartRevisit(NavCore* core, int32_t t_ms, const NavPose* pose) {
  const NavParams* p = &core->params;
  const int32_t nearest = navNearest(core, pose, true, flaggedForRevisit);
  if (nearest < 0) {
    return false;
  }
  const NavVisited* best = &core->memory.visited[nearest];
  int32_t evicted[NAV_MAX_TREES];
  int32_t num_evicted = 0;
  const NavTree* tree = navTreesRestore(&core->memory, best->id, p->min_hits, (double)p->cam_width_px / 2.0,
                                        (double)p->cam_height_px / 2.0, pose->x, pose->y, evicted, &num_evicted);
  for (int32_t k = 0; k < num_evicted; k++) {
    navPushEvent(core, NAV_EVENT_TREE_EVICTED, t_ms, evicted[k], 0.0, 0.0);
  }
  core->revisiting = true;
  core->revisit_arrived = false;
  core->target_id = tree->id;
  core->target_since = t_ms;
  navPushEvent(core, NAV_EVENT_REVISIT, t_ms, tree->id, tree->x, tree->y);
  navBeginRecovery(core, t_ms, tree, 0.0, false);
  return true;
}
