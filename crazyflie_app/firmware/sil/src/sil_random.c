#include "sil_random.h"

#include <math.h>

static uint64_t next64(sil_random_t *rng) {
  uint64_t z = (rng->state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

void silRandomInit(sil_random_t *rng, uint64_t seed, uint64_t stream) {
  rng->state = seed * 0x2545F4914F6CDD1Dull + stream * 0x9E3779B97F4A7C15ull + 1u;
  rng->has_spare = 0;
  rng->spare = 0.0;
  next64(rng);  /* decorrelate neighbouring seeds */
}

double silRandomUniform(sil_random_t *rng) {
  return (double)(next64(rng) >> 11) * (1.0 / 9007199254740992.0);
}

double silRandomGauss(sil_random_t *rng, double std) {
  if (std <= 0.0) {
    return 0.0;
  }
  if (rng->has_spare) {
    rng->has_spare = 0;
    return rng->spare * std;
  }
  double u1 = silRandomUniform(rng);
  double u2 = silRandomUniform(rng);
  if (u1 < 1e-300) {
    u1 = 1e-300;
  }
  const double radius = sqrt(-2.0 * log(u1));
  rng->spare = radius * sin(2.0 * M_PI * u2);
  rng->has_spare = 1;
  return radius * cos(2.0 * M_PI * u2) * std;
}
