// test_solve_gen.h -- REFINE's own simulated roadside problems for the solver tests: a truth
// pose, landmarks on a gently uneven road (some on poles), their exact pixels through mrcal,
// pixel and survey noise, gross outliers. Deterministic from a seed.
#pragma once
#include "core/rs_rng.h"
#include <mrcal/mrcal.h>
#include <stdbool.h>
#include <stdint.h>

#include "calib/rs_calib.h"
#include "core/rs_camera.h"

#define GEN_MAXN 64

// ---- test bookkeeping shared by the REFINE tests ----
extern int gen_failures;
#define CHECK(cond, ...)                                           \
    do {                                                           \
        if (!(cond)) {                                             \
            gen_failures++;                                        \
            printf("FAIL %s:%d: %s: ", __FILE__, __LINE__, #cond); \
            printf(__VA_ARGS__);                                   \
            printf("\n");                                          \
        }                                                          \
    } while (0)
// The library never prints: gen_begin() sends stderr to a temporary file, gen_end() restores it,
// counts every line the library wrote there as a failure, prints the verdict (with `seeds`, a
// description of the seeds used) and returns the exit code.
void gen_begin(void);
int gen_end(const char *seeds);

// core/rs_rng.h's generator (xoshiro256**, seeded through splitmix64): trials seeded with
// consecutive numbers draw independent streams.
typedef struct {
    rs_rng r;
} gen_rng;
void gen_seed(gen_rng *g, uint64_t seed);
double gen_uniform(gen_rng *g, double a, double b);
double gen_normal(gen_rng *g);

typedef enum { GEN_PINHOLE, GEN_OPENCV8, GEN_CAHVOR } gen_lens;

typedef struct {
    mrcal_lensmodel_t lensmodel;
    int Nintrinsics;
    double intrinsics[16]; // truth
    int width, height;
    double rt_true[6];
    double position_true[3];
    int N;
    double p_true[GEN_MAXN * 3], p_survey[GEN_MAXN * 3], sigma_enu[GEN_MAXN * 3];
    double q_true[GEN_MAXN * 2], q_obs[GEN_MAXN * 2], sigma_px[GEN_MAXN];
    bool outlier[GEN_MAXN];
    double mean_range_m;
    rs_camera nominal; // set by gen_view: the camera the problem points to
} gen_problem;

// Fills g with N landmarks (<= GEN_MAXN) seen by a camera 6-15 m above a road some hundreds of
// metres from the ENU origin, pitched down 8-30 deg, ranges 12-150 m. sigma_px and sigma_m are
// the noise 1-sigmas (0: exact). Returns false if the scene could not be built.
bool gen_make(gen_problem *g, gen_rng *rng, gen_lens lens, int N, double sigma_px, double sigma_m);

// Replaces the pixels of the last Nout landmarks by gross mistakes, 200-500 px away.
void gen_add_outliers(gen_problem *g, gen_rng *rng, int Nout);
// The same with the pixel offset drawn from [lo_px, hi_px] instead of 200-500 px.
void gen_add_outliers_px(gen_problem *g, gen_rng *rng, int Nout, double lo_px, double hi_px);

// The size of landmark i's pick error (q_obs - q_true) in sigmas of the pick's whole noise at
// g's sigmas: its Mahalanobis length against sigma_px^2 I + J S J' (S the survey variances, J =
// dq/dp at the truth). NAN where the landmark does not project.
double gen_pick_sigmas(const gen_problem *g, int i);

// Appends Nout gross outliers (new landmarks 12-150 m away whose clicked pixel is 200-500 px off).
void gen_append_outliers(gen_problem *g, gen_rng *rng, int Nout, double sigma_m);

// A problem view of g (pointers into g; g->nominal is its camera, with intrinsics_nominal or,
// when NULL, the true intrinsics).
rs_calib_problem gen_view(gen_problem *g, const double *intrinsics_nominal);

// The camera of g (true lens and intrinsics) at pose rt (a view into g).
rs_camera gen_camera(const gen_problem *g, const double rt[6]);

// e^T C^-1 e for a (n,n) symmetric positive-definite C (Cholesky); NAN if not positive definite.
double gen_nees(const double *e, const double *C, int n);
