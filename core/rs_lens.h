// rs_lens.h -- projection and unprojection through a lens model: mrcal's, with what mrcal 2.2
// lacks for CAHVORE supplied here. Every module projects through these two functions; only
// core/rs_lens.c calls mrcal_project and mrcal_unproject (tests/arch checks it).
//
// Why: many intersections are watched by one overhead fisheye. Its makers publish the lens as
// equidistant (pixel radius r = f theta), which is exactly mrcal's LENSMODEL_CAHVORE at
// linearity 0 with every distortion term zero; an OpenCV fisheye (Kannala-Brandt) with k3 = k4 = 0
// is exactly CAHVORE at linearity 0 with r0 = 0, r1 = k1, r2 = k2 (docs/conventions.md, "Fisheye
// lenses"). mrcal 2.2 projects CAHVORE but gives no gradients, and cannot unproject it; the
// solver needs the first, locate, labels and the renderer the second.
//
// CAHVORE, as mrcal 2.2 projects it (cmod_cahvore_3d_to_2d_general of JPL's libcmod, with the
// point normalised first), for a camera-frame point p and linearity L:
//   v = p / |p|,  o = (cos b sin a, sin b, cos b cos a)   (a = alpha, b = beta: the optical axis)
//   omega = v . o,  l_vec = v - omega o,  l = |l_vec|
//   theta solves  omega sin(theta) - l cos(theta) - (theta - sin theta)(e0 + e1 theta^2 +
//                 e2 theta^4) = 0                        (the entrance pupil moving with theta)
//   chi = theta (L = 0), tan(L theta)/L (L > 0), sin(L theta)/L (L < 0)
//   mu = r0 + r1 chi^2 + r2 chi^4,  u = (l / chi) o + (1 + mu) l_vec
//   q = (fx u_x/u_z + cx, fy u_y/u_z + cy);   theta <= 1e-8: q = pinhole of v.
// Gradients are analytic: forward-mode derivatives through every step, theta's by the implicit
// function theorem (dtheta = -dg / (dg/dtheta) at the solution). tests/core/test_lens.c checks
// values against mrcal_project (<= 1e-9 px) and gradients against central differences.
#pragma once
#include <stdbool.h>

#include <mrcal/mrcal.h>

#ifdef __cplusplus
extern "C" {
#endif

// mrcal_project's contract for every lens model, CAHVORE with gradients included.
// out: q (N,), dq_dp (N,2) rows of d(q)/d(p) (may be NULL), dq_dintrinsics (N,2,Nintrinsics)
//      dense (may be NULL)
// in:  p (N,) camera-frame points; lensmodel; intrinsics (core then distortions)
// For CAHVORE a point more than 90/|L| degrees off the axis (none for L = 0: up to 180) or one
// whose theta iteration does not converge gets q = NaN; the function still returns true, as
// mrcal does for points it cannot project. Returns false only where mrcal_project does.
bool rs_lens_project( // out
    mrcal_point2_t *q, mrcal_point3_t *dq_dp, double *dq_dintrinsics,
    // in
    const mrcal_point3_t *p, int N, const mrcal_lensmodel_t *lensmodel, const double *intrinsics);

// mrcal_unproject's contract (directions v of pixels q, any length) for every lens model.
// CAHVORE: the closed-form inverse of the radial model about the optical axis (a scalar Newton
// on chi (1 + mu(chi)) = |q - c| / f), then Gauss-Newton steps on rs_lens_project in the tangent
// plane of the direction until the reprojection is within 1e-10 px; v is a unit vector, which
// may point behind the image plane (v.z <= 0) for a fisheye that sees past 90 degrees. A pixel
// the lens never reaches (outside a fisheye's circle of 180 degrees) gets v = NaN.
bool rs_lens_unproject( // out
    mrcal_point3_t *v,
    // in
    const mrcal_point2_t *q, int N, const mrcal_lensmodel_t *lensmodel, const double *intrinsics);

// True when the lens model can see a point 90 degrees or more off its axis (CAHVORE at
// linearity <= 0), so that a direction's z <= 0 does not by itself mean "not visible".
bool rs_lens_sees_behind(const mrcal_lensmodel_t *lensmodel);

#ifdef __cplusplus
}
#endif
