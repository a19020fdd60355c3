"""The JeVois engine's part of running a Python module: load it, set its parameters, push frames through it.

The module is loaded the JeVois way (jevois/src/jevois/Core/PythonWrapper.C): the stand-in bindings are
installed as ``libjevois``, the module folder is appended to ``sys.path``, ``import <Module>`` (then
reloaded, as the engine does), the class is constructed with no arguments, ``init()`` runs, then the
``params`` (like the module's params.cfg) are applied.

Each load starts from clean bindings (``libjevois.reset()``) and each runner counts its own frames, so a
run never sees what an earlier run in the same process left behind. On the host several module folders may be
loaded in one process (the repository's, a card copy, a test's modified copy): the folder being loaded goes
first on ``sys.path`` and a module of the same name loaded from another folder is dropped from
``sys.modules`` first, so the files of the folder asked for are the ones that run.

This file runs on the host and in the camera's own runtime (Python 3.7, see ``camera_driver.py``): keep it
to the 3.7 subset and the standard library.
"""
from __future__ import annotations

import importlib
import os
import sys
from typing import Any

try:
    from host_tools.jevois_host import libjevois as standin
except ImportError:  # in the camera runtime, where this folder itself is on sys.path
    import libjevois as standin

class NullLog:
    """A log stream that drops the module's LINFO/LERROR lines (runs that only want the serial output)."""

    def write(self, text: str) -> None:
        pass


DEFAULT_MODULE_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                                  "jevois_module", "ForaNavTrees")


def load_module(module_dir: str | None = None, serial_stream: Any = None, params: dict | None = None,
                log_stream: Any = None) -> tuple[Any, Any]:
    """Load a JeVois Python module folder -> (instance, the libjevois stand-in module)."""
    module_dir = os.path.abspath(module_dir or DEFAULT_MODULE_DIR)
    name = os.path.basename(module_dir.rstrip(os.sep))
    if not os.path.isfile(os.path.join(module_dir, name + ".py")):
        raise FileNotFoundError("no %s.py in %s" % (name, module_dir))
    standin.reset()
    standin.configure(serial_stream=serial_stream, log_stream=log_stream)
    sys.modules["libjevois"] = standin
    _use_folder(module_dir)
    module = importlib.reload(sys.modules[name]) if name in sys.modules else importlib.import_module(name)
    instance = getattr(module, name)()
    if hasattr(instance, "init"):
        instance.init()
    for key, value in (params or {}).items():
        setpar(instance, key, value)
    return instance, standin


def _loaded_from(module, folder: str) -> bool:
    path = getattr(module, "__file__", None)
    return path is not None and os.path.dirname(os.path.abspath(path)) == folder


def _use_folder(module_dir: str) -> None:
    """Make the files of ``module_dir`` the ones ``import`` finds by plain name (the camera's way)."""
    if module_dir in sys.path:
        sys.path.remove(module_dir)
    sys.path.insert(0, module_dir)
    for filename in sorted(os.listdir(module_dir)):
        plain = filename[:-3]
        if filename.endswith(".py") and filename != "__init__.py":
            loaded = sys.modules.get(plain)
            if loaded is not None and not _loaded_from(loaded, module_dir):
                del sys.modules[plain]  # another folder's copy, from an earlier load


def setpar(instance: object, name: str, value: Any) -> None:
    """The engine's ``setpar <name> <value>`` for a module parameter (KeyError if there is none)."""
    parameters = standin.parameters(instance)
    if name not in parameters:
        raise KeyError("no parameter %r (have: %s)" % (name, ", ".join(sorted(parameters))))
    parameters[name].set(value)


def getpar(instance: object, name: str) -> Any:
    """The engine's ``getpar <name>``."""
    return standin.parameters(instance)[name].get()


class FrameLines:
    """Serial sink: records the lines of the current frame and forwards them to the caller's stream."""

    def __init__(self, stream: Any):
        self.stream = stream
        self.buffer = ""
        self.lines = []

    def write(self, text: str) -> None:
        self.buffer += text
        while "\r\n" in self.buffer:
            line, self.buffer = self.buffer.split("\r\n", 1)
            self.lines.append(line)
        if self.stream is not None:
            try:
                self.stream.write(text)
            except TypeError:
                self.stream.write(text.encode("ascii", "replace"))
            if hasattr(self.stream, "flush"):
                self.stream.flush()


class ModuleRunner:
    """Push frames through the camera module as the JeVois engine does, one frame at a time."""

    def __init__(self, module_dir: str | None = None, serial_stream: Any = None, params: dict | None = None,
                 output_size: tuple | None = None, log_stream: Any = None):
        self._sink = FrameLines(serial_stream)
        self._log_stream = log_stream
        self.instance, self.jevois = load_module(module_dir, self._sink, params, log_stream)
        self.output_size = output_size  # (width, height) of the USB output; None = same as the input
        self.output_image = None
        self.frame_number = 0  # this runner's frameNum(), not the process's

    def _bind(self) -> None:
        # The bindings' state is process-wide (as on the camera): point it at this runner before the module
        # runs, so that several runners in one process neither send into each other's streams nor share a
        # frame count.
        self.jevois.configure(serial_stream=self._sink, log_stream=self._log_stream)
        self.jevois.set_frame_number(self.frame_number)

    def process_frame(self, bgr: Any, with_usb: bool = False) -> list:
        """Run process() (with_usb) or processNoUSB() on one BGR frame -> the serial lines it sent."""
        self._sink.lines = []
        self._bind()
        inframe = self.jevois.InputFrame(bgr)
        if with_usb:
            width, height = self.output_size or (bgr.shape[1], bgr.shape[0])
            outframe = self.jevois.OutputFrame(width, height)
            self.instance.process(inframe, outframe)
            self.output_image = outframe.image
        else:
            self.instance.processNoUSB(inframe)
        self.frame_number += 1
        return list(self._sink.lines)

    def setpar(self, name: str, value: Any) -> None:
        setpar(self.instance, name, value)

    def getpar(self, name: str) -> Any:
        return getpar(self.instance, name)

    def command(self, line: str) -> str:
        """A console line the engine does not know, handed to the module's parseSerial."""
        self._bind()
        return self.instance.parseSerial(line)
