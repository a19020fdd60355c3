"""foranav: the ForaNav command line.

Usage: foranav <command> [options]   (foranav <command> --help for each)

Each command lives in its own module, imported only when it runs, which exposes
``add_arguments(parser)`` and ``run(args) -> int``. Bad input never gives a traceback (docs/errors.md): a
ForaNavError or an argument error prints one line naming the file or option and exits with status 2. A
reader that goes away (``foranav train ... | head``) does not stop the work: the rest of the output is
dropped and the command still writes its files.
"""
import argparse
import importlib
import os
import sys
from types import ModuleType
from typing import Any, NoReturn, TextIO

from host_tools import argtypes
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
    "split": ("host_tools.detection.cmd_split", "split annotated imagery by image into train and held-out CSVs"),
    "fly": ("host_tools.flight.cmd_fly", "fly a map with the Crazyflie app on the emulated firmware"),
    "crazyflie": ("host_tools.flight.cmd_crazyflie", "serve idle emulated Crazyflies a client flies (cflib, swarms)"),
    "paper-tests": ("host_tools.flight.cmd_paper_tests", "run the paper's flight Tests 1-9"),
    "replay": ("host_tools.flight.cmd_replay", "replay a recorded clip through both halves"),
    "plantation": ("host_tools.cmd_plantation", "write a random plantation map (columns, gaps, look-alikes, ...)"),
    "sweep": ("host_tools.sweep.cmd_sweep", "fly thousands of random plantations on Dask; store, report"),
    "bench": ("host_tools.cmd_bench", "benchmarks that print figures: foranav bench {sim,detector,flight,sweep,recall,crtp}"),
    "deploy": ("host_tools.deploy.cmd_deploy", "install the camera module on a JeVois microSD card"),
    "package": ("host_tools.deploy.cmd_package", "build a .jvpkg package of the camera module"),
    "serial-check": ("host_tools.deploy.serial_check", "listen to the camera's serial output and check it"),
}


class OneLineParser(argparse.ArgumentParser):
    """An argument error is one line naming the option (argparse prints the whole usage first)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, "%s: error: %s (see %s --help)\n" % (self.prog, message, self.prog))


class _StdoutGuard:
    """stdout that survives its reader going away: after a broken pipe the output goes to /dev/null."""

    def __init__(self, stream: TextIO):
        self._stream = stream
        self.broken = False

    def _silence(self) -> None:
        self.broken = True
        try:
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, self._stream.fileno())  # the interpreter's final flush then succeeds too
            os.close(devnull)
        except (OSError, ValueError, AttributeError):
            self._stream = open(os.devnull, "w")

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            self._silence()
            return len(text)

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            self._silence()

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


def _check_seed(parser: argparse.ArgumentParser, args: argparse.Namespace) -> None:
    """Every command's --seed is a seed (0 .. 2**32 - 1), also where the option is declared as a plain int."""
    value = getattr(args, "seed", None)
    if isinstance(value, int) and not 0 <= value <= argtypes.SEED_MAX:
        parser.error("argument --seed: must be an integer from 0 to %d, got %d" % (argtypes.SEED_MAX, value))


def _check_empty_values(parser: argparse.ArgumentParser, args: argparse.Namespace, argv: list[str]) -> None:
    """No option or argument takes an empty text: `--out ''` is no folder, `--tests ''` no test list (argparse
    would pass '' on, and a command would take it for "not given" and use its default)."""
    for dest, value in sorted(vars(args).items()):
        if value == parser.get_default(dest):  # a default of '' means "none", not a user's empty value
            continue
        values = value if isinstance(value, (list, tuple)) else [value]
        if any(isinstance(v, str) and not v.strip() for v in values):
            option = "--" + dest.replace("_", "-")
            parser.error("argument %s: empty value" % (option if option in argv else dest))


def build_parser() -> OneLineParser:
    parser = OneLineParser(prog="foranav", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", metavar="<command>")
    sub.required = True
    for name, (module, help_text) in COMMANDS.items():
        sub.add_parser(name, help=help_text, add_help=False)
    return parser


def parse_command(argv: list[str]) -> tuple[str, ModuleType, argparse.Namespace]:
    """(command name, its module, parsed args); SystemExit on --help or an argument error (one line)."""
    if not argv or argv[0] in ("-h", "--help") or argv[0] not in COMMANDS:
        build_parser().parse_args(argv)  # prints usage / error and exits
        raise SystemExit(2)
    name = argv[0]
    module = importlib.import_module(COMMANDS[name][0])
    parser = OneLineParser(prog="foranav " + name, description=module.__doc__)
    module.add_arguments(parser)
    args = parser.parse_args(argv[1:])
    _check_seed(parser, args)
    _check_empty_values(parser, args, argv)
    return name, module, args


def quiet_opencv() -> None:
    """OpenCV and its FFmpeg print warnings straight to stderr (a missing image, a damaged video) next to the
    CLI's own one-line error; set before cv2 loads. OPENCV_LOG_LEVEL / OPENCV_FFMPEG_LOGLEVEL set by the user
    still win."""
    os.environ.setdefault("OPENCV_LOG_LEVEL", "ERROR")
    os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")  # AV_LOG_QUIET


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    quiet_opencv()
    try:
        name, module, args = parse_command(argv)
    except SystemExit as done:  # --help (0) or an argument error (2), already printed
        return done.code if isinstance(done.code, int) else 2
    original = sys.stdout
    guard = sys.stdout = _StdoutGuard(original)
    try:
        return int(module.run(args) or 0)
    except ForaNavError as err:
        print("foranav %s: error: %s" % (name, " ".join(str(err).split())), file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("foranav %s: interrupted" % name, file=sys.stderr)
        return 130
    finally:
        guard.flush()  # a reader gone at the very end must not turn a finished run into an error
        if sys.stdout is guard:
            sys.stdout = original


if __name__ == "__main__":
    sys.exit(main())
