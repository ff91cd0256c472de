// rs_synth_dataset.c -- `roadside synth`: the per-image pipeline, shards, resume, merge.
#define _POSIX_C_SOURCE 200809L
#define _XOPEN_SOURCE 700
#include "synth/rs_synth_dataset.h"

#include <errno.h>
#include <dirent.h>
#include <ftw.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cJSON.h>
#include <mrcal/mrcal.h>

#include "core/rs_camera.h"
#include "core/rs_io.h"
#include "geo/rs_site.h"
#include "synth/rs_synth_appearance.h"
#include "synth/rs_synth_labels.h"
#include "synth/rs_synth_render.h"
#include "synth/rs_synth_scene.h"
#include "synth/rs_synth_traffic.h"

void rs_synth_dataset_options_default(rs_synth_dataset_options *opt)
{
    memset(opt, 0, sizeof(*opt));
    opt->count = 1;
    opt->shard_count = 1;
    opt->vehicles = 10;
    opt->split = "train2017";
    opt->shadows = true;
    opt->coarse_below_px = 40;
}

// splitmix64's output function (Steele, Lea, Flood, "Fast splittable pseudorandom number
// generators", OOPSLA 2014).
static uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

uint64_t rs_synth_dataset_image_seed(uint64_t seed, int k)
{
    return mix64(seed + 0x9e3779b97f4a7c15ULL * ((uint64_t)k + 1));
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static bool file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}


// ---- one camera, one background ----

typedef struct {
    char *file;        // owned: absolute/joined path
    char *time_iso;    // owned, may be NULL
    bool overcast;     // conditions cloudy, rain, snow or night: no sun, the sky's soft shadow
    bool night;        // conditions night: no shadow at all
    // cache, filled at first use: the image at the output size, its appearance
    rs_image fitted;
    rs_image linear; // fitted, decoded from sRGB to linear light
    rs_synth_appearance app;
    bool app_ok;       // the appearance could be estimated
} background;

typedef struct {
    const char *id;
    rs_camera cam;  // at the output size
    background *bg;       // (Nbg,) owned: the backgrounds passing the filters
    int Nbg;
    // cache, filled at first use: the POV-Ray canvas of the lens and its resampling map
    bool have_canvas;
    rs_synth_canvas canvas;
    float *canvas_map;    // owned; NULL when the canvas is the lens itself
} camera;

static const char *tag_value(const cJSON *entry, const char *key)
{
    const cJSON *tags = cJSON_GetObjectItemCaseSensitive(entry, "tags");
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(tags, key);
    if (cJSON_IsString(v))
        return v->valuestring;
    if (cJSON_IsBool(v))
        return cJSON_IsTrue(v) ? "true" : "false";
    v = cJSON_GetObjectItemCaseSensitive(entry, key); // "synthetic", "name"
    if (cJSON_IsString(v))
        return v->valuestring;
    if (cJSON_IsBool(v))
        return cJSON_IsTrue(v) ? "true" : "false";
    return NULL;
}

// The camera's backgrounds from site.json passing the filters.
static rs_status read_backgrounds(camera *c, const char *site_dir, const cJSON *site_json,
                                  const rs_synth_dataset_options *opt, rs_err *err)
{
    const cJSON *cams = cJSON_GetObjectItemCaseSensitive(site_json, "cameras"), *cj;
    cJSON_ArrayForEach(cj, cams)
    {
        const cJSON *id = cJSON_GetObjectItemCaseSensitive(cj, "id");
        if (!cJSON_IsString(id) || strcmp(id->valuestring, c->id) != 0)
            continue;
        const cJSON *list = cJSON_GetObjectItemCaseSensitive(cj, "background_images"), *e;
        int n = cJSON_GetArraySize(list), i = 0;
        c->bg = calloc((size_t)(n > 0 ? n : 1), sizeof(background));
        if (!c->bg)
            return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        cJSON_ArrayForEach(e, list)
        {
            i++;
            const cJSON *file = cJSON_GetObjectItemCaseSensitive(e, "file");
            if (!cJSON_IsString(file))
                return rs_err_set(err, RS_ERR_PARSE,
                                  "%s/site.json: cameras[id %s].background_images[%d].file: "
                                  "not a string", site_dir, c->id, i - 1);
            bool keep = true;
            for (int f = 0; f < opt->Nfilters && keep; f++) {
                const char *v = tag_value(e, opt->filter_keys[f]);
                keep = v && strcmp(v, opt->filter_values[f]) == 0;
            }
            if (!keep)
                continue;
            background *b = &c->bg[c->Nbg++];
            b->file = rs_io_join(site_dir, file->valuestring);
            const char *t = tag_value(e, "time");
            b->time_iso = t ? strdup(t) : NULL;
            const char *cond = tag_value(e, "conditions");
            b->overcast = cond && strcmp(cond, "sunny") != 0;
            b->night = cond && strcmp(cond, "night") == 0;
            if (!b->file || (t && !b->time_iso))
                return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        }
    }
    return RS_OK;
}

// Scales a camera to width x height: fx, fy, cx, cy with the pixel-centre origin
// (c' = (c + 0.5) s - 0.5); distortion untouched (it acts on normalised coordinates).
static rs_status scale_camera(rs_camera *cam, int width, int height, const char *id,
                              rs_err *err)
{
    if (width <= 0 || (width == cam->width && height == cam->height))
        return RS_OK;
    mrcal_lensmodel_metadata_t meta = mrcal_lensmodel_metadata(&cam->lensmodel);
    if (!meta.has_core)
        return rs_err_set(err, RS_ERR_UNSUPPORTED, "camera %s: --size: lens model without "
                          "fx, fy, cx, cy cannot be scaled", id);
    const double sx = (double)width / cam->width, sy = (double)height / cam->height;
    if (fabs(sx / sy - 1) > 0.01)
        return rs_err_set(err, RS_ERR_INVALID, "camera %s: --size %dx%d: aspect differs from "
                          "the camera's %dx%d by more than 1 %%", id, width, height, cam->width,
                          cam->height);
    cam->intrinsics[0] *= sx;
    cam->intrinsics[1] *= sy;
    cam->intrinsics[2] = (cam->intrinsics[2] + 0.5) * sx - 0.5;
    cam->intrinsics[3] = (cam->intrinsics[3] + 0.5) * sy - 0.5;
    cam->width = width;
    cam->height = height;
    return RS_OK;
}

// The background at the camera's size (linear resampling when it differs) and its appearance
// (rs_synth_appearance_estimate on the original file: noise, blur, JPEG quality are the
// camera's), computed at first use and kept.
static rs_status background_fit(background *b, int width, int height, rs_err *err)
{
    if (b->fitted.data)
        return RS_OK;
    rs_image src = {0};
    float *map = NULL;
    rs_status st = rs_image_read(&src, b->file, err);
    if (st)
        return st;
    if (src.channels < 3) {
        st = rs_err_set(err, RS_ERR_INVALID, "%s: not an RGB image", b->file);
        goto done;
    }
    map = malloc(sizeof(float) * 2 * (size_t)width * (size_t)height);
    if (!map) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    const double sx = (double)src.width / width, sy = (double)src.height / height;
    for (int v = 0; v < height; v++)
        for (int u = 0; u < width; u++) {
            map[2 * ((size_t)v * width + u) + 0] = (float)((u + 0.5) * sx - 0.5);
            map[2 * ((size_t)v * width + u) + 1] = (float)((v + 0.5) * sy - 0.5);
        }
    if ((st = rs_synth_remap(&b->fitted, &src, map, width, height, 1, err)) ||
        (st = rs_image_alloc(&b->linear, width, height, 3, err)))
        goto done;
    for (size_t i = 0; i < (size_t)width * height; i++)
        for (int c = 0; c < 3; c++)
            b->linear.data[3 * i + c] =
                (float)rs_synth_srgb_decode(b->fitted.data[(size_t)b->fitted.channels * i + c]);
    b->app_ok = rs_synth_appearance_estimate(&b->app, b->file, NULL, NULL) == RS_OK;
done:
    free(map);
    rs_image_free(&src);
    return st;
}

typedef struct {
    const rs_synth_dataset_options *opt;
    rs_site *site;
    rs_lanes lanes;
    camera *cams;
    int Ncams;
    char *split_dir, *parts_dir, *work_root;
} dataset;

// ---- shadows and appearance over a background ----

// Differential rendering (Debevec, "Rendering synthetic objects into real scenes", SIGGRAPH
// 1998): the ground with the vehicles and the ground alone, under the same sun and sky; their
// ratio is the render's shadow pass (rs_synth_render_result.shadow: the ground alone, lit by
// parallel lights, is uniform and needs no pass). On background pixels (id 0) the background
// in linear light is multiplied by it (in [0, 1]: only shadows, no added light).
static void shade_background(rs_image *bg_lin, const float *shadow, const uint16_t *ids)
{
    const size_t n = (size_t)bg_lin->width * (size_t)bg_lin->height;
    for (size_t i = 0; i < n; i++) {
        if (ids[i] != 0 || shadow[i] >= 1)
            continue;
        for (int c = 0; c < 3; c++)
            bg_lin->data[3 * i + c] *= shadow[i];
    }
}

// The composite over a background: shadows (when given), the vehicle layer matched to the
// background (rs_synth_appearance.h; skipped when the background gives no estimate), straight
// alpha over the background in linear light, sRGB, the background's JPEG quality.
// in,out: r (its composite replaced); in: shadow passes may be NULL
static rs_status composite(rs_synth_render_result *r, const background *b, uint64_t seed,
                           rs_err *err)
{
    const rs_synth_appearance app = b->app;
    const bool matched = b->app_ok;
    rs_status st = RS_OK;
    const size_t n = (size_t)r->width * (size_t)r->height;
    rs_image lin = {0};
    if ((st = rs_image_alloc(&lin, r->width, r->height, 3, err)))
        goto done;
    memcpy(lin.data, b->linear.data, sizeof(float) * 3 * n);
    if (r->shadow)
        shade_background(&lin, r->shadow, r->ids);
    if (matched && (st = rs_synth_appearance_apply(&r->rgba, &app, 0.6, seed, err))) {
        rs_image_free(&lin);
        goto done;
    }
    for (size_t i = 0; i < n; i++) {
        const double a = r->rgba.data[4 * i + 3];
        for (int c = 0; c < 3; c++) {
            const double v = a * r->rgba.data[4 * i + c] + (1 - a) * lin.data[3 * i + c];
            r->composite.data[3 * i + c] =
                (float)rs_synth_srgb_encode(v < 0 ? 0 : v > 1 ? 1 : v);
        }
    }
    rs_image_free(&lin);
    if (matched)
        st = rs_synth_appearance_jpeg(&r->composite, &app, err);
done:
    return st;
}

// ---- the random stream of one image ----

static uint64_t rng_next(uint64_t *s)
{
    *s += 0x9e3779b97f4a7c15ULL;
    return mix64(*s);
}

// ---- one image ----


static void stem_of(char *stem, size_t n, int k, const char *camera_id)
{
    snprintf(stem, n, "%06d_%s", k, camera_id);
    for (char *p = stem; *p; p++)
        if (!((*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') ||
              *p == '_' || *p == '-'))
            *p = '_';
}

static rs_status make_image(dataset *d, int k, const char *stem, camera *c, bool *grey,
                            double *seconds_povray, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    uint64_t rng = rs_synth_dataset_image_seed(opt->seed, k);
    char name[600];
    char *work = NULL, *part_tmp = NULL, *part = NULL, *image = NULL;
    rs_synth_traffic_vehicle *tv = NULL;
    rs_synth_vehicle *v = NULL;
    rs_synth_prepared prepared = {0};
    rs_synth_render_result r = {0};
    const background *b = NULL;
    rs_synth_label *labels = NULL;
    double *up = NULL;
    rs_synth_mesh *meshes = NULL;
    const char **ids = NULL;
    uint8_t *coarse = NULL; // (N,) vehicle i gets the coarse mesh
    int N = 0;
    rs_status st;

    work = rs_io_join(d->work_root, stem);
    if (!work)
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_io_remove_tree(work); // a previous, interrupted attempt
    if ((st = rs_io_mkdir_p(work, err)))
        goto done;

    rs_synth_render_options ropt;
    rs_synth_render_options_default(&ropt);
    ropt.povray = opt->povray;
    ropt.write_files = false; // the dataset composites and writes the image itself
    if (!c->have_canvas) {
        const rs_camera *cc = &c->cam;
        if ((st = rs_synth_canvas_for_lens(&c->canvas, &cc->lensmodel, cc->intrinsics, cc->width,
                                           cc->height, 1, err)) ||
            (!c->canvas.identity &&
             (st = rs_synth_canvas_map(&c->canvas_map, &c->canvas, &cc->lensmodel,
                                       cc->intrinsics, cc->width, cc->height, err))))
            goto done;
        c->have_canvas = true;
    }
    ropt.canvas = &c->canvas;
    ropt.canvas_map = c->canvas_map;
    ropt.separate_processes = opt->separate_processes;
    ropt.full_frame = opt->full_frame;
    const uint64_t r_bg = rng_next(&rng);
    if (c->Nbg > 0) {
        background *bm = &c->bg[r_bg % (uint64_t)c->Nbg];
        b = bm;
        if ((st = background_fit(bm, c->cam.width, c->cam.height, err)))
            goto done;
        // the vehicles alone over transparency; composite() puts them onto the background
        ropt.scene.ground_visible = false;
        ropt.scene.overcast = b->overcast;
        ropt.shadow = opt->shadows && !b->night;
        double t_s;
        if (b->time_iso && rs_synth_parse_iso8601(&t_s, b->time_iso, "time", NULL) == RS_OK)
            rs_synth_sun_position(&ropt.scene.sun_azimuth_deg, &ropt.scene.sun_elevation_deg,
                                  d->site->origin.lat_deg, d->site->origin.lon_deg, t_s);
        *grey = false;
    } else {
        ropt.scene.ground_visible = true; // neutral grey ground rendered by POV-Ray
        *grey = true;
    }

    rs_synth_traffic_options topt;
    rs_synth_traffic_options_default(&topt);
    topt.seed = rng_next(&rng);
    topt.count = 0; // every vehicle that fits; the camera's view picks among them below
    if ((st = rs_synth_traffic_place(&tv, &N, &d->lanes, &topt, err)))
        goto done;
    rs_synth_randomise_options xopt;
    rs_synth_randomise_options_default(&xopt);
    xopt.seed = rng_next(&rng);
    if ((st = rs_synth_traffic_randomise(tv, &N, &xopt, err)))
        goto done;
    const size_t n = (size_t)(N > 0 ? N : 1);
    v = calloc(n, sizeof(*v));
    up = malloc(n * sizeof(double));
    meshes = malloc(n * sizeof(rs_synth_mesh));
    ids = malloc(n * sizeof(char *));
    coarse = calloc(n, 1);
    if (!v || !up || !meshes || !ids || !coarse) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    // The vehicles the camera sees (their box meets the image), at most opt->vehicles of them,
    // a uniformly drawn subset kept in placement order: the traffic of the whole site would
    // leave most images nearly empty.
    int Nseen = 0;
    for (int i = 0; i < N; i++) {
        const rs_synth_vehicle vi = {.cls = tv[i].cls, .id = tv[i].id, .e_m = tv[i].e_m,
                                     .n_m = tv[i].n_m, .yaw_deg = tv[i].yaw_deg,
                                     .length_m = tv[i].length_m, .width_m = tv[i].width_m,
                                     .height_m = tv[i].height_m, .rgb = {-1, -1, -1},
                                     .variant = tv[i].variant};
        double corners[8][3];
        int rect[4];
        rs_synth_vehicle_corners_enu(corners, &vi, d->site->ground_normal_enu,
                                     d->site->ground_offset_m);
        if (rs_synth_vehicle_rect(rect, c->canvas.fxycxy, c->canvas.width, c->canvas.height,
                                  c->cam.rt_cam_enu, (const double(*)[3])corners, 0.05)) {
            coarse[Nseen] = rect[3] - rect[1] + 1 < opt->coarse_below_px;
            v[Nseen++] = vi;
        }
    }
    const uint64_t r_pick = rng_next(&rng);
    if (Nseen > opt->vehicles) {
        // selection sampling (Knuth, TAOCP vol. 2, Algorithm S): keep each with probability
        // (still needed) / (still left), in order
        uint64_t s_pick = r_pick;
        int kept = 0;
        for (int i = 0; i < Nseen && kept < opt->vehicles; i++) {
            const double u01 = (double)(rng_next(&s_pick) >> 11) * 0x1.0p-53;
            if (u01 * (Nseen - i) < opt->vehicles - kept) {
                coarse[kept] = coarse[i];
                v[kept++] = v[i];
            }
        }
        Nseen = kept;
    }
    N = Nseen;
    for (int i = 0; i < N; i++)
        ids[i] = v[i].id;
    if ((st = rs_synth_prepare_lod(&prepared, v, NULL, N, coarse, err)))
        goto done;
    const rs_camera *cam = &c->cam;
    if ((st = rs_synth_render(&r, work, &cam->lensmodel, cam->intrinsics, cam->width, cam->height,
                              cam->rt_cam_enu, d->site->ground_normal_enu,
                              d->site->ground_offset_m, &prepared, &ropt, err)))
        goto done;
    *seconds_povray += r.seconds_povray;
    const uint64_t r_look = rng_next(&rng);
    if (b && (st = composite(&r, b, r_look, err)))
        goto done;
    for (int i = 0; i < N; i++) {
        up[i] = rs_synth_ground_up_m(d->site->ground_normal_enu, d->site->ground_offset_m,
                                     prepared.v[i].e_m, prepared.v[i].n_m);
        meshes[i] = prepared.meshes[prepared.imesh[i]];
    }
    if ((st = rs_synth_labels_compute(&labels, cam, prepared.v, up, N, meshes, r.ids, err)))
        goto done;
    char file_name[320];
    snprintf(file_name, sizeof(file_name), "%s.png", stem);
    const rs_synth_label_image img = {.file_name = file_name, .width = r.width, .height = r.height,
                                      .labels = labels, .Nlabels = N, .vehicle_ids = ids};
    const rs_synth_label_options lopt = {.bbox = RS_SYNTH_BBOX_FOOTPRINT, .min_visibility = 0};
    // YOLO, KITTI and the image, then the per-image COCO file last: it marks the image done.
    image = rs_io_join(d->split_dir, file_name);
    snprintf(name, sizeof(name), "annotations/instances_%s.json", opt->split);
    part_tmp = rs_io_join(work, name);
    snprintf(name, sizeof(name), "%s.json", stem);
    part = rs_io_join(d->parts_dir, name);
    if (!image || !part_tmp || !part) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    if ((st = rs_synth_labels_write_yolo(opt->out_dir, opt->split, &img, 1, &lopt, err)) ||
        (st = rs_synth_labels_write_kitti(opt->out_dir, &img, 1, &lopt, err)) ||
        (st = rs_image_write(image, &r.composite, 8, err)) ||
        (st = rs_synth_labels_write_coco(work, opt->split, &img, 1, &lopt, err)))
        goto done;
    if (rename(part_tmp, part) != 0) {
        st = rs_err_set(err, RS_ERR_IO, "%s: %s", part, strerror(errno));
        goto done;
    }
    rs_io_remove_tree(work);
done:
    free(work);
    free(part_tmp);
    free(part);
    free(image);
    free(tv);
    free(v);
    free(up);
    free(meshes);
    free(ids);
    free(coarse);
    free(labels);
    rs_synth_prepared_free(&prepared);
    rs_synth_render_result_free(&r);
    return st;
}

// ---- COCO assembly (run and merge) ----

typedef struct {
    const char *file_name; // borrowed from image
    cJSON *image;          // owned
    cJSON *anns;           // owned array
} coco_entry;

typedef struct {
    coco_entry *e;
    int N, cap;
    cJSON *categories; // owned, from the first document
} coco_acc;

static void coco_acc_free(coco_acc *a)
{
    for (int i = 0; i < a->N; i++) {
        cJSON_Delete(a->e[i].image);
        cJSON_Delete(a->e[i].anns);
    }
    free(a->e);
    cJSON_Delete(a->categories);
    memset(a, 0, sizeof(*a));
}

// Adds the images (with their annotations) of a COCO file to the accumulator.
static rs_status coco_add_file(coco_acc *a, const char *path, rs_err *err)
{
    char *text = NULL;
    rs_status st = rs_io_read_file(&text, NULL, path, err);
    if (st)
        return st;
    cJSON *doc = cJSON_Parse(text);
    free(text);
    const cJSON *images = cJSON_GetObjectItemCaseSensitive(doc, "images");
    const cJSON *anns = cJSON_GetObjectItemCaseSensitive(doc, "annotations"), *im, *an;
    if (!cJSON_IsArray(images) || !cJSON_IsArray(anns)) {
        cJSON_Delete(doc);
        return rs_err_set(err, RS_ERR_PARSE, "%s: not a COCO file (images, annotations)", path);
    }
    if (!a->categories)
        a->categories = cJSON_Duplicate(cJSON_GetObjectItemCaseSensitive(doc, "categories"), 1);
    cJSON_ArrayForEach(im, images)
    {
        const cJSON *id = cJSON_GetObjectItemCaseSensitive(im, "id");
        const cJSON *fn = cJSON_GetObjectItemCaseSensitive(im, "file_name");
        if (!cJSON_IsNumber(id) || !cJSON_IsString(fn)) {
            cJSON_Delete(doc);
            return rs_err_set(err, RS_ERR_PARSE, "%s: images[]: id or file_name missing", path);
        }
        if (a->N == a->cap) {
            int cap = a->cap ? 2 * a->cap : 64;
            coco_entry *e = realloc(a->e, (size_t)cap * sizeof(*e));
            if (!e) {
                cJSON_Delete(doc);
                return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            }
            a->e = e;
            a->cap = cap;
        }
        coco_entry *e = &a->e[a->N++];
        e->image = cJSON_Duplicate(im, 1);
        e->anns = cJSON_CreateArray();
        e->file_name = cJSON_GetObjectItemCaseSensitive(e->image, "file_name")->valuestring;
        cJSON_ArrayForEach(an, anns)
        {
            const cJSON *iid = cJSON_GetObjectItemCaseSensitive(an, "image_id");
            if (cJSON_IsNumber(iid) && iid->valuedouble == id->valuedouble)
                cJSON_AddItemToArray(e->anns, cJSON_Duplicate(an, 1));
        }
    }
    cJSON_Delete(doc);
    return RS_OK;
}

static int entry_cmp(const void *a, const void *b)
{
    return strcmp(((const coco_entry *)a)->file_name, ((const coco_entry *)b)->file_name);
}

// Sorts by file name, drops repeated names, renumbers, writes `path`. *Nimages, *Nanns out.
static rs_status coco_write(coco_acc *a, const char *path, int *Nimages, int *Nanns, rs_err *err)
{
    qsort(a->e, (size_t)a->N, sizeof(coco_entry), entry_cmp);
    cJSON *doc = cJSON_CreateObject();
    cJSON *images = cJSON_AddArrayToObject(doc, "images");
    cJSON *anns = cJSON_AddArrayToObject(doc, "annotations");
    cJSON_AddItemToObject(doc, "categories",
                          a->categories ? cJSON_Duplicate(a->categories, 1) : cJSON_CreateArray());
    int ni = 0, na = 0;
    for (int i = 0; i < a->N; i++) {
        if (i > 0 && strcmp(a->e[i].file_name, a->e[i - 1].file_name) == 0)
            continue;
        ni++;
        cJSON *im = cJSON_Duplicate(a->e[i].image, 1);
        cJSON_ReplaceItemInObjectCaseSensitive(im, "id", cJSON_CreateNumber(ni));
        cJSON_AddItemToArray(images, im);
        cJSON *an;
        cJSON_ArrayForEach(an, a->e[i].anns)
        {
            cJSON *x = cJSON_Duplicate(an, 1);
            cJSON_ReplaceItemInObjectCaseSensitive(x, "id", cJSON_CreateNumber(++na));
            cJSON_ReplaceItemInObjectCaseSensitive(x, "image_id", cJSON_CreateNumber(ni));
            cJSON_AddItemToArray(anns, x);
        }
    }
    char *text = cJSON_Print(doc);
    cJSON_Delete(doc);
    if (!text)
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = rs_io_write_file(path, text, strlen(text), err);
    free(text);
    if (Nimages)
        *Nimages += ni;
    if (Nanns)
        *Nanns += na;
    return st;
}

// ---- run ----

static void dataset_free(dataset *d)
{
    for (int i = 0; i < d->Ncams; i++) {
        rs_camera_free(&d->cams[i].cam);
        for (int b = 0; b < d->cams[i].Nbg; b++) {
            free(d->cams[i].bg[b].file);
            free(d->cams[i].bg[b].time_iso);
            rs_image_free(&d->cams[i].bg[b].fitted);
            rs_image_free(&d->cams[i].bg[b].linear);
        }
        free(d->cams[i].bg);
        free(d->cams[i].canvas_map);
    }
    free(d->cams);
    rs_lanes_free(&d->lanes);
    rs_site_free(d->site);
    free(d->split_dir);
    free(d->parts_dir);
    free(d->work_root);
}

static rs_status dataset_load(dataset *d, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    rs_status st;
    char *text = NULL, *path = NULL;
    cJSON *site_json = NULL;
    if ((st = rs_site_load(&d->site, opt->site_dir, err)))
        return st;
    path = rs_io_join(opt->site_dir, "lanes.geojson");
    if (!path)
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!file_exists(path)) {
        st = rs_err_set(err, RS_ERR_INVALID, "%s: missing: the built-in traffic needs the site's "
                        "lanes (docs/traffic.md)", path);
        goto done;
    }
    if ((st = rs_lanes_read(&d->lanes, path, d->site, err)))
        goto done;
    free(path);
    path = rs_io_join(opt->site_dir, "site.json");
    if (!path || (st = rs_io_read_file(&text, NULL, path, err)))
        goto done;
    site_json = cJSON_Parse(text);
    const int Nc = opt->Ncameras > 0 ? opt->Ncameras : d->site->Ncameras;
    d->cams = calloc((size_t)(Nc > 0 ? Nc : 1), sizeof(camera));
    if (!d->cams) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    for (int i = 0; i < Nc; i++) {
        const char *id = opt->Ncameras > 0 ? opt->cameras[i] : d->site->cameras[i].id;
        if (rs_site_find_camera(d->site, id) < 0) {
            st = rs_err_set(err, RS_ERR_USAGE, "--camera: no camera \"%s\" in %s", id,
                            opt->site_dir);
            goto done;
        }
        camera *c = &d->cams[d->Ncams++];
        c->id = id;
        char name[512];
        snprintf(name, sizeof(name), "%s.cameramodel", id);
        free(path);
        path = rs_io_join(opt->calib_dir, name);
        if (!path) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            goto done;
        }
        if ((st = rs_camera_read(&c->cam, NULL, path, err)) ||
            (st = scale_camera(&c->cam, opt->width, opt->height, id, err)) ||
            (st = read_backgrounds(c, opt->site_dir, site_json, opt, err)))
            goto done;
    }
    if (d->Ncams == 0)
        st = rs_err_set(err, RS_ERR_INVALID, "%s: no camera", opt->site_dir);
done:
    free(path);
    free(text);
    cJSON_Delete(site_json);
    return st;
}

// Assembles DATASET/annotations/instances_<split>.json from every parts/ file.
static rs_status assemble(const dataset *d, int *Nanns, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    coco_acc a = {0};
    rs_status st = RS_OK;
    char name[600], *path = NULL;
    for (int k = 0; k < opt->count && !st; k++) {
        char stem[300];
        stem_of(stem, sizeof(stem), k, d->cams[k % d->Ncams].id);
        snprintf(name, sizeof(name), "%s.json", stem);
        char *part = rs_io_join(d->parts_dir, name);
        if (!part)
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        else if (file_exists(part))
            st = coco_add_file(&a, part, err);
        free(part);
    }
    snprintf(name, sizeof(name), "annotations/instances_%s.json", opt->split);
    if (!st && !(path = rs_io_join(opt->out_dir, name)))
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st)
        st = coco_write(&a, path, NULL, Nanns, err);
    free(path);
    coco_acc_free(&a);
    return st;
}

// ---- the images of a shard: in this process, or in forked workers ----

// What a worker tells the parent after each image, in one write (atomic: < PIPE_BUF).
typedef struct {
    char kind;              // 'm' made, 'g' made over the grey ground, 's' skipped, 'e' error
    int status;             // rs_status of an error
    double seconds_povray;  // of this image
    char msg[400];          // an error's message
} worker_report;

// Makes the images at positions j, j + J, .. of the shard. With fd >= 0 (a worker) each image
// is reported through fd, else counted in *sum with the progress callback called.
static rs_status run_images(dataset *d, rs_synth_dataset_summary *sum, int j, int J, int fd,
                            rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    rs_status st = RS_OK;
    char name[400];
    int pos = 0;
    for (int k = opt->shard_index; k < opt->count && !st; k += opt->shard_count, pos++) {
        if (pos % J != j)
            continue;
        camera *c = &d->cams[k % d->Ncams];
        char stem[300];
        stem_of(stem, sizeof(stem), k, c->id);
        snprintf(name, sizeof(name), "%s.json", stem);
        char *part = rs_io_join(d->parts_dir, name);
        if (!part) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            break;
        }
        worker_report rep = {.kind = 's'};
        if (!file_exists(part)) {
            bool grey = false;
            st = make_image(d, k, stem, c, &grey, &rep.seconds_povray, err);
            rep.kind = st ? 'e' : grey ? 'g' : 'm';
        }
        free(part);
        if (fd >= 0) {
            if (st) {
                rep.status = st;
                snprintf(rep.msg, sizeof(rep.msg), "%.399s", err ? err->msg : "");
            }
            if (write(fd, &rep, sizeof(rep)) != (ssize_t)sizeof(rep))
                return RS_ERR_IO; // the parent is gone
            continue;
        }
        if (st)
            break;
        sum->Nskipped += rep.kind == 's';
        sum->Nmade += rep.kind != 's';
        sum->Ngrey += rep.kind == 'g';
        sum->seconds_povray += rep.seconds_povray;
        if (opt->progress)
            opt->progress(opt->progress_ctx, sum->Nmade + sum->Nskipped, sum->Nimages,
                          sum->Nskipped);
    }
    return st;
}

// opt->jobs forked workers, each running run_images on its share and reporting through a
// pipe; the parent counts, calls the progress callback, and returns the first error (the
// other workers go on to the end of their share: finished images are kept either way).
static rs_status run_workers(dataset *d, rs_synth_dataset_summary *sum, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    const int J = opt->jobs < sum->Nimages ? opt->jobs : sum->Nimages;
    int fds[2];
    if (pipe(fds) != 0)
        return rs_err_set(err, RS_ERR_IO, "synth: pipe: %s", strerror(errno));
    pid_t *pids = calloc((size_t)J, sizeof(pid_t));
    if (!pids) {
        close(fds[0]);
        close(fds[1]);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    rs_status st = RS_OK;
    int started = 0;
    fflush(NULL);
    const pid_t parent = getpid();
    for (int j = 0; j < J; j++, started++) {
        pids[j] = fork();
        if (pids[j] < 0) {
            st = rs_err_set(err, RS_ERR_IO, "synth: fork: %s", strerror(errno));
            break;
        }
        if (pids[j] == 0) {
            // a worker dies with the parent: a killed `roadside synth` leaves nothing running
            // that could race a rerun on the same images
            if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != parent)
                _exit(1);
            close(fds[0]);
            rs_err e = {RS_OK, ""};
            const rs_status ws = run_images(d, sum, j, J, fds[1], &e);
            _exit(ws ? 1 : 0);
        }
    }
    close(fds[1]);
    worker_report rep;
    bool failed = false;
    while (read(fds[0], &rep, sizeof(rep)) == (ssize_t)sizeof(rep)) {
        if (rep.kind == 'e') {
            if (!failed) {
                rep.msg[sizeof(rep.msg) - 1] = 0;
                st = rs_err_set(err, (rs_status)rep.status, "%s", rep.msg);
                failed = true; // the other workers finish their share (resumable work)
            }
            continue;
        }
        sum->Nskipped += rep.kind == 's';
        sum->Nmade += rep.kind != 's';
        sum->Ngrey += rep.kind == 'g';
        sum->seconds_povray += rep.seconds_povray;
        if (!failed && opt->progress)
            opt->progress(opt->progress_ctx, sum->Nmade + sum->Nskipped, sum->Nimages,
                          sum->Nskipped);
    }
    close(fds[0]);
    for (int j = 0; j < started; j++) {
        int ws = 0;
        while (waitpid(pids[j], &ws, 0) < 0 && errno == EINTR) {}
        if (!st && !(WIFEXITED(ws) && WEXITSTATUS(ws) == 0))
            st = rs_err_set(err, RS_ERR_EXTERNAL, "synth: worker %d of %d ended with %s %d", j,
                            J, WIFSIGNALED(ws) ? "signal" : "status",
                            WIFSIGNALED(ws) ? WTERMSIG(ws) : WEXITSTATUS(ws));
    }
    free(pids);
    return st;
}

rs_status rs_synth_dataset_run(rs_synth_dataset_summary *summary,
                               const rs_synth_dataset_options *opt, rs_err *err)
{
    rs_synth_dataset_summary sum = {0};
    const double t0 = now_s();
    if (!opt || !opt->site_dir || !opt->calib_dir || !opt->out_dir || opt->count < 1 ||
        opt->shard_count < 1 || opt->shard_index < 0 || opt->shard_index >= opt->shard_count ||
        opt->vehicles < 0 || !opt->split)
        return rs_err_set(err, RS_ERR_INVALID, "synth: bad options (count >= 1, shard I/N with "
                          "0 <= I < N, site, calib and output folders required)");
    dataset d = {.opt = opt};
    char name[600];
    rs_status st = dataset_load(&d, err);
    if (st)
        goto done;
    snprintf(name, sizeof(name), "labels/%s", opt->split);
    d.split_dir = rs_io_join(opt->out_dir, opt->split);
    d.parts_dir = rs_io_join(opt->out_dir, "parts");
    d.work_root = rs_io_join(opt->out_dir, "work");
    char *labels_dir = rs_io_join(opt->out_dir, name);
    char *annot_dir = rs_io_join(opt->out_dir, "annotations");
    char *kitti_dir = rs_io_join(opt->out_dir, "label_2");
    if (!d.split_dir || !d.parts_dir || !d.work_root || !labels_dir || !annot_dir || !kitti_dir)
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    else if (!(st = rs_io_mkdir_p(d.split_dir, err)) && !(st = rs_io_mkdir_p(d.parts_dir, err)) &&
             !(st = rs_io_mkdir_p(labels_dir, err)) && !(st = rs_io_mkdir_p(annot_dir, err)))
        st = rs_io_mkdir_p(kitti_dir, err);
    free(labels_dir);
    free(annot_dir);
    free(kitti_dir);
    if (st)
        goto done;
    for (int k = opt->shard_index; k < opt->count; k += opt->shard_count)
        sum.Nimages++;
    st = opt->jobs > 1 && sum.Nimages > 1 ? run_workers(&d, &sum, err)
                                          : run_images(&d, &sum, 0, 1, -1, err);
    if (!st) {
        st = assemble(&d, &sum.Nannotations, err);
        rmdir(d.work_root); // empty when every image finished
    }
done:
    dataset_free(&d);
    sum.seconds = now_s() - t0;
    if (summary)
        *summary = sum;
    return st;
}

// ---- merge ----

// Hard-links src to dst (a copy when linking fails), unless dst exists.
static rs_status link_or_copy(const char *src, const char *dst, rs_err *err)
{
    if (file_exists(dst) || link(src, dst) == 0)
        return RS_OK;
    char *data = NULL;
    size_t len = 0;
    rs_status st = rs_io_read_file(&data, &len, src, err);
    if (!st)
        st = rs_io_write_file(dst, data, len, err);
    free(data);
    return st;
}

// Links DIR/<sub>/<stem><ext> of an input into OUT when it exists.
static rs_status link_sidecar(const char *in_dir, const char *out_dir, const char *sub,
                              const char *file_name, const char *ext, rs_err *err)
{
    char rel[1200];
    const char *dot = strrchr(file_name, '.');
    const int stem_len = dot ? (int)(dot - file_name) : (int)strlen(file_name);
    snprintf(rel, sizeof(rel), "%s/%.*s%s", sub, stem_len, file_name, ext);
    char *src = rs_io_join(in_dir, rel), *dst = rs_io_join(out_dir, rel);
    char *folder = rs_io_join(out_dir, sub);
    rs_status st = RS_OK;
    if (!src || !dst || !folder)
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    else if (file_exists(src) && !(st = rs_io_mkdir_p(folder, err)))
        st = link_or_copy(src, dst, err);
    free(src);
    free(dst);
    free(folder);
    return st;
}

// Adds the <split> of every instances_<split>.json in `adir` not yet in splits.
static rs_status list_splits(const char *adir, char ***splits, int *Nsplits, rs_err *err)
{
    DIR *dir = opendir(adir);
    if (!dir)
        return rs_err_set(err, RS_ERR_IO, "%s: %s (not a dataset?)", adir, strerror(errno));
    struct dirent *de;
    rs_status st = RS_OK;
    while (!st && (de = readdir(dir))) {
        const char *n = de->d_name;
        const size_t len = strlen(n);
        if (strncmp(n, "instances_", 10) != 0 || len <= 15 || strcmp(n + len - 5, ".json") != 0)
            continue;
        char split[256];
        snprintf(split, sizeof(split), "%.*s", (int)(len - 15), n + 10);
        bool have = false;
        for (int s = 0; s < *Nsplits; s++)
            have = have || strcmp((*splits)[s], split) == 0;
        if (have)
            continue;
        char **grown = realloc(*splits, (size_t)(*Nsplits + 1) * sizeof(char *));
        if (!grown || !(grown[*Nsplits] = strdup(split))) {
            if (grown)
                *splits = grown;
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            break;
        }
        *splits = grown;
        (*Nsplits)++;
    }
    closedir(dir);
    return st;
}

rs_status rs_synth_dataset_merge(int *Nimages, int *Nannotations, const char *out_dir,
                                 const char *const *inputs, int Ninputs, rs_err *err)
{
    if (Nimages)
        *Nimages = 0;
    if (Nannotations)
        *Nannotations = 0;
    if (!out_dir || Ninputs < 1)
        return rs_err_set(err, RS_ERR_INVALID, "merge: an output and at least one input needed");
    // The splits: every annotations/instances_<split>.json of every input.
    char **splits = NULL;
    int Nsplits = 0;
    rs_status st = RS_OK;
    for (int i = 0; i < Ninputs && !st; i++) {
        char *adir = rs_io_join(inputs[i], "annotations");
        if (!adir)
            return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        rs_status s2 = list_splits(adir, &splits, &Nsplits, err);
        free(adir);
        st = s2;
    }
    for (int s = 0; s < Nsplits && !st; s++) {
        coco_acc a = {0};
        char rel[600];
        snprintf(rel, sizeof(rel), "annotations/instances_%s.json", splits[s]);
        for (int i = 0; i < Ninputs && !st; i++) {
            char *path = rs_io_join(inputs[i], rel);
            if (!path)
                st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            else if (file_exists(path)) {
                const int before = a.N;
                st = coco_add_file(&a, path, err);
                for (int e = before; e < a.N && !st; e++) {
                    char fr[900];
                    snprintf(fr, sizeof(fr), "%s/%s", splits[s], a.e[e].file_name);
                    char *src = rs_io_join(inputs[i], fr), *dst = rs_io_join(out_dir, fr);
                    char *folder = rs_io_join(out_dir, splits[s]);
                    if (!src || !dst || !folder)
                        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
                    else if (!file_exists(src))
                        st = rs_err_set(err, RS_ERR_NOT_FOUND, "%s: listed in %s but missing",
                                        src, path);
                    else if (!(st = rs_io_mkdir_p(folder, err)) &&
                             !(st = link_or_copy(src, dst, err)))
                    {
                        char sub[700];
                        snprintf(sub, sizeof(sub), "labels/%s", splits[s]);
                        if (!(st = link_sidecar(inputs[i], out_dir, sub, a.e[e].file_name,
                                                ".txt", err)))
                            st = link_sidecar(inputs[i], out_dir, "label_2", a.e[e].file_name,
                                              ".txt", err);
                    }
                    free(src);
                    free(dst);
                    free(folder);
                }
            }
            free(path);
        }
        char *out = rs_io_join(out_dir, rel);
        if (!st && !out)
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (!st) {
            char *adir = rs_io_join(out_dir, "annotations");
            st = adir ? rs_io_mkdir_p(adir, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            free(adir);
        }
        if (!st)
            st = coco_write(&a, out, Nimages, Nannotations, err);
        free(out);
        coco_acc_free(&a);
    }
    if (!st && Nsplits == 0)
        st = rs_err_set(err, RS_ERR_NOT_FOUND, "merge: no annotations/instances_*.json in the "
                        "inputs");
    for (int s = 0; s < Nsplits; s++)
        free(splits[s]);
    free(splits);
    return st;
}
