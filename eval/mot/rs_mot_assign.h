// rs_mot_assign.h -- the one assignment solver of the eval room: a minimum-cost matching of the
// rows and columns of a rectangular cost matrix, with forbidden pairs.
//
// Problem: given costs c[i][j] (Nrows x Ncols; +inf or NaN = the pair may not be matched), find
// the matching M (each row and each column in at most one pair, only allowed pairs) that first
// has the most pairs and, among those, the least sum of costs. This is what CLEAR MOT's
// per-step matching (pairs closer than a threshold), IDF1's global ID matching and HOTA's
// per-step matching need.
//
// Method: the Hungarian method (H. W. Kuhn, "The Hungarian method for the assignment problem",
// Naval Research Logistics Quarterly 2, 83-97 (1955)) in its shortest-augmenting-path form with
// potentials (R. Jonker and A. Volgenant, "A shortest augmenting path algorithm for dense and
// sparse linear assignment problems", Computing 38, 325-340 (1987)): each row in turn is joined
// by a Dijkstra-like search over reduced costs, O(n^2) per row. Forbidden pairs get the cost
// B = (1 + max |allowed cost|) x (min(Nrows, Ncols) + 1), larger than any sum of allowed costs,
// so an optimum of the completed problem uses as few forbidden pairs as possible (most allowed
// pairs), then the least allowed cost; forbidden pairs are dropped from the result.
// The matrix is transposed internally when Nrows > Ncols.
// Cost: O(n^2 m) time for n = min(Nrows, Ncols), m = max(Nrows, Ncols) (O(n^3) square), O(n m)
// memory. 300 x 300: about 10 ms.
// Accuracy: optimal; the sum of costs is exact up to the rounding of n additions in double
// precision (relative 1e-16 x n) as long as the allowed costs span less than about 1e12 x their
// smallest difference (B absorbs the rest). Checked against scipy's linear_sum_assignment and
// brute force over permutations (tests/eval/test_mot_assign.c).
#pragma once
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// out:  row_to_col (Nrows,): the column matched to row i, -1 if none; may be NULL
//       col_to_row (Ncols,): the row matched to column j, -1 if none; may be NULL
//       *Npairs: the number of pairs; may be NULL
// in:   cost (Nrows, Ncols) row-major; +inf or NaN forbids a pair; finite values any sign
//       Nrows, Ncols >= 0 (0: nothing matched)
// Errors: RS_ERR_INVALID (negative size, -inf cost), RS_ERR_NOMEM.
rs_status rs_mot_assign( // out
    int *row_to_col, int *col_to_row, int *Npairs,
    // in
    const double *cost, int Nrows, int Ncols, rs_err *err);

#ifdef __cplusplus
}
#endif
