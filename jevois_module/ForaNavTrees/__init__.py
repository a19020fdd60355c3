"""Host-only package marker (not deployed). On the camera, JeVois appends this folder to sys.path and the
module's helpers import each other by plain top-level name (``import foranav_features``); doing the same
here lets ``jevois_module.ForaNavTrees.foranav_*`` imports work on the host unchanged.

Each helper exists once per process: ``foranav_x`` (as the camera code imports it) and
``jevois_module.ForaNavTrees.foranav_x`` (as host code does) are one module object, not two copies whose
classes and exceptions would silently differ. The finder below answers a plain ``foranav_x`` found in this
folder with the package module (importable in any process, so pickles name it), and a package name whose
plain module was imported before this package with that plain module.
"""
import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import os
import sys

MODULE_DIR = os.path.dirname(os.path.abspath(__file__))
HELPER_PREFIX = "foranav_"
if MODULE_DIR not in sys.path:
    sys.path.append(MODULE_DIR)


def _in_this_folder(origin):
    return origin is not None and os.path.dirname(os.path.abspath(origin)) == MODULE_DIR


class _SameModuleLoader(importlib.abc.Loader):
    """Loads a name as the module already (or now) imported under its other name."""

    def __init__(self, other_name):
        self.other_name = other_name
        self.own_spec = None

    def create_module(self, spec):
        module = importlib.import_module(self.other_name)
        self.own_spec = module.__spec__
        return module

    def exec_module(self, module):
        module.__spec__ = self.own_spec  # the import system set the alias's spec; the module keeps its own


class _HelperFinder(importlib.abc.MetaPathFinder):
    def find_spec(self, fullname, path=None, target=None):
        package, _, helper = fullname.rpartition(".")
        if not helper.startswith(HELPER_PREFIX):
            return None
        if package == __name__:
            plain = sys.modules.get(helper)
            if plain is not None and _in_this_folder(getattr(plain, "__file__", None)):
                return importlib.util.spec_from_loader(fullname, _SameModuleLoader(helper))
            return None  # the package module loads from its file, as any submodule
        if package == "":
            found = importlib.machinery.PathFinder.find_spec(fullname)  # where sys.path would load it from
            if found is not None and _in_this_folder(found.origin):
                return importlib.util.spec_from_loader(fullname, _SameModuleLoader(__name__ + "." + fullname))
        return None


if not any(type(finder).__name__ == "_HelperFinder" for finder in sys.meta_path):
    sys.meta_path.insert(0, _HelperFinder())
