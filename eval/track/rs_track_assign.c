// rs_track_assign.c -- the Hungarian method, shortest-augmenting-path form (rs_track_assign.h).
#include "eval/track/rs_track_assign.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

static bool allowed(double c, double max_cost) { return isfinite(c) && c <= max_cost; }

// Minimum-cost assignment of every row of a (n, m), n <= m, row-major, to distinct columns.
// out: row_of_col (m + 1,) 1-based: row_of_col[j] = the row (1-based) matched to column j (1..m),
// 0 for none. Scratch w: 3 (m + 1) + (n + 1) doubles, iw: (m + 1) ints, used: (m + 1) bools.
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

rs_status rs_track_assign(int *col_of_row, int *Nmatched, double *total_cost, const double *cost, int Nrows, int Ncols,
                          double max_cost, rs_err *err)
{
    if (Nrows < 0 || Ncols < 0)
        return rs_err_set(err, RS_ERR_INVALID, "assignment: negative size %d x %d", Nrows, Ncols);
    if (Nmatched) *Nmatched = 0;
    if (total_cost) *total_cost = 0;
    for (int i = 0; i < Nrows; i++) col_of_row[i] = -1;
    if (Nrows == 0 || Ncols == 0) return RS_OK;
    for (size_t k = 0; k < (size_t)Nrows * (size_t)Ncols; k++) {
        if (!allowed(cost[k], max_cost)) continue;
        if (cost[k] < 0)
            return rs_err_set(err, RS_ERR_INVALID, "assignment: cost[%zu][%zu] = %g is negative", k / (size_t)Ncols,
                              k % (size_t)Ncols, cost[k]);
    }
    const bool transposed = Nrows > Ncols;
    const int n = transposed ? Ncols : Nrows, m = transposed ? Nrows : Ncols;
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
            // a pair saves max_cost - x against leaving both unmatched; a forbidden pair saves nothing
            a[(size_t)r * (size_t)m + (size_t)c] = allowed(x, max_cost) ? x - max_cost : 0;
        }
    int *row_of_col = iw, *way = iw + m + 1;
    hungarian(row_of_col, a, n, m, a + (size_t)n * (size_t)m, way, used);
    int matched = 0;
    double total = 0;
    for (int j = 1; j <= m; j++) {
        if (!row_of_col[j]) continue;
        const int r = row_of_col[j] - 1, c = j - 1;
        if (!(a[(size_t)r * (size_t)m + (size_t)c] < 0)) continue; // forbidden, or saves nothing: unmatched
        const int row = transposed ? c : r, col = transposed ? r : c;
        col_of_row[row] = col;
        matched++;
        total += cost[(size_t)row * (size_t)Ncols + (size_t)col];
    }
    free(a), free(iw), free(used);
    if (Nmatched) *Nmatched = matched;
    if (total_cost) *total_cost = total;
    return RS_OK;
}
