// fuzz_site.h -- what the site harnesses share (fuzz_site_json.c, fuzz_landmarks_geojson.c,
// fuzz_observations_csv.c): a per-process copy of the small valid site tests/fuzz/site/ (one
// camera cam1 with 14 landmarks and picks, cut from sites/demo; its model also as OpenCV YAML,
// cameras/cam1.opencv.yaml, for site.json inputs to name), in which one file is replaced by the
// fuzzer's input before the site is read through the public API (geo/rs_site.h).
//
// Each input is held to the reader's own contract, and a breach aborts (libFuzzer then saves the
// input as crash-*):
//   - rs_site_check returns RS_OK; the report's counts add up; every diagnostic names a file of
//     the site folder and says something; errors carry a status, warnings none;
//     rs_site_diag_format behaves like snprintf (the length it returns is the length it writes,
//     and a short buffer gets a prefix of the full line);
//   - rs_site_load succeeds exactly when the check found no error, and otherwise returns the
//     status of the first error the check listed (both promised by geo/rs_site.h);
//   - a loaded site holds finite ENU coordinates, positive sigmas, unique landmark ids,
//     observations of existing landmarks and cameras that pass rs_camera_check.
// Sanitizer reports (ASan, UBSan, LeakSanitizer) are libFuzzer's to catch.
#pragma once
#include <stddef.h>
#include <stdint.h>

#include "geo/rs_site.h" // the site's file names (RS_SITE_JSON, ...)

// Writes data[0, size) as the file `rel` (e.g. "site.json") of the per-process site folder,
// reads the site and checks it as above. The folder is made (mkdtemp under $TMPDIR, else /tmp)
// and filled on the first call, and removed at exit. Returns 0 (libFuzzer's "keep going").
int rs_fuzz_site_input(const char *rel, const uint8_t *data, size_t size);
