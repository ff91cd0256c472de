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

void rs_report_doc_verdicts(rs_doc *doc, const struct rs_report_ctx *rep)
{
    rs_doc_heading(doc, 2, "In short");
    const rs_report_camera *first = NULL;
    for (int c = 0; c < rep->Ncameras && !first; c++)
        if (rep->cameras[c].has_audit) first = &rep->cameras[c];
    if (first) {
        const rs_audit_result *a = &first->audit;
        rs_doc_paragraph(doc, false,
                         "Each camera is judged against what the site is for: vehicles located on the ground to %g m "
                         "(1 sigma) where the landmarks are. A camera passes when the calibration predicts that "
                         "accuracy there (at most %g m over 90%% of the landmarks' area), when landmarks left out "
                         "one at a time are located from their picks within it (median at most %g m), and when its "
                         "surveyed landmarks reproject within the need in pixels (about %.0f px at %s's landmarks; "
                         "each camera's own figure is in its section). The verdicts are those of 'roadside audit' "
                         "on the same files, with the same thresholds.",
                         a->thresholds.need_ground_m, a->thresholds.max_ground_sigma_m, a->thresholds.max_loo_m,
                         a->thresholds.max_rms_surveyed_px, camera_id(rep, first));
    } else
        rs_doc_paragraph(doc, false, "No camera was audited: there is no verdict, only the calibrations' figures.");
    for (int c = 0; c < rep->Ncameras; c++) rs_report_doc_camera_verdict(doc, rep, &rep->cameras[c]);
}

// ---- the pose statistics in words ----

void rs_report_doc_pose_words(rs_doc *doc, const rs_report_camera *cam)
{
    const double vf = cam->variance_factor, cn = cam->condition_number;
    const char *vf_words = !isfinite(vf) ? "cannot be computed (no redundancy)"
                           : vf < 0.25   ? "is small: the stated pick and survey sigmas are pessimistic"
                           : vf <= 4     ? "is about 1: the residuals are as large as the stated pick and survey "
                                           "sigmas predict, so the sigmas in this table can be trusted"
                                         : "is large: the residuals are larger than the stated sigmas, and the "
                                           "sigmas in this table are optimistic";
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
        const char *e = strstr(s, "; ");
        // a "; " inside parentheses belongs to the sentence: "(landmark L003; 0 by data snooping)"
        const char *open = memchr(s, '(', e ? (size_t)(e - s) : strlen(s));
        if (e && open) {
            const char *close = strchr(open, ')');
            if (close && close > e) e = strstr(close, "; ");
        }
        int len = e ? (int)(e - s) : (int)strlen(s);
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
        rs_audit_site_name_landmarks(w, sizeof w, rep->site, cam->icam);
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
