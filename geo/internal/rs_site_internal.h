// rs_site_internal.h -- what the files of geo's site reader share. Not installed, not for other
// modules: use geo/rs_site.h.
//
// The reader is layered, every call going down (never back up):
//
//   rs_site_read.c         rs_site_load, rs_site_check; site.json and landmarks.geojson
//     rs_site_json.c         members of those JSON files, with their messages; repeated keys
//     rs_site_ground.c       the ground model: heights that are unreliable or unknown
//     rs_site_read_camera.c  each camera's model file and observations CSV
//       rs_site_check.c        plausibility checks that need more than one value
//         rs_site_report.c       the report: diagnostics, and reading a site file into it
//   rs_site.c              the site in memory: free, lookups (called by the above, calls none)
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "core/rs_index.h"
#include "geo/rs_site.h"

// ---- the report (rs_site_report.c) ----

// The report as it is being built. `pub` comes first: a rs_site_report* handed out is a pointer
// to this struct.
typedef struct {
    rs_site_report pub;
    int cap;
    bool nomem;   // an allocation failed: the report is incomplete
    bool picking; // rs_site_load_for_picking: a camera with too few picks is a warning, not an error
} rs_site__report;

// Appends one diagnostic (severity RS_SITE_WARNING ignores `status`). On allocation failure
// sets r->nomem and drops the diagnostic.
void rs_site__diag(rs_site__report *r, rs_site_severity severity, rs_status status, const char *file, int line,
                   int feature, const char *feature_id, const char *field, const char *fmt, ...)
    __attribute__((format(printf, 9, 10)));

// The state of one read: where diagnostics go, and what is being read (for messages).
typedef struct {
    rs_site__report *r;
    rs_site *site;
    const char *file;    // the file being read
    int feature;         // the GeoJSON feature being read, or -1
    const char *fid;     // its id, may be NULL
    bool origin_ok;      // site.json gave a valid origin and heights: positions can be checked
    bool landmarks_ok;   // landmarks.geojson was read: observations can be matched to landmarks
    rs_index ids;        // the landmarks by id (when landmarks_ok): picks are matched in O(log n)
    rs_index ids_nocase; // the same without case: the suggestion for an unknown id
    int *picked;         // (3 Nlandmarks,) the line of the camera being read's pick of each landmark
                         //   at its point, base, top (0: none yet); NULL before it is needed
} rs_site__reader;

// A diagnostic at what c is reading (c->file, c->feature, c->fid), at `line` (0: none).
void rs_site__say(rs_site__reader *c, rs_site_severity severity, rs_status status, int line, const char *field,
                  const char *fmt, ...) __attribute__((format(printf, 6, 7)));
#define ERR(c, status, field, ...)          rs_site__say(c, RS_SITE_ERROR, status, 0, field, __VA_ARGS__)
#define ERR_AT(c, status, line, field, ...) rs_site__say(c, RS_SITE_ERROR, status, line, field, __VA_ARGS__)
#define WARN(c, field, ...)                 rs_site__say(c, RS_SITE_WARNING, RS_OK, 0, field, __VA_ARGS__)
#define WARN_AT(c, line, field, ...)        rs_site__say(c, RS_SITE_WARNING, RS_OK, line, field, __VA_ARGS__)

// strdup and rs_io_join that set c->r->nomem when out of memory. NULL in -> NULL out (dup).
char *rs_site__dup(rs_site__reader *c, const char *s);
char *rs_site__join(rs_site__reader *c, const char *dir, const char *rel);

// Reports a missing file, or a folder, at c->file; `why` says what the file is for. True if
// there is a file.
bool rs_site__file_exists(rs_site__reader *c, const char *why);

// True when `path`, with every link followed (realpath), lies inside the site folder, or when it
// does not resolve (a missing file is reported as such by its reader). Paths a site names must
// stay inside it: "/etc/shadow" or "../../x" are refused before anything is read.
bool rs_site__inside(const rs_site__reader *c, const char *path);

// Reads the site file c->file (`why` as above), a regular file of at most max_bytes
// (rs_io_read_file_max). Returns the malloc'ed, NUL-terminated contents (and their length; len
// may be NULL), or NULL after reporting what is wrong.
char *rs_site__read_file(rs_site__reader *c, const char *why, size_t max_bytes, size_t *len);

// ---- JSON members (rs_site_json.c) ----
// Each reads obj[key] ("prefix.key" in messages; prefix may be NULL), reports what is wrong at c
// (a missing required member: "missing (EXPECTED)"; a wrong type, quoting what was found) and
// returns false / NULL then, and for a missing optional member.

struct cJSON;

// A 1-sigma under 1 mm is better than any survey of a road feature (geo/rs_site.h's ranges).
#define RS_SITE__SURVEY_SIGMA_RANGE \
    "a 1-sigma under 1 mm is better than any survey of a road feature, over 100 m it is no survey"

// properties.above_ground_m is at most this: a point 1 km above the road is no landmark of it.
#define RS_SITE__ABOVE_GROUND_MAX_M 1000.0

// Reads and parses the JSON file `name` of the site folder (a UTF-8 byte order mark allowed),
// reporting a syntax error at its line and column. c->file is *path (owned by the caller, who
// frees it and resets c->file) until the caller is done.
struct cJSON *rs_site__read_json_file(rs_site__reader *c, char **path, const char *name, const char *why,
                                      size_t max_bytes);
// "prefix.key" (or "key") into buf, truncated to fit; returns buf.
const char *rs_site__field_name(char *buf, size_t size, const char *prefix, const char *key);
// A short rendering of a JSON value for messages, truncated with "...".
void rs_site__json_excerpt(char *buf, size_t size, const struct cJSON *item);
// obj[key], its full name into field; a missing required member is reported.
const struct cJSON *rs_site__member(rs_site__reader *c, const struct cJSON *obj, const char *prefix, const char *key,
                                    bool required, const char *expected, char *field, size_t size);
// Reports `field` as not of the `expected` type, quoting it.
void rs_site__wrong_type(rs_site__reader *c, const char *field, const struct cJSON *it, const char *expected);
// A finite number; one > 0; one in [lo, hi] (`what` says what the bounds mean).
bool rs_site__get_number(rs_site__reader *c, const struct cJSON *obj, const char *prefix, const char *key,
                         bool required, double *out);
bool rs_site__get_positive(rs_site__reader *c, const struct cJSON *obj, const char *prefix, const char *key,
                           bool required, double *out);
bool rs_site__get_in_range(rs_site__reader *c, const struct cJSON *obj, const char *prefix, const char *key,
                           bool required, double lo, double hi, const char *unit, const char *what, double *out);
// A non-empty string (a pointer into the JSON tree).
bool rs_site__get_string(rs_site__reader *c, const struct cJSON *obj, const char *prefix, const char *key,
                         bool required, const char **out);
// An object; NULL if missing or not an object.
const struct cJSON *rs_site__get_object(rs_site__reader *c, const struct cJSON *obj, const char *prefix,
                                        const char *key, bool required, const char *expected);
// Warns about members of obj not in `known` (NULL-terminated): most often a misspelt name.
void rs_site__warn_unknown_keys(rs_site__reader *c, const struct cJSON *obj, const char *prefix,
                                const char *const *known);
// strcmp of two const char * (qsort).
int rs_site__cmp_key(const void *a, const void *b);
// Reports every key repeated within one object of `item`, recursively (O(k log k) per object):
// JSON readers disagree on which of two equal keys counts.
void rs_site__check_duplicate_keys(rs_site__reader *c, const struct cJSON *item, const char *prefix);

// ---- checks (rs_site_check.c) ----

// Plausibility of a geodetic position given in a site file. given = (lat_deg, lon_deg, h_m)
// as written (h in the site's declared heights). Reports out-of-range latitude/longitude, a
// position that looks swapped (far as given, near the origin once lat and lon are exchanged) or
// in radians (near once converted to degrees) -- saying what the corrected point would be -- and
// warns beyond site->max_landmark_distance_m. geojson_order words the corrected point as a
// GeoJSON [lon, lat, h] triple. origin_ok: the site origin itself is valid (else only the range
// checks run).
// out: llh (ellipsoidal height) and p_enu_m, (3,) each, when usable.
// Returns true when the position is usable (possibly with a warning).
bool rs_site__check_position( // out
    double llh[3], double p_enu_m[3],
    // in,out
    rs_site__report *r,
    // in
    const rs_site *site, bool origin_ok, const char *file, int feature, const char *feature_id, const char *field,
    bool geojson_order, const double given[3]);

// Checks one observation just read from camera cam's CSV (line obs->line, obs->at resolved)
// against the camera's image size (when known: cam->width > 0) and the observations read before
// it (duplicates: a point, a pole's base, a pole's top at most once; `along` picks may repeat).
// picked (may be NULL: the observations before it are searched instead) is (3 Nlandmarks,), the
// line of the pick of each landmark at its point, base, top so far; this pick is recorded in it.
// Returns false if it must not be kept.
bool rs_site__check_observation(rs_site__report *r, const rs_site_camera *cam, const rs_site_observation *obs,
                                const rs_site *site, int *picked);

// Checks a camera once its observations CSV has been read: enough observations to calibrate
// (4 picks of points; with `along` picks, as many numbers fixed as 4 points fix: 8, counting 2
// per point, base or top pick and 1 per along pick, at most 2 per straight segment), and warns
// when every pick is `along` segments of one direction (nothing fixes the camera along it).
void rs_site__check_camera(rs_site__report *r, const rs_site_camera *cam, const rs_site *site);

// Checks across the whole site once everything is read: duplicate landmark and camera ids.
void rs_site__check_site(rs_site__report *r, const rs_site *site);

// ---- the ground model (rs_site_ground.c) ----

// Builds site->ground (geo/rs_site.h, rs_site_ground_model) once every landmark is read and in
// ENU, when at least one landmark's height is UNRELIABLE or UNKNOWN, and gives those landmarks
// their modelled llh.h_m, p_enu_m[2] and sigma_v_m (height_modelled). Landmarks with an unusable
// position (NaN) are left alone. Reports into r: the heights left out of the fit (warnings,
// the first 10 by name), given unreliable heights that disagree with the model (likewise, and
// a summary), and a site ground_plane that gives no height (vertical: an error at site.json).
void rs_site__ground_model(rs_site__report *r, rs_site *site);

// ---- site.json (rs_site_read_json.c) ----

// obj[key] ("prefix.key" in messages), if present, as how far heights can be trusted ("surveyed",
// "unreliable", "unknown") into *out; false (after reporting) when it is not one.
bool rs_site__read_height_trust(rs_site__reader *c, const struct cJSON *obj, const char *prefix, const char *key,
                                rs_site_height *out);
// obj's lat, lon, h ("prefix.lat" ... in messages) into given = (lat, lon, h); false after reporting.
bool rs_site__get_llh(rs_site__reader *c, const struct cJSON *obj, const char *prefix, double given[3]);
// Reads site.json into c->site (origin, heights, ground plane, cameras' entries), reporting.
void rs_site__read_site_json(rs_site__reader *c);

// ---- camera files (rs_site_read_camera.c) ----

// Reads camera i's model file (cam->model_path) into cam->camera, reporting what is wrong.
void rs_site__read_camera_model(rs_site__reader *c, rs_site_camera *cam, int i);

// Reads camera i's observations CSV (cam->observations_path) into cam->observations, matching
// landmark ids against c->site's landmarks (when c->landmarks_ok) and checking each pick.
void rs_site__read_observations(rs_site__reader *c, rs_site_camera *cam, int i);

// ---- CSV, shared by the observations reader (rs_site_read_camera.c) and the importer
// (rs_site_import_read.c) ----

// Splits one CSV line in place into fields (RFC 4180 quoting, surrounding blanks trimmed).
// Stores at most maxf fields; returns how many there are, or -1 for malformed quoting.
int rs_site__split_csv(char *s, char **fields, int maxf);

// ---- building a site folder under a temporary name (rs_site_init.c; also the importer's) ----

// RS_OK when `dir` does not exist (*exists false) or is an empty folder (*exists true); else
// RS_ERR_INVALID ("DIR: exists and is not empty: not overwriting it") or RS_ERR_IO.
rs_status rs_site__check_target(const char *dir, bool *exists, rs_err *err);

// Creates the folder "<dir>.tmp.XXXXXX" next to dir (and dir's parent if need be), with the
// permissions of an ordinary folder. out: *tmp, malloc'ed (caller frees). RS_ERR_IO, RS_ERR_NOMEM.
rs_status rs_site__make_tmp(char **tmp, const char *dir, rs_err *err);
