"""Stock cflib against a firmware-plant flight: the firmware's own groups in the TOCs, a PID gain written and
read back from the firmware's variable, the stabilizer's attitude streamed, as cflib's basiclog and basicparam
examples use them."""
import pytest

from tests.crazyflie_app.firmware.crtp.conftest import Session, wait_for
from tests.crazyflie_app.firmware.sil.conftest import needs_firmware_plant

pytestmark = needs_firmware_plant

WRITTEN_KD = 0.1234
ATTITUDE = ("stabilizer.roll", "stabilizer.pitch", "stabilizer.yaw", "kalman.stateZ")


def test_that_cflib_sees_writes_and_logs_the_firmwares_own_variables(flight_process, tmp_path):
    # Fixture: a firmware-plant flight of map 1 (lockstep, oracle camera) served over CRTP
    child = flight_process(options={"crtp": "127.0.0.1:0", "max_time_s": 12.0, "plant": "firmware"})
    session = Session(child.uri, tmp_path / "toc_cache")
    assert session.first_sent.wait(10)
    child.go()
    session.wait()
    cf = session.cf
    # Test: basicparam's write of pid_attitude.pitch_kd, then a fresh read of it; basiclog's attitude block
    echoes = []
    cf.param.add_update_callback(group="pid_attitude", name="pitch_kd", cb=lambda name, value: echoes.append(value))
    cf.param.set_value("pid_attitude.pitch_kd", WRITTEN_KD)
    wait_for(lambda: echoes, what="the write's echo")
    echoes.clear()
    cf.param.request_param_update("pid_attitude.pitch_kd")
    wait_for(lambda: echoes, what="the read-back")
    samples = session.start_block("attitude", 10, ATTITUDE)
    wait_for(lambda: len(samples) >= 50, what="50 samples")
    estimator = cf.param.get_value("stabilizer.estimator")
    groups = set(cf.param.toc.toc) | set(cf.log.toc.toc)  # cflib forgets its param TOC on disconnect
    session.close()
    child.finish()
    # Assert: the firmware groups are in the TOCs; the value read back is the firmware variable's (float32)
    assert {"stabilizer", "pid_attitude", "posCtlPid", "velCtlPid", "kalman", "ctrltarget", "supervisor",
            "commander", "pm", "motor", "led"} <= groups
    assert float(echoes[-1]) == pytest.approx(WRITTEN_KD, rel=1e-6)
    assert int(estimator) == 2
    timestamps = [ts for ts, _ in samples]
    assert all(b - a == 10 for a, b in zip(timestamps, timestamps[1:]))
    assert all(set(data) == set(ATTITUDE) for _, data in samples)
    assert any(abs(data["kalman.stateZ"]) > 0.0 for _, data in samples)
