// rs_synth_sun.h -- the sun's direction seen from a place on the earth at a UTC time, and the
// ISO 8601 times it is given in. (The light a background image shows: rs_synth_light.h.)
//
// Method: NOAA's solar position equations (the NOAA Global Monitoring Laboratory "Solar
// Calculator" and its spreadsheet, https://gml.noaa.gov/grad/solcalc/calcdetails.html), which
// follow J. Meeus, "Astronomical Algorithms", 2nd ed. (1998), chapters 25 (low-precision solar
// coordinates: geometric mean longitude and anomaly, equation of the centre, apparent longitude,
// obliquity corrected for nutation), and 28 (equation of time). The hour angle comes from the
// true solar time (UTC + equation of time + 4 min per degree of longitude); azimuth and elevation
// from the spherical triangle pole-zenith-sun.
//
// Accuracy: the elevation is GEOMETRIC (no atmospheric refraction, which lifts the sun by ~0.57
// degree at the horizon and ~0.02 degree at 45 degrees) and geocentric (the parallax of 0.0024
// degree is ignored). Against an independent formulation (Blanco-Muriel et al., "Computing the
// solar vector", Solar Energy 70(5), 2001, the "PSA" algorithm, itself within 0.0083 degree of
// the ephemeris) the angle between the two sun directions is at most 0.012 degree over
// 2000..2050 at latitudes -89..89 (tests/synth/backdrop/test_sun.py). NOAA states its equations are valid
// for 1901..2099.
//
// Azimuth is clockwise from north in [0, 360) (a compass bearing, like yaw_deg and
// docs/conventions.md); it is undefined (returned as computed, any value) with the sun within
// 1e-9 degree of the zenith or at a pole.
#pragma once
#include <stdbool.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Solar azimuth (clockwise from north, degrees, [0, 360)) and elevation (above the horizon,
// degrees, [-90, 90], without refraction) at latitude/longitude (degrees, WGS84 geodetic;
// longitude east positive) and UTC time (seconds since 1970-01-01T00:00:00Z, leap seconds not
// counted, as POSIX time). Non-finite inputs or |lat| > 90 give NaN outputs; use
// rs_synth_sun_position_checked for an error instead.
void rs_synth_sun_position( // out
    double *azimuth_deg, double *elevation_deg,
    // in
    double lat_deg, double lon_deg, double unix_time_s);

// The same, with its inputs checked: RS_ERR_INVALID (naming the field) for a non-finite input,
// a latitude outside [-90, 90] or a longitude outside [-540, 540]. Outputs may be NULL.
rs_status rs_synth_sun_position_checked( // out
    double *azimuth_deg, double *elevation_deg,
    // in
    double lat_deg, double lon_deg, double unix_time_s, rs_err *err);

// ---- times ----

// Parses an ISO 8601 time "YYYY-MM-DDTHH:MM[:SS[.fff]]" followed by "Z" or "+HH:MM"/"-HH:MM"
// (a zone is required). out: seconds since 1970 UTC. Returns RS_ERR_PARSE naming `field`.
rs_status rs_synth_parse_iso8601(double *unix_time_s, const char *s, const char *field, rs_err *err);

#ifdef __cplusplus
}
#endif
