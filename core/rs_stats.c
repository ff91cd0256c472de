// rs_stats.c -- median and quantile. See rs_stats.h.
#include "core/rs_stats.h"

#include <math.h>
#include <stdlib.h>

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

void rs_stats_sort(double *x, int n)
{
    if (n > 1) qsort(x, (size_t)n, sizeof *x, cmp_double);
}

double rs_stats_median_sorted(const double *x, int n)
{
    if (n <= 0) return NAN;
    return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

double rs_stats_quantile_sorted(const double *x, int n, double p)
{
    if (n <= 0 || !(p >= 0 && p <= 1)) return NAN;
    const double k = p * (n - 1);
    const int i = (int)floor(k);
    return i + 1 < n ? x[i] + (k - i) * (x[i + 1] - x[i]) : x[n - 1];
}

double rs_stats_median(double *x, int n)
{
    rs_stats_sort(x, n);
    return rs_stats_median_sorted(x, n);
}

double rs_stats_quantile(double *x, int n, double p)
{
    rs_stats_sort(x, n);
    return rs_stats_quantile_sorted(x, n, p);
}

double rs_stats_chi2_quantile(int k, double z)
{
    const double a = 2.0 / (9.0 * k);
    const double b = 1.0 - a + z * sqrt(a);
    return k * b * b * b;
}
