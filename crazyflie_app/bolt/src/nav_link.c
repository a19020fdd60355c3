/*
 * The camera link watch (crazyflie_app/app/link_watch.py): hold while the camera is silent in flight, land when it
 * stays silent.
 */
#include "nav_internal.h"

void navCoreOnFrameMark(NavCore* core, int32_t t_ms) {
  core->has_last_frame_ms = true;
  core->last_frame_ms = t_ms;
}

/* Hold while the camera link is silent in flight, land when it stays silent; false: not holding. */
bool navWatchLink(NavCore* core, int32_t t_ms, NavCommand* command) {
  const bool flying = core->phase == NAV_PHASE_FOLLOW_PATH || core->phase == NAV_PHASE_RETURN_TO_PATH ||
                      core->phase == NAV_PHASE_APPROACH || core->phase == NAV_PHASE_RECOVERY;
  if (!core->has_last_frame_ms || !flying) {
    return false;
  }
  const int32_t silent_ms = t_ms - core->last_frame_ms;
  const NavParams* p = &core->params;
  if (silent_ms > p->link_land_ms) {
    core->link_lost = false;
    core->link_aborted = true;
    NavEvent* e = navPushEvent(core, NAV_EVENT_LINK_LOST, t_ms, 0, 0.0, 0.0);
    if (e != NULL) {
      e->a = (double)silent_ms / 1e3;
      e->variant = 1;
    }
    navDropTarget(core);
    navEnterPhase(core, NAV_PHASE_LAND, t_ms);
    *command = navStepLand(core, t_ms);
    return true;
  }
  if (silent_ms > p->link_hold_ms) {
    if (!core->link_lost) {
      core->link_lost = true;
      core->counters.link_losses++;
      navPushEvent(core, NAV_EVENT_LINK_LOST, t_ms, 0, 0.0, 0.0);
    }
    *command = navHover(core, 0.0, 0.0);
    return true;
  }
  if (core->link_lost) {
    core->link_lost = false;
    NavEvent* e = navPushEvent(core, NAV_EVENT_LINK_RESTORED, t_ms, 0, 0.0, 0.0);
    if (e != NULL) {
      e->a = (double)silent_ms / 1e3;
    }
  }
  return false;
}
