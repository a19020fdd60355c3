"""The camera module's parameters, read the way the camera reads them: by loading the module.

The module files that go onto the card are written to a scratch folder and loaded there through the `libjevois`
stand-in (`host_tools.jevois_host`), in a fresh Python process as the camera's engine does: `import <Module>`,
construct the class, `init()`. The parameters it created are then read back (name, type, description, the value
after `init()`, which is what `params.cfg` starts from), and any `name=value` setting we are asked about is
applied to them as `params.cfg` would be, so the module's own checks (type conversion and the parameter
callbacks it installs with `setCallback`) accept or refuse it.

A fresh process keeps the loaded module, its helpers (imported by plain name) and the stand-in's module-level
state out of the deploying process, and lets two module folders be probed one after the other.
"""
import contextlib
import hashlib
import io
import json
import os
import subprocess
import sys
import tempfile
import traceback
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from host_tools.errors import ForaNavError
from host_tools.jevois_host import libjevois, load_module, setpar

PROBE_TIMEOUT_S = 120
# Probing costs a Python start and a model load (~0.3 s); a deploy and its dry run ask twice with the same bytes.
_CACHE_SIZE = 16
_cache: dict = {}


@dataclass(frozen=True)
class ModuleParameter:
    """A parameter the module created in init(): `default` is its value right after init()."""
    name: str
    type: str
    description: str
    default: object
    category: str


@dataclass(frozen=True)
class ModuleProbe:
    parameters: tuple  # ModuleParameter, in creation order
    refusals: dict  # {(name, value): the module's reason} for the settings asked about that it refuses

    def parameter(self, name: str) -> "ModuleParameter | None":
        return next((p for p in self.parameters if p.name == name), None)


def _request_key(files, module_name, checks):
    digest = hashlib.sha256(module_name.encode())
    for name in sorted(files):
        digest.update(name.encode() + b"\0" + hashlib.sha256(files[name]).digest())
    digest.update(json.dumps(sorted(checks)).encode())
    return digest.hexdigest()


def _child_env():
    # The child imports host_tools from where this process has it (a worktree, an installed copy).
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
    here = str(Path(__file__).resolve().parents[2])
    env["PYTHONPATH"] = here + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    return env


def probe_module(files: dict, module_name: str, checks: Sequence = ()) -> ModuleProbe:
    """Load the module made of `files` ({file name: bytes}) and report its parameters and which of `checks`
    ([(name, value text)]) it refuses. ForaNavError (naming the module file) when it does not load."""
    checks = [tuple(check) for check in checks]
    key = _request_key(files, module_name, checks)
    if key not in _cache:
        if len(_cache) >= _CACHE_SIZE:
            _cache.pop(next(iter(_cache)))
        _cache[key] = _run_probe(files, module_name, checks)
    return _cache[key]


def _run_probe(files, module_name, checks):
    with tempfile.TemporaryDirectory(prefix="foranav-probe-") as scratch:
        folder = Path(scratch) / module_name
        folder.mkdir()
        for name, data in files.items():
            (folder / name).write_bytes(data)
        request = json.dumps({"folder": str(folder), "checks": checks})
        try:
            result = subprocess.run([sys.executable, "-m", __name__], input=request, capture_output=True,
                                    text=True, timeout=PROBE_TIMEOUT_S, cwd=scratch, env=_child_env())
        except subprocess.TimeoutExpired:
            raise ForaNavError("module file %s.py: loading it took over %d s (init() hangs?)"
                               % (module_name, PROBE_TIMEOUT_S))
    try:
        answer = json.loads(result.stdout)
    except ValueError:
        last = (result.stderr.strip().splitlines() or ["no output"])[-1]
        raise ForaNavError("module file %s.py: loading it on the host stand-in failed: %s" % (module_name, last))
    if "error" in answer:
        raise ForaNavError("module file %s.py: does not load (as the camera would load it): %s"
                           % (module_name, answer["error"]))
    parameters = tuple(ModuleParameter(**item) for item in answer["parameters"])
    refusals = {(name, value): reason for name, value, reason in answer["refusals"]}
    return ModuleProbe(parameters, refusals)


# ---------------------------------------------------------------------------------------------------------------
# The child process.

def _with_callbacks(standin):
    """The stand-in's Parameter with JeVois' `setCallback` where the stand-in has none yet: the callback sees
    the new value and raises to refuse it; a refused value leaves the old one (as the engine does)."""
    base = standin.Parameter
    if hasattr(base, "setCallback"):
        return base

    class ParameterWithCallback(base):
        def setCallback(self, callback):
            self.foranav_deploy_callback = callback

        def set(self, value):
            old = self.get()
            super().set(value)
            callback = getattr(self, "foranav_deploy_callback", None)
            if callback is not None:
                try:
                    callback(self.get())
                except Exception:
                    super().set(old)
                    raise

    return ParameterWithCallback


def _json_value(value):
    return value if isinstance(value, (bool, int, float, str)) or value is None else str(value)


def _one_line(err):
    return ("%s: %s" % (type(err).__name__, err)).splitlines()[0] if str(err) else type(err).__name__


def _describe(folder, checks):
    try:
        instance, standin = load_module(folder, log_stream=io.StringIO())
    except Exception as err:  # whatever the module raises is the module's failure to load, for one line
        where = traceback.extract_tb(err.__traceback__)[-1]
        return {"error": "%s (%s line %d)" % (_one_line(err), os.path.basename(where.filename), where.lineno)}
    parameters = standin.parameters(instance)
    described = [{"name": p.name, "type": p.type_str, "description": p.description,
                  "default": _json_value(p.get()), "category": getattr(p.category, "name", str(p.category))}
                 for p in parameters.values()]
    refusals = []
    for name, value in checks:
        if name not in parameters:
            continue
        try:
            setpar(instance, name, value)
        except Exception as err:
            refusals.append([name, value, str(err).splitlines()[0] if str(err) else type(err).__name__])
    return {"parameters": described, "refusals": refusals}


def main() -> int:
    request = json.loads(sys.stdin.read())
    libjevois.Parameter = _with_callbacks(libjevois)  # this process only: it exits after one module
    answer_stream = sys.stdout
    # Whatever the module prints must not mix into the answer.
    with contextlib.redirect_stdout(sys.stderr):
        answer = _describe(request["folder"], request["checks"])
    answer_stream.write(json.dumps(answer))
    return 0


if __name__ == "__main__":
    sys.exit(main())
