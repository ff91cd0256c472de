// rs_geo_geographiclib.cc -- the C contract of rs_geo.h on top of GeographicLib (Geocentric,
// LocalCartesian, UTMUPS). Every exception stops here and becomes an rs_status.
#include <GeographicLib/Constants.hpp>
#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <GeographicLib/UTMUPS.hpp>

#include <cmath>
#include <cstdarg>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

extern "C" {
#include "geo/rs_geo.h"
}

using GeographicLib::Geocentric;
using GeographicLib::GeographicErr;
using GeographicLib::LocalCartesian;
using GeographicLib::UTMUPS;

namespace {

// Field names of the (N,3) arrays, for the error messages.
const char *const llh_fields[3] = {"lat", "lon", "h"};
const char *const ecef_fields[3] = {"x", "y", "z"};
const char *const enu_fields[3] = {"e", "n", "u"};
const char *const enh_fields[3] = {"easting", "northing", "h"};

// Sets err to "row I: what" (just "what" when N == 1, where the row says nothing) and
// returns status.
rs_status fail_row(rs_err *err, rs_status status, int N, int i, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
rs_status fail_row(rs_err *err, rs_status status, int N, int i, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    rs_err_vset(err, status, fmt, ap);
    va_end(ap);
    if (N > 1) rs_err_prefix(err, "row %d", i);
    return status;
}

rs_status check_args(const void *out, const void *in, int N, rs_err *err)
{
    if (N < 0) return rs_err_set(err, RS_ERR_USAGE, "N = %d is negative", N);
    if (N > 0 && (!out || !in)) return rs_err_set(err, RS_ERR_USAGE, "NULL point array");
    return RS_OK;
}

rs_status check_finite(const double *p, const char *const fields[3], int N, int i, rs_err *err)
{
    for (int k = 0; k < 3; k++)
        if (!std::isfinite(p[k]))
            return fail_row(err, RS_ERR_INVALID, N, i, "field '%s': %g is not finite", fields[k], p[k]);
    return RS_OK;
}

rs_status check_llh(const double *llh, int N, int i, rs_err *err)
{
    rs_status st = check_finite(llh, llh_fields, N, i, err);
    if (st) return st;
    if (std::fabs(llh[0]) > 90)
        return fail_row(err, RS_ERR_INVALID, N, i, "field 'lat': %.17g is outside [-90, 90]", llh[0]);
    return RS_OK;
}

rs_status check_origin(const rs_llh *origin, rs_err *err)
{
    if (!origin) return rs_err_set(err, RS_ERR_USAGE, "origin: NULL");
    const double llh[3] = {origin->lat_deg, origin->lon_deg, origin->h_m};
    rs_status st = check_llh(llh, 1, 0, err);
    if (st) rs_err_prefix(err, "origin");
    return st;
}

rs_status check_zone(int zone, bool allow_standard, rs_err *err)
{
    if ((zone < 0 && !allow_standard) || zone > UTMUPS::MAXZONE)
        return rs_err_set(err, RS_ERR_INVALID, "zone: %d is outside [0, 60] (0 is UPS)", zone);
    return RS_OK;
}

// Runs body(i) for i = 0..N-1, stopping at the first non-OK status, and turns any exception
// into a status naming the row it came from.
template <class Body> rs_status for_each_row(int N, rs_err *err, Body body)
{
    int i = 0;
    try {
        for (; i < N; i++) {
            rs_status st = body(i);
            if (st) return st;
        }
        return RS_OK;
    } catch (const GeographicErr &e) {
        return fail_row(err, RS_ERR_INVALID, N, i, "GeographicLib: %s", e.what());
    } catch (const std::bad_alloc &) {
        return fail_row(err, RS_ERR_NOMEM, N, i, "GeographicLib: out of memory");
    } catch (const std::exception &e) {
        return fail_row(err, RS_ERR_EXTERNAL, N, i, "GeographicLib: %s", e.what());
    } catch (...) {
        return fail_row(err, RS_ERR_EXTERNAL, N, i, "GeographicLib: unknown exception");
    }
}

// The same for a single call without rows.
template <class Body> rs_status guarded(rs_err *err, Body body)
{
    return for_each_row(1, err, [&](int) { return body(); });
}

// Checks the arguments, then for each row i: checks in[i] (finite; for geodetic rows, whose
// fields are llh_fields, also the latitude) and computes op(in[i], out[i]).
template <class Op>
rs_status map_rows(double *out, const double *in, int N, const char *const fields[3], rs_err *err, Op op)
{
    rs_status st = check_args(out, in, N, err);
    if (st) return st;
    return for_each_row(N, err, [&](int i) {
        const double *p = in + 3 * i;
        rs_status s = fields == llh_fields ? check_llh(p, N, i, err) : check_finite(p, fields, N, i, err);
        if (s) return s;
        op(p, out + 3 * i);
        return RS_OK;
    });
}

// Checks origin and runs op(the LocalCartesian frame at origin), catching exceptions.
template <class Op> rs_status with_local_cartesian(const rs_llh *origin, rs_err *err, Op op)
{
    rs_status st = check_origin(origin, err);
    if (st) return st;
    return guarded(err, [&]() {
        const LocalCartesian lc(origin->lat_deg, origin->lon_deg, origin->h_m);
        return op(lc);
    });
}

// The UTM/UPS forward projection of one row into `zone` (< 0: the standard zone), hemisphere
// `north` when zone >= 0; returns the zone and hemisphere used.
rs_status utm_forward(const double *llh, int zone, bool north, int N, int i, double enh[3], int *zone_used,
                      bool *north_used, double *gamma_deg, rs_err *err)
{
    rs_status st = check_llh(llh, N, i, err);
    if (st) return st;
    int z;
    bool np;
    double x, y, gamma, k;
    UTMUPS::Forward(llh[0], llh[1], z, np, x, y, gamma, k, zone < 0 ? int(UTMUPS::STANDARD) : zone);
    if (zone >= 0 && np != north) {
        int zt;
        UTMUPS::Transfer(z, np, x, y, z, north, x, y, zt);
        np = north;
    }
    enh[0] = x;
    enh[1] = y;
    enh[2] = llh[2];
    *zone_used = z;
    *north_used = np;
    if (gamma_deg) *gamma_deg = gamma;
    return RS_OK;
}

} // namespace

extern "C" {

rs_status rs_geo_llh_to_ecef(double *p_ecef_m, const double *llh, int N, rs_err *err)
{
    const Geocentric &earth = Geocentric::WGS84();
    return map_rows(p_ecef_m, llh, N, llh_fields, err,
                    [&](const double *p, double *q) { earth.Forward(p[0], p[1], p[2], q[0], q[1], q[2]); });
}

rs_status rs_geo_ecef_to_llh(double *llh, const double *p_ecef_m, int N, rs_err *err)
{
    const Geocentric &earth = Geocentric::WGS84();
    return map_rows(llh, p_ecef_m, N, ecef_fields, err,
                    [&](const double *p, double *q) { earth.Reverse(p[0], p[1], p[2], q[0], q[1], q[2]); });
}

rs_status rs_geo_llh_to_enu(double *p_enu_m, const rs_llh *origin, const double *llh, int N, rs_err *err)
{
    return with_local_cartesian(origin, err, [&](const LocalCartesian &lc) {
        return map_rows(p_enu_m, llh, N, llh_fields, err,
                        [&](const double *p, double *q) { lc.Forward(p[0], p[1], p[2], q[0], q[1], q[2]); });
    });
}

rs_status rs_geo_enu_to_llh(double *llh, const rs_llh *origin, const double *p_enu_m, int N, rs_err *err)
{
    return with_local_cartesian(origin, err, [&](const LocalCartesian &lc) {
        return map_rows(llh, p_enu_m, N, enu_fields, err,
                        [&](const double *p, double *q) { lc.Reverse(p[0], p[1], p[2], q[0], q[1], q[2]); });
    });
}

rs_status rs_geo_enu_frame(double R_ecef_enu[9], double origin_ecef_m[3], const rs_llh *origin, rs_err *err)
{
    if (!R_ecef_enu) return rs_err_set(err, RS_ERR_USAGE, "R_ecef_enu: NULL");
    rs_status st = check_origin(origin, err);
    if (st) return st;
    return guarded(err, [&]() {
        std::vector<double> M(9);
        double X, Y, Z;
        Geocentric::WGS84().Forward(origin->lat_deg, origin->lon_deg, origin->h_m, X, Y, Z, M);
        std::memcpy(R_ecef_enu, M.data(), 9 * sizeof(double));
        if (origin_ecef_m) {
            origin_ecef_m[0] = X;
            origin_ecef_m[1] = Y;
            origin_ecef_m[2] = Z;
        }
        return RS_OK;
    });
}

rs_status rs_geo_utm_to_llh(double *llh, int zone, bool north, const double *enh, int N, rs_err *err)
{
    rs_status st = check_zone(zone, false, err);
    if (st) return st;
    return map_rows(llh, enh, N, enh_fields, err, [&](const double *p, double *q) {
        UTMUPS::Reverse(zone, north, p[0], p[1], q[0], q[1]);
        q[2] = p[2];
    });
}

rs_status rs_geo_llh_to_utm(double *enh, int *zone_out, bool *north_out, int zone, bool north, const double *llh, int N,
                            rs_err *err)
{
    rs_status st = check_args(enh, llh, N, err);
    if (!st) st = check_zone(zone, true, err);
    if (st) return st;
    int zone_all = zone;
    bool north_all = north;
    st = for_each_row(N, err, [&](int i) {
        int z;
        bool np;
        rs_status s = utm_forward(llh + 3 * i, zone, north, N, i, enh + 3 * i, &z, &np, NULL, err);
        if (s) return s;
        if (i == 0) {
            zone_all = z;
            north_all = np;
        } else if (z != zone_all || np != north_all) {
            const std::string zi = UTMUPS::EncodeZone(z, np), z0 = UTMUPS::EncodeZone(zone_all, north_all);
            return fail_row(err, RS_ERR_INVALID, N, i,
                            "zone: standard zone %s differs from row 0's %s; ask for one zone", zi.c_str(), z0.c_str());
        }
        return RS_OK;
    });
    if (st) return st;
    if (zone_out) *zone_out = zone_all;
    if (north_out) *north_out = north_all;
    return RS_OK;
}

rs_status rs_geo_utm_convergence_deg(double *gamma_deg, int zone, bool north, const double *llh, int N, rs_err *err)
{
    rs_status st = check_args(gamma_deg, llh, N, err);
    if (!st) st = check_zone(zone, true, err);
    if (st) return st;
    return for_each_row(N, err, [&](int i) {
        double enh[3];
        int z;
        bool np;
        return utm_forward(llh + 3 * i, zone, north, N, i, enh, &z, &np, gamma_deg + i, err);
    });
}

rs_status rs_geo_utm_zone_parse(int *zone, bool *north, const char *s, rs_err *err)
{
    if (!zone || !north || !s) return rs_err_set(err, RS_ERR_USAGE, "zone: NULL argument");
    rs_status st = guarded(err, [&]() {
        int z;
        bool np;
        UTMUPS::DecodeZone(s, z, np);
        if (z < UTMUPS::MINZONE || z > UTMUPS::MAXZONE) // "INV" decodes to UTMUPS::INVALID
            return rs_err_set(err, RS_ERR_INVALID, "not a zone");
        *zone = z;
        *north = np;
        return RS_OK;
    });
    if (st) rs_err_prefix(err, "zone '%s'", s);
    return st;
}

rs_status rs_geo_utm_zone_format(char *buf, size_t size, int zone, bool north, rs_err *err)
{
    if (!buf) return rs_err_set(err, RS_ERR_USAGE, "zone: NULL buffer");
    rs_status st = check_zone(zone, false, err);
    if (st) return st;
    return guarded(err, [&]() {
        const std::string s = UTMUPS::EncodeZone(zone, north);
        if (s.size() >= size) return rs_err_set(err, RS_ERR_USAGE, "zone: buffer of %zu bytes too small", size);
        std::memcpy(buf, s.c_str(), s.size() + 1);
        return RS_OK;
    });
}

} // extern "C"
