"""The camera's own Python runtime on the host: Python 3.7 + numpy 1.16.6 + OpenCV 4.10, in ``.venv-camera/``.

The JeVois-A33 runs the module under Python 3.7 with numpy 1.16 and OpenCV 4.10; the host venv has much newer
versions. ``build`` makes a venv from the machine's Python 3.7 once (a stamp file records what was installed,
so a second run returns at once) and ``camera_python`` returns its interpreter, for tests and tools that run
``host_tools/jevois_host/camera_driver.py`` there.

Python 3.7 is looked for in this order: ``$FORANAV_CAMERA_PYTHON``, pyenv's versions (``$PYENV_ROOT`` or
``~/.pyenv``), then ``python3.7`` on ``PATH``. ``FORANAV_NO_CAMERA_RUNTIME=1`` lets a machine without one skip
the check (CI never sets it).

Usage: python -m host_tools.jevois_host.camera_runtime build [--venv DIR]
"""
from __future__ import annotations

import argparse
import glob
import os
import shutil
import subprocess
import sys
from pathlib import Path

from host_tools.errors import ForaNavError

REPO_ROOT = Path(__file__).resolve().parents[2]
DEFAULT_VENV = REPO_ROOT / ".venv-camera"
STAMP_NAME = ".installed"
CAMERA_PYTHON_VERSION = (3, 7)
# installed in this order; OpenCV without its dependencies, which would pull a numpy newer than the camera's
REQUIREMENTS = (("numpy==1.16.6", False), ("opencv-python-headless==4.10.0.84", True))
OPT_OUT_VARIABLE = "FORANAV_NO_CAMERA_RUNTIME"
PYTHON_VARIABLE = "FORANAV_CAMERA_PYTHON"
_PROBE = "import sys; print('%d.%d' % sys.version_info[:2])"


def opted_out() -> bool:
    """True when this machine explicitly skips the camera-runtime check."""
    return os.environ.get(OPT_OUT_VARIABLE, "") == "1"


def _is_python37(candidate: str) -> bool:
    try:
        result = subprocess.run([candidate, "-c", _PROBE], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return result.returncode == 0 and result.stdout.strip() == "%d.%d" % CAMERA_PYTHON_VERSION


def _candidates() -> list[str]:
    found = []
    if os.environ.get(PYTHON_VARIABLE):
        found.append(os.environ[PYTHON_VARIABLE])
    pyenv_roots = [os.environ.get("PYENV_ROOT", ""), os.path.expanduser("~/.pyenv")]
    for root in [r for r in pyenv_roots if r]:
        found.extend(sorted(glob.glob(os.path.join(root, "versions", "3.7*", "bin", "python3.7")), reverse=True))
    on_path = shutil.which("python3.7")
    if on_path:
        found.append(on_path)
    return found


def find_python37() -> str | None:
    """The machine's Python 3.7 interpreter, or None."""
    for candidate in _candidates():
        if _is_python37(candidate):
            return candidate
    return None


def _stamp_text() -> str:
    return "".join("%s%s\n" % (req, " --no-deps" if no_deps else "") for req, no_deps in REQUIREMENTS)


def venv_python(venv: Path = DEFAULT_VENV) -> Path:
    return Path(venv) / "bin" / "python"


def is_built(venv: Path = DEFAULT_VENV) -> bool:
    stamp = Path(venv) / STAMP_NAME
    return venv_python(venv).exists() and stamp.exists() and stamp.read_text() == _stamp_text()


def _run(command: list[str], what: str) -> None:
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        last = (result.stderr.strip() or result.stdout.strip() or "no output").splitlines()[-1]
        raise ForaNavError("camera runtime: %s failed: %s" % (what, last))


def build(venv: Path = DEFAULT_VENV) -> Path:
    """Build the camera venv once (no-op when its stamp is current) -> its Python interpreter."""
    venv = Path(venv)
    if is_built(venv):
        return venv_python(venv)
    python37 = find_python37()
    if python37 is None:
        raise ForaNavError("camera runtime: no Python 3.7 found (pyenv versions/3.7*, python3.7 on PATH or "
                           "$%s); install one or set %s=1 to skip" % (PYTHON_VARIABLE, OPT_OUT_VARIABLE))
    if venv.exists():
        shutil.rmtree(venv)  # a half-built venv from an interrupted run
    _run([python37, "-m", "venv", str(venv)], "python3.7 -m venv %s" % venv)
    pip = [str(venv_python(venv)), "-m", "pip", "install", "--quiet", "--disable-pip-version-check", "--no-input"]
    for requirement, no_deps in REQUIREMENTS:
        _run(pip + (["--no-deps"] if no_deps else []) + [requirement], "pip install %s" % requirement)
    _run([str(venv_python(venv)), "-c", "import numpy, cv2"], "import numpy, cv2 in %s" % venv)
    (venv / STAMP_NAME).write_text(_stamp_text())
    return venv_python(venv)


def camera_python(venv: Path = DEFAULT_VENV) -> Path | None:
    """The camera runtime's interpreter (built if needed), or None when this machine opted out and has none."""
    if opted_out() and not is_built(venv) and find_python37() is None:
        return None
    return build(venv)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m host_tools.jevois_host.camera_runtime",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=["build"])
    parser.add_argument("--venv", type=Path, default=DEFAULT_VENV, help="venv folder (default: %(default)s)")
    args = parser.parse_args(argv)
    try:
        python = camera_python(args.venv)
    except ForaNavError as err:
        print(err, file=sys.stderr)
        return 2
    if python is None:
        print("camera runtime: skipped (%s=1 and no Python 3.7 here)" % OPT_OUT_VARIABLE)
    else:
        print("camera runtime: %s" % python)
    return 0


if __name__ == "__main__":
    sys.exit(main())
