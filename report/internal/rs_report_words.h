// rs_report_words.h -- the report's text blocks that are not tables of figures: the verdict per
// camera in plain words (first page and the top of each camera's section), the plain reading
// of the pose table's statistics, the stamp (date, version) and the inputs with their SHA-256.
// Private to report/ (rs_report_words.c).
#pragma once
#include "report/internal/rs_report_doc.h"
#include "report/internal/rs_report_draw.h"

// The first page's "In short": a sentence with the need, then a table with one row per camera:
// its verdict, the figure that decided it and what to do (rs_report_camera_action).
void rs_report_doc_verdicts(rs_doc *doc, const struct rs_report_ctx *rep);

// The first page's row of one camera: the one figure that decided its verdict (the threshold
// failed by the widest margin; the ground error for a pass) and the action, naming
// 'roadside calib SITE --refine focal' when the image says the focal length is off (the cause is
// the lens, not the survey) and the outliers by id.
// out: figure (figure_size bytes), action (action_size bytes), NUL-terminated
void rs_report_camera_action(char *figure, size_t figure_size, char *action, size_t action_size,
                             const struct rs_report_ctx *rep, const rs_report_camera *cam);

// One camera's verdict in words (the same text as in "In short").
void rs_report_doc_camera_verdict(rs_doc *doc, const struct rs_report_ctx *rep, const rs_report_camera *cam);

// Under the pose table: the variance factor, the condition number and the largest influence in
// plain words.
void rs_report_doc_pose_words(rs_doc *doc, const rs_report_camera *cam);

// The camera's warnings, each once, landmarks named by id: the audit's (which include the
// solver's) when it ran, else <id>.json's. Returns how many were written.
int rs_report_doc_warnings(rs_doc *doc, const struct rs_report_ctx *rep, const rs_report_camera *cam);

// "Written <date> by roadside <version>" (one line of text into buf).
void rs_report_stamp(char *buf, size_t size, const struct rs_report_ctx *rep);

// The appendix: every input file read (site.json, landmarks.geojson, lanes.geojson, each
// camera's nominal model, observations, <id>.cameramodel, <id>.json and background image) with
// its size and SHA-256 (OpenSSL's EVP), so that a reader can tell which files the report is of.
void rs_report_doc_inputs(rs_doc *doc, const struct rs_report_ctx *rep);
