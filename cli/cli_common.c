#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "calib/rs_calib_site.h"
#include "cli/rs_cli.h"

int rs_cli_fail(const char *what, rs_status st, const rs_err *err)
{
    const char *detail = (err && err->msg[0]) ? err->msg : rs_strerror(st);
    fprintf(stderr, "roadside: %s: %s\n", what, detail);
    return st == RS_ERR_USAGE ? RS_EXIT_USAGE : RS_EXIT_FAIL;
}

int rs_cli_usage_error(const char *command, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "roadside %s: ", command);
    vfprintf(stderr, fmt, ap);
    fprintf(stderr, "\nTry 'roadside %s --help'.\n", command);
    va_end(ap);
    return RS_EXIT_USAGE;
}

rs_site *rs_cli_load_site(const char *command, const char *dir)
{
    rs_err err = {0};
    rs_site *site = NULL;
    rs_status st = rs_site_load(&site, dir, &err);
    if (st == RS_OK) return site;
    fprintf(stderr, "roadside %s: %s\n(run 'roadside site check %s' for every problem)\n", command,
            err.msg[0] ? err.msg : rs_strerror(st), dir);
    return NULL;
}

int rs_cli_check_cameras(const char *command, const rs_site *site, const char *const *ids, int N)
{
    for (int i = 0; i < N; i++)
        if (rs_site_find_camera(site, ids[i]) < 0)
            return rs_cli_usage_error(command, "--camera %s: no such camera in %s/site.json", ids[i], site->dir);
    return RS_EXIT_OK;
}

rs_site *rs_cli_load_site_or_abandon(const char *command, const char *what, const char *site_dir, const char *out_dir,
                                     const rs_calib_site_outputs *outputs, const char *const *only, int Nonly)
{
    rs_site *site = NULL;
    rs_err err = {0};
    const rs_status st = rs_site_load(&site, site_dir, &err);
    if (st == RS_OK) return site;
    const char *msg = err.msg[0] ? err.msg : rs_strerror(st);
    fprintf(stderr, "roadside %s: %s\n(run 'roadside site check %s' for every problem)\n", command, msg, site_dir);
    // nothing can be done for any camera: what an earlier run wrote for this site is superseded
    char *removed = NULL;
    rs_err rerr = {0};
    char why[sizeof err.msg + 32];
    snprintf(why, sizeof why, "the site could not be read: %s", msg);
    if (rs_calib_site_run_abandon(&removed, out_dir, outputs, site_dir, only, Nonly, why, &rerr))
        fprintf(stderr, "roadside %s: %s\n", command, rerr.msg);
    if (removed && removed[0])
        fprintf(stderr, "roadside %s: nothing written; the earlier %s of this site in %s/ are removed: %s\n", command,
                what, out_dir, removed);
    free(removed);
    return NULL;
}

bool rs_cli_wants_help(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--")) return false;
        if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) return true;
    }
    return false;
}

bool rs_cli_parse_double(const char *s, double *out)
{
    if (!s || !*s) return false;
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (*end != '\0' || errno == ERANGE || !isfinite(v)) return false;
    *out = v;
    return true;
}

bool rs_cli_parse_int(const char *s, long lo, long hi, long *out)
{
    if (!s || !*s) return false;
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (*end != '\0' || errno == ERANGE || v < lo || v > hi) return false;
    *out = v;
    return true;
}

bool rs_cli_parse_llh(const char *s, rs_llh *out)
{
    char buf[256];
    if (!s || strlen(s) >= sizeof buf) return false;
    strcpy(buf, s);
    double v[3];
    char *save = NULL, *tok = strtok_r(buf, ",", &save);
    for (int i = 0; i < 3; i++) {
        if (!tok || !rs_cli_parse_double(tok, &v[i])) return false;
        tok = strtok_r(NULL, ",", &save);
    }
    if (tok) return false;
    if (v[0] < -90 || v[0] > 90) return false;
    out->lat_deg = v[0];
    out->lon_deg = v[1];
    out->h_m = v[2];
    return true;
}

bool rs_cli_parse_int_list(const char *s, long lo, long hi, int *out, int max, int *n)
{
    char *list = s ? strdup(s) : NULL, *save = NULL;
    if (!list) return false;
    *n = 0;
    bool ok = true;
    for (char *t = strtok_r(list, ",", &save); t && ok; t = strtok_r(NULL, ",", &save)) {
        long v;
        ok = *n < max && rs_cli_parse_int(t, lo, hi, &v);
        if (ok) out[(*n)++] = (int)v;
    }
    free(list);
    return ok && *n > 0;
}

char *rs_cli_scratch_dir(char tmpl[4096], const char *what)
{
    const char *t = getenv("TMPDIR");
    snprintf(tmpl, 4096, "%s/roadside-%s-XXXXXX", t && *t ? t : "/tmp", what);
    if (mkdtemp(tmpl)) return tmpl;
    fprintf(stderr, "roadside: %s: cannot create a scratch folder %s: %s\n", what, tmpl, strerror(errno));
    return NULL;
}

bool rs_cli_parse_pair(const char *s, char sep, double *a, double *b)
{
    const char *mid = strchr(s, sep);
    if (!mid) return false;
    char first[64];
    size_t n = (size_t)(mid - s);
    if (n == 0 || n >= sizeof first) return false;
    memcpy(first, s, n);
    first[n] = '\0';
    return rs_cli_parse_double(first, a) && rs_cli_parse_double(mid + 1, b);
}
