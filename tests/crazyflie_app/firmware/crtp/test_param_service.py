"""The param port on a registry: TOC types, read, write, its refusals, and the misc commands."""
import errno
import struct

from crazyflie_app.firmware.crtp.packet import CRTP_PORT_PARAM, CrtpPacket
from crazyflie_app.firmware.crtp.param_service import (MISC_CH, PARAM_NOT_FOUND, READ_CH, WRITE_CH,
                                                       ParamService)
from crazyflie_app.firmware.crtp.toc import TOC_CH
from crazyflie_app.firmware.logparam import (PARAM_FLOAT, PARAM_UINT8, LogParamRegistry, param_add,
                                              param_group)

TUNING = param_group("tune", [param_add(PARAM_FLOAT, "gain", "gain", "", "a threshold"),
                              param_add(PARAM_UINT8, "count", "count", "", "", read_only=True)])
GAIN, COUNT, UNKNOWN = b"\x00\x00", b"\x01\x00", b"\x07\x00"


class _Tuning:
    gain = 1.5
    count = 3


def _service():
    registry = LogParamRegistry()
    owner = _Tuning()
    registry.register_param_group(TUNING, owner)
    return owner, ParamService(registry)


def _ask(service, channel, data):
    answers = service.handle(CrtpPacket(CRTP_PORT_PARAM, channel, bytes(data)), 0)
    return answers[0].data if answers else None


def test_that_toc_items_carry_the_type_and_the_read_only_flag():
    _, service = _service()
    assert _ask(service, TOC_CH, b"\x02" + GAIN) == b"\x02" + GAIN + b"\x06tune\0gain\0"
    assert _ask(service, TOC_CH, b"\x02" + COUNT) == b"\x02" + COUNT + bytes([0x08 | 0x40]) + b"tune\0count\0"
    assert struct.unpack("<BH", _ask(service, TOC_CH, b"\x03")[:3]) == (3, 2)


def test_that_reads_answer_the_value_or_enoent():
    _, service = _service()
    assert _ask(service, READ_CH, GAIN) == GAIN + b"\0" + struct.pack("<f", 1.5)
    assert _ask(service, READ_CH, COUNT) == COUNT + b"\0\x03"
    assert _ask(service, READ_CH, UNKNOWN) == UNKNOWN + bytes([errno.ENOENT])


def test_that_a_write_sets_the_owner_and_echoes_the_new_value():
    owner, service = _service()
    assert _ask(service, WRITE_CH, GAIN + struct.pack("<f", 0.25)) == GAIN + struct.pack("<f", 0.25)
    assert owner.gain == 0.25 and service.writes == 1


def test_that_refused_writes_answer_the_unchanged_value():
    owner, service = _service()
    assert _ask(service, WRITE_CH, COUNT + b"\x09") == COUNT + b"\x03"  # read-only
    assert _ask(service, WRITE_CH, GAIN + b"\x01\x02") == GAIN + struct.pack("<f", 1.5)  # wrong size
    assert _ask(service, WRITE_CH, UNKNOWN + b"\x01") == UNKNOWN + bytes([PARAM_NOT_FOUND])
    assert (owner.gain, owner.count, service.refused_writes) == (1.5, 3, 2)


def test_that_set_by_name_checks_name_type_size_and_access():
    owner, service = _service()

    def by_name(name, type_code, value):
        return _ask(service, MISC_CH, b"\x00" + name + bytes([type_code]) + value)[-1]

    assert by_name(b"tune\0gain\0", 0x06, struct.pack("<f", 2.0)) == 0 and owner.gain == 2.0
    assert by_name(b"tune\0nope\0", 0x06, struct.pack("<f", 2.0)) == errno.ENOENT
    assert by_name(b"tune\0gain\0", 0x08, b"\x01") == errno.EINVAL
    assert by_name(b"tune\0count\0", 0x08, b"\x01") == errno.EACCES


def test_that_defaults_are_the_registration_values_and_nothing_is_persistent():
    owner, service = _service()
    _ask(service, WRITE_CH, GAIN + struct.pack("<f", 9.0))
    assert _ask(service, MISC_CH, b"\x08" + GAIN) == b"\x08" + GAIN + b"\0" + struct.pack("<f", 1.5)
    assert _ask(service, MISC_CH, b"\x06" + GAIN) == b"\x06" + GAIN + struct.pack("<f", 1.5)
    assert _ask(service, MISC_CH, b"\x08" + COUNT) == b"\x08" + COUNT + bytes([errno.ENOENT])  # read-only
    assert _ask(service, MISC_CH, b"\x07" + GAIN) == b"\x07" + GAIN + bytes([errno.ENOENT])  # not extended
    assert _ask(service, MISC_CH, b"\x02" + GAIN) == b"\x02" + GAIN + bytes([PARAM_NOT_FOUND])
    assert _ask(service, MISC_CH, b"\x03" + GAIN) == b"\x03" + GAIN + bytes([errno.ENOENT])  # no storage
    assert _ask(service, MISC_CH, b"\x04" + GAIN) == b"\x04" + GAIN + b"\0" + struct.pack("<f", 1.5)
    assert _ask(service, MISC_CH, b"\x01" + GAIN) is None  # a firmware-to-client message
