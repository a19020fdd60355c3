"""The sweep store: SQLite at <out>/sweep.sqlite, one row per finished flight, committed as each finishes.

Tables:
    meta(key, value)          the sweep's identity (seed, faults, camera, ranges, conditions): a re-run with
                              other values is refused, so one folder holds one sweep
    flights(idx, ...)         per finished flight: spec (JSON), status ('ok' or 'error'), summary (JSON),
                              traceback, cpu_s, wall_s, worker, finished_at, run
    attempts(run, idx)        which flights each run submitted (the kill-and-resume test reads it)
    runs(run, started_at, argv)

Only the client process writes (Dask workers return results to it); each row is its own transaction, so a
killed sweep loses only the flights that were in flight.
"""
import json
import os
import sqlite3
import time
from collections.abc import Iterable, Sequence
from pathlib import Path

from host_tools.errors import ForaNavError

FILENAME = "sweep.sqlite"
SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS flights (
    idx INTEGER PRIMARY KEY, spec TEXT NOT NULL, status TEXT NOT NULL, summary TEXT, traceback TEXT,
    cpu_s REAL, wall_s REAL, worker TEXT, finished_at REAL, run INTEGER);
CREATE TABLE IF NOT EXISTS attempts (run INTEGER NOT NULL, idx INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS runs (run INTEGER PRIMARY KEY AUTOINCREMENT, started_at REAL, argv TEXT);
"""


class SweepStore:
    def __init__(self, out_dir: str | os.PathLike, *, create: bool = True):
        self.path = Path(out_dir) / FILENAME
        if not create and not self.path.exists():
            raise ForaNavError("%s: no sweep store here (run foranav sweep --out %s first)" % (self.path, out_dir))
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.db = sqlite3.connect(str(self.path), timeout=30.0)
        self.db.executescript(SCHEMA)
        self.db.commit()
        self.run = None

    def close(self) -> None:
        self.db.close()

    def __enter__(self) -> "SweepStore":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- identity ------------------------------------------------------------------------------------------

    def check_identity(self, identity: dict) -> None:
        """Record ``identity`` (a dict) on first use; refuse a different one later (ForaNavError)."""
        rows = dict(self.db.execute("SELECT key, value FROM meta"))
        wanted = {k: json.dumps(v, sort_keys=True) for k, v in identity.items()}
        if not rows:
            self.db.executemany("INSERT INTO meta VALUES (?, ?)", sorted(wanted.items()))
            self.db.commit()
            return
        for key, value in wanted.items():
            if rows.get(key) != value:
                raise ForaNavError("%s: holds a sweep with %s %s, not %s (use another --out)"
                                   % (self.path, key, rows.get(key), value))

    def identity(self) -> dict:
        return {k: json.loads(v) for k, v in self.db.execute("SELECT key, value FROM meta")}

    # -- runs and rows -------------------------------------------------------------------------------------

    def start_run(self, argv: Sequence[str]) -> int:
        cur = self.db.execute("INSERT INTO runs (started_at, argv) VALUES (?, ?)", (time.time(), json.dumps(argv)))
        self.db.commit()
        self.run = cur.lastrowid
        return self.run

    def record_attempts(self, indices: Iterable[int]) -> None:
        self.db.executemany("INSERT INTO attempts VALUES (?, ?)", [(self.run, int(i)) for i in indices])
        self.db.commit()

    def finished(self) -> set[int]:
        return {row[0] for row in self.db.execute("SELECT idx FROM flights")}

    def put(self, result: dict) -> None:
        """Store one flight's result (the dict runner.fly_task returns) in its own transaction."""
        self.db.execute(
            "INSERT OR REPLACE INTO flights VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (int(result["index"]), json.dumps(result["spec"], sort_keys=True), result["status"],
             None if result.get("summary") is None else json.dumps(result["summary"], sort_keys=True),
             result.get("traceback"), result.get("cpu_s"), result.get("wall_s"), result.get("worker"),
             time.time(), self.run))
        self.db.commit()

    def rows(self) -> list[dict]:
        """Every stored flight as a dict (spec and summary decoded), by index."""
        out = []
        for idx, spec, status, summary, tb, cpu, wall, worker, finished, run in self.db.execute(
                "SELECT * FROM flights ORDER BY idx"):
            out.append({"index": idx, "spec": json.loads(spec), "status": status,
                        "summary": None if summary is None else json.loads(summary), "traceback": tb,
                        "cpu_s": cpu, "wall_s": wall, "worker": worker, "finished_at": finished, "run": run})
        return out

    def attempts(self) -> dict[int, list[int]]:
        """{run: [idx, ...]} of the flights each run submitted."""
        out = {}
        for run, idx in self.db.execute("SELECT run, idx FROM attempts ORDER BY run, idx"):
            out.setdefault(run, []).append(idx)
        return out
