// rs_synth_ids.c -- the object-ID pass rasterised (synth/rs_synth_ids.h has the method).
#include "synth/rs_synth_ids.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mrcal/poseutils.h>

#include "synth/rs_synth_fleet.h"

#define NEAR_M 1e-6 // clipping plane, camera z, metres

// A value as the scene text writes it with `decimals` places and POV-Ray reads it back: the
// nearest double to the decimal (q / 10^d is correctly rounded, as strtod is; rs_synth_fleet_pov.c's
// fmt_fixed writes q = llround(x 10^d)).
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

// The canvas: the depth (1/z, 0 = empty) and the ID of each pixel of the region.
typedef struct {
    float *w;
    uint16_t *id;
    int x0, y0, x1, y1, stride;
} zbuffer;

// A projected vertex: pixel (u, v) and w = 1/z.
typedef struct {
    double u, v, w;
} vert2;

// Fills the pixel centres inside triangle (a, b, c), edges inclusive, where it is nearer than what
// is there.
static void fill_triangle(zbuffer *z, const vert2 *a, const vert2 *b, const vert2 *c, uint16_t id)
{
    const double area = (b->u - a->u) * (c->v - a->v) - (b->v - a->v) * (c->u - a->u);
    if (!(fabs(area) > 0) || !isfinite(area)) return;
    const double umin = fmin(a->u, fmin(b->u, c->u)), umax = fmax(a->u, fmax(b->u, c->u));
    const double vmin = fmin(a->v, fmin(b->v, c->v)), vmax = fmax(a->v, fmax(b->v, c->v));
    const int i0 = (int)fmax(z->x0, ceil(umin)), i1 = (int)fmin(z->x1, floor(umax));
    const int j0 = (int)fmax(z->y0, ceil(vmin)), j1 = (int)fmin(z->y1, floor(vmax));
    if (i0 > i1 || j0 > j1) return;
    const double s = area > 0 ? 1.0 : -1.0, inv = 1.0 / area;
    for (int j = j0; j <= j1; j++)
        for (int i = i0; i <= i1; i++) {
            // the edge functions, each the doubled area of the sub-triangle opposite a vertex
            const double ea = (c->u - b->u) * (j - b->v) - (c->v - b->v) * (i - b->u);
            const double eb = (a->u - c->u) * (j - c->v) - (a->v - c->v) * (i - c->u);
            const double ec = (b->u - a->u) * (j - a->v) - (b->v - a->v) * (i - a->u);
            if (s * ea < 0 || s * eb < 0 || s * ec < 0) continue;
            const float w = (float)((ea * a->w + eb * b->w + ec * c->w) * inv);
            const size_t k = (size_t)(j - z->y0) * (size_t)z->stride + (size_t)(i - z->x0);
            if (w > z->w[k]) z->w[k] = w, z->id[k] = id;
        }
}

// Clips a camera-frame triangle to z >= NEAR_M (Sutherland-Hodgman, one plane: at most 4
// vertices), projects it and fills it as a fan.
static void fill_3d(zbuffer *z, const double fxycxy[4], const double p[3][3], uint16_t id)
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
    for (int k = 1; k + 1 < m; k++) fill_triangle(z, &q[0], &q[k], &q[k + 1], id);
}

rs_status rs_synth_ids_raster(rs_image *ids, const double fxycxy[4], int width, int height, const double rt_cam_enu[6],
                              const rs_synth_prepared *vehicles, const uint8_t *include,
                              const double ground_normal_enu[3], double ground_offset_m, const int region[4],
                              rs_err *err)
{
    memset(ids, 0, sizeof *ids);
    if (vehicles->N > 65534)
        return rs_err_set(err, RS_ERR_INVALID, "ID pass: %d vehicles (65,534 at most)", vehicles->N);
    rs_status st = rs_image_alloc(ids, width, height, 3, err);
    if (st) return st;
    zbuffer z = {NULL,
                 NULL,
                 region[0] < 0 ? 0 : region[0],
                 region[1] < 0 ? 0 : region[1],
                 region[2] >= width ? width - 1 : region[2],
                 region[3] >= height ? height - 1 : region[3],
                 0};
    if (z.x1 < z.x0 || z.y1 < z.y0) return RS_OK;
    z.stride = z.x1 - z.x0 + 1;
    const size_t n = (size_t)z.stride * (size_t)(z.y1 - z.y0 + 1);
    z.w = calloc(n, sizeof *z.w);
    z.id = calloc(n, sizeof *z.id);
    double(*pc)[3] = NULL;
    int cap = 0;
    if (!z.w || !z.id) st = rs_err_set(err, RS_ERR_NOMEM, "ID pass: out of memory");
    double R[9];
    mrcal_R_from_r(R, NULL, rt_cam_enu);
    for (int i = 0; !st && i < vehicles->N; i++) {
        if (include && !include[i]) continue;
        const rs_synth_vehicle *v = &vehicles->v[i];
        const rs_synth_mesh *m = &vehicles->meshes[vehicles->imesh[i]];
        if (m->Nv > cap) {
            free(pc);
            cap = m->Nv;
            if (!(pc = malloc((size_t)cap * sizeof *pc))) {
                st = rs_err_set(err, RS_ERR_NOMEM, "ID pass: out of memory");
                break;
            }
        }
        // the placement as written: rotate <0, yaw, 0> translate <e, up, n> (POV-Ray <e, u, n>)
        const double yaw = as_printed(v->yaw_deg, 9) * (M_PI / 180), sy = sin(yaw), cy = cos(yaw);
        const double e = as_printed(v->e_m, 6), nn = as_printed(v->n_m, 6),
                     up = as_printed(rs_synth_ground_up_m(ground_normal_enu, ground_offset_m, v->e_m, v->n_m), 6);
        for (int k = 0; k < m->Nv; k++) {
            // the vertex as written (POV-Ray <-y, z, x> of the vehicle frame, 1e-5 m), placed
            const double X = as_written(-m->v[k][1], 5), Y = as_written(m->v[k][2], 5), Z = as_written(m->v[k][0], 5);
            const double p_enu[3] = {X * cy + Z * sy + e, -X * sy + Z * cy + nn, Y + up};
            for (int r = 0; r < 3; r++)
                pc[k][r] = R[3 * r] * p_enu[0] + R[3 * r + 1] * p_enu[1] + R[3 * r + 2] * p_enu[2] + rt_cam_enu[3 + r];
        }
        const uint16_t id = (uint16_t)(i + 1);
        for (int t = 0; t < m->Ntri; t++) {
            const double p[3][3] = {{pc[m->tri[t][0]][0], pc[m->tri[t][0]][1], pc[m->tri[t][0]][2]},
                                    {pc[m->tri[t][1]][0], pc[m->tri[t][1]][1], pc[m->tri[t][1]][2]},
                                    {pc[m->tri[t][2]][0], pc[m->tri[t][2]][1], pc[m->tri[t][2]][2]}};
            fill_3d(&z, fxycxy, p, id);
        }
    }
    for (int y = z.y0; !st && y <= z.y1; y++)
        for (int x = z.x0; x <= z.x1; x++) {
            const uint16_t id = z.id[(size_t)(y - z.y0) * (size_t)z.stride + (size_t)(x - z.x0)];
            float *px = &ids->data[((size_t)y * (size_t)width + (size_t)x) * 3];
            px[0] = (float)(id & 255u) / 255.0f;
            px[1] = (float)(id >> 8) / 255.0f;
        }
    free(pc);
    free(z.w);
    free(z.id);
    if (st) rs_image_free(ids);
    return st;
}
