// fuzz_site_json.c -- libFuzzer harness of the site reader: the input is the site.json (origin,
// heights, sigmas, ground plane, cameras and the files they name) of an otherwise valid
// one-camera site (tests/fuzz/site/), read by rs_site_check and rs_site_load and held to their
// contract (fuzz_site.h). Corpus: tests/fuzz/corpus/site_json/.
#include <stddef.h>
#include <stdint.h>

#include "fuzz_site.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) { return rs_fuzz_site_input(RS_SITE_JSON, data, size); }
