// rs_site_internal.h -- what rs_site.c (the reader) and rs_site_check.c (diagnostics and
// plausibility checks) share. Not installed, not for other modules: use rs_site.h.
#pragma once
#include <stdbool.h>

#include "geo/rs_site.h"

// The report as it is being built. `pub` comes first: a rs_site_report* handed out is a pointer
// to this struct.
typedef struct {
    rs_site_report pub;
    int cap;
    bool nomem; // an allocation failed: the report is incomplete
} rs_site__report;

// Appends one diagnostic (severity RS_SITE_WARNING ignores `status`). On allocation failure
// sets r->nomem and drops the diagnostic.
void rs_site__diag(rs_site__report *r, rs_site_severity severity, rs_status status,
                   const char *file, int line, int feature, const char *feature_id,
                   const char *field, const char *fmt, ...)
    __attribute__((format(printf, 9, 10)));

// The one reader behind rs_site_load and rs_site_check: reads every file of the site folder it
// can, fills *site with everything that could be read (landmarks whose position is unusable get
// NaN coordinates) and reports every problem into r. *site is NULL only when out of memory.
void rs_site__read(// out
                   rs_site **site,
                   // in,out
                   rs_site__report *r,
                   // in
                   const char *dir);

// Plausibility of a geodetic position given in a site file. given = (lat_deg, lon_deg, h_m)
// as written (h in the site's declared heights). Reports out-of-range latitude/longitude, a
// position that looks swapped (far as given, near the origin once lat and lon are exchanged) or
// in radians (near once converted to degrees) -- saying what the corrected point would be -- and
// warns beyond site->max_landmark_distance_m. geojson_order words the corrected point as a
// GeoJSON [lon, lat, h] triple. origin_ok: the site origin itself is valid (else only the range
// checks run).
// out: llh (ellipsoidal height) and p_enu_m, (3,) each, when usable.
// Returns true when the position is usable (possibly with a warning).
bool rs_site__check_position(// out
                             double llh[3], double p_enu_m[3],
                             // in,out
                             rs_site__report *r,
                             // in
                             const rs_site *site, bool origin_ok, const char *file, int feature,
                             const char *feature_id, const char *field, bool geojson_order,
                             const double given[3]);

// Checks one observation just read from camera cam's CSV (line obs->line) against the camera's
// image size (when known: cam->width > 0) and the observations read before it (duplicates).
// Returns false if it must not be kept.
bool rs_site__check_observation(rs_site__report *r, const rs_site_camera *cam,
                                const rs_site_observation *obs, const rs_site *site);

// Checks a camera once its observations CSV has been read: enough observations to calibrate.
void rs_site__check_camera(rs_site__report *r, const rs_site_camera *cam);

// Checks across the whole site once everything is read: duplicate landmark and camera ids.
void rs_site__check_site(rs_site__report *r, const rs_site *site);
