"""Fly a sweep's flights on Dask (dask.distributed), one task per flight, storing each as it finishes.

    run_sweep(specs, store, *, scheduler=None, workers=None, progress=None) -> counts dict

With no ``scheduler`` a LocalCluster of ``workers`` single-threaded worker processes (default: one per core)
is started and shut down after; with ``scheduler`` ('tcp://host:port') the tasks go to that running
cluster. The task is ``fly_task(spec)``: it never raises (a flight that raises comes back with its
traceback), so one bad flight never stops a sweep; a worker that dies is recorded the same way.
"""
import os
import shutil
import tempfile
import platform
import resource
import time
import traceback
from collections.abc import Callable, Sequence
from typing import Any

import cv2

from host_tools import small_pages_for_numpy
from host_tools.errors import ForaNavError
from host_tools.flight.harness import fly
from host_tools.sweep.conditions import harness_inputs
from host_tools.sweep.store import SweepStore


def fly_task(spec: dict) -> dict:
    """Fly one spec (a Dask task) -> result dict: index, spec, status, summary | traceback, cpu_s, wall_s."""
    # one OpenCV thread per worker process: the workers already fill the cores, and idle OpenCV threads
    # spinning on a shared machine cost CPU; results do not depend on it
    cv2.setNumThreads(1)
    small_pages_for_numpy()

    # process CPU: the renderer's OpenCV threads count too (a worker runs one task at a time)
    wall0, cpu0, usage0 = time.perf_counter(), time.process_time(), resource.getrusage(resource.RUSAGE_SELF)
    result = {"index": spec["index"], "spec": spec, "worker": "%s:%d" % (platform.node(), os.getpid())}
    try:
        camera_kwargs, options = harness_inputs(spec["conditions"], spec["camera"], spec.get("fly_args", ()))
        options["profile"] = bool(spec.get("profile"))  # the benchmark's: CPU by stage
        summary = fly(spec["map"], camera=spec["camera"], camera_kwargs=camera_kwargs, options=options,
                      seed=spec["seed"])
        summary.pop("cpu_s", None)
        stages = summary.pop("stage_cpu_s", None)
        if stages is not None:
            result["stage_cpu_s"] = stages
        result.update(status="ok", summary=summary)
    except Exception:  # recorded, never raised: the sweep goes on
        result.update(status="error", traceback=traceback.format_exc())
    usage = resource.getrusage(resource.RUSAGE_SELF)
    result.update(cpu_s=round(time.process_time() - cpu0, 3), wall_s=round(time.perf_counter() - wall0, 3),
                  user_s=round(usage.ru_utime - usage0.ru_utime, 3), system_s=round(usage.ru_stime - usage0.ru_stime, 3),
                  max_rss_mb=round(usage.ru_maxrss / 1024.0, 1))
    return result


# glibc's heap for the workers: Dask sets MALLOC_TRIM_THRESHOLD_=65536 to hand memory back quickly, which also
# freezes malloc's mmap threshold at 128 kB, so every frame-sized array came from a fresh mmap whose pages the
# kernel zeroed: ~1 s of system time per vision flight. Arrays up to 16 MB now come from the heap and stay
# there between frames; a world's ground (tens to hundreds of MB) still goes back when it is freed.
WORKER_MALLOC_ENVIRON = {"MALLOC_MMAP_THRESHOLD_": str(16 * 2 ** 20), "MALLOC_TRIM_THRESHOLD_": str(32 * 2 ** 20)}


def open_client(scheduler: str | None = None, workers: int | None = None) -> tuple[Any, Any]:
    """(client, cluster): a Client of the running cluster at ``scheduler``, or of a new LocalCluster of
    ``workers`` single-threaded processes (cluster is then returned so the caller can close it)."""
    try:  # here, not at the top: dask is needed only to fly a sweep (and takes ~1 s to import)
        import dask
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise ForaNavError("foranav sweep needs dask.distributed: pip install 'dask[distributed]'")
    if scheduler:
        try:
            return Client(scheduler, timeout="20s"), None
        except (OSError, TimeoutError) as err:
            raise ForaNavError("--scheduler %s: cannot connect: %s" % (scheduler, err))
    workers = workers or os.cpu_count() or 1
    # the workers' scratch space and lock files in a folder of this sweep's own, removed by close_client
    # (Dask's default, TMPDIR/dask-scratch-space, kept a lock file per worker after every sweep)
    scratch = tempfile.mkdtemp(prefix="foranav-dask-")
    settings = {"distributed.nanny.pre-spawn-environ." + name: value for name, value in WORKER_MALLOC_ENVIRON.items()}
    settings["temporary-directory"] = scratch
    with dask.config.set(settings):
        cluster = LocalCluster(n_workers=int(workers), threads_per_worker=1, processes=True,
                               dashboard_address=":0", silence_logs=40, local_directory=scratch)
    dask.config.set({"temporary-directory": scratch})  # the scheduler's and client's lock files too
    _scratch_folders[id(cluster)] = scratch
    return Client(cluster), cluster


_scratch_folders: dict = {}  # id(LocalCluster) -> its scratch folder


def close_client(client: Any, cluster: Any) -> None:
    """Close the client, and the LocalCluster open_client started (with its scratch folder)."""
    client.close()
    if cluster is not None:
        cluster.close()
        shutil.rmtree(_scratch_folders.pop(id(cluster), ""), ignore_errors=True)


def fly_on(client: Any, specs: Sequence[dict], on_result: Callable[[dict], None], key_prefix: str = "flight") -> None:
    """Submit one task per spec; call ``on_result(result)`` as each finishes (any order)."""
    from dask.distributed import as_completed  # with open_client's import: dask only for a sweep

    futures = {client.submit(fly_task, spec, key="%s-%06d" % (key_prefix, spec["index"]), pure=False): spec
               for spec in specs}
    for future in as_completed(futures):
        spec = futures.pop(future)
        try:
            result = future.result()
        except Exception:  # the worker died under the flight (KilledWorker, ...)
            result = {"index": spec["index"], "spec": spec, "status": "error", "traceback": traceback.format_exc()}
        on_result(result)


def run_sweep(specs: Sequence[dict], store: SweepStore, *, scheduler: str | None = None, workers: int | None = None,
              progress: Callable[..., None] | None = None) -> dict:
    """Fly the specs not yet in ``store`` -> {"skipped", "flown", "failed", "wall_s"}."""
    finished = store.finished()
    todo = [s for s in specs if s["index"] not in finished]
    counts = {"skipped": len(specs) - len(todo), "flown": 0, "failed": 0, "wall_s": 0.0}
    if not todo:
        return counts
    started = time.monotonic()
    client, cluster = open_client(scheduler, workers)

    def on_result(result):
        store.put(result)
        counts["flown"] += 1
        counts["failed"] += result["status"] != "ok" or not result["summary"]["success"]
        if progress is not None:
            progress(counts["flown"], len(todo), counts["failed"], time.monotonic() - started)

    try:
        store.record_attempts([s["index"] for s in todo])
        fly_on(client, todo, on_result, key_prefix="flight-%d-%d" % (os.getpid(), store.run or 0))
    finally:
        close_client(client, cluster)
    counts["wall_s"] = round(time.monotonic() - started, 2)
    return counts
