"""Fly the paper's Tests 1-9 (three per map) closed-loop: rendered frames, the JeVois module and the
Crazyflie app talking over a real pty. Prints the table (targets reached, non-targets visited, mean deviation
and 95 % CI, mission time, recoveries, detections per frame) and writes results.json, table.md, the Fig. 8
deviation plot (deviation.png), one plot per map with its tests' trajectories (map1_tests.png, like the
paper's Figs. 6-7) and each test's tlog, trajectory plot and summary into --out.

Exit status 0 when all tests pass the paper's criteria (every target reached exactly once, no non-target
visited, mean deviation <= 0.10 m), 1 otherwise.

Examples:
  foranav paper-tests
  foranav paper-tests --out runs/paper --json
  foranav paper-tests --tests 3,6 --jobs 1
  foranav paper-tests --crowns ../shared/data/real/oilpalm_gearth_detectree2/boxes.csv --model real.npz
  foranav paper-tests --app c
  foranav paper-tests --plant firmware
  foranav paper-tests --tests 1,4 --crtp 19850     (Test 1 on udp://127.0.0.1:19850, Test 4 on :19851)
"""
import argparse
import json
import sys
import time
from pathlib import Path

from host_tools import argtypes, fileio
from host_tools.errors import ForaNavError
from host_tools.flight import paper_tests
from host_tools.flight.cmd_fly import add_plant_argument
from host_tools.flight.components import check_crtp_endpoint, plant_config
from host_tools.flight.paper_tests import PAPER_TESTS
from host_tools.flight.registry import POSITIONINGS
from host_tools.flight.vision_camera import model_option
from host_tools.maps import load_map
from host_tools.sim.cli_args import add_appearance_arguments, appearance_from_args


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", default="runs/paper-tests", help="output folder (default runs/paper-tests/)")
    parser.add_argument("--json", action="store_true", help='print {"tests": [...]} (each the fly summary plus '
                        '"test" and "map") instead of the table')
    parser.add_argument("--tests", help="comma-separated test numbers to run (default: 1-9)")
    parser.add_argument("--jobs", type=argtypes.int_range(1, 256), default=None,
                        help="flights in parallel (default: one per CPU)")
    parser.add_argument("--model", metavar="M", default=None,
                        help="the module runs with this model file (.npz) (default: the maps' target species model)")
    add_appearance_arguments(parser)
    parser.add_argument("--app", choices=("python", "c"), default="python",
                        help="flight app: python (default) or c (the C core of crazyflie_app/bolt)")
    add_plant_argument(parser)
    parser.add_argument("--positioning", choices=POSITIONINGS, default="uwb",
                        help="uwb (default): Loco deck + Flow deck; flow: the Flow deck alone (the estimate drifts)")
    parser.add_argument("--crtp", type=argtypes.udp_endpoint, metavar="[HOST:]PORT", default=None,
                        help="each test serves CRTP for cflib/cfclient: the first on PORT, the next on PORT+1, "
                             "... (docs/crtp.md)")


def _selected(text):
    if not text:
        return PAPER_TESTS
    try:
        wanted = {int(part) for part in text.split(",") if part.strip()}
    except ValueError:
        raise ForaNavError("--tests: expected numbers like 1,3,8, got %r" % text)
    unknown = wanted - {t.number for t in PAPER_TESTS}
    if unknown or not wanted:
        raise ForaNavError("--tests: no such test %s (have 1-9)" % sorted(unknown))
    return tuple(t for t in PAPER_TESTS if t.number in wanted)


def _camera_kwargs(args, tests):
    """--crowns/--ground/--model, checked once here (the workers load them again)."""
    species = {t.species for test in tests for t in load_map(test.map).trees}
    spec, _ = appearance_from_args(args, species, "the paper maps")
    kwargs = {} if spec.default else {"appearance": spec.to_dict()}
    if args.model is not None:
        kwargs["model"] = model_option(args.model)
    return kwargs


def run(args: argparse.Namespace) -> int:
    tests = _selected(args.tests)
    fileio.check_output_dir(args.out)
    if args.jobs is not None and args.jobs < 1:
        raise ForaNavError("--jobs: must be at least 1")
    camera_kwargs = _camera_kwargs(args, tests)
    plant_config(args.plant, None)  # the firmware plant is built, or one line saying how
    if args.crtp:
        endpoints = paper_tests.crtp_endpoints(args.crtp, len(tests))
        if int(endpoints[-1].rpartition(":")[2]) > 65535:
            raise ForaNavError("--crtp %s: %d tests need ports up to %s" % (args.crtp, len(tests), endpoints[-1]))
        for endpoint in endpoints:
            check_crtp_endpoint(endpoint)
        for test, endpoint in zip(tests, endpoints):
            print("  CRTP: Test %d answers on udp://%s" % (test.number, endpoint), file=sys.stderr)
    started = time.monotonic()

    def on_result(entry):
        if not args.json:
            print("  Test %d (%s): %s in %.0f s" % (entry["test"], entry["map"], "pass" if entry["passed"]
                                                   else "FAIL", entry["wall_s"]), file=sys.stderr)

    results = paper_tests.run_tests(tests, out_dir=args.out, jobs=args.jobs, on_result=on_result,
                                    camera_kwargs=camera_kwargs, app=args.app, plant=args.plant,
                                    crtp=args.crtp, positioning=args.positioning)
    wall = round(time.monotonic() - started, 1)
    paths = paper_tests.write_outputs(results, Path(args.out), wall_s=wall, appearance=camera_kwargs.get("appearance"))
    if args.json:
        print(json.dumps({"tests": results}, indent=2))
    else:
        print("\n".join(paper_tests.table(results)))
        print("%d/%d tests pass; %.0f s wall; table %s; Fig. 8 plot %s" % (
            sum(e["passed"] for e in results), len(results), wall, paths["table"], paths["plot"]))
    return 0 if all(e["passed"] for e in results) else 1
