"""foranav sweep on real Dask clusters: a two-process localhost cluster through --scheduler, and a sweep
killed mid-way and run again (no finished flight flown twice, none missing). Oracle flights on one short
column, to stay fast."""
import json
import os
import signal
import socket
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import pytest

from host_tools.sweep.runner import fly_task
from host_tools.sweep.specs import flight_spec
from host_tools.plantation_ranges import PlantationRanges
from tests.conftest import REPO_ROOT

ROOT = REPO_ROOT
DASK = Path(sys.executable).with_name("dask")
SMALL = ["--columns", "1", "--column-length-m", "1.2:1.5"]
SMALL_RANGES = PlantationRanges(columns=(1, 1), column_length_m=(1.2, 1.5))
START_TIMEOUT_S = 60.0
SWEEP_TIMEOUT_S = 400.0
KILL_AFTER_ROWS = 2
COUNT = 6


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    return env


def _stop(process):
    """Stop a process group we started, whatever state it is in."""
    if process.poll() is None:
        try:
            os.killpg(process.pid, signal.SIGTERM)
            process.wait(timeout=10)
        except (ProcessLookupError, subprocess.TimeoutExpired):
            try:
                os.killpg(process.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            process.wait()


def _wait_for_port(port, process, timeout):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise RuntimeError("dask scheduler exited: %s" % process.stdout.read()[-2000:])
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=1):
                return
        except OSError:
            time.sleep(0.2)
    raise RuntimeError("dask scheduler not listening on %d" % port)


def _wait_for_workers(address, count, timeout):
    from dask.distributed import Client
    with Client(address, timeout="30s") as client:
        client.wait_for_workers(count, timeout=timeout)


def _sweep(out, *extra):
    return [sys.executable, "-m", "host_tools.cli", "sweep", "--count", str(COUNT), "--seed", "5", "--camera",
            "oracle", "--out", str(out), "--quiet"] + SMALL + list(extra)


@pytest.fixture
def cluster(tmp_path):
    """`dask scheduler` + one `dask worker` as subprocesses on localhost; stopped at the end whatever happens."""
    port = _free_port()
    address = "tcp://127.0.0.1:%d" % port
    logs = tmp_path / "dask"
    logs.mkdir()
    started = []
    try:
        scheduler = subprocess.Popen([str(DASK), "scheduler", "--host", "127.0.0.1", "--port", str(port),
                                      "--no-dashboard"], cwd=str(ROOT), env=_env(), stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, text=True, start_new_session=True)
        started.append(scheduler)
        _wait_for_port(port, scheduler, START_TIMEOUT_S)
        worker = subprocess.Popen([str(DASK), "worker", address, "--nthreads", "1", "--no-dashboard"],
                                  cwd=str(ROOT), env=_env(), stdout=open(logs / "worker.log", "w"),
                                  stderr=subprocess.STDOUT, start_new_session=True)
        started.append(worker)
        _wait_for_workers(address, 1, START_TIMEOUT_S)
        yield address
    finally:
        for process in reversed(started):
            _stop(process)


def test_that_a_sweep_runs_on_a_two_process_dask_cluster_through_the_scheduler(cluster, tmp_path):
    out = tmp_path / "sweep"
    # Test
    done = subprocess.run(_sweep(out, "--scheduler", cluster, "--json"), cwd=str(ROOT), env=_env(),
                          capture_output=True, text=True, timeout=SWEEP_TIMEOUT_S)
    # Assert
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout)
    assert report["flights"] == COUNT and report["this_run"]["flown"] == COUNT
    db = sqlite3.connect(str(out / "sweep.sqlite"))
    rows = db.execute("SELECT idx, status, summary, worker FROM flights ORDER BY idx").fetchall()
    assert [r[0] for r in rows] == list(range(COUNT)) and {r[1] for r in rows} == {"ok"}
    assert all(str(os.getpid()) not in r[3] for r in rows)  # flown on the cluster's worker, not here
    # the same flight flown here gives the same summary: results do not depend on where a flight runs
    here = fly_task(flight_spec(5, 1, camera="oracle", ranges=SMALL_RANGES))["summary"]
    assert json.loads(rows[1][2]) == json.loads(json.dumps(here))
    assert (out / "report.md").exists() and (out / "rates.png").exists() and (out / "deviations.png").exists()
    assert report["flawless"] == sum(json.loads(r[2])["success"] for r in rows)


def test_that_a_killed_sweep_loses_only_the_flights_in_flight_and_resumes(tmp_path):
    out = tmp_path / "sweep"
    store = out / "sweep.sqlite"
    # Fixture: a sweep on a one-worker LocalCluster, killed (SIGKILL, the whole process group) mid-way
    process = subprocess.Popen(_sweep(out, "--workers", "1"), cwd=str(ROOT), env=_env(), stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + SWEEP_TIMEOUT_S
        rows = 0
        while rows < KILL_AFTER_ROWS and time.monotonic() < deadline and process.poll() is None:
            time.sleep(0.2)
            if store.exists():
                try:
                    rows = sqlite3.connect(str(store)).execute("SELECT COUNT(*) FROM flights").fetchone()[0]
                except sqlite3.OperationalError:
                    rows = 0
        assert process.poll() is None, "the sweep ended before it could be killed"
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()
    finally:
        _stop(process)
    db = sqlite3.connect(str(store))
    finished_first = {r[0] for r in db.execute("SELECT idx FROM flights")}
    db.close()
    assert KILL_AFTER_ROWS <= len(finished_first) < COUNT
    # Test: the same command again
    again = subprocess.run(_sweep(out, "--workers", "1", "--json"), cwd=str(ROOT), env=_env(),
                           capture_output=True, text=True, timeout=SWEEP_TIMEOUT_S)
    # Assert
    assert again.returncode == 0, again.stderr[-3000:]
    report = json.loads(again.stdout)
    db = sqlite3.connect(str(store))
    runs = dict(db.execute("SELECT idx, run FROM flights"))
    attempts = {}
    for run, idx in db.execute("SELECT run, idx FROM attempts"):
        attempts.setdefault(run, set()).add(idx)
    first_run, second_run = sorted(attempts)
    assert sorted(runs) == list(range(COUNT))  # none missing
    assert attempts[second_run].isdisjoint(finished_first)  # no finished flight flown again
    assert attempts[second_run] == set(range(COUNT)) - finished_first
    assert all(runs[i] == first_run for i in finished_first)
    assert report["this_run"]["skipped"] == len(finished_first) and report["flights"] == COUNT
