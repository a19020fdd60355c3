"""log.c / param_logic.c: variables addressed by ``group.name`` with firmware-like integer ids.

``log_get_var_id(group, name)`` returns a small integer, or LOG_VARID_INVALID (0xFFFF) for an unknown name,
exactly like logGetVarId; reading through an invalid id is a firmware ASSERT, here FirmwareAssertError.
``param_get_var_id`` returns a ParamVarId(id, index) whose id is 0xFFFF when unknown; paramGet*/paramSet*
assert validity and type, and writes to read-only params assert too. Values are live: a read calls the
variable's getter (no snapshot), as the firmware reads the variable's address.

Tables are declared like the C macros (``LOG_GROUP_START(app) LOG_ADD(LOG_FLOAT, x, &x)``)::

    LOG_TABLE = log_group("app", [log_add(LOG_UINT8, "phase", "phase", "", "app phase")])
    PARAM_TABLE = param_group("app", [param_add(PARAM_FLOAT, "altitude", "altitude_m", "m", "flight height")])

where the third field names the attribute of the owning object (the C ``&variable``).
"""
import math
from collections.abc import Iterable
from dataclasses import dataclass

LOG_VARID_INVALID = 0xFFFF
PARAM_VARID_INVALID = 0xFFFF

LOG_UINT8, LOG_UINT16, LOG_UINT32, LOG_INT8, LOG_INT16, LOG_INT32, LOG_FLOAT = (
    "uint8_t", "uint16_t", "uint32_t", "int8_t", "int16_t", "int32_t", "float")
PARAM_UINT8, PARAM_UINT16, PARAM_UINT32, PARAM_INT8, PARAM_INT16, PARAM_INT32, PARAM_FLOAT = (
    LOG_UINT8, LOG_UINT16, LOG_UINT32, LOG_INT8, LOG_INT16, LOG_INT32, LOG_FLOAT)
_INTEGER_TYPES = (LOG_UINT8, LOG_UINT16, LOG_UINT32, LOG_INT8, LOG_INT16, LOG_INT32)
_INTEGER_RANGES = {"uint8_t": (0, 255), "uint16_t": (0, 65535), "uint32_t": (0, 2 ** 32 - 1),
                   "int8_t": (-128, 127), "int16_t": (-32768, 32767), "int32_t": (-2 ** 31, 2 ** 31 - 1)}


@dataclass(frozen=True)
class ParamVarId:
    """paramVarId_t: the param's id (PARAM_VARID_INVALID when unknown) and its table index."""
    id: int
    index: int


@dataclass(frozen=True)
class Entry:
    """One LOG_ADD / PARAM_ADD line: C type, name, the owner's attribute (the C ``&variable``), unit, doc."""
    type: str
    name: str
    attribute: str
    unit: str
    doc: str
    read_only: bool
    valid: tuple | None = None  # (low, high): what the owner's write check (PARAM_ADD_WITH_CALLBACK) accepts


@dataclass(frozen=True)
class Group:
    """A LOG_GROUP / PARAM_GROUP: its name and entries, in declaration order."""
    group: str
    entries: tuple


class FirmwareAssertError(AssertionError):
    """A failed firmware ASSERT (on the MAV: halt, LED pattern, 'assert failed' on the console)."""


class ParamRangeError(ValueError):
    """A write outside a param's ``valid`` range (or not a finite number): refused, the param keeps its value,
    as an app's PARAM_ADD_WITH_CALLBACK check puts the old value back."""


def log_add(var_type: str, name: str, attribute: str, unit: str = "", doc: str = "") -> Entry:
    return Entry(var_type, name, attribute, unit, doc, True)


def param_add(var_type: str, name: str, attribute: str, unit: str = "", doc: str = "",
              read_only: bool = False, valid: tuple | None = None) -> Entry:
    """A PARAM_ADD line; ``valid=(low, high)`` makes writes outside it (and NaN) refused (ParamRangeError)."""
    return Entry(var_type, name, attribute, unit, doc, read_only, valid)


def log_group(group: str, entries: Iterable[Entry]) -> Group:
    return Group(group, tuple(entries))


def param_group(group: str, entries: Iterable[Entry]) -> Group:
    return Group(group, tuple(entries))


class _Variable:
    __slots__ = ("group", "entry", "owner")

    def __init__(self, group: str, entry: Entry, owner: object):
        self.group, self.entry, self.owner = group, entry, owner

    @property
    def full_name(self) -> str:
        return "%s.%s" % (self.group, self.entry.name)

    def get(self) -> float | int:
        value = getattr(self.owner, self.entry.attribute)
        if self.entry.type in _INTEGER_TYPES:
            return int(value)
        return float(value)

    def set(self, value: float | int) -> None:
        if self.entry.type in _INTEGER_TYPES:
            low, high = _INTEGER_RANGES[self.entry.type]
            value = int(value)
            if not low <= value <= high:
                raise FirmwareAssertError("param %s: %d out of range for %s" % (self.full_name, value,
                                                                                   self.entry.type))
        self._check_valid(value)
        setattr(self.owner, self.entry.attribute, value)

    def _check_valid(self, value: float | int) -> None:
        valid = self.entry.valid
        if valid is None:
            return
        low, high = valid
        if not (math.isfinite(value) and low <= value <= high):
            raise ParamRangeError("param %s: %r refused, valid %g..%g%s" % (
                self.full_name, value, low, high, " " + self.entry.unit if self.entry.unit else ""))


class LogParamRegistry:
    """The log and param tables of one firmware image, in registration order (ids are table indices)."""

    def __init__(self):
        self._logs = []
        self._params = []
        self._log_index = {}
        self._param_index = {}
        self._param_defaults = []  # each param's value when it was registered (the firmware's .data image)

    # -- registration (what the LOG_GROUP/PARAM_GROUP macros do at link time) -----------------------------

    def register_log_group(self, table: Group, owner: object) -> None:
        self._register(table, owner, self._logs, self._log_index)

    def register_param_group(self, table: Group, owner: object) -> None:
        self._register(table, owner, self._params, self._param_index)
        self._param_defaults.extend(v.get() for v in self._params[len(self._param_defaults):])

    @staticmethod
    def _register(table, owner, variables, index):
        for entry in table.entries:
            key = (table.group, entry.name)
            if key in index:
                raise ValueError("%s.%s declared twice" % key)
            if not hasattr(owner, entry.attribute):
                raise ValueError("%s.%s: owner has no attribute %r" % (table.group, entry.name, entry.attribute))
            index[key] = len(variables)
            variables.append(_Variable(table.group, entry, owner))

    # -- log API (log.h) ---------------------------------------------------------------------------------

    def log_get_var_id(self, group: str, name: str) -> int:
        return self._log_index.get((group, name), LOG_VARID_INVALID)

    def log_var_id_is_valid(self, var_id: int) -> bool:
        return var_id != LOG_VARID_INVALID

    def _log_variable(self, var_id, caller):
        if not (isinstance(var_id, int) and 0 <= var_id < len(self._logs)):
            raise FirmwareAssertError("%s: invalid log id 0x%04X" % (caller, var_id & 0xFFFF
                                                                      if isinstance(var_id, int) else 0xFFFF))
        return self._logs[var_id]

    def log_get_float(self, var_id: int) -> float:
        return float(self._log_variable(var_id, "logGetFloat").get())

    def log_get_int(self, var_id: int) -> int:
        return int(self._log_variable(var_id, "logGetInt").get())

    def log_get_uint(self, var_id: int) -> int:
        return int(self._log_variable(var_id, "logGetUint").get()) & 0xFFFFFFFF

    def log_get_type(self, var_id: int) -> str:
        return self._log_variable(var_id, "logGetType").entry.type

    def log_get_group_and_name(self, var_id: int) -> tuple[str, str]:
        v = self._log_variable(var_id, "logGetGroupAndName")
        return v.group, v.entry.name

    # -- param API (param_logic.h) -----------------------------------------------------------------------

    def param_get_var_id(self, group: str, name: str) -> ParamVarId:
        index = self._param_index.get((group, name))
        return ParamVarId(PARAM_VARID_INVALID, 0) if index is None else ParamVarId(index, index)

    def _param_variable(self, var_id, caller):
        if not isinstance(var_id, ParamVarId) or var_id.id == PARAM_VARID_INVALID \
                or not 0 <= var_id.id < len(self._params):
            raise FirmwareAssertError("%s: invalid param id %r" % (caller, var_id))
        return self._params[var_id.id]

    def param_get_int(self, var_id: ParamVarId) -> int:
        v = self._param_variable(var_id, "paramGetInt")
        if v.entry.type not in _INTEGER_TYPES:
            raise FirmwareAssertError("paramGetInt: %s is a %s" % (v.full_name, v.entry.type))
        return int(v.get())

    def param_get_uint(self, var_id: ParamVarId) -> int:
        return self.param_get_int(var_id) & 0xFFFFFFFF

    def param_get_float(self, var_id: ParamVarId) -> float:
        v = self._param_variable(var_id, "paramGetFloat")
        if v.entry.type != PARAM_FLOAT:
            raise FirmwareAssertError("paramGetFloat: %s is a %s" % (v.full_name, v.entry.type))
        return float(v.get())

    def param_get_default(self, var_id: ParamVarId) -> float | int:
        """The param's value at registration: what the firmware's default-value query answers (the value
        in the image's initialised data, before anything set it)."""
        self._param_variable(var_id, "paramGetDefault")  # asserts the id is valid
        return self._param_defaults[var_id.id]

    def _param_writable(self, var_id, caller):
        v = self._param_variable(var_id, caller)
        if v.entry.read_only:
            raise FirmwareAssertError("%s: %s is read-only" % (caller, v.full_name))
        return v

    def param_set_int(self, var_id: ParamVarId, value: int) -> None:
        v = self._param_writable(var_id, "paramSetInt")
        if v.entry.type not in _INTEGER_TYPES:
            raise FirmwareAssertError("paramSetInt: %s is a %s" % (v.full_name, v.entry.type))
        v.set(value)

    def param_set_float(self, var_id: ParamVarId, value: float) -> None:
        v = self._param_writable(var_id, "paramSetFloat")
        if v.entry.type != PARAM_FLOAT:
            raise FirmwareAssertError("paramSetFloat: %s is a %s" % (v.full_name, v.entry.type))
        v.set(float(value))

    # -- by full name, for clients and the harness (cflib's 'group.name' strings) ------------------------

    def log_read(self, full_name: str) -> float | int:
        """Read a log variable by 'group.name'; unknown names fail loudly (KeyError naming the variable)."""
        group, _, name = full_name.partition(".")
        var_id = self.log_get_var_id(group, name)
        if var_id == LOG_VARID_INVALID:
            raise KeyError("no log variable %r" % full_name)
        return self._logs[var_id].get()

    def param_set(self, full_name: str, value: float) -> None:
        """Set a param by 'group.name' (as a client does over the radio); unknown names fail loudly."""
        group, _, name = full_name.partition(".")
        var_id = self.param_get_var_id(group, name)
        if var_id.id == PARAM_VARID_INVALID:
            raise KeyError("no parameter %r" % full_name)
        v = self._params[var_id.id]
        if v.entry.type == PARAM_FLOAT:
            self.param_set_float(var_id, value)
        else:
            self.param_set_int(var_id, value)

    def param_read(self, full_name: str) -> float | int:
        group, _, name = full_name.partition(".")
        var_id = self.param_get_var_id(group, name)
        if var_id.id == PARAM_VARID_INVALID:
            raise KeyError("no parameter %r" % full_name)
        return self._params[var_id.id].get()

    def log_names(self) -> list[str]:
        return [v.full_name for v in self._logs]

    def param_entries(self) -> list[tuple[str, Entry]]:
        return [(v.full_name, v.entry) for v in self._params]
