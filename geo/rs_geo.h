// rs_geo.h -- WGS84 geodetic <-> ECEF <-> site ENU, and UTM/UPS <-> geodetic, through
// GeographicLib (C. F. F. Karney, "Transverse Mercator with an accuracy of a few nanometers",
// J. Geodesy 85, 475-485 (2011); "Geodesics on an ellipsoid", J. Geodesy 87, 43-55 (2013)).
//
// Conventions (docs/conventions.md): geodetic points are llh = (lat_deg, lon_deg, h_m), h
// ellipsoidal above WGS84; ECEF in metres; the site ENU frame is GeographicLib's LocalCartesian
// at the site origin: x east, y north, z up along the ellipsoid normal, origin at the site
// origin's (lat, lon, h). Arrays are row-major, one point per row.
//
// Accuracy: ECEF <-> geodetic and ENU <-> geodetic round trips are exact to within a few
// nanometres anywhere within 5000 km of the surface (GeographicLib::Geocentric, whose inverse
// is Vermeille's closed-form method made robust near the poles and the centre); tested against
// PROJ's cct to 1 micrometre up to 20 km from the origin, at |lat| up to 89.9 degrees.
// UTM/UPS: GeographicLib::UTMUPS (Krueger series to 6th order): error below 5 nm within the
// standard UTM zone and +-3.9 degrees of longitude beyond it.
//
// All functions take N points and return RS_ERR_INVALID (with the row in the message) for a
// non-finite input or a latitude outside [-90, 90]; outputs are then unspecified.
#pragma once
#include <stdbool.h>

#include "rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// A geodetic point: latitude and longitude in degrees, height in metres (ellipsoidal).
typedef struct {
    double lat_deg, lon_deg, h_m;
} rs_llh;

rs_status rs_geo_llh_to_ecef(// out
                             double *p_ecef_m,     // (N,3)
                             // in
                             const double *llh,    // (N,3) lat_deg, lon_deg, h_m
                             int N, rs_err *err);

rs_status rs_geo_ecef_to_llh(// out
                             double *llh,          // (N,3)
                             // in
                             const double *p_ecef_m, // (N,3)
                             int N, rs_err *err);

rs_status rs_geo_llh_to_enu(// out
                            double *p_enu_m,       // (N,3)
                            // in
                            const rs_llh *origin,
                            const double *llh,     // (N,3)
                            int N, rs_err *err);

rs_status rs_geo_enu_to_llh(// out
                            double *llh,           // (N,3)
                            // in
                            const rs_llh *origin,
                            const double *p_enu_m, // (N,3)
                            int N, rs_err *err);

// The rotation R_ecef_enu (row-major 3x3) whose columns are the east, north and up unit
// vectors at `origin` in ECEF, and the origin in ECEF: p_ecef = R_ecef_enu p_enu + origin_ecef.
rs_status rs_geo_enu_frame(// out
                           double R_ecef_enu[9],
                           double origin_ecef_m[3], // may be NULL
                           // in
                           const rs_llh *origin, rs_err *err);

// UTM/UPS. zone is 1..60 for UTM, 0 for UPS; north selects the hemisphere.
// enh is (easting_m, northing_m, h_m) with the standard false easting/northing.
rs_status rs_geo_utm_to_llh(// out
                            double *llh,           // (N,3)
                            // in
                            int zone, bool north,
                            const double *enh,     // (N,3)
                            int N, rs_err *err);

// Forward UTM/UPS in a given zone (zone < 0: each point's standard zone, which must then be
// the same for all N points, and is returned through *zone_out, may be NULL).
rs_status rs_geo_llh_to_utm(// out
                            double *enh,           // (N,3)
                            int *zone_out,         // may be NULL
                            bool *north_out,       // may be NULL
                            // in
                            int zone, bool north,
                            const double *llh,     // (N,3)
                            int N, rs_err *err);

// Meridian convergence of UTM/UPS at each point, in degrees: the angle, clockwise, from true
// north to grid north. (A grid bearing b_grid becomes the true bearing b_grid + gamma.)
rs_status rs_geo_utm_convergence_deg(// out
                                     double *gamma_deg, // (N,)
                                     // in
                                     int zone, bool north,
                                     const double *llh, // (N,3)
                                     int N, rs_err *err);

#ifdef __cplusplus
}
#endif
