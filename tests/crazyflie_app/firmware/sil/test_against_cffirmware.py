"""The firmware plant's build of controller_pid.c, power_distribution_quadrotor.c and their PID and filter code
computes exactly what the firmware's own Python bindings (cffirmware, built by make firmware-sil from the same
source) compute: the shim, the Bolt configuration and the compile flags change nothing in them."""
import ctypes
import random
import sys

import pytest

from crazyflie_app.firmware.commander import modeAbs, modeDisable, modeVelocity
from crazyflie_app.firmware.sil import BUILD_DIR
from crazyflie_app.firmware.sil.stack import SilState, _fresh_library, _Setpoint

from .conftest import needs_firmware_plant

pytestmark = needs_firmware_plant
STEPS = 3000  # 3 s of the 1 kHz loop: position (100 Hz) and attitude (500 Hz) rates both run many times


@pytest.fixture(scope="module")
def cffirmware():
    bindings = BUILD_DIR / "cffirmware"
    if not (bindings / "cffirmware.py").exists():
        pytest.skip("the cffirmware bindings are not built: make firmware-sil")
    sys.path.insert(0, str(bindings))
    try:
        import cffirmware as module
    finally:
        sys.path.remove(str(bindings))
    return module


def random_inputs(rng, step):
    """A setpoint in one of the modes the app and the supervisor use, a state near hover, a gyro reading."""
    mode = rng.choice(("hover", "position", "level"))
    sp = {"mode_x": modeVelocity, "mode_y": modeVelocity, "mode_z": modeAbs, "mode_yaw": modeAbs,
          "velocity": (rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), 0.0), "velocity_body": 1,
          "position": (rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.5, 1.5)),
          "attitude": (0.0, 0.0, rng.uniform(-30, 30)), "mode_roll": modeDisable, "mode_pitch": modeDisable}
    if mode == "position":
        sp.update(mode_x=modeAbs, mode_y=modeAbs, velocity_body=0)
    elif mode == "level":  # the supervisor's level-out: attitude held, yaw rate 0
        sp.update(mode_x=modeDisable, mode_y=modeDisable, mode_roll=modeAbs, mode_pitch=modeAbs,
                  mode_yaw=modeVelocity)
    state = {"x": rng.uniform(-1, 1), "y": rng.uniform(-1, 1), "z": rng.uniform(0.2, 1.5),
             "vx": rng.uniform(-0.5, 0.5), "vy": rng.uniform(-0.5, 0.5), "vz": rng.uniform(-0.3, 0.3),
             "roll": rng.uniform(-5, 5), "pitch": rng.uniform(-5, 5), "yaw": rng.uniform(-30, 30)}
    gyro = tuple(rng.uniform(-20, 20) for _ in range(3))
    return sp, state, gyro


def ours(lib, sp, state, gyro, step):
    c_sp = _Setpoint()
    for name, value in sp.items():
        if isinstance(value, tuple):
            getattr(c_sp, name)[:] = value
        else:
            setattr(c_sp, name, value)
    out = (ctypes.c_double * 8)()
    lib.sil_probe_controller(ctypes.byref(c_sp), ctypes.byref(SilState(**state)), (ctypes.c_double * 3)(*gyro),
                             step, out)
    return list(out)


def theirs(cf, sp, state, gyro, step):
    setpoint, st, sensors, control = cf.setpoint_t(), cf.state_t(), cf.sensorData_t(), cf.control_t()
    for axis in ("x", "y", "z", "roll", "pitch", "yaw"):
        setattr(setpoint.mode, axis, sp["mode_" + axis])
    for i, axis in enumerate("xyz"):
        setattr(setpoint.position, axis, sp["position"][i])
        setattr(setpoint.velocity, axis, sp["velocity"][i])
        setattr(st.position, axis, state[axis])
        setattr(st.velocity, axis, state["v" + axis])
        setattr(sensors.gyro, axis, gyro[i])
    for i, axis in enumerate(("roll", "pitch", "yaw")):
        setattr(setpoint.attitude, axis, sp["attitude"][i])
        setattr(st.attitude, axis, state[axis])
    setpoint.velocity_body = bool(sp["velocity_body"])
    cf.controllerPid(control, setpoint, sensors, st, step)
    uncapped, pwm = cf.motors_thrust_uncapped_t(), cf.motors_thrust_pwm_t()
    cf.powerDistribution(control, uncapped)
    cf.powerDistributionCap(uncapped, pwm)
    motors = [pwm.motors.m1, pwm.motors.m2, pwm.motors.m3, pwm.motors.m4]
    return [control.thrust, control.roll, control.pitch, control.yaw] + motors


def test_that_the_plants_controller_and_mixer_compute_what_cffirmware_computes(cffirmware):
    # Fixture: both controllers fresh; the same random inputs, step by step
    lib = _fresh_library()
    lib.sil_probe_controller.argtypes = [ctypes.POINTER(_Setpoint), ctypes.POINTER(SilState),
                                         ctypes.POINTER(ctypes.c_double), ctypes.c_uint32,
                                         ctypes.POINTER(ctypes.c_double)]
    lib.sil_probe_controller_init()
    cffirmware.controllerPidInit()
    cffirmware.powerDistributionInit()
    rng = random.Random(7)
    inputs = random_inputs(rng, 1)
    for step in range(1, STEPS + 1):
        if step % 250 == 0:
            inputs = random_inputs(rng, step)  # a new situation four times a second, integrators carried over
        # Test
        mine, reference = ours(lib, *inputs, step), theirs(cffirmware, *inputs, step)
        # Assert: bit for bit (both are float32 code on the same source)
        assert mine == reference, "step %d: %s != %s" % (step, mine, reference)
