// rs_rng.c -- xoshiro256** seeded by splitmix64. See rs_rng.h.
#include "core/rs_rng.h"

#include <math.h>

#define GOLDEN_GAMMA 0x9e3779b97f4a7c15ULL

uint64_t rs_rng_mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

uint64_t rs_rng_seed_next(uint64_t *state)
{
    *state += GOLDEN_GAMMA;
    return rs_rng_mix64(*state);
}

uint64_t rs_rng_seed_derive(uint64_t seed, uint64_t k) { return rs_rng_mix64(seed + GOLDEN_GAMMA * (k + 1)); }

double rs_rng_u01(uint64_t x) { return (double)(x >> 11) * 0x1.0p-53; }

void rs_rng_seed(rs_rng *rng, uint64_t seed)
{
    uint64_t x = seed;
    for (int i = 0; i < 4; i++) rng->s[i] = rs_rng_seed_next(&x);
}

static uint64_t rotl64(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

uint64_t rs_rng_u64(rs_rng *rng)
{
    uint64_t *s = rng->s;
    const uint64_t result = rotl64(s[1] * 5, 7) * 9;
    const uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl64(s[3], 45);
    return result;
}

double rs_rng_uniform(rs_rng *rng) { return rs_rng_u01(rs_rng_u64(rng)); }

double rs_rng_uniform_in(rs_rng *rng, double lo, double hi) { return lo + (hi - lo) * rs_rng_uniform(rng); }

double rs_rng_normal(rs_rng *rng)
{
    const double u1 = 1.0 - rs_rng_uniform(rng); // (0, 1]
    const double u2 = rs_rng_uniform(rng);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * M_PI * u2);
}
