// test_mot_assign.c -- rs_mot_assign (eval/mot/rs_mot_assign.h) against brute force over every
// partial matching of small random matrices (up to 6 x 6, with forbidden pairs and ties of
// nothing): the same number of pairs and the same least sum (1e-9), the matching consistent
// (row_to_col and col_to_row inverse, allowed pairs only, its sum the reported one); a 300 x 300
// case for the cost's order (no timing), and the empty and bad-size cases.
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

#include "core/rs_rng.h"
#include "eval/mot/rs_mot_assign.h"
#include "tests/common/rs_test.h"

// Brute force: the best (most pairs, then least sum) over all partial matchings of rows i.. to
// the columns not in `used`. out: *best_n, *best_sum
static void brute(const double *c, int R, int C, int i, unsigned used, int n, double sum, int *best_n, double *best_sum)
{
    if (i == R) {
        if (n > *best_n || (n == *best_n && sum < *best_sum)) *best_n = n, *best_sum = sum;
        return;
    }
    brute(c, R, C, i + 1, used, n, sum, best_n, best_sum); // row i unmatched
    for (int j = 0; j < C; j++)
        if (!(used & (1u << j)) && isfinite(c[i * C + j]))
            brute(c, R, C, i + 1, used | (1u << j), n + 1, sum + c[i * C + j], best_n, best_sum);
}

int main(void)
{
    rs_test_seed = 39;
    rs_rng rng;
    rs_rng_seed(&rng, rs_test_seed);
    rs_err err = {0};
    for (int t = 0; t < 3000; t++) {
        const int R = (int)(rs_rng_u64(&rng) % 7), C = (int)(rs_rng_u64(&rng) % 7);
        const double p_forbid = rs_rng_uniform(&rng) * 0.7;
        const bool negative = t % 3 == 0; // IDF1 and HOTA minimise negated scores
        double c[36];
        for (int k = 0; k < R * C; k++)
            c[k] = rs_rng_uniform(&rng) < p_forbid ? (t % 2 ? INFINITY : NAN)
                                                   : (negative ? -1 : 1) * rs_rng_uniform_in(&rng, 0, 10);
        int row[7], col[7], N = -1;
        rs_status st = rs_mot_assign(row, col, &N, c, R, C, &err);
        CHECK(st == RS_OK, "case %d: %s", t, err.msg);
        int best_n = -1;
        double best_sum = INFINITY;
        brute(c, R, C, 0, 0, 0, 0, &best_n, &best_sum);
        double sum = 0;
        int n = 0;
        for (int i = 0; i < R; i++) {
            if (row[i] < 0) continue;
            n++;
            sum += c[i * C + row[i]];
            CHECK(isfinite(c[i * C + row[i]]), "case %d: forbidden pair (%d, %d) matched", t, i, row[i]);
            CHECK(col[row[i]] == i, "case %d: col_to_row[%d] = %d, not %d", t, row[i], col[row[i]], i);
        }
        for (int j = 0; j < C; j++) CHECK(col[j] < 0 || row[col[j]] == j, "case %d: column %d inconsistent", t, j);
        CHECK(n == N && n == best_n, "case %d (%dx%d): %d pairs (reported %d), brute force %d", t, R, C, n, N, best_n);
        CHECK(fabs(sum - best_sum) <= 1e-9 * (1 + fabs(best_sum)), "case %d: sum %.12g, brute force %.12g", t, sum,
              best_sum);
    }
    // a large square: a permutation of distinct costs whose optimum is known (the diagonal of a
    // matrix c[i][j] = |i - j| + 1 is optimal: every other permutation has a larger sum)
    enum { M = 300 };
    double *big = malloc(sizeof(double) * M * M);
    int *row = malloc(sizeof(int) * M), N = 0;
    for (int i = 0; i < M; i++)
        for (int j = 0; j < M; j++) big[i * M + j] = fabs((double)(i - j)) + 1;
    CHECK(rs_mot_assign(row, NULL, &N, big, M, M, &err) == RS_OK, "%s", err.msg);
    int diag = 0;
    for (int i = 0; i < M; i++) diag += row[i] == i;
    CHECK(N == M && diag == M, "300 x 300: %d pairs, %d on the diagonal", N, diag);
    free(big);
    free(row);
    // empty and bad
    CHECK(rs_mot_assign(NULL, NULL, &N, NULL, 0, 5, &err) == RS_OK && N == 0, "0 x 5");
    CHECK(rs_mot_assign(NULL, NULL, NULL, NULL, -1, 5, &err) == RS_ERR_INVALID, "negative size accepted");
    const double minf[1] = {-INFINITY};
    CHECK(rs_mot_assign(NULL, NULL, NULL, minf, 1, 1, &err) == RS_ERR_INVALID, "-inf accepted");
    return rs_test_end("test_mot_assign");
}
