"""Run numerical code on one core: OpenCV and the BLAS numpy links against.

The detector's few small matrix products go to numpy's BLAS, whose worker threads spin-wait on other cores;
on a busy or small machine (and for an honest one-core benchmark) that costs more than it saves.
The camera's numpy has no threaded BLAS, so this only makes the host behave like it.
"""
import ctypes

import cv2
import numpy  # noqa: F401  (loaded first, so that numpy's BLAS is among the libraries limited below)

_SETTERS = ("scipy_openblas_set_num_threads64_", "scipy_openblas_set_num_threads_64_",
            "openblas_set_num_threads64_", "openblas_set_num_threads", "goto_set_num_threads")


def single_threaded() -> int:
    """Limit OpenCV and any loaded OpenBLAS to one thread; returns the number of BLAS libraries limited."""
    cv2.setNumThreads(1)
    limited = 0
    for path in _loaded_libraries():
        if "blas" not in path.lower():
            continue
        try:
            library = ctypes.CDLL(path)
        except OSError:
            continue
        for name in _SETTERS:
            setter = getattr(library, name, None)
            if setter is not None:
                setter(1)
                limited += 1
                break
    return limited


def _loaded_libraries() -> list[str]:
    try:
        with open("/proc/self/maps") as maps:
            return sorted({line.split()[-1] for line in maps if ".so" in line})
    except OSError:
        return []
