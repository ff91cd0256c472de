// rs_assign.c -- the Hungarian method, shortest augmenting paths with potentials (core/rs_assign.h
// states the problem, the two rules, the references and the cost).
#include "core/rs_assign.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

// Minimum-cost assignment of every row of a (n, m), n <= m, row-major, every entry finite, to
// distinct columns. out: row_of_col (m + 1,): row_of_col[j] = the 1-based row matched to the
// 1-based column j, 0 for none. Scratch: w 3 (m + 1) + (n + 1) doubles, way (m + 1) ints, used
// (m + 1) bools.
static void hungarian(int *row_of_col, const double *a, int n, int m, double *w, int *way, bool *used)
{
    double *u = w, *v = u + n + 1, *minv = v + m + 1;
    for (int i = 0; i <= n; i++) u[i] = 0;
    for (int j = 0; j <= m; j++) v[j] = 0, row_of_col[j] = 0;
    for (int i = 1; i <= n; i++) {
        // add row i: grow a shortest-path tree from the virtual column 0 until a free column
        row_of_col[0] = i;
        int j0 = 0;
        for (int j = 0; j <= m; j++) minv[j] = INFINITY, used[j] = false;
        do {
            used[j0] = true;
            const int i0 = row_of_col[j0];
            double delta = INFINITY;
            int j1 = 0;
            for (int j = 1; j <= m; j++) {
                if (used[j]) continue;
                const double reduced = a[(size_t)(i0 - 1) * (size_t)m + (size_t)(j - 1)] - u[i0] - v[j];
                if (reduced < minv[j]) minv[j] = reduced, way[j] = j0;
                if (minv[j] < delta) delta = minv[j], j1 = j;
            }
            for (int j = 0; j <= m; j++) {
                if (used[j])
                    u[row_of_col[j]] += delta, v[j] -= delta;
                else
                    minv[j] -= delta;
            }
            j0 = j1;
        } while (row_of_col[j0] != 0);
        // augment along the path back to column 0
        do {
            const int j1 = way[j0];
            row_of_col[j0] = row_of_col[j1];
            j0 = j1;
        } while (j0 != 0);
    }
}

// Whether pair cost c may be matched under the rule of miss_cost (rs_assign.h).
static bool allowed(double c, double miss_cost) { return isfinite(c) && (isinf(miss_cost) || c < miss_cost); }

rs_status rs_assign(int *row_to_col, int *col_to_row, int *Npairs, double *total_cost, const double *cost, int Nrows,
                    int Ncols, double miss_cost, rs_err *err)
{
    for (int i = 0; row_to_col && i < Nrows; i++) row_to_col[i] = -1;
    for (int j = 0; col_to_row && j < Ncols; j++) col_to_row[j] = -1;
    if (Npairs) *Npairs = 0;
    if (total_cost) *total_cost = 0;
    if (Nrows < 0 || Ncols < 0)
        return rs_err_set(err, RS_ERR_INVALID, "assignment: negative size %d x %d", Nrows, Ncols);
    if (isnan(miss_cost) || miss_cost == -INFINITY)
        return rs_err_set(err, RS_ERR_INVALID, "assignment: miss_cost %g is not finite or +inf", miss_cost);
    if (Nrows == 0 || Ncols == 0) return RS_OK;
    const bool most_pairs = isinf(miss_cost);
    // the completed problem: an allowed pair costs c - shift, a forbidden one `fill`
    double big = 0;
    for (size_t k = 0; k < (size_t)Nrows * (size_t)Ncols; k++) {
        const double c = cost[k];
        if (c == -INFINITY || (!most_pairs && allowed(c, miss_cost) && !isfinite(c - miss_cost)))
            return rs_err_set(err, RS_ERR_INVALID, "assignment: cost[%zu][%zu] = %g is out of range (miss_cost %g)",
                              k / (size_t)Ncols, k % (size_t)Ncols, c, miss_cost);
        if (isfinite(c) && fabs(c) > big) big = fabs(c);
    }
    const bool transposed = Nrows > Ncols; // solve with n <= m
    const int n = transposed ? Ncols : Nrows, m = transposed ? Nrows : Ncols;
    const double shift = most_pairs ? 0 : miss_cost, fill = most_pairs ? (1 + big) * (n + 1) : 0;
    double *a = malloc(sizeof(double) * ((size_t)n * (size_t)m + 3 * (size_t)(m + 1) + (size_t)(n + 1)));
    int *iw = malloc(sizeof(int) * 2 * (size_t)(m + 1));
    bool *used = malloc(sizeof(bool) * (size_t)(m + 1));
    if (!a || !iw || !used) {
        free(a), free(iw), free(used);
        return rs_err_set(err, RS_ERR_NOMEM, "assignment: out of memory (%d x %d)", Nrows, Ncols);
    }
    for (int r = 0; r < n; r++)
        for (int c = 0; c < m; c++) {
            const double x =
                transposed ? cost[(size_t)c * (size_t)Ncols + (size_t)r] : cost[(size_t)r * (size_t)Ncols + (size_t)c];
            a[(size_t)r * (size_t)m + (size_t)c] = allowed(x, miss_cost) ? x - shift : fill;
        }
    int *row_of_col = iw, *way = iw + m + 1;
    hungarian(row_of_col, a, n, m, a + (size_t)n * (size_t)m, way, used);
    int matched = 0;
    double total = 0;
    for (int j = 1; j <= m; j++) {
        if (!row_of_col[j]) continue;
        const int r = row_of_col[j] - 1, c = j - 1;
        const int row = transposed ? c : r, col = transposed ? r : c;
        const double x = cost[(size_t)row * (size_t)Ncols + (size_t)col];
        if (!allowed(x, miss_cost)) continue; // a forbidden pair completing the problem: unmatched
        if (row_to_col) row_to_col[row] = col;
        if (col_to_row) col_to_row[col] = row;
        matched++;
        total += x;
    }
    free(a), free(iw), free(used);
    if (Npairs) *Npairs = matched;
    if (total_cost) *total_cost = total;
    return RS_OK;
}
