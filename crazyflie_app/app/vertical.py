"""Take-off and landing of the navigation core: the climb is done once the height has stayed within
``takeoffTolerance`` of the flight height for ``takeoffSettle``; landing descends to ``landHeight`` for
``landStep`` (Navigation.c's first step), then from ``landFinal`` down to the ground over another ``landStep``,
then the motors stop (null setpoints).

Navigation.c held ``landFinal`` (0.15 m) and cut the motors there: on the firmware plant that drop hits the
ground at 1.7 m/s, which the crash rule (and a Bolt's landing gear) does not forgive; the ramp touches down
at the descent's speed (docs/flight-app.md)."""
from crazyflie_app.app.nav_types import Command, NavigationParams, Pose

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
        remaining = 1.0 - (elapsed_ms - params.land_step_ms) / params.land_step_ms
        return Command("hover", 0.0, 0.0, params.land_final_m * remaining)
    return None
