// rs_synth_dataset_stats.c -- what a dataset holds (synth/dataset/rs_synth_dataset.h,
// rs_synth_dataset_stats): images and labels per split, camera, weather and time of day, the
// labels' visibility, and how many labelled vehicles stand near the junction, read from the
// dataset's own COCO files (the dataset contract, docs/labels.md). Called by the cli
// (`roadside dataset stats`); calls core/, geo/ and cJSON.
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "geo/rs_lanes.h"
#include "geo/rs_site.h"
#include "synth/dataset/internal/rs_synth_dataset_internal.h"
#include "synth/dataset/rs_synth_dataset.h"

rs_status rs_synth_junction_centre(double centre_enu_m[2], const char *site_dir, rs_err *err)
{
    rs_site *site = NULL;
    rs_lanes lanes = {0};
    rs_status st = rs_site_load(&site, site_dir, err);
    char *path = st ? NULL : rs_io_join(site_dir, RS_SITE_LANES);
    if (!st && !path) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) st = rs_lanes_read(&lanes, path, site, err);
    double se = 0, sn = 0;
    long n = 0;
    for (int i = 0; !st && i < lanes.N; i++) {
        const rs_lane *l = &lanes.lane[i];
        if (!l->kind || strcmp(l->kind, "junction") != 0) continue;
        for (int p = 0; p < l->Npoints; p++, n++) {
            se += l->p_enu_m[p][0];
            sn += l->p_enu_m[p][1];
        }
    }
    centre_enu_m[0] = n ? se / (double)n : 0;
    centre_enu_m[1] = n ? sn / (double)n : 0;
    rs_lanes_free(&lanes);
    rs_site_free(site);
    free(path);
    return st;
}

static void count_value(rs_synth_dataset_count *c, int *N, int cap, const char *value)
{
    if (!value) value = "(missing)";
    for (int i = 0; i < *N; i++)
        if (!strcmp(c[i].value, value)) {
            c[i].images++;
            return;
        }
    if (*N == cap) return;
    snprintf(c[*N].value, sizeof(c[*N].value), "%s", value);
    c[(*N)++].images = 1;
}

static const char *string_of(const cJSON *o, const char *key)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsString(v) ? v->valuestring : NULL;
}

static double number_of(const cJSON *o, const char *key)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsNumber(v) ? v->valuedouble : NAN;
}

// DATASET/backgrounds.json into r->looks (rs_synth_dataset__write_looks); nothing when absent.
static rs_status read_looks(rs_synth_dataset_stats_result *r, const char *dataset_dir, rs_err *err)
{
    char *path = rs_io_join(dataset_dir, "backgrounds.json"), *text = NULL;
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = RS_OK;
    if (rs_synth_dataset__file_exists(path) && !(st = rs_io_read_file(&text, NULL, path, err))) {
        cJSON *doc = cJSON_Parse(text);
        const cJSON *list = cJSON_GetObjectItemCaseSensitive(doc, "backgrounds"), *x;
        if (!cJSON_IsArray(list)) st = rs_err_set(err, RS_ERR_PARSE, "%s: no \"backgrounds\" array", path);
        r->looks_found = !st;
        r->looks_applied = !cJSON_IsFalse(cJSON_GetObjectItemCaseSensitive(doc, "applied"));
        const cJSON *entries = st ? NULL : list;
        cJSON_ArrayForEach(x, entries)
        {
            if (r->Nlooks == RS_SYNTH_STATS_MAX) break;
            rs_synth_dataset_look *l = &r->looks[r->Nlooks++];
            // the file (backgrounds/<camera>/...) tells the cameras' same-named twins apart
            const char *name = string_of(x, "file") ? string_of(x, "file") : string_of(x, "background"),
                       *why = string_of(x, "why");
            snprintf(l->background, sizeof(l->background), "%s", name ? name : "(missing)");
            snprintf(l->why, sizeof(l->why), "%s", why ? why : "");
            const cJSON *o = cJSON_GetObjectItemCaseSensitive(x, "look"),
                        *g = cJSON_GetObjectItemCaseSensitive(o, "gain");
            l->ok = cJSON_IsObject(o);
            if (!l->ok) continue;
            l->look.noise_a = number_of(o, "noise_a");
            l->look.noise_b = number_of(o, "noise_b");
            l->look.noise_sigma = number_of(o, "noise_sigma");
            l->look.blur_sigma_px = number_of(o, "blur_sigma_px");
            l->look.jpeg_quality = (int)number_of(o, "jpeg_quality");
            l->look.jpeg_exact = cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(o, "jpeg_exact"));
            l->look.blockiness = number_of(o, "blockiness");
            for (int c = 0; c < 3; c++)
                l->look.gain[c] = cJSON_GetArraySize(g) == 3 ? cJSON_GetArrayItem(g, c)->valuedouble : NAN;
        }
        cJSON_Delete(doc);
    }
    free(text);
    free(path);
    return st;
}

rs_status rs_synth_dataset_stats(rs_synth_dataset_stats_result *r, const char *dataset_dir,
                                 const double centre_enu_m[2], double radius_m, rs_err *err)
{
    memset(r, 0, sizeof(*r));
    char *names[RS_SYNTH_STATS_MAX];
    int Nnames = 0;
    rs_status st = rs_synth_dataset__splits(names, &Nnames, RS_SYNTH_STATS_MAX, dataset_dir, err);
    char *adir = st ? NULL : rs_io_join(dataset_dir, "annotations");
    if (!st && !adir) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int k = 0; !st && k < Nnames; k++) {
        char file[600];
        snprintf(file, sizeof(file), "instances_%s.json", names[k]);
        char *path = rs_io_join(adir, file), *text = NULL;
        if (!path) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            break;
        }
        if (!(st = rs_io_read_file(&text, NULL, path, err))) {
            cJSON *doc = cJSON_Parse(text);
            const cJSON *images = cJSON_GetObjectItemCaseSensitive(doc, "images");
            const cJSON *anns = cJSON_GetObjectItemCaseSensitive(doc, "annotations"), *x;
            if (!cJSON_IsArray(images) || !cJSON_IsArray(anns))
                st = rs_err_set(err, RS_ERR_PARSE, "%s: not a COCO file (images, annotations)", path);
            else {
                rs_synth_dataset_count *sp = &r->splits[r->Nsplits++];
                snprintf(sp->value, sizeof(sp->value), "%s", names[k]);
                sp->images = cJSON_GetArraySize(images);
                sp->labels = cJSON_GetArraySize(anns);
                r->images += sp->images;
                // issue 40: each image's condition by its id (COCO ids run 1..N), for its labels
                const int Nimg = cJSON_GetArraySize(images);
                int *cond_of = calloc((size_t)Nimg + 1, sizeof(int)); // index into conditions + 1
                cJSON_ArrayForEach(x, images)
                {
                    const char *cv = string_of(x, "condition");
                    count_value(r->conditions, &r->Nconditions, RS_SYNTH_STATS_MAX, cv);
                    const cJSON *id = cJSON_GetObjectItemCaseSensitive(x, "id");
                    int ic = -1;
                    for (int q = 0; q < r->Nconditions && ic < 0; q++)
                        if (!strcmp(r->conditions[q].value, cv ? cv : "(missing)")) ic = q;
                    if (cond_of && cJSON_IsNumber(id) && id->valueint >= 1 && id->valueint <= Nimg)
                        cond_of[id->valueint] = ic + 1;
                    count_value(r->cameras, &r->Ncameras, RS_SYNTH_STATS_MAX, string_of(x, "camera"));
                    count_value(r->weather, &r->Nweather, RS_SYNTH_STATS_MAX, string_of(x, "weather"));
                    count_value(r->time_of_day, &r->Ntime_of_day, RS_SYNTH_STATS_MAX, string_of(x, "time_of_day"));
                }
                cJSON_ArrayForEach(x, anns)
                {
                    r->labels++;
                    const cJSON *iid = cJSON_GetObjectItemCaseSensitive(x, "image_id");
                    if (cond_of && cJSON_IsNumber(iid) && iid->valueint >= 1 && iid->valueint <= Nimg &&
                        cond_of[iid->valueint] > 0)
                        r->conditions[cond_of[iid->valueint] - 1].labels++;
                    const cJSON *p = cJSON_GetObjectItemCaseSensitive(x, "bottom_center_enu_m");
                    if (cJSON_IsArray(p) && cJSON_GetArraySize(p) == 3) {
                        const double de_m = cJSON_GetArrayItem(p, 0)->valuedouble - centre_enu_m[0];
                        const double dn_m = cJSON_GetArrayItem(p, 1)->valuedouble - centre_enu_m[1];
                        const double d = hypot(de_m, dn_m);
                        r->labels_located++;
                        r->labels_near += d < radius_m;
                        r->distance_sum_m += d;
                    }
                    const cJSON *v = cJSON_GetObjectItemCaseSensitive(x, "visibility");
                    if (cJSON_IsNumber(v)) {
                        const double vis = v->valuedouble;
                        r->visibility_hist[vis >= 1 ? 9 : vis <= 0 ? 0 : (int)(vis * 10)]++;
                        r->invisible += cJSON_IsNumber(cJSON_GetObjectItemCaseSensitive(x, "visible_pixels")) &&
                                        cJSON_GetObjectItemCaseSensitive(x, "visible_pixels")->valuedouble <= 0;
                    }
                }
                free(cond_of);
            }
            cJSON_Delete(doc);
        }
        free(text);
        free(path);
    }
    for (int k = 0; k < Nnames; k++) free(names[k]);
    free(adir);
    if (!st) st = read_looks(r, dataset_dir, err);
    return st;
}
