// fuzz_site.c -- the per-process site folder of the site harnesses, and the contract every
// input is held to (fuzz_site.h).
#include "fuzz_site.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "geo/rs_site.h"

#ifndef RS_FUZZ_SITE_DIR
#error "RS_FUZZ_SITE_DIR (the folder of the valid base site) is set by tests/fuzz/meson.build"
#endif

// The files of the base site (tests/fuzz/site/), relative to the site folder.
static const char *const BASE_FILES[] = {"site.json", "landmarks.geojson", "cameras/cam1.cameramodel",
                                         "cameras/cam1.opencv.yaml", "observations/cam1.csv"};

static char *site_dir; // the per-process copy, removed at exit

static void breach(const char *what, const char *detail)
{
    fprintf(stderr, "fuzz_site: contract broken: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
    abort();
}

static void remove_site_dir(void)
{
    if (site_dir) rs_io_remove_tree(site_dir);
    free(site_dir);
    site_dir = NULL;
}

// Writes len bytes to dir/rel. A scratch input, rewritten for every run: plain stdio (an atomic
// write would fsync thousands of times a second).
static void write_scratch(const char *rel, const void *data, size_t len)
{
    char *path = rs_io_join(site_dir, rel);
    if (!path) breach("out of memory", NULL);
    FILE *f = fopen(path, "wb");
    if (!f || (len && fwrite(data, 1, len, f) != len) || fclose(f) != 0) breach("cannot write", path);
    free(path);
}

static void make_site_dir(void)
{
    const char *tmp = getenv("TMPDIR");
    char *templ = rs_io_join(tmp && *tmp ? tmp : "/tmp", "roadside-fuzz-XXXXXX");
    if (!templ || !mkdtemp(templ)) breach("cannot make the site folder", templ);
    site_dir = templ;
    atexit(remove_site_dir);
    rs_err err = {0};
    for (size_t i = 0; i < sizeof BASE_FILES / sizeof *BASE_FILES; i++) {
        char *from = rs_io_join(RS_FUZZ_SITE_DIR, BASE_FILES[i]);
        char *to = rs_io_join(site_dir, BASE_FILES[i]);
        char *slash = to ? strrchr(to, '/') : NULL;
        if (!from || !slash) breach("out of memory", NULL);
        *slash = 0;
        char *text = NULL;
        size_t len = 0;
        if (rs_io_mkdir_p(to, &err) || rs_io_read_file(&text, &len, from, &err)) breach("base site", err.msg);
        write_scratch(BASE_FILES[i], text, len);
        free(text);
        free(from);
        free(to);
    }
    // The base site must load, or every input would only exercise the same error.
    rs_site_report *report = NULL;
    if (rs_site_check(&report, site_dir, &err) || report->Nerrors != 0)
        breach("the base site " RS_FUZZ_SITE_DIR " does not pass rs_site_check", NULL);
    rs_site_report_free(report);
}

// rs_site_diag_format like snprintf: the returned length is what a large enough buffer gets,
// and a short buffer gets a NUL-terminated prefix of it.
static void check_format(const rs_site_diag *d)
{
    char small[24];
    int n = rs_site_diag_format(small, sizeof small, d);
    if (n < 0) breach("rs_site_diag_format returned a negative length", NULL);
    char *full = malloc((size_t)n + 1);
    if (!full) breach("out of memory", NULL);
    int m = rs_site_diag_format(full, (size_t)n + 1, d);
    if (m != n || strlen(full) != (size_t)n) breach("rs_site_diag_format: lengths disagree", full);
    size_t k = strlen(small);
    if (k != ((size_t)n < sizeof small ? (size_t)n : sizeof small - 1) || memcmp(small, full, k) != 0)
        breach("rs_site_diag_format: a short buffer is not a prefix of the line", full);
    free(full);
}

// Returns the first error's status (RS_OK when there is none).
static rs_status check_report(const rs_site_report *r)
{
    size_t ndir = strlen(site_dir);
    int nerr = 0, nwarn = 0;
    rs_status first = RS_OK;
    for (int i = 0; i < r->N; i++) {
        const rs_site_diag *d = &r->diags[i];
        if (!d->file || strncmp(d->file, site_dir, ndir) != 0 || d->file[ndir] != '/')
            breach("a diagnostic names no file of the site folder", d->file);
        if (!d->message || !d->message[0]) breach("a diagnostic without a message", d->file);
        if (d->severity == RS_SITE_ERROR) {
            if (d->status == RS_OK || d->status >= RS_STATUS_COUNT) breach("an error without a status", d->message);
            if (!nerr++) first = d->status;
        } else if (d->severity == RS_SITE_WARNING) {
            if (d->status != RS_OK) breach("a warning with a status", d->message);
            nwarn++;
        } else {
            breach("a diagnostic of no known severity", d->message);
        }
        check_format(d);
    }
    if (nerr != r->Nerrors || nwarn != r->Nwarnings) breach("the report's counts do not add up", NULL);
    return first;
}

static bool finite3(const double *v) { return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }

static void check_site(const rs_site *s)
{
    if (!s->name || s->Nlandmarks < 0 || s->Ncameras < 0) breach("a loaded site without a name or counts", NULL);
    for (int i = 0; i < s->Nlandmarks; i++) {
        const rs_site_landmark *l = &s->landmarks[i];
        if (!l->id || !finite3(l->p_enu_m) || !(l->sigma_h_m > 0 && isfinite(l->sigma_h_m)) ||
            !(l->sigma_v_m > 0 && isfinite(l->sigma_v_m)))
            breach("a loaded landmark with no id, a non-finite position or a bad sigma", l->id);
        if (rs_site_find_landmark(s, l->id) != i) breach("landmark ids are not unique", l->id);
    }
    rs_err err = {0};
    for (int c = 0; c < s->Ncameras; c++) {
        const rs_site_camera *cam = &s->cameras[c];
        if (!cam->id || rs_site_find_camera(s, cam->id) != c) breach("camera ids are missing or not unique", cam->id);
        if (rs_camera_check(&cam->camera, cam->model_path, &err))
            breach("a loaded camera fails rs_camera_check", err.msg);
        if (cam->has_position_prior && (!finite3(cam->prior_p_enu_m) || !(cam->prior_sigma_m > 0)))
            breach("a loaded position prior is not finite", cam->id);
        for (int k = 0; k < cam->Nobservations; k++) {
            const rs_site_observation *o = &cam->observations[k];
            if (o->ilandmark < 0 || o->ilandmark >= s->Nlandmarks || !isfinite(o->q_px[0]) || !isfinite(o->q_px[1]) ||
                !(o->sigma_px > 0 && isfinite(o->sigma_px)))
                breach("a loaded observation is out of range", cam->id);
        }
        double lo[3], hi[3], dmin = 0, dmax = 0;
        if (rs_site_landmark_extent(lo, hi, &dmin, &dmax, s, c) > 0 && !(dmin <= dmax && isfinite(dmax)))
            breach("rs_site_landmark_extent: dmin > dmax or not finite", cam->id);
    }
}

int rs_fuzz_site_input(const char *rel, const uint8_t *data, size_t size)
{
    if (!site_dir) make_site_dir();
    write_scratch(rel, data, size);

    rs_err err = {0};
    rs_site_report *report = NULL;
    if (rs_site_check(&report, site_dir, &err) != RS_OK || !report) breach("rs_site_check did not run", err.msg);
    rs_status first = check_report(report);
    int nerrors = report->Nerrors;
    rs_site_report_free(report);

    rs_site *site = NULL;
    rs_err lerr = {0};
    rs_status st = rs_site_load(&site, site_dir, &lerr);
    if ((st == RS_OK) != (nerrors == 0)) breach("rs_site_load and rs_site_check disagree", lerr.msg);
    if (st == RS_OK) {
        if (!site) breach("rs_site_load returned RS_OK and no site", NULL);
        check_site(site);
    } else {
        if (site) breach("rs_site_load failed and returned a site", NULL);
        if (st != first) breach("rs_site_load returned another status than the first error", lerr.msg);
        if (!lerr.msg[0]) breach("rs_site_load failed without a message", NULL);
    }
    rs_site_free(site);
    return 0;
}
