/*
 * Take-off and landing (crazyflie_app/app/vertical.py).
 */
#include <math.h>

#include "nav_internal.h"

NavCommand navStepTakeoff(NavCore* core, int32_t t_ms, const NavPose* pose) {
  const NavParams* p = &core->params;
  if (fabs(pose->z - p->altitude_m) > p->takeoff_tolerance_m) {
    core->has_settle_since = false;
  } else if (!core->has_settle_since) {
    core->has_settle_since = true;
    core->settle_since = t_ms;
  } else if (t_ms - core->settle_since >= p->takeoff_settle_ms) {
    core->has_settle_since = false;
    navEnterPhase(core, NAV_PHASE_FOLLOW_PATH, t_ms);
  }
  return navHover(core, 0.0, 0.0);
}

NavCommand navStepLand(NavCore* core, int32_t t_ms) {
  const NavParams* p = &core->params;
  const int32_t elapsed = t_ms - core->phase_since;
  if (elapsed < p->land_step_ms) {
    NavCommand c = {NAV_CMD_HOVER, 0.0, 0.0, p->land_height_m};
    return c;
  }
  if (elapsed < 2 * p->land_step_ms) {
    /* down to the ground from landFinal: cutting the motors at landFinal drops the MAV at 1.7 m/s */
    const double remaining = 1.0 - (double)(elapsed - p->land_step_ms) / p->land_step_ms;
    NavCommand c = {NAV_CMD_HOVER, 0.0, 0.0, p->land_final_m * remaining};
    return c;
  }
  navEnterPhase(core, NAV_PHASE_DONE, t_ms);
  return navNullCommand();
}
