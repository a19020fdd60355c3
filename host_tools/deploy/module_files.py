"""The module folder as it goes onto the card: which files, checks that it will load on the camera, and the
generated `script.cfg` / `params.cfg`.

On the camera the folder is `modules/<Vendor>/<Module>/` and the engine imports `<Module>.py`, creates
`class <Module>`, applies `params.cfg` (module parameters, after `init()`), then runs `script.cfg` (console
commands). The host-only `__init__.py`, caches and tests stay behind.
"""
import ast
import collections
import io
import re
import zipfile
from pathlib import Path

from host_tools.deploy.modes import format_fps, format_mode, serial_lines_per_frame
from host_tools.errors import ForaNavError

MODULE_NAME = "ForaNavTrees"
DEFAULT_VENDOR = "ForaNav"
DEFAULT_MODEL = "foranav_oil_palm.npz"
CAMERA_PYTHON = (3, 7)  # JeVois-A33 1.13+ runs Python 3.7.3
# Files that make the module on the camera: code, model/data files and doc assets Inventor shows.
DEPLOYED_SUFFIXES = (".py", ".npz", ".npy", ".yaml", ".yml", ".xml", ".json", ".png")
HOST_ONLY_NAMES = ("__init__.py", "conftest.py")
HOST_ONLY_PATTERNS = (re.compile(r"^test_.*\.py$"), re.compile(r"^.*_test\.py$"))
GENERATED_NAMES = ("script.cfg", "params.cfg")
# The module's cap on trees reported per frame (ForaNavTrees.py); with the end-of-frame mark it must fit `serlimit`.
MAX_TREES_PARAMETER = "maxtrees"
MODEL_NAME_RE = re.compile(r"^foranav_\w+\.npz$")
NAME_RE = re.compile(r"^[A-Z][A-Za-z0-9_]*$")  # JeVois Inventor wants an uppercase first letter

ModuleParameter = collections.namedtuple("ModuleParameter", "name type description default")
ModulePayload = collections.namedtuple("ModulePayload", "files notes")  # files: {name: bytes}; notes: [str]


def check_name(kind, name):
    if not NAME_RE.match(name or ""):
        raise ForaNavError("%s %r: must start with an uppercase letter and use only letters, digits and _ "
                           "(JeVois Inventor's rule; it is also a folder name on the card)" % (kind, name))
    return name


def is_deployed_file(name):
    """Whether a file of the module folder goes to the camera (top level only; folders never do)."""
    if name.startswith(".") or name in HOST_ONLY_NAMES or name in GENERATED_NAMES:
        return False
    if any(pattern.match(name) for pattern in HOST_ONLY_PATTERNS):
        return False
    return name.endswith(DEPLOYED_SUFFIXES)


def read_module_folder(folder):
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


def _check_model_file(name, data):
    # A .npz is a zip archive; a Git LFS pointer or a truncated copy is not, and would only fail on the camera.
    if not zipfile.is_zipfile(io.BytesIO(data)):
        raise ForaNavError("model file %s: not a .npz archive (a Git LFS pointer or a damaged copy?)" % name)


def validate_module(files, module_name=MODULE_NAME, default_model=DEFAULT_MODEL):
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
            _check_model_file(name, files[name])
    named = {text for tree in trees.values() for text in _string_constants(tree) if MODEL_NAME_RE.match(text)}
    notes = ["model file %s is named in the code but not in the module folder: that species cannot be selected "
             "on the camera" % name for name in sorted(named - set(files))]
    return trees, notes


# jevois.Parameter type names (PythonParameter.C); a call passing (name, one of these, description, default)
# is taken as a parameter definition, whether it calls jevois.Parameter directly or through a small helper.
JEVOIS_PARAMETER_TYPES = frozenset((
    "bool", "char", "byte", "uint8", "int16", "uint16", "int", "int32", "uint", "uint32", "long", "int64",
    "uint64", "float", "double", "str", "ipoint", "fpoint", "isize", "fsize", "iscalar", "fscalar"))
_UNKNOWN = object()
_PARAMETER_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def _literal(node, default=_UNKNOWN):
    try:
        return ast.literal_eval(node)
    except ValueError:
        return default


def _top_level_constants(tree):
    """NAME = <literal> assignments at the top of a file, to show defaults given as named constants."""
    constants = {}
    for node in tree.body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name):
            value = _literal(node.value)
            if value is not _UNKNOWN:
                constants[node.targets[0].id] = value
    return constants


def _resolve_default(node, constants, own_stem):
    value = _literal(node)
    if value is not _UNKNOWN:
        return value
    if isinstance(node, ast.Name):
        return constants.get(own_stem, {}).get(node.id, _UNKNOWN)
    if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
        return constants.get(node.value.id, {}).get(node.attr, _UNKNOWN)
    return _UNKNOWN


def _parameter_in_call(args, constants, own_stem):
    for i in range(len(args) - 3):
        name, kind, description = (_literal(arg, None) for arg in args[i:i + 3])
        if (isinstance(name, str) and _PARAMETER_NAME_RE.match(name) and kind in JEVOIS_PARAMETER_TYPES
                and isinstance(description, str)):
            return ModuleParameter(name, kind, description, _resolve_default(args[i + 3], constants, own_stem))
    return None


def module_parameters(trees):
    """Parameters the module defines, read from its source ({file name: ast.Module}), in source order; a
    default that is not a literal or a named constant of the module's files is _UNKNOWN (e.g. from the model)."""
    constants = {name[:-3]: _top_level_constants(tree) for name, tree in trees.items()}
    found = {}
    for name, tree in sorted(trees.items()):
        calls = sorted((node for node in ast.walk(tree) if isinstance(node, ast.Call)),
                       key=lambda node: (node.lineno, node.col_offset))
        for call in calls:
            parameter = _parameter_in_call(call.args, constants, name[:-3])
            if parameter is not None and parameter.name not in found:
                found[parameter.name] = parameter
    return list(found.values())


def _cfg_value(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def script_cfg(vendor, module_name, mode, extra_text=""):
    """Console commands run after the module loads: T2 lines to the 4-pin port, logs off it, a serial budget."""
    lines = [
        "# %s/%s script.cfg, generated by ForaNav for %s: console commands run after the module loads." % (
            vendor, module_name, format_mode(mode)),
        "# T2/MARK lines go to the 4-pin hardware port (the flight controller); log lines go nowhere, so they",
        "# cannot mix into the T2 stream. Use `setpar serlog USB` from a terminal to see the detector's logs.",
        "setpar serout Hard",
        "setpar serlog None",
        "# At most this many serial lines per frame: what 115200 baud carries at %s fps with 20 %% to spare." % (
            format_fps(mode.fps)),
        "setpar serlimit %d" % serial_lines_per_frame(mode.fps),
        "# Fixed exposure (autoexp 1 = manual; absexp at most about one frame period) if the automatic one hunts",
        "# over bright canopy; uncomment to use:",
        "#setcam autoexp 1",
        "#setcam absexp 200",
    ]
    if extra_text.strip():
        lines += ["# From the module folder's own script.cfg:", extra_text.rstrip("\r\n")]
    return "\n".join(lines) + "\n"


def serial_overrides(parameters, mode):
    """{parameter: (value, why)} the mode forces: per-frame trees the serial port cannot carry are capped, so
    the end-of-frame mark is never the line `serlimit` drops."""
    budget = serial_lines_per_frame(mode.fps)
    overrides = {}
    for parameter in parameters:
        if (parameter.name == MAX_TREES_PARAMETER and isinstance(parameter.default, int)
                and parameter.default + 1 > budget):
            overrides[parameter.name] = (budget - 1, "at %s fps the serial port carries %d lines per frame, "
                                         "end-of-frame mark included" % (format_fps(mode.fps), budget))
    return overrides


def params_cfg(vendor, module_name, parameters, extra_text="", overrides=None):
    """Module parameters applied at load (after init()). Defaults live in the code; the known ones are listed
    commented out so a user can see and change them on the card without reading the source. `overrides`
    ({name: (value, why)}) are written as active lines."""
    overrides = overrides or {}
    lines = ["# %s/%s params.cfg, generated by ForaNav: name=value lines applied when the module loads." % (
        vendor, module_name),
             "# Remove the leading # of a line to change that parameter (the values shown are the defaults)."]
    for name, (value, why) in sorted(overrides.items()):
        lines += ["# Set by ForaNav for this camera mode: %s." % why, "%s=%s" % (name, _cfg_value(value))]
    for parameter in parameters:
        lines.append("# %s (%s): %s" % (parameter.name, parameter.type, " ".join(parameter.description.split())))
        if parameter.default is _UNKNOWN:
            lines.append("#   (its default is set by the module when it loads, e.g. from the model file)")
        else:
            lines.append("#%s=%s" % (parameter.name, _cfg_value(parameter.default)))
    if extra_text.strip():
        lines += ["# From the module folder's own params.cfg:", extra_text.rstrip("\r\n")]
    return "\n".join(lines) + "\n"


def build_module_payload(files, vendor, mode, module_name=MODULE_NAME, default_model=DEFAULT_MODEL):
    """ModulePayload for modules/<Vendor>/<Module>/ on the card: the validated module files plus the generated
    script.cfg and params.cfg, and notes for the user. Pure: `files` is what read_module_folder returned."""
    check_name("vendor", vendor)
    check_name("module", module_name)
    own = {name: files[name].decode("utf-8", "replace") for name in GENERATED_NAMES if name in files}
    deployed = {name: data for name, data in files.items() if is_deployed_file(name)}
    trees, notes = validate_module(deployed, module_name, default_model)
    payload = dict(deployed)
    payload["script.cfg"] = script_cfg(vendor, module_name, mode, own.get("script.cfg", "")).encode("utf-8")
    parameters = module_parameters(trees)
    overrides = serial_overrides(parameters, mode)
    notes += ["params.cfg sets %s=%s: %s" % (name, value, why) for name, (value, why) in sorted(overrides.items())]
    payload["params.cfg"] = params_cfg(vendor, module_name, parameters, own.get("params.cfg", ""),
                                       overrides).encode("utf-8")
    return ModulePayload(dict(sorted(payload.items())), notes)


def default_module_folder():
    """The repository's camera module folder (jevois_module/ForaNavTrees)."""
    import jevois_module
    return Path(jevois_module.__file__).resolve().parent / MODULE_NAME
