"""A drone served with its flight app loaded (`foranav crazyflie --map M --app python|c`): stock cflib connects,
logs stateEstimate.z and the app's LOG vars at 10 Hz, waits WAIT_S seconds (the drone must stay on the ground),
writes app.start = 1 and watches the mission until the app reports DONE (phase 7) or a time limit; prints the
height before the start, the greatest height, the phases seen, the trees reached (app.reached) and the
tree_reached console lines.

    python docs/measure/mission_start.py URI [WAIT_S] [LIMIT_S]
"""
import sys
import threading
import time

import cflib.crtp
from cflib.crazyflie import Crazyflie
from cflib.crazyflie.log import LogConfig
from cflib.crazyflie.syncCrazyflie import SyncCrazyflie

PHASE_DONE = 7  # navigation_core.PHASE_DONE
URI = sys.argv[1]
WAIT_S = float(sys.argv[2]) if len(sys.argv) > 2 else 8.0
LIMIT_S = float(sys.argv[3]) if len(sys.argv) > 3 else 300.0

cflib.crtp.init_drivers()
samples = []  # (ms, z, phase, reached, targetId)
console = []
lock = threading.Lock()


def on_data(ms, data, _):
    with lock:
        samples.append((ms, data["stateEstimate.z"], data["app.phase"], data["app.reached"], data["app.targetId"]))


with SyncCrazyflie(URI, cf=Crazyflie(rw_cache="/tmp/mission_start_cache")) as scf:
    cf = scf.cf
    cf.console.receivedChar.add_callback(console.append)
    block = LogConfig("mission", 100)
    for name in ("stateEstimate.z", "app.phase", "app.reached", "app.targetId"):
        block.add_variable(name)
    cf.log.add_config(block)
    block.data_received_cb.add_callback(on_data)
    block.start()
    time.sleep(WAIT_S)
    with lock:
        before = max((z for _, z, _, _, _ in samples), default=None)
        phases_before = sorted({p for _, _, p, _, _ in samples})
    print("before app.start: %d samples over %.1f s, greatest z %.3f m, phases %s"
          % (len(samples), WAIT_S, before, phases_before))
    cf.param.set_value("app.start", 1)
    started = time.monotonic()
    while time.monotonic() - started < LIMIT_S:
        time.sleep(0.5)
        with lock:
            if samples and samples[-1][2] == PHASE_DONE:
                break
    time.sleep(1.0)
    block.stop()
text = "".join(console)
with lock:
    print("after app.start: greatest z %.3f m, phases %s, app.reached %d, mission %.1f s (wall)"
          % (max(z for _, z, _, _, _ in samples), sorted({p for _, _, p, _, _ in samples}),
             samples[-1][3], time.monotonic() - started))
for line in text.splitlines():
    if "tree_reached" in line or "app.start" in line:
        print("  console: " + line)
