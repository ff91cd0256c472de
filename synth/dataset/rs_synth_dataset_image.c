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

#include "core/rs_hash.h"
#include "core/rs_io.h"
#include "core/rs_rng.h"
#include "geo/rs_geo.h"
#include "synth/backdrop/rs_synth_opencv.h"
#include "synth/backdrop/rs_synth_sun.h"
#include "synth/dataset/internal/rs_synth_dataset_internal.h"
#include "synth/labels/rs_synth_labels.h"
#include "synth/povray/rs_synth_render.h"
#include "synth/povray/rs_synth_scene.h"
#include "synth/traffic/rs_synth_sumo.h"
#include "synth/traffic/rs_synth_traffic.h"
#include "synth/traffic/rs_synth_vehicles.h"

// ---- the random stream of one image ----

// The stream of image k: splitmix64 (core/rs_rng.h) from rs_rng_seed_derive(seed, k), stepped
// by rs_rng_seed_next. Its draws, in order: rs_synth_dataset.h ("traffic from SUMO's frames").
uint64_t rs_synth_dataset_image_seed(uint64_t seed, int k) { return rs_rng_seed_derive(seed, (uint64_t)k); }

static uint64_t rng_next(uint64_t *s) { return rs_rng_seed_next(s); }

int rs_synth_dataset__image_background(const rs_synth_dataset__run *d, int k, const rs_synth_dataset__camera *c)
{
    if (c->Nbg <= 0) return -1;
    uint64_t rng = rs_synth_dataset_image_seed(d->opt->seed, k);
    return (int)(rng_next(&rng) % (uint64_t)c->Nbg); // the stream's first draw
}

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
            b->linear.data[3 * i + c] = (float)rs_synth_srgb_decode(fitted.data[(size_t)fitted.channels * i + c]);
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
    c->have_canvas = !st;
    return st;
}

rs_status rs_synth_dataset__prepare_background(const rs_synth_dataset__run *d, rs_synth_dataset__camera *c,
                                               rs_synth_dataset__background *bm, rs_err *err)
{
    rs_status st = background_fit(bm, c->cam.width, c->cam.height, err);
    if (st || bm->light_tried) return st;
    // issue 18: lighting matched to the background's road (dry roads only)
    const char *cond = rs_site_background_tag(bm->src, "conditions");
    bm->light_tried = true;
    const bool dry = !cond || !strcmp(cond, "sunny") || !strcmp(cond, "cloudy");
    bm->light_ok =
        dry && rs_synth_light_from_image(&bm->light, &bm->linear, &c->cam, d->site, &d->lanes, 4, NULL) == RS_OK;
    double t_s;
    const bool timed = bm->time_iso && rs_synth_parse_iso8601(&t_s, bm->time_iso, "time", NULL) == RS_OK;
    bm->sun_ok =
        !timed && !bm->overcast && rs_synth_sun_from_shadows(&bm->sun, &bm->linear, &c->cam, d->site, NULL) == RS_OK;
    return RS_OK;
}

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
        if (ids[i] != 0 || shadow[i] >= 1) continue;
        for (int c = 0; c < 3; c++) bg_lin->data[3 * i + c] *= shadow[i];
    }
}

// The composite over a background: shadows (when given), the vehicle layer matched to the
// background (rs_synth_appearance.h; skipped when the background gives no estimate), straight
// alpha over the background in linear light, sRGB, the background's JPEG quality.
// in,out: r (its composite replaced); in: shadow passes may be NULL
static rs_status composite(rs_synth_render_result *r, const rs_synth_dataset__background *b, uint64_t seed, rs_err *err)
{
    const rs_synth_appearance app = b->app;
    const bool matched = b->app_ok;
    rs_status st = RS_OK;
    const size_t n = (size_t)r->width * (size_t)r->height;
    rs_image lin = {0};
    if ((st = rs_image_alloc(&lin, r->width, r->height, 3, err))) goto done;
    memcpy(lin.data, b->linear.data, sizeof(float) * 3 * n);
    if (r->shadow) shade_background(&lin, r->shadow, r->ids);
    if (matched && (st = rs_synth_appearance_apply(&r->rgba, &app, 0.6, seed, err))) {
        rs_image_free(&lin);
        goto done;
    }
    for (size_t i = 0; i < n; i++) {
        const double a = r->rgba.data[4 * i + 3];
        for (int c = 0; c < 3; c++) {
            const double v = a * r->rgba.data[4 * i + c] + (1 - a) * lin.data[3 * i + c];
            r->composite.data[3 * i + c] = (float)rs_synth_srgb_encode(v < 0 ? 0 : v > 1 ? 1 : v);
        }
    }
    rs_image_free(&lin);
    if (matched) st = rs_synth_appearance_jpeg(&r->composite, &app, err);
done:
    return st;
}

// ---- traffic from SUMO's frames (--traffic-frames) ----

// Frame i of DIR (index entry e) read as a vehicles file (rs_synth_vehicles_read: the one reader
// of that format) and checked for what synth needs: the count the index states, class vehicles
// with their box. On error *list is left empty.
static rs_status read_frame(rs_synth_vehicle_list *list, const char *dir, const rs_synth_sumo_frame_entry *e, int i,
                            rs_err *err)
{
    memset(list, 0, sizeof(*list));
    char *path = rs_io_join(dir, e->file);
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = rs_synth_vehicles_read(list, path, err);
    if (!st && list->N != e->vehicles)
        st = rs_err_set(err, RS_ERR_INVALID, "%s: %d vehicles, but %s/frames.json [%d].vehicles says %d", path, list->N,
                        dir, i, e->vehicles);
    for (int j = 0; !st && j < list->N; j++) {
        const rs_synth_vehicle *v = &list->v[j];
        const char *missing = !(v->length_m > 0) ? "length" : !(v->width_m > 0) ? "width" : "height";
        if (v->cls == RS_SYNTH_USER_MODEL)
            st = rs_err_set(err, RS_ERR_INVALID, "%s: [%d].model: a traffic frame holds class vehicles only", path, j);
        else if (!(v->length_m > 0 && v->width_m > 0 && v->height_m > 0))
            st = rs_err_set(err, RS_ERR_INVALID, "%s: [%d].%s: missing (a traffic frame gives every vehicle's box)",
                            path, j, missing);
    }
    if (st) rs_synth_vehicle_list_free(list);
    free(path);
    return st;
}

// DIR/frames.json with at least one frame.
static rs_status read_index(rs_synth_sumo_frame_entry **entries, int *N, const char *dir, rs_err *err)
{
    rs_status st = rs_synth_sumo_frames_index_read(entries, N, dir, err);
    if (!st && *N == 0)
        st = rs_err_set(err, RS_ERR_INVALID, "%s/frames.json: no frames (an empty list): no traffic to take", dir);
    return st;
}

rs_status rs_synth_dataset_traffic_frames_check(rs_synth_traffic_frames_info *info, const char *dir, rs_err *err)
{
    memset(info, 0, sizeof(*info));
    rs_synth_sumo_frame_entry *e = NULL;
    int N = 0;
    rs_status st = read_index(&e, &N, dir, err);
    if (st) return st;
    // the manifest, as sha256sum prints it, hashed through a temporary file (core's SHA-256)
    const char *tmpdir = getenv("TMPDIR");
    char manifest[4200], hex[65];
    snprintf(manifest, sizeof(manifest), "%s/roadside-frames-XXXXXX", tmpdir && *tmpdir ? tmpdir : "/tmp");
    const int fd = mkstemp(manifest);
    FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
    if (!f) {
        if (fd >= 0) close(fd), remove(manifest);
        free(e);
        return rs_err_set(err, RS_ERR_IO, "%s: %s", manifest, strerror(errno));
    }
    char *index = rs_io_join(dir, "frames.json");
    if (!index) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st && !(st = rs_hash_sha256_file(hex, NULL, index, err))) fprintf(f, "%s  frames.json\n", hex);
    for (int i = 0; i < N && !st; i++) {
        rs_synth_vehicle_list list;
        if ((st = read_frame(&list, dir, &e[i], i, err))) break;
        info->Nvehicles += list.N;
        rs_synth_vehicle_list_free(&list);
        char *path = rs_io_join(dir, e[i].file);
        st = path ? rs_hash_sha256_file(hex, NULL, path, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (!st) fprintf(f, "%s  %s\n", hex, e[i].file);
        free(path);
    }
    if (fclose(f) != 0 && !st) st = rs_err_set(err, RS_ERR_IO, "%s: %s", manifest, strerror(errno));
    if (!st) st = rs_hash_sha256_file(info->sha256, NULL, manifest, err);
    remove(manifest);
    if (!st) info->Nframes = N;
    free(index);
    free(e);
    return st;
}

// The vehicles of image k from DIR: frame r_frame mod Nframes, each vehicle i's variant
// rs_rng_seed_derive(r_looks, i) >> 11 (53 bits, as the built-in traffic draws them).
// out: *which, *iwhich: the frame's frames.json entry and its index there
static rs_status frame_vehicles(rs_synth_vehicle_list *list, rs_synth_sumo_frame_entry *which, int *iwhich,
                                const char *dir, uint64_t r_frame, uint64_t r_looks, rs_err *err)
{
    rs_synth_sumo_frame_entry *e = NULL;
    int N = 0;
    memset(list, 0, sizeof(*list));
    rs_status st = read_index(&e, &N, dir, err);
    if (!st) {
        const int i = (int)(r_frame % (uint64_t)N);
        st = read_frame(list, dir, &e[i], i, err);
        *which = e[i];
        *iwhich = i;
    }
    for (int j = 0; !st && j < list->N; j++) list->v[j].variant = rs_rng_seed_derive(r_looks, (uint64_t)j) >> 11;
    free(e);
    return st;
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

void rs_synth_dataset__stem(char *stem, size_t n, int k, const char *camera_id)
{
    snprintf(stem, n, "%06d_%s", k, camera_id);
    for (char *p = stem; *p; p++)
        if (!((*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') || *p == '_' ||
              *p == '-'))
            *p = '_';
}

rs_status rs_synth_dataset__make_image(rs_synth_dataset__run *d, int k, const char *stem, rs_synth_dataset__camera *c,
                                       bool *grey, double *seconds_povray, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    uint64_t rng = rs_synth_dataset_image_seed(opt->seed, k);
    char name[600];
    char *work = NULL, *part_tmp = NULL, *part = NULL, *image = NULL;
    rs_synth_vehicle *tv = NULL;       // (N,) the built-in traffic
    rs_synth_vehicle_list frame = {0}; // the SUMO frame's vehicles (--traffic-frames)
    rs_synth_sumo_frame_entry frame_entry = {0};
    int frame_index = -1; // into frames.json
    rs_synth_vehicle *v = NULL;
    rs_synth_prepared prepared = {0};
    rs_synth_render_result r = {0};
    const rs_synth_dataset__background *b = NULL;
    rs_synth_label *labels = NULL;
    double *up = NULL;
    rs_synth_mesh *meshes = NULL;
    const char **ids = NULL;
    uint8_t *coarse = NULL; // (N,) vehicle i gets the coarse mesh
    int N = 0;
    rs_status st;

    work = rs_io_join(d->work_root, stem);
    if (!work) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_io_remove_tree(work); // a previous, interrupted attempt
    if ((st = rs_io_mkdir_p(work, err))) goto done;

    rs_synth_render_options ropt;
    rs_synth_render_options_default(&ropt);
    ropt.povray = opt->povray;
    ropt.write_files = false; // the dataset composites and writes the image itself
    if ((st = rs_synth_dataset__prepare_camera(c, err))) goto done; // done already when the parent did it
    ropt.canvas = &c->canvas;
    ropt.canvas_map = c->canvas_map;
    ropt.separate_processes = opt->separate_processes;
    ropt.full_frame = opt->full_frame;
    (void)rng_next(&rng); // the background's draw (rs_synth_dataset__image_background)
    if (c->Nbg > 0) {
        rs_synth_dataset__background *bm = &c->bg[rs_synth_dataset__image_background(d, k, c)];
        b = bm;
        if ((st = rs_synth_dataset__prepare_background(d, c, bm, err))) goto done; // (or the parent did)
        // the vehicles alone over transparency; composite() puts them onto the background
        ropt.scene.ground_visible = false;
        ropt.scene.overcast = b->overcast;
        ropt.shadow = opt->shadows && !b->night;
        double t_s;
        if (b->time_iso && rs_synth_parse_iso8601(&t_s, b->time_iso, "time", NULL) == RS_OK)
            rs_synth_sun_position(&ropt.scene.sun_azimuth_deg, &ropt.scene.sun_elevation_deg, d->site->origin.lat_deg,
                                  d->site->origin.lon_deg, t_s);
        else if (b->sun_ok) // no time: the sun the poles' shadows show
            ropt.scene.sun_azimuth_deg = b->sun.azimuth_deg, ropt.scene.sun_elevation_deg = b->sun.elevation_deg;
        if (b->light_ok) {
            rs_synth_env_estimate env; // the environment the vehicles reflect: the background's own
            const bool env_ok = !rs_synth_env_from_image(&env, &b->linear, &c->cam, d->site, &d->lanes, 4, NULL);
            rs_synth_scene_match_background(&ropt.scene, &b->light, env_ok ? &env : NULL);
        }
        *grey = false;
    } else {
        ropt.scene.ground_visible = true; // neutral grey ground rendered by POV-Ray
        *grey = true;
    }

    // the traffic: the built-in one, or one frame of SUMO's (rs_synth_dataset.h gives the draws)
    const uint64_t r_traffic = rng_next(&rng);
    const uint64_t r_vary = rng_next(&rng);
    const rs_synth_vehicle *all = NULL; // (N,) every vehicle of the site, borrowed
    if (opt->traffic_frames_dir) {
        if ((st = frame_vehicles(&frame, &frame_entry, &frame_index, opt->traffic_frames_dir, r_traffic, r_vary, err)))
            goto done;
        all = frame.v;
        N = frame.N;
    } else {
        rs_synth_traffic_options topt;
        rs_synth_traffic_options_default(&topt);
        topt.seed = r_traffic;
        topt.count = 0; // every vehicle that fits; the camera's view picks among them below
        topt.junction_lanes = opt->junction_traffic;
        if ((st = rs_synth_traffic_place(&tv, &N, &d->lanes, &topt, err))) goto done;
        rs_synth_randomise_options xopt;
        rs_synth_randomise_options_default(&xopt);
        xopt.seed = r_vary;
        if ((st = rs_synth_traffic_randomise(tv, &N, &xopt, err))) goto done;
        all = tv;
    }
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
        const rs_synth_vehicle vi = all[i];
        double corners[8][3];
        int rect[4];
        rs_synth_vehicle_corners_enu(corners, &vi, d->site->ground_normal_enu, d->site->ground_offset_m);
        if (rs_synth_vehicle_rect(rect, c->canvas.fxycxy, c->canvas.width, c->canvas.height, c->cam.rt_cam_enu,
                                  (const double(*)[3])corners, 0.05)) {
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
    for (int i = 0; i < N; i++) ids[i] = v[i].id;
    if ((st = rs_synth_prepare_lod(&prepared, v, NULL, N, coarse, err))) goto done;
    const rs_camera *cam = &c->cam;
    if ((st = rs_synth_render(&r, work, cam, d->site->ground_normal_enu, d->site->ground_offset_m, &prepared, &ropt,
                              err)))
        goto done;
    *seconds_povray += r.seconds_povray;
    const uint64_t r_look = rng_next(&rng);
    if (b && (st = composite(&r, b, r_look, err))) goto done;
    for (int i = 0; i < N; i++) {
        up[i] = rs_synth_ground_up_m(d->site->ground_normal_enu, d->site->ground_offset_m, prepared.v[i].e_m,
                                     prepared.v[i].n_m);
        meshes[i] = prepared.meshes[prepared.imesh[i]];
    }
    if ((st = rs_synth_labels_compute(&labels, cam, prepared.v, up, N, meshes, r.ids, err))) goto done;
    for (int i = 0; i < N; i++) // latitude, longitude of each bottom centre (GeographicLib)
        if ((st = rs_geo_enu_to_llh(labels[i].bottom_center_llh, &d->site->origin, labels[i].bottom_center_enu_m, 1,
                                    err)))
            goto done;
    const int split = rs_synth_dataset__image_split(d, k, c);
    const char *split_name = d->split[split];
    char file_name[320], kitti_name[32];
    snprintf(file_name, sizeof(file_name), "%s.png", stem);
    snprintf(kitti_name, sizeof(kitti_name), "%06d.png", k); // KITTI's numeric names
    rs_synth_image_info info = {.index = k,
                                .camera = c->id,
                                .background = b ? (b->src->name ? b->src->name : b->src->file) : NULL,
                                .weather = b ? rs_site_background_tag(b->src, "conditions") : NULL,
                                .time_iso = b ? b->time_iso : NULL,
                                .sun_azimuth_deg = ropt.scene.sun_azimuth_deg,
                                .sun_elevation_deg = ropt.scene.sun_elevation_deg,
                                .camera_model = c->model_rel,
                                .camera_model_sha256 = c->model_sha256,
                                .calib_source = c->calib_path,
                                .calib_source_sha256 = c->calib_sha256,
                                .ground_offset_m = d->site->ground_offset_m};
    memcpy(info.ground_normal_enu, d->site->ground_normal_enu, sizeof(info.ground_normal_enu));
    info.time_of_day = (b && b->night) || ropt.scene.sun_elevation_deg < -6 ? "night"
                       : ropt.scene.sun_elevation_deg < 6                   ? "twilight"
                                                                            : "day";
    const rs_synth_label_image img = {.file_name = file_name,
                                      .width = r.width,
                                      .height = r.height,
                                      .labels = labels,
                                      .Nlabels = N,
                                      .vehicle_ids = ids,
                                      .info = &info};
    rs_synth_label_image kimg = img;
    kimg.file_name = kitti_name;
    const rs_synth_label_options lopt = {.bbox = (rs_synth_bbox_kind)opt->bbox,
                                         .min_visibility = opt->min_visibility,
                                         .drop_invisible = !opt->keep_invisible};
    // YOLO, KITTI and the image, then the per-image COCO file last: it marks the image done.
    image = rs_io_join(d->split_dir[split], file_name);
    snprintf(name, sizeof(name), "annotations/instances_%s.json", split_name);
    part_tmp = rs_io_join(work, name);
    snprintf(name, sizeof(name), "%s.json", stem);
    part = rs_io_join(d->parts_dir, name);
    char *kitti_dir = rs_io_join(opt->out_dir, "kitti/training");
    if (!image || !part_tmp || !part || !kitti_dir) {
        free(kitti_dir);
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    char yolo_image[600], kitti_image[600], kitti_calib[600];
    snprintf(yolo_image, sizeof(yolo_image), "images/%s/%s", split_name, file_name);
    snprintf(kitti_image, sizeof(kitti_image), "kitti/training/image_2/%s", kitti_name);
    snprintf(kitti_calib, sizeof(kitti_calib), "kitti/training/calib/%06d.txt", k);
    if (!(st = rs_synth_labels_write_yolo(opt->out_dir, split_name, &img, 1, &lopt, err)) &&
        !(st = rs_synth_labels_write_kitti(kitti_dir, &kimg, 1, &lopt, err)) &&
        !(st = rs_image_write(image, &r.composite, 8, err)) &&
        !(st = rs_synth_dataset__link_into(d, image, yolo_image, err)) &&
        !(st = rs_synth_dataset__link_into(d, image, kitti_image, err))) {
        char *cp = rs_io_join(opt->out_dir, kitti_calib);
        st = cp ? rs_synth_labels_write_kitti_calib(cp, cam, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(cp);
    }
    free(kitti_dir);
    if (st || (st = rs_synth_labels_write_coco(work, split_name, &img, 1, &lopt, err))) goto done;
    if (frame_index >= 0 && (st = rs_synth_dataset__coco_set_traffic_frame(part_tmp, frame_entry.file,
                                                                           frame_entry.time_s, frame_index, err)))
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
    rs_synth_vehicle_list_free(&frame);
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
