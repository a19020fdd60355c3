"""Host tooling of the tree detector: training, evaluation, the per-window reference, CLI commands.

The camera-side code (jevois_module/ForaNavTrees/foranav_*.py) imports its siblings by plain top-level name,
as on the JeVois; importing the package below puts that folder on sys.path first.
"""
import jevois_module.ForaNavTrees  # noqa: F401  (adds the module folder to sys.path)
