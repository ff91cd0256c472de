// test_rng_dump.c -- prints draws of core/rs_rng.h for test_rng.py, which recomputes them with an
// independent implementation of xoshiro256** and splitmix64 (Python integers).
//   test_rng_dump SEED COUNT   one line per draw: u64 (decimal), uniform, normal (%.17g)
//   test_rng_dump derive SEED  rs_rng_seed_derive(SEED, k) and rs_rng_seed_next for k = 0..9
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_rng.h"

int main(int argc, char **argv)
{
    if (argc == 3 && !strcmp(argv[1], "derive")) {
        const uint64_t seed = strtoull(argv[2], NULL, 10);
        uint64_t state = seed;
        for (uint64_t k = 0; k < 10; k++) {
            const uint64_t next = rs_rng_seed_next(&state);
            printf("%" PRIu64 " %" PRIu64 "\n", rs_rng_seed_derive(seed, k), next);
        }
        return 0;
    }
    if (argc != 3) {
        fprintf(stderr, "usage: test_rng_dump SEED COUNT | derive SEED\n");
        return 2;
    }
    rs_rng rng;
    rs_rng_seed(&rng, strtoull(argv[1], NULL, 10));
    const long n = strtol(argv[2], NULL, 10);
    for (long i = 0; i < n; i++) {
        const uint64_t u = rs_rng_u64(&rng);
        const double x = rs_rng_uniform(&rng);
        const double z = rs_rng_normal(&rng);
        printf("%" PRIu64 " %.17g %.17g\n", u, x, z);
    }
    return 0;
}
