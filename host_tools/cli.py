"""foranav: the ForaNav command line.

Usage: foranav <command> [options]   (foranav <command> --help for each)

Each command lives in its own module, imported only when it runs, which exposes
``add_arguments(parser)`` and ``run(args) -> int``. Errors of type ForaNavError (bad input) print one line
and exit with status 2.
"""
import argparse
import importlib
import sys

from host_tools.errors import ForaNavError

# command -> (module, one-line help)
COMMANDS = {
    "demo": ("host_tools.demo", "fly Map 1 with both halves over a pty; print a summary, write plot and tlog"),
    "render": ("host_tools.sim.cmd_render", "render one camera view of a map"),
    "synth": ("host_tools.sim.cmd_synth", "write a rendered dataset (crops and annotated frames)"),
    "record": ("host_tools.sim.cmd_record", "fly the path F at constant speed and write a clip"),
    "detect": ("host_tools.detection.cmd_detect", "run the tree detector on images"),
    "train": ("host_tools.detection.cmd_train", "train a detector model from annotated CSVs"),
    "evaluate": ("host_tools.detection.cmd_evaluate", "evaluate a detector model (crop and frame level)"),
    "fly": ("host_tools.flight.cmd_fly", "fly a map with the Crazyflie app on the emulated firmware"),
    "paper-tests": ("host_tools.flight.cmd_paper_tests", "run the paper's flight Tests 1-9"),
    "replay": ("host_tools.flight.cmd_replay", "replay a recorded clip through both halves"),
    "plantation": ("host_tools.cmd_plantation", "write a random plantation map (columns, gaps, look-alikes, ...)"),
    "sweep": ("host_tools.sweep.cmd_sweep", "fly thousands of random plantations on Dask; store, report"),
    "bench": ("host_tools.cmd_bench", "benchmarks: foranav bench {sim,detector,flight}"),
    "deploy": ("host_tools.deploy.cmd_deploy", "install the camera module on a JeVois microSD card"),
    "package": ("host_tools.deploy.cmd_package", "build a .jvpkg package of the camera module"),
    "serial-check": ("host_tools.deploy.serial_check", "listen to the camera's serial output and check it"),
}


def build_parser():
    parser = argparse.ArgumentParser(prog="foranav", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", metavar="<command>")
    sub.required = True
    for name, (module, help_text) in COMMANDS.items():
        sub.add_parser(name, help=help_text, add_help=False)
    return parser


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help") or argv[0] not in COMMANDS:
        build_parser().parse_args(argv)  # prints usage / error and exits
        return 2
    name = argv[0]
    module = importlib.import_module(COMMANDS[name][0])
    parser = argparse.ArgumentParser(prog="foranav " + name, description=module.__doc__)
    module.add_arguments(parser)
    args = parser.parse_args(argv[1:])
    try:
        return int(module.run(args) or 0)
    except ForaNavError as err:
        print("foranav %s: error: %s" % (name, err), file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("foranav %s: interrupted" % name, file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
