"""CRTP over UDP: the emulated Crazyflie as cflib and cfclient see a real one (docs/crtp.md).

One small module per port or job, as the firmware's crtp*.c files:

    packet               crtp.h: the packet, its datagram form, and how a request can be wrong
    link                 the UDP transport (cflib's udp:// link) and the downlink's budget
    server               CrtpServer: the client, the dispatch, the task, and how the clock waits for a client
    link_service         port 15: echo, source, sink, null packets (crtpservice.c)
    platform_service     port 13: protocol/firmware version, device type, deprecated arming (platformservice.c)
    console_service      port 0: the console lines (console.c)
    log_service          port 5: log TOC, blocks, data (log.c)
    param_service        port 2: param TOC, read, write, misc (param_logic.c)
    mem_service          port 4: the Loco deck's memory, empty: no anchors (crtp_mem.c)
    commander_service    ports 3 and 7: setpoints at COMMANDER_PRIORITY_CRTP (crtp_commander*.c)
    supervisor_service   port 9: state bits and arming (crtp_supervisor.c)
    toc, values          the TOC format both log and param use; the type codes and C conversions of values
"""
from crazyflie_app.firmware.crtp.server import DEFAULT_HOST, DEFAULT_PORT, CrtpServer, CrtpStats  # noqa: F401
