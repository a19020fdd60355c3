/* Stand-in for Paparazzi's UART driver: the harness serves the camera's bytes from a buffer (ForaNav harness). */
#ifndef HARNESS_UART_H
#define HARNESS_UART_H
#include <stdint.h>
#include <stdbool.h>
struct uart_periph { const uint8_t *data; long size; long next; };
extern struct uart_periph jevois_harness_uart;
static inline bool uart_char_available(struct uart_periph *p) { return p->next < p->size; }
static inline uint8_t uart_getch(struct uart_periph *p) { return p->data[p->next++]; }
static inline void uart_put_byte(struct uart_periph *p, long fd, uint8_t b) { (void)p; (void)fd; (void)b; }
#endif
