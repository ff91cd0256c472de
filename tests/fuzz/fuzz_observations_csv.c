// fuzz_observations_csv.c -- libFuzzer harness of the observations CSV reader: the input is
// observations/cam1.csv of an otherwise valid one-camera site (tests/fuzz/site/). The CSV reader
// is static inside geo/rs_site_read_camera.c, so it is reached through the site API:
// rs_site_check and rs_site_load, held to their contract (fuzz_site.h). Corpus:
// tests/fuzz/corpus/observations_csv/.
#include <stddef.h>
#include <stdint.h>

#include "fuzz_site.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return rs_fuzz_site_input(RS_SITE_OBSERVATIONS_DIR "/cam1" RS_SITE_OBSERVATIONS_EXT, data, size);
}
