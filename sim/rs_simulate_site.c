// rs_simulate_site.c -- a whole simulated site on disk (rs_simulate_site, sim/rs_simulate.h):
// the options, the site's files written through geo (site.json, landmarks.geojson and the
// observations through geo/rs_site_write.h, lanes.geojson through geo/rs_lanes.h), the camera
// models through core (rs_camera_write_cameramodel), the truth/ folder, and the folder built
// aside and renamed into place. Calls rs_simulate_intersection.c, rs_simulate_lens.c, geo and
// core/.
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "geo/rs_site_write.h"
#include "sim/internal/rs_simulate_internal.h"

// The sigmas a site DECLARES are at least these (sites need sigmas > 0 to weight by), even when
// the noise actually drawn is zero; the noise drawn is recorded in site.json's "simulated".
#define DECLARED_SURVEY_SIGMA_MIN_M 1e-3
#define DECLARED_PIXEL_SIGMA_MIN_PX 1e-2

// ---------------------------------------------------------------------------------------------
// a whole site

void rs_simulate_site_options_default(rs_simulate_site_options *o)
{
    *o = (rs_simulate_site_options){
        .seed = 1,
        .Ncameras = 4,
        .landmarks_per_camera = 12,
        .lensmodel = "LENSMODEL_OPENCV8",
        .width_px = 1920,
        .height_px = 1080,
        .hfov_deg = 60,
        .pixel_sigma_px = 1,
        .survey_sigma_h_m = 0.3,
        .survey_sigma_v_m = 0.5,
        .outlier_fraction = 0.05,
        .focal_error = 1.0,
        .focal_error_range = 1.0,
        .pole_prior_sigma_m = 0,
        .elevated_fraction = 0.25,
        .origin = {.lat_deg = 48.1374, .lon_deg = 11.5755, .h_m = 560.0},
        .force = false,
        .height_noise_m = 0,
        .landmark_heights = RS_SITE_HEIGHT_DEFAULT,
        .poles_per_camera = 0,
        .lines_per_camera = 0,
    };
}

rs_status rs_simulate_site_options_check(const rs_simulate_site_options *o, rs_err *err)
{
    CHECK_OPTION(o->seed <= (1ULL << 53), "seed", "%llu", (unsigned long long)o->seed);
    CHECK_OPTION(o->Ncameras >= 1 && o->Ncameras <= 16, "cameras", "%d (1..16)", o->Ncameras);
    CHECK_OPTION(o->poles_per_camera >= 0 && o->poles_per_camera <= 50, "poles", "%d (0..50)", o->poles_per_camera);
    CHECK_OPTION(o->lines_per_camera >= 0 && o->lines_per_camera <= 20, "lines", "%d (0..20)", o->lines_per_camera);
    const bool shapes = o->poles_per_camera > 0 || o->lines_per_camera > 0;
    CHECK_OPTION(o->landmarks_per_camera >= (shapes ? 0 : 4) && o->landmarks_per_camera <= 100, "landmarks-per-camera",
                 "%d (4..100; 0..100 with poles or lines)", o->landmarks_per_camera);
    CHECK_OPTION(o->pixel_sigma_px >= 0 && o->pixel_sigma_px <= 20, "pixel-sigma", "%g (0..20 px)", o->pixel_sigma_px);
    CHECK_OPTION(o->survey_sigma_h_m >= 0 && o->survey_sigma_h_m <= 100, "survey-sigma", "horizontal %g (0..100 m)",
                 o->survey_sigma_h_m);
    CHECK_OPTION(o->survey_sigma_v_m >= 0 && o->survey_sigma_v_m <= 100, "survey-sigma", "vertical %g (0..100 m)",
                 o->survey_sigma_v_m);
    CHECK_OPTION(o->outlier_fraction >= 0 && o->outlier_fraction <= 0.9, "outliers", "%g (0..0.9)",
                 o->outlier_fraction);
    CHECK_OPTION(o->focal_error >= 0.5 && o->focal_error <= 2.0, "focal-error", "%g (0.5..2)", o->focal_error);
    CHECK_OPTION(o->focal_error_range >= 1.0 && o->focal_error_range <= 2.0, "focal-error-range", "%g (1..2)",
                 o->focal_error_range);
    CHECK_OPTION(o->pole_prior_sigma_m >= 0 && o->pole_prior_sigma_m <= 1000, "pole-prior", "%g (0..1000 m)",
                 o->pole_prior_sigma_m);
    CHECK_OPTION(o->elevated_fraction >= 0 && o->elevated_fraction <= 1, "elevated-fraction", "%g (0..1)",
                 o->elevated_fraction);
    CHECK_OPTION(o->height_noise_m >= 0 && o->height_noise_m <= 100, "height-noise", "%g (0..100 m)",
                 o->height_noise_m);
    CHECK_OPTION(o->landmark_heights >= RS_SITE_HEIGHT_DEFAULT && o->landmark_heights <= RS_SITE_HEIGHT_UNKNOWN,
                 "landmark-heights", "%d", (int)o->landmark_heights);
    CHECK_OPTION(isfinite(o->origin.lat_deg) && fabs(o->origin.lat_deg) <= 89.0, "origin", "latitude %g (-89..89)",
                 o->origin.lat_deg);
    CHECK_OPTION(isfinite(o->origin.lon_deg) && fabs(o->origin.lon_deg) <= 360.0, "origin", "longitude %g",
                 o->origin.lon_deg);
    CHECK_OPTION(isfinite(o->origin.h_m) && fabs(o->origin.h_m) <= 10000.0, "origin", "height %g (-10000..10000 m)",
                 o->origin.h_m);
    mrcal_lensmodel_t lm;
    CHECK_OPTION(o->fisheye >= RS_SIMULATE_FISHEYE_NONE && o->fisheye <= RS_SIMULATE_FISHEYE_KANNALA_BRANDT, "fisheye",
                 "%d", (int)o->fisheye);
    rs_status st = rs_simulate__lens_check(&lm, o->fisheye ? RS_SIMULATE_FISHEYE_LENS : o->lensmodel, o->width_px,
                                           o->height_px, o->hfov_deg, err);
    if (st) return st;
    // The pixel sizes must leave room for the 20 px margin and the 30 px outliers.
    return RS_OK;
}

// ---- writing ----

// The names of camera k's files, relative to the site folder.
typedef struct {
    char id[16], model[64], observations[64], truth_model[64];
} camera_files;

static void camera_files_of(camera_files *f, int k)
{
    rs_simulate__camera_id(f->id, k);
    rs_camera_path(f->model, sizeof f->model, RS_SITE_CAMERAS_DIR, f->id, RS_CAMERA_EXT_CAMERAMODEL);
    rs_camera_path(f->observations, sizeof f->observations, RS_SITE_OBSERVATIONS_DIR, f->id, RS_SITE_OBSERVATIONS_EXT);
    rs_camera_path(f->truth_model, sizeof f->truth_model, "truth", f->id, RS_CAMERA_EXT_CAMERAMODEL);
}

// Writes camera c's lens and size with the given intrinsics and pose (core's writer: atomic).
static rs_status write_cameramodel(const char *dir, const char *rel, const rs_simulate__camera *c,
                                   const double *intrinsics, const double rt_cam_enu[6], rs_err *err)
{
    char *path = rs_io_join(dir, rel);
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", rel);
    rs_camera view = c->cam;
    view.intrinsics = (double *)intrinsics;
    memcpy(view.rt_cam_enu, rt_cam_enu, sizeof view.rt_cam_enu);
    rs_status st = rs_camera_write_cameramodel(&view, path, err);
    free(path);
    return st;
}

static cJSON *json_array(const double *x, int n) { return cJSON_CreateDoubleArray(x, n); }

static cJSON *json_llh(double lat, double lon, double h)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "lat", lat);
    cJSON_AddNumberToObject(o, "lon", lon);
    cJSON_AddNumberToObject(o, "h", h);
    return o;
}

static cJSON *json_options(const rs_simulate_site_options *o)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "generator", "roadside site simulate");
    cJSON_AddNumberToObject(j, "seed", (double)o->seed);
    cJSON_AddNumberToObject(j, "cameras", o->Ncameras);
    cJSON_AddNumberToObject(j, "landmarks_per_camera", o->landmarks_per_camera);
    cJSON_AddStringToObject(j, "lens", o->fisheye ? RS_SIMULATE_FISHEYE_LENS : o->lensmodel);
    if (o->fisheye)
        cJSON_AddStringToObject(j, "fisheye",
                                o->fisheye == RS_SIMULATE_FISHEYE_EQUIDISTANT ? "equidistant" : "kannala-brandt");
    double image[2] = {o->width_px, o->height_px};
    cJSON_AddItemToObject(j, "image", json_array(image, 2));
    cJSON_AddNumberToObject(j, "hfov_deg", o->hfov_deg);
    cJSON_AddNumberToObject(j, "pixel_sigma_px", o->pixel_sigma_px);
    cJSON *ss = cJSON_AddObjectToObject(j, "survey_sigma_m");
    cJSON_AddNumberToObject(ss, "horizontal", o->survey_sigma_h_m);
    cJSON_AddNumberToObject(ss, "vertical", o->survey_sigma_v_m);
    cJSON_AddNumberToObject(j, "outliers", o->outlier_fraction);
    cJSON_AddNumberToObject(j, "focal_error", o->focal_error);
    cJSON_AddNumberToObject(j, "pole_prior_sigma_m", o->pole_prior_sigma_m);
    cJSON_AddNumberToObject(j, "elevated_fraction", o->elevated_fraction);
    cJSON_AddItemToObject(j, "origin", json_llh(o->origin.lat_deg, o->origin.lon_deg, o->origin.h_m));
    // only when asked for: a default site stays byte-identical to what it always was
    if (o->height_noise_m > 0) cJSON_AddNumberToObject(j, "height_noise_m", o->height_noise_m);
    if (o->landmark_heights != RS_SITE_HEIGHT_DEFAULT)
        cJSON_AddStringToObject(j, "landmark_heights", rs_site_height_name(o->landmark_heights));
    if (o->poles_per_camera > 0) cJSON_AddNumberToObject(j, "poles_per_camera", o->poles_per_camera);
    if (o->focal_error_range > 1.0) cJSON_AddNumberToObject(j, "focal_error_range", o->focal_error_range);
    if (o->lines_per_camera > 0) cJSON_AddNumberToObject(j, "lines_per_camera", o->lines_per_camera);
    return j;
}

// site.json, through geo's writer; "simulated" records the options.
static rs_status write_site_json(const char *dir, const rs_simulate__site *s, const rs_simulate_site_options *o,
                                 rs_err *err)
{
    const int K = s->Ncameras;
    static const double up[3] = {0, 0, 1};
    char name[64];
    snprintf(name, sizeof name, "simulated intersection (seed %llu)", (unsigned long long)o->seed);
    camera_files *files = calloc((size_t)K, sizeof *files);
    rs_site_spec_camera *cams = calloc((size_t)K, sizeof *cams);
    rs_llh *priors = calloc((size_t)K, sizeof *priors);
    cJSON *options = json_options(o);
    char *simulated = options ? cJSON_PrintUnformatted(options) : NULL;
    rs_status st;
    if (!files || !cams || !priors || !simulated) {
        st = rs_err_set(err, RS_ERR_NOMEM, "site.json: out of memory");
        goto done;
    }
    for (int k = 0; k < K; k++) {
        camera_files_of(&files[k], k);
        cams[k] = (rs_site_spec_camera){
            .id = files[k].id, .model = files[k].model, .observations = files[k].observations, .note = s->note[k]};
        if (s->prior_llh) {
            const double *p = s->prior_llh + 3 * k;
            priors[k] = (rs_llh){p[0], p[1], p[2]};
            cams[k].position_prior = &priors[k];
            cams[k].prior_sigma_m = o->pole_prior_sigma_m;
        }
    }
    const rs_site_spec spec = {
        .name = name,
        .origin = o->origin,
        .landmark_sigma_h_m = fmax(o->survey_sigma_h_m, DECLARED_SURVEY_SIGMA_MIN_M),
        .landmark_sigma_v_m = fmax(hypot(o->survey_sigma_v_m, o->height_noise_m), DECLARED_SURVEY_SIGMA_MIN_M),
        .landmark_heights = o->landmark_heights,
        .ground_normal_enu = up,
        .ground_offset_m = 0.0,
        .cameras = cams,
        .Ncameras = K,
        .extra_name = "simulated",
        .extra_json = simulated,
    };
    st = rs_site_write_json(dir, &spec, RS_SITE_LAYOUT_TOOL, err);
done:
    cJSON_Delete(options);
    cJSON_free(simulated);
    free(priors);
    free(cams);
    free(files);
    return st;
}

// The vertices of the site's lines as the writer takes them (rs_site_landmark.vertices_llh and
// vertices_given_h_m point into these).
typedef struct {
    rs_llh *llh;
    double *given_h_m;
} line_vertices;

// The site's poles and lines after its points, (*landmarks)[s->Nlandmarks ..]: ids "P001", ...,
// "LN001", ...; heights on the ground follow o->landmark_heights as the points' do (a pole's base
// and a line's vertices are on it); with height noise a pole declares the sigma of its height.
static rs_status shape_landmarks(rs_site_landmark *landmarks, char (*ids)[16], line_vertices *lv,
                                 const rs_simulate__site *s, const rs_simulate_site_options *o, rs_err *err)
{
    size_t Nv = 0;
    for (int i = 0; i < s->Npoles + s->Nlines; i++) Nv += (size_t)s->shape[s->shape_of[i]].Nvertices;
    lv->llh = calloc(Nv + 1, sizeof *lv->llh);
    lv->given_h_m = calloc(Nv + 1, sizeof *lv->given_h_m);
    if (!lv->llh || !lv->given_h_m) return rs_err_set(err, RS_ERR_NOMEM, "landmarks: out of memory");
    const bool unknown = o->landmark_heights == RS_SITE_HEIGHT_UNKNOWN;
    size_t used = 0;
    for (int i = 0; i < s->Npoles + s->Nlines; i++) {
        const rs_simulate__shape *c = &s->shape[s->shape_of[i]];
        const int il = s->Nlandmarks + i;
        if (i < s->Npoles)
            rs_simulate__pole_id(ids[il], i);
        else
            rs_simulate__line_id(ids[il], i - s->Npoles);
        rs_site_landmark *l = &landmarks[il];
        *l = (rs_site_landmark){.id = ids[il],
                                .feature = il,
                                .llh = {c->survey_llh[0], c->survey_llh[1], unknown ? NAN : c->survey_llh[2]},
                                .sigma_h_m = NAN,
                                .sigma_v_m = NAN,
                                .kind = (char *)c->kind,
                                .height = unknown ? RS_SITE_HEIGHT_UNKNOWN : RS_SITE_HEIGHT_DEFAULT,
                                .shape = c->shape};
        if (c->shape == RS_SITE_POLE) {
            l->pole_height_m = c->survey_height_m;
            l->sigma_pole_height_m =
                o->height_noise_m > 0 ? fmax(o->survey_sigma_v_m, DECLARED_SURVEY_SIGMA_MIN_M) : NAN;
            continue;
        }
        l->Nvertices = c->Nvertices;
        l->vertices_llh = &lv->llh[used];
        l->vertices_given_h_m = &lv->given_h_m[used];
        for (int v = 0; v < c->Nvertices; v++) {
            const double *q = &c->survey_llh[3 * v];
            lv->llh[used + v] = (rs_llh){q[0], q[1], unknown ? NAN : q[2]};
            lv->given_h_m[used + v] = unknown ? NAN : q[2];
        }
        used += (size_t)c->Nvertices;
    }
    return RS_OK;
}

// The surveyed landmarks as the site gives them (ids "L001", ...; kinds static strings), then its
// poles and lines (shape_landmarks). With o->landmark_heights, those on the ground follow it (an
// unknown height is not written); those above it say they are surveyed, how far above the ground
// they are and, with height noise, their own sigma_v.
// out: *landmarks (Nlandmarks + Npoles + Nlines,), *ids (that many, 16) that their ids point into
//      and *lv (free all three)
static rs_status site_landmarks(rs_site_landmark **landmarks, char (**ids)[16], line_vertices *lv,
                                const rs_simulate__site *s, const rs_simulate_site_options *o, rs_err *err)
{
    const int L = s->Nlandmarks, Lall = L + s->Npoles + s->Nlines;
    *landmarks = calloc((size_t)(Lall ? Lall : 1), sizeof **landmarks);
    *ids = calloc((size_t)(Lall ? Lall : 1), sizeof **ids);
    if (!*landmarks || !*ids) return rs_err_set(err, RS_ERR_NOMEM, "landmarks: out of memory");
    for (int i = 0; i < L; i++) {
        const double *llh = s->survey_llh + 3 * i;
        rs_simulate__landmark_id((*ids)[i], i);
        rs_site_landmark *l = &(*landmarks)[i];
        *l = (rs_site_landmark){.id = (*ids)[i],
                                .feature = i,
                                .llh = {llh[0], llh[1], llh[2]},
                                .sigma_h_m = NAN,
                                .sigma_v_m = NAN,
                                .kind = (char *)s->cand.c[s->cand_of[i]].kind};
        const double above_ground_m = s->cand.c[s->cand_of[i]].p_enu_m[2];
        if (above_ground_m != 0.0) {
            if (o->height_noise_m > 0) l->sigma_v_m = fmax(o->survey_sigma_v_m, DECLARED_SURVEY_SIGMA_MIN_M);
            if (o->landmark_heights != RS_SITE_HEIGHT_DEFAULT && o->landmark_heights != RS_SITE_HEIGHT_SURVEYED) {
                l->height_stated = RS_SITE_HEIGHT_SURVEYED;
                l->above_ground_m = above_ground_m;
            }
        } else if (o->landmark_heights == RS_SITE_HEIGHT_UNKNOWN) {
            l->height = RS_SITE_HEIGHT_UNKNOWN;
            l->llh.h_m = NAN; // written [lon, lat]
        }
    }
    return shape_landmarks(*landmarks, *ids, lv, s, o, err);
}

// observations/<id>.csv of camera k: its picks of the landmarks it sees, in landmark order.
static rs_status write_observations(const char *dir, const camera_files *f, const rs_simulate__site *s, int k,
                                    const rs_site_landmark *landmarks, double sigma_px, rs_err *err)
{
    const int Nc = s->cand.N;
    rs_site_observation *obs = calloc((size_t)(s->Nlandmarks + s->Npicks + 1), sizeof *obs);
    char *path = rs_io_join(dir, f->observations);
    int n = 0;
    for (int i = 0; obs && i < s->Nlandmarks; i++) {
        size_t kj = (size_t)k * Nc + s->cand_of[i];
        if (s->visible[kj])
            obs[n++] = (rs_site_observation){
                .ilandmark = i, .q_px = {s->q_px[2 * kj], s->q_px[2 * kj + 1]}, .sigma_px = sigma_px};
    }
    for (int i = 0; obs && i < s->Npicks; i++) // then its picks of poles and lines
        if (s->picks[i].cam == k)
            obs[n++] = (rs_site_observation){.ilandmark = s->picks[i].landmark,
                                             .q_px = {s->picks[i].q_px[0], s->picks[i].q_px[1]},
                                             .sigma_px = sigma_px,
                                             .at = s->picks[i].at};
    rs_status st = obs && path ? rs_site_write_observations(path, obs, n, landmarks, err)
                               : rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", f->observations);
    free(path);
    free(obs);
    return st;
}

static rs_status write_truth_landmarks(const char *dir, const rs_simulate__site *s, rs_err *err)
{
    char *path = rs_io_join(dir, "truth/landmarks_enu.csv");
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_io_atomic a;
    rs_status st = rs_io_atomic_open(&a, path, err);
    free(path);
    if (st) return st;
    fprintf(a.f, "id,e,n,u\n");
    for (int i = 0; i < s->Nlandmarks; i++) {
        char id[16];
        rs_simulate__landmark_id(id, i);
        const double *p = s->cand.c[s->cand_of[i]].p_enu_m;
        fprintf(a.f, "%s,%.4f,%.4f,%.4f\n", id, p[0], p[1], p[2]);
    }
    return rs_io_atomic_commit(&a, err);
}

// truth/vertices_enu.csv and truth/picks.csv (rs_simulate_site, sim/rs_simulate.h), when the
// site has poles or lines.
static rs_status write_truth_shapes(const char *dir, const rs_simulate__site *s, rs_err *err)
{
    if (s->Npoles + s->Nlines == 0) return RS_OK;
    char *path = rs_io_join(dir, "truth/vertices_enu.csv");
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_io_atomic a;
    rs_status st = rs_io_atomic_open(&a, path, err);
    free(path);
    if (st) return st;
    fprintf(a.f, "id,shape,vertex,e,n,u\n");
    for (int i = 0; i < s->Npoles + s->Nlines; i++) {
        const rs_simulate__shape *c = &s->shape[s->shape_of[i]];
        char id[16];
        if (i < s->Npoles)
            rs_simulate__pole_id(id, i);
        else
            rs_simulate__line_id(id, i - s->Npoles);
        for (int v = 0; v < c->Nvertices; v++)
            fprintf(a.f, "%s,%s,%d,%.4f,%.4f,%.4f\n", id, rs_site_shape_name(c->shape), v, c->p_enu_m[3 * v],
                    c->p_enu_m[3 * v + 1], c->p_enu_m[3 * v + 2]);
    }
    if ((st = rs_io_atomic_commit(&a, err))) return st;

    if (!(path = rs_io_join(dir, "truth/picks.csv"))) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    st = rs_io_atomic_open(&a, path, err);
    free(path);
    if (st) return st;
    fprintf(a.f, "camera,row,landmark,at,e,n,u,u_true_px,v_true_px,outlier\n");
    for (int k = 0; k < s->Ncameras; k++) {
        int row = 0; // the data row in observations/<id>.csv: the points it sees come first
        for (int i = 0; i < s->Nlandmarks; i++) row += s->visible[(size_t)k * s->cand.N + s->cand_of[i]];
        char cid[16];
        rs_simulate__camera_id(cid, k);
        for (int i = 0; i < s->Npicks; i++) {
            const rs_simulate__pick *p = &s->picks[i];
            if (p->cam != k) continue;
            const int j = p->landmark - s->Nlandmarks;
            char id[16];
            if (j < s->Npoles)
                rs_simulate__pole_id(id, j);
            else
                rs_simulate__line_id(id, j - s->Npoles);
            fprintf(a.f, "%s,%d,%s,%s,%.9f,%.9f,%.9f,%.9f,%.9f,%d\n", cid, ++row, id, rs_site_at_name(p->at),
                    p->p_true_enu_m[0], p->p_true_enu_m[1], p->p_true_enu_m[2], p->q_true_px[0], p->q_true_px[1],
                    p->outlier);
        }
    }
    return rs_io_atomic_commit(&a, err);
}

static rs_status write_truth_json(const char *dir, const rs_simulate__site *s, const rs_simulate_site_options *o,
                                  rs_err *err)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddNumberToObject(j, "seed", (double)o->seed);
    cJSON_AddItemToObject(j, "options", json_options(o));
    cJSON_AddNumberToObject(j, "road_azimuth_deg", s->road_azimuth_deg);
    cJSON_AddNumberToObject(j, "observations", s->Nobservations);
    cJSON_AddNumberToObject(j, "outliers", s->Noutliers);
    cJSON *cams = cJSON_AddArrayToObject(j, "cameras");
    int Nc = s->cand.N;
    for (int k = 0; k < s->Ncameras; k++) {
        const rs_simulate__camera *c = &s->cam[k];
        char id[16];
        rs_simulate__camera_id(id, k);
        cJSON *cj = cJSON_CreateObject();
        cJSON_AddStringToObject(cj, "id", id);
        cJSON_AddItemToObject(cj, "rt_cam_enu", json_array(c->cam.rt_cam_enu, 6));
        cJSON_AddItemToObject(cj, "position_enu_m", json_array(c->p_cam_enu_m, 3));
        cJSON_AddItemToObject(cj, "yaw_pitch_roll_deg", json_array(c->ypr_deg, 3));
        cJSON_AddItemToObject(cj, "intrinsics", json_array(c->cam.intrinsics, c->cam.Nintrinsics));
        cJSON_AddItemToObject(cj, "nominal_intrinsics",
                              json_array(s->nominal + (size_t)k * c->cam.Nintrinsics, c->cam.Nintrinsics));
        cJSON *obs = cJSON_AddArrayToObject(cj, "observed");
        cJSON *out = cJSON_AddArrayToObject(cj, "outliers");
        for (int i = 0; i < s->Nlandmarks; i++) {
            size_t kj = (size_t)k * Nc + s->cand_of[i];
            if (!s->visible[kj]) continue;
            char lid[16];
            rs_simulate__landmark_id(lid, i);
            cJSON_AddItemToArray(obs, cJSON_CreateString(lid));
            if (s->outlier[kj]) cJSON_AddItemToArray(out, cJSON_CreateString(lid));
        }
        cJSON_AddItemToArray(cams, cj);
    }
    cJSON *lms = cJSON_AddArrayToObject(j, "landmarks");
    for (int i = 0; i < s->Nlandmarks; i++) {
        char id[16];
        rs_simulate__landmark_id(id, i);
        const rs_simulate__candidate *c = &s->cand.c[s->cand_of[i]];
        double e[3];
        for (int a = 0; a < 3; a++) e[a] = s->survey_enu_m[3 * i + a] - c->p_enu_m[a];
        cJSON *l = cJSON_CreateObject();
        cJSON_AddStringToObject(l, "id", id);
        cJSON_AddStringToObject(l, "kind", c->kind);
        cJSON_AddItemToObject(l, "enu_m", json_array(c->p_enu_m, 3));
        cJSON_AddItemToObject(l, "survey_error_enu_m", json_array(e, 3));
        cJSON_AddItemToArray(lms, l);
    }
    char *path = rs_io_join(dir, "truth/truth.json"), *text = cJSON_Print(j);
    cJSON_Delete(j);
    rs_io_atomic a;
    rs_status st =
        path && text ? rs_io_atomic_open(&a, path, err) : rs_err_set(err, RS_ERR_NOMEM, "truth.json: out of memory");
    if (!st) {
        fprintf(a.f, "%s\n", text);
        st = rs_io_atomic_commit(&a, err);
    }
    free(text);
    free(path);
    return st;
}

static rs_status write_site(const char *dir, const rs_simulate__site *s, const rs_simulate_site_options *o, rs_err *err)
{
    rs_status st;
    static const char *const folders[3] = {RS_SITE_CAMERAS_DIR, RS_SITE_OBSERVATIONS_DIR, "truth"};
    for (int i = 0; i < 3; i++) {
        char *p = rs_io_join(dir, folders[i]);
        st = p ? rs_io_mkdir_p(p, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(p);
        if (st) return st;
    }
    rs_site_landmark *landmarks = NULL;
    char(*ids)[16] = NULL;
    line_vertices lv = {0};
    const int Nall = s->Nlandmarks + s->Npoles + s->Nlines;
    rs_lanes lanes = {0};
    char *lanes_path = rs_io_join(dir, RS_SITE_LANES);
    if (!lanes_path)
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    else if (!(st = write_site_json(dir, s, o, err)) && !(st = site_landmarks(&landmarks, &ids, &lv, s, o, err)) &&
             !(st = rs_site_write_landmarks(dir, landmarks, Nall, 0, RS_SITE_LAYOUT_TOOL, err)) &&
             !(st = rs_simulate__lanes(&lanes, s, err)) &&
             !(st = rs_lanes_write(lanes_path, &lanes, &o->origin, 0, false, RS_SITE_LAYOUT_TOOL, err)) &&
             !(st = write_truth_landmarks(dir, s, err)) && !(st = write_truth_shapes(dir, s, err)))
        st = write_truth_json(dir, s, o, err);
    static const double zero_rt[6] = {0};
    for (int k = 0; k < s->Ncameras && !st; k++) {
        const rs_simulate__camera *c = &s->cam[k];
        camera_files f;
        camera_files_of(&f, k);
        if (!(st = write_cameramodel(dir, f.model, c, s->nominal + (size_t)k * c->cam.Nintrinsics, zero_rt, err)) &&
            !(st = write_cameramodel(dir, f.truth_model, c, c->cam.intrinsics, c->cam.rt_cam_enu, err)))
            st =
                write_observations(dir, &f, s, k, landmarks, fmax(o->pixel_sigma_px, DECLARED_PIXEL_SIGMA_MIN_PX), err);
    }
    rs_lanes_free(&lanes);
    free(lanes_path);
    free(landmarks);
    free(ids);
    free(lv.llh);
    free(lv.given_h_m);
    return st;
}

// ---- the folder: built aside, renamed into place ----

// 0: does not exist; 1: empty folder; 2: a site simulate wrote and nothing else (its record,
// rs_simulate__record_matches); 3: anything else (a file, a folder holding anything more: a
// surveyor's site, a simulated site with a user's notes added), with why filled.
static int target_state(const char *dir, char *why, size_t n)
{
    struct stat sb;
    snprintf(why, n, "exists and is not an empty folder");
    if (stat(dir, &sb) != 0) return errno == ENOENT ? 0 : 3;
    if (!S_ISDIR(sb.st_mode)) return 3;
    DIR *d = opendir(dir);
    if (!d) return 3;
    bool empty = true;
    for (struct dirent *e; (e = readdir(d));)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
            empty = false;
            break;
        }
    closedir(d);
    if (empty) return 1;
    return rs_simulate__record_matches(why, n, dir) ? 2 : 3;
}

static rs_status check_target(const char *dir, bool force, rs_err *err)
{
    struct stat sb;
    char why[300];
    if (stat(dir, &sb) != 0 && errno != ENOENT)
        return rs_err_set(err, RS_ERR_IO, "%s: cannot use it: %s", dir, strerror(errno));
    switch (target_state(dir, why, sizeof why)) {
    case 0:
    case 1: return RS_OK;
    case 2:
        return force ? RS_OK
                     : rs_err_set(err, RS_ERR_IO, "%s: a simulated site is already there (use --force to replace it)",
                                  dir);
    default:
        return rs_err_set(err, RS_ERR_IO, "%s: %s; refusing to write there%s", dir, why,
                          force ? " even with --force (it replaces only a site roadside site simulate wrote, "
                                  "holding nothing else)"
                                : "");
    }
}

// "<parent>/.<base>.<tag>.XXXXXX" for mkdtemp, beside dir.
static char *sibling_template(const char *dir, const char *tag)
{
    size_t n = strlen(dir);
    while (n > 1 && dir[n - 1] == '/') n--;
    size_t b = n;
    while (b > 0 && dir[b - 1] != '/') b--;
    size_t len = n + strlen(tag) + 16;
    char *t = malloc(len);
    if (t) snprintf(t, len, "%.*s.%.*s.%s.XXXXXX", (int)b, dir, (int)(n - b), dir + b, tag);
    return t;
}

static rs_status simulate_site_into(const char *dir, const rs_simulate_site_options *o, rs_err *err);

rs_status rs_simulate_site(const char *dir, const rs_simulate_site_options *o, rs_err *err)
{
    if (!dir || !*dir) return rs_err_set(err, RS_ERR_USAGE, "no site folder given");
    char *d = strdup(dir);
    if (!d) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (size_t n = strlen(d); n > 1 && d[n - 1] == '/'; n--) d[n - 1] = '\0';
    const char *base = strrchr(d, '/');
    base = base ? base + 1 : d;
    rs_status st;
    if (!*base || !strcmp(base, ".") || !strcmp(base, ".."))
        st = rs_err_set(err, RS_ERR_USAGE, "%s: name the site folder itself, not '.', '..' or '/'", dir);
    else
        st = simulate_site_into(d, o, err);
    free(d);
    return st;
}

static rs_status simulate_site_into(const char *dir, const rs_simulate_site_options *o, rs_err *err)
{
    rs_status st = rs_simulate_site_options_check(o, err);
    if (st) return st;
    if ((st = check_target(dir, o->force, err))) return st;

    rs_simulate__site s = {0};
    char *tmp = NULL, *old = NULL, *parent = NULL;
    if ((st = rs_simulate__site_draw(&s, o, err))) goto done;

    // Build the site in a hidden sibling folder.
    tmp = sibling_template(dir, "tmp");
    if (!tmp) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    parent = strdup(tmp);
    if (!parent) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    char *slash = strrchr(parent, '/');
    if (slash && slash != parent) {
        *slash = '\0';
        if ((st = rs_io_mkdir_p(parent, err))) goto done;
    }
    if (!mkdtemp(tmp)) {
        st = rs_err_set(err, RS_ERR_IO, "%s: cannot create a temporary folder beside it: %s", dir, strerror(errno));
        free(tmp);
        tmp = NULL;
        goto done;
    }
    if ((st = write_site(tmp, &s, o, err)) || (st = rs_simulate__record_write(tmp, err))) goto done;

    // Put it in place: straight over a missing or empty folder; a site being replaced is moved
    // aside first and deleted once the new one is in.
    if ((st = check_target(dir, o->force, err))) goto done;
    char why[300];
    if (target_state(dir, why, sizeof why) == 2) {
        old = sibling_template(dir, "old");
        if (!old || !mkdtemp(old)) {
            st = rs_err_set(err, RS_ERR_IO, "%s: cannot create a temporary folder beside it", dir);
            free(old);
            old = NULL;
            goto done;
        }
        if (rename(dir, old) != 0) {
            st = rs_err_set(err, RS_ERR_IO, "%s: cannot move the old site aside: %s", dir, strerror(errno));
            rmdir(old);
            goto done;
        }
    }
    if (rename(tmp, dir) != 0) {
        st = rs_err_set(err, RS_ERR_IO, "%s: cannot rename the new site into place: %s", dir, strerror(errno));
        if (old) rename(old, dir);
        goto done;
    }
    free(tmp);
    tmp = NULL;
    if (old) rs_io_remove_tree(old);
done:
    if (tmp) rs_io_remove_tree(tmp);
    free(tmp);
    free(old);
    free(parent);
    rs_simulate__site_free(&s);
    return st;
}
