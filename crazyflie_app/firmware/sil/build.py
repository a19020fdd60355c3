"""Build the software-in-the-loop Crazyflie from the Crazyflie firmware source (never committed: GPL-3.0).

    python -m crazyflie_app.firmware.sil.build [--firmware PATH]   (``make firmware-sil`` runs it)

The firmware comes from ``--firmware``, else ``$FORANAV_FIRMWARE``, else the one
``../shared/vendor/crazyflie-firmware-*.tar.gz`` beside the repository: a tarball or a checkout of
github.com/bitcraze/crazyflie-firmware. It is unpacked into ``build/firmware-sil/``, configured for the Bolt
(``make bolt_defconfig``: arming required, brushless idle thrust), and two things are built from it:

* ``cffirmware``, the firmware's own Python bindings (SWIG; ``make bindings_python``; the ``swig`` binary comes
  from the ``swig`` package on PyPI), into ``build/firmware-sil/cffirmware/``;
* ``libforanav_sil.so``: the same firmware files the bindings compile (PID controller, power distribution,
  Kalman core and its flow/ToF/distance models, filters) plus ``commander.c``, ``supervisor.c`` /
  ``supervisor_state_machine.c`` and ``kalman_supervisor.c``, which the bindings leave out, with this
  package's plant, sensors, loop and shim (``src/``).

A stamp file holds what was built from what: a second run with the same inputs does nothing.
"""
import argparse
import hashlib
import os
import re
import shutil
import subprocess
import sys
import tarfile
from pathlib import Path

from crazyflie_app.firmware.sil import BUILD_DIR, LIBRARY, REPO

SOURCE_DIR = Path(__file__).resolve().parent / "src"
BINDINGS_DIR = BUILD_DIR / "cffirmware"
STAMP = BUILD_DIR / "stamp.txt"
FIRMWARE_GLOB = "crazyflie-firmware-*.tar.gz"
DEFAULT_VENDOR = REPO.parent / "shared" / "vendor"
HOW_TO_GET = ("get the Crazyflie firmware (git clone https://github.com/bitcraze/crazyflie-firmware --recursive, "
              "or its tarball) and pass it with --firmware PATH or FORANAV_FIRMWARE=PATH")

# the firmware's own C files, relative to its root
FIRMWARE_SOURCES = (
    "src/modules/src/commander.c",
    "src/modules/src/planner.c",
    "src/modules/src/pptraj.c",
    "src/modules/src/pptraj_compressed.c",
    "src/modules/src/supervisor_state_machine.c",
    "src/modules/src/kalman_supervisor.c",
    "src/modules/src/controller/controller_pid.c",
    "src/modules/src/controller/position_controller_pid.c",
    "src/modules/src/controller/attitude_pid_controller.c",
    "src/modules/src/power_distribution_quadrotor.c",
    "src/modules/src/axis3fSubSampler.c",
    "src/modules/src/kalman_core/kalman_core.c",
    "src/modules/src/kalman_core/mm_flow.c",
    "src/modules/src/kalman_core/mm_tof.c",
    "src/modules/src/kalman_core/mm_distance.c",
    "src/utils/src/pid.c",
    "src/utils/src/filter.c",
    "src/utils/src/num.c",
    "src/utils/src/statsCnt.c",
    "vendor/CMSIS/CMSIS/DSP/Source/BasicMathFunctions/arm_add_f32.c",
    "vendor/CMSIS/CMSIS/DSP/Source/BasicMathFunctions/arm_dot_prod_f32.c",
    "vendor/CMSIS/CMSIS/DSP/Source/BasicMathFunctions/arm_scale_f32.c",
    "vendor/CMSIS/CMSIS/DSP/Source/BasicMathFunctions/arm_sub_f32.c",
    "vendor/CMSIS/CMSIS/DSP/Source/CommonTables/arm_common_tables.c",
    "vendor/CMSIS/CMSIS/DSP/Source/FastMathFunctions/arm_cos_f32.c",
    "vendor/CMSIS/CMSIS/DSP/Source/FastMathFunctions/arm_sin_f32.c",
    "vendor/CMSIS/CMSIS/DSP/Source/MatrixFunctions/arm_mat_mult_f32.c",
    "vendor/CMSIS/CMSIS/DSP/Source/MatrixFunctions/arm_mat_scale_f32.c",
    "vendor/CMSIS/CMSIS/DSP/Source/MatrixFunctions/arm_mat_trans_f32.c",
)
FIRMWARE_INCLUDES = (
    "src/modules/interface", "src/modules/interface/controller", "src/modules/interface/kalman_core",
    "src/modules/interface/outlierfilter", "src/modules/interface/estimator", "src/hal/interface",
    "src/utils/interface", "src/utils/interface/lighthouse", "build/include/generated", "src/config",
    "src/drivers/interface", "src/platform/interface", "src/deck/interface", "vendor/CMSIS/CMSIS/DSP/Include",
    "vendor/CMSIS/CMSIS/Core/Include", "vendor/FreeRTOS/include", "vendor/FreeRTOS/portable/GCC/ARM_CM4F",
    "src/modules/src",  # sil_supervisor.c and sil_high_level.c include supervisor.c, crtp_commander_high_level.c
)
# firmware files our wrappers compile by #include (so the host reaches their statics): sil_supervisor.c,
# sil_high_level.c
INCLUDED_FIRMWARE_SOURCES = ("src/modules/src/supervisor.c", "src/modules/src/crtp_commander_high_level.c")
# ours: the plant, the sensors, the loop and the shim (sil_supervisor.c compiles supervisor.c)
OWN_SOURCES = ("sil_random.c", "sil_plant.c", "sil_sensors.c", "sil_firmware_shim.c", "sil_supervisor.c",
               "sil_high_level.c", "sil_stabilizer.c")
# the firmware files whose FreeRTOS tasks sil_stabilizer.c rewrites as one loop: their LOG/PARAM groups and the
# code that fills the variables only they log are taken from them verbatim at build time (LOOP_TABLES), so
# the loop serves the firmware's own declarations, never a copy kept here
LOOP_FILES = ("src/modules/src/stabilizer.c", "src/modules/src/estimator/estimator_kalman.c")
LOOP_TABLES = "sil_loop_tables.inc"
GENERATED_DIR = BUILD_DIR / "generated"
# stabilizer.c's compressed state and setpoint (stateEstimateZ, ctrltargetZ) and the functions that fill them
LOOP_DEFINITIONS = (r"static struct \{[^}]*\} stateCompressed;", r"static struct \{[^}]*\} setpointCompressed;",
                    r"static void compressState\(\)\s*\{.*?\n\}", r"static void compressSetpoint\(\)\s*\{.*?\n\}")
LINKER_SCRIPT = "sil_tables.ld"
CFLAGS = ("-std=gnu11", "-O2", "-fPIC", "-shared", "-DUNIT_TEST_MODE", "-fno-strict-aliasing",
          "-Wno-address-of-packed-member", "-fvisibility=default")
# DEBUG_PRINT is printf in UNIT_TEST_MODE: the console lines go to the shim's buffer instead of stdout
LDFLAGS = ("-Wl,--wrap=printf", "-Wl,--wrap=puts", "-Wl,--wrap=putchar", "-lm")


class BuildError(Exception):
    """What is missing, in one line, and how to get it."""


def find_firmware(explicit: str | os.PathLike | None = None) -> Path:
    """The firmware tarball or checkout to build from (BuildError naming what is missing)."""
    given = explicit or os.environ.get("FORANAV_FIRMWARE")
    if given:
        path = Path(given)
        if not path.exists():
            raise BuildError("firmware %s: no such file or folder; %s" % (path, HOW_TO_GET))
        return path
    found = sorted(DEFAULT_VENDOR.glob(FIRMWARE_GLOB))
    if not found:
        raise BuildError("no %s in %s; %s" % (FIRMWARE_GLOB, DEFAULT_VENDOR, HOW_TO_GET))
    return found[-1]


def _fingerprint(firmware: Path) -> str:
    digest = hashlib.sha256(str(firmware.resolve()).encode())
    if firmware.is_file():
        stat = firmware.stat()
        digest.update(("%d %d" % (stat.st_size, stat.st_mtime_ns)).encode())
    for name in sorted(os.listdir(SOURCE_DIR)) + ["shim/" + n for n in sorted(os.listdir(SOURCE_DIR / "shim"))]:
        path = SOURCE_DIR / name
        if path.is_file():
            digest.update(name.encode() + path.read_bytes())
    digest.update(" ".join(CFLAGS + LDFLAGS + FIRMWARE_SOURCES + LOOP_FILES + LOOP_DEFINITIONS).encode())
    return digest.hexdigest()


def _unpack(firmware: Path) -> Path:
    """The firmware's root folder: the checkout itself, or the tarball unpacked under BUILD_DIR."""
    if firmware.is_dir():
        root = BUILD_DIR / "crazyflie-firmware"
        if root.exists():
            shutil.rmtree(root)
        shutil.copytree(firmware, root, ignore=shutil.ignore_patterns(".git", "build"))
        return root
    unpacked = BUILD_DIR / "unpacked"
    if unpacked.exists():
        shutil.rmtree(unpacked)
    unpacked.mkdir(parents=True)
    try:
        with tarfile.open(firmware) as archive:
            archive.extractall(unpacked, filter="data")
    except (tarfile.TarError, OSError) as err:
        raise BuildError("firmware %s: cannot unpack: %s; %s" % (firmware, err, HOW_TO_GET))
    roots = [p for p in unpacked.iterdir() if (p / "src" / "modules").is_dir()]
    if len(roots) != 1:
        raise BuildError("firmware %s: no crazyflie-firmware source tree inside; %s" % (firmware, HOW_TO_GET))
    return roots[0]


def _run(command: list[str], cwd: Path, what: str, env: dict | None = None) -> None:
    result = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True)
    if result.returncode != 0:
        errors = [line.strip() for line in (result.stderr or result.stdout).splitlines() if "error" in line.lower()]
        last = errors[0] if errors else (result.stderr or result.stdout).strip().splitlines()[-1:] or [""]
        raise BuildError("%s failed (%s ...): %s" % (what, " ".join(command[:2]), "".join(last)[:300]))


def _tool_env() -> dict:
    """PATH with this interpreter's folder first: the swig package puts its binary there."""
    env = dict(os.environ)
    env["PATH"] = str(Path(sys.executable).parent) + os.pathsep + env.get("PATH", "")
    return env


def _configure(root: Path) -> None:
    if shutil.which("make") is None or shutil.which("gcc") is None:
        raise BuildError("the firmware plant needs make and gcc (apt-get install -y build-essential)")
    _run(["make", "bolt_defconfig"], root, "configuring the firmware for the Bolt")
    _run(["make", "silentoldconfig"], root, "generating the firmware's autoconf.h")


def _build_bindings(root: Path) -> None:
    env = _tool_env()
    if shutil.which("swig", path=env["PATH"]) is None:
        raise BuildError("swig not found: pip install swig (the PyPI package ships the binary) or apt-get install swig")
    _run(["make", "bindings_python", "PYTHON=%s" % sys.executable], root, "building the cffirmware bindings", env)
    if BINDINGS_DIR.exists():
        shutil.rmtree(BINDINGS_DIR)
    BINDINGS_DIR.mkdir(parents=True)
    for built in (root / "build").glob("*cffirmware*"):
        if built.suffix in (".py", ".so"):
            shutil.copy2(built, BINDINGS_DIR / built.name)


def _group_span(name: str, text: str) -> str:
    """A firmware file's LOG/PARAM tables, verbatim: from its first LOG_GROUP_START / PARAM_GROUP_START line
    to its last ..._GROUP_STOP line (in these files nothing but the tables, their comments and the #ifdefs
    around some groups lies between)."""
    starts = [m.start() for m in re.finditer(r"^\s*(LOG|PARAM)_GROUP_START\(", text, re.M)]
    stops = [m.end() for m in re.finditer(r"^\s*(LOG|PARAM)_GROUP_STOP\(\w+\)", text, re.M)]
    if not starts or not stops:
        raise BuildError("%s: no LOG_GROUP/PARAM_GROUP in this firmware version" % name)
    span = text[starts[0]:stops[-1]]
    opened = len(re.findall(r"^\s*#\s*if", span, re.M))
    if opened != len(re.findall(r"^\s*#\s*endif", span, re.M)):
        raise BuildError("%s: its LOG/PARAM tables are not a self-contained span in this firmware version" % name)
    return span


def generate_loop_tables(root: Path) -> Path:
    """sil_loop_tables.inc: the LOG/PARAM groups of LOOP_FILES and stabilizer.c's compression code, copied
    from the firmware source at build time (sil_stabilizer.c includes it after its own variables)."""
    parts = ["/* generated by crazyflie_app/firmware/sil/build.py from the firmware source: do not edit */"]
    stabilizer = (root / LOOP_FILES[0]).read_text()
    for pattern in LOOP_DEFINITIONS:
        match = re.search(pattern, stabilizer, re.S)
        if match is None:
            raise BuildError("%s: no %s in this firmware version" % (LOOP_FILES[0], pattern))
        parts.append(match.group(0))
    for name in LOOP_FILES:
        parts.append("/* from %s */" % name)
        parts.append(_group_span(name, (root / name).read_text()))
    GENERATED_DIR.mkdir(parents=True, exist_ok=True)
    path = GENERATED_DIR / LOOP_TABLES
    path.write_text("\n\n".join(parts) + "\n")
    return path


def _build_library(root: Path) -> None:
    generate_loop_tables(root)
    includes = ["-I%s" % (SOURCE_DIR / "shim"), "-I%s" % SOURCE_DIR, "-I%s" % GENERATED_DIR] + [
        "-I%s" % (root / d) for d in FIRMWARE_INCLUDES]
    sources = [str(root / s) for s in FIRMWARE_SOURCES] + [str(SOURCE_DIR / s) for s in OWN_SOURCES]
    output = LIBRARY.with_suffix(".so.tmp")
    _run(["gcc", *CFLAGS, *includes, "-o", str(output), *sources, *LDFLAGS,
          "-Wl,-T,%s" % (SOURCE_DIR / LINKER_SCRIPT)], root, "building libforanav_sil.so")
    output.replace(LIBRARY)


def build(firmware: str | os.PathLike | None = None, bindings: bool = True) -> Path:
    """Build (if anything changed) and return the library's path; BuildError says what is missing."""
    source = find_firmware(firmware)
    fingerprint = _fingerprint(source) + ("+bindings" if bindings else "")
    if LIBRARY.exists() and STAMP.exists() and STAMP.read_text().strip() == fingerprint:
        return LIBRARY
    BUILD_DIR.mkdir(parents=True, exist_ok=True)
    STAMP.unlink(missing_ok=True)
    root = _unpack(source)
    _configure(root)
    if bindings:
        _build_bindings(root)
    _build_library(root)
    STAMP.write_text(fingerprint + "\n")
    return LIBRARY


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m crazyflie_app.firmware.sil.build", description=__doc__.split("\n\n")[0])
    parser.add_argument("--firmware", help="crazyflie-firmware tarball or checkout (default: $FORANAV_FIRMWARE, "
                                           "else ../shared/vendor/%s)" % FIRMWARE_GLOB)
    parser.add_argument("--no-bindings", action="store_true", help="skip the cffirmware Python bindings")
    parser.add_argument("--if-available", action="store_true",
                        help="without a firmware source, say so and succeed (make setup: the plant is optional)")
    args = parser.parse_args(argv)
    try:
        if args.if_available and not args.firmware:
            try:
                find_firmware()
            except BuildError as err:
                print("firmware plant: not built (%s)" % err)
                return 0
        path = build(args.firmware, bindings=not args.no_bindings)
    except BuildError as err:
        print("firmware plant: %s" % err, file=sys.stderr)
        return 2
    print("firmware plant: %s" % path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
