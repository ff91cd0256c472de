// rs_audit_internal.h -- what the files of audit/ share. Internal to audit.
#pragma once
#include "audit/rs_audit.h"

// Euclidean distance of two (3,) points.
double rs_audit__dist3(const double *a, const double *b);

// The ground uncertainty map of the full solve (r->solve) over the ground plane n . p = offset,
// within opt->range_m of the camera, cells of opt->cell_m (rs_audit_map).
rs_status rs_audit__compute_map(rs_audit_result *r, const rs_calib_problem *pb, const double n[3], double offset,
                                const rs_audit_options *opt, rs_err *err);

// The image and ground coverage of the inlier landmarks (r->image_hull_share, ground_*).
rs_status rs_audit__compute_coverage(rs_audit_result *r, const rs_calib_problem *pb, rs_err *err);
