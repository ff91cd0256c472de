// site_write_roundtrip SITE OUT tool|hand -- geo's writers (geo/rs_site_write.h, rs_lanes_write)
// driven from what geo's reader read: loads SITE (rs_site_load), writes OUT/site.json (with an
// extra "simulated" member), OUT/landmarks.geojson and the observation CSVs from it in the given
// layout, records two backgrounds (rs_site_record_background), writes two lanes both ways
// (rs_lanes_write, [lon, lat] and [lon, lat, h]) and reads them back (rs_lanes_read), then loads
// OUT and prints what test_site_write.py asserts on, one "key value..." per line. The camera
// model files are the test's to copy. Exits 0 whenever it ran (failures are printed as
// "status N message").
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "geo/rs_lanes.h"
#include "geo/rs_site.h"
#include "geo/rs_site_write.h"

// `path` relative to the site folder `dir` (the reader joined them), or path itself.
static const char *relative(const char *path, const char *dir)
{
    size_t n = strlen(dir);
    return path && !strncmp(path, dir, n) && path[n] == '/' ? path + n + 1 : path;
}

static int report(const char *what, rs_status st, const rs_err *err)
{
    printf("status %d %s: %s\n", (int)st, what, err->msg);
    return 0;
}

// Writes OUT's site.json, landmarks.geojson and observations from the loaded site.
static rs_status write_site(const rs_site *site, const char *out, rs_site_layout layout, rs_err *err)
{
    const double N = site->geoid_undulation_m;
    rs_site_spec_camera cams[16];
    rs_llh priors[16];
    if (site->Ncameras > 16) return rs_err_set(err, RS_ERR_INVALID, "too many cameras");
    for (int i = 0; i < site->Ncameras; i++) {
        const rs_site_camera *c = &site->cameras[i];
        cams[i] = (rs_site_spec_camera){.id = c->id,
                                        .model = relative(c->model_path, site->dir),
                                        .observations = relative(c->observations_path, site->dir),
                                        .backgrounds = relative(c->backgrounds_path, site->dir),
                                        .note = c->note};
        if (c->has_position_prior) {
            priors[i] = (rs_llh){c->prior_llh.lat_deg, c->prior_llh.lon_deg, c->prior_llh.h_m - N};
            cams[i].position_prior = &priors[i];
            cams[i].prior_sigma_m = c->prior_sigma_m;
        }
    }
    const rs_site_spec spec = {
        .name = site->name,
        .origin = {site->origin.lat_deg, site->origin.lon_deg, site->origin.h_m - N},
        .geoid_undulation_m = site->heights_orthometric ? &N : NULL,
        .landmark_sigma_h_m = site->landmark_sigma_h_m,
        .landmark_sigma_v_m = site->landmark_sigma_v_m,
        // the default is not written: the fixture's site.json has no "landmark_heights"
        .landmark_heights =
            site->landmark_heights == RS_SITE_HEIGHT_SURVEYED ? RS_SITE_HEIGHT_DEFAULT : site->landmark_heights,
        .ground_normal_enu = site->ground_normal_enu,
        .ground_offset_m = site->ground_offset_m,
        .max_landmark_distance_m = site->max_landmark_distance_m,
        .cameras = cams,
        .Ncameras = site->Ncameras,
        .extra_name = "simulated",
        .extra_json = "{\"seed\": 5, \"values\": [1, 2.5, -0.125], \"text\": \"a \\\"quoted\\\" word\"}",
    };
    rs_status st = rs_site_write_json(out, &spec, layout, err);
    // landmark sigmas equal to the site's default are the default: not written
    rs_site_landmark *lm = calloc((size_t)site->Nlandmarks + 1, sizeof *lm);
    if (!lm) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; i < site->Nlandmarks; i++) {
        lm[i] = site->landmarks[i];
        if (lm[i].sigma_h_m == site->landmark_sigma_h_m) lm[i].sigma_h_m = NAN;
        if (lm[i].sigma_v_m == site->landmark_sigma_v_m) lm[i].sigma_v_m = NAN;
    }
    if (!st) st = rs_site_write_landmarks(out, lm, site->Nlandmarks, N, layout, err);
    free(lm);
    for (int i = 0; i < site->Ncameras && !st; i++) {
        char *path = rs_io_join(out, cams[i].observations);
        st = path ? rs_site_write_observations(path, site->cameras[i].observations, site->cameras[i].Nobservations,
                                               site->landmarks, err)
                  : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(path);
    }
    return st;
}

// Two lanes in ENU written and read back; prints the largest difference of the points.
static rs_status lanes_roundtrip(const rs_site *site, const char *out, bool with_height, rs_site_layout layout,
                                 rs_err *err)
{
    double a[3][3] = {{-40, 3, 0}, {-13.5, 3.25, 0}, {0, 0, 0}}, b[2][3] = {{0, 0, 0}, {20, 45.5, 0}};
    int next_a = 1;
    rs_lane lane[2] = {
        {.id = "A1_in1",
         .kind = "approach",
         .width_m = 3.5,
         .direction = RS_LANE_FORWARD,
         .speed_mps = 13.89,
         .p_enu_m = a,
         .Npoints = 3,
         .next = &next_a,
         .Nnext = 1},
        {.id = "track",
         .kind = NULL,
         .width_m = 2.75,
         .direction = RS_LANE_BOTH,
         .speed_mps = NAN,
         .p_enu_m = b,
         .Npoints = 2,
         .next = NULL,
         .Nnext = 0},
    };
    if (with_height) a[1][2] = b[1][2] = 0.75;
    const rs_lanes lanes = {.lane = lane, .N = 2};
    char name[64];
    snprintf(name, sizeof name, "lanes_%s.geojson", with_height ? "3d" : "2d");
    char *path = rs_io_join(out, name);
    rs_lanes back = {0};
    rs_status st = path
                       ? rs_lanes_write(path, &lanes, &site->origin, site->geoid_undulation_m, with_height, layout, err)
                       : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) st = rs_lanes_read(&back, path, site, err);
    double dmax = 0;
    for (int i = 0; !st && i < 2; i++) {
        const rs_lane *l = &back.lane[i];
        if (strcmp(l->id, lane[i].id) || l->Npoints != lane[i].Npoints || l->Nnext != lane[i].Nnext ||
            l->direction != lane[i].direction || l->width_m != lane[i].width_m) {
            st = rs_err_set(err, RS_ERR_INVALID, "%s: lane %d read back differs", path, i);
            break;
        }
        // without heights the reader puts the points on the ground plane (up = 0 here)
        for (int k = 0; k < l->Npoints; k++)
            for (int j = 0; j < 3; j++) dmax = fmax(dmax, fabs(l->p_enu_m[k][j] - lane[i].p_enu_m[k][j]));
    }
    if (!st) printf("lanes %s %.3g\n", with_height ? "3d" : "2d", dmax);
    rs_lanes_free(&back);
    free(path);
    return st;
}

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: site_write_roundtrip SITE OUT tool|hand\n");
        return 2;
    }
    const rs_site_layout layout = strcmp(argv[3], "hand") ? RS_SITE_LAYOUT_TOOL : RS_SITE_LAYOUT_HAND;
    rs_site *site = NULL, *again = NULL;
    rs_err err = {0};
    rs_status st = rs_site_load(&site, argv[1], &err);
    if (st) return report("load", st, &err);
    if ((st = write_site(site, argv[2], layout, &err))) return report("write", st, &err);

    const char *keys[4] = {"time", "conditions", "foo", "foo"},
               *values[4] = {"2024-06-21T07:30:00+02:00", "sunny", "1", "3"};
    if ((st = rs_site_record_background(argv[2], "north", "morning", false, keys, values, 4,
                                        "{\"method\": \"test\", \"frames\": 3}", &err)) ||
        (st = rs_site_record_background(argv[2], "south", "twin", true, keys + 1, values + 1, 1, NULL, &err)) ||
        (st = rs_site_record_background(argv[2], "north", "evening", false, NULL, NULL, 0, NULL, &err)))
        return report("record", st, &err);
    st = rs_site_record_background(argv[2], "nope", "x", false, NULL, NULL, 0, NULL, &err);
    printf("record_unknown_camera %d\n", (int)st);
    st = rs_site_record_background(argv[2], "north", "x", false, NULL, NULL, 0, "{not json", &err);
    printf("record_bad_source %d\n", (int)st);

    if ((st = lanes_roundtrip(site, argv[2], false, layout, &err)) ||
        (st = lanes_roundtrip(site, argv[2], true, layout, &err)))
        return report("lanes", st, &err);

    if ((st = rs_site_load(&again, argv[2], &err))) return report("reload", st, &err);
    for (int i = 0; i < again->Ncameras; i++) {
        const rs_site_camera *c = &again->cameras[i];
        printf("backgrounds_path %s %s\n", c->id,
               c->backgrounds_path ? relative(c->backgrounds_path, again->dir) : "-");
        for (int j = 0; j < c->Nbackground_images; j++) {
            const rs_site_background *bg = &c->background_images[j];
            printf("background %s %s %s %s %d", c->id, bg->name, bg->file, relative(bg->path, again->dir),
                   bg->synthetic);
            for (int t = 0; t < bg->Ntags; t++) printf(" %s=%s", bg->tags[t].key, bg->tags[t].value);
            const char *time = rs_site_background_tag(bg, "time"), *syn = rs_site_background_tag(bg, "synthetic");
            printf(" | time=%s synthetic=%s name=%s nope=%s\n", time ? time : "-", syn,
                   rs_site_background_tag(bg, "name"), rs_site_background_tag(bg, "nope") ? "?" : "-");
        }
    }
    printf("status 0 done\n");
    rs_site_free(site);
    rs_site_free(again);
    return 0;
}
