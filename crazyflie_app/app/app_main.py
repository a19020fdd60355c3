"""appMain of both flight apps, written once: the Python app (``navigation.NavigationApp``, Python core) and
the C app (``c_app.CNavigationApp``, C core) boot, check and fly the same way, as foranav_app.c does:

wait for the system (``BOOT_DELAY_MS``), check the decks (no Flow deck: abort; no Loco deck: a warning),
resolve the ``stateEstimate`` log ids, wait for a client to write ``app.start`` = 1 when it is 0 (the
default 1 starts at once), wait ``PRE_TAKEOFF_DELAY_MS``, wait for the camera (``app.camWaitMs``),
request arming, then every 10 ms read the estimate, step the core and send its setpoint at
COMMANDER_PRIORITY_EXTRX. What differs between the apps (the core, how a pose is read, how the console prints
events and numbers) is the ``FlightApp`` each passes in.
"""
from collections.abc import Iterator
from typing import Any, Protocol

from crazyflie_app.firmware.commander import COMMANDER_PRIORITY_EXTRX, modeAbs, modeVelocity, setpoint_t
from crazyflie_app.firmware.freertos import PORT_MAX_DELAY, Delay, m2t, v_task_delay
from crazyflie_app.firmware.logparam import LOG_VARID_INVALID, PARAM_VARID_INVALID

DEBUG_MODULE = "FORANAV"
APP_TASK_PRI = 1  # CONFIG_APP_PRIORITY of the NAV-family builds
CAMERA_TASK_PRI = 1
APP_PERIOD_MS = 10  # the C main loop: vTaskDelay(M2T(10))
CAMERA_TASK_PERIOD_MS = 10  # serial polling period; reading never blocks
BOOT_DELAY_MS = 2000  # Navigation.c: wait 2 s, then check the decks
PRE_TAKEOFF_DELAY_MS = 3000  # Navigation.c: wait 3 s more before take-off
CAMERA_WAIT_POLL_MS = 10  # pre-flight camera check: how often app_main looks whether the camera was heard
START_POLL_MS = 10  # app.start 0: how often app_main looks whether a client started it
ESTIMATE_NAMES = ("x", "y", "z", "yaw", "vx", "vy")  # the stateEstimate variables a pose is read from


def set_hover_setpoint(sp: setpoint_t, vx: float, vy: float, z: float, yaw: float) -> None:
    """Body-frame velocity vx, vy (m/s), absolute height z (m) and absolute yaw (deg), as Navigation.c."""
    sp.mode.x = modeVelocity
    sp.mode.y = modeVelocity
    sp.mode.z = modeAbs
    sp.mode.yaw = modeAbs
    sp.velocity.x = vx
    sp.velocity.y = vy
    sp.position.z = z
    sp.attitude.yaw = yaw
    sp.velocity_body = True


def set_null_setpoint(sp: setpoint_t) -> None:
    """memset(&setpoint, 0, sizeof(setpoint)): every axis disabled, thrust 0 -> motors off."""
    sp.memset_zero()


def format_fixed(value: float, decimals: int) -> str:
    """The console's "%.*f" (the C app uses its core's own, as the Bolt build prints it)."""
    return "%.*f" % (decimals, value)


class FlightApp(Protocol):
    """What ``app_main`` needs of an app: the emulated Crazyflie, its core and PARAM values, its setpoint."""

    cf: Any  # firmware.system.Crazyflie
    core: Any  # navigation_core.NavigationCore or c_core.CNavigationCore
    params: Any  # app.* PARAM values: camera_wait_ms, link_hold_ms, ...
    setpoint: setpoint_t
    estimate_ids: list | None  # the stateEstimate log ids, set once resolved

    def camera_alive(self, now: int) -> bool: ...

    def read_pose(self) -> Any: ...

    def print_events(self) -> None: ...

    def format_fixed(self, value: float, decimals: int) -> str: ...

    def camera_task(self) -> Iterator[Delay]: ...


def app_init(app: FlightApp) -> None:
    """appInit(): create the app task (``app_main``) and the app's camera-input task."""
    app.cf.x_task_create(app_main(app), "APP", APP_TASK_PRI)
    app.cf.x_task_create(app.camera_task(), "CAMERA", CAMERA_TASK_PRI)


def app_main(app: FlightApp) -> Iterator[Delay]:
    """The app task (appMain): the checks, arming, then the 10 ms control loop; parks when a check fails."""
    cf = app.cf
    cf.debug_print(DEBUG_MODULE, "ForaNav app started, waiting for the system")
    yield v_task_delay(m2t(BOOT_DELAY_MS))
    if not (yield from _preflight(app)):
        yield v_task_delay(PORT_MAX_DELAY)  # appMain returned: the task parks
        return
    cf.debug_print(DEBUG_MODULE, "Armed")
    app.core.start(cf.x_task_get_tick_count())
    app.print_events()
    while True:
        command = app.core.step(cf.x_task_get_tick_count(), app.read_pose())
        if command.kind == "hover":
            set_hover_setpoint(app.setpoint, command.vx, command.vy, command.z, 0.0)
        else:
            set_null_setpoint(app.setpoint)
        cf.commander_set_setpoint(app.setpoint, COMMANDER_PRIORITY_EXTRX)
        app.print_events()
        yield v_task_delay(m2t(APP_PERIOD_MS))


def _preflight(app: FlightApp) -> Iterator[Delay]:
    """Decks, estimate ids, the camera, arming; returns (``yield from``) True when the app may fly."""
    cf = app.cf
    flow_id = cf.param_get_var_id("deck", "bcFlow2")
    loco_id = cf.param_get_var_id("deck", "bcLoco")
    if flow_id.id == PARAM_VARID_INVALID or not cf.param_get_uint(flow_id):
        cf.debug_print(DEBUG_MODULE, "No flow deck installed, aborting")
        app.core.abort_no_deck(cf.x_task_get_tick_count())
        app.print_events()
        return False
    if loco_id.id == PARAM_VARID_INVALID or not cf.param_get_uint(loco_id):
        cf.debug_print(DEBUG_MODULE, "No Loco deck: flying on Flow dead reckoning, expect drift")
    ids = [cf.log_get_var_id("stateEstimate", name) for name in ESTIMATE_NAMES]
    if LOG_VARID_INVALID in ids:
        cf.debug_print(DEBUG_MODULE, "stateEstimate not available, aborting")
        return False
    app.estimate_ids = ids
    if not app.params.start:  # on the ground, motors off, until a client (cflib, cfclient) writes app.start = 1
        cf.debug_print(DEBUG_MODULE, "Waiting for app.start = 1")
        while not app.params.start:
            yield v_task_delay(m2t(START_POLL_MS))
        cf.debug_print(DEBUG_MODULE, "Started by app.start")
    yield v_task_delay(m2t(PRE_TAKEOFF_DELAY_MS))
    waited_ms = 0
    while not app.camera_alive(cf.x_task_get_tick_count()):
        if waited_ms >= app.params.camera_wait_ms:
            # a camera never heard is a camera lost: flying the path blind would "complete" nothing
            cf.debug_print(DEBUG_MODULE, "No camera heard for %s s, not taking off"
                           % app.format_fixed(app.params.camera_wait_ms / 1000.0, 1))
            app.core.abort_no_camera(cf.x_task_get_tick_count())
            app.print_events()
            return False
        if waited_ms == 0:
            cf.debug_print(DEBUG_MODULE, "Waiting for the camera")
        yield v_task_delay(m2t(CAMERA_WAIT_POLL_MS))
        waited_ms += CAMERA_WAIT_POLL_MS
    # the last check passed. The Bolt requires arming (CONFIG_MOTORS_REQUIRE_ARMING): until armed the
    # supervisor replaces every setpoint by the null one
    if not cf.supervisor_request_arming(True):
        cf.debug_print(DEBUG_MODULE, "Arming refused by the supervisor, aborting")
        return False
    return True
