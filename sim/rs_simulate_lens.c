// rs_simulate_lens.c -- the TRUE lens of a simulated camera (rs_simulate_lens, sim/rs_simulate.h)
// and the check of a lens model name. Calls mrcal and core/ (rs_rng) only.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim/internal/rs_simulate_internal.h"

typedef enum { FAMILY_PINHOLE, FAMILY_STEREOGRAPHIC, FAMILY_ANGULAR, FAMILY_CAHVORE } lens_family;

static lens_family family_of(mrcal_lensmodel_type_t t)
{
    switch (t) {
    case MRCAL_LENSMODEL_STEREOGRAPHIC:
    case MRCAL_LENSMODEL_SPLINED_STEREOGRAPHIC: return FAMILY_STEREOGRAPHIC;
    case MRCAL_LENSMODEL_LONLAT:
    case MRCAL_LENSMODEL_LATLON: return FAMILY_ANGULAR;
    case MRCAL_LENSMODEL_CAHVORE: return FAMILY_CAHVORE;
    default: return FAMILY_PINHOLE;
    }
}

// Parses and checks a lens model name against the image size and field of view.
rs_status rs_simulate__lens_check(mrcal_lensmodel_t *lm, const char *name, int W, int H, double hfov_deg, rs_err *err)
{
    if (!name || !*name) return rs_err_set(err, RS_ERR_USAGE, "lens: empty lens model name");
    if (!mrcal_lensmodel_from_name(lm, name) || !mrcal_lensmodel_type_is_valid(lm->type)) {
        if (lm->type == MRCAL_LENSMODEL_INVALID_BADCONFIG)
            return rs_err_set(err, RS_ERR_USAGE,
                              "lens: '%s' needs its configuration spelled out, e.g. "
                              "LENSMODEL_SPLINED_STEREOGRAPHIC_order=3_Nx=16_Ny=12_fov_x_deg=100 or "
                              "LENSMODEL_CAHVORE_linearity=0.00",
                              name);
        char known[512] = "";
        for (const char *const *n = mrcal_supported_lensmodel_names(); *n; n++) {
            size_t used = strlen(known);
            snprintf(known + used, sizeof known - used, "%s%s", used ? ", " : "", *n);
        }
        return rs_err_set(err, RS_ERR_USAGE, "lens: '%s' is not an mrcal lens model (known: %s)", name, known);
    }
    if (!mrcal_lensmodel_metadata(lm).has_core)
        return rs_err_set(err, RS_ERR_USAGE, "lens: %s has no intrinsics core (fx, fy, cx, cy)", name);
    if (W < 64 || H < 64 || W > 20000 || H > 20000)
        return rs_err_set(err, RS_ERR_USAGE, "image: %dx%d is outside 64x64 .. 20000x20000", W, H);
    double max_hfov = family_of(lm->type) == FAMILY_PINHOLE ? 170.0 : 340.0;
    if (family_of(lm->type) == FAMILY_CAHVORE) // theta |linearity| < 90 degrees
        max_hfov = fmin(340.0, 170.0 / fmax(1e-9, fabs(lm->LENSMODEL_CAHVORE__config.linearity)));
    if (!(hfov_deg >= 1.0 && hfov_deg <= max_hfov))
        return rs_err_set(err, RS_ERR_USAGE, "hfov_deg: %g is outside [1, %g] for %s", hfov_deg, max_hfov, name);
    return RS_OK;
}

rs_status rs_simulate_lens(mrcal_lensmodel_t *lensmodel, double **intrinsics, int *Nintrinsics, rs_rng *rng,
                           const char *lensmodel_name, int width_px, int height_px, double hfov_deg, bool distortion,
                           rs_err *err)
{
    *intrinsics = NULL;
    *Nintrinsics = 0;
    rs_status st = rs_simulate__lens_check(lensmodel, lensmodel_name, width_px, height_px, hfov_deg, err);
    if (st) return st;
    int N = mrcal_lensmodel_num_params(lensmodel);
    double *p = calloc((size_t)N, sizeof *p);
    if (!p) return rs_err_set(err, RS_ERR_NOMEM, "lens: out of memory");

    double half = 0.5 * hfov_deg * RS_RAD_PER_DEG, f;
    switch (family_of(lensmodel->type)) {
    case FAMILY_STEREOGRAPHIC: f = 0.5 * width_px / (2.0 * tan(0.5 * half)); break;
    case FAMILY_ANGULAR: f = 0.5 * width_px / half; break;
    case FAMILY_CAHVORE: { // the image's half width is chi(half): core/rs_lens.h
        const double L = lensmodel->LENSMODEL_CAHVORE__config.linearity;
        const double chi = fabs(L) < 1e-15 ? half : L > 0 ? tan(L * half) / L : sin(L * half) / L;
        f = 0.5 * width_px / chi;
        break;
    }
    default: f = 0.5 * width_px / tan(half); break;
    }
    f *= 1.0 + 0.002 * rs_rng_normal(rng);
    p[0] = p[1] = f;
    p[2] = 0.5 * (width_px - 1) + 0.004 * width_px * rs_rng_normal(rng);
    p[3] = 0.5 * (height_px - 1) + 0.004 * height_px * rs_rng_normal(rng);

    if (distortion) {
        mrcal_lensmodel_type_t t = lensmodel->type;
        if (MRCAL_LENSMODEL_IS_OPENCV(t)) {
            p[4] = -0.08 + 0.02 * rs_rng_normal(rng);                      // k1
            p[5] = 0.03 + 0.01 * rs_rng_normal(rng);                       // k2
            p[6] = 2e-4 * rs_rng_normal(rng);                              // p1
            p[7] = 2e-4 * rs_rng_normal(rng);                              // p2
            if (N > 8) p[8] = -0.005 + 0.002 * rs_rng_normal(rng);         // k3
            if (N > 9) p[9] = 0.01 * rs_rng_normal(rng);                   // k4 (k5, k6 = 0)
            for (int i = 12; i < N; i++) p[i] = 1e-4 * rs_rng_normal(rng); // s1..s4
        } else if (t == MRCAL_LENSMODEL_CAHVORE && fabs(lensmodel->LENSMODEL_CAHVORE__config.linearity) < 1e-15) {
            // a fisheye: Kannala-Brandt's k1, k2 (r1, r2 at linearity 0; docs/conventions.md)
            p[7] = 0.02 + 0.01 * rs_rng_normal(rng);    // r1 = k1
            p[8] = -0.004 + 0.002 * rs_rng_normal(rng); // r2 = k2
        } else if (t == MRCAL_LENSMODEL_CAHVOR || t == MRCAL_LENSMODEL_CAHVORE) {
            p[4] = 1e-3 * rs_rng_normal(rng);         // alpha
            p[5] = 1e-3 * rs_rng_normal(rng);         // beta
            p[7] = -0.05 + 0.01 * rs_rng_normal(rng); // r1 (r0 = 0)
            p[8] = 0.01 + 0.003 * rs_rng_normal(rng); // r2 (CAHVORE's e = 0)
        }
    }
    for (int i = 0; i < N; i++) p[i] = rs_simulate__quantize(p[i], Q_MODEL);
    *intrinsics = p;
    *Nintrinsics = N;
    return RS_OK;
}
