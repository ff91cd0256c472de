// rs_geo.h -- WGS84 geodetic <-> ECEF <-> site ENU, and UTM/UPS <-> geodetic, through
// GeographicLib (C. F. F. Karney, "Transverse Mercator with an accuracy of a few nanometers",
// J. Geodesy 85, 475-485 (2011); "Geodesics on an ellipsoid of revolution", arXiv:1102.1215,
// appendix B, for the geocentric inverse).
//
// Conventions (docs/conventions.md): geodetic points are llh = (lat_deg, lon_deg, h_m), h
// ellipsoidal above WGS84; ECEF in metres; the site ENU frame is GeographicLib's LocalCartesian
// at the site origin: x east, y north, z up along the ellipsoid normal, origin at the site
// origin's (lat, lon, h). Arrays are row-major, one point per row. Output longitudes are in
// [-180, 180]; input longitudes may be any finite number of degrees.
//
// Accuracy:
// - ECEF <-> geodetic (GeographicLib::Geocentric: the forward map is closed form; the inverse
//   is Vermeille's closed-form method, made robust near the poles and the centre of the earth
//   by Karney): GeographicLib states an error bounded by 7 nm for points within 5000 km of the
//   surface of the WGS84 ellipsoid. Measured by tests/geo/test_geo_api.c (2000 random points,
//   heights -1 km ... 1000 km, including the poles): llh -> ECEF within 7 nm of the textbook
//   closed form evaluated in double, llh -> ECEF -> llh -> ECEF within 4 nm; 1000 points within
//   100 km of the centre of the earth: ECEF -> llh -> ECEF within 4 nm.
// - geodetic <-> ENU (GeographicLib::LocalCartesian: the geocentric conversion followed by a
//   rotation): the same bound plus the round-off of the rotation. Measured against PROJ's cct
//   (tests/geo/test_geo_enu_cct.py: 1440 points up to 20 km horizontally and +-1 km vertically
//   from 9 origins at latitudes 0 ... +-89.9 and longitudes up to +-180): llh -> ENU within
//   5 nm; ENU -> llh within 0.12 um, which is the rounding of the 12 printed decimals of a degree
//   (test_geo_api.c: ENU -> llh -> ENU without printing is within 4 nm). Test tolerance 1 um.
// - UTM/UPS (GeographicLib::UTMUPS: Krueger's series to 6th order for UTM, exact polar
//   stereographic for UPS): GeographicLib states about 5 nm, for UTM anywhere within 35 degrees
//   of the central meridian. Measured against cct's +proj=utm / +proj=ups
//   (tests/geo/test_geo_utm_cct.py: 800 points in 6 UTM zones, one of them 6 degrees off its
//   central meridian, across the equator and the antimeridian, and both UPS caps): within 6 nm.
//
// Errors: all functions return RS_OK, or RS_ERR_USAGE for a NULL array with N > 0 or N < 0, or
// RS_ERR_INVALID for a non-finite input, a latitude outside [-90, 90], a zone out of range or
// a UTM/UPS coordinate outside GeographicLib's allowed range, with a message naming the field
// ("field 'lat': 91 is outside [-90, 90]") and, if N > 1, the row ("row 7: field 'lat': ...").
// GeographicLib's exceptions are all caught: GeographicErr gives RS_ERR_INVALID with its
// message, std::bad_alloc RS_ERR_NOMEM, anything else RS_ERR_EXTERNAL. On failure the outputs
// are unspecified (rows before the failing one are converted). The functions are thread-safe.
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// A geodetic point: latitude and longitude in degrees, height in metres (ellipsoidal).
typedef struct {
    double lat_deg, lon_deg, h_m;
} rs_llh;

// Geodetic -> ECEF (closed form).
rs_status rs_geo_llh_to_ecef( // out
    double *p_ecef_m,         // (N,3) metres
    // in
    const double *llh, // (N,3) lat_deg, lon_deg, h_m
    int N, rs_err *err);

// ECEF -> geodetic. Any finite point is accepted, including the centre of the earth (which
// gives lat 90, lon 0, h = -b); of several solutions the one with the smallest |h| is returned.
rs_status rs_geo_ecef_to_llh( // out
    double *llh,              // (N,3) lat_deg, lon_deg, h_m
    // in
    const double *p_ecef_m, // (N,3) metres
    int N, rs_err *err);

// Geodetic -> site ENU at `origin` (GeographicLib::LocalCartesian::Forward).
rs_status rs_geo_llh_to_enu( // out
    double *p_enu_m,         // (N,3) east, north, up, metres
    // in
    const rs_llh *origin, // the site origin
    const double *llh,    // (N,3) lat_deg, lon_deg, h_m
    int N, rs_err *err);

// Site ENU at `origin` -> geodetic (GeographicLib::LocalCartesian::Reverse).
rs_status rs_geo_enu_to_llh( // out
    double *llh,             // (N,3) lat_deg, lon_deg, h_m
    // in
    const rs_llh *origin,  // the site origin
    const double *p_enu_m, // (N,3) east, north, up, metres
    int N, rs_err *err);

// The rotation R_ecef_enu (row-major 3x3) whose columns are the east, north and up unit
// vectors at `origin` in ECEF, and the origin in ECEF: p_ecef = R_ecef_enu p_enu + origin_ecef.
// (GeographicLib::Geocentric::Forward with its rotation matrix.) The frame follows the given
// longitude even at a pole: east = (-sin lon, cos lon, 0) always.
rs_status rs_geo_enu_frame(  // out
    double R_ecef_enu[9],    // (3,3) row-major
    double origin_ecef_m[3], // (3,) metres; may be NULL
    // in
    const rs_llh *origin, rs_err *err);

// UTM/UPS -> geodetic. zone is 1..60 for UTM, 0 for UPS; north selects the hemisphere.
// enh is (easting_m, northing_m, h_m) with the standard false easting/northing; h passes
// through. Allowed ranges (GeographicLib's, 100 km wider than MGRS's): UTM easting
// [0, 1000] km, northing [-9100, 9600] km (north) or [900, 19600] km (south); UPS easting and
// northing [1200, 2800] km (north) or [700, 3300] km (south).
rs_status rs_geo_utm_to_llh( // out
    double *llh,             // (N,3) lat_deg, lon_deg, h_m
    // in
    int zone, bool north,
    const double *enh, // (N,3) easting_m, northing_m, h_m
    int N, rs_err *err);

// Geodetic -> UTM/UPS. zone >= 0 (0 = UPS): project into that zone and hemisphere (a point of
// the other hemisphere gets a northing continued across the equator), and *zone_out, *north_out
// are zone, north. zone < 0: each point's standard zone and hemisphere, which must then be the
// same for all N points, and are returned through *zone_out and *north_out (north is ignored).
rs_status rs_geo_llh_to_utm( // out
    double *enh,             // (N,3) easting_m, northing_m, h_m
    int *zone_out,           // may be NULL
    bool *north_out,         // may be NULL
    // in
    int zone, bool north,
    const double *llh, // (N,3) lat_deg, lon_deg, h_m
    int N, rs_err *err);

// Meridian convergence of UTM/UPS at each point, in degrees: the angle, clockwise, from true
// north to grid north. (A grid bearing b_grid becomes the true bearing b_grid + gamma.)
// zone as for rs_geo_llh_to_utm (zone < 0: each point's own standard zone, which may differ
// between points); the hemisphere does not change gamma, so north is ignored.
rs_status rs_geo_utm_convergence_deg( // out
    double *gamma_deg,                // (N,)
    // in
    int zone, bool north,
    const double *llh, // (N,3) lat_deg, lon_deg, h_m
    int N, rs_err *err);

// Parses a UTM/UPS zone string as GeographicLib::UTMUPS::DecodeZone does: a UTM zone 1..60
// followed by the hemisphere "n"/"s" or "north"/"south" (any case), e.g. "33N", "01s"; UPS is
// the hemisphere alone ("n", "S", "north"). RS_ERR_INVALID for anything else.
rs_status rs_geo_utm_zone_parse( // out
    int *zone,                   // 1..60, or 0 for UPS
    bool *north,
    // in
    const char *s, rs_err *err);

// Formats a zone as GeographicLib::UTMUPS::EncodeZone does ("33n", "01s", and "n"/"s" for UPS)
// into buf (NUL-terminated; 4 bytes are enough). RS_ERR_INVALID for a zone outside 0..60,
// RS_ERR_USAGE if buf is too small.
rs_status rs_geo_utm_zone_format( // out
    char *buf, size_t size,
    // in
    int zone, bool north, rs_err *err);

#ifdef __cplusplus
}
#endif
