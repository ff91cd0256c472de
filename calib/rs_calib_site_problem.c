// rs_calib_site_problem.c -- one camera of a site as the solver's problem (calib/rs_calib_site.h):
// its picks, their landmarks' surveyed positions and sigmas (a pick along a pole or a line: its
// polyline), which picks share a survey error, the nominal camera and its priors.
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "calib/rs_calib_site.h"

rs_status rs_calib_site_problem_init(rs_calib_site_problem *sp, const rs_site *site, int icam, rs_err *err)
{
    memset(sp, 0, sizeof *sp);
    if (!site || icam < 0 || icam >= site->Ncameras)
        return rs_err_set(err, RS_ERR_USAGE, "camera index %d out of range", icam);
    const rs_site_camera *cam = &site->cameras[icam];
    int N = cam->Nobservations;
    bool any_along = false;
    for (int i = 0; i < N; i++) any_along |= cam->observations[i].at == RS_SITE_AT_ALONG;
    size_t n = N > 0 ? (size_t)N : 1;
    sp->p_enu_m = malloc(n * 3 * sizeof(double));
    sp->sigma_enu_m = malloc(n * 3 * sizeof(double));
    sp->q_px = malloc(n * 2 * sizeof(double));
    sp->sigma_px = malloc(n * sizeof(double));
    sp->survey_shared = malloc(n * sizeof(int));
    if (any_along) {
        sp->along = calloc(n, sizeof *sp->along);
        sp->pole_vertices_m = malloc(n * 6 * sizeof(double));
    }
    if (!sp->p_enu_m || !sp->sigma_enu_m || !sp->q_px || !sp->sigma_px || !sp->survey_shared ||
        (any_along && (!sp->along || !sp->pole_vertices_m))) {
        rs_calib_site_problem_free(sp);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < N; i++) {
        const rs_site_observation *o = &cam->observations[i];
        if (o->at == RS_SITE_AT_ALONG) { // the solver chooses the point; p_enu_m: its first vertex
            const int nv = rs_site_along_polyline(&sp->along[i].p_enu_m, &sp->pole_vertices_m[6 * i],
                                                  &sp->sigma_enu_m[3 * i], site, o);
            sp->along[i].Nvertices = nv;
            memcpy(&sp->p_enu_m[3 * i], sp->along[i].p_enu_m, 3 * sizeof(double));
        } else {
            rs_site_observed_point(&sp->p_enu_m[3 * i], &sp->sigma_enu_m[3 * i], site, o);
        }
        sp->q_px[2 * i + 0] = o->q_px[0];
        sp->q_px[2 * i + 1] = o->q_px[1];
        sp->sigma_px[i] = o->sigma_px;
    }
    // the picks of one pole or line share its survey error (rs_calib_problem.survey_shared)
    for (int i = 0; i < N; i++)
        sp->survey_shared[i] = site->landmarks[cam->observations[i].ilandmark].shape == RS_SITE_POINT
                                   ? -1
                                   : cam->observations[i].ilandmark;
    rs_calib_problem *p = &sp->problem;
    p->N = N;
    p->p_enu_m = sp->p_enu_m;
    p->sigma_enu_m = sp->sigma_enu_m;
    p->q_px = sp->q_px;
    p->sigma_px = sp->sigma_px;
    p->along = sp->along;
    p->survey_shared = sp->survey_shared;
    p->camera = &cam->camera;
    p->has_position_prior = cam->has_position_prior;
    if (cam->has_position_prior) {
        memcpy(p->prior_position_enu_m, cam->prior_p_enu_m, sizeof p->prior_position_enu_m);
        p->prior_sigma_m = cam->prior_sigma_m;
    }
    p->focal_rel_sigma = cam->focal_rel_sigma; // the stated intrinsics uncertainty (0: exact)
    p->center_sigma_px = cam->center_sigma_px;
    return RS_OK;
}

void rs_calib_site_problem_free(rs_calib_site_problem *sp)
{
    if (!sp) return;
    free(sp->p_enu_m);
    free(sp->sigma_enu_m);
    free(sp->q_px);
    free(sp->sigma_px);
    free(sp->along);
    free(sp->survey_shared);
    free(sp->pole_vertices_m);
    memset(sp, 0, sizeof *sp);
}

void rs_calib_site_name_landmarks(char *text, size_t size, const rs_site *site, int icam)
{
    char *at = strstr(text, "(index ");
    if (!at || icam < 0 || icam >= site->Ncameras) return;
    const rs_site_camera *cam = &site->cameras[icam];
    char *list = at + strlen("(index "), *end = list;
    while (isdigit((unsigned char)*end) || *end == ',') end++;
    if (end == list) return;
    char names[512] = "";
    size_t n = 0;
    for (char *p = list; p < end && n + 2 < sizeof names;) {
        int i = (int)strtol(p, &p, 10);
        const int il = i >= 0 && i < cam->Nobservations ? cam->observations[i].ilandmark : -1;
        if (il >= 0 && il < site->Nlandmarks && site->landmarks[il].id)
            n += (size_t)snprintf(names + n, sizeof names - n, "%s%s", n ? ", " : "", site->landmarks[il].id);
        else
            n += (size_t)snprintf(names + n, sizeof names - n, "%s#%d", n ? ", " : "", i);
        if (*p == ',') p++;
    }
    char *out = malloc(size);
    if (!out) return;
    // "(index 2,5" -> "(landmarks L003, L006"
    snprintf(out, size, "%.*s(landmark%s %s%s", (int)(at - text), text, strchr(names, ',') ? "s" : "", names, end);
    memcpy(text, out, size);
    text[size - 1] = '\0';
    free(out);
}

const char *rs_calib_site_warning_sentence(char *sentence, size_t size, const char *warnings, const rs_site *site,
                                           int icam)
{
    while (*warnings == ';' || *warnings == ' ') warnings++;
    sentence[0] = '\0';
    if (!*warnings || size < 2) return NULL;
    const size_t n = rs_calib_warning_len(warnings);
    snprintf(sentence, size - 1, "%.*s", (int)n, warnings);
    rs_calib_site_name_landmarks(sentence, size - 1, site, icam);
    sentence[0] = (char)toupper((unsigned char)sentence[0]);
    if (sentence[strlen(sentence) - 1] != '.') strcat(sentence, ".");
    return warnings + n;
}
