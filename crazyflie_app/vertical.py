"""Take-off and landing of the navigation core: the climb is done once the height has stayed within
``takeoffTolerance`` of the flight height for ``takeoffSettle``; landing descends in two steps (Navigation.c:
``landHeight`` for ``landStep``, then ``landFinal`` for as long), then the motors stop (null setpoints)."""
from crazyflie_app.nav_types import Command, NavigationParams, Pose

NULL_COMMAND = Command("null", 0.0, 0.0, 0.0)


class TakeoffRule:
    """Is the MAV at the flight height, and has it stayed there long enough?"""

    def __init__(self, params: NavigationParams):
        self.params = params
        self._since = None

    def done(self, t_ms: int, pose: Pose) -> bool:
        if abs(pose.z - self.params.altitude_m) > self.params.takeoff_tolerance_m:
            self._since = None
        elif self._since is None:
            self._since = t_ms
        elif t_ms - self._since >= self.params.takeoff_settle_ms:
            self._since = None
            return True
        return False


def landing_setpoint(params: NavigationParams, elapsed_ms: int) -> Command | None:
    """The landing Command ``elapsed_ms`` into LAND, or None once landed (motors off)."""
    if elapsed_ms < params.land_step_ms:
        return Command("hover", 0.0, 0.0, params.land_height_m)
    if elapsed_ms < 2 * params.land_step_ms:
        return Command("hover", 0.0, 0.0, params.land_final_m)
    return None
