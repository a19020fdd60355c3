"""Flights of the Crazyflie app: the harness (``run_flight``), cameras, the pty wire, telemetry, plots.

Stable interface for the flight commands::

    from host_tools.flight import run_flight, OracleCamera, register_camera, camera_factory
    summary = run_flight(pmap, OracleCamera(pmap, seed=0), seed=0, out_dir="runs/x", options={"dropout": 0.3})
"""
from host_tools.flight.harness import DEFAULT_OPTIONS, camera_factory, register_camera, run_flight  # noqa: F401
from host_tools.flight.harness import fly, register_app  # noqa: F401
from host_tools.flight.oracle import OracleCamera  # noqa: F401


def _oracle(pmap, seed=0, **kwargs):
    return OracleCamera(pmap, seed=seed, **kwargs)


register_camera("oracle", _oracle)
