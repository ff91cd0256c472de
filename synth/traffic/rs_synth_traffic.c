// rs_synth_traffic.c -- lanes, built-in traffic, domain randomisation, the vehicles file.
// See rs_synth_traffic.h and docs/traffic.md.
#include "synth/traffic/rs_synth_traffic.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "core/rs_rng.h"
#include "core/rs_units.h"
#include "synth/fleet/rs_synth_fleet.h"

// ---------------------------------------------------------------------------------------------
// classes

double rs_synth_class_max_speed_mps(rs_synth_class cls)
{
    return cls == RS_SYNTH_BICYCLE ? RS_SYNTH_BICYCLE_MAX_SPEED_MPS : INFINITY;
}

// ---------------------------------------------------------------------------------------------
// built-in traffic

void rs_synth_traffic_options_default(rs_synth_traffic_options *opt)
{
    memset(opt, 0, sizeof *opt);
    rs_synth_class_mix_default(&opt->mix);
    opt->s0_m = 2.0;
    opt->headway_s = 1.5;
    opt->headway_jitter = 0.5;
    opt->speed_fraction[0] = 0.0;
    opt->speed_fraction[1] = 1.0;
}

static double uniform(rs_rng *rng, double lo, double hi) { return lo + (hi - lo) * rs_rng_uniform(rng); }

static rs_status traffic_options_check(const rs_synth_traffic_options *o, rs_err *err)
{
    double total = 0;
    for (int k = 0; k < RS_SYNTH_NCLASSES; k++) {
        if (!(o->mix.weight[k] >= 0) || !isfinite(o->mix.weight[k]))
            return rs_err_set(err, RS_ERR_INVALID, "mix: weight of %s must be a number >= 0",
                              rs_synth_class_name((rs_synth_class)k));
        total += o->mix.weight[k];
    }
    if (!(total > 0)) return rs_err_set(err, RS_ERR_INVALID, "mix: all weights are 0");
    if (o->count < 0) return rs_err_set(err, RS_ERR_INVALID, "count: %d is negative", o->count);
    if (!(o->s0_m >= 0 && o->s0_m < 100)) return rs_err_set(err, RS_ERR_INVALID, "s0_m: must be in [0, 100) m");
    if (!(o->headway_s >= 0 && o->headway_s < 100))
        return rs_err_set(err, RS_ERR_INVALID, "headway_s: must be in [0, 100) s");
    if (!(o->headway_jitter >= 0 && o->headway_jitter <= 1))
        return rs_err_set(err, RS_ERR_INVALID, "headway_jitter: must be in [0, 1]");
    if (!(o->speed_fraction[0] >= 0 && o->speed_fraction[1] >= o->speed_fraction[0] && o->speed_fraction[1] <= 2))
        return rs_err_set(err, RS_ERR_INVALID, "speed_fraction: need 0 <= a <= b <= 2");
    return RS_OK;
}

rs_status rs_synth_traffic_place(rs_synth_vehicle **vehicles, int *N, const rs_lanes *lanes,
                                 const rs_synth_traffic_options *opt, rs_err *err)
{
    *vehicles = NULL;
    *N = 0;
    rs_status st = traffic_options_check(opt, err);
    if (st) return st;
    rs_rng rng;
    rs_rng_seed(&rng, opt->seed);
    rs_synth_vehicle *v = NULL;
    int n = 0, cap = 0;
    for (int i = 0; i < lanes->N; i++) {
        const rs_lane *lane = &lanes->lane[i];
        // Each lane draws from its own stream, so that one lane's vehicles do not depend on the
        // lanes before it.
        rs_rng lr;
        rs_rng_seed(&lr, rs_rng_u64(&rng));
        if (!opt->junction_lanes && lane->kind && !strcmp(lane->kind, "junction")) continue;
        double L = rs_lane_length_m(lane);
        double vmax = isfinite(lane->speed_mps) ? lane->speed_mps : 13.89;
        bool reverse = lane->direction == RS_LANE_BOTH && rs_rng_uniform(&lr) < 0.5;
        // Downstream end of the free road before the first vehicle: a gap as if a leader stood
        // just beyond the lane's end.
        double front = L; // arc length of the next vehicle's front bumper, in travel direction
        bool first = true;
        for (;;) {
            rs_synth_vehicle x = rs_synth_vehicle_init(rs_synth_class_mix_draw(&opt->mix, rs_rng_uniform(&lr)));
            rs_synth_class_range r;
            rs_synth_class_range_get(&r, x.cls, NULL); // a class of the mix: always valid
            x.length_m = uniform(&lr, r.length_m[0], r.length_m[1]);
            x.width_m = uniform(&lr, r.width_m[0], r.width_m[1]);
            x.height_m = uniform(&lr, r.height_m[0], r.height_m[1]);
            // a bicycle rides at its own speed, whatever the lane's limit (SUMO's bicycle default)
            x.speed_mps = fmin(vmax, rs_synth_class_max_speed_mps(x.cls)) *
                          uniform(&lr, opt->speed_fraction[0], opt->speed_fraction[1]);
            x.variant = rs_rng_u64(&lr) >> 11; // 53 bits: exact as a JSON number
            double gap = opt->s0_m + x.speed_mps * opt->headway_s *
                                         uniform(&lr, 1.0 - opt->headway_jitter, 1.0 + opt->headway_jitter);
            if (first) gap *= rs_rng_uniform(&lr); // the lane's end is no leader
            first = false;
            front -= gap;
            double rear = front - x.length_m;
            if (rear < 0) break;
            double s_centre = 0.5 * (front + rear), p[2], h;
            // In travel direction; a reversed "both" lane runs from its last vertex.
            rs_lane_point(p, &h, lane, reverse ? L - s_centre : s_centre);
            x.e_m = p[0];
            x.n_m = p[1];
            x.yaw_deg = reverse ? fmod(h + 180.0, 360.0) : h;
            x.lane = i;
            front = rear;
            if (n == cap) {
                int c2 = cap ? 2 * cap : 64;
                rs_synth_vehicle *g = realloc(v, sizeof *g * (size_t)c2);
                if (!g) {
                    free(v);
                    return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
                }
                v = g;
                cap = c2;
            }
            v[n++] = x;
        }
    }
    // A uniformly drawn subset of `count` (selection sampling keeps the order).
    if (opt->count > 0 && n > opt->count) {
        int kept = 0;
        for (int i = 0; i < n && kept < opt->count; i++)
            if (rs_rng_uniform(&rng) * (n - i) < opt->count - kept) v[kept++] = v[i];
        n = kept;
    }
    for (int i = 0; i < n; i++) snprintf(v[i].id, sizeof v[i].id, "v%d", i + 1);
    *vehicles = v;
    *N = n;
    return RS_OK;
}

// ---------------------------------------------------------------------------------------------
// domain randomisation

void rs_synth_randomise_options_default(rs_synth_randomise_options *opt)
{
    opt->seed = 0;
    opt->sigma_along_m = sqrt(0.5);
    opt->sigma_across_m = sqrt(0.5);
    opt->yaw_range_deg = 5.0;
    opt->tries = 20;
}

// Footprint corners (4, 2) in ENU, counter-clockwise seen from above.
static void footprint(double c[4][2], const rs_synth_vehicle *v)
{
    double f[2] = {sin(v->yaw_deg * RS_RAD_PER_DEG), cos(v->yaw_deg * RS_RAD_PER_DEG)}, l[2] = {-f[1], f[0]};
    static const double sx[4] = {1, -1, -1, 1}, sy[4] = {-1, -1, 1, 1};
    for (int k = 0; k < 4; k++)
        for (int a = 0; a < 2; a++)
            c[k][a] = (a ? v->n_m : v->e_m) + sx[k] * 0.5 * v->length_m * f[a] + sy[k] * 0.5 * v->width_m * l[a];
}

bool rs_synth_footprints_overlap(const rs_synth_vehicle *a, const rs_synth_vehicle *b)
{
    double ca[4][2], cb[4][2];
    footprint(ca, a);
    footprint(cb, b);
    const double(*rect[2])[2] = {ca, cb};
    // Separating axis theorem: two convex polygons are disjoint iff their projections onto one
    // of their edge normals are disjoint. A rectangle has two distinct edge normals.
    for (int r = 0; r < 2; r++)
        for (int e = 0; e < 2; e++) {
            const double *p = rect[r][e], *q = rect[r][e + 1];
            double ax = -(q[1] - p[1]), ay = q[0] - p[0];
            double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
            for (int s = 0; s < 2; s++)
                for (int k = 0; k < 4; k++) {
                    double t = rect[s][k][0] * ax + rect[s][k][1] * ay;
                    lo[s] = fmin(lo[s], t);
                    hi[s] = fmax(hi[s], t);
                }
            if (hi[0] <= lo[1] || hi[1] <= lo[0]) return false;
        }
    return true;
}

rs_status rs_synth_traffic_randomise(rs_synth_vehicle *vehicles, int *N, const rs_synth_randomise_options *opt,
                                     rs_err *err)
{
    if (!(opt->sigma_along_m >= 0 && opt->sigma_across_m >= 0 && opt->yaw_range_deg >= 0 && opt->yaw_range_deg <= 180 &&
          isfinite(opt->sigma_along_m) && isfinite(opt->sigma_across_m)))
        return rs_err_set(err, RS_ERR_INVALID, "randomisation: sigmas must be >= 0 and the yaw range in [0, 180]");
    if (opt->tries < 1) return rs_err_set(err, RS_ERR_INVALID, "randomisation: tries must be >= 1");
    rs_rng rng;
    rs_rng_seed(&rng, opt->seed);
    int kept = 0;
    for (int i = 0; i < *N; i++) {
        const rs_synth_vehicle x0 = vehicles[i];
        double f[2] = {sin(x0.yaw_deg * RS_RAD_PER_DEG), cos(x0.yaw_deg * RS_RAD_PER_DEG)};
        bool ok = false;
        rs_synth_vehicle x = x0;
        for (int t = 0; t < opt->tries && !ok; t++) {
            double da = opt->sigma_along_m * rs_rng_normal(&rng);
            double dc = opt->sigma_across_m * rs_rng_normal(&rng); // to the left
            double dy = uniform(&rng, -opt->yaw_range_deg, opt->yaw_range_deg);
            x = x0;
            x.e_m += da * f[0] - dc * f[1];
            x.n_m += da * f[1] + dc * f[0];
            x.yaw_deg = fmod(x0.yaw_deg + dy + 360.0, 360.0);
            ok = true;
            for (int j = 0; j < kept && ok; j++) ok = !rs_synth_footprints_overlap(&x, &vehicles[j]);
        }
        if (ok) vehicles[kept++] = x;
    }
    *N = kept;
    return RS_OK;
}

// ---------------------------------------------------------------------------------------------
// output

static double round_to(double x, double q) { return round(x / q) * q + 0.0; }

rs_status rs_synth_traffic_write_json(const char *path, const rs_synth_vehicle *vehicles, int N, rs_err *err)
{
    cJSON *j = cJSON_CreateArray();
    if (!j) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; i < N; i++) {
        const rs_synth_vehicle *v = &vehicles[i];
        const char *name = v->cls < RS_SYNTH_NCLASSES ? rs_synth_class_name(v->cls) : NULL;
        if (!name) {
            cJSON_Delete(j);
            return rs_err_set(err, RS_ERR_INVALID, "vehicle %d: unknown class %d", i, (int)v->cls);
        }
        cJSON *o = cJSON_CreateObject();
        cJSON_AddItemToArray(j, o);
        cJSON_AddStringToObject(o, "id", v->id);
        cJSON_AddStringToObject(o, "class", name);
        cJSON_AddNumberToObject(o, "e", round_to(v->e_m, 1e-4));
        cJSON_AddNumberToObject(o, "n", round_to(v->n_m, 1e-4));
        cJSON_AddNumberToObject(o, "yaw_deg", round_to(v->yaw_deg, 1e-4));
        cJSON_AddNumberToObject(o, "length", round_to(v->length_m, 1e-4));
        cJSON_AddNumberToObject(o, "width", round_to(v->width_m, 1e-4));
        cJSON_AddNumberToObject(o, "height", round_to(v->height_m, 1e-4));
        cJSON_AddNumberToObject(o, "variant", (double)v->variant);
        cJSON_AddNumberToObject(o, "speed_mps", round_to(v->speed_mps, 1e-4));
    }
    char *text = cJSON_Print(j);
    cJSON_Delete(j);
    if (!text) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    size_t n = strlen(text);
    text[n] = '\n';
    rs_status st = rs_io_write_file(path, text, n + 1, err);
    free(text);
    return st;
}
