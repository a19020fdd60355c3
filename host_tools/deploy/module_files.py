"""The module folder as it goes onto the card: which files, checks that it will load on the camera, and its
`script.cfg` / `params.cfg` (generated, merged with the card's copies: module_cfg).

On the camera the folder is `modules/<Vendor>/<Module>/` and the engine imports `<Module>.py`, creates
`class <Module>`, applies `params.cfg` (module parameters, after `init()`), then runs `script.cfg` (console
commands). The host-only `__init__.py`, caches and tests stay behind. The module's parameters are read by
loading it as the camera would (module_probe), never by reading its source.
"""
import ast
import os
import io
import re
import zipfile
from dataclasses import dataclass
from pathlib import Path

import jevois_module

from host_tools.deploy import module_cfg
from host_tools.deploy.modes import CameraMode, serial_lines_per_frame
from host_tools.deploy.module_probe import probe_module
from host_tools.errors import ForaNavError
import host_tools.detection  # noqa: F401  (puts the camera module folder on sys.path)

import foranav_model

MODULE_NAME = "ForaNavTrees"
DEFAULT_VENDOR = "ForaNav"
DEFAULT_MODEL = "foranav_oil_palm.npz"
CAMERA_PYTHON = (3, 7)  # JeVois-A33 1.13+ runs Python 3.7.3
# Files that make the module on the camera: code, model/data files and doc assets Inventor shows.
DEPLOYED_SUFFIXES = (".py", ".npz", ".npy", ".yaml", ".yml", ".xml", ".json", ".png")
HOST_ONLY_NAMES = ("__init__.py", "conftest.py")
HOST_ONLY_PATTERNS = (re.compile(r"^test_.*\.py$"), re.compile(r"^.*_test\.py$"))
GENERATED_NAMES = ("script.cfg", "params.cfg")
MODEL_LOADER = "foranav_model.py"  # the detector's model reader: a folder with it holds ForaNav models
MODEL_NAME_RE = re.compile(r"^foranav_\w+\.npz$")
NAME_RE = re.compile(r"^[A-Z][A-Za-z0-9_]*$")  # JeVois Inventor wants an uppercase first letter


@dataclass(frozen=True)
class ModulePayload:
    files: dict  # {file name: bytes}, sorted by name
    notes: list  # lines for the user


MAX_NAME_CHARS = 64  # a vendor or module name: a folder on the card, in videomappings.cfg lines and paths


def check_name(kind: str, name: str) -> str:
    if len(name or "") > MAX_NAME_CHARS:
        raise ForaNavError("--%s: a name of %d characters; at most %d (a folder name on the card)"
                           % (kind, len(name), MAX_NAME_CHARS))
    if not NAME_RE.match(name or ""):
        raise ForaNavError("%s %r: must start with an uppercase letter and use only letters, digits and _ "
                           "(JeVois Inventor's rule; it is also a folder name on the card)" % (kind, name))
    return name


def is_deployed_file(name: str) -> bool:
    """Whether a file of the module folder goes to the camera (top level only; folders never do)."""
    if name.startswith(".") or name in HOST_ONLY_NAMES or name in GENERATED_NAMES:
        return False
    if any(pattern.match(name) for pattern in HOST_ONLY_PATTERNS):
        return False
    return name.endswith(DEPLOYED_SUFFIXES)


def read_module_folder(folder: str | os.PathLike) -> dict[str, bytes]:
    """Adapter: {file name: bytes} of the files in `folder` that the camera needs, plus the folder's own
    script.cfg/params.cfg if it has them (they are merged into the generated ones)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ForaNavError("module folder %s: not found" % folder)
    files = {}
    for path in sorted(folder.iterdir()):
        if path.is_file() and (is_deployed_file(path.name) or path.name in GENERATED_NAMES):
            files[path.name] = path.read_bytes()
    return files


def _parse_camera_python(name, data):
    try:
        return ast.parse(data.decode("utf-8"), filename=name, feature_version=CAMERA_PYTHON)
    except UnicodeDecodeError:
        raise ForaNavError("module file %s: not UTF-8 text" % name)
    except SyntaxError as err:
        raise ForaNavError("module file %s line %s: not valid Python 3.7 (the camera's Python): %s"
                           % (name, err.lineno, err.msg))


def _string_constants(tree):
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            yield node.value


def _defines_class(tree, class_name):
    return any(isinstance(node, ast.ClassDef) and node.name == class_name for node in tree.body)


def _check_model_file(name, data, files):
    # A .npz is a zip archive; a Git LFS pointer or a truncated copy is not, and would only fail on the camera.
    if not zipfile.is_zipfile(io.BytesIO(data)):
        raise ForaNavError("model file %s: not a .npz archive (a Git LFS pointer or a damaged copy?)" % name)
    if MODEL_LOADER in files:  # a ForaNav detector module: its models are checked whole (network, windows)
        try:
            foranav_model.load_model(io.BytesIO(data), name="model file %s" % name)
        except foranav_model.ModelFormatError as err:
            raise ForaNavError(str(err))


def validate_module(files: dict[str, bytes], module_name: str = MODULE_NAME,
                    default_model: str = DEFAULT_MODEL) -> tuple[dict[str, ast.Module], list[str]]:
    """Refuse a module that would not load on the camera; returns (parsed trees {name: ast.Module}, notes).

    Refused: no `<Module>.py` or no `class <Module>` in it; a .py that is not Python 3.7; a missing default model;
    a .npz that is not an archive. Other `foranav_*.npz` the code names but the folder lacks only get a note:
    the module loads and runs with its default model, and only selecting that species would fail.
    """
    main_file = module_name + ".py"
    if main_file not in files:
        raise ForaNavError("module folder: %s is missing" % main_file)
    trees = {name: _parse_camera_python(name, data) for name, data in sorted(files.items()) if name.endswith(".py")}
    if not _defines_class(trees[main_file], module_name):
        raise ForaNavError("module file %s: no top-level class %s (JeVois creates %s.%s())"
                           % (main_file, module_name, module_name, module_name))
    if default_model not in files:
        raise ForaNavError("model file %s: missing from the module folder (train it with `foranav train`)"
                           % default_model)
    for name in sorted(files):
        if name.endswith(".npz"):
            _check_model_file(name, files[name], files)
    named = {text for tree in trees.values() for text in _string_constants(tree) if MODEL_NAME_RE.match(text)}
    notes = ["model file %s is named in the code but not in the module folder: that species cannot be selected "
             "on the camera" % name for name in sorted(named - set(files))]
    return trees, notes


def _own_params(text):
    """{name: value} of the module folder's own params.cfg (ForaNav's values, set on the card as ours)."""
    own = {}
    for number, raw in enumerate((text or "").splitlines(), 1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if "=" not in line:
            raise ForaNavError("module folder params.cfg line %d: %r is not a name=value line" % (number, line))
        own[module_cfg.params_key(line)] = module_cfg.params_value(line)
    return own


def _check_own_params(own, probe):
    for name, value in own.items():
        if probe.parameter(name) is None:
            raise ForaNavError("module folder params.cfg: the module has no parameter %s (it has: %s)"
                               % (name, ", ".join(p.name for p in probe.parameters)))
        if (name, value) in probe.refusals:
            raise ForaNavError("module folder params.cfg: %s=%s is refused by the module (%s)"
                               % (name, value, probe.refusals[(name, value)]))


def build_module_payload(files: dict, vendor: str, mode: CameraMode, module_name: str = MODULE_NAME,
                         default_model: str = DEFAULT_MODEL, card_files: dict | None = None, force: bool = False,
                         card_label: str | None = None) -> ModulePayload:
    """ModulePayload for modules/<Vendor>/<Module>/ on the card: the validated module files plus script.cfg and
    params.cfg, and notes for the user. `files` is what read_module_folder returned; `card_files` ({name: text})
    holds the card's current params.cfg/script.cfg, whose user settings are merged in (module_cfg);
    `card_label` names that card folder in messages. Everything is checked before anything is written."""
    check_name("vendor", vendor)
    check_name("module", module_name)
    own = {name: files[name].decode("utf-8", "replace") for name in GENERATED_NAMES if name in files}
    card_files = card_files or {}
    label = (card_label or "modules/%s/%s" % (vendor, module_name)) + "/"
    deployed = {name: data for name, data in files.items() if is_deployed_file(name)}
    notes = validate_module(deployed, module_name, default_model)[1]
    own_params = _own_params(own.get("params.cfg"))
    user = module_cfg.card_params_lines(card_files.get("params.cfg"))
    checks = sorted(set(own_params.items()) | {(line.key, module_cfg.params_value(line.line))
                                               for line in user if "=" in line.line})
    probe = probe_module(deployed, module_name, checks)
    _check_own_params(own_params, probe)
    forced = module_cfg.serial_overrides(probe.parameters, mode, own_params)
    yours = {line.key for line in user}
    notes += ["params.cfg sets %s=%s: %s" % (name, value, why) for name, (value, why) in sorted(forced.items())
              if name not in own_params and name not in yours]
    params = module_cfg.merge_params(vendor, module_name, probe.parameters, forced, card_files.get("params.cfg"),
                                     probe.refusals, force, label + "params.cfg", serial_lines_per_frame(mode.fps))
    script = module_cfg.merge_script(mode, module_cfg.command_lines(own.get("script.cfg")),
                                     card_files.get("script.cfg"), label + "script.cfg")
    payload = dict(deployed)
    payload["params.cfg"] = params.text.encode("utf-8", "surrogateescape")
    payload["script.cfg"] = script.text.encode("utf-8", "surrogateescape")
    return ModulePayload(dict(sorted(payload.items())), notes + params.notes + script.notes)


def default_module_folder() -> Path:
    """The repository's camera module folder (jevois_module/ForaNavTrees)."""
    return Path(jevois_module.__file__).resolve().parent / MODULE_NAME
