// test_stats.c -- rs_stats_median and rs_stats_quantile (core/rs_stats.h) against brute force:
// the order statistic of rank k is found by counting (the value with at most k values below it
// and more than k at or below it), never by sorting, on 20,000 random samples of 1..40 values
// (half of them with ties: values drawn from a few integers), every even and odd count.
// Tolerances: the median exactly (0 ulp: the same two values, the same formula); a quantile
// within 1e-15 relative (one interpolation step). p = 0 and p = 1 exactly the minimum and maximum.
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "core/rs_rng.h"
#include "core/rs_stats.h"
#include "tests/common/rs_test.h"

enum { NSAMPLES = 20000, NMAX = 40 };

// The k-th smallest of x (n,), 0-based, by counting.
static double order_stat(const double *x, int n, int k)
{
    for (int i = 0; i < n; i++) {
        int below = 0, at_or_below = 0;
        for (int j = 0; j < n; j++) below += x[j] < x[i], at_or_below += x[j] <= x[i];
        if (below <= k && k < at_or_below) return x[i];
    }
    return NAN;
}

int main(void)
{
    rs_test_seed = 20261128;
    rs_rng rng;
    rs_rng_seed(&rng, rs_test_seed);
    double x[NMAX], work[NMAX], worst_q = 0;
    int Neven = 0;
    for (int s = 0; s < NSAMPLES; s++) {
        const int n = 1 + (s / 2) % NMAX; // every count 1..NMAX, with and without ties
        const bool ties = s % 2;
        for (int i = 0; i < n; i++)
            x[i] = ties ? floor(rs_rng_uniform(&rng) * 5) : rs_rng_uniform_in(&rng, -100.0, 100.0);
        Neven += n % 2 == 0;
        // median: the middle order statistic, or the mean of the two middle ones
        const double want =
            n % 2 ? order_stat(x, n, n / 2) : 0.5 * (order_stat(x, n, n / 2 - 1) + order_stat(x, n, n / 2));
        memcpy(work, x, sizeof(double) * (size_t)n);
        const double got = rs_stats_median(work, n);
        CHECK(got == want, "n %d: median %.17g, brute force %.17g", n, got, want);
        for (int i = 1; i < n; i++) CHECK(work[i - 1] <= work[i], "n %d: not sorted at %d", n, i);
        CHECK(rs_stats_median_sorted(work, n) == want, "n %d: median_sorted", n);
        // quantiles: linear between the order statistics at p (n - 1)
        const double ps[] = {0, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99, 1, rs_rng_uniform(&rng)};
        for (size_t k = 0; k < sizeof ps / sizeof *ps; k++) {
            const double p = ps[k], h = p * (n - 1);
            const int lo = (int)floor(h), hi = lo + 1 < n ? lo + 1 : lo;
            const double a = order_stat(x, n, lo), b = order_stat(x, n, hi);
            const double w = a + (h - lo) * (b - a);
            memcpy(work, x, sizeof(double) * (size_t)n);
            const double q = rs_stats_quantile(work, n, p);
            const double e = fabs(q - w) / fmax(1.0, fabs(w));
            if (e > worst_q) worst_q = e;
            CHECK(e <= 1e-15, "n %d p %g: quantile %.17g, brute force %.17g", n, p, q, w);
            if (p == 0) CHECK(q == order_stat(x, n, 0), "n %d: quantile(0) is not the minimum", n);
            if (p == 1) CHECK(q == order_stat(x, n, n - 1), "n %d: quantile(1) is not the maximum", n);
        }
    }
    // the float selection and median against the double order statistics of the same values
    // (every k of every sample; ties and descending runs included)
    for (int s = 0; s < 4000; s++) {
        const int n = 1 + s % NMAX;
        float f[NMAX], fw[NMAX];
        for (int i = 0; i < n; i++) {
            f[i] = s % 3 == 0   ? (float)floor(rs_rng_uniform(&rng) * 4)
                   : s % 3 == 1 ? (float)(n - i)
                                : (float)rs_rng_uniform_in(&rng, -10.0, 10.0);
            x[i] = f[i];
        }
        for (int k = 0; k < n; k++) {
            memcpy(fw, f, sizeof(float) * (size_t)n);
            const float got = rs_stats_select_f(fw, (size_t)n, (size_t)k);
            CHECK(got == (float)order_stat(x, n, k), "n %d: select_f(k %d) %g, brute force %g", n, k, got,
                  order_stat(x, n, k));
        }
        memcpy(fw, f, sizeof(float) * (size_t)n);
        const double want =
            n % 2 ? order_stat(x, n, n / 2) : 0.5 * (order_stat(x, n, n / 2 - 1) + order_stat(x, n, n / 2));
        CHECK(rs_stats_median_f(fw, (size_t)n) == want, "n %d: median_f %g, brute force %g", n,
              rs_stats_median_f(fw, (size_t)n), want);
    }
    // documented edges: empty samples and p outside [0, 1] give NaN; {1, 2, 3, 4}: median 2.5,
    // quantile 0.9 = 3.7 (numpy.quantile([1, 2, 3, 4], 0.9) = 3.7)
    double e4[4] = {4, 1, 3, 2};
    CHECK(isnan(rs_stats_median(NULL, 0)) && isnan(rs_stats_quantile(NULL, 0, 0.5)), "n = 0: not NaN");
    CHECK(isnan(rs_stats_quantile(e4, 4, 1.5)) && isnan(rs_stats_quantile(e4, 4, NAN)), "p outside [0, 1]: not NaN");
    CHECK(rs_stats_median(e4, 4) == 2.5, "median {1,2,3,4} = %g, not 2.5", rs_stats_median(e4, 4));
    CHECK(fabs(rs_stats_quantile(e4, 4, 0.9) - 3.7) < 1e-15, "quantile 0.9 of {1,2,3,4} = %.17g, not 3.7",
          rs_stats_quantile(e4, 4, 0.9));
    // the chi-square quantile (Wilson-Hilferty) against scipy.stats.chi2.ppf(norm.cdf(z), k), to
    // the accuracy rs_stats.h states: upper tail 1.2 % for k >= 5, 0.3 % for k >= 20; lower tail
    // (z = -2.576) 3 % for k >= 10
    static const struct {
        int k;
        double z, want, tol;
    } chi2[] = {{5, 3.090, 20.513, 0.012},  {7, 3.090, 24.320, 0.012},    {20, 3.090, 45.312, 0.003},
                {40, 3.090, 73.399, 0.003}, {100, 3.090, 149.445, 0.003}, {10, 2.576, 25.190, 0.012},
                {10, -2.576, 2.156, 0.03},  {40, -2.576, 20.706, 0.03}};
    for (size_t i = 0; i < sizeof chi2 / sizeof *chi2; i++) {
        const double got = rs_stats_chi2_quantile(chi2[i].k, chi2[i].z);
        CHECK(fabs(got / chi2[i].want - 1) <= chi2[i].tol, "chi-square quantile k %d z %g: %.4f, scipy %.3f", chi2[i].k,
              chi2[i].z, got, chi2[i].want);
    }
    printf("stats: %d samples of 1..%d values (%d even counts, half with ties): median exact, quantile worst "
           "%.2g relative\n",
           NSAMPLES, NMAX, Neven, worst_q);
    return rs_test_end("core_stats");
}
