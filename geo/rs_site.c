// rs_site.c -- the site in memory (geo/rs_site.h): rs_site_free and the lookups (cameras,
// landmarks, a background's tags, the landmarks' extent, the names of height kinds, shapes and
// pick places). Reading a site is rs_site_read.c; this file calls nothing else of geo, and
// everything of the reader may call it.
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geo/rs_site.h"

void rs_site_free(rs_site *site)
{
    if (!site) return;
    for (int i = 0; i < site->Nlandmarks; i++) {
        free(site->landmarks[i].id);
        free(site->landmarks[i].kind);
        free(site->landmarks[i].note);
        free(site->landmarks[i].vertices_enu_m);
        free(site->landmarks[i].vertices_llh);
        free(site->landmarks[i].vertices_sigma_v_m);
        free(site->landmarks[i].vertices_given_h_m);
    }
    free(site->landmarks);
    for (int i = 0; i < site->Ncameras; i++) {
        rs_site_camera *cam = &site->cameras[i];
        free(cam->id);
        free(cam->model_path);
        free(cam->observations_path);
        free(cam->backgrounds_path);
        free(cam->note);
        for (int j = 0; j < cam->Nbackground_images; j++) {
            rs_site_background *bg = &cam->background_images[j];
            free(bg->name);
            free(bg->file);
            free(bg->path);
            for (int t = 0; t < bg->Ntags; t++) {
                free(bg->tags[t].key);
                free(bg->tags[t].value);
            }
            free(bg->tags);
        }
        free(cam->background_images);
        rs_camera_free(&cam->camera);
        free(cam->observations);
    }
    free(site->cameras);
    free(site->dir);
    free(site->name);
    free(site);
}

const char *rs_site_height_name(rs_site_height h)
{
    switch (h) {
    case RS_SITE_HEIGHT_DEFAULT: return "default";
    case RS_SITE_HEIGHT_SURVEYED: return "surveyed";
    case RS_SITE_HEIGHT_UNRELIABLE: return "unreliable";
    case RS_SITE_HEIGHT_UNKNOWN: return "unknown";
    }
    return "?";
}

const char *rs_site_shape_name(rs_site_shape shape)
{
    switch (shape) {
    case RS_SITE_POINT: return "point";
    case RS_SITE_POLE: return "pole";
    case RS_SITE_LINE: return "line";
    }
    return "?";
}

const char *rs_site_at_name(rs_site_at at)
{
    switch (at) {
    case RS_SITE_AT_POINT: return "point";
    case RS_SITE_AT_BASE: return "base";
    case RS_SITE_AT_TOP: return "top";
    case RS_SITE_AT_ALONG: return "along";
    }
    return "?";
}

bool rs_site_observed_point(double p_enu_m[3], double sigma_enu_m[3], const rs_site *site, const rs_site_observation *o)
{
    const rs_site_landmark *l = &site->landmarks[o->ilandmark];
    if (o->at == RS_SITE_AT_ALONG) return false;
    memcpy(p_enu_m, l->p_enu_m, 3 * sizeof(double));
    sigma_enu_m[0] = sigma_enu_m[1] = l->sigma_h_m;
    sigma_enu_m[2] = l->sigma_v_m;
    if (o->at == RS_SITE_AT_TOP) { // the top: straight up from the base, its height's sigma added
        p_enu_m[2] += l->pole_height_m;
        sigma_enu_m[2] = hypot(l->sigma_v_m, l->sigma_pole_height_m);
    }
    return true;
}

int rs_site_along_polyline(const double **vertices_enu_m, double pole_vertices_enu_m[6], double sigma_enu_m[3],
                           const rs_site *site, const rs_site_observation *o)
{
    const rs_site_landmark *l = &site->landmarks[o->ilandmark];
    *vertices_enu_m = NULL;
    sigma_enu_m[0] = sigma_enu_m[1] = l->sigma_h_m;
    sigma_enu_m[2] = l->sigma_v_m;
    if (o->at != RS_SITE_AT_ALONG) return 0;
    if (l->shape == RS_SITE_POLE) {
        memcpy(pole_vertices_enu_m, l->p_enu_m, 3 * sizeof(double));
        memcpy(pole_vertices_enu_m + 3, l->p_enu_m, 3 * sizeof(double));
        pole_vertices_enu_m[5] += l->pole_height_m;
        *vertices_enu_m = pole_vertices_enu_m;
        return 2;
    }
    *vertices_enu_m = l->vertices_enu_m;
    return l->Nvertices;
}

bool rs_site_seen_point(double p_enu_m[3], double *q_px, const rs_site *site, const rs_site_observation *o,
                        const rs_camera *cam)
{
    double sigma[3], pole[6], q[2];
    const double *v;
    const int n = rs_site_along_polyline(&v, pole, sigma, site, o);
    if (n == 0) {
        rs_site_observed_point(p_enu_m, sigma, site, o);
        const bool ok = rs_camera_project(q, cam, p_enu_m, 1) == 1;
        if (q_px) q_px[0] = q[0], q_px[1] = q[1];
        return ok;
    }
    const bool ok = rs_camera_nearest_on_polyline(p_enu_m, q, cam, v, n, o->q_px);
    if (q_px) q_px[0] = q[0], q_px[1] = q[1];
    return ok;
}

int rs_site_find_camera(const rs_site *site, const char *id)
{
    for (int i = 0; i < site->Ncameras; i++)
        if (site->cameras[i].id && !strcmp(site->cameras[i].id, id)) return i;
    return -1;
}

int rs_site_find_landmark(const rs_site *site, const char *id)
{
    for (int i = 0; i < site->Nlandmarks; i++)
        if (site->landmarks[i].id && !strcmp(site->landmarks[i].id, id)) return i;
    return -1;
}

const char *rs_site_background_tag(const rs_site_background *bg, const char *key)
{
    for (int t = 0; t < bg->Ntags; t++)
        if (bg->tags[t].key && bg->tags[t].value && !strcmp(bg->tags[t].key, key)) return bg->tags[t].value;
    if (!strcmp(key, "name")) return bg->name;
    if (!strcmp(key, "file")) return bg->file;
    if (!strcmp(key, "synthetic")) return bg->synthetic ? "true" : "false";
    return NULL;
}

int rs_site_landmark_extent(double *min_enu_m, double *max_enu_m, double *dmin_m, double *dmax_m, const rs_site *site,
                            int icam)
{
    int n = icam < 0 ? site->Nlandmarks : site->cameras[icam].Nobservations;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double dlo = INFINITY, dhi = -INFINITY;
    for (int i = 0; i < n; i++) {
        int il = icam < 0 ? i : site->cameras[icam].observations[i].ilandmark;
        const rs_site_landmark *l = &site->landmarks[il];
        // every vertex of a line, a pole's base and top
        const int nv = l->shape == RS_SITE_LINE && l->vertices_enu_m ? l->Nvertices : 1;
        for (int v = 0; v < nv + (l->shape == RS_SITE_POLE); v++) {
            double p[3];
            memcpy(p, v < nv && v > 0 ? &l->vertices_enu_m[3 * v] : l->p_enu_m, sizeof p);
            if (v == nv) p[2] += l->pole_height_m;
            for (int k = 0; k < 3; k++) {
                lo[k] = fmin(lo[k], p[k]);
                hi[k] = fmax(hi[k], p[k]);
            }
            double d = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            dlo = fmin(dlo, d);
            dhi = fmax(dhi, d);
        }
    }
    if (n == 0) return 0;
    if (min_enu_m) memcpy(min_enu_m, lo, sizeof lo);
    if (max_enu_m) memcpy(max_enu_m, hi, sizeof hi);
    if (dmin_m) *dmin_m = dlo;
    if (dmax_m) *dmax_m = dhi;
    return n;
}
