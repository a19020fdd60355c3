/*
 * The core's state changes that every job shares (the state machine in nav_core.c, recovery, take-off and
 * landing, the link watch): events, phases, the commands, starting and dropping a target. The lowest layer of
 * the nav_*.c files: it calls none of them but the Kalman filter and tree memory.
 */
#include "nav_internal.h"

static const double INITIAL_VELOCITY_STD = 100.0; /* px/s, PixelKalmanFilter default */

/* -- events and phases ---------------------------------------------------------------------------------- */

NavEvent* navPushEvent(NavCore* core, NavEventKind kind, int32_t t_ms, int32_t tree_id, double x, double y) {
  if (core->num_events >= NAV_MAX_EVENTS) {
    core->events_dropped++;
    return NULL;
  }
  NavEvent* e = &core->events[core->num_events++];
  *e = (NavEvent){.kind = kind, .t_ms = t_ms, .tree_id = tree_id, .x = x, .y = y}; /* a, b, n, variant: 0 */
  return e;
}

void navEnterPhase(NavCore* core, NavPhase phase, int32_t t_ms) {
  if (phase != core->phase) {
    core->phase = phase;
    core->phase_since = t_ms;
    NavEvent* e = navPushEvent(core, NAV_EVENT_PHASE, t_ms, core->target_id, 0.0, 0.0);
    if (e != NULL) {
      e->n = (int32_t)phase;
    }
  }
}

NavCommand navHover(const NavCore* core, double vx, double vy) {
  NavCommand c = {NAV_CMD_HOVER, vx, vy, core->params.altitude_m};
  return c;
}

NavCommand navNullCommand(void) {
  NavCommand c = {NAV_CMD_NULL, 0.0, 0.0, 0.0};
  return c;
}

void navDropTarget(NavCore* core) {
  core->target_id = 0;
  core->has_filter = false;
  core->captured = false;
}

/* -- the target ------------------------------------------------------------------------------------- */

const NavTree* navCoreTarget(const NavCore* core) {
  return core->target_id ? navTreesGet((NavTreeMemory*)&core->memory, core->target_id) : NULL;
}

void navStartTracking(NavCore* core, int32_t t_ms, double u, double v) {
  const NavParams* p = &core->params;
  navKalmanInit(&core->filter, u, v, p->kf_measurement_std_px, p->kf_accel_psd, INITIAL_VELOCITY_STD);
  core->has_filter = true;
  core->filter_t_ms = t_ms;
  core->has_settle_since = false;
  core->has_captured_since = false;
  core->servo_integral[0] = core->servo_integral[1] = 0.0;
  core->has_recovery_since = false;
  navEnterPhase(core, NAV_PHASE_APPROACH, t_ms);
}
