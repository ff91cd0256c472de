// rs_site_json.h -- how geo's writers put a JSON document on disk (rs_site_write.c), shared with
// lanes.geojson's writer (rs_lanes.c). Not installed, not for other modules.
#pragma once
#include <cjson/cJSON.h>

#include "core/rs_status.h"
#include "geo/rs_site_write.h"

// Writes `root` to `path` atomically (rs_io_write_file) in `layout` (geo/rs_site_write.h), with
// a final newline. RS_ERR_NOMEM, RS_ERR_IO.
rs_status rs_site__write_json(const char *path, const cJSON *root, rs_site_layout layout, rs_err *err);

// Adds a number, or fails (false) on a non-finite one (cJSON would write null) or no memory.
bool rs_site__add_number(cJSON *obj, const char *key, double x);

// [x[0], ..., x[n-1]] (owned by the caller), or NULL for a non-finite value or no memory.
cJSON *rs_site__numbers(const double *x, int n);
