// rs_pick_session.c -- the picking session: one camera's picks and the site's landmarks edited in
// memory, re-solved by calib after every change, saved through geo's writers (rs_pick.h).
#include "pick/rs_pick.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include <cjson/cJSON.h>
#include <mrcal/mrcal.h>

#include "audit/rs_audit.h"
#include "calib/rs_calib.h"
#include "calib/rs_calib_site.h"
#include "core/rs_camera.h"
#include "core/rs_index.h"
#include "core/rs_io.h"
#include "geo/rs_geo.h"
#include "geo/rs_site.h"
#include "geo/rs_site_import.h"
#include "geo/rs_site_write.h"
#include "pick/internal/rs_pick_internal.h"

static file_stamp stamp_of(const char *path)
{
    struct stat st;
    file_stamp f = {0};
    if (path && stat(path, &st) == 0) f = (file_stamp){true, st.st_dev, st.st_ino, st.st_size, st.st_mtim};
    return f;
}

static bool stamp_same(const file_stamp *a, const file_stamp *b)
{
    return a->exists == b->exists &&
           (!a->exists || (a->dev == b->dev && a->ino == b->ino && a->size == b->size &&
                           a->mtime.tv_sec == b->mtime.tv_sec && a->mtime.tv_nsec == b->mtime.tv_nsec));
}

static double now_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

static rs_site_camera *cam_of(rs_pick_session *s) { return &s->site->cameras[s->icam]; }

// The covariance of the camera centre C = -R^T t (the translation of rt_enu_cam) from rt's
// covariance: J = d C / d rt_cam_enu (3,6) from mrcal_invert_rt's gradients, Sigma_C = J Sigma J^T.
static void position_covariance(double cov_en[4], const rs_calib_result *r)
{
    double rt_in[6], rt_inv[6], dt_dr[9], dt_dt[9];
    memcpy(rt_in, r->rt_cam_enu, sizeof rt_in);
    mrcal_invert_rt(rt_inv, dt_dr, dt_dt, rt_in);
    double J[3][6];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) J[i][j] = dt_dr[3 * i + j], J[i][3 + j] = dt_dt[3 * i + j];
    double JS[3][6] = {{0}};
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 6; k++)
            for (int j = 0; j < 6; j++) JS[i][k] += J[i][j] * r->covariance_rt_cam_enu[j * 6 + k];
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++) {
            double v = 0;
            for (int k = 0; k < 6; k++) v += JS[a][k] * J[b][k];
            cov_en[2 * a + b] = v;
        }
}

rs_status rs_pick_session_solve(rs_pick_session *s)
{
    const double t0 = now_ms();
    rs_calib_result_free(&s->result);
    free(s->predicted_px);
    s->predicted_px = NULL;
    s->Npredicted = 0;
    s->solved = false;
    s->solve_message[0] = '\0';
    rs_site_camera *cam = cam_of(s);
    rs_err err = {0};
    if (cam->Nobservations < 4) {
        s->solve_status = RS_ERR_DEGENERATE;
        snprintf(s->solve_message, sizeof s->solve_message, "%d pick%s: the camera is solved from 4 picks on",
                 cam->Nobservations, cam->Nobservations == 1 ? "" : "s");
        s->solve_ms = now_ms() - t0;
        return s->solve_status;
    }
    // exactly as `roadside calib` (cli/cmd_calib.c): the site's problem, the default options
    rs_calib_site_problem sp;
    rs_calib_options opt;
    rs_calib_options_default(&opt);
    opt.refine = s->refine;
    rs_status st = rs_calib_site_problem_init(&sp, s->site, s->icam, &err);
    if (!st) st = rs_calib_solve(&s->result, &sp.problem, &opt, &err);
    rs_calib_site_problem_free(&sp);
    s->solve_status = st;
    if (st) {
        rs_calib_result_free(&s->result);
        snprintf(s->solve_message, sizeof s->solve_message, "%s", err.msg[0] ? err.msg : rs_strerror(st));
        s->solve_ms = now_ms() - t0;
        return st;
    }
    s->solved = true;
    // every landmark's surveyed position through the calibrated camera
    const rs_camera calibrated = rs_calib_result_camera(&cam->camera, &s->result);
    const int NL = s->site->Nlandmarks;
    double *p = malloc(sizeof(double) * 3 * (size_t)(NL > 0 ? NL : 1));
    s->predicted_px = malloc(sizeof(double) * 2 * (size_t)(NL > 0 ? NL : 1));
    if (p && s->predicted_px) {
        for (int i = 0; i < NL; i++) memcpy(&p[3 * i], s->site->landmarks[i].p_enu_m, sizeof(double) * 3);
        rs_camera_project(s->predicted_px, &calibrated, p, NL);
        s->Npredicted = NL;
    }
    free(p);
    position_covariance(s->cov_en_m2, &s->result);
    // the ground uncertainty over the view: a vehicle detected to 1 px, located on the ground plane
    const int W = cam->camera.width > 0 ? cam->camera.width : 1920,
              H = cam->camera.height > 0 ? cam->camera.height : 1080;
    for (int j = 0; j < GROUND_NV; j++)
        for (int i = 0; i < GROUND_NU; i++) {
            const double q[2] = {(i + 0.5) * W / GROUND_NU - 0.5, (j + 0.5) * H / GROUND_NV - 0.5};
            double sigma = NAN;
            if (rs_audit_ground_sigma(&sigma, NULL, NULL, &calibrated, s->result.covariance_rt_cam_enu, q, 1.0,
                                      s->site->ground_normal_enu, s->site->ground_offset_m, NULL) != RS_OK)
                sigma = NAN;
            s->ground_sigma_m[j][i] = sigma;
        }
    s->solve_ms = now_ms() - t0;
    return RS_OK;
}

// Records what is on disk now as what the session has read.
static rs_status stamp_files(rs_pick_session *s, rs_err *err)
{
    char *landmarks = rs_io_join(s->site_dir, RS_SITE_LANDMARKS);
    if (!landmarks) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    s->on_disk[0] = stamp_of(landmarks);
    s->on_disk[1] = stamp_of(cam_of(s)->observations_path);
    s->Nloaded = s->site->Nlandmarks;
    free(landmarks);
    return RS_OK;
}

rs_status rs_pick_session_open(rs_pick_session **out, const char *site_dir, const char *camera_id, rs_err *err)
{
    *out = NULL;
    rs_pick_session *s = calloc(1, sizeof *s);
    if (!s) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    s->site_dir = strdup(site_dir);
    s->camera_id = strdup(camera_id);
    if (!s->site_dir || !s->camera_id) {
        rs_pick_session_free(s);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    rs_status st = rs_site_load_for_picking(&s->site, site_dir, err);
    if (st) {
        rs_pick_session_free(s);
        return st;
    }
    s->icam = rs_site_find_camera(s->site, camera_id);
    if (s->icam < 0) {
        rs_pick_session_free(s);
        return rs_err_set(err, RS_ERR_NOT_FOUND, "%s: no camera '%s' in site.json", site_dir, camera_id);
    }
    if ((st = stamp_files(s, err))) {
        rs_pick_session_free(s);
        return st;
    }
    (void)rs_pick_session_solve(s);
    *out = s;
    return RS_OK;
}

static void snapshot_free(snapshot *sn)
{
    free(sn->obs);
    memset(sn, 0, sizeof *sn);
}

void rs_pick_session_free(rs_pick_session *s)
{
    if (!s) return;
    for (int i = 0; i < s->Nundo; i++) snapshot_free(&s->undo[i]);
    free(s->undo);
    rs_calib_result_free(&s->result);
    free(s->predicted_px);
    rs_site_free(s->site);
    free(s->site_dir);
    free(s->camera_id);
    free(s);
}

// Pushes the state before a change.
static rs_status push_undo(rs_pick_session *s, rs_err *err)
{
    if (s->Nundo == s->cap_undo) {
        const int cap = s->cap_undo ? 2 * s->cap_undo : 16;
        snapshot *u = realloc(s->undo, sizeof *u * (size_t)cap);
        if (!u) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        s->undo = u;
        s->cap_undo = cap;
    }
    rs_site_camera *cam = cam_of(s);
    snapshot *sn = &s->undo[s->Nundo];
    sn->obs = malloc(sizeof *sn->obs * (size_t)(cam->Nobservations > 0 ? cam->Nobservations : 1));
    if (!sn->obs) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (cam->Nobservations) memcpy(sn->obs, cam->observations, sizeof *sn->obs * (size_t)cam->Nobservations);
    sn->Nobs = cam->Nobservations;
    sn->Nlandmarks = s->site->Nlandmarks;
    sn->edited = -1;
    s->Nundo++;
    return RS_OK;
}

static void landmark_free(rs_site_landmark *l)
{
    free(l->id);
    free(l->kind);
    free(l->note);
    free(l->vertices_enu_m);
    free(l->vertices_llh);
    free(l->vertices_sigma_v_m);
    free(l->vertices_given_h_m);
    memset(l, 0, sizeof *l);
}

// Puts a point landmark at p (ENU) / llh.
static void place_landmark(rs_site_landmark *l, const double p[3], rs_llh llh)
{
    memcpy(l->p_enu_m, p, sizeof l->p_enu_m);
    l->llh = llh;
    l->given_h_m = llh.h_m;
    l->given_up_m = p[2];
    if (l->Nvertices >= 1 && l->vertices_enu_m && l->vertices_llh) {
        memcpy(l->vertices_enu_m, p, sizeof l->p_enu_m);
        l->vertices_llh[0] = llh;
        if (l->vertices_given_h_m) l->vertices_given_h_m[0] = llh.h_m;
    }
}

rs_status rs_pick_undo(rs_pick_session *s, rs_err *err)
{
    if (s->Nundo == 0) return rs_err_set(err, RS_ERR_NOT_FOUND, "nothing to undo");
    snapshot *sn = &s->undo[--s->Nundo];
    rs_site_camera *cam = cam_of(s);
    free(cam->observations);
    cam->observations = sn->obs;
    cam->Nobservations = sn->Nobs;
    sn->obs = NULL;
    if (sn->edited >= 0 && sn->edited < s->site->Nlandmarks) {
        rs_site_landmark *l = &s->site->landmarks[sn->edited], b = sn->before;
        b.id = l->id, b.kind = l->kind, b.note = l->note; // the live allocations
        b.vertices_enu_m = l->vertices_enu_m, b.vertices_llh = l->vertices_llh;
        b.vertices_sigma_v_m = l->vertices_sigma_v_m, b.vertices_given_h_m = l->vertices_given_h_m;
        *l = b;
        place_landmark(l, b.p_enu_m, b.llh);
        if (l->vertices_sigma_v_m) l->vertices_sigma_v_m[0] = sn->before_sigma_v_m;
    }
    while (s->site->Nlandmarks > sn->Nlandmarks) landmark_free(&s->site->landmarks[--s->site->Nlandmarks]);
    s->dirty = true;
    (void)rs_pick_session_solve(s);
    return RS_OK;
}

static int find_pick(const rs_site_camera *cam, int il)
{
    for (int i = 0; i < cam->Nobservations; i++)
        if (cam->observations[i].ilandmark == il && cam->observations[i].at != RS_SITE_AT_TOP) return i;
    return -1;
}

rs_status rs_pick_set(rs_pick_session *s, const char *id, double u, double v, rs_err *err)
{
    const int il = rs_site_find_landmark(s->site, id);
    if (il < 0) return rs_err_set(err, RS_ERR_NOT_FOUND, "landmark '%s': no such landmark", id);
    if (s->site->landmarks[il].shape == RS_SITE_LINE)
        return rs_err_set(err, RS_ERR_UNSUPPORTED,
                          "landmark '%s': a line is picked along it, which calib does not use yet", id);
    rs_site_camera *cam = cam_of(s);
    const double W = cam->camera.width > 0 ? cam->camera.width : 1e5,
                 H = cam->camera.height > 0 ? cam->camera.height : 1e5;
    if (!isfinite(u) || !isfinite(v) || u < -W || u > 2 * W || v < -H || v > 2 * H)
        return rs_err_set(err, RS_ERR_INVALID, "pick (%g, %g): not a pixel of the %gx%g image", u, v, W, H);
    // the resolution of the observations file (%.6f): what is solved is what is saved
    char buf[64];
    snprintf(buf, sizeof buf, "%.6f", u);
    u = strtod(buf, NULL);
    snprintf(buf, sizeof buf, "%.6f", v);
    v = strtod(buf, NULL);
    rs_status st = push_undo(s, err);
    if (st) return st;
    int k = find_pick(cam, il);
    if (k < 0) {
        rs_site_observation *o = realloc(cam->observations, sizeof *o * (size_t)(cam->Nobservations + 1));
        if (!o) {
            snapshot_free(&s->undo[--s->Nundo]);
            return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        }
        cam->observations = o;
        k = cam->Nobservations++;
        o[k] = (rs_site_observation){.ilandmark = il,
                                     .sigma_px = 1.0,
                                     .line = 0,
                                     .at = s->site->landmarks[il].shape == RS_SITE_POLE ? RS_SITE_AT_BASE
                                                                                        : RS_SITE_AT_POINT};
    }
    cam->observations[k].q_px[0] = u;
    cam->observations[k].q_px[1] = v;
    s->dirty = true;
    (void)rs_pick_session_solve(s);
    return RS_OK;
}

rs_status rs_pick_delete(rs_pick_session *s, const char *id, rs_err *err)
{
    const int il = rs_site_find_landmark(s->site, id);
    rs_site_camera *cam = cam_of(s);
    const int k = il < 0 ? -1 : find_pick(cam, il);
    if (k < 0) return rs_err_set(err, RS_ERR_NOT_FOUND, "landmark '%s': no pick to delete", id);
    rs_status st = push_undo(s, err);
    if (st) return st;
    memmove(&cam->observations[k], &cam->observations[k + 1],
            sizeof *cam->observations * (size_t)(cam->Nobservations - k - 1));
    cam->Nobservations--;
    s->dirty = true;
    (void)rs_pick_session_solve(s);
    return RS_OK;
}

rs_status rs_pick_add_landmark(rs_pick_session *s, char id_out[32], double e, double n, rs_err *err)
{
    rs_site *site = s->site;
    const double lim = site->max_landmark_distance_m > 0 ? site->max_landmark_distance_m : 1000;
    if (!isfinite(e) || !isfinite(n) || hypot(e, n) > lim)
        return rs_err_set(err, RS_ERR_INVALID, "landmark at (%g, %g) m: not within %g m of the site's origin", e, n,
                          lim);
    char id[32];
    for (int k = 1;; k++) {
        snprintf(id, sizeof id, "P%d", k);
        if (rs_site_find_landmark(site, id) < 0) break;
    }
    const double *nn = site->ground_normal_enu;
    const double p[3] = {e, n, (site->ground_offset_m - nn[0] * e - nn[1] * n) / nn[2]};
    double llh[3];
    rs_status st = rs_geo_enu_to_llh(llh, &site->origin, p, 1, err);
    if (st) return st;
    rs_site_landmark l = {0};
    l.id = strdup(id);
    l.kind = strdup(RS_PICK_MAP_KIND);
    l.note = strdup("picked on the orthophoto by roadside pick; height from the site's ground plane");
    l.vertices_enu_m = malloc(sizeof(double) * 3);
    l.vertices_llh = malloc(sizeof(rs_llh));
    l.vertices_sigma_v_m = malloc(sizeof(double));
    l.vertices_given_h_m = malloc(sizeof(double));
    rs_site_landmark *ls = realloc(site->landmarks, sizeof *ls * (size_t)(site->Nlandmarks + 1));
    if (ls) site->landmarks = ls;
    if (!l.id || !l.kind || !l.note || !l.vertices_enu_m || !l.vertices_llh || !l.vertices_sigma_v_m ||
        !l.vertices_given_h_m || !ls) {
        landmark_free(&l);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    if ((st = push_undo(s, err))) {
        landmark_free(&l);
        return st;
    }
    l.feature = site->Nlandmarks;
    l.llh = (rs_llh){llh[0], llh[1], llh[2]};
    memcpy(l.p_enu_m, p, sizeof p);
    l.sigma_h_m = site->landmark_sigma_h_m;
    l.sigma_v_m = site->landmark_sigma_v_m;
    l.height_stated = RS_SITE_HEIGHT_DEFAULT;
    l.height = RS_SITE_HEIGHT_SURVEYED;
    l.given_h_m = llh[2];
    l.given_up_m = p[2];
    l.given_sigma_v_m = l.sigma_v_m;
    l.shape = RS_SITE_POINT;
    l.Nvertices = 1;
    memcpy(l.vertices_enu_m, p, sizeof p);
    l.vertices_llh[0] = l.llh;
    l.vertices_sigma_v_m[0] = l.sigma_v_m;
    l.vertices_given_h_m[0] = l.given_h_m;
    site->landmarks[site->Nlandmarks++] = l;
    if (id_out) snprintf(id_out, 32, "%s", id);
    s->dirty = true;
    (void)rs_pick_session_solve(s);
    return RS_OK;
}

// Moves the landmarks added in this session (those after s->Nloaded) onto `fresh`, the site as it
// is on disk now (another session has saved since this one read it), renaming any whose id is
// taken there, and points this camera's picks at fresh's landmarks by id. On success s->site is
// fresh (the undo history, whose landmark indices no longer hold, is dropped); on failure both
// are as they were but fresh is freed.
static rs_status merge_into(rs_pick_session *s, rs_site *fresh, rs_err *err)
{
    rs_site *site = s->site;
    const int icam = rs_site_find_camera(fresh, s->camera_id);
    const rs_site_camera *cam = cam_of(s);
    const int Nadded = site->Nlandmarks - s->Nloaded, N0 = fresh->Nlandmarks;
    rs_index ids = {0};
    rs_site_observation *obs = malloc(sizeof *obs * (size_t)(cam->Nobservations > 0 ? cam->Nobservations : 1));
    rs_site_landmark *ls = realloc(fresh->landmarks, sizeof *ls * (size_t)(N0 + Nadded > 0 ? N0 + Nadded : 1));
    if (ls) fresh->landmarks = ls;
    rs_status st = !obs || !ls ? rs_err_set(err, RS_ERR_NOMEM, "out of memory") : RS_OK;
    if (!st && icam < 0)
        st = rs_err_set(err, RS_ERR_INVALID, "%s: camera '%s' is no longer in site.json: not saved", s->site_dir,
                        s->camera_id);
    if (!st)
        st = rs_index_init_strided(&ids, (const char *const *)&fresh->landmarks[0].id, sizeof *fresh->landmarks, N0,
                                   false, err);
    // this camera's picks of landmarks read from disk must find them there still, by id
    for (int k = 0; !st && k < cam->Nobservations; k++) {
        obs[k] = cam->observations[k];
        const int il = obs[k].ilandmark;
        obs[k].ilandmark = il >= s->Nloaded ? N0 + il - s->Nloaded : rs_index_find(&ids, site->landmarks[il].id);
        if (obs[k].ilandmark < 0)
            st = rs_err_set(err, RS_ERR_INVALID,
                            "%s: landmark '%s', picked here, is no longer in landmarks.geojson (changed on disk since "
                            "this session read it): not saved",
                            s->site_dir, site->landmarks[il].id);
    }
    // an added landmark whose id another session took meanwhile gets the next free one
    char id[32];
    for (int k = 0; !st && k < Nadded; k++) {
        rs_site_landmark *l = &site->landmarks[s->Nloaded + k];
        if (rs_index_find(&ids, l->id) < 0) continue;
        for (int j = 1;; j++) {
            snprintf(id, sizeof id, "P%d", j);
            bool taken = rs_index_find(&ids, id) >= 0;
            for (int i = s->Nloaded; i < site->Nlandmarks && !taken; i++) taken = !strcmp(site->landmarks[i].id, id);
            if (!taken) break;
        }
        char *renamed = strdup(id);
        if (!renamed) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            break;
        }
        free(l->id);
        l->id = renamed;
    }
    rs_index_free(&ids);
    if (st) {
        free(obs);
        rs_site_free(fresh);
        return st;
    }
    for (int k = 0; k < Nadded; k++) {
        fresh->landmarks[N0 + k] = site->landmarks[s->Nloaded + k];
        fresh->landmarks[N0 + k].feature = N0 + k;
    }
    fresh->Nlandmarks = N0 + Nadded;
    site->Nlandmarks = s->Nloaded; // the added ones are fresh's now
    rs_site_camera *fc = &fresh->cameras[icam];
    free(fc->observations);
    fc->observations = obs;
    fc->Nobservations = cam->Nobservations;
    rs_site_free(site);
    s->site = fresh;
    s->icam = icam;
    for (int i = 0; i < s->Nundo; i++) snapshot_free(&s->undo[i]);
    s->Nundo = 0;
    return RS_OK;
}

rs_status rs_pick_save(rs_pick_session *s, rs_err *err)
{
    // one save at a time on a site, whoever saves (another `roadside pick`, of this camera or
    // another): the lock says who holds it
    char what[160];
    snprintf(what, sizeof what, "roadside pick (camera %.64s) saving", s->camera_id);
    rs_io_lock lock = {0};
    rs_status st = rs_io_lock_dir(&lock, s->site_dir, what, err);
    // held by another: a conflict the user resolves (saving again), not a failure of the disk
    if (st == RS_ERR_IO && err && strstr(err->msg, " is in use by ")) st = RS_ERR_INVALID;
    if (st) return st;
    // what is on disk must be what this session read, or merged with it
    char *landmarks = rs_io_join(s->site_dir, RS_SITE_LANDMARKS);
    if (!landmarks) {
        rs_io_unlock(&lock);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    const file_stamp now[2] = {stamp_of(landmarks), stamp_of(cam_of(s)->observations_path)};
    free(landmarks);
    if (!stamp_same(&now[1], &s->on_disk[1])) {
        rs_io_unlock(&lock);
        return rs_err_set(err, RS_ERR_INVALID,
                          "%s changed on disk since this session read it (another roadside pick of camera '%s'?): "
                          "not saved, so as not to overwrite it; stop this session and start roadside pick again",
                          cam_of(s)->observations_path, s->camera_id);
    }
    if (!stamp_same(&now[0], &s->on_disk[0])) {
        rs_site *fresh = NULL;
        if ((st = rs_site_load_for_picking(&fresh, s->site_dir, err)) || (st = merge_into(s, fresh, err))) {
            rs_err_prefix(err, "landmarks.geojson changed on disk since this session read it, and the merge failed");
            rs_io_unlock(&lock);
            return st;
        }
    }
    rs_site *site = s->site;
    const rs_site_camera *cam = cam_of(s);
    // landmarks first, then the observations: each atomic; landmarks are only ever added, so a
    // stop between the two leaves a consistent site (the old picks, the new landmarks)
    // a landmark's own sigmas only where it has them: the others keep following site.json's
    rs_site_landmark *out = malloc(sizeof *out * (size_t)(site->Nlandmarks > 0 ? site->Nlandmarks : 1));
    if (!out) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; out && i < site->Nlandmarks; i++) {
        out[i] = site->landmarks[i]; // shallow: the writer only reads
        if (!out[i].sigma_h_stated) out[i].sigma_h_m = NAN;
        if (!out[i].sigma_v_stated) out[i].sigma_v_m = out[i].given_sigma_v_m = NAN;
    }
    if (!st)
        st = rs_site_write_landmarks(site->dir, out, site->Nlandmarks, site->geoid_undulation_m, RS_SITE_LAYOUT_HAND,
                                     err);
    free(out);
    if (!st)
        st = rs_site_write_observations(cam->observations_path, cam->observations, cam->Nobservations, site->landmarks,
                                        err);
    // read back: the pose shown is the one `roadside calib` will find on these files
    rs_site *fresh = NULL;
    if (!st) st = rs_site_load_for_picking(&fresh, s->site_dir, err);
    const int icam = fresh ? rs_site_find_camera(fresh, s->camera_id) : -1;
    if (!st && (icam < 0 || fresh->Nlandmarks != site->Nlandmarks))
        st = rs_err_set(err, RS_ERR_INVALID, "%s: the site read back differs from the one saved", s->site_dir);
    if (st) {
        rs_site_free(fresh);
        rs_io_unlock(&lock);
        return st;
    }
    rs_site_free(s->site);
    s->site = fresh;
    s->icam = icam;
    st = stamp_files(s, err);
    rs_io_unlock(&lock);
    s->dirty = false;
    (void)rs_pick_session_solve(s);
    return st;
}

rs_status rs_pick_set_refine(rs_pick_session *s, const char *words, rs_err *err)
{
    unsigned flags = 0;
    if (!rs_calib_refine_parse(words, &flags))
        return rs_err_set(err, RS_ERR_INVALID, "refine '%.60s': expected focal, center or distortion, joined with '+'",
                          words);
    s->refine = flags;
    (void)rs_pick_session_solve(s);
    return RS_OK;
}

// Records landmark il's fields in the step just pushed, for rs_pick_undo.
static void remember_landmark(snapshot *sn, const rs_site_landmark *l, int il)
{
    sn->edited = il;
    sn->before = *l;
    sn->before_sigma_v_m = l->vertices_sigma_v_m ? l->vertices_sigma_v_m[0] : l->sigma_v_m;
}

rs_status rs_pick_set_sigma(rs_pick_session *s, const char *id, double sigma_h_m, double sigma_v_m, rs_err *err)
{
    rs_site *site = s->site;
    const int il = rs_site_find_landmark(site, id);
    if (il < 0) return rs_err_set(err, RS_ERR_NOT_FOUND, "landmark '%s': no such landmark", id);
    const double sig[2] = {sigma_h_m, sigma_v_m};
    for (int k = 0; k < 2; k++)
        if (!isnan(sig[k]) && !(sig[k] >= RS_SITE_SURVEY_SIGMA_MIN_M && sig[k] <= RS_SITE_SURVEY_SIGMA_MAX_M))
            return rs_err_set(err, RS_ERR_INVALID, "landmark '%s': %s %g m: not in [%g, %g] m", id,
                              k ? "sigma_v_m" : "sigma_h_m", sig[k], RS_SITE_SURVEY_SIGMA_MIN_M,
                              RS_SITE_SURVEY_SIGMA_MAX_M);
    rs_status st = push_undo(s, err);
    if (st) return st;
    rs_site_landmark *l = &site->landmarks[il];
    remember_landmark(&s->undo[s->Nundo - 1], l, il);
    l->sigma_h_stated = !isnan(sigma_h_m);
    l->sigma_h_m = l->sigma_h_stated ? sigma_h_m : site->landmark_sigma_h_m;
    l->sigma_v_stated = !isnan(sigma_v_m);
    const double v = l->sigma_v_stated ? sigma_v_m : site->landmark_sigma_v_m;
    l->given_sigma_v_m = v;
    if (!l->height_modelled) { // a modelled height keeps the model's sigma
        l->sigma_v_m = v;
        if (l->vertices_sigma_v_m) l->vertices_sigma_v_m[0] = v;
    }
    s->dirty = true;
    (void)rs_pick_session_solve(s);
    return RS_OK;
}

rs_status rs_pick_move_landmark(rs_pick_session *s, const char *id, double e, double n, rs_err *err)
{
    rs_site *site = s->site;
    const int il = rs_site_find_landmark(site, id);
    if (il < 0) return rs_err_set(err, RS_ERR_NOT_FOUND, "landmark '%s': no such landmark", id);
    rs_site_landmark *l = &site->landmarks[il];
    if (!l->kind || strcmp(l->kind, RS_PICK_MAP_KIND) != 0 || l->shape != RS_SITE_POINT)
        return rs_err_set(err, RS_ERR_UNSUPPORTED,
                          "landmark '%s': surveyed (kind %s): it stays where the survey put it; only landmarks "
                          "picked on the map (kind %s) move",
                          id, l->kind ? l->kind : "none", RS_PICK_MAP_KIND);
    const double lim = site->max_landmark_distance_m > 0 ? site->max_landmark_distance_m : 1000;
    if (!isfinite(e) || !isfinite(n) || hypot(e, n) > lim)
        return rs_err_set(err, RS_ERR_INVALID, "landmark at (%g, %g) m: not within %g m of the site's origin", e, n,
                          lim);
    const double *nn = site->ground_normal_enu;
    const double p[3] = {e, n, (site->ground_offset_m - nn[0] * e - nn[1] * n) / nn[2]};
    double llh[3];
    rs_status st = rs_geo_enu_to_llh(llh, &site->origin, p, 1, err);
    if (!st) st = push_undo(s, err);
    if (st) return st;
    remember_landmark(&s->undo[s->Nundo - 1], l, il);
    place_landmark(l, p, (rs_llh){llh[0], llh[1], llh[2]});
    s->dirty = true;
    (void)rs_pick_session_solve(s);
    return RS_OK;
}

rs_status rs_pick_import(rs_pick_session *s, int *Nadded, int *Npicked, const char *path, rs_err *err)
{
    *Nadded = *Npicked = 0;
    rs_site_import_points pts;
    rs_status st = rs_site_import_read_points(&pts, path, err);
    if (!st && !pts.geographic)
        st = rs_err_set(err, RS_ERR_INVALID,
                        "%s: e,n columns: pick imports lat,lon (a projected CRS needs 'roadside site import --crs')",
                        path);
    const int n0 = s->Nundo;
    for (int k = 0; !st && k < pts.N; k++) {
        const rs_site_import_point *q = &pts.points[k];
        if (rs_site_find_landmark(s->site, q->id) < 0) { // a new landmark there, on the ground plane
            const double llh[3] = {q->y, q->x, s->site->origin.h_m};
            double p[3];
            char gen[32];
            st = rs_geo_llh_to_enu(p, &s->site->origin, llh, 1, err);
            if (!st) st = rs_pick_add_landmark(s, gen, p[0], p[1], err);
            if (!st) {
                rs_site_landmark *l = &s->site->landmarks[s->site->Nlandmarks - 1];
                char *id = strdup(q->id);
                if (!id)
                    st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
                else {
                    free(l->id);
                    l->id = id;
                    ++*Nadded;
                }
            }
        }
        if (!st) st = rs_pick_set(s, q->id, q->q_px[0], q->q_px[1], err);
        if (!st) ++*Npicked;
        if (st && err) { // name the row
            char msg[sizeof err->msg];
            const int k0 = snprintf(msg, sizeof msg, "%.400s:%d: ", path, q->line);
            snprintf(msg + k0, sizeof msg - (size_t)k0, "%.*s", (int)(sizeof msg - (size_t)k0 - 1), err->msg);
            memcpy(err->msg, msg, sizeof msg);
        }
    }
    if (st) { // all or nothing
        while (s->Nundo > n0) (void)rs_pick_undo(s, NULL);
        *Nadded = *Npicked = 0;
    } else if (s->Nundo > n0 + 1) { // one step to undo: the state before the import
        for (int i = n0 + 1; i < s->Nundo; i++) snapshot_free(&s->undo[i]);
        s->Nundo = n0 + 1;
    }
    rs_site_import_points_free(&pts);
    return st;
}

double rs_pick_last_solve_ms(const rs_pick_session *s) { return s->solve_ms; }
int rs_pick_count(const rs_pick_session *s) { return s->site->cameras[s->icam].Nobservations; }

const rs_site *rs_pick_session_site(const rs_pick_session *s) { return s->site; }
int rs_pick_session_camera(const rs_pick_session *s) { return s->icam; }
