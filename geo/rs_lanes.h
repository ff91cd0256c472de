// rs_lanes.h -- the site's traffic lanes, lanes.geojson (docs/site-format.md "lanes.geojson"):
// the one reader and the one writer of the format, used by `site check`, the report's drawings, the built-in
// traffic, SUMO's network and the digital-twin backgrounds; and the geometry of a lane's centre
// line.
//
// Frames: the site ENU frame (east, north, up; metres); headings are compass headings,
// clockwise from north, degrees.
#pragma once
#include <stdbool.h>

#include "core/rs_status.h"
#include "geo/rs_site.h"
#include "geo/rs_site_write.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    RS_LANE_FORWARD = 0, // vehicles travel in vertex order
    RS_LANE_BOTH         // either way (a single-track road)
} rs_lane_direction;

// One lane: a LineString of lanes.geojson in the site ENU frame.
typedef struct {
    char *id;       // owned; unique
    char *kind;     // owned, may be NULL ("approach", "exit", "junction", ...)
    double width_m; // > 0
    rs_lane_direction direction;
    double speed_mps;     // speed limit, > 0; NaN when the file gives none
    double (*p_enu_m)[3]; // (Npoints, 3) owned: east, north, up, metres (up: the given height,
                          //   or on the site's ground plane where none is given)
    int Npoints;          // >= 2; consecutive points at least 1 mm apart
    int *next;            // (Nnext,) owned: indices of the lanes this one continues into
    int Nnext;
    int feature; // index in the file's "features"
} rs_lane;

typedef struct {
    rs_lane *lane; // (N,) owned
    int N;
} rs_lanes;

// Reads lanes.geojson: a FeatureCollection of LineString features, coordinates [lon, lat] or
// [lon, lat, h] (RFC 7946 order, WGS84 degrees), properties: id (string, unique), width_m (> 0),
// direction ("forward" | "both", default "forward"), optional speed_mps (> 0), optional kind
// (string), optional next (list of lane ids). Converted to the site ENU frame with
// rs_geo_llh_to_enu. Heights follow the site's rule for every height (site.json "heights": an
// orthometric h gets the geoid undulation added); a position without h is placed at the
// origin's height for its east and north, and its up coordinate is on the site's ground plane.
// Errors name the file, the feature and the field:
//   "SITE/lanes.geojson: feature 3 (id 'A1_in1'): properties.width_m: must be > 0"
// RS_ERR_IO (unreadable), RS_ERR_PARSE (not JSON, wrong types), RS_ERR_INVALID (out of range,
// duplicate id, fewer than 2 distinct points, a point more than 100 km from the origin),
// RS_ERR_NOT_FOUND (a `next` id that is no lane), RS_ERR_NOMEM.
// out: *lanes (owned; rs_lanes_free). On failure *lanes is empty.
rs_status rs_lanes_read( // out
    rs_lanes *lanes,
    // in
    const char *path, const rs_site *site, rs_err *err);
void rs_lanes_free(rs_lanes *lanes); // NULL-safe; leaves *lanes empty

// Writes lanes.geojson (the format rs_lanes_read reads), atomically (rs_io_write_file): one
// LineString feature per lane in order, properties id, kind (when not NULL), width_m,
// direction ("forward" | "both"), speed_mps (when not NaN), next (the ids of lanes[next[i]];
// always written, [] for none). Points are converted from the site ENU frame to WGS84 with
// rs_geo_enu_to_llh at `origin` and written [lon, lat] -- the reader then puts them on the
// site's ground plane, and their up coordinate is not written -- or, with_height, as
// [lon, lat, h] with h = h_ell - geoid_undulation_m (the site's declared heights).
// in: lanes: every field but `feature` (ignored); origin: the site origin, ellipsoidal height;
//     geoid_undulation_m: N of the site's "heights" (0 for ellipsoidal); layout:
//     geo/rs_site_write.h
// Returns RS_ERR_INVALID (no id, a `next` out of range, a non-finite number), the status of
// rs_geo_enu_to_llh, RS_ERR_IO, RS_ERR_NOMEM.
rs_status rs_lanes_write( // in
    const char *path, const rs_lanes *lanes, const rs_llh *origin, double geoid_undulation_m, bool with_height,
    rs_site_layout layout, rs_err *err);

// Length of a lane's polyline, metres.
double rs_lane_length_m(const rs_lane *lane);

// The point at arc length s (clamped to [0, length]) along a lane and the compass heading of the
// segment it lies on (clockwise from north, degrees, [0, 360)), in the lane's vertex order.
// out: p_enu_m (2,); heading_deg may be NULL
void rs_lane_point(double p_enu_m[2], double *heading_deg,
                   // in
                   const rs_lane *lane, double s_m);

// Distance from a point to the nearest point of a lane's polyline, metres; *heading_deg (may be
// NULL) receives the heading of the nearest segment in vertex order.
double rs_lane_distance_m(double *heading_deg,
                          // in
                          const rs_lane *lane, const double p_enu_m[2]);

#ifdef __cplusplus
}
#endif
