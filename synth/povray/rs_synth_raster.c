// rs_synth_raster.c -- the object-ID and shadow passes rasterised (synth/povray/rs_synth_raster.h has
// the method).
#include "synth/povray/rs_synth_raster.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "synth/fleet/rs_synth_fleet.h"

#define NEAR_M 1e-6 // clipping plane, camera z, metres

// A value as the scene text writes it with `decimals` places and POV-Ray reads it back: the
// nearest double to the decimal (q / 10^d is correctly rounded, as strtod is;
// rs_synth_fleet_pov.c's fmt_fixed writes q = llround(x 10^d)).
static double as_written(double x, int decimals)
{
    const double scale = pow(10.0, decimals), y = x * scale;
    return fabs(y) < 9e18 ? (double)llround(y) / scale : 0.0;
}

// printf's "%.*f" read back (the placement is written with printf).
static double as_printed(double x, int decimals)
{
    char buf[64];
    snprintf(buf, sizeof buf, "%.*f", decimals, x);
    return strtod(buf, NULL);
}

// The canvas window [x0, x1] x [y0, y1] being filled: with a depth buffer and IDs (the ID pass),
// or one bit per light (the shadow pass: `bits`, no depth).
typedef struct {
    float *w;      // 1/z, 0 = empty
    uint16_t *id;  //
    uint8_t *bits; // when not NULL: the shadow pass
    uint16_t value;
    int x0, y0, x1, y1, stride;
} canvas_fill;

// A projected vertex: pixel (u, v) and w = 1/z.
typedef struct {
    double u, v, w;
} vert2;

// Fills the pixel centres inside triangle (a, b, c), edges inclusive: the ID where it is nearer
// than what is there, or the light's bit.
static void fill_triangle(canvas_fill *z, const vert2 *a, const vert2 *b, const vert2 *c)
{
    const double area = (b->u - a->u) * (c->v - a->v) - (b->v - a->v) * (c->u - a->u);
    if (!(fabs(area) > 0) || !isfinite(area)) return;
    const double umin = fmin(a->u, fmin(b->u, c->u)), umax = fmax(a->u, fmax(b->u, c->u));
    const double vmin = fmin(a->v, fmin(b->v, c->v)), vmax = fmax(a->v, fmax(b->v, c->v));
    const int i0 = (int)fmax(z->x0, ceil(umin)), i1 = (int)fmin(z->x1, floor(umax));
    const int j0 = (int)fmax(z->y0, ceil(vmin)), j1 = (int)fmin(z->y1, floor(vmax));
    if (i0 > i1 || j0 > j1) return;
    const double s = area > 0 ? 1.0 : -1.0, inv = 1.0 / area;
    // the edge functions e = K(j) - D (i - o), each the doubled area of the sub-triangle opposite
    // a vertex; inside where s e >= 0 for all three
    const vert2 *from[3] = {b, c, a}, *to[3] = {c, a, b};
    double D[3], o[3];
    for (int k = 0; k < 3; k++) D[k] = to[k]->v - from[k]->v, o[k] = from[k]->u;
    for (int j = j0; j <= j1; j++) {
        double K[3], lo = i0, hi = i1;
        for (int k = 0; k < 3; k++) { // the row's span, widened by a pixel: the test below decides
            K[k] = (to[k]->u - from[k]->u) * (j - from[k]->v);
            if (s * D[k] > 0)
                hi = fmin(hi, floor(o[k] + K[k] / D[k]) + 1);
            else if (s * D[k] < 0)
                lo = fmax(lo, ceil(o[k] + K[k] / D[k]) - 1);
            else if (s * K[k] < 0)
                hi = lo - 1;
        }
        for (int i = (int)lo; i <= (int)hi; i++) {
            const double ea = K[0] - D[0] * (i - o[0]), eb = K[1] - D[1] * (i - o[1]), ec = K[2] - D[2] * (i - o[2]);
            if (s * ea < 0 || s * eb < 0 || s * ec < 0) continue;
            const size_t k = (size_t)(j - z->y0) * (size_t)z->stride + (size_t)(i - z->x0);
            if (z->bits) {
                z->bits[k] |= (uint8_t)z->value;
                continue;
            }
            const float w = (float)((ea * a->w + eb * b->w + ec * c->w) * inv);
            if (w > z->w[k]) z->w[k] = w, z->id[k] = z->value;
        }
    }
}

// Clips a camera-frame triangle to z >= NEAR_M (Sutherland-Hodgman, one plane: at most 4
// vertices), projects it and fills it as a fan.
static void fill_3d(canvas_fill *z, const double fxycxy[4], const double p[3][3])
{
    double poly[4][3];
    int m = 0;
    for (int k = 0; k < 3; k++) {
        const double *a = p[k], *b = p[(k + 1) % 3];
        const bool ina = a[2] >= NEAR_M, inb = b[2] >= NEAR_M;
        if (ina) memcpy(poly[m++], a, sizeof poly[0]);
        if (ina != inb) {
            const double t = (NEAR_M - a[2]) / (b[2] - a[2]);
            for (int c = 0; c < 3; c++) poly[m][c] = a[c] + t * (b[c] - a[c]);
            poly[m++][2] = NEAR_M;
        }
    }
    if (m < 3) return;
    vert2 q[4];
    for (int k = 0; k < m; k++) {
        q[k].w = 1.0 / poly[k][2];
        q[k].u = fxycxy[0] * poly[k][0] * q[k].w + fxycxy[2];
        q[k].v = fxycxy[1] * poly[k][1] * q[k].w + fxycxy[3];
    }
    for (int k = 1; k + 1 < m; k++) fill_triangle(z, &q[0], &q[k], &q[k + 1]);
}

// Vehicle i's mesh vertices in ENU (*p_enu, grown to hold them; *cap its size), placed as the
// scene text places them: the vertex as written (POV-Ray <-y, z, x> of the vehicle frame, 1e-5
// m), rotated about the up axis by the yaw, translated. Returns the count, -1 without memory.
static int place_vertices(double (**p_enu)[3], int *cap, const rs_synth_prepared *vehicles, int i,
                          const double ground_normal_enu[3], double ground_offset_m)
{
    const rs_synth_vehicle *v = &vehicles->v[i];
    const rs_synth_mesh *m = &vehicles->meshes[vehicles->imesh[i]];
    if (m->Nv > *cap) {
        free(*p_enu);
        *cap = m->Nv;
        if (!(*p_enu = malloc((size_t)*cap * sizeof **p_enu))) return -1;
    }
    // rotate <0, yaw, 0> translate <e, up, n> (POV-Ray <e, u, n>)
    const double yaw = as_printed(v->yaw_deg, 9) * (M_PI / 180), sy = sin(yaw), cy = cos(yaw);
    const double e = as_printed(v->e_m, 6), n = as_printed(v->n_m, 6),
                 up = as_printed(rs_synth_ground_up_m(ground_normal_enu, ground_offset_m, v->e_m, v->n_m), 6);
    for (int k = 0; k < m->Nv; k++) {
        const double X = as_written(-m->v[k][1], 5), Y = as_written(m->v[k][2], 5), Z = as_written(m->v[k][0], 5);
        double *p = (*p_enu)[k];
        p[0] = X * cy + Z * sy + e, p[1] = -X * sy + Z * cy + n, p[2] = Y + up;
    }
    return m->Nv;
}

// The window clipped to the canvas; false when empty. Allocates the buffers the mode needs.
static rs_status fill_init(canvas_fill *z, int width, int height, const int region[4], bool shadow, rs_err *err)
{
    memset(z, 0, sizeof *z);
    z->x0 = region[0] < 0 ? 0 : region[0], z->y0 = region[1] < 0 ? 0 : region[1];
    z->x1 = region[2] >= width ? width - 1 : region[2], z->y1 = region[3] >= height ? height - 1 : region[3];
    if (z->x1 < z->x0 || z->y1 < z->y0) return RS_OK;
    z->stride = z->x1 - z->x0 + 1;
    const size_t n = (size_t)z->stride * (size_t)(z->y1 - z->y0 + 1);
    if (shadow)
        z->bits = calloc(n, 1);
    else
        z->w = calloc(n, sizeof *z->w), z->id = calloc(n, sizeof *z->id);
    if (shadow ? !z->bits : !z->w || !z->id) return rs_err_set(err, RS_ERR_NOMEM, "rasterising: out of memory");
    return RS_OK;
}

static void fill_free(canvas_fill *z) { free(z->w), free(z->id), free(z->bits); }

// p_cam = R p + t; in place safe.
static void to_cam(double p_cam[3], const double R[9], const double t[3], const double p_in[3])
{
    const double p[3] = {p_in[0], p_in[1], p_in[2]};
    for (int r = 0; r < 3; r++) p_cam[r] = R[3 * r] * p[0] + R[3 * r + 1] * p[1] + R[3 * r + 2] * p[2] + t[r];
}

// What the passes share: the camera, the lights (the shadow pass), the canvas being filled.
typedef struct {
    const double *fxycxy, *t; // (4,), (3,) the canvas pinhole, the pose's translation
    double R[9];              // the pose's rotation
    const rs_synth_light *lights;
    const double *weight; // (Nlights,) irradiance x cos on the ground; 0: below it
    int Nlights;
    const double *g; // (3,) ground normal, ENU
    double offset;   // ground offset: g . p = offset on the ground
    canvas_fill *z;
} pass;

// Vehicle i, its Nv vertices placed in ENU in p (scratch: may be overwritten), mesh m, filled.
typedef void (*fill_vehicle)(const pass *P, int i, double (*p)[3], int Nv, const rs_synth_mesh *m);

// Each included vehicle placed and given to fill. RS_ERR_NOMEM.
static rs_status fill_vehicles(const pass *P, const rs_synth_prepared *vehicles, const uint8_t *include,
                               fill_vehicle fill, rs_err *err)
{
    double(*p)[3] = NULL;
    int cap = 0;
    rs_status st = RS_OK;
    for (int i = 0; !st && i < vehicles->N; i++) {
        if (include && !include[i]) continue;
        const int Nv = place_vertices(&p, &cap, vehicles, i, P->g, P->offset);
        if (Nv < 0)
            st = rs_err_set(err, RS_ERR_NOMEM, "rasterising: out of memory");
        else
            fill(P, i, p, Nv, &vehicles->meshes[vehicles->imesh[i]]);
    }
    free(p);
    return st;
}

// The ID pass's vehicle: its triangles in the camera frame, nearest first.
static void fill_ids(const pass *P, int i, double (*p)[3], int Nv, const rs_synth_mesh *m)
{
    for (int k = 0; k < Nv; k++) to_cam(p[k], P->R, P->t, p[k]); // in place
    P->z->value = (uint16_t)(i + 1);
    for (int t = 0; t < m->Ntri; t++) {
        const int *f = m->tri[t];
        const double tri[3][3] = {{p[f[0]][0], p[f[0]][1], p[f[0]][2]},
                                  {p[f[1]][0], p[f[1]][1], p[f[1]][2]},
                                  {p[f[2]][0], p[f[2]][1], p[f[2]][2]}};
        fill_3d(P->z, P->fxycxy, tri);
    }
}

// The shadow pass's vehicle: for each light above the ground, each triangle projected onto the
// ground along the light (a vertex below it kept where it is), then into the camera.
static void fill_shadow(const pass *P, int i, double (*p)[3], int Nv, const rs_synth_mesh *m)
{
    (void)i, (void)Nv;
    const double *g = P->g;
    for (int j = 0; j < P->Nlights; j++) {
        if (!(P->weight[j] > 0)) continue;
        const double *d = P->lights[j].dir_enu, gd = g[0] * d[0] + g[1] * d[1] + g[2] * d[2];
        P->z->value = (uint16_t)(1u << j);
        for (int t = 0; t < m->Ntri; t++) {
            double tri[3][3];
            for (int k = 0; k < 3; k++) {
                const double *q = p[m->tri[t][k]];
                const double h = (g[0] * q[0] + g[1] * q[1] + g[2] * q[2] - P->offset) / gd;
                const double s = h > 0 ? h : 0, on[3] = {q[0] - s * d[0], q[1] - s * d[1], q[2] - s * d[2]};
                to_cam(tri[k], P->R, P->t, on);
            }
            fill_3d(P->z, P->fxycxy, tri);
        }
    }
}

rs_status rs_synth_raster_ids(rs_image *ids, const double fxycxy[4], int width, int height, const double rt_cam_enu[6],
                              const rs_synth_prepared *vehicles, const uint8_t *include,
                              const double ground_normal_enu[3], double ground_offset_m, const int region[4],
                              rs_err *err)
{
    memset(ids, 0, sizeof *ids);
    if (vehicles->N > 65534)
        return rs_err_set(err, RS_ERR_INVALID, "ID pass: %d vehicles (65,534 at most)", vehicles->N);
    rs_status st = rs_image_alloc(ids, width, height, 3, err);
    canvas_fill z;
    if (!st) st = fill_init(&z, width, height, region, false, err);
    if (st || !z.stride) {
        if (st) rs_image_free(ids);
        return st;
    }
    pass P = {.fxycxy = fxycxy, .t = &rt_cam_enu[3], .g = ground_normal_enu, .offset = ground_offset_m, .z = &z};
    mrcal_R_from_r(P.R, NULL, rt_cam_enu);
    st = fill_vehicles(&P, vehicles, include, fill_ids, err);
    for (int y = z.y0; !st && y <= z.y1; y++)
        for (int x = z.x0; x <= z.x1; x++) {
            const uint16_t id = z.id[(size_t)(y - z.y0) * (size_t)z.stride + (size_t)(x - z.x0)];
            float *px = &ids->data[((size_t)y * (size_t)width + (size_t)x) * 3];
            px[0] = (float)(id & 255u) / 255.0f;
            px[1] = (float)(id >> 8) / 255.0f;
        }
    fill_free(&z);
    if (st) rs_image_free(ids);
    return st;
}

rs_status rs_synth_raster_shadow(rs_image *frac, const double fxycxy[4], int width, int height,
                                 const double rt_cam_enu[6], const rs_synth_prepared *vehicles, const uint8_t *include,
                                 const double ground_normal_enu[3], double ground_offset_m,
                                 const rs_synth_light *lights, int Nlights, rs_err *err)
{
    memset(frac, 0, sizeof *frac);
    if (Nlights > 8) return rs_err_set(err, RS_ERR_INVALID, "shadow pass: %d lights (8 at most)", Nlights);
    const double *g = ground_normal_enu;
    const double gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    double weight[8] = {0}, unlit = 0;
    for (int j = 0; j < Nlights; j++) {
        const double *d = lights[j].dir_enu, c = (g[0] * d[0] + g[1] * d[1] + g[2] * d[2]) / gn;
        weight[j] = lights[j].irradiance * (c > 0 ? c : 0);
        unlit += weight[j];
    }
    rs_status st = rs_image_alloc(frac, width, height, 1, err);
    canvas_fill z;
    const int all[4] = {0, 0, width - 1, height - 1};
    if (!st) st = fill_init(&z, width, height, all, true, err);
    if (st) {
        rs_image_free(frac);
        return st;
    }
    pass P = {.fxycxy = fxycxy,
              .t = &rt_cam_enu[3],
              .lights = lights,
              .weight = weight,
              .Nlights = Nlights,
              .g = ground_normal_enu,
              .offset = ground_offset_m,
              .z = &z};
    mrcal_R_from_r(P.R, NULL, rt_cam_enu);
    st = fill_vehicles(&P, vehicles, include, fill_shadow, err);
    float of_bits[256]; // the lit fraction of each set of blocked lights
    for (unsigned b = 0; b < 256; b++) {
        double lit = 0;
        for (int j = 0; j < Nlights; j++)
            if (!(b >> j & 1u)) lit += weight[j];
        of_bits[b] = unlit > 0 ? (float)fmin(1.0, lit / unlit) : 1.0f;
    }
    for (size_t k = 0; !st && k < (size_t)width * (size_t)height; k++) frac->data[k] = of_bits[z.bits[k]];
    fill_free(&z);
    if (st) rs_image_free(frac);
    return st;
}
