/*
 * Host-only entry points of the shared library (build/libforanav_nav.so) that crazyflie_app/bolt/c_core.py loads
 * with ctypes: the core and its camera input behind one heap object, flat arguments, snapshot getters.
 * Not part of the Bolt build (src/Kbuild does not list it): on the Bolt, foranav_app.c owns one static app.
 */
#include <stdlib.h>
#include <string.h>

#include "nav_core.h"

typedef struct {
  NavCore core;
  NavCameraInput input;
} NavHostApp;

/* What Python reads after each call, in one copy. */
typedef struct {
  int32_t phase, target_id, waypoint_index, num_trees, num_visited;
  int32_t captured, link_lost, link_aborted, has_target;
  NavCounters counters; /* detections, out_of_column, on_visited, reached, recoveries, abandoned, link_losses,
                         duplicates: the flat uint32 fields of c_core._Status */
  uint32_t evicted, forgotten, lines_dropped, other_labels, frames, frame_overflow, events_dropped, unstored;
  int32_t pending_detections, revisiting;
  double err_u, err_v, target_x, target_y;
} NavHostStatus;

NavHostApp* navHostCreate(const NavParams* params, const double* xy, int32_t waypoints, const char* target_label) {
  NavHostApp* app = calloc(1, sizeof(NavHostApp));
  if (app == NULL) {
    return NULL;
  }
  if (!navCoreInit(&app->core, params, xy, waypoints)) {
    free(app);
    return NULL;
  }
  navCameraInputInit(&app->input, target_label);
  return app;
}

void navHostDestroy(NavHostApp* app) { free(app); }

NavParams* navHostParams(NavHostApp* app) { return &app->core.params; }

void navHostDefaults(NavParams* params) { navParamsDefaults(params); }

void navHostStart(NavHostApp* app, int32_t t_ms) { navCoreStart(&app->core, t_ms); }

void navHostAbortNoDeck(NavHostApp* app, int32_t t_ms) { navCoreAbortNoDeck(&app->core, t_ms); }

void navHostAbortNoCamera(NavHostApp* app, int32_t t_ms) { navCoreAbortNoCamera(&app->core, t_ms); }

int32_t navHostCameraAlive(const NavHostApp* app, int32_t t_ms) {
  return navCameraInputAlive(&app->input, &app->core.params, t_ms) ? 1 : 0;
}

static NavPose pose6(const double* pose) {
  NavPose p = {pose[0], pose[1], pose[2], pose[3], pose[4], pose[5]};
  return p;
}

/* pose: x, y, z, yaw_deg, vx, vy; out: vx, vy, z. Returns the command kind (0 null, 1 hover). */
int32_t navHostStep(NavHostApp* app, int32_t t_ms, const double* pose, double* out) {
  const NavPose p = pose6(pose);
  const NavCommand c = navCoreStep(&app->core, t_ms, &p);
  out[0] = c.vx;
  out[1] = c.vy;
  out[2] = c.z;
  return (int32_t)c.kind;
}

void navHostOnFrameMark(NavHostApp* app, int32_t t_ms) { navCoreOnFrameMark(&app->core, t_ms); }

/* uv: u0, v0, u1, v1, ...; ids and points (x0, y0, ...) of the taken detections out. Returns their number. */
int32_t navHostOnFrame(NavHostApp* app, int32_t t_ms, const double* uv, int32_t count, const double* pose,
                       int32_t* ids, double* points) {
  NavDetection detections[NAV_MAX_FRAME_DETECTIONS];
  const int32_t n = count < NAV_MAX_FRAME_DETECTIONS ? count : NAV_MAX_FRAME_DETECTIONS;
  for (int32_t i = 0; i < n; i++) {
    detections[i].u = uv[2 * i];
    detections[i].v = uv[2 * i + 1];
  }
  const NavPose p = pose6(pose);
  const int32_t taken = navCoreOnFrame(&app->core, t_ms, detections, n, &p);
  for (int32_t i = 0; i < taken; i++) {
    ids[i] = app->core.last_frame_ids[i];
    points[2 * i] = app->core.last_frame_points[i][0];
    points[2 * i + 1] = app->core.last_frame_points[i][1];
  }
  return taken;
}

/* The camera input: returns bytes consumed; *frame_done when a frame was handed to the core. */
int32_t navHostFeed(NavHostApp* app, const uint8_t* data, int32_t length, int32_t t_ms, const double* pose,
                    int32_t pose_valid, int32_t* frame_done) {
  const NavPose p = pose6(pose);
  bool done = false;
  const size_t used = navCameraInputFeed(&app->input, &app->core, data, (size_t)length, t_ms, &p, pose_valid != 0,
                                         &done);
  *frame_done = done ? 1 : 0;
  return (int32_t)used;
}

int32_t navHostEndBatch(NavHostApp* app, int32_t t_ms, const double* pose, int32_t pose_valid) {
  const NavPose p = pose6(pose);
  return navCameraInputEndBatch(&app->input, &app->core, t_ms, &p, pose_valid != 0) ? 1 : 0;
}

/* The frame last handed over: uv (u0, v0, ...), ids, world points. Returns its length. */
int32_t navHostLastFrame(const NavHostApp* app, double* uv, int32_t* ids, double* points) {
  const int32_t n = app->input.last_frame_length;
  for (int32_t i = 0; i < n; i++) {
    uv[2 * i] = app->input.last_frame[i].u;
    uv[2 * i + 1] = app->input.last_frame[i].v;
    ids[i] = app->core.last_frame_ids[i];
    points[2 * i] = app->core.last_frame_points[i][0];
    points[2 * i + 1] = app->core.last_frame_points[i][1];
  }
  return n;
}

void navHostStatus(const NavHostApp* app, NavHostStatus* s) {
  const NavCore* c = &app->core;
  memset(s, 0, sizeof(*s));
  s->phase = (int32_t)c->phase;
  s->target_id = c->target_id;
  s->waypoint_index = c->waypoint_index;
  s->num_trees = c->memory.num_trees;
  s->num_visited = c->memory.num_visited;
  s->captured = c->captured;
  s->link_lost = c->link_lost;
  s->link_aborted = c->link_aborted;
  s->counters = c->counters;
  s->evicted = c->memory.evicted;
  s->forgotten = c->memory.visited_forgotten;
  s->lines_dropped = app->input.assembler.dropped;
  s->other_labels = app->input.other_labels;
  s->frames = app->input.frames;
  s->frame_overflow = app->input.frame_overflow;
  s->unstored = c->memory.unstored;
  s->pending_detections = app->input.frame_length;
  s->revisiting = c->revisiting;
  s->events_dropped = c->events_dropped;
  s->err_u = c->pixel_error[0];
  s->err_v = c->pixel_error[1];
  const NavTree* target = navCoreTarget(c);
  s->has_target = target != NULL;
  s->target_x = target != NULL ? target->x : 0.0;
  s->target_y = target != NULL ? target->y : 0.0;
}

/* Rows of T_d (visited false: id, x, y, hits, last_ms; 5 doubles each) or of the visited list (id, x, y, t_ms,
 * reached, revisit; 6 doubles each) into out; returns their number. */
static int32_t memoryRows(const NavTreeMemory* m, bool visited, double* out, int32_t max_rows) {
  const int32_t count = visited ? m->num_visited : m->num_trees;
  const int32_t n = count < max_rows ? count : max_rows;
  for (int32_t i = 0; i < n; i++) {
    if (visited) {
      const NavVisited* e = &m->visited[i];
      const double row[6] = {e->id, e->x, e->y, e->t_ms, e->reached, e->revisit};
      memcpy(out + 6 * i, row, sizeof(row));
    } else {
      const NavTree* t = &m->trees[i];
      const double row[5] = {t->id, t->x, t->y, t->hits, t->last_ms};
      memcpy(out + 5 * i, row, sizeof(row));
    }
  }
  return n;
}

int32_t navHostTrees(const NavHostApp* app, double* out, int32_t max_rows) {
  return memoryRows(&app->core.memory, false, out, max_rows);
}

int32_t navHostVisited(const NavHostApp* app, double* out, int32_t max_rows) {
  return memoryRows(&app->core.memory, true, out, max_rows);
}

/* Pops the oldest event: its console line into text, kind / tree id / x / y / t out. 0: none left. */
int32_t navHostNextEvent(NavHostApp* app, char* text, int32_t size, int32_t* kind, int32_t* tree_id, double* xy,
                         int32_t* t_ms, char* detail, int32_t detail_size) {
  NavEvent e;
  if (navCoreDrainEvents(&app->core, &e, 1) == 0) {
    return 0;
  }
  navFormatEvent(&e, text, (size_t)size);
  *kind = (int32_t)e.kind;
  *tree_id = e.tree_id;
  xy[0] = e.x;
  xy[1] = e.y;
  *t_ms = e.t_ms;
  navFormatEventDetail(&e, detail, (size_t)detail_size);
  return 1;
}

int32_t navHostParseLine(const char* line, int32_t length, char* label, int32_t label_size, double* xywh) {
  const NavMessage m = navParseLine(line, length);
  strncpy(label, m.label, (size_t)label_size - 1);
  label[label_size - 1] = '\0';
  xywh[0] = m.x;
  xywh[1] = m.y;
  xywh[2] = m.w;
  xywh[3] = m.h;
  return (int32_t)m.kind;
}

int32_t navHostFormatFixed(char* out, int32_t size, double value, int32_t decimals) {
  return navFormatFixed(out, (size_t)size, value, decimals);
}

int32_t navHostMaxFrameDetections(void) { return NAV_MAX_FRAME_DETECTIONS; }
int32_t navHostSizeofParams(void) { return (int32_t)sizeof(NavParams); }
