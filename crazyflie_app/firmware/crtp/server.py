"""The CRTP server of one emulated Crazyflie: its link, its services, and the task that runs them.

``CrtpServer(cf, host, port, lockstep=True)`` binds ``udp://host:port`` (cflib's UDP link) and, once
``start()`` has created its task (``CRTP``, priority 0: on a tick it runs after the stabilizer and the app, so
a log sample shows that tick's state), serves every port a client uses through the emulated Crazyflie's public
services only: ``cf.registry`` (log and param), ``cf.console``, ``cf.commander_set_setpoint(sp,
COMMANDER_PRIORITY_CRTP)``, ``cf.supervisor_request_arming`` and ``cf.supervisor_get_info_bitfield``, the
tick clock and ``cf.x_task_create``.

The client is the address of the latest request that was not a keep-alive (a null packet or an echo, which are
answered whoever sends them: cflib's scan probes with a null packet). A client that has sent nothing for
``CLIENT_TIMEOUT_S`` (the firmware's radio activity timeout) is gone: its log blocks are deleted, as the
firmware's logReset when the link drops. Replies go to whoever asked; log data and console text go to the
client. The log blocks are the Crazyflie's, not a client's: the firmware has one link and no notion of who
is on it, so a second client's request changes where the data go (as the SITL socket link answers whoever
spoke last) but deletes nothing; the log reset that cflib sends when it connects deletes every block, the
first client's too, as on a Crazyflie (docs/crtp.md, "A second client").

The clock. Without a client the task only looks at the socket every ``CRTP_POLL_MS`` of simulated time and
never waits, so a flight's outputs are the same bytes as without the server. With a client, in lockstep:

- while the client keeps sending requests (the next one within ``HOLD_QUIET_S`` of the last), the clock
  holds: a client's exchange (its connection: the TOCs, every param value, its log blocks; a param write)
  happens at one simulated instant, so a client loses nothing of the flight from the moment it spoke. A
  client that never stops talking cannot freeze the flight: holding draws on ``HOLD_BANK_S`` of wall time,
  refilled at ``HOLD_PER_SIM_S`` per simulated second;
- log data and console text wait for the downlink (``link.DownlinkBudget``) instead of being dropped: the
  clock runs no faster than the link carries what the client asked for.

With ``lockstep=False`` (``--realtime``) nothing holds the wall clock: requests are served while the pacer
waits (``serve_for``), and what the downlink cannot carry is dropped (log data, counted) or kept for later
(console text, in its bounded backlog), as on the MAV.
"""
import time
from dataclasses import dataclass

from crazyflie_app.firmware import freertos
from crazyflie_app.firmware.crtp import link_service
from crazyflie_app.firmware.crtp.commander_service import CommanderService
from crazyflie_app.firmware.crtp.console_service import ConsoleService
from crazyflie_app.firmware.crtp.high_level_service import HighLevelService
from crazyflie_app.firmware.crtp.link import Address, DownlinkBudget, UdpLink
from crazyflie_app.firmware.crtp.log_service import LogService
from crazyflie_app.firmware.crtp.mem_service import MemService
from crazyflie_app.firmware.crtp.packet import (CRTP_PORT_LINK, CRTP_PORT_LOCALIZATION, CRTP_PORT_LOG, CRTP_PORT_MEM,
                                                CRTP_PORT_PARAM, CRTP_PORT_PLATFORM, CRTP_PORT_SETPOINT,
                                                CRTP_PORT_SETPOINT_GENERIC, CRTP_PORT_SETPOINT_HL,
                                                CRTP_PORT_SUPERVISOR, CrtpPacket, MalformedPacket, Unserved, decode)
from crazyflie_app.firmware.crtp.param_service import ParamService
from crazyflie_app.firmware.crtp.platform_service import PlatformService
from crazyflie_app.firmware.crtp.supervisor_service import SupervisorService

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 19850  # cflib's UDP scan probes 19850..19859
CRTP_TASK_PRI = 0
CRTP_POLL_MS = 10  # simulated ms between two looks at the socket
CLIENT_TIMEOUT_S = 1.0  # CONFIG_RADIO_ACTIVITY_TIMEOUT_MS
HOLD_QUIET_S = 0.05  # a client's next request within this: still the same exchange (cflib under load)
HOLD_BANK_S = 2.0
HOLD_PER_SIM_S = 1.0
MAX_DATAGRAMS_PER_BURST = 256  # read at a time; the rest waits in the socket (whose buffer bounds a flood)
# the firmware's, not this emulation's (the high-level commander: the reduced plant has none)
UNSERVED_PORTS = (CRTP_PORT_LOCALIZATION, CRTP_PORT_SETPOINT_HL)


@dataclass
class CrtpStats:
    """What the server has seen and done (``foranav bench``-style figures and the robustness tests)."""
    datagrams: int = 0
    malformed: int = 0  # empty, oversized, or unparsable by its service
    unserved: int = 0  # the firmware serves it, this emulation does not
    unknown_port: int = 0
    replies: int = 0
    streamed: int = 0  # log data and console packets sent
    stream_dropped: int = 0  # log data the downlink could not carry (realtime only)
    connections: int = 0
    lost_clients: int = 0
    held_s: float = 0.0  # wall time the clock held for a talking client (lockstep)
    waited_s: float = 0.0  # wall time the clock waited for the downlink (lockstep)


class _HoldBank:
    """Wall seconds the clock may still hold for a client: refilled as simulated time passes."""

    def __init__(self):
        self.seconds = HOLD_BANK_S
        self._tick = 0

    def refill(self, tick: int) -> None:
        self.seconds = min(HOLD_BANK_S, self.seconds + (tick - self._tick) / 1000.0 * HOLD_PER_SIM_S)
        self._tick = tick


class CrtpServer:
    """Serve the emulated Crazyflie ``cf`` on ``udp://host:port`` (port 0: any free port, see ``address``)."""

    def __init__(self, cf, host: str = DEFAULT_HOST, port: int = DEFAULT_PORT, *, lockstep: bool = True):
        self.cf = cf
        self.lockstep = bool(lockstep)
        self.link = UdpLink(host, port)
        self.budget = DownlinkBudget()
        self.stats = CrtpStats()
        self.log = LogService(cf.registry)
        self.param = ParamService(cf.registry)
        self.commander = CommanderService(cf)
        self.console = ConsoleService(cf.console)
        self._handlers = {
            CRTP_PORT_PARAM: self.param.handle, CRTP_PORT_LOG: self.log.handle,
            CRTP_PORT_MEM: MemService(cf.registry, cf.high_level).handle,
            CRTP_PORT_SETPOINT: self.commander.handle, CRTP_PORT_SETPOINT_GENERIC: self.commander.handle,
            CRTP_PORT_SUPERVISOR: SupervisorService(cf).handle, CRTP_PORT_PLATFORM: PlatformService(cf).handle,
            CRTP_PORT_LINK: link_service.handle,
        }
        self.high_level = None
        if cf.high_level is not None:  # the firmware plant runs the firmware's high-level commander
            self.high_level = HighLevelService(cf.high_level)
            self._handlers[CRTP_PORT_SETPOINT_HL] = self.high_level.handle
        self.client: Address | None = None
        self._last_heard = 0.0
        self._hold = _HoldBank()
        self.closed = False

    @property
    def address(self) -> Address:
        return self.link.address

    @property
    def uri(self) -> str:
        host, port = self.address
        return "udp://%s:%d" % (host, port)

    def start(self) -> None:
        """Create the server's task on the Crazyflie (at the current tick)."""
        self.cf.x_task_create(self.task(), "CRTP", CRTP_TASK_PRI)

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            self.console.detach()
            self.link.close()

    # -- the task -------------------------------------------------------------------------------------------

    def task(self) -> freertos.Task:
        while not self.closed:
            now = self.cf.x_task_get_tick_count()
            self._serve(now)
            self._check_client()
            self._stream(now)
            wake = now + CRTP_POLL_MS
            due = self.log.next_due()
            if due is not None:
                wake = min(wake, due)
            yield freertos.v_task_delay(max(1, wake - now))

    def _serve(self, now: int) -> None:
        """Answer what is waiting; in lockstep, hold the clock while the client keeps asking."""
        self._hold.refill(now)
        held_from = None
        while self._serve_burst(now) and self.lockstep:
            if held_from is None:
                held_from = time.monotonic()
            left = self._hold.seconds - (time.monotonic() - held_from)
            if left <= 0 or not self.link.wait_readable(min(HOLD_QUIET_S, left)):
                break
        if held_from is not None:
            spent = time.monotonic() - held_from
            self._hold.seconds -= spent
            self.stats.held_s += spent

    def _serve_burst(self, now: int) -> bool:
        """Handle up to MAX_DATAGRAMS_PER_BURST waiting datagrams; True if the client asked for something."""
        talking = False
        for _ in range(MAX_DATAGRAMS_PER_BURST):
            received = self.link.receive()
            if received is None:
                break
            talking |= self.handle_datagram(received[0], received[1], now)
        return talking

    def serve_for(self, seconds: float) -> None:
        """Serve requests as they come for ``seconds`` of wall time (the realtime pacer's wait)."""
        deadline = time.monotonic() + seconds
        while not self.closed:
            left = deadline - time.monotonic()
            if left <= 0 or not self.link.wait_readable(left):
                return
            self._serve_burst(self.cf.x_task_get_tick_count())

    # -- one datagram ---------------------------------------------------------------------------------------

    def handle_datagram(self, datagram: bytes, address: Address, now: int) -> bool:
        """Decode, dispatch and answer one datagram; True when it was a request of the client (not a
        keep-alive). Never raises for what a client sends."""
        self.stats.datagrams += 1
        packet = decode(datagram)
        if packet is None:
            self.stats.malformed += 1
            return False
        keepalive = link_service.is_keepalive(packet)
        if address != self.client and not keepalive:
            self._new_client(address)
        if address == self.client:
            self._last_heard = time.monotonic()
        for answer in self._dispatch(packet, now):
            self.link.send(answer.encode(), address)
            self.stats.replies += 1
        return not keepalive

    def _dispatch(self, packet: CrtpPacket, now: int) -> list[CrtpPacket]:
        handler = self._handlers.get(packet.port)
        if handler is None:
            if packet.port in UNSERVED_PORTS:
                self.stats.unserved += 1
            else:
                self.stats.unknown_port += 1
            return []
        try:
            return handler(packet, now)
        except MalformedPacket:
            self.stats.malformed += 1
        except Unserved:
            self.stats.unserved += 1
        return []

    # -- the client -----------------------------------------------------------------------------------------

    def _new_client(self, address: Address) -> None:
        self.client = address  # the downlink follows; the blocks stay (the firmware's log is one for all)
        self.stats.connections += 1

    def _check_client(self) -> None:
        if self.client is not None and time.monotonic() - self._last_heard > CLIENT_TIMEOUT_S:
            self.client = None
            self.log.reset()
            self.stats.lost_clients += 1

    # -- what the Crazyflie sends on its own ----------------------------------------------------------------

    def _stream(self, now: int) -> None:
        samples = self.log.due_packets(now)  # no blocks without a client: then this only keeps time
        if self.client is None:
            return
        for packet in samples:
            self._send_stream(packet, droppable=True)
        while self.console.pending and self.client is not None:
            if not self._send_stream(self.console.pending[0], droppable=False):
                break
            self.console.pending.popleft()

    def _send_stream(self, packet: CrtpPacket, droppable: bool) -> bool:
        if not self.budget.take():
            if not self.lockstep:
                self.stats.stream_dropped += droppable
                return False
            started = time.monotonic()
            while not self.budget.take():  # lockstep: the clock waits for the downlink
                time.sleep(self.budget.seconds_to_next())
            self.stats.waited_s += time.monotonic() - started
        self.link.send(packet.encode(), self.client)
        self.stats.streamed += 1
        return True
