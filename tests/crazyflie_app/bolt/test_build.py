"""Builds of the C core: the host library under -Wall -Wextra -Werror, the Bolt variant (no printf float, no
strtod: newlib-nano without syscalls) agreeing with it, and the ARM objects warning-free and free of libc
calls that the firmware cannot link. The full firmware build is `make bolt` (docs/bolt.md, .ci/run)."""
import ctypes
import random
import re
import shutil
import subprocess

import pytest

from crazyflie_app.bolt import c_core
from crazyflie_app.app.nav_types import POSE_HISTORY_LENGTH

CORE_SOURCES = tuple(name for name in c_core.SOURCES if name != "nav_host.c")  # nav_host.c: host only
BOLT_DEFINES = ("-DNAV_NO_PRINTF_FLOAT", "-DNAV_NO_STRTOD")
ARM_FLAGS = ("-mcpu=cortex-m4", "-mthumb", "-mfloat-abi=hard", "-mfpu=fpv4-sp-d16", "-fno-math-errno", "-Os",
             "-std=gnu11", "-Wall", "-Wextra", "-Werror", "-ffunction-sections", "-fdata-sections")
# what the core may take from newlib / libm on the Bolt (all linkable without syscalls or malloc)
ARM_ALLOWED_IMPORTS = {"cos", "sin", "hypot", "pow", "floor", "fabs", "fma", "memcpy", "memmove", "memset", "memcmp",
                       "strlen", "strcmp", "strncpy", "__aeabi_memcpy", "__aeabi_memmove", "__aeabi_memset",
                       "__aeabi_memclr", "__aeabi_memcpy4", "__aeabi_memclr4", "__aeabi_memset4",
                       "__aeabi_memmove4", "__aeabi_memcpy8", "__aeabi_memclr8", "__aeabi_uldivmod",
                       "__aeabi_ldivmod", "__aeabi_uidivmod", "__aeabi_uidiv", "__aeabi_idiv", "__aeabi_idivmod",
                       "__aeabi_d2ulz", "__aeabi_ul2d", "__aeabi_l2d", "__aeabi_d2lz"}


def load(path):
    lib = ctypes.CDLL(str(path))
    lib.navHostFormatFixed.argtypes = [ctypes.c_char_p, ctypes.c_int32, ctypes.c_double, ctypes.c_int32]
    lib.navHostParseLine.argtypes = [ctypes.c_char_p, ctypes.c_int32, ctypes.c_char_p, ctypes.c_int32,
                                     ctypes.POINTER(ctypes.c_double)]
    return lib


def fixed(lib, value, decimals):
    out = ctypes.create_string_buffer(48)
    lib.navHostFormatFixed(out, len(out), value, decimals)
    return out.value.decode()


def parsed(lib, line):
    label, xywh = ctypes.create_string_buffer(80), (ctypes.c_double * 4)()
    kind = lib.navHostParseLine(line, len(line), label, len(label), xywh)
    return kind, tuple(xywh)


def test_that_the_host_library_builds_warning_free_and_the_bolt_variant_formats_and_parses_alike(tmp_path):
    host = load(c_core.build_library(tmp_path / "host.so"))
    bolt = load(c_core.build_library(tmp_path / "bolt.so", extra_flags=BOLT_DEFINES))
    rng = random.Random(7)
    values = [rng.uniform(-20, 20) for _ in range(5000)] + [round(rng.uniform(-9, 9), 4) for _ in range(5000)]
    values += [0.0, -0.0004, 0.0005, 0.0015, 1.25, 2.5, -3.9, 12.3456, 0.125, 0.375]
    for decimals in (1, 2, 3):
        for value in values:
            assert fixed(bolt, value, decimals) == fixed(host, value, decimals) == "%.*f" % (decimals, value)
    lines = [b"T2 %d %d" % (rng.randint(-1000, 1000), rng.randint(-750, 750)) for _ in range(2000)]
    lines += [b"T2 %.3f %.2e" % (rng.uniform(-999, 999), rng.uniform(-700, 700)) for _ in range(2000)]
    for line in lines:
        assert parsed(bolt, line) == parsed(host, line), line


ARM_GCC = shutil.which("arm-none-eabi-gcc")


@pytest.mark.skipif(ARM_GCC is None, reason="arm-none-eabi-gcc not installed (apt-get install gcc-arm-none-eabi)")
def test_that_the_core_compiles_for_the_bolt_under_werror_and_imports_nothing_unlinkable(tmp_path):
    imports, defined = set(), set()
    for name in CORE_SOURCES:
        obj = tmp_path / name.replace(".c", ".o")
        subprocess.run([ARM_GCC, *ARM_FLAGS, *BOLT_DEFINES, "-c", str(c_core.SOURCE_DIR / name), "-o", str(obj)],
                       check=True, capture_output=True, text=True)
        for flag, names in (("-u", imports), ("--defined-only", defined)):
            symbols = subprocess.run(["arm-none-eabi-nm", flag, str(obj)], check=True, capture_output=True, text=True)
            names |= {line.split()[-1] for line in symbols.stdout.splitlines() if line.strip()}
    internal = imports & defined  # the core's own functions, called across its files
    libgcc = {name for name in imports if name.startswith("__aeabi_")}  # soft double, division: libgcc
    assert imports - internal - libgcc <= ARM_ALLOWED_IMPORTS, sorted(imports - internal - libgcc - ARM_ALLOWED_IMPORTS)
    assert not imports & {"malloc", "free", "snprintf", "printf", "strtod", "sprintf"}


def test_that_the_bolt_kbuild_builds_every_core_source_and_the_adapter():
    objects = re.findall(r"^obj-y \+= (\w+)\.o$", (c_core.SOURCE_DIR / "Kbuild").read_text(), re.M)
    adapter = {path.stem for path in c_core.SOURCE_DIR.glob("foranav_*.c")}
    assert sorted(objects) == sorted({name[:-2] for name in CORE_SOURCES} | adapter)
    assert "nav_core.c" in CORE_SOURCES and "foranav_app" in adapter


def test_that_the_committed_bolt_path_is_map1s_and_a_bad_map_is_refused(tmp_path, capsys):
    from host_tools import bolt_path

    assert (c_core.SOURCE_DIR / "foranav_path.h").read_text() == bolt_path.path_header("map1")
    assert "#define FORANAV_PATH_WAYPOINTS 4" in bolt_path.path_header("map1")
    bad = tmp_path / "bad.json"
    bad.write_text('{"name": "x", "altitude_m": 1.0, "waypoints": [[0, 0]], "trees": []}')
    assert bolt_path.main([str(bad)]) == 2
    assert "waypoints" in capsys.readouterr().err


def test_that_the_c_core_keeps_as_much_pose_history_as_the_python_core():
    # with 48 ticks against Python's 128 the cores chose different setpoints for a target last seen 0.5 s ago
    header = (c_core.SOURCE_DIR / "nav_core.h").read_text()
    defined = re.search(r"^#define NAV_POSE_HISTORY (\d+)", header, re.M)
    assert defined is not None and int(defined.group(1)) == POSE_HISTORY_LENGTH
