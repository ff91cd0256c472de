// rs_track_io.h -- the files `roadside track` writes: the tracks as CSV (issue 39's interface 3),
// GeoJSON and SAE J3224-style JSON lines. Its input, the located-detections CSV (interface 2), is
// read by localise's one reader (eval/localise/rs_localise.h, rs_localise_read).
//
// Tracks CSV (written): the header
//   time_s,track_id,e_m,n_m,lat_deg,lon_deg,speed_mps,heading_deg,sigma_e_m,sigma_n_m,cov_en_m2,
//   sigma_speed_mps,sigma_heading_deg,age_s,detections,cameras
// one row per rs_track_row (positions to the nanometre, so that a reader can check the filter
// to 1e-9 m); cameras: the ids that updated the track at that step joined by '+', empty when the
// track coasts. lat_deg, lon_deg: the ENU point (e_m, n_m, u_m) through the site origin
// (geo/rs_geo.h). GeoJSON: one LineString per track (a Point for a track reported once; WGS84
// [lon, lat, h], RFC 7946) whose
// properties hold the track's id and class and, per vertex, arrays of the CSV's other columns.
// SDSM JSON lines: one object per row mirroring J3224's DetectedObjectCommonData (docs/track.md
// lists the fields, units and confidence classes).
// Every output is written atomically (core/rs_io.h).
#pragma once
#include <stddef.h>

#include "core/rs_status.h"
#include "eval/track/rs_track.h"
#include "geo/rs_geo.h"

#ifdef __cplusplus
extern "C" {
#endif

#define RS_TRACK_TRACKS_HEADER                                                                                     \
    "time_s,track_id,e_m,n_m,lat_deg,lon_deg,speed_mps,heading_deg,sigma_e_m,sigma_n_m,cov_en_m2,sigma_speed_mps," \
    "sigma_heading_deg,age_s,detections,cameras"

// Writes the tracker's rows as the tracks CSV to path (atomically). RS_ERR_IO, RS_ERR_NOMEM,
// RS_ERR_EXTERNAL (geodesy).
rs_status rs_track_write_csv(const char *path, const rs_track_tracker *tracker, const rs_llh *origin, rs_err *err);

// Writes the tracks as GeoJSON LineStrings (atomically).
rs_status rs_track_write_geojson(const char *path, const rs_track_tracker *tracker, const rs_llh *origin, rs_err *err);

// Writes the rows as SDSM-style JSON lines (atomically).
rs_status rs_track_write_sdsm(const char *path, const rs_track_tracker *tracker, const rs_llh *origin, rs_err *err);

#ifdef __cplusplus
}
#endif
