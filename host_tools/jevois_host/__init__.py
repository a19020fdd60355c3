"""Run the JeVois camera module on the host, unchanged, over images, video or rendered frames.

The module is loaded the JeVois way (see ``engine``): the stand-in bindings (``libjevois``) are installed, the
module folder goes on ``sys.path``, the class is constructed, ``init()`` runs, then the ``params`` (like the
module's params.cfg) are applied. The same two files (``engine.py``, ``libjevois.py``) also run in the camera's
own runtime, Python 3.7 + numpy 1.16 + OpenCV 4.10 (``camera_runtime``, ``camera_driver.py``).

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
from host_tools.jevois_host import libjevois
from host_tools.jevois_host.engine import DEFAULT_MODULE_DIR, ModuleRunner, NullLog, getpar, load_module, setpar

__all__ = ["DEFAULT_MODULE_DIR", "ModuleRunner", "NullLog", "getpar", "libjevois", "load_module", "setpar"]
