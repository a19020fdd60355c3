"""ForaNav host tools: simulator, harness, replay, training, benchmarks, deploy, plots, telemetry."""
import os

# The detector and simulator do many small matrix products; OpenBLAS worker threads only fight over the
# cores (a --camera sim flight runs ~3x faster single-threaded on a 2-core host). This must run before numpy
# is loaded, hence here: every foranav command imports this package first. The benchmarks also call
# host_tools.detection.threads.single_threaded() for when numpy was loaded by someone else.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
