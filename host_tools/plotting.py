"""matplotlib as the figure writers use it: the Agg backend (files only, no display), chosen before pyplot
loads. ``from host_tools.plotting import plt``; figures are written with ``host_tools.fileio.write_figure``."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)
from matplotlib.collections import PatchCollection  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402

__all__ = ["Circle", "PatchCollection", "plt"]
