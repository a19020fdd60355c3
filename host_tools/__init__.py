"""ForaNav host tools: simulator, harness, replay, training, benchmarks, deploy, plots, telemetry."""
import os

# The detector and simulator do many small matrix products; OpenBLAS worker threads only fight over the
# cores (a --camera sim flight runs ~3x faster single-threaded on a 2-core host). This must run before numpy
# is loaded, hence here: every foranav command imports this package first. The benchmarks also call
# host_tools.threads.single_threaded() for when numpy was loaded by someone else.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

# numpy asks the kernel for huge pages on every large array; a flight allocates and frees frame-sized arrays
# ~20 times a frame, and each fresh huge page is zeroed by the kernel: about a second of system time per
# vision flight (docs/results.md, "Cost of a vision flight"). Small pages cost a tenth of that.
os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")


def small_pages_for_numpy() -> None:
    """The same, for a process that loaded numpy before this package (a Dask worker)."""
    import numpy  # noqa: PLC0415  (loaded already: this only reaches its switch)
    core = getattr(numpy, "_core", None) or getattr(numpy, "core")
    core.multiarray._set_madvise_hugepage(False)
