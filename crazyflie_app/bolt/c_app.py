"""The C flight app on the emulated firmware: the C core (bolt/src, via c_core) behind the adapter of
bolt/src/foranav_app.c, written here against the emulated firmware calls.

``CNavigationApp(cf, flight_path, target_label=None)`` is what ``foranav fly --app c`` flies. Its tasks do
what ``appMain`` and the camera task of foranav_app.c do, call for call: wait for the system, check the decks,
resolve the ``stateEstimate`` log ids, wait, wait for the camera (``app.camWaitMs``), request arming, then
every 10 ms read the estimate, step the C
core and send its setpoint at COMMANDER_PRIORITY_EXTRX; the camera task reads UART2 in 64-byte chunks
(``uart2GetDataWithTimeout``) and feeds the bytes to the C camera input (line assembler, T2/N2/MARK parser,
frames), which hands each frame to the C core. PARAM and LOG tables are the Python app's (same names, same
units); the console lines are the C core's ``navFormatEvent``.

It has the interface the harness uses of ``navigation.NavigationApp`` (``start``, ``phase``, ``params``,
``core.counters``, ``link.lines_dropped``, ``target_x`` ...). The cf must have UART2 attached
(``cf.attach_uart2(path)``).
"""
from collections.abc import Iterator, Sequence

from crazyflie_app.app.app_main import CAMERA_TASK_PERIOD_MS, DEBUG_MODULE, app_init
from crazyflie_app.bolt.c_core import CFrame, CNavigationCore, CParams, c_params
from crazyflie_app.firmware.commander import setpoint_t
from crazyflie_app.firmware.freertos import Delay, m2t, v_task_delay
from crazyflie_app.firmware.system import Crazyflie
from crazyflie_app.app.navigation import LOG_TABLE, PARAM_TABLE

UART2_BAUDRATE = 115200
UART_READ_CHUNK = 64  # foranav_app.c: uint8_t buffer[64]
UART_READ_TIMEOUT_TICKS = 1


class _UartLinkStatus:
    """What the harness reads of the app's link: lines dropped for length (C assembler), port opens."""

    def __init__(self, app: "CNavigationApp"):
        self._app = app

    lines_dropped = property(lambda self: self._app.core.lines_dropped)
    opens = property(lambda self: self._app.cf.uart2.opens)

    def close(self) -> None:
        self._app.cf.uart2.close()


class CNavigationApp:
    def __init__(self, cf: Crazyflie, flight_path: Sequence[tuple[float, float]], serial_url: str | None = None,
                 params: CParams | None = None, link: object = None, target_label: str | None = None):
        if cf.uart2 is None:
            raise ValueError("CNavigationApp reads UART2: cf.attach_uart2(path) first")
        self.cf = cf
        self.target_label = target_label
        self.core = CNavigationCore(params if params is not None else c_params(), flight_path, target_label)
        self.params = self.core.params  # the C struct: PARAM writes reach the core at once
        self.link = _UartLinkStatus(self)
        self.setpoint = setpoint_t()
        self.estimate_ids = None
        self.last_detection_ms = -1
        cf.registry.register_param_group(PARAM_TABLE, self.params)
        cf.registry.register_log_group(LOG_TABLE, self)

    def start(self) -> None:
        """appInit() of foranav_app.c: its appMain (``app_main.app_main``, as the Python app's) and camera task."""
        app_init(self)

    # -- what appMain asks of the app -------------------------------------------------------------------------

    def camera_alive(self, now: int) -> bool:
        return self.core.camera_alive(now)

    def format_fixed(self, value: float, decimals: int) -> str:
        return self.core.format_fixed(value, decimals)

    def read_pose(self) -> tuple[float, ...]:
        cf = self.cf
        return tuple(cf.log_get_float(var_id) for var_id in self.estimate_ids)

    def print_events(self) -> None:
        for event in self.core.events:
            self.cf.debug_print(DEBUG_MODULE, event.text)
            self.cf.event_trigger(event.kind, tree_id=event.tree_id, x=event.x, y=event.y)
        del self.core.events[:]

    # -- the camera task --------------------------------------------------------------------------------------

    def camera_task(self) -> Iterator[Delay]:
        cf = self.cf
        cf.uart2_init(UART2_BAUDRATE)
        while True:
            now = cf.x_task_get_tick_count()
            valid = self.estimate_ids is not None
            pose = self.read_pose() if valid else None
            while True:
                data = cf.uart2_get_data_with_timeout(UART_READ_CHUNK, UART_READ_TIMEOUT_TICKS)
                if not data:
                    break
                self._frames_done(self.core.feed(data, now, pose, valid), now, pose)
            self._frames_done(self.core.end_batch(now, pose, valid), now, pose)
            self.print_events()
            yield v_task_delay(m2t(CAMERA_TASK_PERIOD_MS))

    def _frames_done(self, frames: list[CFrame], now: int, pose: tuple[float, ...] | None) -> None:
        for detections, ids, points in frames:
            self.last_detection_ms = now
            for (u, v), tree_id, (wx, wy) in zip(detections, ids, points):
                self.cf.event_trigger("detection", u=u, v=v, tree_id=tree_id, z=pose[2], x=wx, y=wy)
            self.print_events()

    # -- LOG variables ----------------------------------------------------------------------------------------

    phase = property(lambda self: self.core.phase)
    target_id = property(lambda self: self.core.target_id)
    num_trees = property(lambda self: self.core.status().num_trees)
    num_visited = property(lambda self: self.core.status().num_visited)
    waypoint_index = property(lambda self: self.core.waypoint_index)
    reached = property(lambda self: self.core.status().reached)
    recoveries = property(lambda self: self.core.status().recoveries)
    abandoned = property(lambda self: self.core.status().abandoned)
    detections = property(lambda self: self.core.status().detections)
    out_of_column = property(lambda self: self.core.status().out_of_column)
    evicted = property(lambda self: self.core.status().evicted)
    unstored = property(lambda self: self.core.status().unstored)
    duplicates = property(lambda self: self.core.status().duplicates)
    frame_overflow = property(lambda self: self.core.frame_overflow)
    pending_detections = property(lambda self: self.core.pending_detections)
    forgotten = property(lambda self: self.core.status().forgotten)
    captured = property(lambda self: int(self.core.captured))
    err_u = property(lambda self: self.core.pixel_error[0])
    err_v = property(lambda self: self.core.pixel_error[1])
    link_dropped = property(lambda self: self.core.lines_dropped)
    link_opens = property(lambda self: self.cf.uart2.opens)
    link_lost = property(lambda self: int(self.core.link_lost))
    link_losses = property(lambda self: self.core.status().link_losses)
    frames = property(lambda self: self.core.frames)
    other_labels = property(lambda self: self.core.other_labels)
    target_x = property(lambda self: self.core.target_xy[0])
    target_y = property(lambda self: self.core.target_xy[1])
