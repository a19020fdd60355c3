"""Camera link watch of the navigation core.

Once the camera has sent an end-of-frame mark, a link silent for ``linkHoldMs`` while flying makes the MAV
hold position (zero velocity at the flight height) until frames come back, when the mission resumes where it
was; silent for ``linkLandMs`` it lands (LAND, then DONE with ``link_aborted``). A camera that sends no frame
marks cannot be told from one that sees nothing, so it is not watched.
"""
from crazyflie_app.app.nav_types import Counters, Event, NavigationParams

HOLD, LAND = "hold", "land"


class LinkWatch:
    """Time of the last end-of-frame mark and the lost / aborted flags."""

    def __init__(self, params: NavigationParams):
        self.params = params
        self.last_frame_ms = None  # None: not watched (no frame mark yet)
        self.link_lost = False
        self.link_aborted = False

    def on_frame_mark(self, t_ms: int) -> None:
        self.last_frame_ms = t_ms

    def check(self, t_ms: int, flying: bool, events: list[Event], counters: Counters) -> str | None:
        """HOLD while the link is silent in flight, LAND when it stays silent, else None; the decisions go
        to ``events`` (and ``counters.link_losses``)."""
        if self.last_frame_ms is None or not flying:
            return None
        silent_ms = t_ms - self.last_frame_ms
        p = self.params
        if silent_ms > p.link_land_ms:
            self.link_lost, self.link_aborted = False, True
            events.append(Event("link_lost", t_ms, detail="camera silent %.1f s: landing" % (silent_ms / 1e3)))
            return LAND
        if silent_ms > p.link_hold_ms:
            if not self.link_lost:
                self.link_lost = True
                counters.link_losses += 1
                events.append(Event("link_lost", t_ms, detail="camera silent: holding position"))
            return HOLD
        if self.link_lost:
            self.link_lost = False
            events.append(Event("link_restored", t_ms, detail="after %.1f s" % (silent_ms / 1e3)))
        return None
