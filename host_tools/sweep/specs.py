"""The flights of a sweep: one spec per index, a pure function of (sweep seed, index, faults, camera, ranges).

A spec is a plain dict (JSON and pickle friendly):

    index, seed (the flight's), plantation_seed, camera, faults, conditions (see conditions.py), factors
    (what the plantation generator drew), map (the map JSON object)

Flight i of a sweep is the same whatever the count, the order or the number of workers, so a sweep can be
extended (a larger --count) or resumed.
"""
import dataclasses
import os
import shlex
from collections.abc import Sequence

import numpy as np

from host_tools.maps import map_to_dict
from host_tools.plantation import generate
from host_tools.plantation_ranges import DEFAULT_PROFILE, PROFILES, PlantationRanges, profile_of
from host_tools.sweep import conditions as cond

SEED_LIMIT = 2 ** 31 - 1
# Tuning seeds and reporting seeds (docs/sweeps.md): a rate that is reported comes from sweeps nobody looked
# at while changing the app, the camera or the generator.
TUNING_SWEEP_SEEDS = range(0, 1000)  # sweeps looked at while changing code
REPORTING_SWEEP_SEEDS = range(1000, 2000)  # reported rates only, each seed once (ledger in docs/sweeps.md)
TUNING_PLANTATION_SEEDS = range(0, 10_000)  # foranav plantation --seed in tests and examples


def seed_role(sweep_seed: int) -> str:
    """'tuning', 'reporting' or 'unassigned': what a sweep with this seed may be used for."""
    if sweep_seed in TUNING_SWEEP_SEEDS:
        return "tuning"
    return "reporting" if sweep_seed in REPORTING_SWEEP_SEEDS else "unassigned"


def plantation_seed(sweep_seed: int, index: int) -> int:
    """The plantation seed of flight ``index`` of the sweep with ``sweep_seed`` (the first draw of its spec)."""
    return int(np.random.default_rng([int(sweep_seed), int(index), 0x5EE9]).integers(0, SEED_LIMIT))


def flight_spec(sweep_seed: int, index: int, *, faults: str = "none", camera: str = "sim",
                ranges: PlantationRanges | None = None, overrides: dict | None = None,
                fly_args: Sequence[str] = ()) -> dict:
    """Spec of flight ``index`` of the sweep with ``sweep_seed``; ``fly_args``: the sweep's own ``foranav fly``
    arguments for every flight (``--app c``, ``--model M``, ``--crowns CSV ...``), replayed with it."""
    rng = np.random.default_rng([int(sweep_seed), int(index), 0x5EE9])
    plantation_seed = int(rng.integers(0, SEED_LIMIT))
    flight_seed = int(rng.integers(0, SEED_LIMIT))
    conditions = cond.draw(rng, cond.preset(faults, overrides), camera)
    ranges = ranges or PlantationRanges()
    pmap, factors = generate(plantation_seed, ranges)
    spec = {"index": int(index), "seed": flight_seed, "plantation_seed": plantation_seed, "camera": camera,
            "faults": faults, "conditions": conditions, "factors": factors, "map": map_to_dict(pmap)}
    if fly_args:  # only then: the specs of a plain sweep keep their bytes
        spec["fly_args"] = list(fly_args)
    return spec


def make_specs(count: int, sweep_seed: int, *, faults: str = "none", camera: str = "sim",
               ranges: PlantationRanges | None = None, overrides: dict | None = None,
               fly_args: Sequence[str] = ()) -> list[dict]:
    return [flight_spec(sweep_seed, i, faults=faults, camera=camera, ranges=ranges, overrides=overrides,
                        fly_args=fly_args)
            for i in range(int(count))]


def ranges_arguments(ranges: PlantationRanges | None) -> list[str]:
    """The ``foranav plantation`` options that give ``ranges``: the nearest profile (when not the default)
    and the ranges that differ from it."""
    profile, differing = profile_of(ranges)
    args = [] if profile == DEFAULT_PROFILE else ["--profile", profile]
    for name in differing:
        args += ["--" + name.replace("_", "-"), "%s:%s" % tuple(getattr(ranges, name))]
    return args


def stored_ranges(stored: dict) -> PlantationRanges:
    """The ranges a sweep store recorded; a store from before the wide profile lacks the geometry ranges,
    whose values were then the classic profile's."""
    return dataclasses.replace(PROFILES["classic"], **{k: tuple(v) for k, v in stored.items()})


def fly_command(spec: dict, map_path: str | os.PathLike) -> str:
    """The exact ``foranav fly`` command that replays this flight (its map written at ``map_path``)."""
    words = ["foranav", "fly", "--map", str(map_path), "--camera", spec["camera"], "--seed", str(spec["seed"])]
    words += cond.fly_arguments(spec["conditions"]) + list(spec.get("fly_args", ()))
    return " ".join(shlex.quote(w) for w in words)


def plantation_command(spec: dict, map_path: str | os.PathLike, ranges: PlantationRanges | None = None) -> str:
    """The ``foranav plantation`` command that writes this flight's map."""
    words = ["foranav", "plantation", "--seed", str(spec["plantation_seed"])]
    words += ranges_arguments(ranges or PlantationRanges()) + ["--out", str(map_path)]
    return " ".join(shlex.quote(w) for w in words)
