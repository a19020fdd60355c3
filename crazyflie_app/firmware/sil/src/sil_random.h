/* A seeded random stream for the plant and the sensors (splitmix64: small, fast, and the same numbers on
 * every host, unlike rand()). Each noise source owns its own stream, so adding one never shifts another. */
#pragma once
#include <stdint.h>

typedef struct {
  uint64_t state;
  int has_spare;
  double spare;
} sil_random_t;

void silRandomInit(sil_random_t *rng, uint64_t seed, uint64_t stream);
double silRandomUniform(sil_random_t *rng);          /* [0, 1) */
double silRandomGauss(sil_random_t *rng, double std); /* N(0, std^2) */
