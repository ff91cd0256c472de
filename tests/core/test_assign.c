// test_assign -- rs_assign (core/rs_assign.h) against brute force over every matching, under both
// of its rules:
// - a finite miss_cost (the tracker's rule): 20,000 random cost matrices of 1..6 rows and 1..6
//   columns, a random share of forbidden pairs (cost above miss_cost, or infinite); the matching
//   must be valid (distinct columns, allowed pairs, row_to_col and col_to_row inverse) and reach
//   the brute force's least total of (cost - miss_cost) over the matched pairs (to 1e-9);
// - miss_cost = +inf (the MOT metrics' rule): 3,000 random matrices of 0..6 rows and columns with
//   +inf or NaN forbidden pairs, costs of either sign (IDF1 and HOTA minimise negated scores): the
//   brute force's number of pairs and least sum (1e-9 relative);
// plus hand-worked cases, a 300 x 300 matrix whose optimum is known (both rules; no timing), the
// empty sizes and bad input (negative size, -inf cost, NaN or -inf miss_cost).
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../common/rs_test.h"
#include "core/rs_assign.h"
#include "core/rs_rng.h"

enum { MAXN = 6 };

// ---- the tracker's rule: a finite miss_cost ----

typedef struct {
    int pairs;
    double cost;
} value;

// The objective: the sum of (cost - miss_cost) over the pairs (less is better).
static double objective(value v, double maxc) { return v.cost - v.pairs * maxc; }

// The best value over every matching of rows r.. given the columns used so far.
static value brute_miss(const double *c, int n, int m, double maxc, int r, bool *used, value so_far)
{
    if (r == n) return so_far;
    value best = brute_miss(c, n, m, maxc, r + 1, used, so_far); // row r unmatched
    for (int j = 0; j < m; j++) {
        const double x = c[r * m + j];
        if (used[j] || !isfinite(x) || x >= maxc) continue;
        used[j] = true;
        const value v = brute_miss(c, n, m, maxc, r + 1, used, (value){so_far.pairs + 1, so_far.cost + x});
        used[j] = false;
        if (objective(v, maxc) < objective(best, maxc) - 1e-12) best = v;
    }
    return best;
}

static void hand_cases(void)
{
    // rows (4 1 3; 2 0 5; 3 2 2): the optimum is (0,1) + (1,0) + (2,2) = 1 + 2 + 2 = 5 (by hand over
    // the six permutations: 5, 6, 6, 7, 9, 11)
    const double a[9] = {4, 1, 3, 2, 0, 5, 3, 2, 2};
    int col[3], n;
    double total;
    CHECK(rs_assign(col, NULL, &n, &total, a, 3, 3, 100, NULL) == RS_OK, "3x3");
    CHECK(n == 3 && fabs(total - 5) < 1e-12 && col[0] == 1 && col[1] == 0 && col[2] == 2,
          "3x3: %d pairs, %g, (%d %d %d)", n, total, col[0], col[1], col[2]);
    CHECK(rs_assign(col, NULL, &n, &total, a, 3, 3, INFINITY, NULL) == RS_OK && n == 3 && fabs(total - 5) < 1e-12,
          "3x3, most pairs: %d pairs, %g", n, total);
    // a miss costs miss_cost: (0,1) + (1,0) = 5 + 1 saves 194 against 200; (0,0) alone, 0, saves
    // only 100; with miss_cost 5.5 the pair (0,1) = 5 saves 0.5 and (1,0) 4.5, together 5 against
    // (0,0)'s 5.5: then (0,0) alone. With miss_cost +inf: the two pairs (most pairs first).
    const double b[4] = {0, 5, 1, INFINITY};
    CHECK(rs_assign(col, NULL, &n, &total, b, 2, 2, 100, NULL) == RS_OK, "2x2");
    CHECK(n == 2 && col[0] == 1 && col[1] == 0 && fabs(total - 6) < 1e-12, "2x2, miss 100: %d pairs, %g", n, total);
    CHECK(rs_assign(col, NULL, &n, &total, b, 2, 2, 5.5, NULL) == RS_OK, "2x2");
    CHECK(n == 1 && col[0] == 0 && col[1] == -1 && total == 0, "2x2, miss 5.5: %d pairs, %g", n, total);
    CHECK(rs_assign(col, NULL, &n, &total, b, 2, 2, INFINITY, NULL) == RS_OK, "2x2");
    CHECK(n == 2 && col[0] == 1 && col[1] == 0 && fabs(total - 6) < 1e-12, "2x2, miss +inf: %d pairs, %g", n, total);
    // a pair at exactly miss_cost saves nothing: unmatched
    const double e[1] = {6};
    CHECK(rs_assign(col, NULL, &n, &total, e, 1, 1, 6, NULL) == RS_OK && n == 0 && col[0] == -1, "cost = miss_cost");
    // everything forbidden; empty sizes
    const double c[2] = {7, 8};
    CHECK(rs_assign(col, NULL, &n, &total, c, 1, 2, 6, NULL) == RS_OK && n == 0 && col[0] == -1, "all forbidden");
    CHECK(rs_assign(col, NULL, &n, &total, c, 0, 2, 6, NULL) == RS_OK && n == 0, "no rows");
    CHECK(rs_assign(col, NULL, &n, &total, c, 2, 0, 6, NULL) == RS_OK && n == 0 && col[0] == -1 && col[1] == -1,
          "no columns");
    // a negative cost is a pair like any other: it saves miss_cost - cost = 7
    const double d[1] = {-1};
    CHECK(rs_assign(col, NULL, &n, &total, d, 1, 1, 6, NULL) == RS_OK && n == 1 && col[0] == 0 && total == -1,
          "negative cost: %d pairs, %g", n, total);
}

static void random_miss_cost(rs_rng *rng)
{
    int cases = 0, rect = 0, with_forbidden = 0;
    for (int trial = 0; trial < 20000; trial++) {
        const int n = 1 + (int)(MAXN * rs_rng_uniform(rng)), m = 1 + (int)(MAXN * rs_rng_uniform(rng));
        const double p_forbid = rs_rng_uniform(rng) * 0.7, maxc = 10;
        double c[MAXN * MAXN];
        bool any_forbidden = false;
        for (int k = 0; k < n * m; k++) {
            const double u = rs_rng_uniform(rng);
            if (u < p_forbid) {
                c[k] = u < p_forbid / 2 ? INFINITY : rs_rng_uniform_in(rng, maxc + 1e-9, 2 * maxc);
                any_forbidden = true;
            } else // integers now and then: ties between matchings
                c[k] = trial % 3 ? rs_rng_uniform_in(rng, 0, maxc) : floor(rs_rng_uniform_in(rng, 0, 4));
        }
        int col[MAXN], row[MAXN], got_n = -1;
        double got_cost = NAN;
        CHECK(rs_assign(col, row, &got_n, &got_cost, c, n, m, maxc, NULL) == RS_OK, "trial %d", trial);
        bool used[MAXN] = {false}, valid = true;
        int pairs = 0;
        double total = 0;
        for (int i = 0; i < n; i++) {
            if (col[i] < 0) continue;
            const double x = c[i * m + col[i]];
            valid = valid && col[i] < m && !used[col[i]] && isfinite(x) && x < maxc && row[col[i]] == i;
            if (col[i] < m) used[col[i]] = true;
            pairs++, total += x;
        }
        for (int j = 0; j < m; j++) valid = valid && (row[j] < 0 ? !used[j] : col[row[j]] == j);
        bool used0[MAXN] = {false};
        const value want = brute_miss(c, n, m, maxc, 0, used0, (value){0, 0});
        CHECK(valid && pairs == got_n && fabs(total - got_cost) < 1e-9, "trial %d: invalid matching", trial);
        const double got_obj = objective((value){pairs, total}, maxc), want_obj = objective(want, maxc);
        CHECK(fabs(got_obj - want_obj) < 1e-9, "trial %d (%dx%d): %d pairs cost %.12g, brute force %d pairs cost %.12g",
              trial, n, m, pairs, total, want.pairs, want.cost);
        cases++, rect += n != m, with_forbidden += any_forbidden;
    }
    printf("miss_cost 10: %d matrices (%d rectangular, %d with forbidden pairs) against brute force\n", cases, rect,
           with_forbidden);
}

// ---- the MOT rule: miss_cost = +inf ----

// Brute force: the best (most pairs, then least sum) over all partial matchings of rows i.. to
// the columns not in `used`. out: *best_n, *best_sum
static void brute_most(const double *c, int R, int C, int i, unsigned used, int n, double sum, int *best_n,
                       double *best_sum)
{
    if (i == R) {
        if (n > *best_n || (n == *best_n && sum < *best_sum)) *best_n = n, *best_sum = sum;
        return;
    }
    brute_most(c, R, C, i + 1, used, n, sum, best_n, best_sum); // row i unmatched
    for (int j = 0; j < C; j++)
        if (!(used & (1u << j)) && isfinite(c[i * C + j]))
            brute_most(c, R, C, i + 1, used | (1u << j), n + 1, sum + c[i * C + j], best_n, best_sum);
}

static void random_most_pairs(rs_rng *rng)
{
    rs_err err = {0};
    int cases = 0, rect = 0;
    for (int t = 0; t < 3000; t++) {
        const int R = (int)(rs_rng_u64(rng) % 7), C = (int)(rs_rng_u64(rng) % 7);
        const double p_forbid = rs_rng_uniform(rng) * 0.7;
        const bool negative = t % 3 == 0; // IDF1 and HOTA minimise negated scores
        double c[36];
        for (int k = 0; k < R * C; k++)
            c[k] = rs_rng_uniform(rng) < p_forbid ? (t % 2 ? INFINITY : NAN)
                                                  : (negative ? -1 : 1) * rs_rng_uniform_in(rng, 0, 10);
        int row[7], col[7], N = -1;
        double reported = NAN;
        rs_status st = rs_assign(row, col, &N, &reported, c, R, C, INFINITY, &err);
        CHECK(st == RS_OK, "case %d: %s", t, err.msg);
        int best_n = -1;
        double best_sum = INFINITY;
        brute_most(c, R, C, 0, 0, 0, 0, &best_n, &best_sum);
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
        CHECK(fabs(sum - best_sum) <= 1e-9 * (1 + fabs(best_sum)) && fabs(sum - reported) <= 1e-12 * (1 + fabs(sum)),
              "case %d: sum %.12g (reported %.12g), brute force %.12g", t, sum, reported, best_sum);
        cases++, rect += R != C;
    }
    printf("miss_cost +inf: %d matrices (%d rectangular) against brute force\n", cases, rect);
}

// A large square: a permutation of distinct costs whose optimum is known (the diagonal of a
// matrix c[i][j] = |i - j| + 1 is optimal: every other permutation has a larger sum), under
// both rules (miss_cost 1000: every diagonal pair saves 999).
static void large(void)
{
    enum { M = 300 };
    rs_err err = {0};
    double *big = malloc(sizeof(double) * M * M);
    int *row = malloc(sizeof(int) * M), N = 0;
    CHECK(big && row, "out of memory");
    if (!big || !row) return;
    for (int i = 0; i < M; i++)
        for (int j = 0; j < M; j++) big[i * M + j] = fabs((double)(i - j)) + 1;
    const double miss[2] = {INFINITY, 1000};
    for (int k = 0; k < 2; k++) {
        double total = 0;
        CHECK(rs_assign(row, NULL, &N, &total, big, M, M, miss[k], &err) == RS_OK, "%s", err.msg);
        int diag = 0;
        for (int i = 0; i < M; i++) diag += row[i] == i;
        CHECK(N == M && diag == M && total == M, "300 x 300, miss_cost %g: %d pairs, %d on the diagonal, total %g",
              miss[k], N, diag, total);
    }
    free(big);
    free(row);
}

static void bad_input(void)
{
    rs_err err = {0};
    int N = -1, row[1] = {7};
    CHECK(rs_assign(NULL, NULL, &N, NULL, NULL, 0, 5, INFINITY, &err) == RS_OK && N == 0, "0 x 5");
    CHECK(rs_assign(NULL, NULL, NULL, NULL, NULL, -1, 5, INFINITY, &err) == RS_ERR_INVALID &&
              strstr(err.msg, "negative size"),
          "negative size accepted: %s", err.msg);
    const double minf[1] = {-INFINITY}, one[1] = {1};
    CHECK(rs_assign(row, NULL, NULL, NULL, minf, 1, 1, INFINITY, &err) == RS_ERR_INVALID && row[0] == -1,
          "-inf accepted");
    CHECK(rs_assign(NULL, NULL, NULL, NULL, minf, 1, 1, 5, &err) == RS_ERR_INVALID, "-inf accepted (miss_cost 5)");
    CHECK(rs_assign(NULL, NULL, NULL, NULL, one, 1, 1, NAN, &err) == RS_ERR_INVALID && strstr(err.msg, "miss_cost"),
          "NaN miss_cost accepted: %s", err.msg);
    CHECK(rs_assign(NULL, NULL, NULL, NULL, one, 1, 1, -INFINITY, &err) == RS_ERR_INVALID, "-inf miss_cost accepted");
    const double huge[1] = {-1.5e308};
    CHECK(rs_assign(NULL, NULL, NULL, NULL, huge, 1, 1, 1.5e308, &err) == RS_ERR_INVALID, "overflow accepted");
}

int main(void)
{
    hand_cases();
    rs_test_seed = 39;
    rs_rng rng;
    rs_rng_seed(&rng, rs_test_seed);
    random_miss_cost(&rng);
    rs_rng_seed(&rng, rs_test_seed);
    random_most_pairs(&rng);
    large();
    bad_input();
    return rs_test_end("test_assign");
}
