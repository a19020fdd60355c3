"""Flight conditions of a sweep: per flight, drawn from the distributions of a fault preset, and turned into
exactly the options ``foranav fly`` takes (so every flight of a sweep replays with one fly command).

Presets (every value drawn independently per flight; U(a, b) uniform, P(flow) the chance of the flow
estimator; values are rounded so the fly command carries them exactly):

    condition          none              moderate              harsh
    dropout            0                 U(0, 0.2)             U(0.1, 0.4)      per detection, on the wire
    pixel_noise_px     camera default    U(0, 2)               U(1, 4)          detection centre noise (std)
    latency_ms         camera default    U(1, 2) frames        U(1, 3) frames   camera processing latency
    fps                camera default    U(6, 10)              U(4, 10)         camera frame rate
    wind_mps2          0                 U(0, 0.1)             U(0.1, 0.4)      gust acceleration std
    estimator          uwb               P(flow) = 0.25        P(flow) = 0.5    uwb (biased) / flow (drifting)
    cam_offset_m       (0, 0)            U(-0.05, 0.05) each   U(-0.1, 0.1)     mount offset (fwd, left), known
                                                                                to the app (app.camOffsetX/Y)

The Flow deck's drift (firmware plant only; none of the presets above sets it; ``drift`` is ``moderate`` with
the flow deck alone in every flight and these drawn too; docs/sweeps.md has the table of flawless rate
against the drift per 10 m flown):

    condition          drift
    flow_scale         U(0.9, 1.1)      counts reported per count of motion (pixel angle, lens, height error)
    flow_bias_counts   U(0, 0.1)        counts added to each 10 ms frame, x and y (0.1 ~ 2.6 cm/s at 1.25 m)
    ground_texture     U(0.2, 1)        below 0.5 the counts under-read, below 0.35 frames lose the motion flag

Wind: with the oracle on Map 1 and no other fault, gusts of 0.05-0.15 m/s^2 are flown flawlessly (slower),
0.2 and above make the app abandon targets (APPROACH never settles within settleRadius before its timeout);
with the other moderate faults on random plantations misses start near 0.16 m/s^2. So moderate stays below
that (U(0, 0.1)) and harsh covers it (U(0.1, 0.4)); see docs/sweeps.md.

Camera defaults: sim 9 fps, one frame of latency, no added pixel noise (the rendered frames carry sensor
noise); oracle 10 fps, 50 ms, 1.5 px. A preset can be narrowed or widened per condition with explicit
ranges (``overrides``: name -> (lo, hi); estimator: the flow probability).
"""
import argparse
from collections.abc import Sequence

import numpy as np

from host_tools.errors import ForaNavError
from host_tools.flight import cmd_fly, oracle, registry, vision_camera
from host_tools.sim.camera import MOUNT_OFFSET_RANGE_M

FAULT_PRESETS = {
    "none": {},
    "moderate": {"dropout": (0.0, 0.2), "pixel_noise_px": (0.0, 2.0), "latency_frames": (1.0, 2.0),
                 "fps": (6.0, 10.0), "wind_mps2": (0.0, 0.1), "flow_probability": 0.25,
                 "cam_offset_m": (-0.05, 0.05)},
    "harsh": {"dropout": (0.1, 0.4), "pixel_noise_px": (1.0, 4.0), "latency_frames": (1.0, 3.0),
              "fps": (4.0, 10.0), "wind_mps2": (0.1, 0.4), "flow_probability": 0.5,
              "cam_offset_m": (-0.1, 0.1)},
}
FAULT_PRESETS["drift"] = dict(FAULT_PRESETS["moderate"], flow_probability=1.0, flow_scale=(0.9, 1.1),
                              flow_bias_counts=(0.0, 0.1), ground_texture=(0.2, 1.0))
CONDITION_NAMES = ("dropout", "pixel_noise_px", "latency_frames", "fps", "wind_mps2", "flow_probability",
                   "cam_offset_m")
# drawn after every condition above, so the flights of the other presets keep their values
DRIFT_CONDITION_NAMES = ("flow_scale", "flow_bias_counts", "ground_texture")
CAMERAS = ("sim", "oracle")
# Each condition within what its fly option accepts (a sweep runs `fly` with it): checked here, in the parent,
# so a NaN, inf or 1e9 is one line before any Dask worker starts (issue 45: workers died and the scheduler
# gave up). latency_frames: frames of delay, fly --latency-ms at most 5000 ms at the slowest 2 fps = 10 frames.
CONDITION_BOUNDS = {"dropout": (0.0, 1.0), "pixel_noise_px": registry.PIXEL_NOISE_RANGE_PX,
                    "latency_frames": (0.0, 10.0), "fps": registry.FPS_RANGE, "wind_mps2": registry.WIND_RANGE_MPS2,
                    "flow_probability": (0.0, 1.0), "cam_offset_m": MOUNT_OFFSET_RANGE_M,
                    "flow_scale": registry.FLOW_SCALE_RANGE, "flow_bias_counts": registry.FLOW_BIAS_RANGE_COUNTS,
                    "ground_texture": registry.GROUND_TEXTURE_RANGE}


def preset(name: str, overrides: dict | None = None) -> dict:
    """The distributions of preset ``name`` with ``overrides`` applied (ForaNavError on a bad one)."""
    if name not in FAULT_PRESETS:
        raise ForaNavError("--faults: unknown preset %r (have %s)" % (name, ", ".join(FAULT_PRESETS)))
    spec = dict(FAULT_PRESETS[name])
    for key, value in (overrides or {}).items():
        if key not in CONDITION_NAMES + DRIFT_CONDITION_NAMES:
            raise ForaNavError("--condition %s: unknown (known: %s)"
                               % (key, ", ".join(CONDITION_NAMES + DRIFT_CONDITION_NAMES)))
        if key == "flow_probability":
            if not 0.0 <= float(value) <= 1.0:
                raise ForaNavError("--condition flow_probability: must be in [0, 1], got %r" % (value,))
        elif len(value) != 2 or value[0] > value[1]:
            raise ForaNavError("--condition %s: expected LO:HI with LO <= HI, got %r" % (key, value))
        lo, hi = CONDITION_BOUNDS[key]
        if not all(lo <= v <= hi for v in (value if isinstance(value, tuple) else (value,))):
            raise ForaNavError("--condition %s: must lie in [%g, %g] (what fly accepts), got %r"
                               % (key, lo, hi, value))
        spec[key] = value
    if "dropout" in spec and not 0.0 <= spec["dropout"][0] <= spec["dropout"][1] <= 1.0:
        raise ForaNavError("--condition dropout: must lie in [0, 1]")
    for key in ("pixel_noise_px", "wind_mps2"):
        if key in spec and spec[key][0] < 0:
            raise ForaNavError("--condition %s: must not be negative" % key)
    if "fps" in spec and spec["fps"][0] <= 0 or "latency_frames" in spec and spec["latency_frames"][0] < 0:
        raise ForaNavError("--condition fps must be positive, latency_frames not negative")
    return spec


def draw(rng: np.random.Generator, distributions: dict, camera: str) -> dict:
    """One flight's conditions (a dict of plain values) from ``distributions`` (see ``preset``)."""
    if camera not in CAMERAS:
        raise ForaNavError("--camera %s: a sweep flies sim or oracle" % camera)
    d = distributions
    # draw every condition in a fixed order whatever the preset, so presets share one random sequence shape
    values = {key: float(rng.random()) for key in CONDITION_NAMES}
    offset_roll = (float(rng.random()), float(rng.random()))
    out = {}
    if "dropout" in d:
        out["dropout"] = _scaled(values["dropout"], d["dropout"], 4)
    if "pixel_noise_px" in d:
        out["pixel_noise_px"] = _scaled(values["pixel_noise_px"], d["pixel_noise_px"], 3)
    if "fps" in d:
        fps = _scaled(values["fps"], d["fps"], 6)
        out["frame_period_ms"] = int(round(1000.0 / fps))
    if "latency_frames" in d:
        period = out.get("frame_period_ms", _default_period(camera))
        out["latency_ms"] = int(round(_scaled(values["latency_frames"], d["latency_frames"], 6) * period))
    if "wind_mps2" in d:
        out["wind_mps2"] = _scaled(values["wind_mps2"], d["wind_mps2"], 3)
    if "flow_probability" in d:
        out["estimator"] = "flow" if values["flow_probability"] < float(d["flow_probability"]) else "uwb"
    if "cam_offset_m" in d:
        out["cam_offset_m"] = [_scaled(offset_roll[0], d["cam_offset_m"], 4),
                               _scaled(offset_roll[1], d["cam_offset_m"], 4)]
    if any(key in d for key in DRIFT_CONDITION_NAMES):  # only then: the other presets' streams are unchanged
        drift_roll = {key: float(rng.random()) for key in DRIFT_CONDITION_NAMES}
        for key in DRIFT_CONDITION_NAMES:
            if key in d:
                out[key] = _scaled(drift_roll[key], d[key], 4)
    return out


def _scaled(unit: float, lo_hi: tuple[float, float], digits: int) -> float:
    lo, hi = lo_hi
    return round(lo + unit * (hi - lo), digits)


def _default_period(camera: str) -> int:
    return vision_camera.DEFAULT_FRAME_PERIOD_MS if camera == "sim" else oracle.DEFAULT_FRAME_PERIOD_MS


def fly_arguments(conditions: dict) -> list[str]:
    """The ``foranav fly`` options that reproduce ``conditions`` (list of strings, in a fixed order)."""
    args = []
    if conditions.get("dropout"):
        args += ["--dropout", repr(conditions["dropout"])]
    if "pixel_noise_px" in conditions:
        args += ["--pixel-noise", repr(conditions["pixel_noise_px"])]
    if "latency_ms" in conditions:
        args += ["--latency-ms", str(conditions["latency_ms"])]
    if "frame_period_ms" in conditions:
        # fly rounds 1000 / fps to whole milliseconds: this fps gives back the same period
        args += ["--fps", repr(1000.0 / conditions["frame_period_ms"])]
    if conditions.get("estimator", "uwb") != "uwb":
        args += ["--estimator", conditions["estimator"]]
    if conditions.get("wind_mps2"):
        args += ["--wind", repr(conditions["wind_mps2"])]
    if "cam_offset_m" in conditions:
        args += ["--cam-offset", repr(conditions["cam_offset_m"][0]), repr(conditions["cam_offset_m"][1])]
    for key, option in (("flow_scale", "--flow-scale"), ("flow_bias_counts", "--flow-bias"),
                        ("ground_texture", "--ground-texture")):
        if key in conditions:
            args += [option, repr(conditions[key])]
    return args


def harness_inputs(conditions: dict, camera: str, extra_arguments: Sequence[str] = ()) -> tuple[dict, dict]:
    """(camera_kwargs, options) for harness.fly, built by ``foranav fly``'s own option code from
    ``fly_arguments(conditions)`` and the sweep's ``extra_arguments`` (``--app``, ``--model``, ``--crowns``):
    one definition, so the replay command flies exactly the same flight."""
    parser = argparse.ArgumentParser(prog="foranav fly")
    cmd_fly.add_arguments(parser)
    args = parser.parse_args(["--map", "-", "--camera", camera] + fly_arguments(conditions) + list(extra_arguments))
    return cmd_fly.camera_kwargs(args), cmd_fly.flight_options(args)
