// test_geo_api -- the C API of rs_geo.h directly: geodetic -> ECEF against the closed-form
// formula, ECEF <-> geodetic round trips near the poles and inside the earth down to its
// centre, the ENU frame against LocalCartesian and the ellipsoid normal, the sign of the
// meridian convergence against finite differences of the projection, and the error paths.
// Fixed seed, printed on failure.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_units.h"
#include "geo/rs_geo.h"
#include "tests/common/rs_test.h"

enum { SEED = 20261122 };

static const double a_m = 6378137.0, f_wgs84 = 1 / 298.257223563;

static double uniform(double lo, double hi) { return lo + (hi - lo) * drand48(); }

static double dist3(const double *a, const double *b)
{
    double d = sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
    return isnan(d) ? INFINITY : d;
}

// Keeps the largest of the errors; NaN counts as infinite.
static void track(double *worst, double e) { *worst = fmax(*worst, isnan(e) ? INFINITY : e); }

// Closed-form geodetic -> ECEF, the oracle of rs_geo_llh_to_ecef.
static void ecef_closed_form(const double llh[3], double p[3])
{
    double e2 = f_wgs84 * (2 - f_wgs84), s = sin(llh[0] * RS_RAD_PER_DEG), c = cos(llh[0] * RS_RAD_PER_DEG);
    double n = a_m / sqrt(1 - e2 * s * s);
    p[0] = (n + llh[2]) * c * cos(llh[1] * RS_RAD_PER_DEG);
    p[1] = (n + llh[2]) * c * sin(llh[1] * RS_RAD_PER_DEG);
    p[2] = (n * (1 - e2) + llh[2]) * s;
}

static void test_llh_ecef(void)
{
    // latitudes near and at the poles, at the equator, and random; heights -1 km ... 1000 km
    enum { N = 2000 };
    static double llh[N * 3], ecef[N * 3], llh2[N * 3], ecef2[N * 3];
    const double special_lat[] = {90, -90, 89.9999999, -89.999999999, 0, 1e-12, 45};
    for (int i = 0; i < N; i++) {
        llh[3 * i] = i < 7 * 8 ? special_lat[i % 7] : uniform(-90, 90);
        llh[3 * i + 1] = uniform(-540, 540);
        llh[3 * i + 2] = i % 2 ? uniform(-1000, 1000) : uniform(-1000, 1e6);
    }
    rs_err err = {0};
    CHECK(rs_geo_llh_to_ecef(ecef, llh, N, &err) == RS_OK, "llh_to_ecef: %s", err.msg);
    CHECK(rs_geo_ecef_to_llh(llh2, ecef, N, &err) == RS_OK, "ecef_to_llh: %s", err.msg);
    CHECK(rs_geo_llh_to_ecef(ecef2, llh2, N, &err) == RS_OK, "llh_to_ecef: %s", err.msg);
    double worst_formula = 0, worst_trip = 0, worst_h = 0;
    for (int i = 0; i < N; i++) {
        double ref[3];
        ecef_closed_form(llh + 3 * i, ref);
        track(&worst_formula, dist3(ref, ecef + 3 * i));
        track(&worst_trip, dist3(ecef + 3 * i, ecef2 + 3 * i));
        track(&worst_h, fabs(llh[3 * i + 2] - llh2[3 * i + 2]));
        CHECK(llh2[3 * i + 1] >= -180 && llh2[3 * i + 1] <= 180, "lon %.17g out of [-180, 180]", llh2[3 * i + 1]);
    }
    printf("llh -> ecef vs closed form: max %.3e m; llh -> ecef -> llh -> ecef: max %.3e m, "
           "h %.3e m (%d points)\n",
           worst_formula, worst_trip, worst_h, N);
    CHECK(worst_formula < 2e-8, "llh -> ecef differs from the closed form by %.3e m", worst_formula);
    CHECK(worst_trip < 1e-8, "ecef round trip error %.3e m", worst_trip);
    CHECK(worst_h < 1e-8, "height round trip error %.3e m", worst_h);

    // the pole itself: lat must come back as +-90 exactly enough that the point is the pole
    double pole[3] = {90, 123, 10}, p[3], back[3];
    rs_geo_llh_to_ecef(p, pole, 1, NULL);
    rs_geo_ecef_to_llh(back, p, 1, NULL);
    CHECK(fabs(back[0] - 90) < 1e-12 && fabs(back[2] - 10) < 1e-8, "pole: lat %.17g h %.17g", back[0], back[2]);
}

static void test_centre(void)
{
    // ECEF -> llh -> ECEF for points inside 100 km of the centre of the earth, and the centre
    enum { N = 1000 };
    static double ecef[N * 3], llh[N * 3], ecef2[N * 3];
    for (int i = 0; i < 3 * N; i++) ecef[i] = i < 3 ? 0 : uniform(-1e5, 1e5) * (i < 30 ? 1e-9 : 1);
    rs_err err = {0};
    CHECK(rs_geo_ecef_to_llh(llh, ecef, N, &err) == RS_OK, "ecef_to_llh near the centre: %s", err.msg);
    CHECK(rs_geo_llh_to_ecef(ecef2, llh, N, &err) == RS_OK, "llh_to_ecef near the centre: %s", err.msg);
    double worst = 0;
    for (int i = 0; i < N; i++) track(&worst, dist3(ecef + 3 * i, ecef2 + 3 * i));
    printf("ecef -> llh -> ecef within 100 km of the centre: max %.3e m (%d points)\n", worst, N);
    CHECK(worst < 1e-8, "round trip error near the centre %.3e m", worst);
    double b_m = a_m * (1 - f_wgs84);
    CHECK(fabs(llh[0]) == 90 && fabs(llh[2] + b_m) < 1e-8, "centre: lat %.17g h %.17g (expected +-90, -%.17g)", llh[0],
          llh[2], b_m);
}

static void test_enu_frame(void)
{
    const rs_llh origins[] = {{0, 0, 0}, {45, 15, 250}, {-89.9, 179.99, 10}, {90, 30, 0}, {-90, -60, -100}};
    double worst_rot = 0, worst_enu = 0, worst_trip = 0;
    for (size_t k = 0; k < sizeof origins / sizeof origins[0]; k++) {
        const rs_llh *o = &origins[k];
        double R[9], o_ecef[3], o_ref[3], llh_o[3] = {o->lat_deg, o->lon_deg, o->h_m};
        rs_err err = {0};
        CHECK(rs_geo_enu_frame(R, o_ecef, o, &err) == RS_OK, "enu_frame: %s", err.msg);
        ecef_closed_form(llh_o, o_ref);
        track(&worst_enu, dist3(o_ecef, o_ref));
        // columns: east = (-sin lon, cos lon, 0), up = the ellipsoid normal, north = up x east
        double la = o->lat_deg * RS_RAD_PER_DEG, lo = o->lon_deg * RS_RAD_PER_DEG;
        double east[3] = {-sin(lo), cos(lo), 0}, up[3] = {cos(la) * cos(lo), cos(la) * sin(lo), sin(la)};
        double north[3] = {up[1] * east[2] - up[2] * east[1], up[2] * east[0] - up[0] * east[2],
                           up[0] * east[1] - up[1] * east[0]};
        for (int r = 0; r < 3; r++) {
            track(&worst_rot, fabs(R[3 * r + 0] - east[r]));
            track(&worst_rot, fabs(R[3 * r + 1] - north[r]));
            track(&worst_rot, fabs(R[3 * r + 2] - up[r]));
        }
        // R^T (ecef(p) - origin) must be LocalCartesian's ENU, for points up to 20 km away
        enum { N = 200 };
        double enu[N * 3], llh[N * 3], ecef[N * 3], enu2[N * 3];
        for (int i = 0; i < N; i++) {
            enu[3 * i] = uniform(-2e4, 2e4);
            enu[3 * i + 1] = uniform(-2e4, 2e4);
            enu[3 * i + 2] = uniform(-1e3, 1e3);
        }
        CHECK(rs_geo_enu_to_llh(llh, o, enu, N, &err) == RS_OK, "enu_to_llh: %s", err.msg);
        CHECK(rs_geo_llh_to_ecef(ecef, llh, N, &err) == RS_OK, "llh_to_ecef: %s", err.msg);
        CHECK(rs_geo_llh_to_enu(enu2, o, llh, N, &err) == RS_OK, "llh_to_enu: %s", err.msg);
        for (int i = 0; i < N; i++) {
            double d[3], q[3];
            for (int c = 0; c < 3; c++) d[c] = ecef[3 * i + c] - o_ecef[c];
            for (int c = 0; c < 3; c++) q[c] = R[c] * d[0] + R[3 + c] * d[1] + R[6 + c] * d[2];
            track(&worst_enu, dist3(q, enu + 3 * i));
            track(&worst_trip, dist3(enu2 + 3 * i, enu + 3 * i));
        }
    }
    printf("enu frame: columns vs closed form max %.3e; R^T (ecef - o) vs enu max %.3e m; "
           "enu -> llh -> enu max %.3e m\n",
           worst_rot, worst_enu, worst_trip);
    CHECK(worst_rot < 1e-15, "R_ecef_enu columns off by %.3e", worst_rot);
    CHECK(worst_enu < 1e-8, "R_ecef_enu and origin disagree with llh_to_enu by %.3e m", worst_enu);
    CHECK(worst_trip < 1e-8, "enu round trip error %.3e m", worst_trip);
}

static void test_convergence(void)
{
    // gamma is the bearing of grid north clockwise from true north: moving north along the
    // meridian, the grid direction of travel is at -gamma from grid north.
    const double pts[][3] = {{45, 17, 0}, {45, 13, 0}, {-33, -70, 0}, {10, -179.8, 0}, {87, 30, 0}, {-88, -100, 0}};
    double worst = 0;
    for (size_t k = 0; k < sizeof pts / sizeof pts[0]; k++) {
        const double d = 1e-6;
        double llh[9], enh[9], gamma;
        int zone;
        bool north;
        memcpy(llh, pts[k], sizeof pts[k]);
        memcpy(llh + 3, pts[k], sizeof pts[k]);
        memcpy(llh + 6, pts[k], sizeof pts[k]);
        llh[3] -= d;
        llh[6] += d;
        rs_err err = {0};
        CHECK(rs_geo_llh_to_utm(enh, &zone, &north, -1, true, llh, 1, &err) == RS_OK, "llh_to_utm: %s", err.msg);
        CHECK(rs_geo_llh_to_utm(enh + 3, NULL, NULL, zone, north, llh + 3, 2, &err) == RS_OK, "llh_to_utm: %s",
              err.msg);
        CHECK(rs_geo_utm_convergence_deg(&gamma, -1, true, llh, 1, &err) == RS_OK, "convergence: %s", err.msg);
        double fd = -atan2(enh[6] - enh[3], enh[7] - enh[4]) / RS_RAD_PER_DEG;
        track(&worst, fabs(gamma - fd));
        if (k == 0) CHECK(gamma > 1, "gamma %.17g east of the central meridian at lat 45 should be ~ +1.4", gamma);
    }
    printf("convergence vs finite differences: max %.3e deg\n", worst);
    CHECK(worst < 1e-6, "convergence off by %.3e deg", worst);
}

static void test_errors(void)
{
    rs_err err = {0};
    double llh[9] = {45, 15, 0, NAN, 15, 0, 45, 15, 0}, out[9];
    const rs_llh origin = {45, 15, 0}, bad_origin = {91, 0, 0};

    CHECK(rs_geo_llh_to_ecef(out, llh, 3, &err) == RS_ERR_INVALID && strstr(err.msg, "row 1: field 'lat'"),
          "NaN lat in row 1: %s", err.msg);
    CHECK(rs_geo_llh_to_enu(out, &origin, llh, 3, &err) == RS_ERR_INVALID && strstr(err.msg, "row 1"),
          "NaN lat in row 1 (enu): %s", err.msg);
    CHECK(rs_geo_llh_to_ecef(out, llh, 3, NULL) == RS_ERR_INVALID, "err may be NULL");
    llh[3] = 90.5;
    CHECK(rs_geo_llh_to_utm(out, NULL, NULL, -1, true, llh, 3, &err) == RS_ERR_INVALID &&
              strstr(err.msg, "row 1: field 'lat': 90.5 is outside [-90, 90]"),
          "lat 90.5: %s", err.msg);
    llh[3] = 45;
    llh[5] = INFINITY;
    CHECK(rs_geo_llh_to_enu(out, &origin, llh, 3, &err) == RS_ERR_INVALID && strstr(err.msg, "row 1: field 'h'"),
          "inf h: %s", err.msg);
    double ecef[3] = {1, NAN, 0};
    CHECK(rs_geo_ecef_to_llh(out, ecef, 1, &err) == RS_ERR_INVALID && !strncmp(err.msg, "field 'y'", 9),
          "NaN y, N = 1 (no row): %s", err.msg);
    CHECK(rs_geo_enu_to_llh(out, &origin, ecef, 1, &err) == RS_ERR_INVALID && !strncmp(err.msg, "field 'n'", 9),
          "NaN n: %s", err.msg);
    CHECK(rs_geo_llh_to_enu(out, &bad_origin, llh, 1, &err) == RS_ERR_INVALID && strstr(err.msg, "origin: field 'lat'"),
          "bad origin: %s", err.msg);
    CHECK(rs_geo_enu_frame(out, NULL, &bad_origin, &err) == RS_ERR_INVALID, "bad origin (frame): %s", err.msg);
    CHECK(rs_geo_llh_to_enu(out, NULL, llh, 1, &err) == RS_ERR_USAGE, "NULL origin: %s", err.msg);
    CHECK(rs_geo_llh_to_ecef(NULL, llh, 1, &err) == RS_ERR_USAGE, "NULL output: %s", err.msg);
    CHECK(rs_geo_llh_to_ecef(out, llh, -1, &err) == RS_ERR_USAGE, "N < 0: %s", err.msg);
    CHECK(rs_geo_llh_to_ecef(NULL, NULL, 0, &err) == RS_OK, "N = 0 with NULL arrays is fine");

    // UTM/UPS
    double enh[6] = {500000, 5e6, 0, 500000, 1e8, 0};
    CHECK(rs_geo_utm_to_llh(out, 61, true, enh, 1, &err) == RS_ERR_INVALID && strstr(err.msg, "zone"), "zone 61: %s",
          err.msg);
    CHECK(rs_geo_utm_to_llh(out, -1, true, enh, 1, &err) == RS_ERR_INVALID, "zone -1: %s", err.msg);
    CHECK(rs_geo_utm_to_llh(out, 33, true, enh, 2, &err) == RS_ERR_INVALID &&
              strstr(err.msg, "row 1: GeographicLib: Northing"),
          "northing out of range: %s", err.msg);
    double two[6] = {45, 14, 0, 45, 19, 0};
    CHECK(rs_geo_llh_to_utm(out, NULL, NULL, -1, true, two, 2, &err) == RS_ERR_INVALID &&
              strstr(err.msg, "row 1: zone: standard zone 34n differs from row 0's 33n"),
          "two standard zones: %s", err.msg);
    int zone = -5;
    bool north = false;
    CHECK(rs_geo_llh_to_utm(out, &zone, &north, 33, true, two, 2, &err) == RS_OK && zone == 33 && north,
          "one requested zone: %s", err.msg);
    two[0] = -0.01; // southern point into a northern zone: northing continued below 0
    CHECK(rs_geo_llh_to_utm(out, &zone, &north, 33, true, two, 1, &err) == RS_OK && out[1] < 0 && out[1] > -2000,
          "continued northing %.17g: %s", out[1], err.msg);
    CHECK(rs_geo_llh_to_utm(out, &zone, &north, -1, true, two, 1, &err) == RS_OK && zone == 33 && !north &&
              out[1] > 9.99e6,
          "standard southern zone: %d %d %.17g", zone, north, out[1]);

    // zone strings
    const struct {
        const char *s;
        int zone;
        bool north;
    } zs[] = {{"33N", 33, true}, {"01s", 1, false}, {"60north", 60, true}, {"n", 0, true}, {"S", 0, false}};
    for (size_t k = 0; k < sizeof zs / sizeof zs[0]; k++) {
        CHECK(rs_geo_utm_zone_parse(&zone, &north, zs[k].s, &err) == RS_OK && zone == zs[k].zone &&
                  north == zs[k].north,
              "zone '%s' -> %d %d: %s", zs[k].s, zone, north, err.msg);
    }
    const char *bad[] = {"61n", "0n", "33", "", "INV", "33x", "+3n"};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++)
        CHECK(rs_geo_utm_zone_parse(&zone, &north, bad[k], &err) == RS_ERR_INVALID, "zone '%s' accepted", bad[k]);
    char buf[8];
    CHECK(rs_geo_utm_zone_format(buf, sizeof buf, 1, false, &err) == RS_OK && !strcmp(buf, "01s"), "format 1s: %s",
          buf);
    CHECK(rs_geo_utm_zone_format(buf, sizeof buf, 0, true, &err) == RS_OK && !strcmp(buf, "n"), "format UPS: %s", buf);
    CHECK(rs_geo_utm_zone_format(buf, 3, 33, true, &err) == RS_ERR_USAGE, "small buffer: %s", err.msg);
    CHECK(rs_geo_utm_zone_format(buf, sizeof buf, 61, true, &err) == RS_ERR_INVALID, "zone 61 formatted");
}

int main(void)
{
    srand48(SEED);
    rs_test_seed = SEED;
    test_llh_ecef();
    test_centre();
    test_enu_frame();
    test_convergence();
    test_errors();
    return rs_test_end("test_geo_api");
}
