"""Run the JeVois camera module on the host, unchanged, over images, video or rendered frames.

The module is loaded the JeVois way (jevois/src/jevois/Core/PythonWrapper.C): the stand-in bindings are
installed as ``libjevois``, the module folder is appended to ``sys.path``, ``import <Module>`` (then
reloaded, as the engine does), the class is constructed with no arguments, ``init()`` runs, then the
``params`` (like the module's params.cfg) are applied.

API for harnesses::

    from host_tools.jevois_host import ModuleRunner, load_module
    runner = ModuleRunner(serial_stream=pty_or_None, params={"serstyle": "Terse"})
    lines = runner.process_frame(bgr)                  # headless (processNoUSB): ["T2 12 -40", "MARK STOP"]
    lines = runner.process_frame(bgr, with_usb=True)   # process(): runner.output_image has boxes and fps
    runner.setpar("svmthresh", 0.3); runner.getpar("svmthresh")
    reply = runner.command("foranav maxtrees 1")       # the module's parseSerial, "" or "ERR ..."

Serial lines go, CRLF-terminated, to ``serial_stream`` (text or binary, e.g. a pty master) as they are
sent; ``process_frame`` also returns them (without line endings).
"""
import importlib
import os
import sys

from host_tools.jevois_host import libjevois as _standin

DEFAULT_MODULE_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                                  "jevois_module", "ForaNavTrees")


def load_module(module_dir=None, serial_stream=None, params=None, log_stream=None):
    """Load a JeVois Python module folder -> (instance, the libjevois stand-in module)."""
    module_dir = os.path.abspath(module_dir or DEFAULT_MODULE_DIR)
    name = os.path.basename(module_dir.rstrip(os.sep))
    if not os.path.isfile(os.path.join(module_dir, name + ".py")):
        raise FileNotFoundError("no %s.py in %s" % (name, module_dir))
    _standin.configure(serial_stream=serial_stream, log_stream=log_stream)
    sys.modules["libjevois"] = _standin
    if module_dir not in sys.path:
        sys.path.append(module_dir)
    module = importlib.reload(importlib.import_module(name)) if name in sys.modules else importlib.import_module(name)
    instance = getattr(module, name)()
    if hasattr(instance, "init"):
        instance.init()
    for key, value in (params or {}).items():
        setpar(instance, key, value)
    return instance, _standin


def setpar(instance, name, value):
    """The engine's ``setpar <name> <value>`` for a module parameter (KeyError if there is none)."""
    parameters = _standin.parameters(instance)
    if name not in parameters:
        raise KeyError("no parameter %r (have: %s)" % (name, ", ".join(sorted(parameters))))
    parameters[name].set(value)


def getpar(instance, name):
    return _standin.parameters(instance)[name].get()


class _FrameLines(object):
    """Serial sink: records the lines of the current frame and forwards them to the caller's stream."""

    def __init__(self, stream):
        self.stream = stream
        self.buffer = ""
        self.lines = []

    def write(self, text):
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


class ModuleRunner(object):
    """Push frames through the camera module as the JeVois engine does, one frame at a time."""

    def __init__(self, module_dir=None, serial_stream=None, params=None, output_size=None, log_stream=None):
        self._sink = _FrameLines(serial_stream)
        self._log_stream = log_stream
        self.instance, self.jevois = load_module(module_dir, self._sink, params, log_stream)
        self.output_size = output_size  # (width, height) of the USB output; None = same as the input
        self.output_image = None

    def process_frame(self, bgr, with_usb=False):
        """Run process() (with_usb) or processNoUSB() on one BGR frame -> the serial lines it sent."""
        self._sink.lines = []
        # The bindings' streams are process-wide (as on the camera): point them at this runner's sink, so
        # that several runners in one process do not send into each other's streams.
        self.jevois.configure(serial_stream=self._sink, log_stream=self._log_stream)
        inframe = self.jevois.InputFrame(bgr)
        if with_usb:
            width, height = self.output_size or (bgr.shape[1], bgr.shape[0])
            outframe = self.jevois.OutputFrame(width, height)
            self.instance.process(inframe, outframe)
            self.output_image = outframe.image
        else:
            self.instance.processNoUSB(inframe)
        self.jevois._next_frame()
        return list(self._sink.lines)

    def setpar(self, name, value):
        setpar(self.instance, name, value)

    def getpar(self, name):
        return getpar(self.instance, name)

    def command(self, line):
        """A console line the engine does not know, handed to the module's parseSerial."""
        self.jevois.configure(serial_stream=self._sink, log_stream=self._log_stream)
        return self.instance.parseSerial(line)
