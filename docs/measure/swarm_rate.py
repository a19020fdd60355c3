"""3 drones served by `foranav crazyflie --count 3`; stock cflib flies all three (arm, hover 0.5 m for 10 s,
land) while a 100 Hz log block of stateEstimate.x/y/z streams from each; prints samples/s and the largest gap."""
import sys, threading, time
import cflib.crtp
from cflib.crazyflie import Crazyflie
from cflib.crazyflie.log import LogConfig
from cflib.crazyflie.syncCrazyflie import SyncCrazyflie
PORT = int(sys.argv[1])
cflib.crtp.init_drivers()
results = {}
def fly(i):
    stamps = []
    with SyncCrazyflie("udp://127.0.0.1:%d" % (PORT + i), cf=Crazyflie(rw_cache="/tmp/swarm_rate_cache%d" % i)) as scf:
        cf = scf.cf
        lc = LogConfig("pos", 10)
        for v in ("stateEstimate.x", "stateEstimate.y", "stateEstimate.z"): lc.add_variable(v)
        cf.log.add_config(lc); lc.data_received_cb.add_callback(lambda ts, d, _: stamps.append(ts)); lc.start()
        cf.supervisor.send_arming_request(True); time.sleep(0.5)
        t0 = time.time()
        while time.time() - t0 < 12:
            z = min(0.5, 0.1 + (time.time() - t0) * 0.2) if time.time() - t0 < 10 else 0.05
            cf.commander.send_hover_setpoint(0, 0, 0, z); time.sleep(0.02)
        cf.commander.send_stop_setpoint(); time.sleep(0.2); lc.stop()
    steady = [s for s in stamps if stamps[0] + 1000 <= s <= stamps[-1]]
    gaps = [b - a for a, b in zip(stamps, stamps[1:])]
    results[i] = (len(stamps), (stamps[-1] - stamps[0]) / 1000.0, max(gaps), sum(g > 10 for g in gaps))
threads = [threading.Thread(target=fly, args=(i,)) for i in range(3)]
[t.start() for t in threads]; [t.join() for t in threads]
for i, (n, span, gap, missed) in sorted(results.items()):
    print("drone %d: %d samples over %.2f s = %.1f Hz, largest gap %d ms, %d gaps > 10 ms" % (i, n, span, (n - 1) / span, gap, missed))
