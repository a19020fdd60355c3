"""The log port on a registry: TOC items, block commands and their errors, periods and samples."""
import errno
import struct

from crazyflie_app.firmware import Crazyflie
from crazyflie_app.firmware.crtp.log_service import (CONTROL_CH, LOG_CH, LOG_MAX_BLOCKS, LOG_MAX_OPS, LogService)
from crazyflie_app.firmware.crtp.packet import CRTP_PORT_LOG, CrtpPacket
from crazyflie_app.firmware.crtp.toc import TOC_CH
from crazyflie_app.firmware.crtp.values import LOG_TYPE_CODES

FLOAT, UINT8 = LOG_TYPE_CODES["float"], LOG_TYPE_CODES["uint8_t"]


def _service():
    cf = Crazyflie()
    return cf, LogService(cf.registry)


def _control(service, *data, now=0):
    (answer,) = service.handle(CrtpPacket(CRTP_PORT_LOG, CONTROL_CH, bytes(data)), now)
    return answer.data[2]


def _settings(*pairs):
    return [b for fetch, var_id in pairs for b in (fetch, var_id & 0xFF, var_id >> 8)]


def test_that_toc_items_name_each_variable_with_its_type():
    cf, service = _service()
    (info,) = service.handle(CrtpPacket(CRTP_PORT_LOG, TOC_CH, b"\x03"), 0)
    command, count, crc, max_blocks, max_ops = struct.unpack("<BHIBB", info.data)
    assert count == len(cf.registry.log_names()) and (max_blocks, max_ops) == (LOG_MAX_BLOCKS, LOG_MAX_OPS)
    z = cf.log_get_var_id("stateEstimate", "z")
    (item,) = service.handle(CrtpPacket(CRTP_PORT_LOG, TOC_CH, bytes([2, z, 0])), 0)
    assert item.data == bytes([2, z, 0, FLOAT]) + b"stateEstimate\0z\0"
    (past_end,) = service.handle(CrtpPacket(CRTP_PORT_LOG, TOC_CH, bytes([2, 0xFF, 0xFF])), 0)
    assert past_end.data == b"\x02"


def test_that_block_commands_answer_the_firmwares_errors():
    cf, service = _service()
    z = cf.log_get_var_id("stateEstimate", "z")
    assert _control(service, 3, 1, 10) == errno.ENOENT  # start before create
    assert _control(service, 6, 1, *_settings((FLOAT, z))) == 0
    assert _control(service, 6, 1, *_settings((FLOAT, z))) == errno.EEXIST
    assert _control(service, 7, 1, *_settings((FLOAT, 999))) == errno.ENOENT  # no such variable
    assert _control(service, 7, 1, *_settings((FLOAT, 0xFFFF))) == errno.ENOENT  # raw memory: none here
    assert _control(service, 7, 1, *_settings((0x0F, z))) == errno.EINVAL  # no such fetch type
    assert _control(service, 7, 1, *_settings(*[(FLOAT, z)] * 6)) == errno.E2BIG  # 4 + 24 > 26 bytes
    assert len(service.blocks[1].ops) == 1, "a refused append changes nothing"
    assert _control(service, 0, 2) == errno.ENOEXEC  # the v1 create is not served
    assert _control(service, 2, 1) == 0 and _control(service, 2, 1) == errno.ENOENT


def test_that_blocks_and_variables_are_limited_as_on_the_mav():
    cf, service = _service()
    for block in range(LOG_MAX_BLOCKS):
        assert _control(service, 6, block, *_settings(*[(UINT8, 0)] * 8)) == 0
    assert _control(service, 6, 99, *_settings((UINT8, 0))) == errno.ENOMEM  # a 17th block
    assert sum(len(b.ops) for b in service.blocks.values()) == LOG_MAX_OPS
    assert _control(service, 2, 0) == 0
    assert _control(service, 6, 0, *_settings(*[(UINT8, 0)] * 9)) == errno.ENOMEM  # 129 variables
    assert _control(service, 5) == 0 and not service.blocks


def test_that_a_started_block_samples_every_period_from_its_start():
    cf, service = _service()
    z, info = cf.log_get_var_id("stateEstimate", "z"), cf.log_get_var_id("supervisor", "info")
    _control(service, 6, 4, *_settings((FLOAT, z), (FLOAT, info)))
    assert _control(service, 3, 4, 5, now=120) == 0  # 5 x 10 ms
    assert service.next_due() == 170
    assert service.due_packets(169) == []
    (sample,) = service.due_packets(170)
    assert sample.channel == LOG_CH and sample.data[:4] == bytes([4, 170, 0, 0])
    assert struct.unpack("<ff", sample.data[4:]) == (0.0, 0.0)  # on the ground, supervisor state 0 as float
    assert service.next_due() == 220
    assert _control(service, 4, 4) == 0 and service.next_due() is None  # stopped


def test_that_a_period_of_zero_is_one_sample_and_timestamps_wrap_at_24_bits():
    cf, service = _service()
    _control(service, 6, 1, *_settings((UINT8, 0)))
    _control(service, 8, 1, 0, 0, now=2 ** 24 + 5)  # START_BLOCK_V2, period 0 ms
    (sample,) = service.due_packets(2 ** 24 + 5)
    assert sample.data[1:4] == bytes([5, 0, 0])
    assert service.next_due() is None
