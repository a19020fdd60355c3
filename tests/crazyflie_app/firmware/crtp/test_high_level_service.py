"""Port 8 and the trajectory memory on the firmware plant: the packets stock cflib's HighLevelCommander builds,
run by the firmware's own high-level commander (takeoff, go_to, a trajectory from memory, land), and bad input
answered as the firmware answers, never a crash. The reduced plant has no high-level commander."""
import errno
import math
import struct

import pytest
from cflib.crazyflie.high_level_commander import HighLevelCommander

from crazyflie_app.firmware import Crazyflie
from crazyflie_app.firmware.crtp import CrtpServer
from crazyflie_app.firmware.crtp.packet import CRTP_PORT_MEM, CRTP_PORT_SETPOINT_HL, CrtpPacket
from tests.crazyflie_app.firmware.sil.conftest import needs_firmware_plant

CLIENT = ("127.0.0.1", 1)  # handle_datagram's reply goes to this address (nobody listens)
TRAJ_MEMORY_ID = 0  # the trajectory memory comes first
POLY4D = struct.Struct("<33f")  # pptraj.h struct poly4d: 8 x, 8 y, 8 z, 8 yaw coefficients, duration
MEM_WRITE_CHUNK = 24


class _Client:
    """What cflib's Crazyflie object is to its HighLevelCommander: send_packet (captured here, then handed to
    the server as its UDP driver would send it) and the platform's protocol version."""

    class _Platform:
        @staticmethod
        def get_protocol_version():
            return 12

    def __init__(self, server, cf):
        self.server, self.cf = server, cf
        self.platform = self._Platform()
        self.answers = []
        server.link.send = lambda data, address: self.answers.append(data)

    def send_packet(self, pk):
        self.send_raw(bytes([pk.header]) + bytes(pk.data))

    def send_raw(self, datagram: bytes):
        self.server.handle_datagram(datagram, CLIENT, self.cf.x_task_get_tick_count())


def _firmware():
    cf = Crazyflie(seed=0, plant="firmware", start=(0.0, 0.0, 0.0), bounds=(0.0, 0.0, 2.0, 2.0))
    server = CrtpServer(cf, "127.0.0.1", 0, lockstep=False)
    client = _Client(server, cf)
    return cf, server, client, HighLevelCommander(client)


def _fly(cf, until_ms):
    cf.run_until(until_ms)
    return cf.model.truth


def _result(answer: bytes) -> int:
    packet = CrtpPacket(answer[0] >> 4, answer[0] & 3, answer[1:])
    assert packet.port == CRTP_PORT_SETPOINT_HL and len(packet.data) == 4
    return packet.data[3]


@needs_firmware_plant
def test_that_takeoff_go_to_and_land_fly_the_firmwares_plans():
    # Fixture: an armed firmware on the ground at (0, 0)
    cf, server, client, commander = _firmware()
    cf.run_until(1000)
    cf.supervisor_request_arming(True)
    cf.run_until(1500)
    # Test: cflib's takeoff, go_to, land
    commander.takeoff(0.8, 2.0)
    at_height = _fly(cf, 5000)
    height = (at_height.x, at_height.y, at_height.z)
    commander.go_to(1.0, 0.5, 0.8, 0.0, 2.5)
    arrived = _fly(cf, 9000)
    goal = (arrived.x, arrived.y, arrived.z)
    target_x = cf.registry.log_read("ctrltarget.x")  # the planner's setpoint, as the firmware logs it
    commander.land(0.0, 2.0)
    landed = _fly(cf, 14000)
    # Assert: each command answered 0; the MAV was where the planner put it; it landed, not crashed
    assert [_result(a) for a in client.answers] == [0, 0, 0]
    assert height == pytest.approx((0.0, 0.0, 0.8), abs=0.1)
    assert goal == pytest.approx((1.0, 0.5, 0.8), abs=0.1)
    assert landed.z == 0.0 and not cf.model.crashed
    assert target_x == pytest.approx(1.0, abs=0.01)
    server.close()
    cf.close()


def _upload(client, pieces: bytes) -> list[int]:
    """The trajectory memory written as cflib's TrajectoryMemory does: [id, address u32, <= 24 bytes] each."""
    statuses = []
    for address in range(0, len(pieces), MEM_WRITE_CHUNK):
        client.answers.clear()
        chunk = pieces[address:address + MEM_WRITE_CHUNK]
        client.send_raw(bytes([(CRTP_PORT_MEM << 4) | 2, TRAJ_MEMORY_ID]) + struct.pack("<I", address) + chunk)
        statuses.append(client.answers[-1][6])
    return statuses


@needs_firmware_plant
def test_that_an_uploaded_trajectory_is_flown():
    # Fixture: one piece, 3 s: x(t) = 0.2 t (0.6 m), y = 0, z = 0, yaw 0, flown relative to the hover point
    cf, server, client, commander = _firmware()
    piece = POLY4D.pack(*([0.0, 0.2] + [0.0] * 6 + [0.0] * 8 + [0.0] * 8 + [0.0] * 8 + [3.0]))
    assert set(_upload(client, piece)) == {0}
    commander.define_trajectory(3, 0, 1)
    cf.run_until(1000)
    cf.supervisor_request_arming(True)
    cf.run_until(1500)
    commander.takeoff(0.7, 2.0)
    cf.run_until(5000)
    x0 = cf.model.truth.x
    # Test
    commander.start_trajectory(3, 1.0, relative_position=True)
    end = _fly(cf, 9000)
    # Assert: the planner flew the piece: 0.6 m along x at the hover height
    assert all(_result(a) == 0 for a in client.answers[-3:])
    assert end.x - x0 == pytest.approx(0.6, abs=0.1) and end.z == pytest.approx(0.7, abs=0.1)
    server.close()
    cf.close()


@needs_firmware_plant
def test_that_bad_high_level_input_is_answered_as_the_firmware_answers():
    cf, server, client, commander = _firmware()
    cf.run_until(200)
    # an unknown command: the firmware's ENOEXEC
    client.send_raw(bytes([CRTP_PORT_SETPOINT_HL << 4, 0xEE, 1, 2]))
    unknown = _result(client.answers[-1])
    # a trajectory id past its table (31 entries): ENOEXEC
    commander.define_trajectory(40, 0, 1)
    past_table = _result(client.answers[-1])
    # a trajectory defined past the 4096-byte memory: refused (EINVAL) instead of read past the memory
    commander.define_trajectory(2, 4000, 10)
    past_memory = _result(client.answers[-1])
    # a memory write past the end: the firmware's EIO; the start of an undefined trajectory: nothing to fly
    client.answers.clear()
    client.send_raw(bytes([(CRTP_PORT_MEM << 4) | 2, TRAJ_MEMORY_ID]) + struct.pack("<I", 4090) + bytes(12))
    write_past = client.answers[-1][6]
    commander.start_trajectory(5, 1.0)
    undefined = _result(client.answers[-1])
    # a truncated takeoff (the command byte only): the firmware reads zeros, answers; an empty packet: dropped
    client.send_raw(bytes([CRTP_PORT_SETPOINT_HL << 4, 7]))
    truncated = _result(client.answers[-1])
    answers = len(client.answers)
    malformed = server.stats.malformed
    client.send_raw(bytes([CRTP_PORT_SETPOINT_HL << 4]))
    cf.run_until(1000)
    assert (unknown, past_table, past_memory, write_past) == (errno.ENOEXEC, errno.ENOEXEC, errno.EINVAL, errno.EIO)
    assert undefined in (0, errno.EBUSY) and truncated in (0, errno.EBUSY)  # EBUSY: not armed, blocked
    assert len(client.answers) == answers and server.stats.malformed == malformed + 1
    assert not cf.model.crashed and cf.model.truth.z == 0.0
    server.close()
    cf.close()


def test_that_the_reduced_plant_has_no_high_level_commander():
    cf = Crazyflie(seed=0)
    server = CrtpServer(cf, "127.0.0.1", 0, lockstep=False)
    client = _Client(server, cf)
    HighLevelCommander(client).takeoff(1.0, 2.0)
    assert client.answers == [] and server.stats.unserved == 1
    assert not math.isnan(cf.model.truth.z) and cf.high_level is None
    server.close()
    cf.close()
