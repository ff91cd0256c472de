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

float rs_stats_select_f(float *v, size_t n, size_t k)
{
    size_t lo = 0, hi = n - 1;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        float a = v[lo], b = v[mid], c = v[hi];
        const float pivot = a < b ? (b < c ? b : (a < c ? c : a)) : (a < c ? a : (b < c ? c : b));
        size_t i = lo, j = hi;
        while (i <= j) {
            while (v[i] < pivot) i++;
            while (v[j] > pivot) j--;
            if (i <= j) {
                const float t = v[i];
                v[i] = v[j];
                v[j] = t;
                i++;
                if (j == 0) break;
                j--;
            }
        }
        if (k <= j)
            hi = j;
        else if (k >= i)
            lo = i;
        else
            return v[k];
    }
    return v[k];
}

double rs_stats_median_f(float *v, size_t n)
{
    const double upper = rs_stats_select_f(v, n, n / 2);
    if (n % 2) return upper;
    // the lower middle is the largest of the part left of n / 2
    float lower = v[0];
    for (size_t i = 1; i < n / 2; i++)
        if (v[i] > lower) lower = v[i];
    return 0.5 * (lower + upper);
}
