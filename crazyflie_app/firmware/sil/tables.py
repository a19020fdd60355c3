"""The firmware's own LOG and PARAM tables, read out of the firmware plant's library at run time.

Every firmware file compiled into ``libforanav_sil.so`` declares its groups with the firmware's real
``LOG_GROUP_START`` / ``PARAM_GROUP_START`` macros (``src/shim/log.h`` and ``param.h`` keep them live in this
host build), so each group is a ``struct log_s`` / ``struct param_s`` array in a ``.log.<group>`` /
``.param.<group>`` section, gathered by ``src/sil_tables.ld`` between ``_log_start`` and ``_log_stop`` (and
``_param_*``) as the firmware's linker script does. This module walks those arrays as the firmware's log.c and
param_logic.c walk theirs and hands each group to the emulated Crazyflie's registry, with an owner whose
attributes read and write the firmware's variables at their addresses: a write from cflib lands in the
firmware's variable (and runs its PARAM_ADD_WITH_CALLBACK callback, as paramWriteProcess does), a log block
samples the variable the firmware's code updates. Nothing here names a group or a variable.
"""
import ctypes
from collections.abc import Callable
from dataclasses import dataclass

from crazyflie_app.firmware.logparam import (LOG_FLOAT, LOG_INT8, LOG_INT16, LOG_INT32, LOG_UINT8, LOG_UINT16,
                                              LOG_UINT32, Entry, Group)

# log.h
LOG_TYPES = {1: LOG_UINT8, 2: LOG_UINT16, 3: LOG_UINT32, 4: LOG_INT8, 5: LOG_INT16, 6: LOG_INT32, 7: LOG_FLOAT}
LOG_FP16 = 8
LOG_TYPE_MASK = 0x0F
LOG_BY_FUNCTION, LOG_GROUP, LOG_START = 0x40, 0x80, 1
# param.h
PARAM_TYPES = {0x08: LOG_UINT8, 0x00: LOG_INT8, 0x09: LOG_UINT16, 0x01: LOG_INT16, 0x0A: LOG_UINT32,
               0x02: LOG_INT32, 0x06: LOG_FLOAT}
PARAM_TYPE_MASK, PARAM_RONLY, PARAM_GROUP, PARAM_START = 0x0F, 0x40, 0x80, 1
C_TYPES = {LOG_UINT8: ctypes.c_uint8, LOG_UINT16: ctypes.c_uint16, LOG_UINT32: ctypes.c_uint32,
           LOG_INT8: ctypes.c_int8, LOG_INT16: ctypes.c_int16, LOG_INT32: ctypes.c_int32, LOG_FLOAT: ctypes.c_float}


class _LogS(ctypes.Structure):
    """log.h struct log_s"""
    _fields_ = [("type", ctypes.c_uint8), ("name", ctypes.c_char_p), ("address", ctypes.c_void_p)]


class _ParamS(ctypes.Structure):
    """param.h struct param_s"""
    _fields_ = [("type", ctypes.c_uint8), ("extended_type", ctypes.c_uint8), ("name", ctypes.c_char_p),
                ("address", ctypes.c_void_p), ("callback", ctypes.c_void_p), ("getter", ctypes.c_void_p)]


class _LogByFunction(ctypes.Structure):
    """log.h logByFunction_t: an acquire function (its union's first member) and its data"""
    _fields_ = [("acquire", ctypes.c_void_p), ("data", ctypes.c_void_p)]


@dataclass(frozen=True)
class Variable:
    """One LOG_ADD / PARAM_ADD of the firmware: where it lives and how to read it."""
    kind: str  # "log" or "param"
    group: str
    name: str
    type: str  # logparam's C type names
    address: int
    read_only: bool = True
    by_function: bool = False  # LOG_ADD_BY_FUNCTION: address is a logByFunction_t
    callback: int = 0  # PARAM_ADD_WITH_CALLBACK: run after a write

    @property
    def key(self) -> str:
        return "%s:%s.%s" % (self.kind, self.group, self.name)


def _table(lib: ctypes.CDLL, prefix: str, struct: type) -> list:
    start = ctypes.addressof(ctypes.c_char.in_dll(lib, "_%s_start" % prefix))
    stop = ctypes.addressof(ctypes.c_char.in_dll(lib, "_%s_stop" % prefix))
    count = (stop - start) // ctypes.sizeof(struct)
    return list((struct * count).from_address(start))


def _walk(rows, is_group, is_start, variable) -> tuple[list[Variable], list[str]]:
    """The variables of a table in declaration order, each in the group its last GROUP_START opened (the
    firmware's own walk); entries of a type this host cannot read are named in ``skipped``."""
    variables, skipped, group = [], [], None
    for row in rows:
        if row.type & is_group:
            group = row.name.decode() if row.type & is_start else None
            continue
        if group is None:
            continue
        made = variable(group, row)
        if made is None:
            skipped.append("%s.%s" % (group, row.name.decode()))
        else:
            variables.append(made)
    return variables, skipped


def _log_variable(group: str, row: _LogS) -> Variable | None:
    var_type = LOG_TYPES.get(row.type & LOG_TYPE_MASK)
    if var_type is None:  # LOG_FP16 variables: none in the files compiled here
        return None
    return Variable("log", group, row.name.decode(), var_type, row.address or 0,
                    by_function=bool(row.type & LOG_BY_FUNCTION))


def _param_variable(group: str, row: _ParamS) -> Variable | None:
    var_type = PARAM_TYPES.get(row.type & PARAM_TYPE_MASK)
    if var_type is None or not row.address:  # a param with a getter only (none here) has no address
        return None
    return Variable("param", group, row.name.decode(), var_type, row.address, read_only=bool(row.type & PARAM_RONLY),
                    callback=row.callback or 0)


class FirmwareVariables:
    """The owner the registry reads and writes: attribute ``group.name`` is the firmware's variable."""

    def __init__(self, lib: ctypes.CDLL, tick: Callable[[], int]):
        object.__setattr__(self, "_cells", {})
        object.__setattr__(self, "_callbacks", {})
        object.__setattr__(self, "_functions", {})
        object.__setattr__(self, "_lib", lib)  # keeps the library mapped while its addresses are used
        object.__setattr__(self, "_tick", tick)

    def add(self, variable: Variable) -> None:
        if variable.by_function:
            acquire = _LogByFunction.from_address(variable.address)
            function = ctypes.CFUNCTYPE(C_TYPES[variable.type], ctypes.c_uint32, ctypes.c_void_p)(acquire.acquire)
            self._functions[variable.key] = (function, acquire.data)
            return
        self._cells[variable.key] = C_TYPES[variable.type].from_address(variable.address)
        if variable.callback:
            self._callbacks[variable.key] = ctypes.CFUNCTYPE(None)(variable.callback)

    def freeze(self) -> None:
        """Before the library is unloaded: every variable keeps its last value, in memory of its own."""
        for key, cell in list(self._cells.items()):
            self._cells[key] = type(cell)(cell.value)
        for key in list(self._functions):
            function, data = self._functions.pop(key)
            self._cells[key] = C_TYPES[LOG_FLOAT](function(self._tick() & 0xFFFFFFFF, data))
        self._callbacks.clear()
        object.__setattr__(self, "_lib", None)

    def __getattr__(self, key: str):
        cell = self._cells.get(key)
        if cell is not None:
            return cell.value
        if key in self._functions:
            function, data = self._functions[key]
            return function(self._tick() & 0xFFFFFFFF, data)
        raise AttributeError(key)

    def __setattr__(self, key: str, value) -> None:
        cell = self._cells.get(key)
        if cell is None:
            raise AttributeError(key)
        cell.value = value
        callback = self._callbacks.get(key)
        if callback is not None:  # param_logic.c paramNotifyChanged()
            callback()


@dataclass
class FirmwareTables:
    """The firmware's log and param groups, for ``LogParamRegistry.register_*_group``."""
    log_groups: list[Group]
    param_groups: list[Group]
    owner: FirmwareVariables
    skipped: list[str]  # variables of a type the registry cannot serve (none in the files compiled here)

    def log_names(self) -> set[str]:
        return {"%s.%s" % (g.group, e.name) for g in self.log_groups for e in g.entries}

    def param_names(self) -> set[str]:
        return {"%s.%s" % (g.group, e.name) for g in self.param_groups for e in g.entries}


def _groups(variables: list[Variable]) -> list[Group]:
    """Consecutive variables of one group as one Group (a group declared in two files stays two)."""
    groups = []
    for variable in variables:
        entry = Entry(variable.type, variable.name, variable.key, "", "", variable.read_only)
        if groups and groups[-1].group == variable.group:
            groups[-1] = Group(variable.group, groups[-1].entries + (entry,))
        else:
            groups.append(Group(variable.group, (entry,)))
    return groups


def read_tables(lib: ctypes.CDLL, tick: Callable[[], int]) -> FirmwareTables:
    """Walk the library's log and param tables (after sil_boot: defaults are the booted values)."""
    logs, log_skipped = _walk(_table(lib, "log", _LogS), LOG_GROUP, LOG_START, _log_variable)
    params, param_skipped = _walk(_table(lib, "param", _ParamS), PARAM_GROUP, PARAM_START, _param_variable)
    owner = FirmwareVariables(lib, tick)
    for variable in logs + params:
        owner.add(variable)
    return FirmwareTables(_groups(logs), _groups(params), owner, log_skipped + param_skipped)
