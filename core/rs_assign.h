// rs_assign.h -- the one assignment solver of roadside: an optimal matching of the rows and
// columns of a rectangular cost matrix, with forbidden pairs (the Hungarian method in its
// shortest-augmenting-path form). `roadside track` associates tracks with detections through
// it, `roadside eval --tracks` matches vehicles with tracks (CLEAR MOT, IDF1, HOTA).
//
// Problem: rows i and columns j, costs c[i][j] (Nrows x Ncols, any sign; +inf or NaN: the pair
// is forbidden). A matching M pairs each row and each column at most once. One parameter,
// miss_cost, chooses the objective:
// - miss_cost finite (the tracker's global-nearest-neighbour rule with a non-assignment cost:
//   S. Blackman and R. Popoli, "Design and Analysis of Modern Tracking Systems", Artech House
//   1999, 6.5): M minimises the sum over its pairs of (c - miss_cost). Each pair saves
//   miss_cost - c against leaving its row and column unmatched, so miss_cost is the price of a
//   miss; pairs with c >= miss_cost save nothing and are left unmatched (they are forbidden).
// - miss_cost = +INFINITY (what CLEAR MOT's per-step matching, IDF1's global ID matching and
//   HOTA's per-step matching need): M has the most allowed pairs and, among those, the least sum
//   of costs.
//
// Method: the problem is completed to a full assignment of the smaller side (the matrix is
// transposed internally when Nrows > Ncols) and solved by the Hungarian method with row and
// column potentials, adding one row at a time and augmenting along a shortest path found
// Dijkstra-style over reduced costs (H. W. Kuhn, "The Hungarian method for the assignment
// problem", Naval Research Logistics Quarterly 2, 83-97 (1955); the O(n^3) shortest-augmenting-
// path form: R. Jonker and A. Volgenant, "A shortest augmenting path algorithm for dense and
// sparse linear assignment problems", Computing 38, 325-340 (1987)). Finite miss_cost: an allowed
// pair costs c - miss_cost (< 0), a forbidden one 0, the same as unmatched, so the best full
// assignment is the best partial matching. miss_cost = +inf: a forbidden pair costs
// B = (1 + max |allowed cost|) x (min(Nrows, Ncols) + 1), more than any sum of allowed costs, so an
// optimum uses as few forbidden pairs as possible (most allowed pairs), then the least allowed
// cost. Forbidden pairs are dropped from the result.
// Cost: O(n^2 m) time for n = min(Nrows, Ncols), m = max(Nrows, Ncols) (O(n^3) square); O(n m)
// memory (a copy of the matrix). 300 x 300: about 10 ms.
// Accuracy: exact in the combinatorial sense (an optimal matching); the total is the sum of the
// matched pairs' costs in double precision (relative 1e-16 x n). With miss_cost = +inf, as long
// as the allowed costs span less than about 1e12 x their smallest difference (B absorbs the
// rest). tests/core/test_assign.c checks both rules against brute force over every matching
// (23,000 random matrices up to 6 x 6, forbidden pairs, ties) and a 300 x 300 case.
#pragma once

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Solves the assignment of cost (Nrows, Ncols) under the rule miss_cost chooses (above).
// Returns RS_OK; RS_ERR_INVALID (a negative size, a -inf cost, miss_cost NaN or -inf, a finite
// miss_cost whose c - miss_cost overflows); RS_ERR_NOMEM. On an error the outputs hold "nothing
// matched".
rs_status rs_assign(    // out
    int *row_to_col,    // (Nrows,) the column matched to row i, -1 for none; may be NULL
    int *col_to_row,    // (Ncols,) the row matched to column j, -1 for none; may be NULL
    int *Npairs,        // the number of matched pairs; may be NULL
    double *total_cost, // the sum of the matched pairs' costs c; may be NULL
    // in
    const double *cost,   // (Nrows, Ncols) row-major; +inf or NaN forbids a pair; may be NULL when
                          // Nrows or Ncols is 0
    int Nrows, int Ncols, // >= 0 (0: nothing matched)
    double miss_cost,     // finite: the price of leaving a row or column unmatched (the
                          // tracker's rule); +INFINITY: most pairs, then least cost
    rs_err *err);

#ifdef __cplusplus
}
#endif
