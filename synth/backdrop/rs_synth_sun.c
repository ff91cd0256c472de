// rs_synth_sun.c -- solar azimuth and elevation (NOAA / Meeus); ISO 8601 times (synth/backdrop/rs_synth_sun.h).
#include "synth/backdrop/rs_synth_sun.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_pose.h"
#include "core/rs_units.h"
#include "synth/fleet/rs_synth_vehicle.h"

void rs_synth_sun_position(double *azimuth_deg, double *elevation_deg, double lat_deg, double lon_deg,
                           double unix_time_s)
{
    double az = NAN, el = NAN;
    if (isfinite(lat_deg) && isfinite(lon_deg) && isfinite(unix_time_s) && fabs(lat_deg) <= 90.0) {
        // Julian century from J2000.0 (UTC is used for TT: the ~70 s difference moves the sun by
        // 0.0008 degree).
        double jd = unix_time_s / 86400.0 + 2440587.5;
        double T = (jd - 2451545.0) / 36525.0;
        double L0 = fmod(280.46646 + T * (36000.76983 + T * 0.0003032), 360.0);           // mean longitude
        double M = 357.52911 + T * (35999.05029 - 0.0001537 * T);                         // mean anomaly
        double e = 0.016708634 - T * (0.000042037 + 0.0000001267 * T);                    // eccentricity
        double C = sin(M * RS_RAD_PER_DEG) * (1.914602 - T * (0.004817 + 0.000014 * T)) + // equation of
                   sin(2 * M * RS_RAD_PER_DEG) * (0.019993 - 0.000101 * T) +              // the centre
                   sin(3 * M * RS_RAD_PER_DEG) * 0.000289;
        double omega = 125.04 - 1934.136 * T;                                     // lunar node
        double lambda = L0 + C - 0.00569 - 0.00478 * sin(omega * RS_RAD_PER_DEG); // apparent long.
        double eps0 = 23.0 + (26.0 + (21.448 - T * (46.815 + T * (0.00059 - T * 0.001813))) / 60.0) / 60.0;
        double eps = eps0 + 0.00256 * cos(omega * RS_RAD_PER_DEG); // obliquity
        double decl = asin(sin(eps * RS_RAD_PER_DEG) * sin(lambda * RS_RAD_PER_DEG));
        // Equation of time (Meeus eq. 28.3, in minutes).
        double y = tan(eps * RS_RAD_PER_DEG / 2) * tan(eps * RS_RAD_PER_DEG / 2);
        double eot = 4.0 / RS_RAD_PER_DEG *
                     (y * sin(2 * L0 * RS_RAD_PER_DEG) - 2 * e * sin(M * RS_RAD_PER_DEG) +
                      4 * e * y * sin(M * RS_RAD_PER_DEG) * cos(2 * L0 * RS_RAD_PER_DEG) -
                      0.5 * y * y * sin(4 * L0 * RS_RAD_PER_DEG) - 1.25 * e * e * sin(2 * M * RS_RAD_PER_DEG));
        // True solar time in minutes of the UTC day, then the hour angle (0 at local noon).
        double utc_min = fmod(unix_time_s, 86400.0) / 60.0;
        double tst = utc_min + eot + 4.0 * lon_deg;
        double H = (tst / 4.0 - 180.0) * RS_RAD_PER_DEG;
        double phi = lat_deg * RS_RAD_PER_DEG;
        // Sun direction in the local east-north-up frame.
        double east = -cos(decl) * sin(H);
        double north = sin(decl) * cos(phi) - cos(decl) * sin(phi) * cos(H);
        double up = sin(decl) * sin(phi) + cos(decl) * cos(phi) * cos(H);
        el = asin(fmax(-1.0, fmin(1.0, up))) / RS_RAD_PER_DEG;
        az = atan2(east, north) / RS_RAD_PER_DEG;
        if (az < 0) az += 360.0;
        if (az >= 360.0) az -= 360.0;
    }
    if (azimuth_deg) *azimuth_deg = az;
    if (elevation_deg) *elevation_deg = el;
}

rs_status rs_synth_sun_position_checked(double *azimuth_deg, double *elevation_deg, double lat_deg, double lon_deg,
                                        double unix_time_s, rs_err *err)
{
    if (!isfinite(lat_deg) || fabs(lat_deg) > 90.0)
        return rs_err_set(err, RS_ERR_INVALID, "lat: %g is outside [-90, 90]", lat_deg);
    if (!isfinite(lon_deg) || fabs(lon_deg) > 540.0)
        return rs_err_set(err, RS_ERR_INVALID, "lon: %g is outside [-540, 540]", lon_deg);
    if (!isfinite(unix_time_s)) return rs_err_set(err, RS_ERR_INVALID, "time: %g is not finite", unix_time_s);
    rs_synth_sun_position(azimuth_deg, elevation_deg, lat_deg, lon_deg, unix_time_s);
    return RS_OK;
}

// ---- ISO 8601 times ----

// Days from 1970-01-01 to year-month-day (proleptic Gregorian).
static long days_from_civil(long y, unsigned m, unsigned d)
{
    y -= m <= 2;
    const long era = (y >= 0 ? y : y - 399) / 400;
    const unsigned yoe = (unsigned)(y - era * 400);
    const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
    const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    return era * 146097 + (long)doe - 719468;
}

rs_status rs_synth_parse_iso8601(double *unix_time_s, const char *s, const char *field, rs_err *err)
{
    int Y, Mo, D, h, mi, n = 0;
    double sec = 0;
    if (sscanf(s, "%4d-%2d-%2dT%2d:%2d%n", &Y, &Mo, &D, &h, &mi, &n) != 5 || n != 16) goto bad;
    const char *p = s + n;
    if (*p == ':') {
        char *end;
        sec = strtod(p + 1, &end);
        if (end == p + 1 || !(sec >= 0 && sec < 61)) goto bad;
        p = end;
    }
    double zone_s;
    if (*p == 'Z' && p[1] == 0) {
        zone_s = 0;
    } else if ((*p == '+' || *p == '-') && strlen(p) == 6 && p[3] == ':' && isdigit((unsigned char)p[1]) &&
               isdigit((unsigned char)p[2]) && isdigit((unsigned char)p[4]) && isdigit((unsigned char)p[5])) {
        const int zh = (p[1] - '0') * 10 + (p[2] - '0'), zm = (p[4] - '0') * 10 + (p[5] - '0');
        if (zh > 14 || zm > 59) goto bad;
        zone_s = (*p == '+' ? 1 : -1) * (zh * 3600.0 + zm * 60.0);
    } else {
        goto bad;
    }
    if (Mo < 1 || Mo > 12 || D < 1 || D > 31 || h > 23 || mi > 59 || h < 0 || mi < 0) goto bad;
    *unix_time_s = days_from_civil(Y, (unsigned)Mo, (unsigned)D) * 86400.0 + h * 3600.0 + mi * 60.0 + sec - zone_s;
    return RS_OK;
bad:;
    char shown[64];
    rs_synth_safe_text(shown, sizeof(shown), s);
    return rs_err_set(err, RS_ERR_PARSE,
                      "%s: \"%s\" is not an ISO 8601 time YYYY-MM-DDTHH:MM[:SS]Z or with a "
                      "+HH:MM offset",
                      field, shown);
}
