// fuzz_lanes.c -- libFuzzer harness of the lanes.geojson reader (rs_lanes_read, geo/rs_lanes.h):
// the input is written to a per-process temporary lanes.geojson (tests/fuzz/fuzz_scratch.h) and
// read against the one-camera fuzz site (tests/fuzz/site/, loaded once). Corpus:
// tests/fuzz/corpus/lanes/.
//
// Held to the header's contract, a breach aborting: lanes that read are at least one, each with
// an id, at least 2 finite points and every next index a lane of the file; a failed read leaves no
// lanes and says why.
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "fuzz_scratch.h"
#include "geo/rs_lanes.h"
#include "geo/rs_site.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void breach(const char *what, const char *detail) { fuzz_breach("fuzz_lanes", what, detail); }

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static rs_site *site;
    rs_err err = {0};
    if (!site && rs_site_load(&site, RS_FUZZ_SITE_DIR, &err) != RS_OK) breach("the fuzz site does not load", err.msg);
    const char *path = fuzz_scratch_write("fuzz_lanes", data, size, "lanes.geojson", "lanes.geojson");
    rs_lanes lanes = {0};
    const rs_status st = rs_lanes_read(&lanes, path, site, &err);
    if (st == RS_OK) {
        if (lanes.N < 1) breach("lanes that read are none", NULL);
        for (int i = 0; i < lanes.N; i++) {
            const rs_lane *l = &lanes.lane[i];
            if (!l->id) breach("a lane without an id", NULL);
            if (l->Npoints < 2) breach("a lane of fewer than 2 points", l->id);
            for (int k = 0; k < l->Npoints; k++)
                if (!isfinite(l->p_enu_m[k][0]) || !isfinite(l->p_enu_m[k][1])) breach("a point not finite", l->id);
            for (int k = 0; k < l->Nnext; k++)
                if (l->next[k] < 0 || l->next[k] >= lanes.N) breach("a next index outside the lanes", l->id);
        }
    } else {
        if (lanes.lane || lanes.N) breach("a failed read left lanes", NULL);
        if (!err.msg[0]) breach("a failed read without a message", NULL);
    }
    rs_lanes_free(&lanes);
    return 0;
}
