// test_track_assign -- rs_track_assign (eval/track/rs_track_assign.h) against brute force over
// every matching: 20,000 random cost matrices of 1..6 rows and 1..6 columns, a random share of
// forbidden pairs (cost above the bound, or infinite); the solver's matching must be valid
// (distinct columns, allowed pairs) and reach the brute force's optimum: the least total of
// (cost - bound) over the matched pairs (to 1e-9). Plus hand-worked cases.
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "../../common/rs_test.h"
#include "core/rs_rng.h"
#include "eval/track/rs_track_assign.h"

enum { MAXN = 6 };

typedef struct {
    int pairs;
    double cost;
} value;

// The objective: the sum of (cost - bound) over the pairs (less is better).
static double objective(value v, double maxc) { return v.cost - v.pairs * maxc; }

// The best value over every matching of rows r.. given the columns used so far.
static value brute(const double *c, int n, int m, double maxc, int r, bool *used, value so_far)
{
    if (r == n) return so_far;
    value best = brute(c, n, m, maxc, r + 1, used, so_far); // row r unmatched
    for (int j = 0; j < m; j++) {
        const double x = c[r * m + j];
        if (used[j] || !isfinite(x) || x > maxc) continue;
        used[j] = true;
        const value v = brute(c, n, m, maxc, r + 1, used, (value){so_far.pairs + 1, so_far.cost + x});
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
    CHECK(rs_track_assign(col, &n, &total, a, 3, 3, 100, NULL) == RS_OK, "3x3");
    CHECK(n == 3 && fabs(total - 5) < 1e-12 && col[0] == 1 && col[1] == 0 && col[2] == 2,
          "3x3: %d pairs, %g, (%d %d %d)", n, total, col[0], col[1], col[2]);
    // a miss costs the bound: (0,1) + (1,0) = 5 + 1 saves 194 against 200; (0,0) alone, 0, saves
    // only 100; with the bound 5.5 the pair (0,1) = 5 saves 0.5 and (1,0) 4.5, together 5 against
    // (0,0)'s 5.5: then (0,0) alone
    const double b[4] = {0, 5, 1, INFINITY};
    CHECK(rs_track_assign(col, &n, &total, b, 2, 2, 100, NULL) == RS_OK, "2x2");
    CHECK(n == 2 && col[0] == 1 && col[1] == 0 && fabs(total - 6) < 1e-12, "2x2, bound 100: %d pairs, %g", n, total);
    CHECK(rs_track_assign(col, &n, &total, b, 2, 2, 5.5, NULL) == RS_OK, "2x2");
    CHECK(n == 1 && col[0] == 0 && col[1] == -1 && total == 0, "2x2, bound 5.5: %d pairs, %g", n, total);
    // everything forbidden; empty sizes
    const double c[2] = {7, 8};
    CHECK(rs_track_assign(col, &n, &total, c, 1, 2, 6, NULL) == RS_OK && n == 0 && col[0] == -1, "all forbidden");
    CHECK(rs_track_assign(col, &n, &total, c, 0, 2, 6, NULL) == RS_OK && n == 0, "no rows");
    CHECK(rs_track_assign(col, &n, &total, c, 2, 0, 6, NULL) == RS_OK && n == 0 && col[0] == -1 && col[1] == -1,
          "no columns");
    // a negative allowed cost is refused
    const double d[1] = {-1};
    rs_err err = {0};
    CHECK(rs_track_assign(col, &n, &total, d, 1, 1, 6, &err) == RS_ERR_INVALID && strstr(err.msg, "negative"),
          "negative: %s", err.msg);
}

int main(void)
{
    hand_cases();
    rs_test_seed = 39;
    rs_rng rng;
    rs_rng_seed(&rng, rs_test_seed);
    int cases = 0, rect = 0, with_forbidden = 0;
    for (int trial = 0; trial < 20000; trial++) {
        const int n = 1 + (int)(MAXN * rs_rng_uniform(&rng)), m = 1 + (int)(MAXN * rs_rng_uniform(&rng));
        const double p_forbid = rs_rng_uniform(&rng) * 0.7, maxc = 10;
        double c[MAXN * MAXN];
        bool any_forbidden = false;
        for (int k = 0; k < n * m; k++) {
            const double u = rs_rng_uniform(&rng);
            if (u < p_forbid) {
                c[k] = u < p_forbid / 2 ? INFINITY : rs_rng_uniform_in(&rng, maxc + 1e-9, 2 * maxc);
                any_forbidden = true;
            } else // integers now and then: ties between matchings
                c[k] = trial % 3 ? rs_rng_uniform_in(&rng, 0, maxc) : floor(rs_rng_uniform_in(&rng, 0, 4));
        }
        int col[MAXN], got_n = -1;
        double got_cost = NAN;
        CHECK(rs_track_assign(col, &got_n, &got_cost, c, n, m, maxc, NULL) == RS_OK, "trial %d", trial);
        bool used[MAXN] = {false}, valid = true;
        int pairs = 0;
        double total = 0;
        for (int i = 0; i < n; i++) {
            if (col[i] < 0) continue;
            const double x = c[i * m + col[i]];
            valid = valid && col[i] < m && !used[col[i]] && isfinite(x) && x <= maxc;
            if (col[i] < m) used[col[i]] = true;
            pairs++, total += x;
        }
        bool used0[MAXN] = {false};
        const value want = brute(c, n, m, maxc, 0, used0, (value){0, 0});
        CHECK(valid && pairs == got_n && fabs(total - got_cost) < 1e-9, "trial %d: invalid matching", trial);
        const double got_obj = objective((value){pairs, total}, maxc), want_obj = objective(want, maxc);
        CHECK(fabs(got_obj - want_obj) < 1e-9, "trial %d (%dx%d): %d pairs cost %.12g, brute force %d pairs cost %.12g",
              trial, n, m, pairs, total, want.pairs, want.cost);
        cases++, rect += n != m, with_forbidden += any_forbidden;
    }
    printf("%d matrices (%d rectangular, %d with forbidden pairs) against brute force\n", cases, rect, with_forbidden);
    return rs_test_end("test_track_assign");
}
