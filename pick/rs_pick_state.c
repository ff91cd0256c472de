// rs_pick_state.c -- the picking session seen from outside (rs_pick.h): its state as the page's
// JSON (landmarks, picks, the solve, the ground uncertainty) and its picks exported as point pairs.
#include "pick/rs_pick.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "calib/rs_calib.h"
#include "calib/rs_calib_site.h"
#include "geo/rs_site.h"
#include "pick/internal/rs_pick_internal.h"

char *rs_pick_export(const rs_pick_session *s, bool csv)
{
    const rs_site *site = s->site;
    const rs_site_camera *cam = &site->cameras[s->icam];
    cJSON *root = csv ? NULL : cJSON_CreateObject(), *res = root ? cJSON_AddArrayToObject(root, "results") : NULL;
    size_t cap = 64 + (size_t)cam->Nobservations * 160, len = 0;
    char *text = csv ? malloc(cap) : NULL;
    if (csv ? !text : !res) {
        cJSON_Delete(root);
        return NULL;
    }
    if (csv) len = (size_t)snprintf(text, cap, "id,lat,lon,u,v,sigma_px\n");
    for (int k = 0; k < cam->Nobservations; k++) {
        const rs_site_observation *o = &cam->observations[k];
        if (o->at == RS_SITE_AT_TOP || o->at == RS_SITE_AT_ALONG) continue; // a pair is a point's
        const rs_site_landmark *l = &site->landmarks[o->ilandmark];
        if (csv) {
            len += (size_t)snprintf(text + len, cap - len, "%s,%.9f,%.9f,%.6f,%.6f,%g\n", l->id, l->llh.lat_deg,
                                    l->llh.lon_deg, o->q_px[0], o->q_px[1], o->sigma_px);
            continue;
        }
        cJSON *r = cJSON_CreateObject();
        cJSON_AddItemToArray(res, r);
        cJSON_AddStringToObject(r, "id", l->id);
        cJSON_AddNumberToObject(r, "x", o->q_px[0]);
        cJSON_AddNumberToObject(r, "y", o->q_px[1]);
        cJSON_AddNumberToObject(r, "lat", l->llh.lat_deg);
        cJSON_AddNumberToObject(r, "lng", l->llh.lon_deg);
    }
    if (csv) return text;
    text = cJSON_Print(root);
    cJSON_Delete(root);
    return text;
}

// ---- the state as JSON ----

static cJSON *numbers(const double *x, int n)
{
    cJSON *a = cJSON_CreateArray();
    for (int i = 0; a && i < n; i++)
        cJSON_AddItemToArray(a, isfinite(x[i]) ? cJSON_CreateNumber(x[i]) : cJSON_CreateNull());
    return a;
}

static void add_num(cJSON *o, const char *k, double x)
{
    if (isfinite(x))
        cJSON_AddNumberToObject(o, k, x);
    else
        cJSON_AddNullToObject(o, k);
}

// Why a landmark is flagged, in words ("" when it is not).
static void flag_reason(char *buf, size_t n, const rs_calib_result *r, int k)
{
    buf[0] = '\0';
    if (!r->inlier[k]) {
        if (r->w_test && isfinite(r->w_test[k]))
            snprintf(buf, n, "rejected by data snooping: w = %.2f (critical 3.29); normalised residual %.2f sigma",
                     r->w_test[k], r->normalised_residual[k]);
        else
            snprintf(buf, n, "rejected as an outlier: normalised residual %.2f sigma > 3.717",
                     r->normalised_residual[k]);
    } else if (r->redundancy && r->redundancy[k] < 0.1) {
        snprintf(buf, n, "uncontrolled: redundancy %.2f, an error in this pick would not show", r->redundancy[k]);
    }
}

// calib's warnings name its command-line options; on the page the same choice is the refine
// menu. Returns a malloc'ed copy with "run with --refine WORDS" said as that menu (NULL: no memory).
static char *warnings_for_page(const char *w)
{
    if (!w) return NULL;
    static const char from[] = "run with --refine ", to[] = "choose refine: ";
    char *out = malloc(strlen(w) * 3 + 64), *o = out;
    if (!out) return NULL;
    for (const char *p = w; *p;) {
        if (!strncmp(p, from, sizeof from - 1)) {
            p += sizeof from - 1;
            const char *e = p + strcspn(p, " ,.;)");
            o += sprintf(o, "%s%.*s above (calib's --refine %.*s)", to, (int)(e - p), p, (int)(e - p), p);
            p = e;
        } else
            *o++ = *p++;
    }
    *o = '\0';
    return out;
}

char *rs_pick_state_json(const rs_pick_session *s)
{
    const rs_site *site = s->site;
    const rs_site_camera *cam = &site->cameras[s->icam];
    cJSON *root = cJSON_CreateObject();
    if (!root) return NULL;
    cJSON *c = cJSON_AddObjectToObject(root, "camera");
    cJSON_AddStringToObject(c, "id", cam->id);
    cJSON_AddNumberToObject(c, "width", cam->camera.width);
    cJSON_AddNumberToObject(c, "height", cam->camera.height);
    cJSON_AddStringToObject(root, "site", site->name ? site->name : "");
    cJSON_AddBoolToObject(root, "can_undo", s->Nundo > 0);
    cJSON_AddBoolToObject(root, "unsaved", s->dirty);
    cJSON_AddNumberToObject(root, "picks", cam->Nobservations);
    char refine[64];
    rs_calib_refine_name(refine, sizeof refine, s->refine);
    cJSON_AddStringToObject(root, "refine", refine);
    // the pick index of each landmark
    int *pick_of = calloc((size_t)(site->Nlandmarks > 0 ? site->Nlandmarks : 1), sizeof *pick_of);
    if (!pick_of) {
        cJSON_Delete(root);
        return NULL;
    }
    for (int i = 0; i < site->Nlandmarks; i++) pick_of[i] = -1;
    for (int k = 0; k < cam->Nobservations; k++)
        if (cam->observations[k].at != RS_SITE_AT_TOP) pick_of[cam->observations[k].ilandmark] = k;
    const rs_calib_result *r = &s->result;
    cJSON *ls = cJSON_AddArrayToObject(root, "landmarks");
    int Nflagged = 0;
    for (int i = 0; i < site->Nlandmarks; i++) {
        const rs_site_landmark *l = &site->landmarks[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddItemToArray(ls, o);
        cJSON_AddStringToObject(o, "id", l->id);
        cJSON_AddStringToObject(o, "kind", l->kind ? l->kind : "");
        cJSON_AddStringToObject(o, "shape", rs_site_shape_name(l->shape));
        cJSON_AddItemToObject(o, "enu_m", numbers(l->p_enu_m, 3));
        cJSON_AddNumberToObject(o, "sigma_h_m", l->sigma_h_m);
        cJSON_AddNumberToObject(o, "sigma_v_m", l->given_sigma_v_m);
        cJSON_AddBoolToObject(o, "sigma_stated", l->sigma_h_stated || l->sigma_v_stated);
        cJSON_AddItemToObject(o, "lat_lon_deg", numbers((const double[]){l->llh.lat_deg, l->llh.lon_deg}, 2));
        const int k = pick_of[i];
        if (k >= 0)
            cJSON_AddItemToObject(o, "pick_px", numbers(cam->observations[k].q_px, 2));
        else
            cJSON_AddNullToObject(o, "pick_px");
        if (s->solved && i < s->Npredicted)
            cJSON_AddItemToObject(o, "predicted_px", numbers(&s->predicted_px[2 * i], 2));
        else
            cJSON_AddNullToObject(o, "predicted_px");
        if (s->solved && k >= 0) {
            const double res[2] = {s->predicted_px[2 * i] - cam->observations[k].q_px[0],
                                   s->predicted_px[2 * i + 1] - cam->observations[k].q_px[1]};
            cJSON_AddItemToObject(o, "residual_px", numbers(res, 2));
            add_num(o, "residual_norm_px", hypot(res[0], res[1]));
            add_num(o, "normalised_residual", r->normalised_residual[k]);
            cJSON_AddBoolToObject(o, "inlier", r->inlier[k]);
            char why[256];
            flag_reason(why, sizeof why, r, k);
            cJSON_AddBoolToObject(o, "flagged", why[0] != '\0');
            cJSON_AddStringToObject(o, "flag", why);
            Nflagged += why[0] != '\0';
        } else {
            cJSON_AddNullToObject(o, "residual_px");
            cJSON_AddBoolToObject(o, "flagged", false);
            cJSON_AddStringToObject(o, "flag", "");
        }
    }
    free(pick_of);
    cJSON *so = cJSON_AddObjectToObject(root, "solve");
    cJSON_AddBoolToObject(so, "ok", s->solved);
    cJSON_AddStringToObject(so, "message", s->solve_message);
    add_num(so, "time_ms", s->solve_ms);
    if (s->solved) {
        cJSON_AddItemToObject(so, "rt_cam_enu", numbers(r->rt_cam_enu, 6));
        cJSON_AddItemToObject(so, "covariance_rt_cam_enu", numbers(r->covariance_rt_cam_enu, 36));
        cJSON_AddItemToObject(so, "position_enu_m", numbers(r->position_enu_m, 3));
        cJSON_AddItemToObject(so, "sigma_position_enu_m", numbers(r->sigma_position_enu_m, 3));
        cJSON_AddItemToObject(so, "covariance_position_en_m2", numbers(s->cov_en_m2, 4));
        cJSON_AddItemToObject(so, "yaw_pitch_roll_deg", numbers(r->yaw_pitch_roll_deg, 3));
        cJSON_AddItemToObject(so, "sigma_yaw_pitch_roll_deg", numbers(r->sigma_yaw_pitch_roll_deg, 3));
        add_num(so, "rms_surveyed_px", rs_calib_site_rms_surveyed_px(site, s->icam, r, NULL));
        add_num(so, "rms_adjusted_px", r->rms_px);
        add_num(so, "variance_factor", r->variance_factor);
        cJSON_AddNumberToObject(so, "inliers", r->Ninliers);
        cJSON_AddNumberToObject(so, "flagged", Nflagged);
        char *w = warnings_for_page(r->warnings);
        cJSON_AddStringToObject(so, "warnings", w ? w : r->warnings);
        free(w);
        cJSON *g = cJSON_AddObjectToObject(root, "ground_uncertainty");
        cJSON_AddStringToObject(g, "what",
                                "1-sigma horizontal ground error (m) of a point detected to 1 px, "
                                "sampled on a grid over the image");
        cJSON_AddNumberToObject(g, "nu", GROUND_NU);
        cJSON_AddNumberToObject(g, "nv", GROUND_NV);
        cJSON_AddItemToObject(g, "sigma_m", numbers(&s->ground_sigma_m[0][0], GROUND_NU * GROUND_NV));
    }
    char *text = cJSON_PrintUnformatted(root);
    cJSON_Delete(root);
    return text;
}
