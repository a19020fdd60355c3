"""Serve idle emulated Crazyflies that a client flies (cflib, cfclient, Bitcraze's examples), in real time.

Each drone is the emulated Crazyflie (--plant firmware: the real firmware's commander, supervisor, PID
controller and Kalman filter; --plant reduced: the reduced model) resting on the ground of --map; without --app no
app runs: the client owns it. It arms it (cf.supervisor.send_arming_request(True)), flies it with setpoints
(cf.commander, cflib's MotionCommander), reads and writes every param and log variable the plant declares
(docs/crtp.md). Drone i of --count N serves udp://HOST:PORT+i, one process each, and starts 0.5 m to the left
of the previous one at the map's first waypoint. cflib's scan finds ports 19850-19859.

--app python|c loads the flight app (and starts its camera, --camera sim|oracle, as foranav fly): the drone
rests on the ground, motors off, its app waiting after its checks until the client writes the param
app.start = 1 (cf.param.set_value("app.start", 1)); then it flies the mission of --map as foranav fly would
(take-off 3 s later), the client watching with log blocks (app.phase, app.reached, stateEstimate.z, ...);
landed, it stays and answers. Its outputs (flight.tlog, summary.json, trajectory.png) go to --out/droneI/.

Runs until Ctrl-C, SIGTERM or --max-time-s; nothing is left running afterwards. Each drone writes its MAVLink
log to --out/droneI.tlog (default runs/crazyflie-<map>/). A crash (a ground hit faster than 2.5 m/s, a flip)
is printed; the drone then lies where it fell and still answers.

Examples:
  foranav crazyflie --plant firmware                          (then: CFLIB_URI=udp://127.0.0.1:19850 python
                                                               motion_commander_demo.py)
  foranav crazyflie --plant firmware --count 3 --crtp 19850   (a swarm: udp://127.0.0.1:19850..19852)
  foranav crazyflie --map map2 --max-time-s 60
  foranav crazyflie --plant firmware --map map1 --app python --camera oracle   (then write app.start = 1)
"""
import argparse
import sys
from pathlib import Path

from host_tools import argtypes
from host_tools.flight.client_owned import DroneSpec, check_ports, serve_drones
from host_tools.flight.cmd_fly import APP_CHOICES, CAMERA_CHOICES
from crazyflie_app.firmware.system import PLANTS
from host_tools.errors import ForaNavError
from host_tools.maps import load_map

DEFAULT_ENDPOINT = "127.0.0.1:19850"
MAX_COUNT = 10  # cflib's UDP scan covers 19850-19859


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--plant", choices=PLANTS, default="firmware",
                        help="firmware: the real firmware (make firmware-sil); reduced: the reduced model "
                             "(default firmware)")
    parser.add_argument("--crtp", type=argtypes.udp_endpoint, metavar="[HOST:]PORT", default=DEFAULT_ENDPOINT,
                        help="the first drone's UDP endpoint; drone i serves PORT+i (default %s)" % DEFAULT_ENDPOINT)
    parser.add_argument("--count", type=argtypes.int_range(1, MAX_COUNT), default=1,
                        help="number of drones, one process each (default 1, at most %d)" % MAX_COUNT)
    parser.add_argument("--map", default="map1", help="built-in map name or map file: the ground the drones "
                                                      "stand on (default map1)")
    parser.add_argument("--seed", type=argtypes.seed, default=0, help="seed of drone 0's sensor noise; drone i "
                                                                     "uses seed + i (default 0)")
    parser.add_argument("--max-time-s", type=argtypes.positive, default=None,
                        help="stop after this many seconds (default: until Ctrl-C)")
    parser.add_argument("--app", choices=APP_CHOICES, default=None,
                        help="load the flight app (python or c), waiting on the ground for the client to write "
                             "app.start = 1 (default: none, the client flies the drone)")
    parser.add_argument("--camera", choices=CAMERA_CHOICES, default="sim",
                        help="the loaded app's camera: sim (default, rendered frames + the JeVois module) or "
                             "oracle (ground-truth detector); only with --app")
    parser.add_argument("--out", default=None, help="folder for the drones' tlogs (default runs/crazyflie-<map>)")


def run(args: argparse.Namespace) -> int:
    load_map(args.map)  # a bad map is an error before any drone starts
    if args.app is None and args.camera != "sim":
        raise ForaNavError("--camera %s: only with --app (a drone without an app has no camera)" % args.camera)
    host, _, port = args.crtp.rpartition(":")
    if int(port) + args.count - 1 > 65535:
        raise ForaNavError("--crtp %s: %d drones need ports up to %d" % (args.crtp, args.count,
                                                                         int(port) + args.count - 1))
    out = Path(args.out) if args.out else Path("runs") / ("crazyflie-%s" % Path(args.map).stem)
    specs = [DroneSpec(index=i, plant=args.plant, host=host, port=int(port) + i, map=args.map, seed=args.seed,
                       out_dir=str(out), max_time_s=args.max_time_s, app=args.app, camera=args.camera)
             for i in range(args.count)]
    check_ports(specs)  # a port in use is one line before anything else
    if args.plant == "firmware":
        from crazyflie_app.firmware.sil.stack import FirmwarePlantUnavailable, check_available
        try:
            check_available()
        except FirmwarePlantUnavailable as err:
            print("foranav crazyflie: %s" % err, file=sys.stderr)
            return 2
    else:
        print("reduced plant: no firmware LOG/PARAM groups (stabilizer, kalman, pid_*, posCtlPid, ctrltarget, "
              "...): use --plant firmware for Bitcraze's examples", file=sys.stderr)
    if args.app is None:
        print("tlogs: %s/drone<i>.tlog; Ctrl-C stops every drone" % out, file=sys.stderr)
    else:
        print("app %s loaded, waiting on the ground for app.start = 1; outputs: %s/drone<i>/ (flight.tlog, "
              "summary.json, trajectory.png); Ctrl-C stops every drone" % (args.app, out), file=sys.stderr)
    return serve_drones(specs)
