// rs_calib_solve_state.c -- the state of one rs_calib_solve: its set-up, the sigmas in use
// (calib/internal/rs_calib_solve_state.h).
#include "calib/internal/rs_calib_solve_state.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

rs_status rs_calib__state_init(rs_calib_solve_state *s, rs_calib_result *res, const rs_calib_problem *pb,
                               const rs_calib_options *opt, unsigned user_refine, int Ni, rs_err *err)
{
    const int N = pb->N;
    s->pb = pb;
    s->opt = opt;
    s->user_refine = user_refine;
    s->res = res;
    s->focal_scale = 1.0;
    s->p_survey_c = malloc((size_t)N * 3 * sizeof(double));
    s->p_c = malloc((size_t)N * 3 * sizeof(double));
    s->cov = malloc((size_t)(6 + Ni) * (size_t)(6 + Ni) * sizeof(double));
    s->block_chi2 = malloc((size_t)N * sizeof(double));
    s->q_pred = malloc((size_t)N * 2 * sizeof(double));
    s->use = malloc((size_t)N * sizeof(bool));
    s->sigma_px = malloc((size_t)N * sizeof(double));
    s->sigma_enu = malloc((size_t)N * 3 * sizeof(double));
    s->e = malloc((size_t)N * RS_NOISE_NCOMP * sizeof(double));
    s->r = malloc((size_t)N * RS_NOISE_NCOMP * sizeof(double));
    s->dpos = malloc((size_t)N * RS_NOISE_NCOMP * 3 * sizeof(double));
    s->dground = malloc((size_t)N * RS_NOISE_NCOMP * 2 * sizeof(double));
    s->chi2_excluded = malloc((size_t)N * sizeof(double));
    s->share = malloc((size_t)(N > 0 ? N : 1) * sizeof(double));
    if (pb->along) {
        s->along_c = calloc((size_t)N * 3, sizeof(double));
        s->s_along = calloc((size_t)N, sizeof(double));
    }
    if (!s->p_survey_c || !s->p_c || !s->cov || !s->block_chi2 || !s->q_pred || !s->use || !s->sigma_px ||
        !s->sigma_enu || !s->e || !s->r || !s->dpos || !s->dground || !s->chi2_excluded || !s->share ||
        (pb->along && (!s->along_c || !s->s_along)))
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; i < N; i++) s->chi2_excluded[i] = NAN;
    for (int i = 0; i < N; i++) { // picks sharing a survey error (quadratic: N is tens)
        s->share[i] = 1;
        for (int j = 0; j < N && pb->survey_shared && pb->survey_shared[i] >= 0; j++)
            s->share[i] += j != i && pb->survey_shared[j] == pb->survey_shared[i];
    }
    s->scale_free = rs_calib__scale_free(pb, opt);
    const double log_theta0[RS_NOISE_NGROUPS] = {0, 0, 0};
    rs_calib__scale_sigmas(s, log_theta0);

    // centred frame
    double *c = s->centroid_enu_m;
    for (int k = 0; k < 3; k++) c[k] = 0;
    for (int i = 0; i < N; i++)
        for (int k = 0; k < 3; k++) c[k] += pb->p_enu_m[3 * i + k] / N;
    for (int i = 0; i < N; i++)
        for (int k = 0; k < 3; k++) s->p_survey_c[3 * i + k] = pb->p_enu_m[3 * i + k] - c[k];
    memcpy(s->p_c, s->p_survey_c, (size_t)N * 3 * sizeof(double));

    s->rp = (rs_calib_refine_problem){.N = N,
                                      .p_survey_c_m = s->p_survey_c,
                                      .sigma_enu_m = pb->sigma_enu_m ? s->sigma_enu : NULL,
                                      .q_px = pb->q_px,
                                      .sigma_px = s->sigma_px,
                                      .use = s->use,
                                      .along_c = s->along_c,
                                      .s_along_m = s->s_along,
                                      .lensmodel = (&pb->camera->lensmodel),
                                      .intrinsics_nominal = pb->camera->intrinsics,
                                      .has_position_prior = pb->has_position_prior,
                                      .prior_sigma_m = pb->prior_sigma_m};
    for (int k = 0; k < 3; k++) s->rp.prior_position_c_m[k] = pb->prior_position_enu_m[k] - c[k];
    s->ro = (rs_calib_refine_options){.refine = opt->refine,
                                      .robust_scale = opt->robust_scale,
                                      .max_iterations = opt->max_iterations,
                                      .focal_prior_rel_sigma = opt->focal_prior_rel_sigma,
                                      .center_prior_sigma_px = opt->center_prior_sigma_px,
                                      .distortion_prior_sigma = opt->distortion_prior_sigma,
                                      .covariance = false,
                                      .rough = true};
    for (int i = 0; i < N; i++) s->use[i] = true;
    return RS_OK;
}

void rs_calib__state_free(rs_calib_solve_state *s)
{
    free(s->p_survey_c);
    free(s->p_c);
    free(s->cov);
    free(s->block_chi2);
    free(s->q_pred);
    free(s->use);
    free(s->sigma_px);
    free(s->sigma_enu);
    free(s->e);
    free(s->r);
    free(s->dpos);
    free(s->dground);
    free(s->chi2_excluded);
    free(s->along_c);
    free(s->share);
    free(s->s_along);
}

void rs_calib__scale_sigmas(rs_calib_solve_state *s, const double log_theta[RS_NOISE_NGROUPS])
{
    const rs_calib_problem *pb = s->pb;
    const double fp = exp(0.5 * log_theta[RS_NOISE_PIXEL]), fh = exp(0.5 * log_theta[RS_NOISE_SURVEY_H]),
                 fv = exp(0.5 * log_theta[RS_NOISE_SURVEY_V]);
    for (int i = 0; i < pb->N; i++) {
        s->sigma_px[i] = (pb->sigma_px ? pb->sigma_px[i] : 1.0) * fp;
        const double widen = sqrt(s->share[i]); // picks sharing one survey error (rs_calib.h)
        for (int k = 0; k < 3; k++)
            s->sigma_enu[3 * i + k] = (pb->sigma_enu_m ? pb->sigma_enu_m[3 * i + k] : 0.0) * (k < 2 ? fh : fv) * widen;
    }
}

bool rs_calib__scale_free(const rs_calib_problem *pb, const rs_calib_options *opt)
{
    if (opt->refine != RS_CALIB_REFINE_NONE || pb->has_position_prior || pb->along) return false;
    for (int k = 0; k < 3 * pb->N && pb->sigma_enu_m; k++)
        if (pb->sigma_enu_m[k] > 0) return false;
    return true;
}
