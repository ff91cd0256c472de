// rs_rng.h -- roadside's one random generator: xoshiro256** (Blackman & Vigna, "Scrambled
// linear pseudorandom number generators", ACM TOMS 47(4), 2021), seeded through splitmix64
// (Steele, Lea & Flood, "Fast splittable pseudorandom number generators", OOPSLA 2014).
//
// Every module draws from this generator: the site simulator, the vehicle fleet, traffic,
// appearance noise, the dataset's per-image streams and the evaluation benchmark's data. The
// same seed gives bit-identical draws on every machine with IEEE doubles and the same libm
// (the normal uses log and cos).
//
// Seeds for independent sub-streams (one per image, one per vehicle, ...) are derived with
// splitmix64, the same function that seeds the generator: rs_rng_seed_next() steps a seed
// sequence, rs_rng_seed_derive() gives the k-th member of one without stepping.
#pragma once
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    uint64_t s[4];
} rs_rng;

// Seeds the generator. Any seed is fine, 0 included.
void rs_rng_seed(rs_rng *rng, uint64_t seed);

// The next 64 random bits.
uint64_t rs_rng_u64(rs_rng *rng);

// Uniform in [0, 1), 53 random bits.
double rs_rng_uniform(rs_rng *rng);

// Uniform in [lo, hi): lo + (hi - lo) * rs_rng_uniform().
double rs_rng_uniform_in(rs_rng *rng, double lo, double hi);

// Standard normal N(0, 1) by Box-Muller; no state is cached, so a draw never depends on the
// parity of the draws before it.
double rs_rng_normal(rs_rng *rng);

// splitmix64's output function (a bijective 64-bit mixer).
uint64_t rs_rng_mix64(uint64_t z);

// One step of the splitmix64 sequence: advances *state by the golden-ratio increment and
// returns the mixed value. What rs_rng_seed() uses to fill the generator's state.
uint64_t rs_rng_seed_next(uint64_t *state);

// The k-th (k >= 0) member of the splitmix64 sequence that starts at `seed`, without stepping:
// rs_rng_mix64(seed + 0x9e3779b97f4a7c15 (k + 1)).
uint64_t rs_rng_seed_derive(uint64_t seed, uint64_t k);

// A double in [0, 1) from the top 53 bits of x.
double rs_rng_u01(uint64_t x);

#ifdef __cplusplus
}
#endif
