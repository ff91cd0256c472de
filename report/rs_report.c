// rs_report.c -- `roadside report`: reads a site's calibration outputs, runs the audit, and
// writes the report as HTML and PDF (see rs_report.h).
#include "report/rs_report.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cJSON.h>

#include "calib/rs_calib_site.h"
#include "core/rs_image.h"
#include "core/rs_io.h"
#include "report/internal/rs_report_doc.h"
#include "report/internal/rs_report_draw.h"
#include "report/internal/rs_report_words.h"

void rs_report_options_default(rs_report_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->range_m = 100;
    opt->grid_m = 0;
    opt->figure_width_px = 1000;
    opt->audit = true;
    rs_audit_options_default(&opt->audit_options);
    opt->audit_options.range_m = opt->range_m;
}

// ---- <id>.json, read by calib (rs_calib_site_result_read) ----

// Fills the <id>.json part of cam from `path`: the figures copied, the strings handed over.
static rs_status read_result_json(rs_report_camera *cam, const rs_site *site, const char *path, rs_err *err)
{
    rs_calib_site_result r;
    rs_status st = rs_calib_site_result_read(&r, path, err);
    if (st == RS_OK && !(cam->landmarks = calloc((size_t)r.N + 1, sizeof *cam->landmarks)))
        st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    if (st) {
        rs_calib_site_result_free(&r);
        return st;
    }
    memcpy(cam->position_enu_m, r.position_enu_m, sizeof cam->position_enu_m);
    memcpy(cam->sigma_position_enu_m, r.sigma_position_enu_m, sizeof cam->sigma_position_enu_m);
    memcpy(cam->position_llh, r.position_llh, sizeof cam->position_llh);
    memcpy(cam->yaw_pitch_roll_deg, r.yaw_pitch_roll_deg, sizeof cam->yaw_pitch_roll_deg);
    memcpy(cam->sigma_yaw_pitch_roll_deg, r.sigma_yaw_pitch_roll_deg, sizeof cam->sigma_yaw_pitch_roll_deg);
    cam->rms_surveyed_px = r.rms_surveyed_px;
    cam->rms_adjusted_px = r.rms_adjusted_px;
    cam->variance_factor = r.variance_factor;
    cam->condition_number = r.condition_number;
    cam->Nused = r.Nused;
    cam->Nrejected = r.Nrejected;
    cam->lensmodel = r.lensmodel;
    cam->warnings = r.warnings;
    cam->Nwarnings = r.Nwarnings;
    cam->focal_off = r.focal_off;
    cam->center_off = r.center_off;
    cam->focal_rel = r.focal_rel;
    r.lensmodel = NULL;
    r.warnings = NULL;
    r.Nwarnings = 0;
    for (int i = 0; i < r.N; i++) {
        const rs_calib_site_landmark *m = &r.landmarks[i];
        rs_report_landmark *l = &cam->landmarks[cam->N++];
        l->id = m->id;
        r.landmarks[i].id = NULL;
        l->ilandmark = rs_site_find_landmark(site, l->id);
        memcpy(l->observed_px, m->observed_px, sizeof l->observed_px);
        memcpy(l->predicted_surveyed_px, m->predicted_surveyed_px, sizeof l->predicted_surveyed_px);
        memcpy(l->residual_surveyed_px, m->residual_surveyed_px, sizeof l->residual_surveyed_px);
        l->normalised = m->normalised_residual;
        l->inlier = m->inlier;
    }
    rs_calib_site_result_free(&r);
    return RS_OK;
}

// ---- lanes.geojson ----

// Appends one polyline: the GeoJSON positions `coords` converted to ENU, offset by offset_m to
// the left in the (E, N) plane (0: the centreline).
static rs_status lanes_add_line(rs_report_lanes *lanes, const cJSON *coords, const rs_site *site, const char *path,
                                const char *field, bool junction, double offset_m, rs_err *err)
{
    int n = cJSON_GetArraySize(coords);
    if (!cJSON_IsArray(coords) || n < 2)
        return rs_err_set(err, RS_ERR_PARSE, "%s: %s: expected an array of at least 2 positions", path, field);
    int have = lanes->Nlines ? lanes->start[lanes->Nlines] : 0;
    int *start = realloc(lanes->start, (size_t)(lanes->Nlines + 2) * sizeof *start);
    if (start) lanes->start = start;
    bool *jn = realloc(lanes->junction, (size_t)(lanes->Nlines + 1) * sizeof *jn);
    if (jn) lanes->junction = jn;
    double *p = realloc(lanes->p_enu_m, (size_t)(have + n) * 3 * sizeof *p);
    if (p) lanes->p_enu_m = p;
    if (!start || !jn || !p) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    if (lanes->Nlines == 0) start[0] = 0;
    p += 3 * have;
    int i = 0;
    const cJSON *pos;
    cJSON_ArrayForEach(pos, coords)
    {
        int m = cJSON_GetArraySize(pos);
        double v[3] = {0, 0, 0};
        for (int k = 0; k < m && k < 3; k++) {
            const cJSON *x = cJSON_GetArrayItem(pos, k);
            if (!cJSON_IsNumber(x) || !isfinite(x->valuedouble))
                return rs_err_set(err, RS_ERR_PARSE, "%s: %s[%d][%d]: not a finite number", path, field, i, k);
            v[k] = x->valuedouble;
        }
        if (!cJSON_IsArray(pos) || m < 2 || m > 3 || fabs(v[1]) > 90 || fabs(v[0]) > 180)
            return rs_err_set(err, RS_ERR_PARSE, "%s: %s[%d]: expected [lon, lat] or [lon, lat, h] in degrees", path,
                              field, i);
        double llh[3] = {v[1], v[0], m == 3 ? v[2] + site->geoid_undulation_m : site->origin.h_m};
        rs_status st = rs_geo_llh_to_enu(&p[3 * i], &site->origin, llh, 1, err);
        if (st) return rs_err_prefix(err, "%s: %s[%d]", path, field, i);
        if (m == 2) { // on the ground plane
            const double *nn = site->ground_normal_enu;
            p[3 * i + 2] = (site->ground_offset_m - nn[0] * p[3 * i] - nn[1] * p[3 * i + 1]) / nn[2];
        }
        i++;
    }
    if (offset_m != 0) { // left normal of the mean direction at each vertex
        double *q = malloc((size_t)n * 2 * sizeof *q);
        if (!q) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
        for (int k = 0; k < n; k++) {
            int a = k > 0 ? k - 1 : 0, b = k + 1 < n ? k + 1 : n - 1;
            double de = p[3 * b] - p[3 * a], dn = p[3 * b + 1] - p[3 * a + 1], len = hypot(de, dn);
            q[2 * k] = len > 0 ? p[3 * k] - offset_m * dn / len : p[3 * k];
            q[2 * k + 1] = len > 0 ? p[3 * k + 1] + offset_m * de / len : p[3 * k + 1];
        }
        for (int k = 0; k < n; k++) p[3 * k] = q[2 * k], p[3 * k + 1] = q[2 * k + 1];
        free(q);
    }
    lanes->junction[lanes->Nlines] = junction;
    lanes->Nlines++;
    start[lanes->Nlines] = have + n;
    return RS_OK;
}

// One LineString's lines: both edges when the feature has a width_m, else the centreline.
static rs_status lanes_add_feature(rs_report_lanes *lanes, const cJSON *coords, const cJSON *props, const rs_site *site,
                                   const char *path, const char *field, rs_err *err)
{
    const cJSON *kind = cJSON_GetObjectItemCaseSensitive(props, "kind");
    const cJSON *width = cJSON_GetObjectItemCaseSensitive(props, "width_m");
    bool junction = cJSON_IsString(kind) && !strcmp(kind->valuestring, "junction");
    if (junction || !cJSON_IsNumber(width) || !(width->valuedouble > 0) || !(width->valuedouble < 100))
        return lanes_add_line(lanes, coords, site, path, field, junction, 0, err);
    rs_status st = lanes_add_line(lanes, coords, site, path, field, false, width->valuedouble / 2, err);
    if (!st) st = lanes_add_line(lanes, coords, site, path, field, false, -width->valuedouble / 2, err);
    return st;
}

static rs_status read_lanes(rs_report_lanes *lanes, const rs_site *site, rs_err *err)
{
    char *path = rs_io_join(site->dir, RS_SITE_LANES);
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, RS_SITE_LANES ": out of memory");
    FILE *f = fopen(path, "rb");
    if (!f) { // optional
        free(path);
        return RS_OK;
    }
    fclose(f);
    char *text = NULL;
    rs_status st = rs_io_read_file(&text, NULL, path, err);
    cJSON *root = st ? NULL : cJSON_Parse(text);
    free(text);
    const cJSON *features = cJSON_GetObjectItemCaseSensitive(root, "features");
    if (!st && !cJSON_IsArray(features))
        st = rs_err_set(err, RS_ERR_PARSE, "%s: features: expected a GeoJSON FeatureCollection", path);
    int k = 0;
    const cJSON *feat;
    if (!st) cJSON_ArrayForEach(feat, features)
        {
            char field[96];
            const cJSON *geom = cJSON_GetObjectItemCaseSensitive(feat, "geometry");
            const cJSON *props = cJSON_GetObjectItemCaseSensitive(feat, "properties");
            const cJSON *type = cJSON_GetObjectItemCaseSensitive(geom, "type");
            const cJSON *coords = cJSON_GetObjectItemCaseSensitive(geom, "coordinates");
            if (!cJSON_IsString(type)) {
                st = rs_err_set(err, RS_ERR_PARSE, "%s: features[%d].geometry.type: expected a string", path, k);
                break;
            }
            if (!strcmp(type->valuestring, "LineString")) {
                snprintf(field, sizeof field, "features[%d].geometry.coordinates", k);
                st = lanes_add_feature(lanes, coords, props, site, path, field, err);
            } else if (!strcmp(type->valuestring, "MultiLineString") && cJSON_IsArray(coords)) {
                int j = 0;
                const cJSON *line;
                cJSON_ArrayForEach(line, coords)
                {
                    snprintf(field, sizeof field, "features[%d].geometry.coordinates[%d]", k, j++);
                    if ((st = lanes_add_feature(lanes, line, props, site, path, field, err))) break;
                }
            } else
                st = rs_err_set(err, RS_ERR_PARSE,
                                "%s: features[%d].geometry.type: '%s': expected LineString or "
                                "MultiLineString with coordinates",
                                path, k, type->valuestring);
            if (st) break;
            k++;
        }
    cJSON_Delete(root);
    free(path);
    return st;
}

// ---- backgrounds ----

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

static bool is_image_name(const char *name)
{
    return rs_io_has_extension(name, "png") || rs_io_has_extension(name, "jpg") || rs_io_has_extension(name, "jpeg");
}

// An image file as a cairo surface: PNG through cairo, JPEG through OpenCV (cv::imread).
static rs_status read_image(cairo_surface_t **out, const char *path, rs_err *err)
{
    *out = NULL;
    // core's one image reader (OpenCV), then cairo's premultiplied ARGB32; the image is shown
    // opaque (alpha dropped), greyscale as grey
    rs_image im = {0};
    rs_status st = rs_image_read(&im, path, err);
    if (st) return st;
    const int w = im.width, h = im.height, nc = im.channels;
    cairo_surface_t *img = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, w, h);
    if (cairo_surface_status(img) != CAIRO_STATUS_SUCCESS) {
        rs_image_free(&im);
        cairo_surface_destroy(img);
        return rs_err_set(err, RS_ERR_NOMEM, "%s: %d x %d px: no memory for the image", path, w, h);
    }
    cairo_surface_flush(img);
    unsigned char *data = cairo_image_surface_get_data(img);
    const int stride = cairo_image_surface_get_stride(img);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *px = &im.data[((size_t)y * (size_t)w + (size_t)x) * (size_t)nc];
            uint32_t argb = 0xff000000u;
            for (int c = 0; c < 3; c++) {
                const float v = px[nc >= 3 ? c : 0];
                const uint32_t byte = (uint32_t)lrintf(255.0f * (v < 0 ? 0 : v > 1 ? 1 : v));
                argb |= byte << (16 - 8 * c); // R, G, B
            }
            memcpy(data + (size_t)y * (size_t)stride + 4 * (size_t)x, &argb, 4);
        }
    cairo_surface_mark_dirty(img);
    rs_image_free(&im);
    *out = img;
    return RS_OK;
}

// The first image (PNG or JPEG, by name) in the camera's backgrounds folder: the site camera's
// "backgrounds", else SITE/backgrounds/<id>/. No folder or no image: RS_OK with no image.
static rs_status read_background(rs_report_camera *cam, const rs_site *site, rs_err *err)
{
    const rs_site_camera *sc = &site->cameras[cam->icam];
    char *dir = NULL;
    if (sc->backgrounds_path)
        dir = strdup(sc->backgrounds_path);
    else {
        char rel[512];
        snprintf(rel, sizeof rel, "backgrounds/%s", sc->id);
        dir = rs_io_join(site->dir, rel);
    }
    if (!dir) return rs_err_set(err, RS_ERR_NOMEM, "backgrounds: out of memory");
    DIR *d = opendir(dir);
    if (!d) {
        free(dir);
        return RS_OK;
    }
    char **names = NULL;
    int n = 0;
    struct dirent *e;
    rs_status st = RS_OK;
    while ((e = readdir(d)) && !st) {
        if (e->d_name[0] == '.' || !is_image_name(e->d_name)) continue;
        char **nn = realloc(names, (size_t)(n + 1) * sizeof *nn);
        if (!nn || !(nn[n] = strdup(e->d_name))) st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", dir);
        if (nn) names = nn;
        if (!st) n++;
    }
    closedir(d);
    if (!st && n) {
        qsort(names, (size_t)n, sizeof *names, cmp_str);
        cam->background_path = rs_io_join(dir, names[0]);
        if (!cam->background_path) st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", dir);
    }
    for (int i = 0; i < n; i++) free(names[i]);
    free(names);
    free(dir);
    if (st || !cam->background_path) return st;
    return read_image(&cam->background, cam->background_path, err);
}

// ---- loading ----

static void camera_free(rs_report_camera *cam)
{
    rs_camera_free(&cam->model);
    free(cam->lensmodel);
    for (int i = 0; i < cam->N; i++) free(cam->landmarks[i].id);
    free(cam->landmarks);
    for (int i = 0; i < cam->Nwarnings; i++) free(cam->warnings[i]);
    free(cam->warnings);
    free(cam->fov_en_m);
    free(cam->background_path);
    if (cam->background) cairo_surface_destroy(cam->background);
    rs_audit_result_free(&cam->audit);
}

static rs_status camera_load(rs_report_camera *cam, const rs_site *site, const char *calib_dir,
                             const rs_report_options *opt, rs_err *err)
{
    const char *id = site->cameras[cam->icam].id;
    char model_path[4096], json_path[4096];
    rs_status st = rs_camera_path(model_path, sizeof model_path, calib_dir, id, RS_CAMERA_EXT_CAMERAMODEL) &&
                           rs_camera_path(json_path, sizeof json_path, calib_dir, id, RS_CALIB_SITE_EXT_JSON)
                       ? RS_OK
                       : rs_err_set(err, RS_ERR_INVALID, "%s: path too long", calib_dir);
    if (!st) {
        FILE *f = fopen(json_path, "rb");
        if (!f)
            st = rs_err_set(err, RS_ERR_NOT_FOUND, "%s: no calibration of camera '%s' (run 'roadside calib %s -o %s')",
                            json_path, id, site->dir, calib_dir);
        else
            fclose(f);
    }
    if (!st) st = rs_camera_read(&cam->model, NULL, model_path, err);
    if (!st && (cam->model.width < 1 || cam->model.height < 1))
        st = rs_err_set(err, RS_ERR_INVALID, "%s: imagersize: %d x %d: the report needs the image size", model_path,
                        cam->model.width, cam->model.height);
    if (!st) st = read_result_json(cam, site, json_path, err);
    if (!st && !rs_report_camera_geometry(cam)) st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", id);
    if (!st) st = read_background(cam, site, err);
    if (!st && opt->audit) {
        // the audit of the calibration in calib_dir, exactly `roadside audit SITE --calib
        // CALIB_DIR`: one verdict for both (its rms_surveyed_px rule applies to these files)
        rs_err aerr = {0};
        rs_status ast = rs_audit_site_camera(&cam->audit, site, cam->icam, calib_dir, NULL, &opt->audit_options, &aerr);
        cam->has_audit = ast == RS_OK;
        if (ast) {
            rs_audit_result_free(&cam->audit);
            snprintf(cam->audit_error, sizeof cam->audit_error, "%s", aerr.msg[0] ? aerr.msg : rs_strerror(ast));
        }
    } else if (!st)
        snprintf(cam->audit_error, sizeof cam->audit_error, "the audit was not requested");
    return st;
}

rs_status rs_report_load_cameras(struct rs_report_ctx *rep, const rs_report_options *opt, rs_err *err)
{
    rep->cameras = calloc((size_t)rep->site->Ncameras + 1, sizeof *rep->cameras);
    if (!rep->cameras) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = read_lanes(&rep->lanes, rep->site, err);
    for (int c = 0; c < rep->site->Ncameras && !st; c++) {
        if (opt->progress) {
            char what[300];
            snprintf(what, sizeof what, "camera %s (%d of %d): reading its calibration%s", rep->site->cameras[c].id,
                     c + 1, rep->site->Ncameras, opt->audit ? " and auditing it" : "");
            opt->progress(opt->progress_ctx, what);
        }
        rs_report_camera *cam = &rep->cameras[rep->Ncameras++];
        cam->rep = rep;
        cam->icam = c;
        cam->colour = c;
        st = camera_load(cam, rep->site, rep->calib_dir, opt, err);
    }
    if (!st && !rs_report_best_map(rep)) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    return st;
}

// The site map's orthophoto (rep->ortho): the one named, else SITE/ortho.tif when the site has
// one; none otherwise. A file that is there but unreadable is an error naming it.
static rs_status load_ortho(struct rs_report_ctx *rep, const rs_report_options *opt, rs_err *err)
{
    if (opt->ortho_path) {
        rep->ortho_path = strdup(opt->ortho_path);
    } else {
        rep->ortho_path = rs_io_join(rep->site->dir, "ortho.tif");
        struct stat sb; // (a link loop or a FIFO there is read, and refused with its reason)
        if (rep->ortho_path && lstat(rep->ortho_path, &sb) != 0 && errno == ENOENT) {
            free(rep->ortho_path);
            rep->ortho_path = NULL;
            return RS_OK;
        }
    }
    if (!rep->ortho_path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = rs_geo_ortho_read(&rep->ortho, rep->ortho_path, &rep->site->origin, 2048, err);
    if (st) rs_err_prefix(err, "orthophoto");
    return st;
}

void rs_report_free_cameras(struct rs_report_ctx *rep)
{
    for (int c = 0; c < rep->Ncameras; c++) camera_free(&rep->cameras[c]);
    free(rep->cameras);
    free(rep->lanes.start);
    free(rep->lanes.p_enu_m);
    free(rep->lanes.junction);
    free(rep->best_map.sigma_m);
    rs_geo_ortho_free(&rep->ortho);
    free(rep->ortho_path);
    rep->ortho_path = NULL;
    rep->cameras = NULL;
    rep->Ncameras = 0;
}

// ---- the document ----

// The audit's verdict (rs_audit_result.pass), never one of the report's own.
static const char *verdict(const rs_report_camera *cam)
{
    if (!cam->has_audit) return "not audited";
    return cam->audit.pass ? "pass" : "FAIL";
}

// A residual in a table cell: "-" when <id>.json predates it.
static void cell_px(rs_doc *doc, double v)
{
    if (isfinite(v))
        rs_doc_cell(doc, "%.3f", v);
    else
        rs_doc_cell(doc, "-");
}

static void doc_site(rs_doc *doc, const struct rs_report_ctx *rep, const char *calib_dir)
{
    const rs_site *site = rep->site;
    rs_doc_heading(doc, 1, "Camera calibration report: %s", site->name);
    char stamp[200];
    rs_report_stamp(stamp, sizeof stamp, rep);
    rs_doc_paragraph(doc, false, "%s from the calibration in %s. The inputs and their SHA-256 are listed at the end.",
                     stamp, calib_dir);
    rs_report_doc_verdicts(doc, rep); // the action first, then the evidence
    rs_doc_heading(doc, 2, "The evidence");
    rs_doc_paragraph(doc, false,
                     "Site folder %s; origin %.8f, %.8f, %.3f m (latitude, longitude in degrees, WGS84 "
                     "ellipsoidal height%s); %d surveyed landmarks; %d cameras. Positions are in the site's local "
                     "east-north-up frame (metres from the origin); yaw is the compass heading of the optical axis, "
                     "pitch its elevation (negative looking down), roll the turn about it.",
                     site->dir, site->origin.lat_deg, site->origin.lon_deg, site->origin.h_m,
                     site->heights_orthometric ? "; the site's heights are orthometric, converted" : "",
                     site->Nlandmarks, site->Ncameras);
    char audit[700] = "the audit was not requested";
    const rs_audit_options *ao = rep->audit_options;
    if (ao)
        snprintf(audit, sizeof audit,
                 "the verdict of roadside audit %s --calib %s --need-ground-m %g (thresholds per camera in its "
                 "section)",
                 site->dir, calib_dir, ao->need_ground_m);
    rs_doc_paragraph(doc, false,
                     "In the table: the RMS reprojection error of the inliers' surveyed positions through the "
                     "calibration, in pixels (what anyone can check with the survey and the picks; "
                     "docs/calibration.md, \"Residuals: which is which\"); the leave-one-out figures, each inlier "
                     "predicted by the pose solved without it, in pixels and on the ground; audit: %s.",
                     audit);
    rs_doc_table(doc, 9);
    static const char *head[9] = {"camera",          "used",          "rejected",
                                  "rms_surveyed_px", "loo_rms_px",    "loo_median_m",
                                  "sigma pos m",     "sigma yaw deg", "audit"};
    for (int k = 0; k < 9; k++) rs_doc_cell(doc, "%s", head[k]);
    for (int c = 0; c < rep->Ncameras; c++) {
        const rs_report_camera *cam = &rep->cameras[c];
        const double *s = cam->sigma_position_enu_m;
        rs_doc_cell(doc, "%s", site->cameras[cam->icam].id);
        rs_doc_cell(doc, "%d", cam->Nused);
        rs_doc_cell(doc, "%d", cam->Nrejected);
        cell_px(doc, cam->rms_surveyed_px);
        if (cam->has_audit && cam->audit.loo_count > 0) {
            rs_doc_cell(doc, "%.3f", cam->audit.loo_rms_px);
            rs_doc_cell(doc, "%.3f", cam->audit.loo_median_m);
        } else {
            rs_doc_cell(doc, "-");
            rs_doc_cell(doc, "-");
        }
        rs_doc_cell(doc, "%.3f", sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]));
        rs_doc_cell(doc, "%.3f", cam->sigma_yaw_pitch_roll_deg[0]);
        rs_doc_cell(doc, "%s", verdict(cam));
    }
    char colour[400] = "";
    if (rep->best_map.sigma_m)
        snprintf(colour, sizeof colour,
                 "; colour: the 1-sigma horizontal error in metres of a vehicle located on "
                 "the ground by the best camera seeing it (pose covariance plus %g px detection noise), with "
                 "labelled contours",
                 rep->detection_sigma_px);
    char ortho[320] = "";
    if (rep->ortho.rgb)
        snprintf(ortho, sizeof ortho, " Drawn on the orthophoto %s (%s%s, %.2g m per pixel as drawn).", rep->ortho_path,
                 rep->ortho.crs_name ? rep->ortho.crs_name : "its CRS",
                 rep->ortho.warped ? ", reprojected to the site's frame" : "", rep->ortho.grid.cell_m);
    rs_doc_figure(doc, rs_report_draw_site_map, rep, 0.8,
                  "Site map, north up, in the local east-north-up frame: cameras (discs, with a line along the "
                  "heading), the ground each camera sees within %g m (dashed outline%s), surveyed "
                  "landmarks (dots)%s%s.%s",
                  rep->range_m, rep->best_map.sigma_m ? "" : ", tinted",
                  rep->lanes.Nlines ? " and lane lines (yellow)" : "", colour, ortho);
}

static void doc_camera(rs_doc *doc, const struct rs_report_ctx *rep, const rs_report_camera *cam)
{
    const rs_site *site = rep->site;
    const char *id = site->cameras[cam->icam].id;
    rs_doc_heading(doc, 2, "Camera %s", id);
    rs_report_doc_camera_verdict(doc, rep, cam);
    if (site->cameras[cam->icam].note) rs_doc_paragraph(doc, false, "Note: %s", site->cameras[cam->icam].note);
    char bg[700];
    if (cam->background)
        snprintf(bg, sizeof bg, "background %s (%d x %d px)", cam->background_path,
                 cairo_image_surface_get_width(cam->background), cairo_image_surface_get_height(cam->background));
    else
        snprintf(bg, sizeof bg, "no background image, neutral canvas");
    rs_doc_figure(doc, rs_report_draw_camera, cam, (double)cam->model.height / cam->model.width,
                  "%s, %d x %d px, %s: picks (green circles; red crosses for outliers), the surveyed landmarks "
                  "reprojected through the calibration (blue dots), inlier residual vectors (surveyed, from the pick "
                  "to the reprojection) magnified %g times (pink; the scale "
                  "bar gives their length in pixels) and outlier residuals at true size (dashed red), ground grid "
                  "every %g m and lane lines projected through the "
                  "calibrated lens model.",
                  id, cam->model.width, cam->model.height, bg, cam->magnification, rep->grid_m);

    rs_doc_heading(doc, 3, "Pose of %s", id);
    rs_doc_table(doc, 3);
    rs_doc_cell(doc, "quantity");
    rs_doc_cell(doc, "value");
    rs_doc_cell(doc, "1-sigma");
    static const char *enu[3] = {"east", "north", "up"};
    for (int k = 0; k < 3; k++) {
        rs_doc_cell(doc, "position %s, m", enu[k]);
        rs_doc_cell(doc, "%.3f", cam->position_enu_m[k]);
        rs_doc_cell(doc, "%.3f", cam->sigma_position_enu_m[k]);
    }
    rs_doc_cell(doc, "latitude, deg");
    rs_doc_cell(doc, "%.8f", cam->position_llh[0]);
    rs_doc_cell(doc, "-");
    rs_doc_cell(doc, "longitude, deg");
    rs_doc_cell(doc, "%.8f", cam->position_llh[1]);
    rs_doc_cell(doc, "-");
    rs_doc_cell(doc, "height (ellipsoidal), m");
    rs_doc_cell(doc, "%.3f", cam->position_llh[2]);
    rs_doc_cell(doc, "%.3f", cam->sigma_position_enu_m[2]);
    static const char *ypr[3] = {"yaw (heading), deg", "pitch (elevation), deg", "roll, deg"};
    for (int k = 0; k < 3; k++) {
        rs_doc_cell(doc, "%s", ypr[k]);
        rs_doc_cell(doc, "%.3f", cam->yaw_pitch_roll_deg[k]);
        rs_doc_cell(doc, "%.3f", cam->sigma_yaw_pitch_roll_deg[k]);
    }
    rs_doc_cell(doc, "rms_surveyed_px: RMS reprojection error of the inliers' surveyed positions, px");
    cell_px(doc, cam->rms_surveyed_px);
    rs_doc_cell(doc, "-");
    rs_doc_cell(doc, "rms_adjusted_px: the same after the landmarks moved within their survey sigmas, px");
    rs_doc_cell(doc, "%.3f", cam->rms_adjusted_px);
    rs_doc_cell(doc, "-");
    rs_doc_cell(doc, "variance factor chi2/dof (about 1: sigmas right)");
    rs_doc_cell(doc, "%.3f", cam->variance_factor);
    rs_doc_cell(doc, "-");
    rs_doc_cell(doc, "condition number");
    rs_doc_cell(doc, "%.2f", cam->condition_number);
    rs_doc_cell(doc, "-");
    rs_doc_cell(doc, "landmarks used / rejected");
    rs_doc_cell(doc, "%d / %d", cam->Nused, cam->Nrejected);
    rs_doc_cell(doc, "-");
    rs_doc_cell(doc, "lens model");
    rs_doc_cell(doc, "%s", cam->lensmodel);
    rs_doc_cell(doc, "-");
    rs_report_doc_pose_words(doc, cam);

    const rs_audit_result *a = cam->has_audit ? &cam->audit : NULL;
    rs_doc_heading(doc, 3, "Landmarks of %s", id);
    rs_doc_paragraph(doc, false,
                     "Residual du, dv = the landmark's surveyed position reprojected through the calibration - "
                     "picked pixel (the residuals of the RMS in the pose table); normalised = the residual in "
                     "sigmas (pick and survey together). Leave-one-out (loo): the pose re-solved without the "
                     "landmark, then its "
                     "surveyed position projected (px) and its pick located on the ground (m); influence: how far "
                     "leaving it out moves (m) and turns (deg) the camera.");
    rs_doc_table(doc, 11);
    static const char *lhead[11] = {"landmark", "u px",   "v px",  "du px",   "dv px",    "normalised",
                                    "status",   "loo px", "loo m", "infl. m", "infl. deg"};
    for (int k = 0; k < 11; k++) rs_doc_cell(doc, "%s", lhead[k]);
    const rs_site_camera *sc = &site->cameras[cam->icam];
    for (int i = 0; i < cam->N; i++) {
        const rs_report_landmark *l = &cam->landmarks[i];
        rs_doc_cell(doc, "%s", l->id);
        rs_doc_cell(doc, "%.2f", l->observed_px[0]);
        rs_doc_cell(doc, "%.2f", l->observed_px[1]);
        cell_px(doc, l->residual_surveyed_px[0]);
        cell_px(doc, l->residual_surveyed_px[1]);
        rs_doc_cell(doc, "%.2f", l->normalised);
        rs_doc_cell(doc, "%s", l->inlier ? "inlier" : "outlier");
        // the audit's landmark i is the site camera's observation i
        const rs_audit_landmark *al = NULL;
        if (a && i < a->N && i < sc->Nobservations && sc->observations[i].ilandmark == l->ilandmark)
            al = &a->landmarks[i];
        if (al && al->loo_ok) {
            rs_doc_cell(doc, "%.3f", al->loo_error_px);
            rs_doc_cell(doc, "%.3f", al->loo_ground_error_m);
            rs_doc_cell(doc, "%.3f", al->influence_m);
            rs_doc_cell(doc, "%.3f", al->influence_deg);
        } else
            for (int k = 0; k < 4; k++) rs_doc_cell(doc, "-");
    }

    rs_doc_heading(doc, 3, "Ground localisation uncertainty of %s", id);
    rs_doc_figure(doc, rs_report_draw_camera_map, cam, 0.8,
                  "%s seen from above, north up: the 1-sigma horizontal error in metres of a vehicle located on the "
                  "ground from this camera (pose covariance plus %g px detection noise), as a colour scale with "
                  "labelled contours, over the ground it sees within %g m (dashed); its landmarks (black dots, red "
                  "crosses for outliers).",
                  id, rep->detection_sigma_px, rep->range_m);
    if (a) {
        rs_doc_paragraph(
            doc, false,
            "Leave-one-out over %d landmarks: each predicted %.3f px off (RMS), worst %.3f px; on "
            "the ground %.3f m off (median), worst %.3f m. Coverage: the inlier picks span %.0f%% of the image; the "
            "inlier landmarks "
            "span %.0f%% of the %.0f m2 of ground the camera sees within %g m.",
            a->loo_count, a->loo_rms_px, a->loo_max_px, a->loo_median_m, a->loo_max_m, 100 * a->image_hull_share,
            100 * a->ground_hull_share, a->ground_seen_m2, rep->range_m);
    }

    rs_doc_heading(doc, 3, "Verdict and warnings for %s", id);
    if (a)
        rs_doc_paragraph(doc, !a->pass,
                         "Audit (roadside audit --calib of these files, need %g m): %s%s%s. Thresholds: "
                         "the surveyed landmarks' and the held-out landmarks' RMS reprojection errors at most %.3g px "
                         "(%g m at %.1f px per metre of ground at "
                         "the landmarks), the held-out landmarks' median ground error at most %g m, predicted ground "
                         "error (90th percentile where "
                         "the landmarks are, %.2f m here) at most %g m.",
                         a->thresholds.need_ground_m, a->pass ? "pass, every threshold met" : "FAIL",
                         a->pass ? "" : ": ", a->pass ? "" : a->failures, a->thresholds.max_rms_surveyed_px,
                         a->thresholds.need_ground_m, a->px_per_m, a->thresholds.max_loo_m,
                         a->ground_sigma_inside_p90_m, a->thresholds.max_ground_sigma_m);
    else
        rs_doc_paragraph(doc, true, "No audit for this camera: %s.", cam->audit_error);
    if (!rs_report_doc_warnings(doc, rep, cam)) rs_doc_paragraph(doc, false, "No warnings.");
}

// ---- writing ----

static rs_status write_report(rs_report_summary *summary, const char *out_dir, const rs_site *site,
                              const rs_report_options *opt_in, rs_err *err)
{
    rs_report_options opt;
    if (opt_in)
        opt = *opt_in;
    else
        rs_report_options_default(&opt);
    if (summary) memset(summary, 0, sizeof *summary);
    if (!(opt.range_m > 0) || !isfinite(opt.range_m) || !isfinite(opt.grid_m) || opt.figure_width_px < 200 ||
        opt.figure_width_px > 10000)
        return rs_err_set(err, RS_ERR_INVALID,
                          "report options: range_m > 0, finite grid_m and figure_width_px in "
                          "[200, 10000] expected");
    if (site->Ncameras < 1) return rs_err_set(err, RS_ERR_INVALID, "%s: the site has no camera", site->dir);
    opt.audit_options.range_m = opt.range_m; // one range for the figures and the maps

    struct rs_report_ctx rep = {
        .site = site, .range_m = opt.range_m, .version = opt.version, .written_utc_s = opt.written_utc_s};
    rep.grid_m = opt.grid_m > 0 ? opt.grid_m : opt.range_m / 10;
    rep.detection_sigma_px = opt.audit_options.detection_sigma_px;
    rep.audit_options = opt.audit ? &opt.audit_options : NULL;
    char *default_calib = opt.calib_dir ? NULL : rs_io_join(site->dir, "calib");
    const char *calib_dir = opt.calib_dir ? opt.calib_dir : default_calib;
    rep.calib_dir = calib_dir;
    rs_doc doc = {0};
    char *html_path = rs_io_join(out_dir, "report.html"), *pdf_path = rs_io_join(out_dir, "report.pdf");
    rs_status st = calib_dir && html_path && pdf_path ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "report: out of memory");
    if (!st) st = rs_report_load_cameras(&rep, &opt, err);
    if (!st) st = load_ortho(&rep, &opt, err);
    if (!st) {
        doc_site(&doc, &rep, calib_dir);
        for (int c = 0; c < rep.Ncameras; c++) doc_camera(&doc, &rep, &rep.cameras[c]);
        rs_report_doc_inputs(&doc, &rep);
    }
    if (!st) st = rs_io_mkdir_p(out_dir, err);
    char title[512];
    snprintf(title, sizeof title, "roadside report: %s", site->name);
    // both files under temporary names, then both into place: the two are one report
    rs_io_atomic html = {0}, pdf = {0};
    if (!st) st = rs_io_atomic_open(&html, html_path, err);
    if (!st) st = rs_io_atomic_open(&pdf, pdf_path, err);
    if (!st) st = rs_io_atomic_release(&html, err);
    if (!st) st = rs_io_atomic_release(&pdf, err);
    if (!st && opt.progress) opt.progress(opt.progress_ctx, "drawing report.html");
    if (!st) st = rs_doc_write_html(&doc, title, opt.figure_width_px, html.tmp_path, err);
    if (!st && opt.progress) opt.progress(opt.progress_ctx, "drawing report.pdf");
    if (!st) st = rs_doc_write_pdf(&doc, title, pdf.tmp_path, err);
    if (!st) st = rs_io_atomic_commit(&html, err);
    if (!st) st = rs_io_atomic_commit(&pdf, err);
    rs_io_atomic_abort(&html);
    rs_io_atomic_abort(&pdf);
    if (!st && summary) {
        summary->Ncameras = rep.Ncameras;
        summary->Nfigures = doc.Nfigures;
        for (int c = 0; c < rep.Ncameras; c++) {
            summary->Naudit_failed += opt.audit && !rep.cameras[c].has_audit;
            summary->Naudit_fail += rep.cameras[c].has_audit && !rep.cameras[c].audit.pass;
        }
    }
    rs_doc_free(&doc);
    rs_report_free_cameras(&rep);
    free(html_path);
    free(pdf_path);
    free(default_calib);
    return st;
}

rs_status rs_report_write(rs_report_summary *summary, const char *out_dir, const rs_site *site,
                          const rs_report_options *opt, rs_err *err)
{
    rs_err local = {0};
    if (!err) err = &local;
    struct stat sb;
    const bool out_existed = stat(out_dir, &sb) == 0;
    rs_status st = write_report(summary, out_dir, site, opt, err);
    if (st) { // no report, and no earlier one that would look like this run's
        int Nremoved = 0;
        rs_err rerr = {0};
        if (rs_report_remove(&Nremoved, out_dir, &rerr)) {
            char first[sizeof err->msg];
            snprintf(first, sizeof first, "%s", err->msg);
            rs_err_set(err, st, "%s; and %s", first, rerr.msg);
        }
        if (summary) summary->Nremoved = Nremoved;
        if (!out_existed) (void)rmdir(out_dir); // only when this call made it (and it is empty)
    }
    return st;
}

rs_status rs_report_remove(int *Nremoved, const char *out_dir, rs_err *err)
{
    if (Nremoved) *Nremoved = 0;
    rs_status first = RS_OK;
    static const char *const names[] = {"report.html", "report.pdf"};
    for (int k = 0; k < 2; k++) {
        char *path = rs_io_join(out_dir, names[k]);
        bool was = false;
        rs_status st = path ? rs_io_remove_if_exists(path, &was, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(path);
        if (Nremoved) *Nremoved += was;
        if (st && !first) first = st;
    }
    return first;
}
