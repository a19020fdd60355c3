/* Stand-in for Paparazzi's std.h, with only what modules/sensors/cameras/jevois.c uses (ForaNav harness). */
#ifndef HARNESS_STD_H
#define HARNESS_STD_H
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#define Max(x, y) ((x) > (y) ? (x) : (y))
#define RadOfDeg(d) ((d) * 3.14159265358979f / 180.f)
#endif
