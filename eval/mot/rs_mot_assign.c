// rs_mot_assign.c -- the Hungarian method, shortest augmenting paths with potentials
// (eval/mot/rs_mot_assign.h states the problem, the references and the cost).
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "eval/mot/rs_mot_assign.h"

// a (n, m) row-major with n <= m, every entry finite. out: p (m + 1,), p[j] = 1-based row of
// column j (1-based), 0 if none. Work arrays: u (n + 1,), v, minv, way (m + 1,), used (m + 1,).
static void hungarian(int *p, const double *a, int n, int m, double *u, double *v, double *minv, int *way, bool *used)
{
    for (int j = 0; j <= m; j++) p[j] = 0, v[j] = 0;
    for (int i = 0; i <= n; i++) u[i] = 0;
    for (int i = 1; i <= n; i++) {
        p[0] = i;
        int j0 = 0;
        for (int j = 0; j <= m; j++) minv[j] = INFINITY, used[j] = false;
        do {
            used[j0] = true;
            const int i0 = p[j0];
            double delta = INFINITY;
            int j1 = 0;
            for (int j = 1; j <= m; j++) {
                if (used[j]) continue;
                const double cur = a[(size_t)(i0 - 1) * m + (j - 1)] - u[i0] - v[j];
                if (cur < minv[j]) minv[j] = cur, way[j] = j0;
                if (minv[j] < delta) delta = minv[j], j1 = j;
            }
            for (int j = 0; j <= m; j++)
                if (used[j])
                    u[p[j]] += delta, v[j] -= delta;
                else
                    minv[j] -= delta;
            j0 = j1;
        } while (p[j0] != 0);
        do {
            const int j1 = way[j0];
            p[j0] = p[j1];
            j0 = j1;
        } while (j0);
    }
}

rs_status rs_mot_assign(int *row_to_col, int *col_to_row, int *Npairs, const double *cost, int Nrows, int Ncols,
                        rs_err *err)
{
    if (Nrows < 0 || Ncols < 0) return rs_err_set(err, RS_ERR_INVALID, "rs_mot_assign: negative size");
    for (int i = 0; row_to_col && i < Nrows; i++) row_to_col[i] = -1;
    for (int j = 0; col_to_row && j < Ncols; j++) col_to_row[j] = -1;
    if (Npairs) *Npairs = 0;
    if (Nrows == 0 || Ncols == 0) return RS_OK;
    const bool tr = Nrows > Ncols; // solve with n <= m
    const int n = tr ? Ncols : Nrows, m = tr ? Nrows : Ncols;
    double big = 0;
    for (size_t k = 0; k < (size_t)Nrows * Ncols; k++) {
        if (cost[k] == -INFINITY)
            return rs_err_set(err, RS_ERR_INVALID, "rs_mot_assign: cost[%zu][%zu] is -inf", k / Ncols, k % Ncols);
        if (isfinite(cost[k]) && fabs(cost[k]) > big) big = fabs(cost[k]);
    }
    big = (1 + big) * (n + 1);
    double *a = malloc(sizeof(double) * ((size_t)n * m + 3 * (size_t)(m + 1) + (size_t)(n + 1)));
    int *ints = malloc(sizeof(int) * 2 * (size_t)(m + 1));
    bool *used = malloc((size_t)(m + 1));
    if (!a || !ints || !used) {
        free(a);
        free(ints);
        free(used);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    double *u = a + (size_t)n * m, *v = u + (n + 1), *minv = v + (m + 1);
    int *p = ints, *way = ints + (m + 1);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < m; j++) {
            const double c = tr ? cost[(size_t)j * Ncols + i] : cost[(size_t)i * Ncols + j];
            a[(size_t)i * m + j] = isfinite(c) ? c : big;
        }
    hungarian(p, a, n, m, u, v, minv, way, used);
    int count = 0;
    for (int j = 1; j <= m; j++) {
        if (!p[j]) continue;
        const int i = p[j] - 1, jj = j - 1;
        const int r = tr ? jj : i, c = tr ? i : jj;
        if (!isfinite(cost[(size_t)r * Ncols + c])) continue; // a forbidden pair completing the matrix
        if (row_to_col) row_to_col[r] = c;
        if (col_to_row) col_to_row[c] = r;
        count++;
    }
    if (Npairs) *Npairs = count;
    free(a);
    free(ints);
    free(used);
    return RS_OK;
}
