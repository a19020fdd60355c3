/*
 * One camera frame into the core (crazyflie_app/app/frame_input.py and NavigationCore.on_frame): ground points,
 * duplicates merged, association with T_d, new trees stored, the target's filter updated.
 */
#include "nav_internal.h"

static void measureTarget(NavCore* core, int32_t t_ms, const NavDetection* det, const NavPose* capture,
                          const NavPose* now) {
  double u, v;
  navEgoCorrected(core, det->u, det->v, capture, now, &u, &v);
  if (core->phase == NAV_PHASE_RECOVERY) {
    navPushEvent(core, NAV_EVENT_REACQUIRED, t_ms, core->target_id, 0.0, 0.0);
    navStartTracking(core, t_ms, u, v);
    return;
  }
  if (!core->has_filter) {
    return;
  }
  navPredictFilter(core, t_ms);
  navKalmanUpdate(&core->filter, u, v);
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
    if (!navInPlantingColumn(core, wx, wy)) {
      core->counters.out_of_column++;
      return 0;
    }
    int32_t evicted[NAV_MAX_TREES];
    int32_t num_evicted = 0;
    tree_id = navTreesAdd(&core->memory, wx, wy, t_ms, det->u, det->v, pose_now->x, pose_now->y, core->protected_ids,
                          *num_protected, evicted, &num_evicted);
    for (int32_t e = 0; e < num_evicted; e++) {
      navPushEvent(core, NAV_EVENT_TREE_EVICTED, t_ms, evicted[e], 0.0, 0.0);
      if (evicted[e] == core->target_id) {
        navDropTarget(core);
      }
    }
    if (tree_id == 0) {
      return 0; /* T_d full of trees seen in this very frame: counted in memory.unstored */
    }
    core->protected_ids[(*num_protected)++] = tree_id; /* a later new tree of this frame must not evict it */
    navPushEvent(core, NAV_EVENT_TREE_ADDED, t_ms, tree_id, wx, wy);
  } else {
    navTreesUpdate(&core->memory, tree_id, wx, wy, t_ms, det->u, det->v);
  }
  if (tree_id == core->target_id) {
    measureTarget(core, t_ms, det, capture, pose_now);
  }
  return tree_id;
}

/* Stored trees that are a reached tree seen again are dropped into the visited list (the target too). */
static void absorbReached(NavCore* core, int32_t t_ms, const NavPose* pose_now) {
  int32_t dropped[NAV_MAX_TREES], twins[NAV_MAX_TREES];
  const int32_t count = navTreesAbsorbReached(&core->memory, core->params.duplicate_radius_m, t_ms, pose_now->x,
                                              pose_now->y, dropped, twins);
  for (int32_t k = 0; k < count; k++) {
    NavEvent* e = navPushEvent(core, NAV_EVENT_TREE_ABSORBED, t_ms, dropped[k], 0.0, 0.0);
    if (e != NULL) {
      e->n = twins[k];
    }
    if (dropped[k] == core->target_id) {
      navDropTarget(core);
    }
  }
}

/* FrameInput.association_radius: outside the planting column only dupRadius, so a tree the column rule never
 * admitted (the next column's first tree on a turn) cannot pass for a stored neighbour. */
static double associationRadius(const NavCore* core, double x, double y) {
  const NavParams* p = &core->params;
  if (navInPlantingColumn(core, x, y)) {
    return p->merge_radius_m;
  }
  return p->duplicate_radius_m < p->merge_radius_m ? p->duplicate_radius_m : p->merge_radius_m;
}

int32_t navCoreOnFrame(NavCore* core, int32_t t_ms, const NavDetection* detections, int32_t count,
                       const NavPose* pose_now) {
  const NavParams* p = &core->params;
  if (count > NAV_MAX_FRAME_DETECTIONS) {
    count = NAV_MAX_FRAME_DETECTIONS;
  }
  const NavPose* found = navPoseAt(core, t_ms - p->cam_latency_ms);
  const NavPose capture = found != NULL ? *found : *pose_now;
  for (int32_t i = 0; i < count; i++) {
    navPixelToWorld(core, detections[i].u, detections[i].v, &capture, &core->last_frame_points[i][0],
                    &core->last_frame_points[i][1]);
  }
  core->num_last_frame_points = count;
  const int32_t kept = navMergeDuplicates(core, detections, count, p->duplicate_radius_m);
  core->counters.duplicates += (uint32_t)(count - kept);
  for (int32_t k = 0; k < kept; k++) {
    core->association_radii[k] = associationRadius(core, core->merged_points[k][0], core->merged_points[k][1]);
  }
  navTreesAssociate(&core->memory, (const double (*)[2])core->merged_points, core->association_radii, kept,
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
  absorbReached(core, t_ms, pose_now);
  return count;
}
