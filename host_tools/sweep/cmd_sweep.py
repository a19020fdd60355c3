"""Fly N random plantations on a Dask cluster and report how often the method fails.

Flight i of a sweep is a function of --seed and i only: a random plantation (foranav plantation's
generator and ranges, options as there) and conditions drawn from the --faults preset (none, moderate,
harsh; see docs/sweeps.md for the distributions; --condition NAME=LO:HI changes one). One Dask task per
flight: with no --scheduler a LocalCluster of --workers processes (default: one per core) is started and
shut down after; --scheduler tcp://HOST:PORT submits to a running cluster, started with

    dask scheduler --host 127.0.0.1 --port 8786
    dask worker tcp://127.0.0.1:8786 --nworkers 2 --nthreads 1     (from the project's venv and folder)

Results go to DIR/sweep.sqlite as flights finish: the same command again skips the finished flights (a
larger --count extends the sweep), a killed sweep loses only the flights in flight, and a flight that
raises is stored with its traceback. Then DIR/report.md, deviations.png and rates.png are written (the
flawless rate with a 95 % Wilson interval, failure taxonomy, deviations, rates by factor, the worst flights
each with the foranav fly command that replays it, then every failed flight with its plantation and fly
commands); --json prints the report as JSON.

Exit status 0 when every flight ran (flawless or not), 1 when some raised, 2 on bad input.

Examples:
  foranav sweep --count 500 --seed 1 --out runs/sweep-sim --camera sim
  foranav sweep --count 500 --seed 2 --out runs/sweep-moderate --faults moderate
  foranav sweep --count 50 --seed 3 --out runs/s --camera oracle --scheduler tcp://127.0.0.1:8786
  foranav sweep --out runs/sweep-sim --report-only
"""
import argparse
import dataclasses
import json
import sys
import time
from typing import TextIO
from pathlib import Path

from host_tools import argtypes, fileio
from host_tools.cmd_plantation import add_range_arguments, ranges_from_args
from host_tools.errors import ForaNavError
from host_tools.flight.cmd_fly import add_plant_argument
from host_tools.flight.components import plant_config
from host_tools.flight.vision_camera import model_option
from host_tools.maps import SPECIES
from host_tools.plantation_ranges import PlantationRanges
from host_tools.sim.cli_args import appearance_from_args
from host_tools.sweep import report as report_mod
from host_tools.sweep.conditions import FAULT_PRESETS, preset
from host_tools.sweep.runner import run_sweep
from host_tools.sweep.specs import make_specs, seed_role, stored_ranges
from host_tools.sweep.store import SweepStore

PROGRESS_EVERY_S = 10.0  # without a terminal: one progress line this often
BAR_WIDTH = 30


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--count", type=argtypes.int_range(1, 10_000_000), default=None, help="number of flights (required unless --report-only)")
    parser.add_argument("--seed", type=argtypes.seed, default=0, help="sweep seed (default 0)")
    parser.add_argument("--out", required=True, help="sweep folder: store, report, maps of the worst flights")
    parser.add_argument("--faults", choices=sorted(FAULT_PRESETS), default="none",
                        help="condition preset (default none)")
    parser.add_argument("--condition", action="append", default=[], metavar="NAME=LO:HI",
                        help="override one condition's range (estimator: flow_probability=P); repeatable")
    parser.add_argument("--camera", choices=("sim", "oracle"), default="sim",
                        help="sim (default): rendered frames + the JeVois module; oracle: ground-truth detector")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://host:port)")
    parser.add_argument("--workers", type=argtypes.int_range(1, 1024), default=None,
                        help="LocalCluster worker processes (default: one per core)")
    parser.add_argument("--app", choices=("python", "c"), default="python",
                        help="flight app of every flight: python (default) or c (the C core of crazyflie_app/bolt)")
    add_plant_argument(parser)
    parser.add_argument("--model", metavar="M", default=None,
                        help="sim: the module runs with this model file (.npz) in every flight")
    parser.add_argument("--crowns", nargs="+", action="extend", default=None, metavar="CSV",
                        help="sim: draw every plantation's trees from the boxes of these annotation CSVs "
                             "(photo crowns, docs/simulator.md)")
    parser.add_argument("--report-only", action="store_true", help="write the report of the stored flights")
    parser.add_argument("--json", action="store_true", help="print the report as one JSON object")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    add_range_arguments(parser)


def _fly_arguments(args):
    """The ``foranav fly`` arguments every flight of the sweep gets (paths absolute, files checked now)."""

    words = []
    if args.app != "python":
        words += ["--app", args.app]
    if args.plant != "reduced":
        plant_config(args.plant, None)  # built, or one line saying how
        words += ["--plant", args.plant]
    if (args.model is not None or args.crowns) and args.camera != "sim":
        raise ForaNavError("--crowns/--model: only with --camera sim (the oracle sees no pixels)")
    if args.model is not None:
        words += ["--model", str(model_option(args.model))]
    if args.crowns:
        appearance_from_args(args, SPECIES, "the sweep's plantations")  # every CSV loads, one line if not
        words += ["--crowns"] + [str(Path(path).resolve()) for path in args.crowns]
    return words


def _overrides(texts):
    out = {}
    for text in texts:
        name, sep, value = text.partition("=")
        if not sep:
            raise ForaNavError("--condition: expected NAME=LO:HI, got %r" % text)
        try:
            parts = [float(v) for v in value.split(":")]
        except ValueError:
            raise ForaNavError("--condition %s: expected numbers, got %r" % (name, value))
        out[name] = parts[0] if name == "flow_probability" else (parts[0], parts[-1])
    return out


class ProgressBar:
    """Flights done, rate and ETA on stderr: redrawn in place on a terminal, a line every 10 s otherwise."""

    def __init__(self, total: int, skipped: int, stream: TextIO | None = None):
        self.total, self.skipped = total, skipped
        self.stream = stream or sys.stderr
        self.tty = self.stream.isatty()
        self.last = 0.0

    def __call__(self, done, todo, failed, elapsed_s):
        now = time.monotonic()
        if not self.tty and done < todo and now - self.last < PROGRESS_EVERY_S:
            return
        self.last = now
        rate = done / elapsed_s if elapsed_s > 0 else 0.0
        eta = (todo - done) / rate if rate > 0 else float("nan")
        filled = int(BAR_WIDTH * done / max(todo, 1))
        text = "[%s%s] %d/%d flights  %.2f flights/s  ETA %s  %d not flawless" % (
            "#" * filled, "." * (BAR_WIDTH - filled), done + self.skipped, self.total, rate, _duration(eta), failed)
        if self.tty:
            self.stream.write("\r" + text + ("\n" if done == todo else ""))
        else:
            self.stream.write(text + "\n")
        self.stream.flush()


def _duration(seconds):
    if seconds != seconds:
        return "?"
    seconds = int(round(seconds))
    return "%dh%02dm" % (seconds // 3600, seconds % 3600 // 60) if seconds >= 3600 else \
        "%dm%02ds" % (seconds // 60, seconds % 60)


def run(args: argparse.Namespace) -> int:
    if args.report_only:
        store = SweepStore(args.out, create=False)
        counts = None
    else:
        if args.count is None or args.count < 1:
            raise ForaNavError("--count: a positive number of flights is required")
        if args.workers is not None and args.workers < 1:
            raise ForaNavError("--workers: must be >= 1")
        if args.scheduler and args.workers is not None:
            raise ForaNavError("--workers: only without --scheduler (the cluster has its own workers)")
        ranges = ranges_from_args(args)
        overrides = _overrides(args.condition)
        distributions = preset(args.faults, overrides)  # bad ranges fail before anything is written
        fly_args = _fly_arguments(args)
        identity = {"seed": args.seed, "faults": args.faults, "camera": args.camera,
                    "conditions": sorted(overrides.items()), "distributions": distributions,
                    "ranges": dataclasses.asdict(ranges)}
        if fly_args:  # only then: a plain sweep's identity is what earlier versions stored
            identity["fly_args"] = fly_args
        fileio.check_output_dir(args.out, "--out")
        store = SweepStore(args.out)
        try:
            store.check_identity(identity)
        except ForaNavError:
            store.close()
            raise
        specs = make_specs(args.count, args.seed, faults=args.faults, camera=args.camera, ranges=ranges,
                           overrides=overrides, fly_args=fly_args)
        store.start_run(sys.argv)
        finished = len(store.finished() & {s["index"] for s in specs})
        bar = None if args.quiet or args.json else ProgressBar(len(specs), finished)
        counts = run_sweep(specs, store, scheduler=args.scheduler, workers=args.workers, progress=bar)
    with store:
        identity = store.identity()
        rows = store.rows()
        if not args.report_only:
            rows = [r for r in rows if r["index"] < args.count]
    ranges = stored_ranges(identity["ranges"]) if "ranges" in identity else PlantationRanges()
    report = report_mod.build_report(rows, args.out, identity={k: identity[k] for k in ("seed", "faults", "camera")
                                                               if k in identity}, ranges=ranges)
    if counts is not None:
        report["this_run"] = counts
    report_mod.write_report(report, rows, args.out)
    if args.json:
        print(json.dumps(report, indent=2))
    else:
        print(report_mod.headline(report))
        if "seed" in identity:
            print("seed %d: a %s seed (docs/sweeps.md)" % (identity["seed"], seed_role(int(identity["seed"]))))
        print("failures: " + (", ".join("%s %d" % kv for kv in report["failures"].items() if kv[1]) or "none"))
        if counts is not None:
            print("this run: %d flown, %d skipped (already stored), %.0f s" % (counts["flown"], counts["skipped"],
                                                                             counts["wall_s"]))
        print("report: %s/report.md" % args.out)
    return 1 if report["failures"]["crash"] else 0
