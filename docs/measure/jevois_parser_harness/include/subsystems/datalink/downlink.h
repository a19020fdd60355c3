/* Stand-in for Paparazzi's telemetry: the harness reports through ABI only (ForaNav harness). */
#ifndef HARNESS_DOWNLINK_H
#define HARNESS_DOWNLINK_H
#define DefaultChannel 0
#define DefaultDevice 0
#define DOWNLINK_SEND_JEVOIS(...) do { } while (0)
#endif
