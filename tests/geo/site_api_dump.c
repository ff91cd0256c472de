// site_api_dump SITE -- loads SITE through the C API (rs_site_load) and prints what the test
// drivers test_site_api.py and test_site_heights_model.py assert on, one "key value" per line:
// the status and its message, the counts, every observation, the lookups, the extents, the
// ground model and each landmark's height record. Exits 0 whenever it ran.
#include <math.h>
#include <stdio.h>

#include "geo/rs_site.h"

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: site_api_dump SITE\n");
        return 2;
    }
    rs_site_free(NULL); // accepts NULL
    rs_site_report_free(NULL);
    rs_site *site = (rs_site *)1;
    rs_err err = {0};
    rs_status st = rs_site_load(&site, argv[1], &err);
    printf("status %d %s\n", (int)st, rs_strerror(st));
    printf("message %s\n", err.msg);
    if (st != RS_OK) {
        printf("site_is_null %d\n", site == NULL);
        return 0;
    }
    printf("landmarks %d\ncameras %d\n", site->Nlandmarks, site->Ncameras);
    for (int i = 0; i < site->Ncameras; i++) {
        const rs_site_camera *c = &site->cameras[i];
        printf("camera %s %d %d %d %d %d\n", c->id, (int)c->camera.lensmodel.type, c->camera.Nintrinsics,
               c->camera.width, c->camera.height, c->has_position_prior);
        for (int j = 0; j < c->Nobservations; j++) {
            const rs_site_observation *o = &c->observations[j];
            printf("obs %s %s %.17g %.17g %.17g %d\n", c->id, site->landmarks[o->ilandmark].id, o->q_px[0], o->q_px[1],
                   o->sigma_px, o->line);
        }
    }
    printf("find_camera_south %d\nfind_camera_nope %d\n", rs_site_find_camera(site, "south"),
           rs_site_find_camera(site, "nope"));
    printf("find_landmark_L05 %d\nfind_landmark_l05 %d\n", rs_site_find_landmark(site, "L05"),
           rs_site_find_landmark(site, "l05"));
    double lo[3], hi[3], dmin, dmax;
    int n = rs_site_landmark_extent(lo, hi, &dmin, &dmax, site, -1);
    printf("extent %d %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", n, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2],
           dmin, dmax);
    n = rs_site_landmark_extent(NULL, NULL, NULL, &dmax, site, 1);
    printf("extent_south %d %.17g\n", n, dmax);
    printf("ground %.17g %.17g %.17g %.17g\n", site->ground_normal_enu[0], site->ground_normal_enu[1],
           site->ground_normal_enu[2], site->ground_offset_m);
    for (int i = 0; i < site->Nlandmarks; i++) {
        const rs_site_landmark *l = &site->landmarks[i];
        printf("landmark %s %d %.17g %.17g %.17g %.17g %.17g %.17g %.17g %s\n", l->id, l->feature, l->llh.lat_deg,
               l->llh.lon_deg, l->llh.h_m, l->p_enu_m[0], l->p_enu_m[1], l->p_enu_m[2], l->sigma_h_m,
               l->kind ? l->kind : "-");
    }
    // the ground model (rs_site_ground_model) and each landmark's height record
    const rs_site_ground_model *m = &site->ground;
    printf("landmark_heights %s %d\n", rs_site_height_name(site->landmark_heights), site->ground_plane_given);
    printf("ground_model %d %d %d %d %d %d", (int)m->source, m->Nmodelled, m->Nunreliable, m->Nunknown, m->Ncandidates,
           m->Nused);
    const double v[] = {m->centre_en_m[0], m->centre_en_m[1], m->up_m, m->slope[0], m->slope[1]};
    for (int k = 0; k < 5; k++) printf(" %.17g", v[k]);
    for (int k = 0; k < 9; k++) printf(" %.17g", m->cov[k]);
    const double w[] = {m->rms_m,
                        m->stated_sigma_m,
                        m->scale_m,
                        m->scatter_m,
                        m->sigma_min_m,
                        m->sigma_max_m,
                        m->mean_given_minus_model_m,
                        m->max_abs_given_minus_model_m};
    for (int k = 0; k < 8; k++) printf(" %.17g", w[k]);
    printf(" %d\n", m->Ndisagree);
    for (int i = 0; i < site->Nlandmarks; i++) {
        const rs_site_landmark *l = &site->landmarks[i];
        double up, sigma_plane;
        rs_site_ground_predict(&up, &sigma_plane, m, l->p_enu_m[0], l->p_enu_m[1]);
        printf("lheight %s %s %s %d %d %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", l->id,
               rs_site_height_name(l->height_stated), rs_site_height_name(l->height), l->height_modelled,
               l->ground_used, l->above_ground_m, l->given_h_m, l->given_up_m, l->given_sigma_v_m, l->sigma_v_m,
               l->llh.h_m, l->p_enu_m[0], l->p_enu_m[1], l->p_enu_m[2], up, sigma_plane);
    }
    // issue 13, item 4: each landmark's shape and vertices, each pick's place on it
    for (int i = 0; i < site->Nlandmarks; i++) {
        const rs_site_landmark *l = &site->landmarks[i];
        printf("shape %s %s %.17g %.17g %d\n", l->id, rs_site_shape_name(l->shape), l->pole_height_m,
               l->sigma_pole_height_m, l->Nvertices);
        for (int k = 0; k < l->Nvertices; k++) {
            const rs_llh *v = &l->vertices_llh[k];
            const double *p = &l->vertices_enu_m[3 * k];
            printf("vertex %s %d %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", l->id, k, v->lat_deg, v->lon_deg,
                   v->h_m, p[0], p[1], p[2], l->vertices_sigma_v_m[k], l->vertices_given_h_m[k]);
        }
    }
    for (int i = 0; i < site->Ncameras; i++) {
        const rs_site_camera *c = &site->cameras[i];
        for (int j = 0; j < c->Nobservations; j++)
            printf("obsat %s %s %s %d\n", c->id, site->landmarks[c->observations[j].ilandmark].id,
                   rs_site_at_name(c->observations[j].at), c->observations[j].line);
    }
    rs_site_free(site);
    return 0;
}
