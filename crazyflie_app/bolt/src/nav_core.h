/*
 * ForaNav navigation core: the pure C port of crazyflie_app/app/navigation_core.py (Algorithm 1 as a state
 * machine), with the pixel Kalman filter (nav_kalman.c), the tree memory (nav_trees.c) and the camera's
 * serial line assembler and parser (nav_serial.c).
 *
 * Pure: no firmware call, no clock, no file-level static state. Everything one flight needs lives in one
 * NavCore struct passed in, so one process can fly many flights (the host tests do) and the firmware adapter
 * (foranav_app.c) owns exactly one. All arithmetic is in double, like the Python port, so the differential
 * test (tests/crazyflie_app/bolt/test_differential_c_vs_python.py) can hold both cores to 1e-9.
 *
 * Capacities are compiled in (no malloc on the Bolt): the PARAMs app.treeCapacity and app.visitedCap are
 * clamped to NAV_MAX_TREES and NAV_MAX_VISITED; a camera frame keeps at most NAV_MAX_FRAME_DETECTIONS
 * detections (the rest are counted in framesTruncated); the event queue drops (and counts) past
 * NAV_MAX_EVENTS until the adapter drains it.
 */
#ifndef NAV_CORE_H
#define NAV_CORE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define NAV_MAX_WAYPOINTS 64
#define NAV_MAX_TREES 64
#define NAV_MAX_VISITED 128
#define NAV_MAX_FRAME_DETECTIONS 64 /* app.frameCap (default 64) is clamped to it */
#define NAV_MAX_EVENTS 64 /* drained every tick; a frame of 64 new trees would overflow it (counted) */
/* Ticks of pose history for latency compensation: 1.28 s at 100 Hz, as the Python core
 * (nav_types.POSE_HISTORY_LENGTH; tests/crazyflie_app/bolt/test_build.py checks it). Not only the camera latency
 * looks back: a target selected from T_d is ego-corrected from the pose of its last detection, up to
 * app.lostTimeout (1.5 s) old; with 48 ticks the two cores chose different setpoints there. */
#define NAV_POSE_HISTORY 128
#define NAV_POSITION_AVERAGE_WINDOW 20
#define NAV_MAX_LINE_LENGTH 64 /* longest valid serial message (foranav_serial.MAX_LINE_LENGTH) */
#define NAV_LABEL_LENGTH (NAV_MAX_LINE_LENGTH + 1)

typedef enum {
  NAV_PHASE_BOOT = 0,
  NAV_PHASE_TAKEOFF,
  NAV_PHASE_FOLLOW_PATH,
  NAV_PHASE_APPROACH,
  NAV_PHASE_RECOVERY,
  NAV_PHASE_RETURN_TO_PATH,
  NAV_PHASE_LAND,
  NAV_PHASE_DONE,
  NAV_PHASE_NO_DECK,
  NAV_PHASE_NO_CAMERA,
} NavPhase;

typedef enum {
  NAV_EVENT_PHASE = 0,
  NAV_EVENT_TREE_ADDED,
  NAV_EVENT_TREE_EVICTED,
  NAV_EVENT_TARGET_SELECTED,
  NAV_EVENT_TREE_REACHED,
  NAV_EVENT_RECOVERY,
  NAV_EVENT_APPROACH_BY_MEMORY,
  NAV_EVENT_REACQUIRED,
  NAV_EVENT_ABANDONED,
  NAV_EVENT_WAYPOINT,
  NAV_EVENT_LINK_LOST,
  NAV_EVENT_LINK_RESTORED,
  NAV_EVENT_REVISIT,
  NAV_EVENT_TREE_ABSORBED,
  NAV_EVENT_KIND_COUNT,
} NavEventKind;

typedef enum { NAV_CMD_NULL = 0, NAV_CMD_HOVER = 1 } NavCommandKind;

/* Every threshold and speed law (navigation_core.NavigationParams); the app exports each as app.<name>. */
typedef struct {
  double altitude_m;
  double takeoff_tolerance_m;
  int32_t takeoff_settle_ms;
  double land_height_m;
  double land_final_m;
  int32_t land_step_ms;
  double arrival_min_speed;
  double cruise_speed;
  double waypoint_tolerance_m;
  double lookahead_m;
  double approach_speed;
  double servo_gain;
  double capture_radius_px;
  double settle_radius_px;
  int32_t settle_dwell_ms;
  double settle_speed;
  double settle_relax;
  int32_t settle_grace_ms;
  double servo_integral;
  double servo_integral_band;
  double recovery_distance_m;
  int32_t lost_timeout_ms;
  int32_t recovery_timeout_ms;
  int32_t target_timeout_ms;
  double recovery_speed;
  double return_tolerance_m;
  double merge_radius_m;
  double duplicate_radius_m;
  double crown_size_m;
  double column_factor;
  double row_spacing_m;     /* 0: not given */
  int32_t anchor_min_trees; /* 0: re-anchoring off */
  double anchor_gain;
  int32_t min_hits;
  int32_t tree_capacity;
  int32_t visited_capacity;
  int32_t cam_width_px;
  int32_t cam_height_px;
  double cam_scale;
  double cam_offset_x_m;
  double cam_offset_y_m;
  int32_t cam_latency_ms;
  double kf_measurement_std_px;
  double kf_accel_psd;
  int32_t link_hold_ms;
  int32_t link_land_ms;
  int32_t camera_wait_ms; /* used by the adapters (pre-flight camera check) */
  int32_t frame_capacity; /* used by the camera input */
  int32_t start; /* used by the adapters: 0 = wait on the ground for a client to write app.start = 1 */
} NavParams;

typedef struct { double x, y, z, yaw_deg, vx, vy; } NavPose; /* the estimate: m, m, m, deg, m/s, m/s */
typedef struct { NavCommandKind kind; double vx, vy, z; } NavCommand; /* hover: body vx, vy; abs z */
typedef struct { double u, v; } NavDetection; /* image position, px */

/* A decision worth a console line. Its detail text (navFormatEventDetail) is made from a, b, n and variant
 * only when printed, so the core never formats floats (the Bolt's newlib-nano printf has no %f). */
typedef struct {
  NavEventKind kind;
  int32_t t_ms;
  int32_t tree_id;
  double x, y;
  double a, b;     /* s_t (reached), e_d (recovery), silence in s (link events) */
  int32_t n;       /* phase entered, waypoint index, ms not seen, the reached twin's id (tree_absorbed) */
  int32_t variant; /* recovery: 1 e_d, 0 not seen; link_lost: 1 landing, 0 holding; abandoned: 1 revisit */
} NavEvent;

typedef struct {
  uint32_t detections, out_of_column, on_visited, reached, recoveries, abandoned, link_losses, duplicates;
} NavCounters;

/* pixel_kalman.PixelKalmanFilter: x = [u, v, du, dv] (px, px/s), P the full 4x4 covariance. */
typedef struct {
  double x[4];
  double P[4][4];
  double R; /* measurement variance, px^2 (R = R I) */
  double accel_psd;
  uint32_t updates, predictions;
} NavKalman;

typedef struct { int32_t id; double x, y; int32_t hits, first_ms, last_ms; double u, v; } NavTree;
/* revisit: abandoned while unseen (hidden): the app goes back for it once before landing */
typedef struct { int32_t id; double x, y; int32_t t_ms; bool reached; bool revisit; } NavVisited;

/* tree_memory.TreeMemory: T_d (insertion order) and the visited list (oldest first). */
typedef struct {
  int32_t capacity, visited_capacity;
  NavTree trees[NAV_MAX_TREES];
  int32_t num_trees;
  NavVisited visited[NAV_MAX_VISITED];
  int32_t num_visited;
  uint32_t evicted, visited_forgotten;
  uint32_t unstored; /* new trees not stored: T_d full of trees seen in the same frame */
  uint32_t absorbed; /* stored trees dropped as a reached tree seen again */
  int32_t next_id;
} NavTreeMemory;

/* Association result of one detection: kind 0 none, 1 stored tree, 2 visited tree. */
typedef struct { int kind; int32_t id; } NavAssociation;

/* Bytes -> lines (foranav_serial.LineAssembler) and lines -> frames (NavigationApp.on_camera_line). */
typedef struct {
  char buf[NAV_MAX_LINE_LENGTH + 1];
  int32_t length;
  bool overlong;
  uint32_t dropped; /* lines dropped for length */
} NavLineAssembler;

typedef enum { NAV_LINE_NONE = 0, NAV_LINE_T2, NAV_LINE_N2, NAV_LINE_MARK_START, NAV_LINE_MARK_STOP } NavLineKind;

typedef struct {
  NavLineKind kind;
  char label[NAV_LABEL_LENGTH]; /* N2 only */
  double x, y, w, h;           /* standardized coordinates (w, h: N2 only) */
} NavMessage;

typedef struct {
  int32_t t_ms;
  NavPose pose;
} NavPoseSample;

typedef struct {
  NavParams params;
  double planned[NAV_MAX_WAYPOINTS][2]; /* the waypoints as given */
  double path[NAV_MAX_WAYPOINTS][2];    /* the path flown: the waypoints moved by offset (re-anchoring) */
  int32_t path_length;
  double offset[2];
  bool has_progress; /* a tree of the current segment was reached ... */
  double progress;   /* ... this far along it ... */
  int32_t progress_ms; /* ... at this time */
  NavTreeMemory memory;
  NavCounters counters;
  NavPhase phase;
  int32_t waypoint_index;
  int32_t target_id;
  bool has_filter;
  NavKalman filter;
  int32_t filter_t_ms;
  NavEvent events[NAV_MAX_EVENTS];
  int32_t num_events;
  uint32_t events_dropped;
  int32_t phase_since;
  bool has_settle_since;
  int32_t settle_since;
  bool has_recovery_since;
  int32_t recovery_since;
  int32_t target_since;
  bool has_last_tick;
  int32_t last_tick;
  NavPoseSample poses[NAV_POSE_HISTORY]; /* ring buffer */
  int32_t poses_head, poses_count;
  double pixel_error[2];
  double last_frame_points[NAV_MAX_FRAME_DETECTIONS][2];
  int32_t last_frame_ids[NAV_MAX_FRAME_DETECTIONS];
  int32_t num_last_frame_points;
  bool captured;
  bool has_captured_since;
  int32_t captured_since;
  double servo_integral[2];
  bool has_last_frame_ms; /* camera link watch: none until the first end-of-frame mark */
  int32_t last_frame_ms;
  bool link_lost;
  bool link_aborted;
  bool revisiting;      /* flying back, before landing, to a tree abandoned while hidden */
  bool revisit_arrived; /* ... and over its stored s_t once */
  /* per-frame scratch (kept here, not on the camera task's stack) */
  NavDetection merged[NAV_MAX_FRAME_DETECTIONS];
  double merged_points[NAV_MAX_FRAME_DETECTIONS][2];
  double association_radii[NAV_MAX_FRAME_DETECTIONS];
  int32_t merged_counts[NAV_MAX_FRAME_DETECTIONS];
  int32_t owner[NAV_MAX_FRAME_DETECTIONS];
  int32_t merged_ids[NAV_MAX_FRAME_DETECTIONS];
  NavAssociation assignment[NAV_MAX_FRAME_DETECTIONS];
  int32_t protected_ids[NAV_MAX_FRAME_DETECTIONS];
} NavCore;

/* The camera input of the app (NavigationApp.camera_task / on_camera_line / _end_frame): one per app. */
typedef struct {
  NavLineAssembler assembler;
  NavDetection frame[NAV_MAX_FRAME_DETECTIONS];
  int32_t frame_length;
  bool marks_seen;
  bool heard;             /* a valid camera message (frame mark or detection) was received ... */
  int32_t last_heard_ms;  /* ... last at this tick */
  uint32_t frame_overflow; /* detections dropped beyond app.frameCap in one frame */
  char target_label[NAV_LABEL_LENGTH]; /* "" = accept every N2 label */
  uint32_t other_labels;
  uint32_t frames;
  NavDetection last_frame[NAV_MAX_FRAME_DETECTIONS]; /* the frame last handed to the core */
  int32_t last_frame_length;
} NavCameraInput;

#ifdef __cplusplus
extern "C" {
#endif

/* -- nav_core.c -- */
void navParamsDefaults(NavParams* params);
double navFocalPx(const NavParams* params);
/* false: fewer than 2 or more than NAV_MAX_WAYPOINTS waypoints (xy: x0, y0, x1, y1, ...) */
bool navCoreInit(NavCore* core, const NavParams* params, const double* xy, int32_t waypoints);
void navCoreStart(NavCore* core, int32_t t_ms);
void navCoreAbortNoDeck(NavCore* core, int32_t t_ms);
void navCoreAbortNoCamera(NavCore* core, int32_t t_ms); /* camera never heard before take-off */
NavCommand navCoreStep(NavCore* core, int32_t t_ms, const NavPose* pose);
void navCoreOnFrameMark(NavCore* core, int32_t t_ms);
/* Returns the number of detections taken (<= NAV_MAX_FRAME_DETECTIONS); ids in core->last_frame_ids. */
int32_t navCoreOnFrame(NavCore* core, int32_t t_ms, const NavDetection* detections, int32_t count,
                       const NavPose* pose_now);
/* The target's stored tree, or NULL (no target). */
const NavTree* navCoreTarget(const NavCore* core);
/* Pops the events (returns how many were copied into out, oldest first). */
int32_t navCoreDrainEvents(NavCore* core, NavEvent* out, int32_t max_events);
/* The console line of an event, exactly as the Python app prints it, and its detail part alone. */
int navFormatEvent(const NavEvent* event, char* out, size_t size);
int navFormatEventDetail(const NavEvent* event, char* out, size_t size);
/* "%.*f" (snprintf on the host; built with NAV_NO_PRINTF_FLOAT, as for the Bolt, an integer formatter). */
int navFormatFixed(char* out, size_t size, double value, int decimals);
const char* navPhaseName(int32_t phase);
const char* navEventKindName(int32_t kind);

/* -- nav_kalman.c -- */
void navKalmanInit(NavKalman* kf, double u, double v, double measurement_std_px, double accel_psd,
                   double initial_velocity_std);
void navKalmanPredict(NavKalman* kf, double dt);
void navKalmanUpdate(NavKalman* kf, double u, double v);

/* -- nav_trees.c -- */
void navTreesInit(NavTreeMemory* memory, int32_t capacity, int32_t visited_capacity);
NavTree* navTreesGet(NavTreeMemory* memory, int32_t id);
/* Point i goes to the nearest free stored or visited tree within radii[i] (exclusive per frame). */
void navTreesAssociate(const NavTreeMemory* memory, const double (*points)[2], const double* radii,
                       int32_t count, NavAssociation* result);
/* Returns the new id, or 0 when T_d is full of protected trees (ids a detection of this frame refers to;
 * counted in unstored); evicted ids go to evicted[] (at most NAV_MAX_TREES), their count to *num_evicted. */
int32_t navTreesAdd(NavTreeMemory* memory, double x, double y, int32_t t_ms, double u, double v,
                    double mav_x, double mav_y, const int32_t* protected_ids, int32_t num_protected,
                    int32_t* evicted, int32_t* num_evicted);
/* After capacity was lowered: evict the farthest trees until T_d fits. Returns how many (ids in evicted). */
int32_t navTreesEvictToCapacity(NavTreeMemory* memory, double mav_x, double mav_y, int32_t* evicted);
/* Drop every stored tree within radius of a reached visited entry (that tree seen again) into the visited
 * list, not reached, at that entry's position (a full list forgets its entry farthest from the MAV first).
 * Returns how many; their ids go to dropped[], the reached entries' ids to twins[] (at most NAV_MAX_TREES
 * each). */
int32_t navTreesAbsorbReached(NavTreeMemory* memory, double radius, int32_t t_ms, double mav_x, double mav_y,
                              int32_t* dropped, int32_t* twins);
/* True when a reached visited entry other than the one at index lies within radius of it. */
bool navTreesNearReached(const NavTreeMemory* memory, int32_t index, double radius);
/* Move a visited entry back into T_d (same id and position, hits, last seen when visited, image (u, v));
 * a full T_d evicts its farthest tree first. NULL if id is not visited. */
NavTree* navTreesRestore(NavTreeMemory* memory, int32_t id, int32_t hits, double u, double v, double mav_x,
                         double mav_y, int32_t* evicted, int32_t* num_evicted);
void navTreesUpdate(NavTreeMemory* memory, int32_t id, double x, double y, int32_t t_ms, double u, double v);
bool navTreesMarkVisited(NavTreeMemory* memory, int32_t id, int32_t t_ms, double mav_x, double mav_y,
                         bool reached, bool revisit);

/* -- nav_serial.c -- */
void navLineAssemblerInit(NavLineAssembler* assembler);
/* One received byte; true when it completes a line (then *line / *length: the line, without terminator,
 * valid until the next push). Overlong lines are dropped whole (counted in dropped). */
bool navLineAssemblerPush(NavLineAssembler* assembler, uint8_t byte, const char** line, int32_t* length);
/* foranav_serial.parse_line: T2 / N2 / MARK START / MARK STOP, or NAV_LINE_NONE for anything else. */
NavMessage navParseLine(const char* line, int32_t length);
double navStdToImgX(double x, int32_t width);
double navStdToImgY(double y, int32_t height);

void navCameraInputInit(NavCameraInput* input, const char* target_label);
/* Feeds received UART bytes: T2/N2 lines join the frame, a MARK ends it and hands it to the core with
 * pose_now (the estimate at t_ms; pose_valid false before the app has its estimate or once it is DONE: the
 * frame is dropped). Stops right after a frame was handed over (*frame_done true; the frame is in
 * last_frame, the core's last_frame_points/ids) and returns the bytes consumed: call again with the rest. */
size_t navCameraInputFeed(NavCameraInput* input, NavCore* core, const uint8_t* data, size_t length, int32_t t_ms,
                          const NavPose* pose_now, bool pose_valid, bool* frame_done);
/* After each read batch: a camera that sends no frame marks has each batch of lines as one frame.
 * Returns true when a frame was handed over. */
bool navCameraInputEndBatch(NavCameraInput* input, NavCore* core, int32_t t_ms, const NavPose* pose_now,
                            bool pose_valid);
/* Pre-flight check: a valid camera message within app.linkHoldMs (app.camWaitMs 0: no check). */
bool navCameraInputAlive(const NavCameraInput* input, const NavParams* params, int32_t t_ms);

#ifdef __cplusplus
}
#endif

#endif /* NAV_CORE_H */
