/*
 * Path following (crazyflie_app/app/path_following.py): the current segment of F, the planting column around it,
 * the waypoint rule and the carrot velocity along the segment. A segment is flown navEndReach beyond its end
 * waypoint, until the rest of the planting column beyond it has been in whole view. The path flown is the
 * waypoints moved by the re-anchoring's offset (corrected from the trees seen at each tree reached), and trees
 * behind the last one reached on a segment are passed (path_following.py says why).
 */
#include <math.h>

#include "nav_internal.h"

double navDistanceToSegment(double px, double py, const double a[2], const double b[2]) {
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  const double length2 = dx * dx + dy * dy;
  const double t = length2 == 0.0 ? 0.0 : maxd(0.0, mind(1.0, ((px - a[0]) * dx + (py - a[1]) * dy) / length2));
  return hypot(px - a[0] - t * dx, py - a[1] - t * dy);
}

static int32_t segmentIndex(const NavCore* core) {
  int32_t k = core->waypoint_index > 1 ? core->waypoint_index : 1;
  return k < core->path_length - 1 ? k : core->path_length - 1;
}

void navCurrentSegment(const NavCore* core, const double** a, const double** b) {
  const int32_t k = segmentIndex(core);
  *a = core->path[k - 1];
  *b = core->path[k];
}

double navColumnHalfWidth(const NavParams* p) {
  double half = p->column_factor * p->crown_size_m;
  if (p->row_spacing_m > 0.0 && p->row_spacing_m / 2.0 < half) {
    half = p->row_spacing_m / 2.0;
  }
  return half;
}

bool navInPlantingColumn(const NavCore* core, double x, double y) {
  const double *a, *b;
  navCurrentSegment(core, &a, &b);
  return navDistanceToSegment(x, y, a, b) <= navColumnHalfWidth(&core->params);
}

void navAdvanceWaypoint(NavCore* core) {
  core->waypoint_index++;
  if (core->waypoint_index >= 2) {
    core->has_progress = false;
  }
}

double navAlong(const NavCore* core, double x, double y) {
  const double *a, *b;
  navCurrentSegment(core, &a, &b);
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  double length = hypot(dx, dy);
  if (length == 0.0) {
    length = 1e-9;
  }
  return ((x - a[0]) * dx + (y - a[1]) * dy) / length;
}

void navNoteReached(NavCore* core, double x, double y, int32_t t_ms) {
  core->progress = navAlong(core, x, y);
  core->progress_ms = t_ms;
  core->has_progress = true;
}

bool navBehind(const NavCore* core, double x, double y, int32_t first_ms) {
  return core->has_progress && first_ms > core->progress_ms &&
         navAlong(core, x, y) < core->progress - core->params.merge_radius_m;
}

/* the unit normal of the planned current segment (false: no length) */
static bool plannedNormal(const NavCore* core, const double** a, double* nx, double* ny) {
  const int32_t k = segmentIndex(core);
  const double* b = core->planned[k];
  *a = core->planned[k - 1];
  const double dx = b[0] - (*a)[0], dy = b[1] - (*a)[1];
  const double length = hypot(dx, dy);
  if (length == 0.0) {
    return false;
  }
  *nx = -dy / length;
  *ny = dx / length;
  return true;
}

bool navAcrossPlanned(const NavCore* core, double x, double y, double* across) {
  const double* a;
  double nx, ny;
  if (!plannedNormal(core, &a, &nx, &ny)) {
    return false;
  }
  *across = (x - a[0]) * nx + (y - a[1]) * ny;
  return true;
}

void navReanchor(NavCore* core, double across_sum, int32_t count) {
  const double* a;
  double nx, ny;
  if (core->params.anchor_min_trees <= 0 || count < core->params.anchor_min_trees ||
      !plannedNormal(core, &a, &nx, &ny)) {
    return;
  }
  const double shift =
      core->params.anchor_gain * (across_sum / (double)count - (core->offset[0] * nx + core->offset[1] * ny));
  core->offset[0] = core->offset[0] + shift * nx;
  core->offset[1] = core->offset[1] + shift * ny;
  for (int32_t i = 0; i < core->path_length; i++) {
    core->path[i][0] = core->planned[i][0] + core->offset[0];
    core->path[i][1] = core->planned[i][1] + core->offset[1];
  }
}

/* The MAV is in the first row past its first waypoint (PathFollower.in_first_row). */
static bool inFirstRow(const NavCore* core, const NavPose* pose) {
  const double* a = core->path[0];
  const double* b = core->path[1];
  const double along = (pose->x - a[0]) * (b[0] - a[0]) + (pose->y - a[1]) * (b[1] - a[1]);
  return along > 0.0 && navDistanceToSegment(pose->x, pose->y, a, b) <= navColumnHalfWidth(&core->params);
}

double navEndReach(const NavParams* p) {
  const double in_view_m = (double)p->cam_height_px / 2.0 * p->altitude_m / navFocalPx(p) - p->crown_size_m / 2.0;
  return maxd(0.0, navColumnHalfWidth(p) - in_view_m);
}

void navSegmentEnd(const NavCore* core, double end[2]) {
  const double* goal = core->path[core->waypoint_index];
  end[0] = goal[0];
  end[1] = goal[1];
  if (core->waypoint_index == 0) {
    return;
  }
  const double* a = core->path[core->waypoint_index - 1];
  const double dx = goal[0] - a[0], dy = goal[1] - a[1];
  const double length = hypot(dx, dy);
  if (length == 0.0) {
    return;
  }
  const double reach = navEndReach(&core->params);
  end[0] = goal[0] + dx / length * reach;
  end[1] = goal[1] + dy / length * reach;
}

double navCrossTrack(const NavCore* core, const NavPose* pose) {
  const double *a, *b;
  navCurrentSegment(core, &a, &b);
  double end[2] = {b[0], b[1]};
  if (core->waypoint_index > 0 && core->waypoint_index < core->path_length) {
    navSegmentEnd(core, end);
  }
  return navDistanceToSegment(pose->x, pose->y, a, end);
}

bool navWaypointReached(const NavCore* core, const NavPose* pose) {
  double end[2];
  navSegmentEnd(core, end);
  if (hypot(end[0] - pose->x, end[1] - pose->y) < core->params.waypoint_tolerance_m) {
    return true;
  }
  if (core->waypoint_index == 0) {
    return inFirstRow(core, pose);
  }
  const double* a = core->path[core->waypoint_index - 1];
  const double dx = end[0] - a[0], dy = end[1] - a[1];
  return (pose->x - end[0]) * dx + (pose->y - end[1]) * dy >= 0.0;
}

void navFollowVelocity(const NavCore* core, const NavPose* pose, const double* goal, double* wx, double* wy) {
  const NavParams* p = &core->params;
  double carrot[2];
  double end[2] = {goal[0], goal[1]};
  if (core->waypoint_index == 0) {
    carrot[0] = goal[0];
    carrot[1] = goal[1];
  } else {
    const double* a = core->path[core->waypoint_index - 1];
    navSegmentEnd(core, end);
    const double dx = end[0] - a[0], dy = end[1] - a[1];
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
  const double to_goal = hypot(end[0] - pose->x, end[1] - pose->y);
  const double speed = mind(p->cruise_speed, maxd(p->arrival_min_speed, to_goal));
  *wx = ex / distance * speed;
  *wy = ey / distance * speed;
}
