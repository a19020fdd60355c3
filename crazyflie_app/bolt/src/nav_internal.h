/*
 * The core's internal functions, shared between its nav_*.c files: nav_core.c (the state machine), nav_state.c
 * (the state changes every job shares, the lowest layer) and one file per job, as the Python modules (nav_geometry.c: camera_geometry.py, nav_path.c: path_following.py,
 * nav_servo.c: visual_servo.py, nav_recovery.c: recovery.py, nav_vertical.c: vertical.py, nav_link.c:
 * link_watch.py, nav_frame.c: frame_input.py). Private: the public API, used by the ctypes binding and the
 * firmware adapter, is nav_core.h.
 */
#ifndef NAV_INTERNAL_H
#define NAV_INTERNAL_H

#include "nav_core.h"

static inline double maxd(double a, double b) { return a > b ? a : b; }
static inline double mind(double a, double b) { return a < b ? a : b; }

/* events, phases, commands and the target (nav_state.c) */
NavEvent* navPushEvent(NavCore* core, NavEventKind kind, int32_t t_ms, int32_t tree_id, double x, double y);
void navEnterPhase(NavCore* core, NavPhase phase, int32_t t_ms);
NavCommand navHover(const NavCore* core, double vx, double vy);
NavCommand navNullCommand(void);
void navDropTarget(NavCore* core);
void navStartTracking(NavCore* core, int32_t t_ms, double u, double v);

/* camera geometry (nav_geometry.c) */
void navRotate(double yaw_deg, double bx, double by, double* wx, double* wy); /* body -> world */
void navUnrotate(double yaw_deg, double wx, double wy, double* bx, double* by); /* world -> body */
void navCameraGroundPoint(const NavCore* core, const NavPose* pose, double* x, double* y);
void navPixelToWorld(const NavCore* core, double u, double v, const NavPose* pose, double* x, double* y);
void navEgoCorrected(const NavCore* core, double u, double v, const NavPose* capture, const NavPose* now,
                     double* cu, double* cv);
const NavPose* navPoseAt(const NavCore* core, int32_t t_ms);
void navRecordPose(NavCore* core, int32_t t_ms, const NavPose* pose);
int32_t navMergeDuplicates(NavCore* core, const NavDetection* detections, int32_t count, double radius);

/* path following (nav_path.c) */
double navDistanceToSegment(double px, double py, const double a[2], const double b[2]);
void navCurrentSegment(const NavCore* core, const double** a, const double** b);
bool navInPlantingColumn(const NavCore* core, double x, double y);
/* Half the planting column's width: columnFactor crowns, at most half of rowSpacing when given. */
double navColumnHalfWidth(const NavParams* p);
/* On to the next waypoint (a new segment forgets its progress). */
void navAdvanceWaypoint(NavCore* core);
/* Along the current segment from its start (m); progress and the trees behind it (PathFollower.behind). */
double navAlong(const NavCore* core, double x, double y);
void navNoteReached(NavCore* core, double x, double y, int32_t t_ms);
/* a tree first seen at first_ms, after the last reach of the segment, and behind it: that tree seen again */
bool navBehind(const NavCore* core, double x, double y, int32_t first_ms);
/* Re-anchoring (PathFollower.reanchor): the distance of (x, y) across the planned current segment (false: the
 * segment has no length), and the correction from the sum of count such distances. */
bool navAcrossPlanned(const NavCore* core, double x, double y, double* across);
void navReanchor(NavCore* core, double across_sum, int32_t count);
/* How far beyond its end waypoint a segment is flown (PathFollower.end_reach_m), and where it ends. */
double navEndReach(const NavParams* p);
void navSegmentEnd(const NavCore* core, double end[2]);
/* Distance of the MAV from the current segment, as flown (up to its end beyond the waypoint). */
double navCrossTrack(const NavCore* core, const NavPose* pose);
bool navWaypointReached(const NavCore* core, const NavPose* pose);
void navFollowVelocity(const NavCore* core, const NavPose* pose, const double* goal, double* wx, double* wy);

/* visual servo (nav_servo.c) */
void navServoVelocity(double offset_fwd_m, double offset_left_m, double gain, double max_speed,
                      const double integral[2], double integral_gain, double* vx, double* vy);
void navPredictFilter(NavCore* core, int32_t t_ms);
void navSettleThresholds(const NavCore* core, int32_t t_ms, double* radius, double* speed);
void navIntegrateServo(NavCore* core, int32_t t_ms, const double offset[2], double error_px, double speed);

/* tree memory (nav_trees.c) */
int32_t navTreesEntry(const NavTreeMemory* memory, bool visited, int32_t index, double* x, double* y);

/* recovery (nav_recovery.c) */
/* Whether entry index of T_d or of the visited list may be chosen. */
typedef bool (*NavEligible)(const NavCore* core, int32_t index);
int32_t navNearest(const NavCore* core, const NavPose* pose, bool visited, NavEligible eligible);
NavCommand navAfterTree(NavCore* core, int32_t t_ms, const NavPose* pose);
NavCommand navAbandonTarget(NavCore* core, int32_t t_ms, const NavPose* pose, const NavTree* tree, bool unseen);
NavCommand navStepRecovery(NavCore* core, int32_t t_ms, const NavPose* pose);
void navBeginRecovery(NavCore* core, int32_t t_ms, const NavTree* tree, double e_d, bool counted);
bool navStartRevisit(NavCore* core, int32_t t_ms, const NavPose* pose);

/* take-off and landing (nav_vertical.c) */
NavCommand navStepTakeoff(NavCore* core, int32_t t_ms, const NavPose* pose);
NavCommand navStepLand(NavCore* core, int32_t t_ms);

/* the camera link watch (nav_link.c) */
bool navWatchLink(NavCore* core, int32_t t_ms, NavCommand* command);

#endif
