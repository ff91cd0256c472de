// rs_synth_dataset_image.c -- one image of `roadside synth` (synth/dataset/rs_synth_dataset.h): its
// random stream, its background (fitted to the camera, with its appearance), the traffic the
// camera sees (built-in, or one of SUMO's frames: --traffic-frames, checked here too), the
// render, the composite with shadows, the labels and the image's files, the per-image COCO
// file last. Called by rs_synth_dataset.c; calls the other rooms of synth/
// (traffic, fleet, render, labels, appearance) and core/.
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <unistd.h>

#include "core/rs_color.h"
#include "core/rs_hash.h"
#include "core/rs_io.h"
#include "core/rs_rng.h"
#include "geo/rs_geo.h"
#include "synth/backdrop/rs_synth_opencv.h"
#include "synth/backdrop/rs_synth_sun.h"
#include "synth/dataset/internal/rs_synth_dataset_internal.h"
#include "synth/labels/rs_synth_labels.h"
#include "synth/povray/rs_synth_composite.h"
#include "synth/povray/rs_synth_render.h"
#include "synth/povray/rs_synth_scene.h"
#include "synth/traffic/rs_synth_sumo.h"
#include "synth/traffic/rs_synth_traffic.h"
#include "synth/traffic/rs_synth_vehicles.h"

// ---- the background ----

// The background at the camera's size (linear resampling when it differs), decoded to linear
// light, and its appearance (rs_synth_appearance_estimate on the original file: noise, blur,
// JPEG quality are the camera's), computed at first use and kept. On error nothing is kept.
static rs_status background_fit(rs_synth_dataset__background *b, int width, int height, rs_err *err)
{
    if (b->linear.data) return RS_OK;
    rs_image src = {0}, fitted = {0};
    float *map = NULL;
    rs_status st = rs_image_read(&src, b->src->path, err);
    if (st) return st;
    if (src.channels < 3) {
        st = rs_err_set(err, RS_ERR_INVALID, "%s: not an RGB image", b->src->path);
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
    if ((st = rs_synth_remap(&fitted, &src, map, width, height, 1, err)) ||
        (st = rs_image_alloc(&b->linear, width, height, 3, err)))
        goto done;
    for (size_t i = 0; i < (size_t)width * height; i++)
        for (int c = 0; c < 3; c++)
            b->linear.data[3 * i + c] = (float)rs_color_srgb_decode(fitted.data[(size_t)fitted.channels * i + c]);
    rs_image_free(&fitted); // before the estimate: its buffers come on top (the parent's peak)
    b->app_ok = rs_synth_appearance_estimate(&b->app, b->src->path, &src, NULL, NULL) == RS_OK;
done:
    if (st) rs_image_free(&b->linear);
    free(map);
    rs_image_free(&fitted);
    rs_image_free(&src);
    return st;
}

rs_status rs_synth_dataset__prepare_camera(rs_synth_dataset__camera *c, rs_err *err)
{
    if (c->have_canvas) return RS_OK;
    const rs_camera *cc = &c->cam;
    rs_status st = rs_synth_canvas_for_lens(&c->canvas, &cc->lensmodel, cc->intrinsics, cc->width, cc->height, 1, err);
    if (!st && !c->canvas.identity)
        st =
            rs_synth_canvas_map(&c->canvas_map, &c->canvas, &cc->lensmodel, cc->intrinsics, cc->width, cc->height, err);
    if (!st) st = rs_synth_dataset__prepare_kitti(c, err);
    c->have_canvas = !st;
    return st;
}

// The scene's light and environment over background bm: overcast or not, the sun of its time tag
// (or of its poles' shadows), the lights and environment matched to it when its light was
// estimated (bm prepared: rs_synth_dataset__prepare_background).
static void background_scene(rs_synth_scene_options *scene, const rs_synth_dataset__run *d,
                             const rs_synth_dataset__camera *c, const rs_synth_dataset__background *bm)
{
    scene->overcast = bm->overcast;
    double t_s;
    if (bm->time_iso && rs_synth_parse_iso8601(&t_s, bm->time_iso, "time", NULL) == RS_OK)
        rs_synth_sun_position(&scene->sun_azimuth_deg, &scene->sun_elevation_deg, d->site->origin.lat_deg,
                              d->site->origin.lon_deg, t_s);
    else if (bm->sun_ok) // no time: the sun the poles' shadows show
        scene->sun_azimuth_deg = bm->sun.azimuth_deg, scene->sun_elevation_deg = bm->sun.elevation_deg;
    if (bm->light_ok) {
        rs_synth_env_estimate env; // the environment the vehicles reflect: the background's own
        const bool env_ok = !rs_synth_env_from_image(&env, &bm->linear, &c->cam, d->site, &d->lanes, 4, NULL);
        rs_synth_scene_match_background(scene, &bm->light, env_ok ? &env : NULL);
    }
}

rs_status rs_synth_dataset__prepare_background(const rs_synth_dataset__run *d, rs_synth_dataset__camera *c,
                                               rs_synth_dataset__background *bm, rs_err *err)
{
    rs_status st = background_fit(bm, c->cam.width, c->cam.height, err);
    if (st || bm->light_tried) return st;
    // issue 40: the condition its tags leave open, estimated from the image
    if (!bm->cond_known) {
        if ((st = rs_synth_condition_estimate(&bm->cond, &bm->linear, err))) return st;
        bm->cond_known = true;
        bm->overcast = bm->cond.overcast;
        bm->night = bm->cond.time_of_day == RS_SYNTH_TOD_NIGHT;
        rs_synth_condition_label(bm->cond_label, sizeof(bm->cond_label), &bm->cond);
    }
    // issue 18: lighting matched to the background's road (dry roads only)
    bm->light_tried = true;
    const bool dry = bm->cond.surface == RS_SYNTH_SURFACE_DRY;
    bm->light_ok =
        dry && rs_synth_light_from_background(&bm->light, &bm->linear, &c->cam, d->site, &d->lanes, 4, NULL) == RS_OK;
    double t_s;
    const bool timed = bm->time_iso && rs_synth_parse_iso8601(&t_s, bm->time_iso, "time", NULL) == RS_OK;
    bm->sun_ok =
        !timed && !bm->overcast && rs_synth_sun_from_shadows(&bm->sun, &bm->linear, &c->cam, d->site, NULL) == RS_OK;
    // issue 40: the background itself as the environment, made once here (by the parent for its
    // workers: 0.2 s per background, and a background serves several images of several workers)
    if (bm->light_ok) {
        rs_synth_render_options o;
        rs_synth_render_options_default(&o);
        background_scene(&o.scene, d, c, bm);
        if ((st = rs_synth_scene_env_map(&bm->env_map, &o.scene, &bm->linear, &c->cam, d->site, err))) return st;
        bm->env_map_tried = true;
    }
    return RS_OK;
}

// ---- shadows and appearance over a background ----

// The composite over a background (rs_synth_composite_background: the shadows, the vehicle layer
// in the background's camera look unless --no-appearance or the background gave no estimate,
// its JPEG quality). in,out: r (its composite replaced)
static rs_status composite(rs_synth_render_result *r, const rs_synth_dataset__background *b, bool look, uint64_t seed,
                           rs_err *err)
{
    const rs_synth_composite_options copt = {.look = look && b->app_ok ? &b->app : NULL,
                                             .layer_blur_sigma_px = 0,
                                             .seed = seed,
                                             .light_matched = b->light_ok,
                                             .headlight_irradiance = r->headlight_irradiance,
                                             .mirror = r->mirror.data ? &r->mirror : NULL,
                                             .ids = r->ids};
    rs_image comp = {0};
    rs_status st = rs_synth_composite_background(&comp, &r->rgba, &b->linear, r->shadow, &copt, err);
    if (st) return st;
    rs_image_free(&r->composite);
    r->composite = comp;
    return RS_OK;
}

// ---- one image ----

rs_status rs_synth_dataset__link_into(const rs_synth_dataset__run *d, const char *src, const char *rel, rs_err *err)
{
    char *dst = rs_io_join(d->opt->out_dir, rel);
    char *tmp = dst ? malloc(strlen(dst) + 32) : NULL;
    rs_status st = RS_OK;
    if (!dst || !tmp) {
        free(dst);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    snprintf(tmp, strlen(dst) + 32, "%s.%ld.lnk", dst, (long)getpid());
    (void)remove(tmp);
    if (link(src, tmp) != 0) {
        // another file system: a copy, written atomically
        char *data = NULL;
        size_t len = 0;
        if (!(st = rs_io_read_file(&data, &len, src, err))) st = rs_io_write_file(dst, data, len, err);
        free(data);
    } else if (rename(tmp, dst) != 0) {
        st = rs_err_set(err, RS_ERR_IO, "%s: %s", dst, strerror(errno));
        (void)remove(tmp);
    }
    free(tmp);
    free(dst);
    return st;
}

// The render options of image k: the camera's canvas, and over a background the sun of its time
// tag (or of its poles' shadows) and the lights and environment matched to it. Consumes the
// stream's first draw (the background's). out: *ropt, *b (the background, NULL: the grey
// ground).
static rs_status image_render_options(rs_synth_render_options *ropt, const rs_synth_dataset__background **b,
                                      rs_synth_dataset__run *d, int k, rs_synth_dataset__camera *c, uint64_t *rng,
                                      rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    rs_synth_render_options_default(ropt);
    ropt->povray = opt->povray;
    ropt->write_files = false;                               // the dataset composites and writes the image itself
    rs_status st = rs_synth_dataset__prepare_camera(c, err); // done already when the parent did it
    if (st) return st;
    ropt->canvas = &c->canvas;
    ropt->canvas_map = c->canvas_map;
    ropt->separate_processes = opt->separate_processes;
    ropt->full_frame = opt->full_frame;
    (void)rs_rng_seed_next(rng); // the background's draw (rs_synth_dataset__image_background)
    *b = NULL;
    if (c->Nbg <= 0) {
        ropt->scene.ground_visible = true; // neutral grey ground rendered by POV-Ray
        return RS_OK;
    }
    rs_synth_dataset__background *bm = &c->bg[rs_synth_dataset__image_background(d, k, c)];
    if (opt->labels_only) { // no render: the background is named only, never decoded
        *b = bm;
        return RS_OK;
    }
    if ((st = rs_synth_dataset__prepare_background(d, c, bm, err))) return st; // (or the parent did)
    *b = bm;
    // the vehicles alone over transparency; composite() puts them onto the background
    ropt->scene.ground_visible = false;
    ropt->shadow = opt->shadows && !bm->night;
    background_scene(&ropt->scene, d, c, bm);
    if (bm->light_ok) {
        if (!bm->env_map_tried) { // (made by prepare_background, unless that failed in the parent)
            if ((st = rs_synth_scene_env_map(&bm->env_map, &ropt->scene, &bm->linear, &c->cam, d->site, err)))
                return st;
            bm->env_map_tried = true;
        }
        ropt->env_map = &bm->env_map;
    }
    return RS_OK;
}

// The vehicles of one image: the site's traffic (the built-in one, or one frame of SUMO's:
// rs_synth_dataset.h gives the draws), of which those the camera sees (their box meets the
// canvas: culled here, once; render takes their rectangles as they are), at most opt->vehicles
// of them, a uniformly drawn subset kept in placement order: the traffic of the whole site
// would leave most images nearly empty.
typedef struct {
    rs_synth_vehicle *v;    // (N,) owned: the vehicles rendered
    int (*rect)[4];         // (N,) owned: each one's canvas rectangle (rs_synth_vehicle_rect)
    uint8_t *coarse;        // (N,) owned: the rs_synth_lod of each (opt->coarse_below_px, medium_below_px)
    rs_synth_obj_spec *obj; // (N,) owned: a user model's spec (--models), zeroed for the others
    int N;
    int iframe; // the SUMO frame's index in frames.json, -1 for the built-in traffic
} image_traffic;

static void image_traffic_free(image_traffic *t)
{
    free(t->v);
    free(t->rect);
    free(t->coarse);
    free(t->obj);
    memset(t, 0, sizeof(*t));
}

// The site's vehicles before the camera picks among them. out: *all (N,) owned by *owned_list
// (SUMO) or *owned (built-in)
static rs_status site_traffic(const rs_synth_vehicle **all, int *N, rs_synth_vehicle_list *owned_list,
                              rs_synth_vehicle **owned, int *iframe, const rs_synth_dataset__run *d, int k,
                              uint64_t *rng, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    const uint64_t r_traffic = rs_rng_seed_next(rng);
    const uint64_t r_vary = rs_rng_seed_next(rng);
    rs_status st;
    if (opt->traffic_frames_dir) {
        if ((st = rs_synth_dataset__frame_vehicles(owned_list, iframe, d, k, r_traffic, r_vary, err))) return st;
        *all = owned_list->v;
        *N = owned_list->N;
        return RS_OK;
    }
    rs_synth_traffic_options topt;
    rs_synth_traffic_options_default(&topt);
    topt.seed = r_traffic;
    topt.count = 0; // every vehicle that fits; the camera's view picks among them below
    topt.junction_lanes = opt->junction_traffic;
    if ((st = rs_synth_traffic_place(owned, N, &d->lanes, &topt, err))) return st;
    rs_synth_randomise_options xopt;
    rs_synth_randomise_options_default(&xopt);
    xopt.seed = r_vary;
    if ((st = rs_synth_traffic_randomise(*owned, N, &xopt, err))) return st;
    *all = *owned;
    return RS_OK;
}

static rs_status image_vehicles(image_traffic *t, const rs_synth_dataset__run *d, int k,
                                const rs_synth_dataset__camera *c, uint64_t *rng, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    memset(t, 0, sizeof(*t));
    t->iframe = -1;
    rs_synth_vehicle_list frame = {0};
    rs_synth_vehicle *builtin = NULL;
    const rs_synth_vehicle *all = NULL;
    int N = 0;
    rs_status st = site_traffic(&all, &N, &frame, &builtin, &t->iframe, d, k, rng, err);
    const size_t n = (size_t)(N > 0 ? N : 1);
    if (!st && (!(t->v = calloc(n, sizeof(*t->v))) || !(t->rect = calloc(n, sizeof(*t->rect))) ||
                !(t->coarse = calloc(n, 1)) || !(t->obj = calloc(n, sizeof(*t->obj)))))
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    int Nseen = 0;
    for (int i = 0; i < N && !st; i++) {
        // --models: the vehicle may become one of the library's models of its class (its box)
        rs_synth_vehicle x = all[i];
        rs_synth_obj_spec spec = {0};
        rs_synth_dataset__pick_model(&x, &spec, d, k, i);
        double corners[8][3];
        rs_synth_vehicle_corners_enu(corners, &x, d->site->ground_normal_enu, d->site->ground_offset_m);
        if (rs_synth_vehicle_rect(t->rect[Nseen], &c->canvas, c->cam.rt_cam_enu, (const double(*)[3])corners, 0.05)) {
            // labels alone: every vehicle's coarse mesh (rs_synth_fleet_build_lod; the box and roof
            // line exact) for a faster ID pass and visibility (docs/synth.md, "Sequences and labels
            // without rendering")
            const int tall_px = t->rect[Nseen][3] - t->rect[Nseen][1] + 1;
            t->coarse[Nseen] = opt->labels_only || tall_px < opt->coarse_below_px ? RS_SYNTH_LOD_COARSE
                               : tall_px < opt->medium_below_px                   ? RS_SYNTH_LOD_MEDIUM
                                                                                  : RS_SYNTH_LOD_FULL;
            t->obj[Nseen] = spec;
            t->v[Nseen++] = x;
        }
    }
    const uint64_t r_pick = st ? 0 : rs_rng_seed_next(rng);
    if (!st && Nseen > opt->vehicles && !opt->sequence) { // a sequence keeps every vehicle in view
        // selection sampling (Knuth, TAOCP vol. 2, Algorithm S): keep each with probability
        // (still needed) / (still left), in order
        uint64_t s_pick = r_pick;
        int kept = 0;
        for (int i = 0; i < Nseen && kept < opt->vehicles; i++) {
            const double u01 = (double)(rs_rng_seed_next(&s_pick) >> 11) * 0x1.0p-53;
            if (u01 * (Nseen - i) < opt->vehicles - kept) {
                t->coarse[kept] = t->coarse[i];
                memcpy(t->rect[kept], t->rect[i], sizeof(t->rect[i]));
                t->obj[kept] = t->obj[i];
                t->v[kept++] = t->v[i];
            }
        }
        Nseen = kept;
    }
    t->N = Nseen;
    rs_synth_vehicle_list_free(&frame);
    free(builtin);
    if (st) image_traffic_free(t);
    return st;
}

// What the COCO writer records of image k (rs_synth_image_info; docs/labels.md).
static rs_synth_image_info image_info(const rs_synth_dataset__run *d, int k, const rs_synth_dataset__camera *c,
                                      const rs_synth_dataset__background *b, const rs_synth_render_options *ropt,
                                      int iframe)
{
    rs_synth_image_info info = {.index = k,
                                .camera = c->id,
                                .background = b ? (b->src->name ? b->src->name : b->src->file) : NULL,
                                .weather = b ? rs_site_background_tag(b->src, "conditions") : NULL,
                                .time_iso = b ? b->time_iso : NULL,
                                .sun_azimuth_deg = ropt->scene.sun_azimuth_deg,
                                .sun_elevation_deg = ropt->scene.sun_elevation_deg,
                                .camera_model = c->model_rel,
                                .camera_model_sha256 = c->model_sha256,
                                .calib_source = c->calib_path,
                                .calib_source_sha256 = c->calib_sha256,
                                .ground_offset_m = d->site->ground_offset_m};
    memcpy(info.ground_normal_enu, d->site->ground_normal_enu, sizeof(info.ground_normal_enu));
    if (b && b->cond_known) { // issue 40: the tagged or estimated condition
        info.time_of_day = rs_synth_condition_time_name(b->cond.time_of_day);
        info.surface = rs_synth_condition_surface_name(b->cond.surface);
        info.condition = b->cond_label;
        info.condition_estimated = b->cond.estimated;
        if (!info.weather) info.weather = info.surface;
    } else
        info.time_of_day = ropt->scene.sun_elevation_deg < RS_SYNTH_DUSK_LOW_DEG     ? "night"
                           : ropt->scene.sun_elevation_deg <= RS_SYNTH_DUSK_HIGH_DEG ? "dusk"
                                                                                     : "day";
    if (iframe >= 0) {
        info.traffic_frame_file = d->frames[iframe].file;
        info.traffic_frame_time_s = d->frames[iframe].time_s;
        info.traffic_frame_index = iframe;
    }
    return info;
}

// Image k's files: YOLO, KITTI and the image, then the per-image COCO file last (written in
// work, renamed into parts/<stem>.json): it marks the image done.
static rs_status image_files(const rs_synth_dataset__run *d, int k, const char *stem, const char *work,
                             const rs_synth_dataset__camera *c, const rs_synth_render_result *r,
                             const rs_synth_label_image *img, const rs_synth_label_input *lin, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    const int split = rs_synth_dataset__image_split(d, k, c);
    const char *split_name = d->split[split];
    char name[600];
    const rs_synth_label_options lopt = {.bbox = (rs_synth_bbox_kind)opt->bbox,
                                         .min_visibility = opt->min_visibility,
                                         .drop_invisible = !opt->keep_invisible};
    char *image = rs_io_join(d->split_dir[split], img->file_name);
    snprintf(name, sizeof(name), "annotations/instances_%s.json", split_name);
    char *part_tmp = rs_io_join(work, name);
    snprintf(name, sizeof(name), "%s.json", stem);
    char *part = rs_io_join(d->parts_dir, name);
    char yolo_image[600];
    snprintf(yolo_image, sizeof(yolo_image), "images/%s/%s", split_name, img->file_name);
    unsigned char *kept = malloc((size_t)(img->Nlabels > 0 ? img->Nlabels : 1)); // the vehicles labelled
    rs_status st = RS_OK;
    if (!image || !part_tmp || !part || !kept) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; !st && i < img->Nlabels; i++) {
        double box[4];
        kept[i] = (unsigned char)rs_synth_label_kept(box, &img->labels[i], &lopt);
    }
    if (!st && opt->labels_only) { // the labels alone: no image, YOLO or KITTI files
        if (!(st = rs_synth_labels_write_coco(work, split_name, img, 1, &lopt, err)) && rename(part_tmp, part) != 0)
            st = rs_err_set(err, RS_ERR_IO, "%s: %s", part, strerror(errno));
    } else if (!st && !(st = rs_synth_labels_write_yolo(opt->out_dir, split_name, img, 1, &lopt, err)) &&
               !(st = rs_image_write(image, &r->composite, 8, err)) &&
               !(st = rs_synth_dataset__link_into(d, image, yolo_image, err)) &&
               !(st = rs_synth_dataset__kitti_files(d, k, c, image, &r->composite, r->ids, lin, img->labels, kept,
                                                    err)) &&
               !(st = rs_synth_labels_write_coco(work, split_name, img, 1, &lopt, err)) && rename(part_tmp, part) != 0)
        st = rs_err_set(err, RS_ERR_IO, "%s: %s", part, strerror(errno));
    free(kept);
    free(part);
    free(part_tmp);
    free(image);
    return st;
}

rs_status rs_synth_dataset__make_image(rs_synth_dataset__run *d, int k, const char *stem, rs_synth_dataset__camera *c,
                                       bool *grey, int *condition, double *seconds_povray, rs_err *err)
{
    uint64_t rng = rs_synth_dataset_image_seed(d->opt->seed, k);
    image_traffic t = {0};
    rs_synth_prepared prepared = {0};
    rs_synth_render_result r = {0};
    rs_synth_label *labels = NULL;
    const rs_synth_dataset__background *b = NULL;
    rs_synth_render_options ropt;
    double *up = NULL;
    rs_synth_mesh *meshes = NULL;
    const char **ids = NULL;
    char *work = rs_io_join(d->work_root, stem);
    if (!work) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_io_remove_tree(work); // a previous, interrupted attempt
    rs_status st = rs_io_mkdir_p(work, err);
    if (!st) st = image_render_options(&ropt, &b, d, k, c, &rng, err);
    if (st) goto done;
    *grey = b == NULL;
    *condition = b && b->cond_known ? 3 * (int)b->cond.time_of_day + (int)b->cond.surface : -1;
    if ((st = image_vehicles(&t, d, k, c, &rng, err))) goto done;
    const int N = t.N;
    const size_t n = (size_t)(N > 0 ? N : 1);
    up = malloc(n * sizeof(double));
    meshes = malloc(n * sizeof(rs_synth_mesh));
    ids = malloc(n * sizeof(char *));
    if (!up || !meshes || !ids) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    for (int i = 0; i < N; i++) ids[i] = t.v[i].id;
    if ((st = rs_synth_prepare_lod(&prepared, t.v, t.obj, N, t.coarse, err))) goto done;
    ropt.vehicle_rects = (const int(*)[4])t.rect;
    if (b && b->cond_known && !d->opt->labels_only) { // issue 40: lights, street lights, snow; the passes
        rs_synth_scene_apply_condition(&ropt.scene, &b->cond, d->site, &prepared);
        ropt.headlights = ropt.scene.lights_on;
        ropt.mirror = b->cond.surface == RS_SYNTH_SURFACE_WET;
    }
    if (d->opt->labels_only) { // the ID pass alone, rasterised (rs_synth_dataset.h, "sequences")
        r.width = c->cam.width;
        r.height = c->cam.height;
        if ((st = rs_synth_render_ids(&r.ids, &c->cam, &c->canvas, c->canvas_map, d->site->ground_normal_enu,
                                      d->site->ground_offset_m, &prepared, err)))
            goto done;
    } else {
        if ((st = rs_synth_render(&r, work, &c->cam, d->site->ground_normal_enu, d->site->ground_offset_m, &prepared,
                                  &ropt, err)))
            goto done;
        *seconds_povray += r.seconds_povray;
        const uint64_t r_look = rs_rng_seed_next(&rng);
        if (b && (st = composite(&r, b, !d->opt->no_appearance, r_look, err))) goto done;
    }
    for (int i = 0; i < N; i++) {
        up[i] = rs_synth_ground_up_m(d->site->ground_normal_enu, d->site->ground_offset_m, prepared.v[i].e_m,
                                     prepared.v[i].n_m);
        meshes[i] = prepared.meshes[prepared.imesh[i]];
    }
    const rs_synth_label_input lin = {.cam = &c->cam,
                                      .vehicles = prepared.v,
                                      .Nvehicles = N,
                                      .up_m = up,
                                      .meshes = meshes,
                                      .id_image = r.ids,
                                      .origin = &d->site->origin};
    if ((st = rs_synth_labels_compute(&labels, &lin, err))) goto done;
    char file_name[320];
    snprintf(file_name, sizeof(file_name), "%s.png", stem);
    const rs_synth_image_info info = image_info(d, k, c, b, &ropt, t.iframe);
    const rs_synth_label_image img = {.file_name = file_name,
                                      .width = r.width,
                                      .height = r.height,
                                      .labels = labels,
                                      .Nlabels = N,
                                      .vehicle_ids = ids,
                                      .info = &info};
    if ((st = image_files(d, k, stem, work, c, &r, &img, &lin, err))) goto done;
    rs_io_remove_tree(work);
done:
    free(work);
    image_traffic_free(&t);
    free(up);
    free(meshes);
    free(ids);
    free(labels);
    rs_synth_prepared_free(&prepared);
    rs_synth_render_result_free(&r);
    return st;
}
