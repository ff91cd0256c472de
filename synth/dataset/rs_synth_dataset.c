// rs_synth_dataset.c -- `roadside synth` (synth/dataset/rs_synth_dataset.h): the run. Loads the site
// through geo (rs_site_load: cameras, each camera's tagged backgrounds, lanes), the calibrated
// cameras, then makes this shard's images -- skipping finished ones (resume) -- in this process
// or in forked workers, and assembles DATASET's COCO file. Calls rs_synth_dataset_image.c (one
// image), rs_synth_dataset_coco.c (assembly), geo and core/.
#define _POSIX_C_SOURCE 200809L
#define _XOPEN_SOURCE   700
#define _GNU_SOURCE     // sched_getaffinity, CPU_COUNT
#include <errno.h>
#include <math.h>
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "core/rs_hash.h"
#include <cjson/cJSON.h>
#include <mrcal/mrcal.h>

#include "core/rs_io.h"
#include "synth/dataset/internal/rs_synth_dataset_internal.h"
#include "synth/labels/rs_synth_labels.h"

void rs_synth_dataset_options_default(rs_synth_dataset_options *opt)
{
    memset(opt, 0, sizeof(*opt));
    opt->count = 1;
    opt->shard_count = 1;
    opt->vehicles = 10;
    opt->split = "train2017";
    opt->val_split = "val2017";
    opt->val_fraction = RS_SYNTH_VAL_FRACTION_DEFAULT;
    opt->bbox = RS_SYNTH_BBOX_FOOTPRINT;
    opt->junction_traffic = true;
    opt->shadows = true;
    opt->coarse_below_px = 40;
    opt->medium_below_px = 120;
    opt->frame_end = -1;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

// Scales a camera to width x height: fx, fy, cx, cy with the pixel-centre origin
// (c' = (c + 0.5) s - 0.5); distortion untouched (it acts on normalised coordinates).
static rs_status scale_camera(rs_camera *cam, int width, int height, const char *id, rs_err *err)
{
    if (width <= 0 || (width == cam->width && height == cam->height)) return RS_OK;
    mrcal_lensmodel_metadata_t meta = mrcal_lensmodel_metadata(&cam->lensmodel);
    if (!meta.has_core)
        return rs_err_set(err, RS_ERR_UNSUPPORTED,
                          "camera %s: --size: lens model without "
                          "fx, fy, cx, cy cannot be scaled",
                          id);
    const double sx = (double)width / cam->width, sy = (double)height / cam->height;
    if (fabs(sx / sy - 1) > 0.01)
        return rs_err_set(err, RS_ERR_INVALID,
                          "camera %s: --size %dx%d: aspect differs from "
                          "the camera's %dx%d by more than 1 %%",
                          id, width, height, cam->width, cam->height);
    cam->intrinsics[0] *= sx;
    cam->intrinsics[1] *= sy;
    cam->intrinsics[2] = (cam->intrinsics[2] + 0.5) * sx - 0.5;
    cam->intrinsics[3] = (cam->intrinsics[3] + 0.5) * sy - 0.5;
    cam->width = width;
    cam->height = height;
    return RS_OK;
}

// ---- the CPUs this process may use ----

// The cgroup v2 quota of this process's cgroup (/proc/self/cgroup "0::/PATH" ->
// /sys/fs/cgroup/PATH/cpu.max "QUOTA PERIOD"), in CPUs rounded up; 0 when none or unknown.
static int cgroup_cpus(void)
{
    char line[4096], path[4300];
    FILE *f = fopen("/proc/self/cgroup", "r");
    if (!f) return 0;
    int cpus = 0;
    while (fgets(line, sizeof(line), f)) {
        if (strncmp(line, "0::", 3) != 0) continue;
        line[strcspn(line, "\n")] = 0;
        // the cgroup and its parents: the tightest quota on the way up counts
        for (char *end = line + strlen(line); end >= line + 3; end--) {
            if (*end != '/' && *end != 0) continue;
            const char save = *end;
            *end = 0;
            snprintf(path, sizeof(path), "/sys/fs/cgroup%s/cpu.max", line + 3);
            *end = save;
            FILE *m = fopen(path, "r");
            long long quota = 0, period = 0;
            char q[32] = "";
            if (m && fscanf(m, "%31s %lld", q, &period) == 2 && strcmp(q, "max") != 0 &&
                sscanf(q, "%lld", &quota) == 1 && quota > 0 && period > 0) {
                const int c = (int)((quota + period - 1) / period);
                if (cpus == 0 || c < cpus) cpus = c;
            }
            if (m) fclose(m);
            if (end == line + 3) break;
        }
        break;
    }
    fclose(f);
    return cpus;
}

int rs_synth_dataset_usable_cpus(char *why, size_t n)
{
    int cpus = 0;
    const char *from = "online CPUs";
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof(set), &set) == 0 && CPU_COUNT(&set) > 0) {
        cpus = CPU_COUNT(&set);
        from = "affinity mask";
    } else {
        const long c = sysconf(_SC_NPROCESSORS_ONLN);
        cpus = c > 0 ? (int)c : 1;
    }
    const int cg = cgroup_cpus();
    if (cg > 0 && cg < cpus) {
        cpus = cg;
        from = "cgroup cpu.max quota";
    }
    const char *slurm = getenv("SLURM_CPUS_PER_TASK");
    char *end = NULL;
    const long sl = slurm ? strtol(slurm, &end, 10) : 0;
    if (slurm && end && !*end && sl > 0 && sl < cpus) {
        cpus = (int)sl;
        from = "SLURM_CPUS_PER_TASK";
    }
    if (cpus < 1) cpus = 1;
    if (why) snprintf(why, n, "%s: %d CPU%s", from, cpus, cpus == 1 ? "" : "s");
    return cpus;
}

// ---- the site's cameras and backgrounds ----

static void dataset_free(rs_synth_dataset__run *d)
{
    for (int i = 0; i < d->Ncams; i++) {
        rs_camera_free(&d->cams[i].cam);
        for (int b = 0; b < d->cams[i].Nbg; b++) {
            rs_image_free(&d->cams[i].bg[b].linear);
            rs_image_free(&d->cams[i].bg[b].env_map);
        }
        free(d->cams[i].bg);
        free(d->cams[i].canvas_map);
        free(d->cams[i].kitti_map);
        rs_camera_free(&d->cams[i].kitti_cam);
        free(d->cams[i].calib_path);
    }
    free(d->cams);
    free(d->frames);
    for (int i = 0; d->model_meshes && i < d->models.N; i++) rs_synth_mesh_free(&d->model_meshes[i]);
    free(d->model_meshes);
    rs_synth_vehicle_list_free(&d->models);
    rs_lanes_free(&d->lanes);
    rs_site_free(d->site);
    free(d->split_dir[0]);
    free(d->split_dir[1]);
    free(d->parts_dir);
    free(d->work_root);
}

// The backgrounds of the site's camera sc (site.json "background_images", read by geo) whose
// tags match every filter, each with its condition from its tags (rs_synth_condition_from_tags).
static rs_status select_backgrounds(rs_synth_dataset__camera *c, const rs_site_camera *sc,
                                    const rs_synth_dataset_options *opt, const rs_site *site, rs_err *err)
{
    c->bg =
        calloc((size_t)(sc->Nbackground_images > 0 ? sc->Nbackground_images : 1), sizeof(rs_synth_dataset__background));
    if (!c->bg) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; i < sc->Nbackground_images; i++) {
        const rs_site_background *e = &sc->background_images[i];
        bool keep = true;
        for (int f = 0; f < opt->Nfilters && keep; f++) {
            const char *v = rs_site_background_tag(e, opt->filter_keys[f]);
            keep = v && strcmp(v, opt->filter_values[f]) == 0;
        }
        if (!keep) continue;
        rs_synth_dataset__background *b = &c->bg[c->Nbg++];
        b->src = e;
        b->time_iso = rs_site_background_tag(e, "time");
        rs_status st =
            rs_synth_condition_from_tags(&b->cond, &b->cond_known, e, site->origin.lat_deg, site->origin.lon_deg, err);
        if (st) return st;
        b->overcast = b->cond_known && b->cond.overcast;
        b->night = b->cond_known && b->cond.time_of_day == RS_SYNTH_TOD_NIGHT;
        if (b->cond_known) rs_synth_condition_label(b->cond_label, sizeof(b->cond_label), &b->cond);
    }
    return RS_OK;
}

static rs_status dataset_load(rs_synth_dataset__run *d, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    rs_status st;
    char *path = NULL;
    if ((st = rs_site_load(&d->site, opt->site_dir, err))) return st;
    path = rs_io_join(opt->site_dir, RS_SITE_LANES);
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    // the built-in traffic needs the lanes; SUMO's frames do not (the lanes then only help to
    // find the road in a background, rs_synth_light_from_image)
    if (!rs_synth_dataset__file_exists(path) && !opt->traffic_frames_dir) {
        st = rs_err_set(err, RS_ERR_INVALID,
                        "%s: missing: the built-in traffic needs the site's "
                        "lanes (docs/traffic.md)",
                        path);
        goto done;
    }
    if (rs_synth_dataset__file_exists(path) && (st = rs_lanes_read(&d->lanes, path, d->site, err))) goto done;
    const int Nc = opt->Ncameras > 0 ? opt->Ncameras : d->site->Ncameras;
    d->cams = calloc((size_t)(Nc > 0 ? Nc : 1), sizeof(rs_synth_dataset__camera));
    if (!d->cams) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    for (int i = 0; i < Nc; i++) {
        const char *id = opt->Ncameras > 0 ? opt->cameras[i] : d->site->cameras[i].id;
        const int isite = rs_site_find_camera(d->site, id);
        if (isite < 0) {
            st = rs_err_set(err, RS_ERR_USAGE, "--camera: no camera \"%s\" in %s", id, opt->site_dir);
            goto done;
        }
        rs_synth_dataset__camera *c = &d->cams[d->Ncams++];
        c->id = id;
        char name[512];
        rs_camera_path(name, sizeof(name), NULL, id, RS_CAMERA_EXT_CAMERAMODEL);
        free(path);
        path = rs_io_join(opt->calib_dir, name);
        if (!path) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            goto done;
        }
        c->calib_path = strdup(path);
        if (!c->calib_path) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            goto done;
        }
        if ((st = rs_camera_read(&c->cam, NULL, path, err)) ||
            (st = rs_hash_sha256_file(c->calib_sha256, NULL, path, err)) ||
            (st = scale_camera(&c->cam, opt->width, opt->height, id, err)) ||
            (st = select_backgrounds(c, &d->site->cameras[isite], opt, d->site, err)))
            goto done;
    }
    if (d->Ncams == 0) st = rs_err_set(err, RS_ERR_INVALID, "%s: no camera", opt->site_dir);
done:
    free(path);
    return st;
}

// calib's <id>.json (the pose and its covariance, calib/rs_calib_site.h) copied as it is beside
// the model into DATASET/cameras/, when the calibration folder has one: `roadside localise
// --dataset` reads the pose covariance from it (eval/localise/rs_localise_dataset.h). The pose
// does not change with --size, so the record holds for the scaled model too.
static rs_status copy_calibration_record(const char *id, const char *calib_dir, const char *cameras_dir, rs_err *err)
{
    char from[4096], to[4096];
    if (!rs_camera_path(from, sizeof from, calib_dir, id, ".json") ||
        !rs_camera_path(to, sizeof to, cameras_dir, id, ".json"))
        return rs_err_set(err, RS_ERR_INVALID, "%s: path too long", calib_dir);
    if (rs_io_check_regular(from, RS_IO_MAX_FILE_BYTES, NULL) != RS_OK) return RS_OK; // none: nothing to copy
    char *text = NULL;
    size_t len = 0;
    rs_status st = rs_io_read_file(&text, &len, from, err);
    if (!st) st = rs_io_write_file(to, text, len, err);
    free(text);
    return st;
}

// The camera each image's labels were projected with, at the output size, copied into
// DATASET/cameras/<id>.cameramodel (so that eval reads it from the dataset itself). A copy
// already there from an earlier run or another shard must be the same file: images made with
// another calibration or size must not be mixed into one dataset.
static rs_status write_camera_copies(rs_synth_dataset__run *d, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    char *dir = rs_io_join(opt->out_dir, "cameras");
    rs_status st = dir ? rs_io_mkdir_p(dir, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; i < d->Ncams && !st; i++) {
        rs_synth_dataset__camera *c = &d->cams[i];
        char name[300], tmp_name[360];
        snprintf(name, sizeof(name), "%.250s" RS_CAMERA_EXT_CAMERAMODEL, c->id);
        snprintf(tmp_name, sizeof(tmp_name), ".new.%ld.%s", (long)getpid(), name);
        snprintf(c->model_rel, sizeof(c->model_rel), "../cameras/%.300s", name);
        char *path = rs_io_join(dir, name), *tmp = rs_io_join(dir, tmp_name);
        char have[65] = "";
        if (!path || !tmp)
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        else if (!(st = rs_camera_write_cameramodel(&c->cam, tmp, err)) &&
                 !(st = rs_hash_sha256_file(c->model_sha256, NULL, tmp, err))) {
            if (rs_synth_dataset__file_exists(path) && !rs_hash_sha256_file(have, NULL, path, NULL) &&
                strcmp(have, c->model_sha256) != 0)
                st = rs_err_set(err, RS_ERR_INVALID,
                                "%s: %s holds images made with another camera model of %s (another "
                                "calibration or --size); use a new output folder",
                                path, opt->out_dir, c->id);
            else if (rename(tmp, path) != 0)
                st = rs_err_set(err, RS_ERR_IO, "%s: %s", path, strerror(errno));
        }
        if (!st) st = copy_calibration_record(c->id, opt->calib_dir, dir, err);
        if (tmp) (void)remove(tmp);
        free(path);
        free(tmp);
    }
    free(dir);
    return st;
}

// DATASET/run.json: {"run": every option that decides what an image is or where it goes,
// with each camera model's SHA-256, "shard": "I/N"}. A folder that holds another run's
// images (a different "run") is refused: images of different runs must not be mixed (merge
// refuses them too, rs_synth_dataset_merge).
// With SUMO's frames, "traffic_frames": {"frames", "vehicles", "sha256"} (the folder's content,
// rs_synth_traffic_frames_info) joins the run (so merge refuses shards of other traffic), and
// the folder's path is noted beside it (not compared: shards may read copies at other paths).
// With --models, "models": {"entries", "sha256"} (the library file's; not the model files')
// joins the run in the same way, its path beside it.
static rs_status write_run_record(const rs_synth_dataset__run *d, const rs_synth_traffic_frames_info *frames,
                                  rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    cJSON *doc = cJSON_CreateObject(), *run = cJSON_AddObjectToObject(doc, "run");
    cJSON_AddStringToObject(run, "contract", RS_SYNTH_DATASET_CONTRACT_VERSION);
    cJSON_AddNumberToObject(run, "count", opt->count);
    char seed[32];
    snprintf(seed, sizeof(seed), "%llu", (unsigned long long)opt->seed);
    cJSON_AddStringToObject(run, "seed", seed);
    cJSON_AddNumberToObject(run, "width", d->cams[0].cam.width);
    cJSON_AddNumberToObject(run, "height", d->cams[0].cam.height);
    cJSON *cams = cJSON_AddObjectToObject(run, "cameras"); // in image order: id -> model SHA-256
    cJSON *order = cJSON_AddArrayToObject(run, "camera_order");
    for (int i = 0; i < d->Ncams; i++) {
        cJSON_AddStringToObject(cams, d->cams[i].id, d->cams[i].model_sha256);
        cJSON_AddItemToArray(order, cJSON_CreateString(d->cams[i].id));
    }
    cJSON_AddNumberToObject(run, "vehicles", opt->vehicles);
    cJSON *bg = cJSON_AddArrayToObject(run, "backgrounds");
    for (int f = 0; f < opt->Nfilters; f++) {
        char kv[600];
        snprintf(kv, sizeof(kv), "%s=%s", opt->filter_keys[f], opt->filter_values[f]);
        cJSON_AddItemToArray(bg, cJSON_CreateString(kv));
    }
    cJSON_AddBoolToObject(run, "shadows", opt->shadows);
    cJSON_AddBoolToObject(run, "junction_traffic", opt->junction_traffic);
    if (opt->no_appearance) cJSON_AddBoolToObject(run, "appearance", false); // absent when on: older records equal
    if (opt->traffic_frames_dir) { // absent for the built-in traffic: older records stay equal
        cJSON *tf = cJSON_AddObjectToObject(run, "traffic_frames");
        cJSON_AddNumberToObject(tf, "frames", frames->Nframes);
        cJSON_AddNumberToObject(tf, "vehicles", (double)frames->Nvehicles);
        cJSON_AddStringToObject(tf, "sha256", frames->sha256);
        cJSON_AddStringToObject(doc, "traffic_frames_dir", opt->traffic_frames_dir);
    }
    if (opt->models_path) { // absent without a library: older records stay equal
        cJSON *ml = cJSON_AddObjectToObject(run, "models");
        cJSON_AddNumberToObject(ml, "entries", d->models.N);
        cJSON_AddStringToObject(ml, "sha256", d->models_sha256);
        cJSON_AddStringToObject(doc, "models_path", opt->models_path);
    }
    if (opt->sequence) { // absent otherwise: older records stay equal
        cJSON *seq = cJSON_AddObjectToObject(run, "sequence");
        cJSON_AddNumberToObject(seq, "frame_first", opt->frame_first);
        cJSON_AddNumberToObject(seq, "frame_end", opt->frame_end);
        cJSON_AddBoolToObject(seq, "labels_only", opt->labels_only);
    }
    cJSON_AddNumberToObject(run, "bbox", opt->bbox);
    cJSON_AddNumberToObject(run, "min_visibility", opt->min_visibility);
    cJSON_AddBoolToObject(run, "keep_invisible", opt->keep_invisible);
    cJSON_AddNumberToObject(run, "coarse_below_px", opt->coarse_below_px);
    cJSON_AddNumberToObject(run, "medium_below_px", opt->medium_below_px);
    cJSON_AddBoolToObject(run, "full_frame", opt->full_frame);
    cJSON_AddStringToObject(run, "split", opt->split);
    cJSON_AddStringToObject(run, "val_split", opt->val_split);
    cJSON_AddNumberToObject(run, "val_fraction", opt->val_fraction);
    cJSON *vc = cJSON_AddArrayToObject(run, "val_cameras");
    for (int i = 0; i < opt->Nval_cameras; i++) cJSON_AddItemToArray(vc, cJSON_CreateString(opt->val_cameras[i]));
    cJSON *vb = cJSON_AddArrayToObject(run, "val_backgrounds");
    for (int f = 0; f < opt->Nval_bg; f++) {
        char kv[600];
        snprintf(kv, sizeof(kv), "%s=%s", opt->val_bg_keys[f], opt->val_bg_values[f]);
        cJSON_AddItemToArray(vb, cJSON_CreateString(kv));
    }
    char shard[64];
    snprintf(shard, sizeof(shard), "%d/%d", opt->shard_index, opt->shard_count);
    cJSON *shards = cJSON_AddArrayToObject(doc, "shards");     // every shard run into this folder
    cJSON *finished = cJSON_AddArrayToObject(doc, "finished"); // those that finished (merge needs it)
    char *path = rs_io_join(opt->out_dir, "run.json"), *text = NULL, *old = NULL;
    rs_status st = path ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st && rs_synth_dataset__file_exists(path) && rs_io_read_file(&old, NULL, path, NULL) == RS_OK) {
        cJSON *prev = cJSON_Parse(old);
        cJSON *prun = cJSON_GetObjectItemCaseSensitive(prev, "run");
        const cJSON *x;
        if (prun && !cJSON_Compare(prun, run, 1))
            st = rs_err_set(err, RS_ERR_INVALID,
                            "%s: %s holds the images of another run (other options, seed, size or calibration); "
                            "use a new output folder",
                            path, opt->out_dir);
        cJSON_ArrayForEach(x, cJSON_GetObjectItemCaseSensitive(prev, "shards"))
        {
            if (cJSON_IsString(x) && strcmp(x->valuestring, shard) != 0)
                cJSON_AddItemToArray(shards, cJSON_CreateString(x->valuestring));
        }
        // the other shards' completion records stay; this shard's is withdrawn until it finishes
        cJSON_ArrayForEach(x, cJSON_GetObjectItemCaseSensitive(prev, "finished"))
        {
            if (cJSON_IsString(x) && strcmp(x->valuestring, shard) != 0)
                cJSON_AddItemToArray(finished, cJSON_CreateString(x->valuestring));
        }
        cJSON_Delete(prev);
    }
    cJSON_AddItemToArray(shards, cJSON_CreateString(shard));
    if (!st && !(text = cJSON_Print(doc))) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) st = rs_io_write_file(path, text, strlen(text), err);
    free(old);
    free(path);
    free(text);
    cJSON_Delete(doc);
    return st;
}

// Whether any image can go to the validation split.
static bool has_val(const rs_synth_dataset_options *opt)
{
    return opt->val_fraction > 0 || opt->Nval_cameras > 0 || opt->Nval_bg > 0;
}

// ---- the images of a shard: in this process, or in forked workers ----

// What a worker tells the parent after each image, in one write (atomic: < PIPE_BUF).
typedef struct {
    char kind;             // 'm' made, 'g' made over the grey ground, 's' skipped, 'e' error
    bool remade;           // made again: found finished but damaged (note says why)
    int status;            // rs_status of an error
    double seconds_povray; // of this image
    int condition;         // its background's condition (time_of_day x 3 + surface), -1 none
    char msg[400];         // an error's message
    char note[700];        // a resume notice, "" if none
} worker_report;

// Counts one image's report into *sum, passes its notice on and calls the progress callback.
static void count_report(const rs_synth_dataset_options *opt, rs_synth_dataset_summary *sum, const worker_report *rep,
                         bool progress)
{
    if (rep->note[0] && opt->notice) opt->notice(opt->notice_ctx, rep->note);
    sum->Nskipped += rep->kind == 's';
    sum->Nmade += rep->kind != 's';
    sum->Nremade += rep->remade;
    sum->Ngrey += rep->kind == 'g';
    if (rep->kind != 'e' && rep->condition >= 0 && rep->condition < 9) sum->Ncondition[rep->condition]++;
    sum->seconds_povray += rep->seconds_povray;
    if (progress && opt->progress)
        opt->progress(opt->progress_ctx, sum->Nmade + sum->Nskipped, sum->Nimages, sum->Nskipped);
}

// Makes the images at positions j, j + J, .. of the shard. With fd >= 0 (a worker) each image
// is reported through fd, else counted in *sum with the progress callback called.
static rs_status run_images(rs_synth_dataset__run *d, rs_synth_dataset_summary *sum, int j, int J, int fd, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    rs_status st = RS_OK;
    char name[400];
    int pos = 0;
    for (int k = opt->shard_index; k < opt->count && !st; k += opt->shard_count, pos++) {
        if (pos % J != j) continue;
        rs_synth_dataset__camera *c = &d->cams[k % d->Ncams];
        char stem[300];
        rs_synth_dataset__stem(stem, sizeof(stem), k, c->id);
        snprintf(name, sizeof(name), "%s.json", stem);
        char *part = rs_io_join(d->parts_dir, name);
        if (!part) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            break;
        }
        worker_report rep = {.kind = 's', .condition = -1};
        rs_synth_dataset__state state;
        char why[600];
        st = rs_synth_dataset__check_finished(&state, why, sizeof(why), d, stem, c,
                                              rs_synth_dataset__image_split(d, k, c), err);
        if (!st && state == RS_SYNTH_DATASET__DAMAGED) {
            // unfinished from now on: an interruption of the remake leaves it to the next run
            (void)remove(part); // (a folder in its place, if not empty, stops the remake's rename)
            rep.remade = true;
            snprintf(rep.note, sizeof(rep.note), "%s: remaking image %d", why, k);
        }
        const int ib = rs_synth_dataset__image_background(d, k, c); // its condition, for the mix
        if (ib >= 0 && c->bg[ib].cond_known)
            rep.condition = 3 * (int)c->bg[ib].cond.time_of_day + (int)c->bg[ib].cond.surface;
        if (!st && state != RS_SYNTH_DATASET__FINISHED) {
            bool grey = false;
            st = rs_synth_dataset__make_image(d, k, stem, c, &grey, &rep.condition, &rep.seconds_povray, err);
            rep.kind = grey ? 'g' : 'm';
        }
        if (st) rep.kind = 'e';
        free(part);
        if (fd >= 0) {
            if (st) {
                rep.status = st;
                snprintf(rep.msg, sizeof(rep.msg), "%.399s", err ? err->msg : "");
            }
            if (write(fd, &rep, sizeof(rep)) != (ssize_t)sizeof(rep)) return RS_ERR_IO; // the parent is gone
            continue;
        }
        if (st) {
            if (rep.note[0] && opt->notice) opt->notice(opt->notice_ctx, rep.note);
            break;
        }
        count_report(opt, sum, &rep, true);
    }
    return st;
}

// ---- what the workers share, prepared by the parent before it forks them ----

// The most background memory the parent prepares for its workers (12 bytes per pixel each:
// 129 backgrounds at 720x480); past it a worker prepares what its images need itself.
#define SHARED_BACKGROUND_BYTES ((size_t)512 << 20)

// The camera of the first image of worker j's share (positions j, j + J, ..), -1 if none.
static int worker_camera(const rs_synth_dataset__run *d, int j, int J)
{
    const rs_synth_dataset_options *opt = d->opt;
    int pos = 0;
    for (int k = opt->shard_index; k < opt->count; k += opt->shard_count, pos++)
        if (pos % J == j) return k % d->Ncams;
    return -1;
}

// Prepares, in this process, what the images of worker j's share that are to be made (no
// parts/<stem>.json yet) need: their camera's canvas map and their background
// (rs_synth_dataset__prepare_camera, rs_synth_dataset__prepare_background), so that the
// worker forked next inherits them (copy-on-write) instead of computing its own, as every
// worker of the same camera did before (issue 18: 0.28 s of canvas map, 0.08 s of road pixels
// and about 0.05 s per background, in each of 8 workers). Errors are left for the worker to
// meet and report with its image; nothing is kept of a failed preparation. *bg_bytes counts
// the background memory prepared (SHARED_BACKGROUND_BYTES at most).
static void prepare_for_worker(rs_synth_dataset__run *d, int j, int J, size_t *bg_bytes)
{
    const rs_synth_dataset_options *opt = d->opt;
    char stem[300], name[400];
    int pos = 0;
    for (int k = opt->shard_index; k < opt->count; k += opt->shard_count, pos++) {
        if (pos % J != j) continue;
        rs_synth_dataset__camera *c = &d->cams[k % d->Ncams];
        rs_synth_dataset__stem(stem, sizeof(stem), k, c->id);
        snprintf(name, sizeof(name), "%s.json", stem);
        char *part = rs_io_join(d->parts_dir, name);
        const bool finished = !part || rs_synth_dataset__file_exists(part);
        free(part);
        rs_err e = {RS_OK, ""};
        if (finished || rs_synth_dataset__prepare_camera(c, &e) != RS_OK) continue;
        const int b = rs_synth_dataset__image_background(d, k, c);
        if (b < 0 || opt->labels_only || c->bg[b].linear.data) continue; // (labels alone: never decoded)
        const size_t bytes = (size_t)12 * (size_t)c->cam.width * (size_t)c->cam.height;
        if (*bg_bytes + bytes > SHARED_BACKGROUND_BYTES) continue;
        if (rs_synth_dataset__prepare_background(d, c, &c->bg[b], &e) == RS_OK) *bg_bytes += bytes;
    }
}

// opt->jobs forked workers, each running run_images on its share and reporting through a
// pipe; the parent counts, calls the progress callback, and returns the first error (the
// other workers go on to the end of their share: finished images are kept either way).
static rs_status run_workers(rs_synth_dataset__run *d, rs_synth_dataset_summary *sum, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    const int J = opt->jobs < sum->Nimages ? opt->jobs : sum->Nimages;
    int fds[2];
    if (pipe(fds) != 0) return rs_err_set(err, RS_ERR_IO, "synth: pipe: %s", strerror(errno));
    pid_t *pids = calloc((size_t)J, sizeof(pid_t));
    if (!pids) {
        close(fds[0]);
        close(fds[1]);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    rs_status st = RS_OK;
    int started = 0;
    // The workers forked camera by camera (those whose share starts with camera 0 first, ..):
    // what the parent prepares for one is then there for the next of the same camera, and the
    // one-camera cache of road pixels (rs_synth_light_from_image) is filled once per camera.
    // Which worker makes an image does not change the image.
    int *order = calloc((size_t)J, sizeof(int));
    if (!order) {
        free(pids);
        close(fds[0]);
        close(fds[1]);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    int Norder = 0;
    for (int cam = -1; cam < d->Ncams; cam++)
        for (int j = 0; j < J; j++)
            if (worker_camera(d, j, J) == cam) order[Norder++] = j;
    size_t bg_bytes = 0;
    const pid_t parent = getpid();
    for (int o = 0; o < J; o++, started++) {
        const int j = order[o];
        prepare_for_worker(d, j, J, &bg_bytes);
        fflush(NULL);
        pids[o] = fork(); // (in fork order)
        if (pids[o] < 0) {
            st = rs_err_set(err, RS_ERR_IO, "synth: fork: %s", strerror(errno));
            break;
        }
        if (pids[o] == 0) {
            // a worker dies with the parent: a killed `roadside synth` leaves nothing running
            // that could race a rerun on the same images
            if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != parent) _exit(1);
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
        rep.msg[sizeof(rep.msg) - 1] = 0;
        rep.note[sizeof(rep.note) - 1] = 0;
        if (rep.kind == 'e') {
            if (rep.note[0] && opt->notice) opt->notice(opt->notice_ctx, rep.note);
            if (!failed) {
                st = rs_err_set(err, (rs_status)rep.status, "%s", rep.msg);
                failed = true; // the other workers finish their share (resumable work)
            }
            continue;
        }
        count_report(opt, sum, &rep, !failed);
    }
    close(fds[0]);
    for (int o = 0; o < started; o++) {
        int ws = 0;
        while (waitpid(pids[o], &ws, 0) < 0 && errno == EINTR) {}
        if (!st && !(WIFEXITED(ws) && WEXITSTATUS(ws) == 0))
            st = rs_err_set(err, RS_ERR_EXTERNAL, "synth: worker %d of %d ended with %s %d", order[o], J,
                            WIFSIGNALED(ws) ? "signal" : "status", WIFSIGNALED(ws) ? WTERMSIG(ws) : WEXITSTATUS(ws));
    }
    free(order);
    free(pids);
    return st;
}

// A sequence's frames [frame_first, frame_end) checked against the frames read; sets o->count.
static rs_status sequence_range(rs_synth_dataset_options *o, const rs_synth_dataset__run *d, rs_err *err)
{
    if (o->frame_end < 0) o->frame_end = d->Nframes;
    if (o->frame_first < 0 || o->frame_first >= o->frame_end || o->frame_end > d->Nframes)
        return rs_err_set(err, RS_ERR_USAGE, "--frames %d:%d: not a range of the %d frames of %s/frames.json",
                          o->frame_first, o->frame_end, d->Nframes, o->traffic_frames_dir);
    if ((long)(o->frame_end - o->frame_first) * d->Ncams > 100000000)
        return rs_err_set(err, RS_ERR_USAGE, "--sequence: more than 10^8 images");
    o->count = (o->frame_end - o->frame_first) * d->Ncams;
    return RS_OK;
}

// After a sequence's images: DATASET/tracks_gt.csv when every image of it is finished (a shard
// whose siblings are still running leaves it to the last). out: *written
static rs_status sequence_tracks(bool *written, const rs_synth_dataset__run *d, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    *written = false;
    char stem[300], name[400];
    for (int k = 0; k < opt->count; k++) {
        rs_synth_dataset__stem(stem, sizeof(stem), k, d->cams[k % d->Ncams].id);
        snprintf(name, sizeof(name), "%s.json", stem);
        char *part = rs_io_join(d->parts_dir, name);
        const bool there = part && rs_synth_dataset__file_exists(part);
        free(part);
        if (!there) return RS_OK;
    }
    const char **ids = malloc(sizeof(char *) * (size_t)d->Ncams);
    if (!ids) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; i < d->Ncams; i++) ids[i] = d->cams[i].id;
    rs_status st =
        rs_synth_dataset_tracks_gt_write(NULL, opt->out_dir, opt->traffic_frames_dir, opt->frame_first, opt->frame_end,
                                         ids, d->Ncams, d->site->ground_normal_enu, d->site->ground_offset_m, err);
    free(ids);
    *written = !st;
    return st;
}

rs_status rs_synth_dataset_run(rs_synth_dataset_summary *summary, const rs_synth_dataset_options *opt_in, rs_err *err)
{
    rs_synth_dataset_summary sum = {0};
    const double t0 = now_s();
    if (opt_in && opt_in->sequence && !opt_in->traffic_frames_dir)
        return rs_err_set(err, RS_ERR_USAGE, "--sequence needs --traffic-frames DIR");
    if (opt_in && opt_in->labels_only && !opt_in->sequence)
        return rs_err_set(err, RS_ERR_USAGE, "--labels-only is for sequences (--sequence)");
    rs_synth_dataset_options o = opt_in ? *opt_in : (rs_synth_dataset_options){0};
    const rs_synth_dataset_options *opt = opt_in ? &o : NULL;
    if (opt && opt->sequence) o.count = 1; // set from the frames once they are read
    if (!opt || !opt->site_dir || !opt->calib_dir || !opt->out_dir || opt->count < 1 || opt->shard_count < 1 ||
        opt->shard_index < 0 || opt->shard_index >= opt->shard_count || opt->vehicles < 0 || !opt->split ||
        !opt->val_split || strcmp(opt->split, opt->val_split) == 0 || !(opt->val_fraction >= 0) ||
        !(opt->val_fraction <= 1) || !(opt->min_visibility >= 0) || !(opt->min_visibility <= 1))
        return rs_err_set(err, RS_ERR_INVALID,
                          "synth: bad options (count >= 1, shard I/N with 0 <= I < N, site, calib and "
                          "output folders required, two different split names, fractions in [0, 1])");
    rs_synth_dataset__run d = {.opt = opt};
    rs_io_lock lock = {0};
    char name[600];
    rs_synth_traffic_frames_info frames = {0};
    rs_status st = dataset_load(&d, err);
    // SUMO's frames, every one read and checked before DATASET is touched
    if (!st && opt->traffic_frames_dir) st = rs_synth_dataset__frames_load(&d, &frames, err);
    if (!st && opt->models_path) st = rs_synth_dataset__models_load(&d, err);
    if (!st && opt->sequence) st = sequence_range(&o, &d, err);
    if (st) goto done;
    d.val_fallback = rs_synth_dataset__val_fallback(&d);
    // One run per dataset folder: a second one would remake the same images in the same work/
    // folders. The lock is taken before anything in DATASET is touched (but DATASET itself).
    // DATASET must be roadside's (issue 42): a folder of anything else is refused, untouched
    if ((st = rs_synth_dataset__claim_folder(opt->out_dir, "roadside synth", err))) goto done;
    if ((st = rs_io_lock_dir(&lock, opt->out_dir, "roadside synth", err))) goto done;
    d.split[0] = opt->split;
    d.split[1] = opt->val_split;
    // a run killed while writing a file leaves its temporary; no writer is left to finish it
    rs_synth_dataset__remove_temporaries(opt->out_dir, d.split, 2);
    d.parts_dir = rs_io_join(opt->out_dir, "parts");
    d.work_root = rs_io_join(opt->out_dir, "work");
    if (!d.parts_dir || !d.work_root) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    // the folders of each split that can receive images: COCO's <split>/, YOLO's images/<split>
    // and labels/<split>, KITTI's kitti/training/{image_2,label_2,calib}
    for (int s = 0; s < (has_val(opt) ? 2 : 1) && !st; s++) {
        const char *sub[3] = {"%s", "images/%s", "labels/%s"};
        for (int j = 0; j < 3 && !st; j++) {
            snprintf(name, sizeof(name), sub[j], d.split[s]);
            char *dir = rs_io_join(opt->out_dir, name);
            st = dir ? rs_io_mkdir_p(dir, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            if (j == 0 && !st)
                d.split_dir[s] = dir;
            else
                free(dir);
        }
    }
    const char *const common[] = {
        "parts",          "annotations", "kitti/training/image_2", "kitti/training/label_2", "kitti/training/calib",
        "kitti/ImageSets"};
    for (size_t j = 0; j < sizeof(common) / sizeof(common[0]) && !st; j++) {
        char *dir = rs_io_join(opt->out_dir, common[j]);
        st = dir ? rs_io_mkdir_p(dir, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(dir);
    }
    if (!st) st = write_camera_copies(&d, err);
    if (!st) st = write_run_record(&d, &frames, err);
    if (!st) st = rs_synth_dataset__models_cache(&d, err);
    if (st) goto done;
    for (int k = opt->shard_index; k < opt->count; k += opt->shard_count) sum.Nimages++;
    st = opt->jobs > 1 && sum.Nimages > 1 ? run_workers(&d, &sum, err) : run_images(&d, &sum, 0, 1, -1, err);
    if (!st && !opt->labels_only) st = rs_synth_dataset__write_looks(&d, err);
    if (!st) {
        st = rs_synth_dataset__assemble(&d, &sum.Nannotations, &sum.Nleft_out, err);
        rs_synth_dataset__models_uncache(&d);
        rmdir(d.work_root); // empty when every image finished
    }
    if (!st && opt->sequence) st = sequence_tracks(&sum.tracks_gt, &d, err);
    if (!st) st = rs_synth_dataset__write_completion(&d, sum.Ncondition, err); // the completion record, last
done:
    rs_io_unlock(&lock);
    dataset_free(&d);
    sum.seconds = now_s() - t0;
    if (summary) *summary = sum;
    return st;
}
