// rs_simulate_shapes.c -- the poles and lines of a simulated site as landmarks (issue 13, item 4;
// sim/internal/rs_simulate_internal.h): candidates along the intersection's roads, the ones
// chosen so that each camera sees about o->poles_per_camera and o->lines_per_camera, their picks
// (a pole at its base, its top and along it; a line along it) and their survey. Everything is
// drawn from a stream of its own (SHAPES_STREAM). Calls rs_simulate_camera.c, geo
// (rs_geo_enu_to_llh) and core/.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sim/internal/rs_simulate_internal.h"

// The road layout of rs_simulate_intersection.c: 3.5 m lanes, two each way.
#define LANE_M         3.5
#define ROAD_HALF_M    (2 * LANE_M)
// Sampling of a segment or polyline for visibility: every SAMPLE_M along a line, POLE_SAMPLES
// along a pole. A line is visible when at least LINE_VISIBLE_M of it is in the image, a pole when
// a fifth of it is; picks land at least MARGIN_PX inside the image (as for points).
#define SAMPLE_M       0.25
#define LINE_VISIBLE_M 2.0
#define POLE_SAMPLES   50
#define MARGIN_PX      20.0
#define OUTLIER_MIN_PX 30.0
#define ALONG_PER_LINE 3
#define ALONG_PER_POLE 1
#define MAX_TRIES      100000

enum { MIN_CONSTRAINTS = 8 }; // what 4 points fix (geo's site check: 2 per point, 1 per along pick)

void rs_simulate__pole_id(char id[16], int i) { snprintf(id, 16, "P%03d", i + 1); }
void rs_simulate__line_id(char id[16], int i) { snprintf(id, 16, "LN%03d", i + 1); }

void rs_simulate__shapes_free(rs_simulate__site *s)
{
    for (int i = 0; i < s->Nshapes; i++) {
        free(s->shape[i].p_enu_m);
        free(s->shape[i].survey_enu_m);
        free(s->shape[i].survey_llh);
    }
    free(s->shape);
    free(s->shape_of);
    free(s->picks);
    s->shape = NULL, s->shape_of = NULL, s->picks = NULL;
    s->Nshapes = s->Npoles = s->Nlines = s->Npicks = 0;
}

// ---- candidates ----

// A new candidate with n vertices given in the road frame as (along, s) pairs of approach a
// (outward direction dirs[a], s to its left) or, with a < 0, as road-frame (x, y); up[i] the
// heights. Rotated into ENU, rounded to 0.1 mm.
static rs_simulate__shape *add_shape(rs_simulate__site *s, rs_site_shape shape, const char *kind, int n,
                                     const double (*xy)[2], const double *up)
{
    rs_simulate__shape *grown = realloc(s->shape, (size_t)(s->Nshapes + 1) * sizeof *grown);
    if (!grown) return NULL;
    s->shape = grown;
    rs_simulate__shape *c = &s->shape[s->Nshapes];
    *c = (rs_simulate__shape){.shape = shape, .kind = kind, .Nvertices = n};
    if (!(c->p_enu_m = malloc((size_t)n * 3 * sizeof *c->p_enu_m))) return NULL;
    s->Nshapes++;
    for (int i = 0; i < n; i++) {
        double *p = &c->p_enu_m[3 * i];
        p[0] = rs_simulate__quantize(s->R_road[0] * xy[i][0] + s->R_road[1] * xy[i][1], Q_ENU);
        p[1] = rs_simulate__quantize(s->R_road[2] * xy[i][0] + s->R_road[3] * xy[i][1], Q_ENU);
        p[2] = rs_simulate__quantize(up[i], Q_ENU);
        if (i > 0)
            c->length_m += sqrt((p[0] - p[-3]) * (p[0] - p[-3]) + (p[1] - p[-2]) * (p[1] - p[-2]) +
                                (p[2] - p[-1]) * (p[2] - p[-1]));
    }
    c->height_m = shape == RS_SITE_POLE ? c->p_enu_m[5] - c->p_enu_m[2] : 0;
    return c;
}

// Road-frame (x, y) of (along, s) on approach a.
static void road_xy(double xy[2], int a, double along, double s)
{
    static const double dirs[4][2] = {{1, 0}, {0, 1}, {-1, 0}, {0, -1}};
    xy[0] = along * dirs[a][0] - s * dirs[a][1];
    xy[1] = along * dirs[a][1] + s * dirs[a][0];
}

static bool add_pole(rs_simulate__site *s, int a, double along, double side, double height_m, const char *kind)
{
    double xy[2][2];
    road_xy(xy[0], a, along, side);
    road_xy(xy[1], a, along, side);
    const double up[2] = {0, height_m};
    return add_shape(s, RS_SITE_POLE, kind, 2, (const double(*)[2])xy, up) != NULL;
}

// A straight line from along0 to along1 at s on approach a, a vertex every `step` metres.
static bool add_straight(rs_simulate__site *s, int a, double along0, double along1, double side, double step,
                         const char *kind)
{
    const int n = 1 + (int)ceil(fabs(along1 - along0) / step - 1e-9);
    double xy[64][2], up[64] = {0};
    if (n > 64) return false;
    for (int i = 0; i < n; i++) road_xy(xy[i], a, along0 + (along1 - along0) * i / (n - 1), side);
    return add_shape(s, RS_SITE_LINE, kind, n, (const double(*)[2])xy, up) != NULL;
}

// Every pole and line of the intersection, in the road frame of rs_simulate_intersection.c.
static rs_status build_shapes(rs_simulate__site *s, rs_rng *rng, rs_err *err)
{
    bool ok = true;
    for (int a = 0; a < 4 && ok; a++) // poles: delineators on both verges, lamp and sign posts
        for (int k = 0; k < 5 && ok; k++)
            for (int side = -1; side <= 1 && ok; side += 2)
                ok = add_pole(s, a, 16.0 + 10.0 * k, side * (ROAD_HALF_M + 1.0), rs_rng_uniform_in(rng, 1.0, 1.2),
                              "delineator_post");
    for (int a = 0; a < 4 && ok; a++) {
        ok = add_pole(s, a, 20.0, ROAD_HALF_M + 2.5, rs_rng_uniform_in(rng, 6.0, 10.0), "lamp_post") &&
             add_pole(s, a, 40.0, ROAD_HALF_M + 2.5, rs_rng_uniform_in(rng, 6.0, 10.0), "lamp_post") &&
             add_pole(s, a, 30.0, -ROAD_HALF_M - 2.5, rs_rng_uniform_in(rng, 3.0, 4.5), "sign_post");
    }
    for (int a = 0; a < 4 && ok; a++) { // lines: the stop bar's centre across the inbound lanes,
        double bar[2][2];               // the centre line and the two edge lines
        const double up[2] = {0, 0};
        road_xy(bar[0], a, 13.25, 0.2);
        road_xy(bar[1], a, 13.25, ROAD_HALF_M - 0.2);
        ok = add_shape(s, RS_SITE_LINE, "stop_bar", 2, (const double(*)[2])bar, up) &&
             add_straight(s, a, 14.0, 58.0, 0.0, 4.0, "centre_line") &&
             add_straight(s, a, 14.0, 58.0, ROAD_HALF_M - 0.1, 4.0, "edge_line") &&
             add_straight(s, a, 14.0, 58.0, -ROAD_HALF_M + 0.1, 4.0, "edge_line");
    }
    // kerbs round the four corners: the kerb of approach a's left verge (s = +7), an arc of 5 m
    // radius, the kerb of the next approach's right verge, a vertex every 6 m on the straight runs
    for (int a = 0; a < 4 && ok; a++) {
        double xy[32][2], up[32] = {0};
        int n = 0;
        for (double along = 55.0; along > 12.0 + 1e-9; along -= 6.0) road_xy(xy[n++], a, along, ROAD_HALF_M);
        double c[2], e[2];
        road_xy(c, a, ROAD_HALF_M + 5.0, ROAD_HALF_M + 5.0);
        road_xy(e, a, 1.0, 0.0);           // unit outward direction of approach a
        const double l[2] = {-e[1], e[0]}; // its left
        for (int k = 0; k <= 8; k++) {     // from (along 12, s 7) to the next approach's kerb
            const double t = M_PI / 2 * k / 8;
            xy[n][0] = c[0] - 5.0 * (sin(t) * e[0] + cos(t) * l[0]);
            xy[n][1] = c[1] - 5.0 * (sin(t) * e[1] + cos(t) * l[1]);
            n++;
        }
        for (double along = 18.0; along < 56.0; along += 6.0) road_xy(xy[n++], (a + 1) % 4, along, -ROAD_HALF_M);
        ok = add_shape(s, RS_SITE_LINE, "kerb", n, (const double(*)[2])xy, up) != NULL;
    }
    return ok ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "poles and lines: out of memory");
}

// ---- visibility and picks ----

// The point at arc length t_m along candidate c.
static void point_at(double p[3], const rs_simulate__shape *c, double t_m)
{
    for (int i = 1; i < c->Nvertices; i++) {
        const double *a = &c->p_enu_m[3 * (i - 1)], *b = a + 3;
        const double L =
            sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) + (b[2] - a[2]) * (b[2] - a[2]));
        if (t_m <= L || i == c->Nvertices - 1) {
            const double f = L > 0 ? fmin(fmax(t_m / L, 0.0), 1.0) : 0.0;
            for (int k = 0; k < 3; k++) p[k] = a[k] + f * (b[k] - a[k]);
            return;
        }
        t_m -= L;
    }
    memcpy(p, c->p_enu_m, 3 * sizeof *p);
}

// True when enough of candidate c is in camera cam's image to be picked along.
static bool shape_visible(const rs_simulate__camera *cam, const rs_simulate__shape *c)
{
    const int n = c->shape == RS_SITE_POLE ? POLE_SAMPLES : 1 + (int)(c->length_m / SAMPLE_M);
    const int need = c->shape == RS_SITE_POLE ? POLE_SAMPLES / 5 : (int)(LINE_VISIBLE_M / SAMPLE_M);
    int seen = 0;
    for (int i = 0; i < n && seen < need; i++) {
        double p[3], q[2];
        point_at(p, c, c->length_m * i / (n > 1 ? n - 1 : 1));
        seen += rs_simulate__camera_sees(cam, q, p, MARGIN_PX);
    }
    return seen >= need;
}

static bool add_pick(rs_simulate__site *s, rs_rng *rng, const rs_simulate_site_options *o, int k, int landmark,
                     int ishape, rs_site_at at, const double p[3], const double q_true[2])
{
    rs_simulate__pick *grown = realloc(s->picks, (size_t)(s->Npicks + 1) * sizeof *grown);
    if (!grown) return false;
    s->picks = grown;
    rs_simulate__pick *pk = &s->picks[s->Npicks++];
    *pk = (rs_simulate__pick){.cam = k, .landmark = landmark, .shape = ishape, .at = at};
    memcpy(pk->p_true_enu_m, p, sizeof pk->p_true_enu_m);
    memcpy(pk->q_true_px, q_true, sizeof pk->q_true_px);
    rs_simulate__camera_pick(rng, pk->q_px, &pk->outlier, pk->q_true_px, 1, &s->cam[k], o->pixel_sigma_px,
                             o->outlier_fraction, OUTLIER_MIN_PX);
    return true;
}

// An along pick of candidate c by camera k: a uniformly random point of the part of it in the
// image (by rejection: c is visible, so at least a fifth of a pole or 2 m of a line is).
static bool pick_along(rs_simulate__site *s, rs_rng *rng, const rs_simulate_site_options *o, int k, int landmark,
                       int ishape)
{
    const rs_simulate__shape *c = &s->shape[ishape];
    for (int tries = 0; tries < MAX_TRIES; tries++) {
        double p[3], q[2];
        point_at(p, c, rs_rng_uniform_in(rng, 0.0, c->length_m));
        if (rs_simulate__camera_sees(&s->cam[k], q, p, MARGIN_PX))
            return add_pick(s, rng, o, k, landmark, ishape, RS_SITE_AT_ALONG, p, q);
    }
    return true; // cannot happen for a visible candidate; no pick then
}

// Chooses candidates of one shape so that each camera sees about `per_camera` of them; visible
// (Ncameras, Nshapes) as computed.
static void choose(rs_simulate__site *s, rs_rng *rng, const bool *visible, rs_site_shape shape, int per_camera,
                   int *pool)
{
    for (int k = 0; k < s->Ncameras; k++) {
        int have = 0, n = 0;
        for (int j = 0; j < s->Nshapes; j++) {
            if (s->shape[j].shape != shape || !visible[(size_t)k * s->Nshapes + j]) continue;
            if (s->shape[j].chosen)
                have++;
            else
                pool[n++] = j;
        }
        for (int i = n - 1; i > 0; i--) { // Fisher-Yates
            const int j = (int)(rs_rng_u64(rng) % (uint64_t)(i + 1)), t = pool[i];
            pool[i] = pool[j], pool[j] = t;
        }
        for (int i = 0; i < n && have < per_camera; i++, have++) s->shape[pool[i]].chosen = true;
    }
}

rs_status rs_simulate__shapes_draw(rs_simulate__site *s, const rs_simulate_site_options *o, rs_err *err)
{
    if (o->poles_per_camera == 0 && o->lines_per_camera == 0) return RS_OK;
    rs_rng rng;
    rs_rng_seed(&rng, rs_rng_seed_derive(o->seed, SHAPES_STREAM));
    rs_status st = build_shapes(s, &rng, err);
    if (st) return st;
    const int K = s->Ncameras, N = s->Nshapes;
    bool *visible = calloc((size_t)K * N, sizeof *visible);
    int *pool = malloc((size_t)N * sizeof *pool);
    s->shape_of = malloc((size_t)N * sizeof *s->shape_of);
    if (!visible || !pool || !s->shape_of) {
        st = rs_err_set(err, RS_ERR_NOMEM, "poles and lines: out of memory");
        goto done;
    }
    for (int k = 0; k < K; k++)
        for (int j = 0; j < N; j++) visible[(size_t)k * N + j] = shape_visible(&s->cam[k], &s->shape[j]);
    choose(s, &rng, visible, RS_SITE_POLE, o->poles_per_camera, pool);
    choose(s, &rng, visible, RS_SITE_LINE, o->lines_per_camera, pool);
    for (int pass = 0; pass < 2; pass++) // poles first, then lines, each in candidate order
        for (int j = 0; j < N; j++)
            if (s->shape[j].chosen && (s->shape[j].shape == RS_SITE_POLE) == (pass == 0)) {
                s->shape_of[s->Npoles + s->Nlines] = j;
                *(pass == 0 ? &s->Npoles : &s->Nlines) += 1;
            }

    // picks: by camera, then landmark; a pole at its base and top where they are in the image,
    // and along it; a line along it
    for (int k = 0; k < K; k++)
        for (int i = 0; i < s->Npoles + s->Nlines; i++) {
            const int j = s->shape_of[i], landmark = s->Nlandmarks + i;
            const rs_simulate__shape *c = &s->shape[j];
            if (!visible[(size_t)k * N + j]) continue;
            bool ok = true;
            if (c->shape == RS_SITE_POLE) {
                for (int v = 0; v < 2 && ok; v++) {
                    double q[2];
                    if (rs_simulate__camera_sees(&s->cam[k], q, &c->p_enu_m[3 * v], MARGIN_PX))
                        ok = add_pick(s, &rng, o, k, landmark, j, v ? RS_SITE_AT_TOP : RS_SITE_AT_BASE,
                                      &c->p_enu_m[3 * v], q);
                }
            }
            const int nalong = c->shape == RS_SITE_POLE ? ALONG_PER_POLE : ALONG_PER_LINE;
            for (int m = 0; m < nalong && ok; m++) ok = pick_along(s, &rng, o, k, landmark, j);
            if (!ok) {
                st = rs_err_set(err, RS_ERR_NOMEM, "poles and lines: out of memory");
                goto done;
            }
        }

    // the survey: a pole's base and height, a line's vertices, with the noise of points (and
    // the extra height noise of the ground, from a stream of its own)
    rs_rng hrng;
    rs_rng_seed(&hrng, rs_rng_seed_derive(o->seed, HEIGHT_NOISE_STREAM + 1));
    for (int i = 0; i < s->Npoles + s->Nlines; i++) {
        rs_simulate__shape *c = &s->shape[s->shape_of[i]];
        const int n = c->shape == RS_SITE_POLE ? 1 : c->Nvertices;
        c->survey_enu_m = malloc((size_t)n * 3 * sizeof *c->survey_enu_m);
        c->survey_llh = malloc((size_t)n * 3 * sizeof *c->survey_llh);
        if (!c->survey_enu_m || !c->survey_llh) {
            st = rs_err_set(err, RS_ERR_NOMEM, "poles and lines: out of memory");
            goto done;
        }
        rs_simulate__survey_noise(&rng, c->survey_enu_m, c->p_enu_m, n, o->survey_sigma_h_m, o->survey_sigma_v_m);
        if (o->height_noise_m > 0)
            for (int v = 0; v < n; v++) c->survey_enu_m[3 * v + 2] += o->height_noise_m * rs_rng_normal(&hrng);
        c->survey_height_m = c->height_m + (c->shape == RS_SITE_POLE ? o->survey_sigma_v_m * rs_rng_normal(&rng) : 0);
        if (c->shape == RS_SITE_POLE && !(c->survey_height_m > 0.01)) c->survey_height_m = 0.01; // a pole stays one
        if ((st = rs_geo_enu_to_llh(c->survey_llh, &o->origin, c->survey_enu_m, n, err))) goto done;
    }

    // enough picks for each camera: as many numbers fixed as 4 points fix
    for (int k = 0; k < K; k++) {
        int fixed = 0;
        for (int j = 0; j < s->cand.N; j++)
            fixed += 2 * (s->landmark_of[j] >= 0 && s->visible[(size_t)k * s->cand.N + j]);
        for (int i = 0; i < s->Npicks; i++)
            fixed += s->picks[i].cam == k ? (s->picks[i].at == RS_SITE_AT_ALONG ? 1 : 2) : 0;
        if (fixed < MIN_CONSTRAINTS) {
            st = rs_err_set(err, RS_ERR_DEGENERATE,
                            "camera %d: its picks of points, poles and lines fix %d numbers, it needs %d (ask for "
                            "more --poles, --lines or --points)",
                            k + 1, fixed, MIN_CONSTRAINTS);
            goto done;
        }
    }
done:
    free(visible);
    free(pool);
    return st;
}
