// rs_report.h -- the per-intersection calibration report (`roadside report`): one
// self-contained HTML file and the same content as a PDF, for an engineer to send to a city.
//
// Purpose: from a site (rs_site_load) and the files `roadside calib` wrote for its cameras
// (<id>.cameramodel and <id>.json in calib_dir), write
//   out_dir/report.html  one file, no external resource: figures are base64 PNG data URIs,
//                        the CSS is inline, there is no script; every string read from an
//                        input file is HTML-escaped
//   out_dir/report.pdf   A4, the same headings, tables and figures drawn with cairo's PDF
//                        surface (figures as vectors)
// Content: first the verdict per camera in plain words (rs_audit_site_verdict: the need, the
// ground accuracy where the landmarks are and at the farthest one, outliers named with what to
// do), the date, the version and the SHA-256 of every input (an appendix table); then a site
// summary table and a top-down ENU map of the site (cameras, their fields of
// view on the ground cut at range_m, landmarks, lanes, and the smallest 1-sigma ground error
// over the cameras' uncertainty maps as a colour scale with labelled contours); then per camera
//   - its image (the first PNG/JPEG in the camera's backgrounds folder, else a neutral canvas)
//     with the picks, the surveyed landmarks reprojected and the residual vectors magnified
//     (the factor written, with a scale bar in pixels), and the ground grid and lane lines
//     projected through the calibrated camera (mrcal_project, full lens model);
//   - the pose (ENU, lat/lon/h, yaw/pitch/roll) with 1-sigma, rms_surveyed_px and the labelled
//     rms_adjusted_px (docs/calibration.md, "Residuals: which is which"), variance factor,
//     condition;
//   - per-landmark residuals (surveyed) and leave-one-out figures (rs_audit_site_camera);
//   - a top-down map of the ground the camera sees with the 1-sigma ground localisation error
//     (rs_audit_map) as a colour scale with labelled contours;
//   - coverage, the audit's verdict and every warning in plain words.
// The audit is that of the calibration files in calib_dir, exactly `roadside audit SITE --calib
// CALIB_DIR` (rs_audit_site_camera with calib_dir): the verdict shown is the audit's.
// Lanes: an optional SITE/lanes.geojson, a FeatureCollection of LineString / MultiLineString
// features with [lon, lat] or [lon, lat, h] positions (h in the site's declared heights; without
// h the line lies on the site's ground plane).
//
// Conventions: docs/conventions.md (site ENU, rt_cam_enu, pixel (0,0) = centre of the top-left
// pixel, yaw/pitch/roll). docs/report.md describes the report section by section.
//
// Cost: the audit (a full solve, one leave-one-out solve per landmark and the map, ~0.5 s per
// camera at the default 1 m cells over 100 m), plus ~0.2 s per camera of drawing.
#pragma once
#include <stdbool.h>

#include "audit/rs_audit.h"
#include "core/rs_status.h"
#include "geo/rs_site.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    const char *calib_dir;          // folder with <id>.cameramodel and <id>.json; NULL: SITE/calib
    double range_m;                 // ground shown within this horizontal distance of each camera,
                                    //   metres (default 100; also the audit's range_m)
    double grid_m;                  // ground grid spacing drawn into the images, metres; <= 0:
                                    //   automatic (a 1-2-5 number near range_m / 10; default 0)
    int figure_width_px;            // width of the HTML's PNG figures (default 1000, >= 200)
    bool audit;                     // audit the calibration (as `roadside audit --calib`) for the
                                    //   leave-one-out figures, the uncertainty map, the warnings
                                    //   and the verdict (default true; false: "not audited")
    rs_audit_options audit_options; // (default rs_audit_options_default: need_ground_m 1 m and
                                    //   the thresholds derived from it); its range_m is replaced
                                    //   by range_m above
    const char *ortho_path;         // the orthophoto the site map is drawn on (any georeferenced
                                    //   image GDAL reads, any CRS: rs_geo_ortho_read); NULL:
                                    //   SITE/ortho.tif when there is one (`roadside ortho` writes
                                    //   it), else none
    const char *version;            // the software version printed on the report; NULL: "unknown"
    long long written_utc_s;        // the date printed, seconds since 1970 UTC; 0: now
    // called before each stage that takes a while (loading and auditing camera i of N, the
    // HTML, the PDF) with a line in words; may be NULL. The library never prints: the cli
    // puts the line on stderr.
    void (*progress)(void *progress_ctx, const char *what);
    void *progress_ctx;
} rs_report_options;

// Fills opt with the defaults above. opt must not be NULL.
void rs_report_options_default(rs_report_options *opt);

// What was written.
typedef struct {
    int Ncameras;      // cameras in the report
    int Nfigures;      // figures in each of the two files (1 + 2 per camera)
    int Naudit_failed; // cameras whose audit could not run (their sections say why)
    int Naudit_fail;   // cameras whose audit ran and found a threshold exceeded
    int Nremoved;      // on failure: files of an earlier report removed from out_dir (0..2)
} rs_report_summary;

// Writes out_dir/report.html and out_dir/report.pdf (out_dir is created if needed), together or
// not at all: both are written under temporary names first and renamed into place only when
// both are complete. On failure neither file is left in out_dir, not even an earlier report's
// (it would look like this run's): summary->Nremoved counts those removed, and a folder this
// call created is removed again.
//
// out:  summary (may be NULL)
// in:   out_dir; site (rs_site_load); opt (may be NULL: defaults)
// Errors: RS_ERR_IO / RS_ERR_NOT_FOUND (a camera's <id>.json or <id>.cameramodel missing: run
// `roadside calib` first), RS_ERR_PARSE / RS_ERR_INVALID (a malformed calibration file, lanes
// file or background image, naming the file and field), RS_ERR_INVALID (bad options),
// RS_ERR_NOMEM, RS_ERR_EXTERNAL (cairo). An audit that fails for a camera is not an error: the
// report says so in that camera's section.
rs_status rs_report_write( // out
    rs_report_summary *summary,
    // in
    const char *out_dir, const rs_site *site,
    const rs_report_options *opt, // may be NULL
    rs_err *err);                 // may be NULL

// Removes out_dir/report.html and out_dir/report.pdf if they are there: what a run that could not
// even call rs_report_write (its site unreadable) does, so that no earlier report looks like
// its own. *Nremoved (may be NULL): how many files were removed. Errors: RS_ERR_IO, RS_ERR_NOMEM.
rs_status rs_report_remove( // out
    int *Nremoved,
    // in
    const char *out_dir, rs_err *err);

#ifdef __cplusplus
}
#endif
