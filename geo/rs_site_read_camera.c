// rs_site_read_camera.c -- reading each camera's files of a site: the model file
// (cameras/<id>.cameramodel, or OpenCV intrinsics) and the observations CSV
// (observations/<id>.csv), reporting every problem on the way. Called by rs_site_read.c; calls
// rs_site_check.c (each pick, each camera), rs_site_report.c and rs_site.c (landmark lookup).
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/rs_io.h"
#include "core/rs_text.h"
#include "geo/internal/rs_site_internal.h"

static const double DEFAULT_SIGMA_PX = 1.0;

// ---- camera models ----

// Reports a failed core camera read as a diagnostic: its message is "PATH: FIELD: what", and
// the diagnostic names the file already.
static void camera_error(rs_site__reader *c, const rs_site_camera *cam, const rs_err *e)
{
    if (e->status == RS_ERR_NOMEM) c->r->nomem = true;
    size_t n = strlen(cam->model_path);
    const char *what = strncmp(e->msg, cam->model_path, n) || e->msg[n] != ':' ? e->msg : e->msg + n + 1;
    // "PATH:LINE: what" names a line: the diagnostic's own (not "PATH: : what")
    char *after = NULL;
    const long line = what != e->msg && isdigit((unsigned char)*what) ? strtol(what, &after, 10) : 0;
    if (after && *after == ':' && line > 0 && line < 1000000000) what = after + 1;
    while (*what == ' ') what++;
    ERR_AT(c, e->status, after && *after == ':' ? (int)line : 0, NULL, "%s", what);
}

// Whether cam's intrinsics are in the ranges calib can use (geo/rs_site.h RS_SITE_FOCAL_*,
// RS_SITE_DISTORTION_MAX); each one outside is reported with its range.
static void check_intrinsics(rs_site__reader *c, const rs_site_camera *cam)
{
    const rs_camera *k = &cam->camera;
    mrcal_lensmodel_metadata_t meta = mrcal_lensmodel_metadata(&k->lensmodel);
    if (!meta.has_core || k->Nintrinsics < 4 || k->width <= 0 || k->height <= 0) return;
    static const char *const core_names[4] = {"fx", "fy", "cx", "cy"};
    const double W = k->width, H = k->height;
    const double lo[4] = {RS_SITE_FOCAL_MIN_W * W, RS_SITE_FOCAL_MIN_W * W, -W / 2, -H / 2},
                 hi[4] = {RS_SITE_FOCAL_MAX_W * W, RS_SITE_FOCAL_MAX_W * W, 1.5 * W, 1.5 * H};
    for (int j = 0; j < 4; j++)
        if (!(k->intrinsics[j] >= lo[j] && k->intrinsics[j] <= hi[j]))
            ERR(c, RS_ERR_INVALID, core_names[j], "%g px is outside [%g, %g] px for a %dx%d image%s", k->intrinsics[j],
                lo[j], hi[j], k->width, k->height,
                j < 2 ? ": a focal length from 0.05 to 100 image widths"
                      : ": the principal point within half an image of it");
    const bool opencv = k->lensmodel.type >= MRCAL_LENSMODEL_OPENCV4 && k->lensmodel.type <= MRCAL_LENSMODEL_OPENCV12;
    for (int j = 4; opencv && j < k->Nintrinsics; j++)
        if (!(fabs(k->intrinsics[j]) <= RS_SITE_DISTORTION_MAX)) {
            char field[48];
            snprintf(field, sizeof field, "distortion[%d]", j - 4);
            ERR(c, RS_ERR_INVALID, field, "%g is outside [-%g, %g]: no lens distorts that much", k->intrinsics[j],
                RS_SITE_DISTORTION_MAX, RS_SITE_DISTORTION_MAX);
        }
}

void rs_site__read_camera_model(rs_site__reader *c, rs_site_camera *cam, int i)
{
    char why[160];
    snprintf(why, sizeof why, "named by cameras[%d].model in site.json", i);
    c->file = cam->model_path;
    if (!rs_site__file_exists(c, why)) goto done;
    rs_err e = {0};
    if (rs_io_has_extension(cam->model_path, "yaml") || rs_io_has_extension(cam->model_path, "yml") ||
        rs_io_has_extension(cam->model_path, "json")) {
        if (rs_camera_read(&cam->camera, NULL, cam->model_path, &e))
            camera_error(c, cam, &e);
        else if (cam->camera.width == 0 || cam->camera.height == 0) {
            ERR(c, RS_ERR_PARSE, cam->camera.width == 0 ? "image_width" : "image_height", "missing");
            rs_camera_free(&cam->camera);
        } else
            check_intrinsics(c, cam);
        goto done;
    }
    size_t len = 0;
    char *text = rs_site__read_file(c, why, RS_IO_MAX_SMALL_FILE_BYTES, &len);
    if (!text) goto done;
    int line = 0;
    const char *bad = rs_camera_cameramodel_problem(text, len, &line); // core's rule, with the line
    if (bad)
        ERR_AT(c, RS_ERR_PARSE, line, NULL, "not a valid mrcal .cameramodel: %s", bad);
    else if (rs_camera_read_cameramodel_text(&cam->camera, text, len, cam->model_path, &e))
        camera_error(c, cam, &e);
    else {
        memset(cam->camera.rt_cam_enu, 0, sizeof cam->camera.rt_cam_enu); // intrinsics only
        check_intrinsics(c, cam);
    }
    free(text);
done:
    c->file = NULL;
}

// ---- observations/<id>.csv ----

int rs_site__split_csv(char *s, char **fields, int maxf)
{
    int n = 0;
    for (;;) {
        while (*s == ' ' || *s == '\t') s++;
        char *start = s, *out = s;
        if (*s == '"') {
            for (s++;; s++) {
                if (!*s) return -1;
                if (*s == '"' && s[1] == '"')
                    *out++ = *s++;
                else if (*s == '"')
                    break;
                else
                    *out++ = *s;
            }
            s++;
            while (*s == ' ' || *s == '\t') s++;
            if (*s && *s != ',') return -1;
        } else {
            while (*s && *s != ',') s++;
            out = s;
            while (out > start && (out[-1] == ' ' || out[-1] == '\t')) out--;
        }
        char sep = *s;
        *out = '\0';
        if (n < maxf) fields[n] = start;
        n++;
        if (sep != ',') return n;
        s++;
    }
}

static bool parse_csv_number(rs_site__reader *c, int line, const char *field, const char *text, double *out)
{
    char why[RS_TEXT_WHY_BYTES];
    if (rs_text_parse_double(out, why, text)) return true;
    ERR_AT(c, strncmp(why, "not finite", 10) ? RS_ERR_PARSE : RS_ERR_INVALID, line, field, "%s", why);
    return false;
}

enum { COL_LANDMARK, COL_U, COL_V, COL_SIGMA, COL_AT, NCOLS, MAXFIELDS = 32 };
static const char *const column_names[NCOLS] = {"landmark", "u", "v", "sigma_px", "at"};

// Reads the header line; fills col[] with the index of each known column (-1 if absent).
static bool read_csv_header(rs_site__reader *c, int line, char **fields, int nfields, int col[NCOLS])
{
    for (int k = 0; k < NCOLS; k++) col[k] = -1;
    for (int f = 0; f < nfields && f < MAXFIELDS; f++) {
        int k = 0;
        while (k < NCOLS && strcmp(fields[f], column_names[k])) k++;
        if (k == NCOLS)
            WARN_AT(c, line, "header", "unknown column '%s', ignored", fields[f]);
        else if (col[k] >= 0)
            ERR_AT(c, RS_ERR_PARSE, line, "header", "column '%s' appears twice", fields[f]);
        else
            col[k] = f;
    }
    for (int k = 0; k < COL_SIGMA; k++)
        if (col[k] < 0) {
            bool other_separator = nfields == 1 && strpbrk(fields[0], ";\t");
            ERR_AT(c, RS_ERR_PARSE, line, "header",
                   "no column '%s': the first line must be the header landmark,u,v (and optionally "
                   ",sigma_px and ,at)%s",
                   column_names[k], other_separator ? "; separate the fields with commas, not semicolons or tabs" : "");
            return false;
        }
    return true;
}

static void read_observation_row(rs_site__reader *c, rs_site_camera *cam, int line, char **fields, const int col[NCOLS])
{
    const char *id = fields[col[COL_LANDMARK]];
    rs_site_observation obs = {.ilandmark = -1, .sigma_px = DEFAULT_SIGMA_PX, .line = line};
    bool ok = true;
    if (!*id) {
        ERR_AT(c, RS_ERR_PARSE, line, "landmark", "empty");
        ok = false;
    }
    ok = parse_csv_number(c, line, "u", fields[col[COL_U]], &obs.q_px[0]) && ok;
    ok = parse_csv_number(c, line, "v", fields[col[COL_V]], &obs.q_px[1]) && ok;
    if (col[COL_SIGMA] >= 0 && *fields[col[COL_SIGMA]]) {
        if (!parse_csv_number(c, line, "sigma_px", fields[col[COL_SIGMA]], &obs.sigma_px))
            ok = false;
        else if (!(obs.sigma_px >= RS_SITE_PIXEL_SIGMA_MIN_PX && obs.sigma_px <= RS_SITE_PIXEL_SIGMA_MAX_PX)) {
            ERR_AT(c, RS_ERR_INVALID, line, "sigma_px",
                   "%g px is outside [%g, %g] px: a 1-sigma under %g px is beyond any corner detector, over %g px "
                   "it is no pick",
                   obs.sigma_px, RS_SITE_PIXEL_SIGMA_MIN_PX, RS_SITE_PIXEL_SIGMA_MAX_PX, RS_SITE_PIXEL_SIGMA_MIN_PX,
                   RS_SITE_PIXEL_SIGMA_MAX_PX);
            ok = false;
        }
    }
    // where on the landmark: a name, or empty for the landmark's default (resolved below)
    const char *at = col[COL_AT] >= 0 ? fields[col[COL_AT]] : "";
    bool at_given = false;
    if (*at) {
        rs_site_at a = RS_SITE_AT_POINT;
        while (a <= RS_SITE_AT_ALONG && strcmp(at, rs_site_at_name(a))) a++;
        if (a > RS_SITE_AT_ALONG) {
            ERR_AT(c, RS_ERR_PARSE, line, "at",
                   "'%.40s': expected point (a point), base, top or along (a pole), along (a line), or empty for "
                   "the landmark's default",
                   at);
            ok = false;
        } else {
            obs.at = a;
            at_given = true;
        }
    }
    if (!ok || !c->landmarks_ok) return;
    obs.ilandmark = rs_index_find(&c->ids, id);
    if (obs.ilandmark < 0) {
        const int similar = rs_index_find(&c->ids_nocase, id); // differs only in case: the commonest slip
        const char *like = similar >= 0 ? c->site->landmarks[similar].id : NULL;
        ERR_AT(c, RS_ERR_NOT_FOUND, line, "landmark", "'%s' is not a landmark of landmarks.geojson%s%s%s", id,
               like ? " (ids are case-sensitive: '" : "", like ? like : "", like ? "'?)" : "");
        return;
    }
    const rs_site_shape shape = c->site->landmarks[obs.ilandmark].shape;
    if (!at_given) {
        obs.at = shape == RS_SITE_POINT ? RS_SITE_AT_POINT : RS_SITE_AT_ALONG;
    } else if ((shape == RS_SITE_POINT) != (obs.at == RS_SITE_AT_POINT) ||
               (shape == RS_SITE_LINE && obs.at != RS_SITE_AT_ALONG)) {
        ERR_AT(c, RS_ERR_INVALID, line, "at", "'%s' is a %s: it is picked %s, not at '%s'", id,
               rs_site_shape_name(shape),
               shape == RS_SITE_POINT  ? "at 'point' (the default)"
               : shape == RS_SITE_POLE ? "at 'base', 'top' or 'along' (the default)"
                                       : "'along' (the default)",
               rs_site_at_name(obs.at));
        return;
    }
    if (!rs_site__check_observation(c->r, cam, &obs, c->site, c->picked)) return;
    rs_site_observation *grown = realloc(cam->observations, (size_t)(cam->Nobservations + 1) * sizeof obs);
    if (!grown) {
        c->r->nomem = true;
        return;
    }
    cam->observations = grown;
    cam->observations[cam->Nobservations++] = obs;
}

void rs_site__read_observations(rs_site__reader *c, rs_site_camera *cam, int i)
{
    char why[160];
    snprintf(why, sizeof why, "named by cameras[%d].observations in site.json", i);
    c->file = cam->observations_path;
    size_t len = 0;
    char *text = rs_site__read_file(c, why, RS_IO_MAX_FILE_BYTES, &len);
    if (!text) goto done;
    if (c->landmarks_ok && !c->picked && !(c->picked = calloc((size_t)c->site->Nlandmarks * 3 + 1, sizeof(int)))) {
        c->r->nomem = true;
        goto done;
    }
    rs_text_lines lines;
    rs_text_lines_init(&lines, text, len, RS_TEXT_MAX_LINE_BYTES);
    int nheader = 0, col[NCOLS];
    bool have_header = false;
    for (;;) {
        char *s = NULL;
        rs_err e = {0};
        if (rs_text_next_line(&s, &lines, NULL, &e) != RS_OK) {
            // the rest of the file is not read: refused, never silently cut short
            ERR_AT(c, e.status, lines.line, NULL, "%s; the lines after it were not read", e.msg);
            goto done;
        }
        if (!s) break;
        const int line = lines.line;
        while (isspace((unsigned char)*s)) s++;
        if (!*s || *s == '#') continue; // blank lines and comments
        char *fields[MAXFIELDS];
        int n = rs_site__split_csv(s, fields, MAXFIELDS);
        if (n < 0) {
            ERR_AT(c, RS_ERR_PARSE, line, NULL, "malformed quoting (a \" that is not closed, or text after it)");
            continue;
        }
        if (!have_header) {
            if (!read_csv_header(c, line, fields, n, col)) goto done;
            have_header = true;
            nheader = n;
            continue;
        }
        if (n != nheader) {
            ERR_AT(c, RS_ERR_PARSE, line, NULL, "%d field%s, the header has %d%s", n, n == 1 ? "" : "s", nheader,
                   n > nheader ? " (a decimal comma? write 12.5, not 12,5)" : "");
            continue;
        }
        read_observation_row(c, cam, line, fields, col);
    }
    if (!have_header)
        ERR(c, RS_ERR_PARSE, "header", "the file is empty: the first line must be the header landmark,u,v");
    else if (c->landmarks_ok)
        rs_site__check_camera(c->r, cam, c->site);
done:
    // the next camera starts with no picks recorded
    for (int k = 0; c->picked && k < cam->Nobservations; k++)
        c->picked[3 * cam->observations[k].ilandmark] = c->picked[3 * cam->observations[k].ilandmark + 1] =
            c->picked[3 * cam->observations[k].ilandmark + 2] = 0;
    free(text);
    c->file = NULL;
}
