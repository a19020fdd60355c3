"""The firmware plant: the real Crazyflie firmware (commander, supervisor, PID controller, power distribution,
Kalman estimator) built for the host around a rigid-body quadrotor with sensor models. ``build`` builds it
from the firmware source, ``stack`` loads it, ``plant`` offers it to the emulated Crazyflie."""
from pathlib import Path

REPO = Path(__file__).resolve().parents[3]
BUILD_DIR = REPO / "build" / "firmware-sil"
LIBRARY = BUILD_DIR / "libforanav_sil.so"  # what ``make firmware-sil`` builds and ``stack`` loads
