/*
 * Camera geometry (crazyflie_app/app/camera_geometry.py): body/world rotation, pixel -> ground point, the ego-motion
 * correction of a detection, the pose history of the latency lookup, and the merge of duplicate detections.
 */
#include <math.h>

#include "nav_internal.h"

static const double DEG_TO_RAD = 3.14159265358979323846 / 180.0; /* CPython math.radians */

void navRotate(double yaw_deg, double bx, double by, double* wx, double* wy) { /* body -> world */
  const double c = cos(yaw_deg * DEG_TO_RAD), s = sin(yaw_deg * DEG_TO_RAD);
  *wx = bx * c - by * s;
  *wy = bx * s + by * c;
}

void navUnrotate(double yaw_deg, double wx, double wy, double* bx, double* by) { /* world -> body */
  const double c = cos(yaw_deg * DEG_TO_RAD), s = sin(yaw_deg * DEG_TO_RAD);
  *bx = wx * c + wy * s;
  *by = -wx * s + wy * c;
}

void navCameraGroundPoint(const NavCore* core, const NavPose* pose, double* x, double* y) {
  double ox, oy;
  navRotate(pose->yaw_deg, core->params.cam_offset_x_m, core->params.cam_offset_y_m, &ox, &oy);
  *x = pose->x + ox;
  *y = pose->y + oy;
}

void navPixelToWorld(const NavCore* core, double u, double v, const NavPose* pose, double* x, double* y) {
  const NavParams* p = &core->params;
  const double scale = maxd(pose->z, 0.05) / navFocalPx(p);
  const double fwd = ((double)p->cam_height_px / 2.0 - v) * scale, left = ((double)p->cam_width_px / 2.0 - u) * scale;
  double wx, wy, cx, cy;
  navRotate(pose->yaw_deg, fwd, left, &wx, &wy);
  navCameraGroundPoint(core, pose, &cx, &cy);
  *x = cx + wx;
  *y = cy + wy;
}

/* The measured pixel moved to where the tree appears now, given the MAV's motion since capture. */
void navEgoCorrected(const NavCore* core, double u, double v, const NavPose* capture, const NavPose* now,
                     double* cu, double* cv) {
  double fwd, left;
  navUnrotate(now->yaw_deg, now->x - capture->x, now->y - capture->y, &fwd, &left);
  const double scale = navFocalPx(&core->params) / maxd(now->z, 0.05);
  *cu = u + left * scale;
  *cv = v + fwd * scale;
}

/* The newest recorded pose not later than t_ms (the oldest kept one if none); NULL if none recorded. */
const NavPose* navPoseAt(const NavCore* core, int32_t t_ms) {
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

void navRecordPose(NavCore* core, int32_t t_ms, const NavPose* pose) {
  core->poses[core->poses_head].t_ms = t_ms;
  core->poses[core->poses_head].pose = *pose;
  core->poses_head = (core->poses_head + 1) % NAV_POSE_HISTORY;
  if (core->poses_count < NAV_POSE_HISTORY) {
    core->poses_count++;
  }
}

/* Detections of one frame closer than radius on the ground are one tree seen twice (overlapping detector
 * windows on one big crown): greedy in line order, each joins the first kept one within the radius (running
 * mean of pixel and ground position) or is kept (navigation_core.merge_duplicates). */
int32_t navMergeDuplicates(NavCore* core, const NavDetection* detections, int32_t count, double radius) {
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
