// rs_report_words.c -- the report's verdicts in plain words, the plain reading of the pose
// statistics, the date and version stamp, and the inputs with their SHA-256
// (report/internal/rs_report_words.h).
#include "report/internal/rs_report_words.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "core/rs_hash.h"

#include "core/rs_io.h"

static const char *camera_id(const struct rs_report_ctx *rep, const rs_report_camera *cam)
{
    return rep->site->cameras[cam->icam].id;
}

// ---- verdicts ----

void rs_report_doc_camera_verdict(rs_doc *doc, const struct rs_report_ctx *rep, const rs_report_camera *cam)
{
    const char *id = camera_id(rep, cam);
    if (cam->has_audit)
        rs_doc_paragraph(doc, !cam->audit.pass, "%s: %s. %s", id, cam->audit.pass ? "pass" : "FAIL",
                         cam->audit.verdict);
    else
        rs_doc_paragraph(doc, true, "%s: not audited (%s): no verdict; the figures below are the calibration's own.",
                         id, cam->audit_error);
}

// The ids of the camera's outliers, ", "-joined into buf ("" when none).
static void outlier_ids(char *buf, size_t size, const rs_report_camera *cam)
{
    buf[0] = '\0';
    size_t n = 0;
    for (int i = 0; i < cam->N && n + 1 < size; i++)
        if (!cam->landmarks[i].inlier)
            n += (size_t)snprintf(buf + n, size - n, "%s%s", n ? ", " : "", cam->landmarks[i].id);
}

void rs_report_camera_action(char *figure, size_t figure_size, char *action, size_t action_size,
                             const struct rs_report_ctx *rep, const rs_report_camera *cam)
{
    const char *site_dir = rep->site->dir;
    char outliers[256];
    outlier_ids(outliers, sizeof outliers, cam);
    if (cam->focal_off) { // the cause is the lens, not the survey: refine it, do not resurvey
        snprintf(figure, figure_size, "the image says the focal length is %.0f%% %s than the nominal",
                 100 * fabs(cam->focal_rel), cam->focal_rel >= 0 ? "longer" : "shorter");
        snprintf(action, action_size, "recalibrate with the focal length free: roadside calib %s --refine focal%s",
                 site_dir, cam->center_off ? " (then --refine focal+center if the centre is still off)" : "");
        return;
    }
    if (!cam->has_audit) {
        snprintf(figure, figure_size, "no audit");
        snprintf(action, action_size, "%s", cam->audit_error);
        return;
    }
    const rs_audit_result *a = &cam->audit;
    if (a->pass) {
        snprintf(figure, figure_size, "ground error %.2f m (1 sigma, 90%% of the landmarks' area; need %g m)",
                 a->ground_sigma_inside_p90_m, a->thresholds.need_ground_m);
        if (outliers[0])
            snprintf(action, action_size, "use it; re-survey or re-pick %s (left out)", outliers);
        else
            snprintf(action, action_size, "none: use it");
        return;
    }
    // the threshold failed by the widest margin decides
    const double ratio[4] = {a->ground_sigma_inside_p90_m / a->thresholds.max_ground_sigma_m,
                             a->loo_count ? a->loo_median_m / a->thresholds.max_loo_m : NAN,
                             a->rms_surveyed_px / a->thresholds.max_rms_surveyed_px,
                             a->loo_count ? a->loo_rms_px / a->thresholds.max_loo_px : NAN};
    int worst = -1;
    for (int k = 0; k < 4; k++)
        if (ratio[k] > 1 && (worst < 0 || ratio[k] > ratio[worst])) worst = k;
    switch (worst) {
    case 0:
        snprintf(figure, figure_size, "predicted ground error %.2f m > need %g m (90%% of the landmarks' area)",
                 a->ground_sigma_inside_p90_m, a->thresholds.max_ground_sigma_m);
        snprintf(action, action_size,
                 "add landmarks spread over the area the camera must cover, or survey them more accurately; "
                 "then re-pick and recalibrate");
        break;
    case 1:
        snprintf(figure, figure_size, "landmarks held out are located %.2f m off (median) > %g m", a->loo_median_m,
                 a->thresholds.max_loo_m);
        snprintf(action, action_size,
                 "survey the landmarks more accurately or add landmarks spread over the area; then re-pick and "
                 "recalibrate");
        break;
    case 2:
    case 3:
        snprintf(figure, figure_size, "%s reproject %.0f px off (RMS) > %.0f px",
                 worst == 2 ? "the surveyed landmarks" : "landmarks held out",
                 worst == 2 ? a->rms_surveyed_px : a->loo_rms_px,
                 worst == 2 ? a->thresholds.max_rms_surveyed_px : a->thresholds.max_loo_px);
        snprintf(action, action_size,
                 "check the survey and the picks of the landmarks named in its section; then "
                 "recalibrate");
        break;
    default: snprintf(figure, figure_size, "%s", a->failures); snprintf(action, action_size, "see its section");
    }
    if (outliers[0]) {
        size_t n = strlen(action);
        snprintf(action + n, action_size - n, "; re-survey or re-pick %s (left out)", outliers);
    }
}

void rs_report_doc_verdicts(rs_doc *doc, const struct rs_report_ctx *rep)
{
    rs_doc_heading(doc, 2, "In short");
    const rs_report_camera *first = NULL;
    for (int c = 0; c < rep->Ncameras && !first; c++)
        if (rep->cameras[c].has_audit) first = &rep->cameras[c];
    if (first)
        rs_doc_paragraph(doc, false,
                         "Each camera against what the site is for: vehicles located on the ground to %g m (1 sigma) "
                         "where its landmarks are. The verdicts are those of 'roadside audit' on the same files; "
                         "each camera's section gives the evidence.",
                         first->audit.thresholds.need_ground_m);
    else
        rs_doc_paragraph(doc, false, "No camera was audited: there is no verdict, only the calibrations' figures.");
    rs_doc_table(doc, 4);
    rs_doc_cell(doc, "camera");
    rs_doc_cell(doc, "verdict");
    rs_doc_cell(doc, "what decided it");
    rs_doc_cell(doc, "what to do");
    for (int c = 0; c < rep->Ncameras; c++) {
        const rs_report_camera *cam = &rep->cameras[c];
        char figure[512], action[1200];
        rs_report_camera_action(figure, sizeof figure, action, sizeof action, rep, cam);
        rs_doc_cell(doc, "%s", camera_id(rep, cam));
        rs_doc_cell(doc, "%s", !cam->has_audit ? "not audited" : cam->audit.pass ? "pass" : "FAIL");
        rs_doc_cell(doc, "%s", figure);
        rs_doc_cell(doc, "%s", action);
    }
}

// ---- the pose statistics in words ----

void rs_report_doc_pose_words(rs_doc *doc, const rs_report_camera *cam)
{
    const double vf = cam->variance_factor, cn = cam->condition_number;
    // a warning that the intrinsics may be off limits what the variance factor can vouch for
    bool lens_doubt = cam->focal_off || cam->center_off;
    for (int i = 0; i < cam->Nwarnings && !lens_doubt; i++)
        lens_doubt = strstr(cam->warnings[i], "because of the intrinsics") != NULL;
    const char *vf_words = !isfinite(vf) ? "cannot be computed (no redundancy)"
                           : vf < 0.25   ? "is small: the stated pick and survey sigmas are pessimistic"
                           : vf > 4      ? "is large: the residuals are larger than the stated sigmas, and the "
                                           "sigmas in this table are optimistic"
                           : lens_doubt  ? "is about 1: the residuals are as large as the stated pick and survey "
                                           "sigmas predict; the sigmas in this table still hold only for the lens "
                                           "as calibrated, which the warnings below doubt"
                                         : "is about 1: the residuals are as large as the stated pick and survey "
                                           "sigmas predict, so the sigmas in this table can be trusted";
    const char *cn_words = !isfinite(cn) ? "cannot be computed"
                           : cn <= 10    ? "the landmarks pin the pose down well (well-spread scenes give 1.5-10)"
                           : cn <= 100   ? "the pose is less well determined than in a well-spread scene (1.5-10)"
                                         : "weak geometry: the landmarks barely determine the pose (above 100)";
    char infl[200] = "";
    if (cam->has_audit) {
        const rs_audit_result *a = &cam->audit;
        int worst = -1;
        for (int i = 0; i < a->N; i++)
            if (a->landmarks[i].loo_ok && isfinite(a->landmarks[i].influence_m) &&
                (worst < 0 || a->landmarks[i].influence_m > a->landmarks[worst].influence_m))
                worst = i;
        if (worst >= 0 && worst < cam->N)
            snprintf(infl, sizeof infl,
                     " Influence: leaving out any one landmark moves the camera at most %.2f m and turns it %.2f deg "
                     "(%s); a landmark the pose leans on is named in the warnings.",
                     a->landmarks[worst].influence_m, a->landmarks[worst].influence_deg, cam->landmarks[worst].id);
    }
    rs_doc_paragraph(doc, false, "In plain words: the variance factor chi2/dof %.2f %s. Condition number %.1f: %s.%s",
                     vf, vf_words, cn, cn_words, infl);
}

// ---- warnings ----

// "a; b; c" -> one warning paragraph each, skipping those already given (seen, "\n"-joined).
static int warning_list(rs_doc *doc, const char *prefix, const char *list, char *seen, size_t seen_size)
{
    int n = 0;
    for (const char *s = list; *s;) {
        const int len = (int)rs_calib_warning_len(s); // "; " inside parentheses belongs to the sentence
        char one[1200];
        snprintf(one, sizeof one, "%.*s", len, s);
        if (len > 0 && !strstr(seen, one)) {
            rs_doc_paragraph(doc, true, "%s%s", prefix, one);
            size_t used = strlen(seen);
            snprintf(seen + used, seen_size - used, "%s\n", one);
            n++;
        }
        s += len;
        while (*s == ';' || *s == ' ') s++;
    }
    return n;
}

int rs_report_doc_warnings(rs_doc *doc, const struct rs_report_ctx *rep, const rs_report_camera *cam)
{
    char seen[8192] = "";
    int n = 0;
    if (cam->has_audit) { // the audit's warnings start with the solver's, landmarks already named
        n += warning_list(doc, "", cam->audit.warnings, seen, sizeof seen);
        for (int i = 0; i < cam->audit.N && i < cam->N; i++)
            if (cam->audit.landmarks[i].reason[0]) {
                rs_doc_paragraph(doc, true, "Landmark %s: %s", cam->landmarks[i].id, cam->audit.landmarks[i].reason);
                n++;
            }
        return n;
    }
    for (int i = 0; i < cam->Nwarnings; i++) {
        char w[1200];
        snprintf(w, sizeof w, "%s", cam->warnings[i]);
        rs_calib_site_name_landmarks(w, sizeof w, rep->site, cam->icam);
        n += warning_list(doc, "", w, seen, sizeof seen);
    }
    return n;
}

// ---- stamp and inputs ----

void rs_report_stamp(char *buf, size_t size, const struct rs_report_ctx *rep)
{
    time_t t = rep->written_utc_s > 0 ? (time_t)rep->written_utc_s : time(NULL);
    struct tm tm;
    char date[64] = "unknown date";
    if (gmtime_r(&t, &tm)) strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", &tm);
    snprintf(buf, size, "Written %s by roadside %s", date, rep->version ? rep->version : "unknown");
}

static void input_row(rs_doc *doc, const char *what, const char *path)
{
    char hex[65];
    long long bytes = 0;
    struct stat sb;
    if (!path || stat(path, &sb) != 0 || !S_ISREG(sb.st_mode)) return;
    const bool ok = rs_hash_sha256_file(hex, &bytes, path, NULL) == RS_OK;
    rs_doc_cell(doc, "%s", what);
    rs_doc_cell(doc, "%s", path);
    rs_doc_cell(doc, "%lld", ok ? bytes : (long long)sb.st_size);
    rs_doc_cell(doc, "%s", ok ? hex : "(unreadable)");
}

void rs_report_doc_inputs(rs_doc *doc, const struct rs_report_ctx *rep)
{
    const rs_site *site = rep->site;
    rs_doc_heading(doc, 2, "Inputs");
    char stamp[200];
    rs_report_stamp(stamp, sizeof stamp, rep);
    rs_doc_paragraph(doc, false,
                     "%s. The files this report was made from, with their size in bytes and SHA-256 "
                     "(sha256sum FILE prints the same), so that anyone can tell whether a file has changed since.",
                     stamp);
    rs_doc_table(doc, 4);
    rs_doc_cell(doc, "input");
    rs_doc_cell(doc, "file");
    rs_doc_cell(doc, "bytes");
    rs_doc_cell(doc, "SHA-256");
    static const char *const site_files[] = {RS_SITE_JSON, RS_SITE_LANDMARKS, RS_SITE_LANES};
    for (size_t k = 0; k < sizeof site_files / sizeof site_files[0]; k++) {
        char *path = rs_io_join(site->dir, site_files[k]);
        input_row(doc, "site", path);
        free(path);
    }
    for (int c = 0; c < rep->Ncameras; c++) {
        const rs_report_camera *cam = &rep->cameras[c];
        const rs_site_camera *sc = &site->cameras[cam->icam];
        char what[300], path[4096];
        snprintf(what, sizeof what, "%s nominal model", sc->id);
        input_row(doc, what, sc->model_path);
        snprintf(what, sizeof what, "%s picks", sc->id);
        input_row(doc, what, sc->observations_path);
        static const char *const suffixes[] = {RS_CAMERA_EXT_CAMERAMODEL, RS_CALIB_SITE_EXT_JSON};
        for (int k = 0; k < 2; k++) {
            const bool ok = rep->calib_dir && rs_camera_path(path, sizeof path, rep->calib_dir, sc->id, suffixes[k]);
            snprintf(what, sizeof what, "%s calibration", sc->id);
            input_row(doc, what, ok ? path : NULL);
        }
        snprintf(what, sizeof what, "%s image", sc->id);
        input_row(doc, what, cam->background_path);
    }
}
