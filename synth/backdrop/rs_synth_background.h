// rs_synth_background.h -- backgrounds of a camera's view: the temporal median of video frames or
// of an image sequence (`roadside background`), and the names and tags every background has in
// site.json (docs/backgrounds.md). Digital-twin backgrounds ray-traced from the site's lanes
// (`roadside site render-backgrounds`): synth/povray/rs_synth_twin.h.
//
// Tags: every background has a name (its file backgrounds/<camera>/<name>.png), a time (ISO 8601
// with a zone, rs_synth_parse_iso8601), conditions (one of rs_synth_background_conditions), a
// `synthetic` flag, and free key=value tags. They are recorded in site.json, in the camera's
// "background_images" list (docs/site-format.md), by geo (rs_site_record_background); the
// camera's "backgrounds" folder is set to "backgrounds/<camera>" if it was absent. Everything
// else in site.json is kept as it was. The site loader reads them back (rs_site_background,
// geo/rs_site.h).
#pragma once
#include "core/rs_camera.h"
#include "core/rs_status.h"
#include "geo/rs_site.h"
#include <mrcal/mrcal.h>
#include <stdbool.h>
#include <stddef.h>
#ifdef __cplusplus
extern "C" {
#endif

// ---- temporal median ----

// A background by temporal median, streaming with bounded memory.
//
// Method: the frames of all inputs, in order, are decimated into a buffer of at most
// `max_frames` frames (8-bit RGB): frame i is kept when i is a multiple of the stride s (first
// s = 1); when the buffer is full the frames at odd buffer positions are dropped and s doubles.
// So the buffer always holds frames evenly spaced over the whole input (every s-th frame, between
// max_frames/2 and max_frames of them), whatever its length, and nothing else grows with the
// input. The result is, per pixel and channel, the exact lower median (order statistic
// floor((n-1)/2)) of the n kept frames. With n <= max_frames all frames are used and the median
// is exact; a value seen in more than half of the kept frames is returned exactly.
//
// Memory bound: (max_frames + 3) x width x height x 3 bytes (the buffer, one decoded frame in
// OpenCV's BGR and RGB, the result): 174 MB for 1920 x 1080 with max_frames = 25, 29 MB for
// 720 x 480.
typedef struct {
    int width, height;
    unsigned char *rgb; // (height, width, 3) owned (free()): the median
    long Nframes_read;  // frames decoded from all inputs
    int Nframes_used;   // frames the median was taken over
    int stride;         // every stride-th frame was used
    size_t bytes_bound; // the memory bound above for this size and max_frames
} rs_synth_median;

// out: *out (rs_synth_median_free)
// in:  inputs (Ninputs,): image files (one frame each) and/or videos (cv::VideoCapture);
//      max_frames in [3, 255]
// Returns RS_ERR_IO for an unreadable input, RS_ERR_INVALID when frame sizes differ (naming the
// input), RS_ERR_DEGENERATE when no frame was read, RS_ERR_NOMEM.
rs_status rs_synth_background_median( // out
    rs_synth_median *out,
    // in
    const char *const *inputs, int Ninputs, int max_frames, rs_err *err);
void rs_synth_median_free(rs_synth_median *m); // NULL-safe; zeroes *m
// The memory bound of rs_synth_background_median, bytes.
size_t rs_synth_median_bytes_bound(int width, int height, int max_frames);

// ---- tags and site.json ----

// The recognised conditions, NULL-terminated: "sunny", "cloudy", "rain", "snow", "night", "dusk"
// (issue 40; what each means for the vehicles: synth/backdrop/rs_synth_condition.h).
extern const char *const rs_synth_background_conditions[];

typedef struct {
    const char *name;          // file stem: [A-Za-z0-9_.-], not starting with '.', <= 100 chars
    const char *time_iso;      // ISO 8601 with zone, may be NULL
    const char *conditions;    // one of rs_synth_background_conditions, may be NULL
    bool synthetic;            // rendered, not photographed
    const char *const *keys;   // (Ntags,) further free tags (not "time"/"conditions"/"synthetic")
    const char *const *values; // (Ntags,)
    int Ntags;
} rs_synth_background_tags;

// Parses "key=value" into tags: "time" and "conditions" go to their fields (validated), other
// keys ([A-Za-z0-9_.-]+) to keys/values (pointing into `kv`'s storage; kv is modified: the '=' is
// replaced by NUL). The caller provides keys/values arrays with room for one more tag.
// Returns RS_ERR_USAGE naming the tag when it is malformed.
rs_status rs_synth_background_tag_parse(rs_synth_background_tags *tags,
                                        // in,out
                                        const char **keys, const char **values, char *kv, rs_err *err);
// Checks a name, a time and conditions (RS_ERR_USAGE / RS_ERR_PARSE naming the field).
rs_status rs_synth_background_tags_check(const rs_synth_background_tags *tags, rs_err *err);

// True if s can be a file or folder name here: 1..100 characters of [A-Za-z0-9_.-], not starting
// with '.' (camera ids used as folder names are checked with it too).
bool rs_synth_background_name_ok(const char *s);

// The path "SITE/backgrounds/<camera>/<name>.png" (malloc'ed, caller frees; NULL on no memory).
char *rs_synth_background_path(const char *site_dir, const char *camera_id, const char *name);

// Records a background in SITE/site.json through geo (rs_site_record_background,
// geo/rs_site_write.h): the camera's "background_images" gets (or has replaced, same name) the
// entry
//   {"name": ..., "file": "backgrounds/<camera>/<name>.png", "synthetic": bool,
//    "tags": {"time": ..., "conditions": ..., key: value ...}, "source": <source>}
// and site.json is rewritten atomically. The tags are taken as given (check them first with
// rs_synth_background_tags_check).
// in: source_json: how the image was made, a JSON object as text; may be NULL.
// Returns RS_ERR_IO / RS_ERR_PARSE for site.json, RS_ERR_NOT_FOUND for an unknown camera.
rs_status rs_synth_background_record(const char *site_dir, const char *camera_id, const rs_synth_background_tags *tags,
                                     const char *source_json, rs_err *err);

// `roadside background`: writes a temporal median as SITE/backgrounds/<id>/<name>.png (8-bit,
// atomically; the folder is created) and records it in site.json with its tags and its source
// (method "temporal median", the inputs, frames read and used, the stride).
// out: *path_out, the image's path (malloc'ed: caller frees; NULL on failure)
rs_status rs_synth_background_save_median(char **path_out, const char *site_dir, const char *camera_id,
                                          const rs_synth_background_tags *tags, const rs_synth_median *med,
                                          const char *const *inputs, int Ninputs, rs_err *err);

#ifdef __cplusplus
}
#endif
