// rs_stats.h -- the one median and quantile (order statistics of a sample of doubles; a selection
// and median of floats for large samples), and the
// chi-square quantile the tests of a sample's scale share.
//
// Definitions, for a sample x of n values sorted ascending into s[0] <= ... <= s[n-1]:
//   median:      s[(n-1)/2] for odd n; for even n the mean of the two middle values,
//                0.5 * (s[n/2 - 1] + s[n/2]) (never the upper or lower one alone).
//   quantile p:  linear interpolation between the order statistics at the position
//                k = p (n - 1): with i = floor(k), s[i] + (k - i) (s[i+1] - s[i]) (s[n-1] when
//                i = n - 1). Hyndman & Fan's definition 7, the default of numpy.quantile
//                ("linear"), R's quantile() and Excel's PERCENTILE.INC; p = 0 gives the
//                minimum, p = 1 the maximum, p = 0.5 the median (to one rounding: the median's
//                own formula above is the one to quote).
// Preconditions: no NaN among the values (their order would be undefined); p in [0, 1].
// Returns NaN for n <= 0 (and for p outside [0, 1]).
// Accuracy: the median is exact up to the rounding of one addition and one halving; a quantile
// up to that of one subtraction, one multiplication and one addition (tests/core/test_stats.c
// against brute force on 20,000 random samples of 1..40 values, ties included: 0 ulp median,
// 1e-15 relative quantile).
#pragma once
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

// Sorts x (n,) ascending in place (qsort). n <= 0 does nothing.
void rs_stats_sort(double *x, int n);

// Median and quantile of x (n,), which they sort in place (the caller's order is lost: pass a
// copy to keep it).
double rs_stats_median(double *x, int n);
double rs_stats_quantile(double *x, int n, double p);

// The same of x (n,) already sorted ascending (several quantiles of one sample sort it once).
double rs_stats_median_sorted(const double *x, int n);
double rs_stats_quantile_sorted(const double *x, int n, double p);

// The k-th smallest of v (n,) of floats (0-based, k < n, n >= 1), v reordered: Hoare's selection
// with a median-of-three pivot, O(n) on average, for large samples (an image's pixels: a full
// sort of a 6-megapixel image's values was most of the appearance estimate's time,
// synth/backdrop/rs_synth_appearance.c). No NaN among the values.
float rs_stats_select_f(float *v, size_t n, size_t k);

// The median of v (n,) of floats, n >= 1, by the definition above (the mean of the two middle
// values for even n), v reordered.
double rs_stats_median_f(float *v, size_t n);

// The chi-square distribution's quantile with k degrees of freedom at the standard normal
// quantile z (z = 3.090: the 99.9 % point), by Wilson & Hilferty's cube-root normal
// approximation (1931): k (1 - 2/(9k) + z sqrt(2/(9k)))^3. Accuracy against scipy's chi2.ppf:
// upper tail (z in [2.5, 3.1]) within 1.2 % for k >= 5, 0.3 % for k >= 20; lower tail
// (z = -2.576) within 3 % for k >= 10 (worse below). k >= 1.
double rs_stats_chi2_quantile(int k, double z);

#ifdef __cplusplus
}
#endif
