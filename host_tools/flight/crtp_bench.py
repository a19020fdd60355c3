"""CRTP benchmark: how many datagrams a second the server handles, and what serving a client costs a flight.

``foranav bench crtp [--json]`` prints:

- dispatch: requests a second through ``CrtpServer.handle_datagram`` (decode, service, reply) with no socket,
  for a mix of what cflib asks (log and param TOC items, param reads, echoes) and of malformed datagrams;
- udp: datagrams a second the server reads off its socket and answers while another process sends the same
  mix as fast as it can, and how many the socket dropped;
- cflib: what stock cflib's UDP driver takes in, datagrams sent at a fixed rate (why the lockstep clock waits for
  the downlink rather than sending as fast as it flies);
- flight: the oracle flight of Map 1 (what ``foranav fly --map map1 --camera oracle`` flies) without
  ``--crtp``, with ``--crtp`` and no client, and with stock cflib in another process streaming a 100 Hz log
  block of stateEstimate.x/y/z: the flight process's CPU seconds and wall seconds, and the samples received.

Prints figures, asserts nothing. ``python -m host_tools.flight.crtp_bench --client URI`` is the client process.
"""
import argparse
import json
import socket
import subprocess
import sys
import time
from dataclasses import asdict

from crazyflie_app.firmware import Crazyflie
from crazyflie_app.firmware.crtp import CrtpServer
from host_tools.flight import OracleCamera
from host_tools.flight.harness import Flight
from host_tools.maps import load_map

BENCH_MAP = "map1"
DISPATCH_DATAGRAMS = 200_000
UDP_DATAGRAMS = 200_000
CLIENT_BLOCK_MS = 10
CLIENT_QUIET_S = 2.0  # no sample for this long: the flight is over
CLIENT_START_TIMEOUT_S = 30.0
INTAKE_RATES = (1000, 5000, 20000, 50000)  # datagrams/s sent to cflib's UDP driver, for one second each
INTAKE_SETTLE_S = 0.5


def request_mix(count: int) -> list[bytes]:
    """What a connecting cflib sends, plus echoes and a share of malformed datagrams, in a fixed order."""
    kinds = [bytes([0x50, 2, 3, 0]),  # log TOC item 3
             bytes([0x20, 2, 5, 0]),  # param TOC item 5
             bytes([0x21, 5, 0]),  # param read 5
             bytes([0xF0]) + bytes(9),  # echo (cflib's ping)
             bytes([0x51, 3]),  # truncated log command
             bytes(40)]  # oversized
    return [kinds[i % len(kinds)] for i in range(count)]


def measure_dispatch(count: int = DISPATCH_DATAGRAMS) -> dict:
    server = CrtpServer(Crazyflie(), "127.0.0.1", 0)
    datagrams = request_mix(count)
    try:
        started = time.perf_counter()
        for datagram in datagrams:
            server.handle_datagram(datagram, ("127.0.0.1", 9), 0)  # answers go to the discard port
        wall = time.perf_counter() - started
    finally:
        server.close()
    return {"datagrams": count, "wall_s": round(wall, 3), "per_s": int(count / wall)}


_SENDER = """
import socket, sys
from host_tools.flight.crtp_bench import request_mix
host, port, count = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
for datagram in request_mix(count):
    sock.sendto(datagram, (host, port))
"""


def measure_udp(count: int = UDP_DATAGRAMS) -> dict:
    """A sender process blasts ``count`` datagrams; the server reads and answers as its task does."""
    server = CrtpServer(Crazyflie(), "127.0.0.1", 0, lockstep=False)
    host, port = server.address
    try:
        sender = subprocess.Popen([sys.executable, "-c", _SENDER, host, str(port), str(count)])
        server.link.wait_readable(CLIENT_START_TIMEOUT_S)
        started = time.perf_counter()
        while sender.poll() is None or server.link.wait_readable(0.2):
            server.serve_for(0.05)
        wall = time.perf_counter() - started
    finally:
        server.close()
    handled = server.stats.datagrams
    return {"sent": count, "handled": handled, "dropped_by_socket": count - handled, "wall_s": round(wall, 3),
            "per_s": int(handled / wall)}


def measure_cflib_intake() -> list[dict]:
    """Datagrams received by cflib's UdpDriver (its receive thread and queue) out of one second's worth sent at
    each rate (from this process: the sender shares the interpreter with cflib's thread, as a flight would)."""
    from cflib.crtp.crtpstack import CRTPPacket
    from cflib.crtp.udpdriver import UdpDriver

    rows = []
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sender:
        sender.bind(("127.0.0.1", 0))
        driver = UdpDriver()
        driver.connect("udp://127.0.0.1:%d" % sender.getsockname()[1], None, lambda message: None)
        try:
            driver.send_packet(CRTPPacket(0x52, bytes(20)))  # tells the sender where the driver listens
            _, address = sender.recvfrom(64)
            for rate in INTAKE_RATES:
                started = time.perf_counter()
                for i in range(rate):
                    sender.sendto(b"\x52" + i.to_bytes(4, "little") + bytes(20), address)
                    while time.perf_counter() < started + (i + 1) / rate:
                        pass
                time.sleep(INTAKE_SETTLE_S)
                received = 0
                while driver.receive_packet(0) is not None:
                    received += 1
                rows.append({"rate_per_s": rate, "sent": rate, "received": received})
        finally:
            driver.close()
    return rows


def _flight(client: bool, crtp: bool) -> dict:
    pmap = load_map(BENCH_MAP)
    options = {"crtp": "127.0.0.1:0"} if crtp else {}
    flight = Flight(pmap, OracleCamera(pmap, seed=0), seed=0, options=options)
    process = None
    try:
        if client:
            process = subprocess.Popen([sys.executable, "-m", "host_tools.flight.crtp_bench", "--client",
                                        flight.crtp.uri], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                       text=True)  # cflib reports the closed link when the flight ends
            flight.crtp.link.wait_readable(CLIENT_START_TIMEOUT_S)  # meet the client at the first tick
        wall0 = time.perf_counter()
        flight.run()
        wall = time.perf_counter() - wall0
    finally:
        flight.close()
    row = {"client": client, "crtp": crtp, "cpu_s": round(flight.cpu_s, 2), "wall_s": round(wall, 2),
           "mission_s": flight.summary()["mission_time_s"]}
    if process is not None:
        out, _ = process.communicate(timeout=60)
        row["samples"] = json.loads(out.strip().splitlines()[-1])["samples"] if out.strip() else 0
        row["server"] = asdict(flight.crtp.stats)
    return row


def measure_flights() -> list[dict]:
    return [_flight(False, False), _flight(False, True), _flight(True, True)]


def client_main(uri: str) -> int:
    """The client process: stock cflib, a 100 Hz block of the position, until the samples stop."""
    import cflib.crtp
    from cflib.crazyflie import Crazyflie as CflibCrazyflie
    from cflib.crazyflie.log import LogConfig
    from cflib.crazyflie.syncCrazyflie import SyncCrazyflie

    cflib.crtp.init_drivers()
    samples = []
    with SyncCrazyflie(uri, cf=CflibCrazyflie()) as scf:
        block = LogConfig("bench", CLIENT_BLOCK_MS)
        for name in ("stateEstimate.x", "stateEstimate.y", "stateEstimate.z"):
            block.add_variable(name)
        scf.cf.log.add_config(block)
        block.data_received_cb.add_callback(lambda ts, data, _: samples.append(ts))
        block.start()
        seen = -1
        while len(samples) != seen:
            seen = len(samples)
            time.sleep(CLIENT_QUIET_S)
    print(json.dumps({"samples": len(samples)}))
    return 0


def run(args: argparse.Namespace) -> int:
    results = {"dispatch": measure_dispatch(), "udp": measure_udp(), "cflib": measure_cflib_intake(),
               "flight": measure_flights()}
    if getattr(args, "json", False):
        print(json.dumps({"crtp": results}, indent=2))
        return 0
    d, u = results["dispatch"], results["udp"]
    print("dispatch  %d requests/s (%d in %.2f s, no socket)" % (d["per_s"], d["datagrams"], d["wall_s"]))
    print("udp       %d datagrams/s handled (%d of %d sent; %d dropped by the socket)" % (
        u["per_s"], u["handled"], u["sent"], u["dropped_by_socket"]))
    print("cflib     " + "; ".join("%d of %d received at %d/s" % (r["received"], r["sent"], r["rate_per_s"])
                                   for r in results["cflib"]))
    print("%-34s %8s %8s %12s %9s" % ("flight (map1, oracle)", "CPU (s)", "wall (s)", "mission (s)", "samples"))
    for row in results["flight"]:
        label = "with --crtp, cflib 100 Hz block" if row["client"] else (
            "with --crtp, no client" if row["crtp"] else "without --crtp")
        print("%-34s %8.2f %8.2f %12.1f %9s" % (label, row["cpu_s"], row["wall_s"], row["mission_s"],
                                               row.get("samples", "-")))
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--client", metavar="URI", help="run the cflib client process of the flight figures")
    arguments = parser.parse_args()
    sys.exit(client_main(arguments.client) if arguments.client else run(arguments))
