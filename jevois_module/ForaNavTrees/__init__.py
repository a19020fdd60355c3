"""Host-only package marker (not deployed). On the camera, JeVois appends this folder to sys.path and the
module's helpers import each other by plain top-level name (``import foranav_features``); doing the same
here lets ``jevois_module.ForaNavTrees.foranav_*`` imports work on the host unchanged."""
import os
import sys

MODULE_DIR = os.path.dirname(os.path.abspath(__file__))
if MODULE_DIR not in sys.path:
    sys.path.append(MODULE_DIR)
