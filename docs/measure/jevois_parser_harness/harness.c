/* ForaNav's harness around an autopilot's JeVois parser compiled unmodified (Paparazzi's
 * sw/airborne/modules/sensors/cameras/jevois.c, not part of this repository: docs/hardware.md).
 *
 * Reads the camera's serial bytes on stdin, hands them to the parser through its UART polling function
 * (jevois_event) and prints one line per message the parser publishes on its ABI bus:
 *     <byte offset at which it was published> <type> <id or -> <nb> <coord...>
 * Build and use: docs/measure/paparazzi_jevois.py.
 */
#include <stdio.h>
#include <stdlib.h>
#include "std.h"
#include "mcu_periph/uart.h"
#include "subsystems/abi.h"
#include "modules/sensors/cameras/jevois.h"

struct uart_periph jevois_harness_uart;

void AbiSendMsgJEVOIS_MSG(uint8_t sender, uint8_t type, char *id, uint8_t nb, int16_t *coord, uint16_t *dim,
                          struct FloatQuat quat, char *extra)
{
  (void)sender; (void)dim; (void)quat; (void)extra;
  /* the byte that made the parser publish was the last one taken from the UART */
  printf("%ld %d %s %d", jevois_harness_uart.next - 1, type, (id && id[0]) ? id : "-", nb);
  for (int i = 0; i < nb && i < 18; i++) {
    printf(" %d", coord[i]);
  }
  printf("\n");
}

int main(void)
{
  static uint8_t data[1 << 24];
  long size = (long)fread(data, 1, sizeof data, stdin);
  jevois_harness_uart.data = data;
  jevois_harness_uart.size = size;
  jevois_harness_uart.next = 0;
  jevois_init();
  jevois_event();
  return 0;
}
