// rs_report_words.h -- the report's text blocks that are not tables of figures: the verdict per
// camera in plain words (first page and the top of each camera's section), the plain reading
// of the pose table's statistics, the stamp (date, version) and the inputs with their SHA-256.
// Private to report/ (rs_report_words.c).
#pragma once
#include "report/internal/rs_report_doc.h"
#include "report/internal/rs_report_draw.h"

// The first page's "In short": one paragraph per camera, its audit verdict in words (a warning
// box when it fails or was not audited), after a paragraph with the need and the thresholds.
void rs_report_doc_verdicts(rs_doc *doc, const struct rs_report_ctx *rep);

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
