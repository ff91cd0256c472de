// roadside geo -- stream coordinates through rs_geo: geodetic <-> site ENU, UTM/UPS.
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"

static void usage(FILE *out)
{
    fprintf(out, "usage: roadside geo enu --origin LAT,LON,H [--from utm:ZONE]\n"
                 "       roadside geo llh --origin LAT,LON,H\n"
                 "       roadside geo utm [--zone ZONE]\n"
                 "\n"
                 "Converts points read from stdin, one per line, and writes one line per point.\n"
                 "\n"
                 "  enu   lat lon h (degrees, degrees, metres; WGS84, h ellipsoidal) -> e n u, metres,\n"
                 "        in the site ENU frame at --origin (GeographicLib's LocalCartesian: x east,\n"
                 "        y north, z up along the ellipsoid normal). With --from utm:ZONE the input\n"
                 "        lines are easting northing h (metres) in that UTM/UPS zone.\n"
                 "  llh   e n u in the site ENU frame at --origin -> lat lon h.\n"
                 "  utm   lat lon h -> easting northing h ZONE, in --zone if given, otherwise in each\n"
                 "        point's standard zone.\n"
                 "\n"
                 "  --origin LAT,LON,H  the site origin, degrees, degrees, metres (ellipsoidal)\n"
                 "  --from utm:ZONE     (enu) read UTM/UPS coordinates of ZONE\n"
                 "  --zone ZONE         (utm) project into ZONE\n"
                 "  ZONE is a UTM zone 1..60 and hemisphere, e.g. 33N or 19s, or N / S for UPS.\n"
                 "\n"
                 "Fields are separated by spaces, tabs or commas; blank lines and lines starting with #\n"
                 "are skipped (and print nothing). Output: metres with 9 decimals, degrees with 12.\n"
                 "The output is streamed: on a bad line (wrong number of fields, not a finite number,\n"
                 "latitude outside [-90, 90], coordinate outside the zone) the command stops with a\n"
                 "message naming the line and field and exits 1, after the lines before it have been\n"
                 "printed. Exit status: 0 ok, 1 bad input, 2 usage error.\n"
                 "Accuracy: a few nanometres (GeographicLib); see geo/rs_geo.h.\n");
}

typedef enum { MODE_ENU, MODE_LLH, MODE_UTM } geo_mode;

typedef struct {
    geo_mode mode;
    rs_llh origin;
    bool from_utm; // enu: input is UTM/UPS
    int zone;      // UTM/UPS zone (0 = UPS) of --from / --zone; -1: standard zone (utm)
    bool north;
} geo_args;

// Value of option `name` at argv[*i], as "--name VALUE" or "--name=VALUE"; NULL if argv[*i]
// is not that option. Sets *missing if the value is absent.
static const char *option_value(int argc, char **argv, int *i, const char *name, bool *missing)
{
    size_t n = strlen(name);
    if (strncmp(argv[*i], name, n) != 0) return NULL;
    if (argv[*i][n] == '=') return argv[*i] + n + 1;
    if (argv[*i][n] != '\0') return NULL;
    if (*i + 1 >= argc) {
        *missing = true;
        return "";
    }
    return argv[++*i];
}

static int parse_args(int argc, char **argv, geo_args *a)
{
    *a = (geo_args){.zone = -1, .north = true};
    if (argc < 2) return rs_cli_usage_error("geo", "missing mode: enu, llh or utm");
    if (!strcmp(argv[1], "enu"))
        a->mode = MODE_ENU;
    else if (!strcmp(argv[1], "llh"))
        a->mode = MODE_LLH;
    else if (!strcmp(argv[1], "utm"))
        a->mode = MODE_UTM;
    else
        return rs_cli_usage_error("geo", "unknown mode '%s': enu, llh or utm", argv[1]);
    bool have_origin = false;
    for (int i = 2; i < argc; i++) {
        bool missing = false;
        const char *v;
        rs_err err = {0};
        if (a->mode != MODE_UTM && (v = option_value(argc, argv, &i, "--origin", &missing))) {
            if (missing || !rs_cli_parse_llh(v, &a->origin))
                return rs_cli_usage_error("geo", "--origin: '%s' is not LAT,LON,H (finite, |LAT| <= 90)", v);
            have_origin = true;
        } else if (a->mode == MODE_ENU && (v = option_value(argc, argv, &i, "--from", &missing))) {
            if (missing || strncmp(v, "utm:", 4) != 0 || rs_geo_utm_zone_parse(&a->zone, &a->north, v + 4, &err))
                return rs_cli_usage_error("geo", "--from: '%s': %s", v,
                                          err.msg[0] ? err.msg : "expected utm:ZONE, e.g. utm:33N");
            a->from_utm = true;
        } else if (a->mode == MODE_UTM && (v = option_value(argc, argv, &i, "--zone", &missing))) {
            if (missing || rs_geo_utm_zone_parse(&a->zone, &a->north, v, &err))
                return rs_cli_usage_error("geo", "--zone: '%s': %s", v,
                                          err.msg[0] ? err.msg : "expected a zone, e.g. 33N, 19S, N");
        } else {
            return rs_cli_usage_error("geo", "unexpected argument '%s' for 'geo %s'", argv[i], argv[1]);
        }
    }
    if (a->mode != MODE_UTM && !have_origin) return rs_cli_usage_error("geo", "%s needs --origin", argv[1]);
    return RS_EXIT_OK;
}

// Splits `line` into exactly three finite numbers. false with err set otherwise.
static bool parse_line(char *line, const char *const fields[3], double v[3], rs_err *err)
{
    char *save = NULL, *tok = strtok_r(line, " \t\r\n,", &save);
    int n = 0;
    for (; tok; tok = strtok_r(NULL, " \t\r\n,", &save), n++) {
        if (n >= 3) continue;
        if (!rs_cli_parse_double(tok, &v[n])) {
            rs_err_set(err, RS_ERR_PARSE, "field '%s': '%s' is not a finite number", fields[n], tok);
            return false;
        }
    }
    if (n != 3) {
        rs_err_set(err, RS_ERR_PARSE, "expected 3 fields (%s %s %s), found %d", fields[0], fields[1], fields[2], n);
        return false;
    }
    return true;
}

// Converts one point; prints it on success.
static rs_status convert(const geo_args *a, const double in[3], rs_err *err)
{
    double out[3], llh[3];
    rs_status st = RS_OK;
    switch (a->mode) {
    case MODE_ENU:
        if (a->from_utm) st = rs_geo_utm_to_llh(llh, a->zone, a->north, in, 1, err);
        if (!st) st = rs_geo_llh_to_enu(out, &a->origin, a->from_utm ? llh : in, 1, err);
        if (!st) printf("%.9f %.9f %.9f\n", out[0], out[1], out[2]);
        break;
    case MODE_LLH:
        st = rs_geo_enu_to_llh(out, &a->origin, in, 1, err);
        if (!st) printf("%.12f %.12f %.9f\n", out[0], out[1], out[2]);
        break;
    case MODE_UTM: {
        int zone;
        bool north;
        char zs[8];
        st = rs_geo_llh_to_utm(out, &zone, &north, a->zone, a->north, in, 1, err);
        if (!st) st = rs_geo_utm_zone_format(zs, sizeof zs, zone, north, err);
        if (!st) printf("%.9f %.9f %.9f %s\n", out[0], out[1], out[2], zs);
        break;
    }
    }
    return st;
}

int rs_cli_geo(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        usage(stdout);
        return RS_EXIT_OK;
    }
    geo_args a;
    int rc = parse_args(argc, argv, &a);
    if (rc) return rc;
    static const char *const llh_fields[3] = {"lat", "lon", "h"};
    static const char *const utm_fields[3] = {"easting", "northing", "h"};
    static const char *const enu_fields[3] = {"e", "n", "u"};
    const char *const *fields = a.mode == MODE_LLH ? enu_fields : a.from_utm ? utm_fields : llh_fields;

    char *line = NULL;
    size_t cap = 0;
    long lineno = 0;
    rs_err err = {0};
    rs_status st = RS_OK;
    while (getline(&line, &cap, stdin) >= 0) {
        lineno++;
        const char *p = line + strspn(line, " \t\r\n");
        if (*p == '\0' || *p == '#') continue;
        double v[3];
        st = parse_line(line, fields, v, &err) ? convert(&a, v, &err) : err.status;
        if (st) break;
    }
    free(line);
    if (st) {
        fflush(stdout);
        fprintf(stderr, "roadside geo: <stdin>:%ld: %s\n", lineno, err.msg);
        return RS_EXIT_FAIL;
    }
    if (ferror(stdin)) return rs_cli_fail("geo: reading <stdin>", RS_ERR_IO, NULL);
    return RS_EXIT_OK;
}
