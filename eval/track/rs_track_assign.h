// rs_track_assign.h -- optimal assignment (linear sum assignment) of a rectangular cost matrix
// with forbidden pairs: the Hungarian method in its shortest-augmenting-path form.
//
// Problem: rows i (tracks) and columns j (detections), cost[i][j] >= 0 where a pair is allowed
// (cost <= max_cost and finite), forbidden otherwise. The solver returns the one-to-one matching
// of allowed pairs with the least total of (cost - max_cost) over its pairs: each matched pair
// saves max_cost - cost against leaving its row and column unmatched, so max_cost is the price of
// a miss (the global-nearest-neighbour rule with a non-assignment cost: S. Blackman and
// R. Popoli, "Design and Analysis of Modern Tracking Systems", Artech House 1999, 6.5). A pair at
// exactly max_cost saves nothing and is left unmatched.
//
// Method: the pairs' savings a[i][j] = cost - max_cost (<= 0), forbidden pairs 0 (the same as
// unmatched), so the best full assignment of the smaller side is the best partial matching; it
// is solved (rows <= columns; the matrix is transposed otherwise) by the Hungarian method with
// row and column potentials, adding one row at a time and augmenting along a shortest path found
// Dijkstra-style (H. W. Kuhn, "The Hungarian method for the assignment problem", Naval Research
// Logistics Quarterly 2, 83-97 (1955); the O(n^3) shortest-augmenting-path form: R. Jonker and
// A. Volgenant, "A shortest augmenting path algorithm for dense and sparse linear assignment
// problems", Computing 38, 325-340 (1987)); pairs whose saving is 0 are then dropped.
// Cost: O(n^2 m) time for n = min(Nrows, Ncols), m = max(Nrows, Ncols): O(n^3) for a square
// matrix; O(n + m) extra memory besides a copy of the matrix.
// Accuracy: exact in the combinatorial sense (optimal matching); the total cost is summed in
// double precision. tests/eval/track/test_track_assign.c checks it against brute force over
// all matchings on 20,000 random matrices up to 6 x 6, forbidden pairs included.
#pragma once

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Solves the assignment of cost (Nrows, Ncols), row-major. Pairs with cost > max_cost or a
// non-finite cost are forbidden; allowed costs must be >= 0 (RS_ERR_INVALID otherwise).
// Returns RS_OK, RS_ERR_INVALID (a negative allowed cost, negative sizes), RS_ERR_NOMEM.
rs_status rs_track_assign( // out
    int *col_of_row,       // (Nrows,) the column matched to each row, -1 for none
    int *Nmatched,         // the number of matched pairs, may be NULL
    double *total_cost,    // the sum of the matched pairs' costs, may be NULL
    // in
    const double *cost, // (Nrows, Ncols) row-major
    int Nrows, int Ncols, double max_cost, rs_err *err);

#ifdef __cplusplus
}
#endif
