// rs_synth_dataset.c -- `roadside synth` (synth/rs_synth_dataset.h): the run. Loads the site
// through geo (rs_site_load: cameras, each camera's tagged backgrounds, lanes), the calibrated
// cameras, then makes this shard's images -- skipping finished ones (resume) -- in this process
// or in forked workers, and assembles DATASET's COCO file. Calls rs_synth_dataset_image.c (one
// image), rs_synth_dataset_coco.c (assembly), geo and core/.
#define _POSIX_C_SOURCE 200809L
#define _XOPEN_SOURCE   700
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <mrcal/mrcal.h>

#include "core/rs_io.h"
#include "synth/internal/rs_synth_dataset_internal.h"

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

// ---- the site's cameras and backgrounds ----

static void dataset_free(rs_synth_dataset__run *d)
{
    for (int i = 0; i < d->Ncams; i++) {
        rs_camera_free(&d->cams[i].cam);
        for (int b = 0; b < d->cams[i].Nbg; b++) {
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

// The backgrounds of the site's camera sc (site.json "background_images", read by geo) whose
// tags match every filter.
static rs_status select_backgrounds(rs_synth_dataset__camera *c, const rs_site_camera *sc,
                                    const rs_synth_dataset_options *opt, rs_err *err)
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
        const char *cond = rs_site_background_tag(e, "conditions");
        b->overcast = cond && strcmp(cond, "sunny") != 0;
        b->night = cond && strcmp(cond, "night") == 0;
    }
    return RS_OK;
}

static rs_status dataset_load(rs_synth_dataset__run *d, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    rs_status st;
    char *path = NULL;
    if ((st = rs_site_load(&d->site, opt->site_dir, err))) return st;
    path = rs_io_join(opt->site_dir, "lanes.geojson");
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!rs_synth_dataset__file_exists(path)) {
        st = rs_err_set(err, RS_ERR_INVALID,
                        "%s: missing: the built-in traffic needs the site's "
                        "lanes (docs/traffic.md)",
                        path);
        goto done;
    }
    if ((st = rs_lanes_read(&d->lanes, path, d->site, err))) goto done;
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
        snprintf(name, sizeof(name), "%s.cameramodel", id);
        free(path);
        path = rs_io_join(opt->calib_dir, name);
        if (!path) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            goto done;
        }
        if ((st = rs_camera_read(&c->cam, NULL, path, err)) ||
            (st = scale_camera(&c->cam, opt->width, opt->height, id, err)) ||
            (st = select_backgrounds(c, &d->site->cameras[isite], opt, err)))
            goto done;
    }
    if (d->Ncams == 0) st = rs_err_set(err, RS_ERR_INVALID, "%s: no camera", opt->site_dir);
done:
    free(path);
    return st;
}

// ---- the images of a shard: in this process, or in forked workers ----

// What a worker tells the parent after each image, in one write (atomic: < PIPE_BUF).
typedef struct {
    char kind;             // 'm' made, 'g' made over the grey ground, 's' skipped, 'e' error
    bool remade;           // made again: found finished but damaged (note says why)
    int status;            // rs_status of an error
    double seconds_povray; // of this image
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
        worker_report rep = {.kind = 's'};
        rs_synth_dataset__state state;
        char why[600];
        st = rs_synth_dataset__check_finished(&state, why, sizeof(why), d, stem, c, err);
        if (!st && state == RS_SYNTH_DATASET__DAMAGED) {
            // unfinished from now on: an interruption of the remake leaves it to the next run
            (void)remove(part); // (a folder in its place, if not empty, stops the remake's rename)
            rep.remade = true;
            snprintf(rep.note, sizeof(rep.note), "%s: remaking image %d", why, k);
        }
        if (!st && state != RS_SYNTH_DATASET__FINISHED) {
            bool grey = false;
            st = rs_synth_dataset__make_image(d, k, stem, c, &grey, &rep.seconds_povray, err);
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
    for (int j = 0; j < started; j++) {
        int ws = 0;
        while (waitpid(pids[j], &ws, 0) < 0 && errno == EINTR) {}
        if (!st && !(WIFEXITED(ws) && WEXITSTATUS(ws) == 0))
            st = rs_err_set(err, RS_ERR_EXTERNAL, "synth: worker %d of %d ended with %s %d", j, J,
                            WIFSIGNALED(ws) ? "signal" : "status", WIFSIGNALED(ws) ? WTERMSIG(ws) : WEXITSTATUS(ws));
    }
    free(pids);
    return st;
}

rs_status rs_synth_dataset_run(rs_synth_dataset_summary *summary, const rs_synth_dataset_options *opt, rs_err *err)
{
    rs_synth_dataset_summary sum = {0};
    const double t0 = now_s();
    if (!opt || !opt->site_dir || !opt->calib_dir || !opt->out_dir || opt->count < 1 || opt->shard_count < 1 ||
        opt->shard_index < 0 || opt->shard_index >= opt->shard_count || opt->vehicles < 0 || !opt->split)
        return rs_err_set(err, RS_ERR_INVALID,
                          "synth: bad options (count >= 1, shard I/N with "
                          "0 <= I < N, site, calib and output folders required)");
    rs_synth_dataset__run d = {.opt = opt};
    rs_io_lock lock = {0};
    char name[600];
    rs_status st = dataset_load(&d, err);
    if (st) goto done;
    // One run per dataset folder: a second one would remake the same images in the same work/
    // folders. The lock is taken before anything in DATASET is touched (but DATASET itself).
    if ((st = rs_io_mkdir_p(opt->out_dir, err))) goto done;
    if ((st = rs_io_lock_dir(&lock, opt->out_dir, "roadside synth", err))) goto done;
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
    if (st) goto done;
    for (int k = opt->shard_index; k < opt->count; k += opt->shard_count) sum.Nimages++;
    st = opt->jobs > 1 && sum.Nimages > 1 ? run_workers(&d, &sum, err) : run_images(&d, &sum, 0, 1, -1, err);
    if (!st) {
        st = rs_synth_dataset__assemble(&d, &sum.Nannotations, &sum.Nleft_out, err);
        rmdir(d.work_root); // empty when every image finished
    }
done:
    rs_io_unlock(&lock);
    dataset_free(&d);
    sum.seconds = now_s() - t0;
    if (summary) *summary = sum;
    return st;
}
