// rs_calib_along.h -- internal: landmarks picked anywhere along a pole or a line
// (rs_calib_polyline; calib/rs_calib_along.c has the method; docs/calibration.md "Poles and
// lines"): their checks, the point landmarks the initial pose is made from, and the segment each
// pick is on.
#pragma once
#include <stdbool.h>

#include "calib/internal/rs_calib_solve_state.h"
#include "calib/rs_calib.h"
#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Whether landmark i (in [0, pb->N)) of pb is picked along a polyline.
bool rs_calib__is_along(const rs_calib_problem *pb, int i);

// Checks pb->along (RS_ERR_INVALID naming the landmark); *Npoints: the point landmarks.
rs_status rs_calib__along_validate(int *Npoints, const rs_calib_problem *pb, rs_err *err);

// The point landmarks of pb alone (for the initial pose): *sub is pb itself when it has no along
// picks, else it points into *buffer (owned by the caller, free() it; NULL when not needed).
// Errors: RS_ERR_NOMEM.
rs_status rs_calib__point_problem(rs_calib_problem *sub, double **buffer, const rs_calib_problem *pb, rs_err *err);

// For each along landmark of s's problem, the segment its pick is on at the pose s->rt_c through
// res->intrinsics (centred frame): sets s->p_survey_c and s->p_c to the point of the segment
// nearest the pick's ray, s->along_c to the segment's direction and s->s_along to 0. Nothing
// without along picks.
void rs_calib__along_choose(rs_calib_solve_state *s);

#ifdef __cplusplus
}
#endif
