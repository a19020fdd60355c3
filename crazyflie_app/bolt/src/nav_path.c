/*
 * Path following (crazyflie_app/app/path_following.py): the current segment of F, the planting column around it,
 * the waypoint rule and the carrot velocity along the segment. A segment is flown navEndReach beyond its end
 * waypoint, until the rest of the planting column beyond it has been in whole view.
 */
#include <math.h>

#include "nav_internal.h"

double navDistanceToSegment(double px, double py, const double a[2], const double b[2]) {
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  const double length2 = dx * dx + dy * dy;
  const double t = length2 == 0.0 ? 0.0 : maxd(0.0, mind(1.0, ((px - a[0]) * dx + (py - a[1]) * dy) / length2));
  return hypot(px - a[0] - t * dx, py - a[1] - t * dy);
}

void navCurrentSegment(const NavCore* core, const double** a, const double** b) {
  int32_t k = core->waypoint_index > 1 ? core->waypoint_index : 1;
  k = k < core->path_length - 1 ? k : core->path_length - 1;
  *a = core->path[k - 1];
  *b = core->path[k];
}

bool navInPlantingColumn(const NavCore* core, double x, double y) {
  const double *a, *b;
  navCurrentSegment(core, &a, &b);
  return navDistanceToSegment(x, y, a, b) <= core->params.column_factor * core->params.crown_size_m;
}

double navEndReach(const NavParams* p) {
  const double in_view_m = (double)p->cam_height_px / 2.0 * p->altitude_m / navFocalPx(p) - p->crown_size_m / 2.0;
  return maxd(0.0, p->column_factor * p->crown_size_m - in_view_m);
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
    return false;
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
