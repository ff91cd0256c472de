// rs_track_assign.h -- optimal assignment (linear sum assignment) of a rectangular cost matrix
// with forbidden pairs: the Hungarian method in its shortest-augmenting-path form.
//
// Problem: rows i (tracks) and columns j (detections), cost[i][j] >= 0 where a pair is allowed
// (cost <= max_cost and finite), forbidden otherwise. Among all one-to-one matchings of allowed
// pairs, the solver returns one with the largest number of pairs and, among those, the smallest
// total cost (lexicographic: cardinality first). A tracker wants exactly that: no gated pair is
// left unmatched to save cost.
//
// Method: forbidden entries get the cost BIG = 1 + min(Nrows, Ncols) (1 + the largest allowed
// cost), larger than any sum of allowed costs a matching can hold, so minimising the total with
// every row of the smaller side matched maximises the allowed pairs first; pairs at BIG are then
// dropped. The square-or-wide problem (rows <= columns; the matrix is transposed otherwise) is
// solved by the Hungarian method with row and column potentials, adding one row at a time and
// augmenting along a shortest path found Dijkstra-style (H. W. Kuhn, "The Hungarian method for
// the assignment problem", Naval Research Logistics Quarterly 2, 83-97 (1955); the O(n^3)
// shortest-augmenting-path form: R. Jonker and A. Volgenant, "A shortest augmenting path
// algorithm for dense and sparse linear assignment problems", Computing 38, 325-340 (1987)).
// Cost: O(n^2 m) time for n = min(Nrows, Ncols), m = max(Nrows, Ncols): O(n^3) for a square
// matrix; O(n + m) extra memory besides a copy of the matrix.
// Accuracy: exact in the combinatorial sense (optimal matching); the total cost is summed in
// double precision. tests/eval/track/test_track_assign.c checks it against brute force over
// all injective maps on 20,000 random matrices up to 7 x 7, forbidden pairs included.
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
