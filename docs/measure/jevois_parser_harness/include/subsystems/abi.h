/* Stand-in for Paparazzi's ABI bus: each JEVOIS_MSG the parser publishes is printed by the harness (ForaNav). */
#ifndef HARNESS_ABI_H
#define HARNESS_ABI_H
#include <stdint.h>
#include "math/pprz_algebra_float.h"
#define CAM_JEVOIS_ID 1
void AbiSendMsgJEVOIS_MSG(uint8_t sender, uint8_t type, char *id, uint8_t nb, int16_t *coord, uint16_t *dim,
                          struct FloatQuat quat, char *extra);
#define AbiSendMsgFOLLOW_TARGET(...) do { } while (0)
#endif
