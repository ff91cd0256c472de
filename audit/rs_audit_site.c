// rs_audit_site.c -- audits of a site's cameras: external calibration files, new picks
// (--against), <id>.audit.json. See rs_audit.h.
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include <cjson/cJSON.h>

#include "audit/rs_audit.h"
#include "calib/rs_calib_site.h"
#include "core/rs_camera.h"
#include "core/rs_io.h"

// ---- external calibration files ----

void rs_audit_calibration_free(rs_audit_calibration *cal)
{
    if (!cal) return;
    free(cal->path);
    rs_camera_free(&cal->camera);
    memset(cal, 0, sizeof *cal);
}

rs_status rs_audit_calibration_read(rs_audit_calibration *out, const char *path, rs_err *err)
{
    memset(out, 0, sizeof *out);
    rs_status st = rs_camera_read(&out->camera, &out->extra, path, err);
    if (st == RS_OK && !rs_io_has_extension(path, "cameramodel") && !out->extra.has_pose)
        st = rs_err_set(err, RS_ERR_INVALID, "%s: R (or rvec) and tvec (or t): missing, the pose is needed", path);
    if (st == RS_OK && !(out->path = strdup(path))) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (st) rs_audit_calibration_free(out);
    return st;
}

// The calibration file of camera `id` given a file or a folder: <id>.cameramodel, then
// <id>.opencv.yaml, <id>.yaml, <id>.yml, <id>.json. Returns a malloc'ed path or NULL.
static char *find_calibration(const char *calib_path, const char *id, rs_err *err)
{
    struct stat sb;
    if (stat(calib_path, &sb) != 0) {
        rs_err_set(err, RS_ERR_IO, "%s: %s", calib_path, strerror(errno));
        return NULL;
    }
    if (!S_ISDIR(sb.st_mode)) {
        char *p = strdup(calib_path);
        if (!p) rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        return p;
    }
    static const char *const ext[] = {RS_CAMERA_EXT_CAMERAMODEL, RS_CAMERA_EXT_OPENCV_YAML, ".yaml", ".yml", ".json"};
    for (size_t k = 0; k < sizeof ext / sizeof ext[0]; k++) {
        char p[4096];
        if (!rs_camera_path(p, sizeof p, calib_path, id, ext[k])) {
            rs_err_set(err, RS_ERR_INVALID, "%s: path too long", calib_path);
            return NULL;
        }
        if (stat(p, &sb) == 0 && S_ISREG(sb.st_mode)) {
            char *found = strdup(p);
            if (!found) rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            return found;
        }
    }
    rs_err_set(err, RS_ERR_NOT_FOUND, "%s: no %s.cameramodel, %s.opencv.yaml, %s.yaml, %s.yml or %s.json", calib_path,
               id, id, id, id, id);
    return NULL;
}

// ---- new picks (--against) ----

// Splits a CSV line in place at commas, trimming blanks; returns the field count.
static int csv_fields(char *s, char **f, int maxf)
{
    int n = 0;
    for (char *tok = s;; tok++) {
        char *end = strchr(tok, ',');
        if (end) *end = '\0';
        while (isspace((unsigned char)*tok)) tok++;
        char *e = tok + strlen(tok);
        while (e > tok && isspace((unsigned char)e[-1])) *--e = '\0';
        if (n < maxf) f[n] = tok;
        n++;
        if (!end) break;
        tok = end;
    }
    return n;
}

static bool csv_number(const char *s, double *v)
{
    char *end;
    errno = 0;
    *v = strtod(s, &end);
    return *s && *end == '\0' && errno == 0 && isfinite(*v);
}

// Reads `path` (landmark,u,v[,sigma_px]) into q_new (N,2) / s_new (N,) indexed like the camera's
// observations; rows not re-picked stay NaN.
static rs_status read_new_picks(double *q_new, double *s_new, const rs_site *site, int icam, const char *path,
                                rs_err *err)
{
    const rs_site_camera *cam = &site->cameras[icam];
    for (int i = 0; i < cam->Nobservations; i++) q_new[2 * i] = q_new[2 * i + 1] = s_new[i] = NAN;
    char *text = NULL;
    rs_status st = rs_io_read_file(&text, NULL, path, err);
    if (st) return st;
    int line = 0, col_sigma = -1;
    bool header = false;
    for (char *s = text, *next; s && *s; s = next) {
        next = strchr(s, '\n');
        if (next) *next++ = '\0';
        line++;
        size_t len = strlen(s);
        if (len && s[len - 1] == '\r') s[len - 1] = '\0';
        char *f[8];
        int n = csv_fields(s, f, 8);
        if (n == 1 && (f[0][0] == '\0' || f[0][0] == '#')) continue;
        if (!header) {
            if (n < 3 || strcmp(f[0], "landmark") || strcmp(f[1], "u") || strcmp(f[2], "v") ||
                (n >= 4 && strcmp(f[3], "sigma_px")) || n > 4) {
                st = rs_err_set(err, RS_ERR_PARSE, "%s:%d: header: expected \"landmark,u,v[,sigma_px]\"", path, line);
                goto done;
            }
            col_sigma = n == 4 ? 3 : -1;
            header = true;
            continue;
        }
        if (n != (col_sigma < 0 ? 3 : 4)) {
            st = rs_err_set(err, RS_ERR_PARSE, "%s:%d: %d fields, the header has %d", path, line, n,
                            col_sigma < 0 ? 3 : 4);
            goto done;
        }
        int il = rs_site_find_landmark(site, f[0]);
        if (il < 0) {
            st = rs_err_set(err, RS_ERR_NOT_FOUND, "%s:%d: landmark: '%s' is not in the site's landmarks", path, line,
                            f[0]);
            goto done;
        }
        double u, v, sg = 1;
        static const char *const names[] = {"u", "v", "sigma_px"};
        double *dst[] = {&u, &v, &sg};
        for (int k = 0; k < (col_sigma < 0 ? 2 : 3); k++)
            if (!csv_number(f[1 + k], dst[k])) {
                st = rs_err_set(err, RS_ERR_PARSE, "%s:%d: %s: '%s' is not a finite number", path, line, names[k],
                                f[1 + k]);
                goto done;
            }
        if (!(sg > 0)) {
            st = rs_err_set(err, RS_ERR_INVALID, "%s:%d: sigma_px: %g, must be > 0", path, line, sg);
            goto done;
        }
        for (int i = 0; i < cam->Nobservations; i++)
            if (cam->observations[i].ilandmark == il) {
                if (isfinite(q_new[2 * i])) {
                    st = rs_err_set(err, RS_ERR_INVALID, "%s:%d: landmark: '%s' picked twice", path, line, f[0]);
                    goto done;
                }
                q_new[2 * i] = u;
                q_new[2 * i + 1] = v;
                s_new[i] = sg;
            }
    }
    if (!header) st = rs_err_set(err, RS_ERR_PARSE, "%s: empty, expected the header \"landmark,u,v[,sigma_px]\"", path);
done:
    free(text);
    return st;
}

// ---- a site camera ----

rs_status rs_audit_site_camera(rs_audit_result *result, const rs_site *site, int icam, const char *calib_path,
                               const char *against_csv, const rs_audit_options *opt, rs_err *err)
{
    memset(result, 0, sizeof *result);
    const rs_site_camera *cam = &site->cameras[icam];
    rs_calib_site_problem sp;
    rs_audit_calibration cal;
    memset(&cal, 0, sizeof cal);
    double *q_new = NULL;
    rs_status st = rs_calib_site_problem_init(&sp, site, icam, err);
    if (st) return st;
    if (calib_path) {
        char *path = find_calibration(calib_path, cam->id, err);
        st = path ? rs_audit_calibration_read(&cal, path, err) : err ? err->status : RS_ERR_NOT_FOUND;
        free(path);
        if (st) goto done;
    }
    if (against_csv) {
        int N = cam->Nobservations;
        q_new = malloc((size_t)(N > 0 ? N : 1) * 3 * sizeof *q_new);
        if (!q_new) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            goto done;
        }
        if ((st = read_new_picks(q_new, q_new + 2 * N, site, icam, against_csv, err))) goto done;
    }
    st = rs_audit_camera(result, &sp.problem, site->ground_normal_enu, site->ground_offset_m, q_new,
                         q_new ? q_new + 2 * cam->Nobservations : NULL, calib_path ? &cal : NULL, opt, err);
    if (st == RS_OK) { // landmarks named by id, the verdict in words
        rs_calib_site_name_landmarks(result->warnings, sizeof result->warnings, site, icam);
        rs_audit_site_verdict(result->verdict, sizeof result->verdict, site, icam, result);
    }
done:
    free(q_new);
    rs_audit_calibration_free(&cal);
    rs_calib_site_problem_free(&sp);
    return st;
}

// ---- in words ----

// The id of the camera's observation i ("#i" when out of range).
static const char *obs_id(char *buf, size_t size, const rs_site *site, int icam, int i)
{
    const rs_site_camera *cam = &site->cameras[icam];
    if (i >= 0 && i < cam->Nobservations && cam->observations[i].ilandmark >= 0 &&
        cam->observations[i].ilandmark < site->Nlandmarks && site->landmarks[cam->observations[i].ilandmark].id)
        return site->landmarks[cam->observations[i].ilandmark].id;
    snprintf(buf, size, "#%d", i);
    return buf;
}

// Appends printf text to a fixed buffer (truncating).
__attribute__((format(printf, 3, 4))) static void say(char *buf, size_t size, const char *fmt, ...)
{
    size_t n = strlen(buf);
    if (n + 1 >= size) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf + n, size - n, fmt, ap);
    va_end(ap);
}

void rs_audit_site_verdict(char *text, size_t size, const rs_site *site, int icam, const rs_audit_result *r)
{
    text[0] = '\0';
    char buf[16];
    const double need = r->thresholds.need_ground_m;
    say(text, size, "%s for the need of %g m (1 sigma on the ground where the landmarks are). ",
        r->pass ? "Good enough" : "NOT good enough", need);
    if (isfinite(r->ground_sigma_inside_median_m)) {
        int far = -1; // the farthest inlier with a predicted sigma
        for (int i = 0; i < r->N; i++)
            if (r->landmarks[i].inlier && isfinite(r->landmarks[i].sigma_ground_m) &&
                (far < 0 || r->landmarks[i].distance_m > r->landmarks[far].distance_m))
                far = i;
        say(text, size,
            "Ground positions within the landmarks' area are good to %.2f m (1 sigma, median; 90%% of it "
            "within %.2f m)",
            r->ground_sigma_inside_median_m, r->ground_sigma_inside_p90_m);
        if (far >= 0)
            say(text, size, ", %.2f m at the farthest landmark, %s, %.0f m from the camera",
                r->landmarks[far].sigma_ground_m, obs_id(buf, sizeof buf, site, icam, far),
                r->landmarks[far].distance_m);
        say(text, size, ". ");
    }
    if (r->loo_count)
        say(text, size,
            "Checked against the survey, each landmark left out in turn is located from its pick "
            "%.2f m from its surveyed position (median; worst %.2f m)%s. ",
            r->loo_median_m, r->loo_max_m,
            r->loo_median_m > r->thresholds.max_loo_m ? ", more than the need allows" : "");
    for (int i = 0; i < r->N; i++) {
        const rs_audit_landmark *L = &r->landmarks[i];
        const char *id = obs_id(buf, sizeof buf, site, icam, i);
        const double px = hypot(L->residual_surveyed_px[0], L->residual_surveyed_px[1]);
        if (!L->inlier) {
            say(text, size, "Landmark %s disagrees with the survey", id);
            if (L->loo_ok && isfinite(L->loo_ground_error_m))
                say(text, size, " by %.1f m on the ground", L->loo_ground_error_m);
            if (isfinite(px)) say(text, size, " (%.0f px in the image)", px);
            say(text, size, ": it was left out; re-survey it or re-pick it. ");
        } else if (L->reason[0])
            say(text, size, "Landmark %s: %s%s%.1f m on the ground: check its survey and its pick. ", id,
                L->loo_ok ? "the others locate it " : "", L->loo_ok ? "" : "", L->loo_ok ? L->loo_ground_error_m : NAN);
    }
    // the image says the nominal focal length is wrong: that, not the survey, is the first fix
    const rs_calib_intrinsics_check *ic = &r->solve.intrinsics_check;
    const bool focal_off = ic->focal_tested && ic->chi2_focal > ic->critical_focal;
    if (!r->pass) {
        say(text, size, "Fails: %s.", r->failures);
        if (focal_off)
            say(text, size,
                " The image says the focal length is %.0f%% %s than the nominal: recalibrate with 'roadside calib %s "
                "--refine focal' first (a resurvey will not fix a wrong focal length).",
                100 * fabs(ic->focal_rel), ic->focal_rel >= 0 ? "longer" : "shorter", site->dir);
        else if (r->loo_count && r->loo_median_m > r->thresholds.max_loo_m)
            say(text, size,
                " To meet the need, survey the landmarks more accurately or add landmarks spread over the "
                "area, then re-pick and recalibrate.");
    } else if (r->warnings[0])
        say(text, size, "Passes, with warnings below.");
    else
        say(text, size, "Passes every threshold.");
}

// ---- JSON ----

static cJSON *num_array(const double *v, int n) { return cJSON_CreateDoubleArray(v, n); }

// A "; "-separated text as a JSON list of strings.
static cJSON *sentences(const char *text)
{
    cJSON *a = cJSON_CreateArray();
    for (const char *s = text; a && *s;) {
        const size_t n = rs_calib_warning_len(s); // a "; " inside parentheses belongs to the sentence
        char *one = strndup(s, n);
        if (one) cJSON_AddItemToArray(a, cJSON_CreateString(one));
        free(one);
        s += n + (s[n] ? 2 : 0);
    }
    return a;
}

// Adds name: number members from a table.
typedef struct {
    const char *name;
    double value;
} named_number;

static void add_numbers(cJSON *o, const named_number *v, size_t n)
{
    for (size_t i = 0; i < n; i++) cJSON_AddNumberToObject(o, v[i].name, v[i].value);
}
#define ADD_NUMBERS(o, ...)                               \
    add_numbers((o), (const named_number[]){__VA_ARGS__}, \
                sizeof((const named_number[]){__VA_ARGS__}) / sizeof(named_number))

static void add_landmarks(cJSON *root, const rs_site *site, const rs_site_camera *cam, const rs_audit_result *r)
{
    cJSON *lms = cJSON_AddArrayToObject(root, "landmarks");
    for (int i = 0; lms && i < r->N; i++) {
        const rs_audit_landmark *L = &r->landmarks[i];
        const rs_site_observation *o = &cam->observations[i];
        cJSON *l = cJSON_CreateObject();
        cJSON_AddStringToObject(l, "id", site->landmarks[o->ilandmark].id);
        cJSON_AddItemToObject(l, "observed_px", num_array(o->q_px, 2));
        cJSON_AddBoolToObject(l, "inlier", L->inlier);
        cJSON_AddItemToObject(l, "residual_surveyed_px", num_array(L->residual_surveyed_px, 2));
        cJSON_AddItemToObject(l, "residual_adjusted_px", num_array(L->residual_adjusted_px, 2));
        cJSON_AddNumberToObject(l, "normalised_residual", L->normalised_residual);
        cJSON_AddStringToObject(l, "reason", L->reason);
        cJSON_AddBoolToObject(l, "loo_ok", L->loo_ok);
        cJSON_AddItemToObject(l, "loo_predicted_px", num_array(L->loo_predicted_px, 2));
        ADD_NUMBERS(l, {"loo_error_px", L->loo_error_px}, {"loo_normalised", L->loo_normalised},
                    {"loo_ground_error_m", L->loo_ground_error_m}, {"influence_m", L->influence_m},
                    {"influence_deg", L->influence_deg}, {"sigma_ground_m", L->sigma_ground_m},
                    {"distance_m", L->distance_m});
        if (r->has_external)
            cJSON_AddItemToObject(l, "external_residual_surveyed_px",
                                  num_array(&r->external.residual_surveyed_px[2 * i], 2));
        cJSON_AddItemToArray(lms, l);
    }
}

static void add_map(cJSON *root, const rs_audit_map *m)
{
    cJSON *jm = cJSON_AddObjectToObject(root, "uncertainty_map");
    ADD_NUMBERS(jm, {"e0_m", m->e0_m}, {"n0_m", m->n0_m}, {"cell_m", m->cell_m}, {"nx", m->nx}, {"ny", m->ny},
                {"detection_sigma_px", m->detection_sigma_px}, {"range_m", m->range_m});
    cJSON_AddItemToObject(jm, "camera_en_m", num_array(m->camera_en_m, 2));
    cJSON *rows = cJSON_AddArrayToObject(jm, "sigma_m");
    for (int iy = 0; rows && iy < m->ny; iy++) cJSON_AddItemToArray(rows, num_array(&m->sigma_m[iy * m->nx], m->nx));
}

char *rs_audit_result_json(const rs_site *site, int icam, const rs_audit_result *r, const rs_audit_options *opt)
{
    rs_audit_options defaults;
    if (!opt) {
        rs_audit_options_default(&defaults);
        opt = &defaults;
    }
    const rs_site_camera *cam = &site->cameras[icam];
    // the solve: the same object as `roadside calib`'s <id>.json
    char *solve_text = rs_calib_site_result_json(site, icam, &r->solve);
    cJSON *solve = solve_text ? cJSON_Parse(solve_text) : NULL;
    free(solve_text);
    cJSON *root = cJSON_CreateObject();
    if (!root || !solve) {
        cJSON_Delete(root);
        cJSON_Delete(solve);
        return NULL;
    }
    cJSON_AddStringToObject(root, "camera", cam->id);
    cJSON_AddStringToObject(root, "site", site->name ? site->name : "");
    cJSON_AddBoolToObject(root, "pass", r->pass);
    cJSON_AddItemToObject(root, "failures", sentences(r->failures));
    cJSON_AddItemToObject(root, "warnings", sentences(r->warnings));
    cJSON_AddStringToObject(root, "verdict", r->verdict);
    // the headline the threshold applies to (the external calibration's with --calib)
    ADD_NUMBERS(root, {"rms_surveyed_px", r->rms_surveyed_px});
    // the thresholds applied: those not given derive from need_ground_m (px_per_m converts)
    ADD_NUMBERS(cJSON_AddObjectToObject(root, "thresholds"), {"need_ground_m", r->thresholds.need_ground_m},
                {"px_per_m", r->px_per_m}, {"max_rms_surveyed_px", r->thresholds.max_rms_surveyed_px},
                {"max_loo_px", r->thresholds.max_loo_px}, {"max_loo_m", r->thresholds.max_loo_m},
                {"max_ground_sigma_m", r->thresholds.max_ground_sigma_m},
                {"outlier_threshold", opt->calib.outlier_threshold}, {"alpha", opt->alpha},
                {"consistency_px", opt->consistency_px});
    cJSON_AddItemToObject(root, "solve", solve);
    ADD_NUMBERS(cJSON_AddObjectToObject(root, "leave_one_out"), {"count", r->loo_count}, {"rms_px", r->loo_rms_px},
                {"max_px", r->loo_max_px}, {"median_m", r->loo_median_m}, {"max_m", r->loo_max_m});
    ADD_NUMBERS(cJSON_AddObjectToObject(root, "coverage"), {"image_hull_share", r->image_hull_share},
                {"ground_seen_m2", r->ground_seen_m2}, {"ground_hull_share", r->ground_hull_share},
                {"ground_sigma_inside_median_m", r->ground_sigma_inside_median_m},
                {"ground_sigma_inside_p90_m", r->ground_sigma_inside_p90_m}, {"range_m", opt->range_m});
    ADD_NUMBERS(cJSON_AddObjectToObject(root, "degeneracy"), {"condition_number", r->condition_number},
                {"collinearity", r->collinearity}, {"planarity", r->planarity}, {"head_on_deg", r->head_on_deg});
    add_landmarks(root, site, cam, r);
    if (r->map.sigma_m) add_map(root, &r->map);
    if (r->has_against) {
        const rs_audit_against *a = &r->against;
        cJSON *ja = cJSON_AddObjectToObject(root, "against");
        cJSON_AddBoolToObject(ja, "moved", a->moved);
        ADD_NUMBERS(ja, {"landmarks", a->M}, {"chi2", a->chi2}, {"dof", a->dof}, {"p_value", a->p_value},
                    {"rms_shift_px", a->rms_shift_px}, {"rotation_deg", a->rotation_deg}, {"shift_m", a->shift_m});
        cJSON_AddItemToObject(ja, "dyaw_pitch_roll_deg", num_array(a->dyaw_pitch_roll_deg, 3));
        cJSON_AddItemToObject(ja, "shift_enu_m", num_array(a->shift_enu_m, 3));
        cJSON_AddItemToObject(ja, "rt_cam_enu_new", num_array(a->rt_cam_enu_new, 6));
        cJSON_AddStringToObject(ja, "message", a->message);
    }
    if (r->has_external) {
        const rs_audit_external *x = &r->external;
        cJSON *jx = cJSON_AddObjectToObject(root, "external");
        cJSON_AddBoolToObject(jx, "consistent", x->consistent);
        cJSON_AddItemToObject(jx, "inconsistencies", sentences(x->consistency));
        ADD_NUMBERS(jx, {"rms_surveyed_px", x->rms_surveyed_px}, {"max_px", x->max_px},
                    {"rotation_vs_site_deg", x->rotation_deg}, {"shift_vs_site_m", x->shift_m},
                    {"R_orthonormality", x->R_orthonormality}, {"P_max_px", x->P_max_px}, {"P_scale", x->P_scale});
    }
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    return text;
}

static const char *const audit_suffixes[] = {".audit.json"};
const rs_calib_site_outputs rs_audit_site_outputs = {"audit.run.json", "roadside audit", audit_suffixes, 1};

rs_status rs_audit_site_write(const char *out_dir, const rs_site *site, int icam, const rs_audit_result *result,
                              const rs_audit_options *opt, rs_err *err)
{
    rs_err e = {0};
    char *path = rs_io_child_path(out_dir, site->cameras[icam].id, ".audit.json", &e);
    char *text = path ? rs_audit_result_json(site, icam, result, opt) : NULL;
    rs_status st = !path  ? rs_err_set(err, e.status, "%s", e.msg)
                   : text ? rs_io_write_file(path, text, strlen(text), err)
                          : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (st && path) (void)rs_io_remove_if_exists(path, NULL, NULL); // an earlier run's: not this run's
    free(path);
    free(text);
    return st;
}
