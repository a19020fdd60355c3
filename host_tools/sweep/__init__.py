"""Sweeps: thousands of flights over random plantations and conditions, on Dask, stored as they finish.

    specs.make_specs(...)   the flights of a sweep (plain, picklable dicts), a function of the seed only
    runner.run_sweep(...)   flies the unfinished ones on a Dask cluster, one task per flight
    store.SweepStore        SQLite under --out: one row per flight (spec, summary or traceback, timings)
    report.build_report(..) flawless rate (Wilson 95 %), failure taxonomy, deviations, rates by factor
"""
