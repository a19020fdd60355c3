"""docs/img/crtp_cfclient_plotter.png: stock cfclient under Xvfb, connected to a --realtime flight over CRTP,
its plotter showing the climb (``make crtp-screenshot``; docs/crtp.md).

Needs the Debian packages xvfb, x11-utils, xdotool and imagemagick (and Qt's xcb libraries, libxcb-cursor0 among
them) and cfclient from PyPI in its own venv (``build/cfclient-venv``, made by the make target: cfclient pins
PyQt6 and numpy versions the project's venv does not need). The steps are what a user does by hand, clicked by
xdotool: start the flight (``--realtime --speed 0.5``), start cfclient with a log configuration of the estimate
(``stateEstimate.x/y/z`` every 100 ms) in its configuration folder, Scan, Connect, choose the configuration in the
plotter (which starts the block), watch the climb; then one screenshot of the screen.

    python -m host_tools.flight.crtp_screenshot --cfclient build/cfclient-venv/bin/cfclient --out PNG
"""
import argparse
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

DISPLAY = ":97"
SCREEN = "1400x900x24"
PORT = 19850
URI = "udp://127.0.0.1:%d" % PORT
WAIT_SERVING_S = 120.0  # the realtime camera process renders and loads before the flight starts
UI_STEP_S = 2.5  # scan, connect, choose the plotter's configuration: one step each
WINDOW_TIMEOUT_S = 60
SPEED = 0.5  # half the flight's speed: connected (3 steps) before the take-off at 5 s of flight time
SHOT_AT_FLIGHT_S = 20.0  # the climb to 1.25 m and the first metres of the path
# where cfclient 2026.8 puts its Scan and Connect buttons in a 1400x900 window (the toolbar's left end)
SCAN_BUTTON, CONNECT_BUTTON, PLOTTER_CHOICE = (390, 47), (304, 47), (700, 182)
LOG_CONFIG = {"logconfig": {"logblock": {"name": "ForaNav estimate", "period": 100, "variables": [
    {"name": "stateEstimate.%s" % axis, "type": "TOC", "stored_as": "float", "fetch_as": "float"}
    for axis in "xyz"]}}}


def _serving(timeout_s: float) -> bool:
    """True once a null packet to the flight's port is answered (the flight is running)."""
    deadline = time.monotonic() + timeout_s
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.settimeout(0.2)
        while time.monotonic() < deadline:
            try:
                probe.sendto(b"\xff", ("127.0.0.1", PORT))
                if probe.recv(64):
                    return True
            except OSError:
                time.sleep(0.2)
    return False


def _wait_for_display(env: dict, timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while subprocess.run(["xdpyinfo"], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode:
        if time.monotonic() > deadline:
            raise SystemExit("Xvfb did not start on %s" % DISPLAY)
        time.sleep(0.1)


def _click(env: dict, point: tuple[int, int]) -> None:
    subprocess.run(["xdotool", "mousemove", str(point[0]), str(point[1]), "click", "1"], env=env, check=True)


def take(cfclient: str, out: Path, speed: float, cfclient_log: Path | None = None) -> None:
    home = Path(tempfile.mkdtemp(prefix="cfclient-home-"))
    config = home / ".config" / "cfclient"
    (config / "log").mkdir(parents=True)
    (config / "log" / "ForaNav_estimate.json").write_text(json.dumps(LOG_CONFIG))
    (config / "config.json").write_text(json.dumps({"open_tabs": "Plotter", "link_uri": URI,
                                                    "window_size": [1400, 900]}))
    env = dict(os.environ, DISPLAY=DISPLAY, HOME=str(home))
    processes = []
    try:
        processes.append(subprocess.Popen(["Xvfb", DISPLAY, "-screen", "0", SCREEN], stderr=subprocess.DEVNULL))
        _wait_for_display(env)
        flight_out = home / "flight"
        processes.append(subprocess.Popen(
            [sys.executable, "-m", "host_tools.cli", "fly", "--map", "map1", "--realtime", "--speed", str(speed),
             "--crtp", str(PORT), "--out", str(flight_out)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        log = open(cfclient_log, "w") if cfclient_log else subprocess.DEVNULL
        processes.append(subprocess.Popen([cfclient], env=env, stdout=subprocess.DEVNULL, stderr=log))
        subprocess.run(["xdotool", "search", "--sync", "--name", "Crazyflie client"], env=env, check=True,
                       stdout=subprocess.DEVNULL, timeout=WINDOW_TIMEOUT_S)
        if not _serving(WAIT_SERVING_S):
            raise SystemExit("the flight never answered on %s" % URI)
        time.sleep(UI_STEP_S)  # cfclient's own scan at start-up is over
        started = time.monotonic()
        _click(env, SCAN_BUTTON)  # cfclient selects the configured link_uri when the scan finds it
        time.sleep(UI_STEP_S)
        _click(env, CONNECT_BUTTON)
        time.sleep(UI_STEP_S)
        _click(env, PLOTTER_CHOICE)  # the plotter lists the configuration; choosing it starts the block
        time.sleep(0.3)
        subprocess.run(["xdotool", "key", "Return"], env=env, check=True)
        time.sleep(max(0.0, SHOT_AT_FLIGHT_S / speed - (time.monotonic() - started)))
        out.parent.mkdir(parents=True, exist_ok=True)
        subprocess.run(["import", "-window", "root", str(out)], env=env, check=True)
    finally:
        for process in reversed(processes):
            process.terminate()
            try:
                process.wait(10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        shutil.rmtree(home, ignore_errors=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cfclient", required=True, help="the cfclient executable (its own venv)")
    parser.add_argument("--out", default="docs/img/crtp_cfclient_plotter.png")
    parser.add_argument("--speed", type=float, default=SPEED, help="the flight's --speed (default %g)" % SPEED)
    parser.add_argument("--cfclient-log", type=Path, default=None, help="keep cfclient's log (stderr) there")
    args = parser.parse_args(argv)
    take(args.cfclient, Path(args.out), args.speed, args.cfclient_log)
    print(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
