// rs_bench_site.h -- `roadside bench site`: reading and checking sites of N landmarks (issue 14:
// validation in O(N log N); 1,000,000 landmarks checked in seconds with bounded memory).
//
// Each site is written by geo's writer (geo/rs_site_write.h) into a folder of its own under
// work_dir (removed afterwards): N landmarks uniformly within 500 m of the origin and 10 m of
// height, one camera with four picks, and two planted defects the check must find -- the last
// landmark repeats the first one's id (an error) and the one before it sits at the second one's
// position (a warning). With picks > 0 the camera has that many picks of distinct landmarks
// instead, and `unknown` more rows naming ids no landmark has (each an error the check must
// report: issue 42, "site check is O(picks x landmarks)"). rs_site_check then runs in a child process, so that the peak resident
// memory measured is the check's own.
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int Nlandmarks;
    int Npicks, Nunknown; // the camera's picks (4 when none were asked for) and rows of unknown ids
    double file_mib;      // landmarks.geojson, MiB
    double write_s;       // writing the site (wall)
    double check_s;       // rs_site_check (wall, in the child)
    double check_cpu_s;   // its CPU time, user + sys
    double peak_mib;      // the child's peak resident set, MiB (reading, checking, the report)
    int Nerrors, Nwarnings;
    bool found; // exactly the two planted defects (and each unknown id) were reported, by id
} rs_bench_site_row;

// Fills *row for a site of Nlandmarks (>= 4) landmarks drawn with `seed`, with Npicks picks
// (0: four; at most Nlandmarks - 1: landmarks 0, 1, ... in order) and Nunknown rows of unknown ids. RS_ERR_IO when the site
// cannot be written or the child cannot run, RS_ERR_USAGE (too many picks), RS_ERR_NOMEM.
rs_status rs_bench_site_run(rs_bench_site_row *row, int Nlandmarks, int Npicks, int Nunknown, uint64_t seed,
                            const char *work_dir, rs_err *err);

#ifdef __cplusplus
}
#endif
