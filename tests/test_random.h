/* test_random.h — deterministic random numbers for tests (splitmix64).
 * Define BS_TEST_SEED before including to give a test file its own stream. */
#ifndef BS_TEST_RANDOM_H
#define BS_TEST_RANDOM_H

#include <math.h>
#include <stdint.h>

#ifndef BS_TEST_SEED
#define BS_TEST_SEED 0x9E3779B97F4A7C15ull
#endif

static uint64_t rng = BS_TEST_SEED;

/* Uniform in [0, 1). */
static inline double urand(void) {
  uint64_t z = (rng += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return (double)(z >> 11) * 0x1.0p-53;
}

/* Standard normal (Box–Muller). */
static inline double nrand(void) {
  double u = urand(), v = urand();
  return sqrt(-2.0 * log(u + 1e-300)) * cos(6.283185307179586 * v);
}

/* A uniformly random rotation (from a random unit quaternion), row-major. */
static inline void rand_rot(double Q[9]) {
  double q[4], n = 0;
  for (int i = 0; i < 4; i++) {
    q[i] = nrand();
    n += q[i] * q[i];
  }
  n = sqrt(n);
  double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
  Q[0] = 1 - 2 * (y * y + z * z), Q[1] = 2 * (x * y - z * w), Q[2] = 2 * (x * z + y * w);
  Q[3] = 2 * (x * y + z * w), Q[4] = 1 - 2 * (x * x + z * z), Q[5] = 2 * (y * z - x * w);
  Q[6] = 2 * (x * z - y * w), Q[7] = 2 * (y * z + x * w), Q[8] = 1 - 2 * (x * x + y * y);
}

#endif
