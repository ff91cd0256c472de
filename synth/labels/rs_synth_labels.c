// rs_synth_labels.c -- per-vehicle labels through mrcal's projection, and the COCO / YOLO /
// KITTI writers. docs/labels.md defines the fields; rs_synth_labels.h states the method.
#include "synth/labels/rs_synth_labels.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>
#include <mrcal/mrcal.h>

#include "core/rs_io.h"
#include "core/rs_lens.h"
#include "geo/rs_geo.h"

#define EDGE_SAMPLES 64
#define MAXPOLY      16
#define MAXPLANES    5

// ---------------------------------------------------------------- geometry

// Half-spaces n . p >= d in the camera frame that a point must satisfy to be projected.
typedef struct {
    double n[MAXPLANES][3], d[MAXPLANES];
    int N;
} clip_planes;

typedef struct {
    const rs_camera *cam;
    clip_planes planes;
    double max_theta; // a lens that sees behind (rs_lens_sees_behind): no planes; a point is
                      // projected when it lies RS_SYNTH_LABEL_ZMIN_M or more from the camera and
                      // at most max_theta off the axis (else 0: the planes decide)
} projector;

// A fisheye's field for the labels: the largest angle off the axis of the image's border and of a
// grid every 16 pixels, plus 5 degrees (at most 180; 180 when a pixel has no direction: the
// lens's circle lies inside the image). Beyond it a distortion polynomial may fold points back
// into the image, where the render (which samples the lens's directions) never puts them.
static rs_status fisheye_field(projector *pr, const rs_camera *cam, rs_err *err)
{
    const int S = 16, Nx = (cam->width - 1) / S + 2, Ny = (cam->height - 1) / S + 2, N = Nx * Ny;
    mrcal_point2_t *q = malloc((size_t)N * sizeof(*q));
    mrcal_point3_t *v = malloc((size_t)N * sizeof(*v));
    rs_status st = q && v ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "labels: out of memory");
    for (int j = 0; !st && j < Ny; j++)
        for (int i = 0; i < Nx; i++)
            q[j * Nx + i] =
                (mrcal_point2_t){.x = fmin(i * S - 0.5, cam->width - 0.5), .y = fmin(j * S - 0.5, cam->height - 0.5)};
    if (!st && !rs_lens_unproject(v, q, N, &cam->lensmodel, cam->intrinsics))
        st = rs_err_set(err, RS_ERR_EXTERNAL, "labels: the lens cannot unproject its image");
    double theta = 0;
    for (int k = 0; !st && k < N; k++) {
        const double t = atan2(hypot(v[k].x, v[k].y), v[k].z);
        theta = isfinite(t) ? fmax(theta, t) : M_PI;
    }
    pr->max_theta = fmin(M_PI, theta + 5 * M_PI / 180);
    free(q), free(v);
    return st;
}

// True when the camera-frame point p may be projected (the planes aside): always for a lens
// that does not see behind (the planes clip it), else within the fisheye's field.
static bool projectable(const projector *pr, const double p[3])
{
    if (!(pr->max_theta > 0)) return true;
    const double s = hypot(p[0], p[1]);
    return hypot(s, p[2]) >= RS_SYNTH_LABEL_ZMIN_M && atan2(s, p[2]) <= pr->max_theta;
}

static rs_status projector_init(projector *pr, const rs_camera *cam, rs_err *err)
{
    pr->cam = cam;
    pr->max_theta = 0;
    clip_planes *c = &pr->planes;
    if (rs_lens_sees_behind(&cam->lensmodel)) { // z <= 0 may be in view: no planes
        c->N = 0;
        return fisheye_field(pr, cam, err);
    }
    c->N = 1;
    c->n[0][0] = c->n[0][1] = 0, c->n[0][2] = 1, c->d[0] = RS_SYNTH_LABEL_ZMIN_M;
    if (cam->lensmodel.type == MRCAL_LENSMODEL_PINHOLE) return RS_OK;
    // The frustum through the image border, widened by 25 % of its extent on every side.
    enum { S = 32 };
    mrcal_point2_t q[4 * S];
    mrcal_point3_t v[4 * S];
    double W = cam->width, H = cam->height;
    for (int k = 0; k < S; k++) {
        double f = (double)k / S;
        q[k] = (mrcal_point2_t){.x = -0.5 + f * W, .y = -0.5};
        q[S + k] = (mrcal_point2_t){.x = W - 0.5, .y = -0.5 + f * H};
        q[2 * S + k] = (mrcal_point2_t){.x = W - 0.5 - f * W, .y = H - 0.5};
        q[3 * S + k] = (mrcal_point2_t){.x = -0.5, .y = H - 0.5 - f * H};
    }
    if (!rs_lens_unproject(v, q, 4 * S, &cam->lensmodel, cam->intrinsics))
        return rs_err_set(err, RS_ERR_EXTERNAL, "labels: mrcal_unproject of the image border failed");
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int i = 0; i < 4 * S; i++) {
        if (!(v[i].z > 0)) return RS_OK; // wider than a hemisphere: z >= ZMIN only
        for (int k = 0; k < 2; k++) {
            double a = v[i].xyz[k] / v[i].z;
            lo[k] = fmin(lo[k], a);
            hi[k] = fmax(hi[k], a);
        }
    }
    for (int k = 0; k < 2; k++) {
        double m = 0.25 * (hi[k] - lo[k]);
        // x >= (lo - m) z  and  x <= (hi + m) z  (k = 0; y for k = 1)
        double *n1 = c->n[c->N], *n2 = c->n[c->N + 1];
        n1[0] = n1[1] = n1[2] = n2[0] = n2[1] = n2[2] = 0;
        n1[k] = 1, n1[2] = -(lo[k] - m);
        n2[k] = -1, n2[2] = hi[k] + m;
        c->d[c->N] = c->d[c->N + 1] = 0;
        c->N += 2;
    }
    return RS_OK;
}

// Sutherland-Hodgman: clips the polygon p (n points, camera frame) to every plane. Returns the
// new count (0 when nothing is left).
static int clip_polygon(double out[MAXPOLY][3], const double in[][3], int n, const clip_planes *c)
{
    double a[MAXPOLY][3], b[MAXPOLY][3];
    memcpy(a, in, (size_t)n * sizeof a[0]);
    for (int j = 0; j < c->N && n > 0; j++) {
        int m = 0;
        for (int i = 0; i < n; i++) {
            const double *p = a[i], *q = a[(i + 1) % n];
            double sp = c->n[j][0] * p[0] + c->n[j][1] * p[1] + c->n[j][2] * p[2] - c->d[j];
            double sq = c->n[j][0] * q[0] + c->n[j][1] * q[1] + c->n[j][2] * q[2] - c->d[j];
            if (sp >= 0 && m < MAXPOLY) memcpy(b[m++], p, sizeof b[0]);
            if ((sp >= 0) != (sq >= 0) && m < MAXPOLY) {
                double t = sp / (sp - sq);
                for (int k = 0; k < 3; k++) b[m][k] = p[k] + t * (q[k] - p[k]);
                m++;
            }
        }
        n = m;
        memcpy(a, b, (size_t)n * sizeof a[0]);
    }
    memcpy(out, a, (size_t)n * sizeof a[0]);
    return n;
}

static void box_empty(double b[4])
{
    b[0] = b[1] = INFINITY;
    b[2] = b[3] = -INFINITY;
}

static int box_valid(const double b[4]) { return b[0] <= b[2] && b[1] <= b[3]; }

static void box_nan(double b[4]) { b[0] = b[1] = b[2] = b[3] = NAN; }

// Grows `box` by the projection of the polygon's edges sampled densely (after clipping).
static rs_status grow_by_polygon(double box[4], const projector *pr, const double poly[][3], int n, rs_err *err)
{
    double c[MAXPOLY][3];
    int m = clip_polygon(c, poly, n, &pr->planes);
    if (m == 0) return RS_OK;
    mrcal_point3_t p[MAXPOLY * EDGE_SAMPLES] = {0};
    mrcal_point2_t q[MAXPOLY * EDGE_SAMPLES];
    int N = 0;
    for (int i = 0; i < m; i++)
        for (int s = 0; s < EDGE_SAMPLES; s++) {
            double t = (double)s / EDGE_SAMPLES;
            for (int k = 0; k < 3; k++) p[N].xyz[k] = c[i][k] + t * (c[(i + 1) % m][k] - c[i][k]);
            if (projectable(pr, p[N].xyz)) N++;
        }
    if (!rs_lens_project(q, NULL, NULL, p, N, &pr->cam->lensmodel, pr->cam->intrinsics))
        return rs_err_set(err, RS_ERR_EXTERNAL, "labels: mrcal_project failed");
    for (int i = 0; i < N; i++) {
        if (!isfinite(q[i].x) || !isfinite(q[i].y)) continue;
        box[0] = fmin(box[0], q[i].x);
        box[1] = fmin(box[1], q[i].y);
        box[2] = fmax(box[2], q[i].x);
        box[3] = fmax(box[3], q[i].y);
    }
    return RS_OK;
}

static void to_cam(double p_cam[3], const rs_camera *cam, const rs_synth_vehicle *v, double up_m, const double p_v[3])
{
    double p_enu[3];
    rs_synth_vehicle_to_enu(p_enu, v, up_m, p_v);
    mrcal_transform_point_rt(p_cam, NULL, NULL, cam->rt_cam_enu, p_enu);
}

static double box_area(const double b[4]) { return box_valid(b) ? (b[2] - b[0]) * (b[3] - b[1]) : 0; }

// Intersection with the image [-0.5, W-0.5] x [-0.5, H-0.5]; NaN when empty.
static void clip_to_image(double out[4], const double b[4], int W, int H)
{
    double c[4] = {fmax(b[0], -0.5), fmax(b[1], -0.5), fmin(b[2], W - 0.5), fmin(b[3], H - 0.5)};
    if (box_valid(b) && c[0] < c[2] && c[1] < c[3])
        memcpy(out, c, sizeof c);
    else
        box_nan(out);
}

// ---------------------------------------------------------------- rasterising (full_px)

// A mask over the pixel window [x0, x1] x [y0, y1] (inclusive, inside the image).
typedef struct {
    uint8_t *mask; // (y1 - y0 + 1, x1 - x0 + 1)
    int x0, y0, x1, y1;
} raster;

// Marks the pixel centres inside the 2D triangle (inclusive edges).
static void raster_triangle(raster *r, const double a[2], const double b[2], const double c[2])
{
    double area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    if (!isfinite(area) || area == 0) return;
    double s = area > 0 ? 1 : -1;
    int i0 = (int)fmax(r->x0, ceil(fmin(a[0], fmin(b[0], c[0])))),
        i1 = (int)fmin(r->x1, floor(fmax(a[0], fmax(b[0], c[0]))));
    int j0 = (int)fmax(r->y0, ceil(fmin(a[1], fmin(b[1], c[1])))),
        j1 = (int)fmin(r->y1, floor(fmax(a[1], fmax(b[1], c[1]))));
    const double *P[3] = {a, b, c};
    for (int j = j0; j <= j1; j++)
        for (int i = i0; i <= i1; i++) {
            int inside = 1;
            for (int e = 0; e < 3 && inside; e++) {
                const double *p = P[e], *q = P[(e + 1) % 3];
                double w = (q[0] - p[0]) * (j - p[1]) - (q[1] - p[1]) * (i - p[0]);
                inside = s * w >= 0;
            }
            if (inside) r->mask[(size_t)(j - r->y0) * (r->x1 - r->x0 + 1) + (i - r->x0)] = 1;
        }
}

// Clips a 3D triangle (camera frame), projects the polygon and rasterises it as a fan.
static rs_status raster_triangle3(raster *r, const projector *pr, const double tri[3][3], rs_err *err)
{
    double c[MAXPOLY][3];
    int m = clip_polygon(c, tri, 3, &pr->planes);
    if (m < 3) return RS_OK;
    mrcal_point3_t p[MAXPOLY];
    mrcal_point2_t q[MAXPOLY];
    for (int i = 0; i < m; i++) {
        memcpy(p[i].xyz, c[i], sizeof c[i]);
        if (!projectable(pr, c[i])) return RS_OK; // out of a fisheye's field: not in the image
    }
    if (!rs_lens_project(q, NULL, NULL, p, m, &pr->cam->lensmodel, pr->cam->intrinsics))
        return rs_err_set(err, RS_ERR_EXTERNAL, "labels: mrcal_project failed");
    for (int i = 1; i + 1 < m; i++) raster_triangle(r, q[0].xy, q[i].xy, q[i + 1].xy);
    return RS_OK;
}

static const int box_faces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};

// Pixels the vehicle covers alone: its mesh's triangles (or the box's faces) rasterised at
// pixel centres, each triangle with straight edges between its projected corners, within its
// body box (in the image) plus a 2 px margin for the chords of a distorting lens.
static rs_status full_pixels(long *count, const projector *pr, const rs_synth_vehicle *v, double up_m,
                             const rs_synth_mesh *mesh, const double corners[8][3], const double body_box_px[4],
                             rs_err *err)
{
    raster r = {NULL, (int)fmax(0, floor(body_box_px[0]) - 2), (int)fmax(0, floor(body_box_px[1]) - 2),
                (int)fmin(pr->cam->width - 1, ceil(body_box_px[2]) + 2),
                (int)fmin(pr->cam->height - 1, ceil(body_box_px[3]) + 2)};
    size_t size = (size_t)(r.x1 - r.x0 + 1) * (size_t)(r.y1 - r.y0 + 1);
    r.mask = calloc(size, 1);
    if (!r.mask) return rs_err_set(err, RS_ERR_NOMEM, "labels: out of memory");
    rs_status st = RS_OK;
    if (mesh && mesh->Ntri > 0) {
        double(*pc)[3] = malloc((size_t)mesh->Nv * sizeof *pc);
        if (!pc) st = rs_err_set(err, RS_ERR_NOMEM, "labels: out of memory");
        for (int i = 0; i < mesh->Nv && !st; i++) to_cam(pc[i], pr->cam, v, up_m, mesh->v[i]);
        for (int t = 0; t < mesh->Ntri && !st; t++) {
            double tri[3][3];
            for (int k = 0; k < 3; k++) memcpy(tri[k], pc[mesh->tri[t][k]], sizeof tri[k]);
            st = raster_triangle3(&r, pr, tri, err);
        }
        free(pc);
    } else
        for (int f = 0; f < 6 && !st; f++)
            for (int k = 1; k <= 2 && !st; k++) {
                double tri[3][3];
                memcpy(tri[0], corners[box_faces[f][0]], sizeof tri[0]);
                memcpy(tri[1], corners[box_faces[f][k]], sizeof tri[1]);
                memcpy(tri[2], corners[box_faces[f][k + 1]], sizeof tri[2]);
                st = raster_triangle3(&r, pr, tri, err);
            }
    long n = 0;
    for (size_t i = 0; i < size; i++) n += r.mask[i];
    free(r.mask);
    *count = n;
    return st;
}

// ---------------------------------------------------------------- labels

static rs_status label_one(rs_synth_label *L, const projector *pr, const rs_synth_vehicle *v, int k, double up_m,
                           const rs_synth_mesh *mesh, int with_ids, rs_err *err)
{
    const rs_camera *cam = pr->cam;
    double Lm = v->length_m, Wm = v->width_m, Hm = v->height_m;
    if (!(Lm > 0 && Wm > 0 && Hm > 0 && isfinite(Lm + Wm + Hm) && isfinite(up_m) && isfinite(v->e_m) &&
          isfinite(v->n_m) && isfinite(v->yaw_deg)))
        return rs_err_set(err, RS_ERR_INVALID,
                          "vehicle %d: dimensions, position, yaw or ground height not resolved or "
                          "not finite",
                          k);
    memset(L, 0, sizeof *L);
    L->index = k;
    L->cls = rs_synth_vehicle_label_class(v);
    double c_v[3] = {0, 0, Hm / 2};
    rs_synth_vehicle_to_enu(L->center_enu_m, v, up_m, c_v);
    L->dims_m[0] = Lm, L->dims_m[1] = Wm, L->dims_m[2] = Hm;
    L->yaw_deg = v->yaw_deg;
    double corners[8][3];
    for (int c = 0; c < 8; c++) {
        double p_v[3] = {c & 1 ? Lm / 2 : -Lm / 2, c & 2 ? Wm / 2 : -Wm / 2, c & 4 ? Hm : 0};
        to_cam(corners[c], cam, v, up_m, p_v);
        L->corners_px[c][0] = L->corners_px[c][1] = NAN;
        if (pr->max_theta > 0 ? projectable(pr, corners[c]) : corners[c][2] >= RS_SYNTH_LABEL_ZMIN_M) {
            mrcal_point2_t q;
            mrcal_point3_t p = {{corners[c][0], corners[c][1], corners[c][2]}};
            if (!rs_lens_project(&q, NULL, NULL, &p, 1, &cam->lensmodel, cam->intrinsics))
                return rs_err_set(err, RS_ERR_EXTERNAL, "vehicle %d: mrcal_project failed", k);
            L->corners_px[c][0] = q.x, L->corners_px[c][1] = q.y;
        }
    }
    // Body: the 6 faces; footprint: the bottom face (corners 0 2 3 1).
    rs_status st = RS_OK;
    box_empty(L->body_box_full_px);
    for (int f = 0; f < 6 && !st; f++) {
        double poly[4][3];
        for (int i = 0; i < 4; i++) memcpy(poly[i], corners[box_faces[f][i]], sizeof poly[i]);
        st = grow_by_polygon(L->body_box_full_px, pr, poly, 4, err);
    }
    box_empty(L->footprint_box_full_px);
    double fp[4][3]; // the bottom face, corners 0 2 3 1
    for (int i = 0; i < 4; i++) memcpy(fp[i], corners[(const int[]){0, 2, 3, 1}[i]], sizeof fp[i]);
    if (!st) st = grow_by_polygon(L->footprint_box_full_px, pr, (const double(*)[3])fp, 4, err);
    if (st) return st;
    if (!box_valid(L->body_box_full_px)) box_nan(L->body_box_full_px);
    if (!box_valid(L->footprint_box_full_px)) box_nan(L->footprint_box_full_px);
    clip_to_image(L->body_box_px, L->body_box_full_px, cam->width, cam->height);
    clip_to_image(L->footprint_box_px, L->footprint_box_full_px, cam->width, cam->height);
    L->in_image = box_valid(L->body_box_px);
    double full = box_area(L->body_box_full_px);
    L->truncation = L->in_image && full > 0 ? 1 - box_area(L->body_box_px) / full : 1;
    if (L->truncation < 0) L->truncation = 0;
    L->footprint_center_px[0] = 0.5 * (L->footprint_box_full_px[0] + L->footprint_box_full_px[2]);
    L->footprint_center_px[1] = 0.5 * (L->footprint_box_full_px[1] + L->footprint_box_full_px[3]);
    double o[3] = {0, 0, 0}, fwd[3] = {1, 0, 0}, f_cam[3];
    to_cam(L->bottom_center_cam_m, cam, v, up_m, o);
    rs_synth_vehicle_to_enu(L->bottom_center_enu_m, v, up_m, o);
    L->bottom_center_llh[0] = L->bottom_center_llh[1] = L->bottom_center_llh[2] = NAN;
    to_cam(f_cam, cam, v, up_m, fwd);
    for (int i = 0; i < 3; i++) f_cam[i] -= L->bottom_center_cam_m[i];
    L->rotation_y_rad = atan2(-f_cam[2], f_cam[0]);
    memcpy(L->forward_cam, f_cam, sizeof f_cam);
    L->bottom_center_px[0] = L->bottom_center_px[1] = NAN;
    if (pr->max_theta > 0 ? projectable(pr, L->bottom_center_cam_m)
                          : L->bottom_center_cam_m[2] >= RS_SYNTH_LABEL_ZMIN_M) {
        mrcal_point3_t p;
        mrcal_point2_t q;
        memcpy(p.xyz, L->bottom_center_cam_m, sizeof p.xyz);
        if (!rs_lens_project(&q, NULL, NULL, &p, 1, &cam->lensmodel, cam->intrinsics))
            return rs_err_set(err, RS_ERR_EXTERNAL, "vehicle %d: mrcal_project failed", k);
        L->bottom_center_px[0] = q.x, L->bottom_center_px[1] = q.y;
    }
    L->visible_px = L->full_px = -1;
    L->visibility = NAN;
    box_nan(L->visible_box_px);
    if (with_ids && L->in_image) return full_pixels(&L->full_px, pr, v, up_m, mesh, corners, L->body_box_px, err);
    if (with_ids) L->full_px = 0;
    return RS_OK;
}

rs_status rs_synth_labels_compute(rs_synth_label **labels, const rs_synth_label_input *in, rs_err *err)
{
    const rs_camera *cam = in->cam;
    const rs_synth_vehicle *vehicles = in->vehicles;
    const double *up_m = in->up_m;
    const int Nvehicles = in->Nvehicles;
    const rs_synth_mesh *meshes = in->meshes;
    const uint16_t *id_image = in->id_image;
    *labels = NULL;
    if (Nvehicles < 0 || (Nvehicles > 0 && (!vehicles || !up_m)) || cam->width <= 0 || cam->height <= 0)
        return rs_err_set(err, RS_ERR_INVALID, "labels: bad vehicle count, arrays or image size");
    projector pr;
    rs_status st = projector_init(&pr, cam, err);
    if (st) return st;
    rs_synth_label *out = calloc((size_t)(Nvehicles > 0 ? Nvehicles : 1), sizeof *out);
    if (!out) return rs_err_set(err, RS_ERR_NOMEM, "labels: out of memory");
    for (int k = 0; k < Nvehicles && !st; k++)
        st = label_one(&out[k], &pr, &vehicles[k], k, up_m[k], meshes ? &meshes[k] : NULL, id_image != NULL, err);
    if (!st && id_image) {
        for (int k = 0; k < Nvehicles; k++) {
            out[k].visible_px = 0;
            box_empty(out[k].visible_box_px);
        }
        for (int j = 0; j < cam->height && !st; j++)
            for (int i = 0; i < cam->width; i++) {
                unsigned id = id_image[(size_t)j * cam->width + i];
                if (id == 0) continue;
                if ((int)id > Nvehicles) {
                    st = rs_err_set(err, RS_ERR_INVALID, "ID image: pixel (%d, %d) holds %u, but there are %d vehicles",
                                    i, j, id, Nvehicles);
                    break;
                }
                rs_synth_label *L = &out[id - 1];
                L->visible_px++;
                L->visible_box_px[0] = fmin(L->visible_box_px[0], i - 0.5);
                L->visible_box_px[1] = fmin(L->visible_box_px[1], j - 0.5);
                L->visible_box_px[2] = fmax(L->visible_box_px[2], i + 0.5);
                L->visible_box_px[3] = fmax(L->visible_box_px[3], j + 0.5);
            }
        for (int k = 0; k < Nvehicles; k++) {
            rs_synth_label *L = &out[k];
            if (!box_valid(L->visible_box_px)) box_nan(L->visible_box_px);
            L->visibility = L->full_px > 0 ? fmin(1.0, (double)L->visible_px / L->full_px) : 0;
        }
    }
    for (int k = 0; k < Nvehicles && !st && in->origin; k++) // latitude, longitude of each bottom centre
        st = rs_geo_enu_to_llh(out[k].bottom_center_llh, in->origin, out[k].bottom_center_enu_m, 1, err);
    if (st) {
        free(out);
        return st;
    }
    *labels = out;
    return RS_OK;
}

// ---------------------------------------------------------------- writers

// The kinds' names (rs_synth_bbox_kind order) and what each box is, for the files' metadata.
static const char *const kind_names[] = {"footprint", "body", "visible"};
static const char *const kind_meanings[] = {
    "the ground footprint: the image box of the vehicle's rectangle on the ground (the bottom face of its 3D "
    "box), the bottom-centre convention of roadside detection; NOT the box around the whole vehicle",
    "the whole vehicle, amodal: the image box of its 3D box, occluded parts included, clipped to the image",
    "the vehicle's visible pixels: the box of its pixels in the object-ID pass"};

const char *rs_synth_bbox_kind_name(rs_synth_bbox_kind kind)
{
    return (unsigned)kind < 3 ? kind_names[kind] : "unknown";
}

const char *rs_synth_bbox_kind_meaning(rs_synth_bbox_kind kind)
{
    return (unsigned)kind < 3 ? kind_meanings[kind] : "unknown";
}

rs_status rs_synth_bbox_kind_parse(rs_synth_bbox_kind *kind, const char *name, rs_err *err)
{
    const char *const *names = kind_names;
    for (int i = 0; i < 3; i++)
        if (name && strcmp(name, names[i]) == 0) {
            *kind = (rs_synth_bbox_kind)i;
            return RS_OK;
        }
    return rs_err_set(err, RS_ERR_USAGE, "--bbox: '%s' is not footprint, body or visible", name ? name : "");
}

int rs_synth_label_kept(double box[4], const rs_synth_label *L, const rs_synth_label_options *opt)
{
    rs_synth_label_options def = {RS_SYNTH_BBOX_FOOTPRINT, 0, false};
    if (!opt) opt = &def;
    const double *b = opt->bbox == RS_SYNTH_BBOX_BODY      ? L->body_box_px
                      : opt->bbox == RS_SYNTH_BBOX_VISIBLE ? L->visible_box_px
                                                           : L->footprint_box_px;
    memcpy(box, b, 4 * sizeof *b);
    if (!L->in_image || !(box[2] > box[0] && box[3] > box[1])) return 0;
    if (opt->min_visibility > 0 && isfinite(L->visibility) && L->visibility < opt->min_visibility) return 0;
    if (L->visible_px == 0 && opt->drop_invisible) return 0; // (-1: no ID pass, unknown)
    return 1;
}

static int valid_split(const char *s)
{
    if (!s || !*s || strlen(s) > 64) return 0;
    for (; *s; s++)
        if (!((*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') || (*s >= '0' && *s <= '9') || *s == '_' ||
              *s == '-'))
            return 0;
    return 1;
}

// cJSON array of n doubles (NaN -> null).
static cJSON *numbers(const double *x, int n)
{
    cJSON *a = cJSON_CreateArray();
    for (int i = 0; a && i < n; i++)
        cJSON_AddItemToArray(a, isfinite(x[i]) ? cJSON_CreateNumber(x[i]) : cJSON_CreateNull());
    return a;
}

static cJSON *xywh(const double b[4])
{
    double w[4] = {b[0], b[1], b[2] - b[0], b[3] - b[1]};
    return box_valid(b) ? numbers(w, 4) : cJSON_CreateNull();
}

static cJSON *annotation(const rs_synth_label *L, const double box[4], int id, int image_id, const char *vehicle_id)
{
    cJSON *a = cJSON_CreateObject();
    if (!a) return NULL;
    cJSON_AddNumberToObject(a, "id", id);
    cJSON_AddNumberToObject(a, "image_id", image_id);
    cJSON_AddNumberToObject(a, "category_id", (int)L->cls + 1);
    // bbox and segmentation in COCO's corner convention: the top-left pixel's top-left corner
    // is (0, 0), i.e. roadside's pixel-centre coordinates + 0.5 (the YOLO line's origin too)
    const double c[4] = {box[0] + 0.5, box[1] + 0.5, box[2] + 0.5, box[3] + 0.5};
    cJSON_AddItemToObject(a, "bbox", xywh(c));
    const double poly[8] = {c[0], c[1], c[2], c[1], c[2], c[3], c[0], c[3]}; // the box, clockwise
    cJSON *seg = cJSON_AddArrayToObject(a, "segmentation");
    if (seg) cJSON_AddItemToArray(seg, numbers(poly, 8));
    cJSON_AddNumberToObject(a, "area", (box[2] - box[0]) * (box[3] - box[1]));
    cJSON_AddNumberToObject(a, "iscrowd", 0);
    if (isfinite(L->bottom_center_px[0])) cJSON_AddItemToObject(a, "bottom_center", numbers(L->bottom_center_px, 2));
    cJSON_AddItemToObject(a, "footprint_center", numbers(L->footprint_center_px, 2));
    cJSON_AddItemToObject(a, "footprint_bbox", xywh(L->footprint_box_px));
    cJSON_AddItemToObject(a, "footprint_bbox_full", xywh(L->footprint_box_full_px));
    cJSON_AddItemToObject(a, "body_bbox", xywh(L->body_box_px));
    cJSON_AddItemToObject(a, "body_bbox_full", xywh(L->body_box_full_px));
    cJSON_AddNumberToObject(a, "truncation", L->truncation);
    cJSON *corners = cJSON_CreateArray();
    for (int c = 0; corners && c < 8; c++)
        cJSON_AddItemToArray(corners,
                             isfinite(L->corners_px[c][0]) ? numbers(L->corners_px[c], 2) : cJSON_CreateNull());
    cJSON_AddItemToObject(a, "corners_px", corners);
    cJSON *b3 = cJSON_CreateObject();
    if (b3) {
        cJSON_AddItemToObject(b3, "center_enu_m", numbers(L->center_enu_m, 3));
        cJSON_AddItemToObject(b3, "dimensions_m", numbers(L->dims_m, 3));
        cJSON_AddNumberToObject(b3, "yaw_deg", L->yaw_deg);
    }
    cJSON_AddItemToObject(a, "box3d", b3);
    cJSON_AddItemToObject(a, "bottom_center_enu_m", numbers(L->bottom_center_enu_m, 3));
    if (isfinite(L->bottom_center_llh[0])) {
        cJSON_AddNumberToObject(a, "bottom_center_lat_deg", L->bottom_center_llh[0]);
        cJSON_AddNumberToObject(a, "bottom_center_lon_deg", L->bottom_center_llh[1]);
        cJSON_AddNumberToObject(a, "bottom_center_h_m", L->bottom_center_llh[2]);
    }
    cJSON_AddNumberToObject(a, "vehicle_index", L->index);
    if (vehicle_id) cJSON_AddStringToObject(a, "vehicle_id", vehicle_id);
    if (L->visible_px >= 0) {
        cJSON_AddNumberToObject(a, "visible_pixels", (double)L->visible_px);
        cJSON_AddNumberToObject(a, "full_pixels", (double)L->full_px);
        cJSON_AddNumberToObject(a, "visibility", L->visibility);
        cJSON_AddItemToObject(a, "visible_bbox", xywh(L->visible_box_px));
    }
    return a;
}

static void add_string_or_null(cJSON *o, const char *key, const char *s)
{
    cJSON_AddItemToObject(o, key, s ? cJSON_CreateString(s) : cJSON_CreateNull());
}

static void add_number_or_null(cJSON *o, const char *key, double x)
{
    cJSON_AddItemToObject(o, key, isfinite(x) ? cJSON_CreateNumber(x) : cJSON_CreateNull());
}

// The dataset contract's image fields (docs/labels.md).
static void add_image_info(cJSON *o, const rs_synth_image_info *in)
{
    if (in->index >= 0) cJSON_AddNumberToObject(o, "index", in->index);
    add_string_or_null(o, "camera", in->camera);
    add_string_or_null(o, "background", in->background);
    add_string_or_null(o, "weather", in->weather);
    add_string_or_null(o, "time_of_day", in->time_of_day);
    if (in->condition) { // issue 40
        cJSON_AddStringToObject(o, "surface", in->surface ? in->surface : "dry");
        cJSON_AddStringToObject(o, "condition", in->condition);
        cJSON_AddBoolToObject(o, "condition_estimated", in->condition_estimated);
    }
    add_string_or_null(o, "time", in->time_iso);
    add_number_or_null(o, "sun_azimuth_deg", in->sun_azimuth_deg);
    add_number_or_null(o, "sun_elevation_deg", in->sun_elevation_deg);
    cJSON *c = cJSON_CreateObject();
    if (c) {
        add_string_or_null(c, "camera_model", in->camera_model);
        add_string_or_null(c, "camera_model_sha256", in->camera_model_sha256);
        add_string_or_null(c, "source", in->calib_source);
        add_string_or_null(c, "source_sha256", in->calib_source_sha256);
        cJSON_AddItemToObject(c, "ground_normal_enu", numbers(in->ground_normal_enu, 3));
        add_number_or_null(c, "ground_offset_m", in->ground_offset_m);
    }
    cJSON_AddItemToObject(o, "calibration", c);
    if (in->traffic_frame_file) {
        cJSON *f = cJSON_AddObjectToObject(o, "traffic_frame");
        cJSON_AddStringToObject(f, "file", in->traffic_frame_file);
        cJSON_AddNumberToObject(f, "time_s", in->traffic_frame_time_s);
        cJSON_AddNumberToObject(f, "index", in->traffic_frame_index);
    }
}

static rs_status check_images(const char *what, const rs_synth_label_image *images, int N, rs_err *err)
{
    for (int i = 0; i < N; i++)
        if (!images[i].file_name || !*images[i].file_name || strchr(images[i].file_name, '/') || images[i].width <= 0 ||
            images[i].height <= 0 || images[i].Nlabels < 0 || (images[i].Nlabels > 0 && !images[i].labels))
            return rs_err_set(err, RS_ERR_INVALID, "%s: image %d: file name (no '/'), size or labels missing", what, i);
    return RS_OK;
}

rs_status rs_synth_labels_write_coco(const char *dir, const char *split, const rs_synth_label_image *images,
                                     int Nimages, const rs_synth_label_options *opt, rs_err *err)
{
    if (!valid_split(split)) return rs_err_set(err, RS_ERR_INVALID, "COCO: split must be [A-Za-z0-9_-]+");
    rs_status st = check_images("COCO", images, Nimages, err);
    if (st) return st;
    cJSON *root = cJSON_CreateObject(), *jimages = cJSON_CreateArray(), *jann = cJSON_CreateArray(),
          *jcat = cJSON_CreateArray();
    // info and licenses: pycocotools (which YOLOX's COCO loader calls) copies "info" when it
    // loads detections; COCO lists both at the top
    cJSON *info = cJSON_AddObjectToObject(root, "info");
    cJSON_AddStringToObject(info, "description", "roadside synth: synthetic roadside vehicles (docs/labels.md)");
    cJSON_AddStringToObject(info, "contributor", "roadside");
    cJSON_AddStringToObject(info, "version", RS_SYNTH_DATASET_CONTRACT_VERSION);
    cJSON_AddStringToObject(info, "url", "");
    // what a trainer must know of the boxes (docs/labels.md, "Which box")
    const rs_synth_bbox_kind kind = opt ? opt->bbox : RS_SYNTH_BBOX_FOOTPRINT;
    cJSON_AddStringToObject(info, "bbox_kind", rs_synth_bbox_kind_name(kind));
    cJSON_AddStringToObject(info, "bbox_meaning", rs_synth_bbox_kind_meaning(kind));
    cJSON_AddStringToObject(info, "bbox_origin",
                            "COCO corner convention: (0, 0) is the top-left corner of the top-left pixel; "
                            "bbox and segmentation only, the other pixel fields have (0, 0) at that pixel's "
                            "centre (0.5 less)");
    cJSON *lic = cJSON_AddArrayToObject(root, "licenses");
    cJSON *l0 = cJSON_CreateObject();
    cJSON_AddNumberToObject(l0, "id", 1);
    cJSON_AddStringToObject(l0, "name", "synthetic: no third-party rights in the rendered vehicles");
    cJSON_AddStringToObject(l0, "url", "");
    cJSON_AddItemToArray(lic, l0);
    cJSON_AddItemToObject(root, "images", jimages);
    cJSON_AddItemToObject(root, "annotations", jann);
    cJSON_AddItemToObject(root, "categories", jcat);
    for (int c = 0; c < RS_SYNTH_NCLASSES; c++) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "id", c + 1);
        cJSON_AddStringToObject(o, "name", rs_synth_class_name((rs_synth_class)c));
        cJSON_AddStringToObject(o, "supercategory", "vehicle");
        cJSON_AddItemToArray(jcat, o);
    }
    int ann_id = 1;
    for (int i = 0; i < Nimages; i++) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "id", i + 1);
        cJSON_AddStringToObject(o, "file_name", images[i].file_name);
        cJSON_AddNumberToObject(o, "width", images[i].width);
        cJSON_AddNumberToObject(o, "height", images[i].height);
        cJSON_AddNumberToObject(o, "license", 1);
        if (images[i].info) add_image_info(o, images[i].info);
        cJSON_AddItemToArray(jimages, o);
        for (int l = 0; l < images[i].Nlabels; l++) {
            const rs_synth_label *L = &images[i].labels[l];
            double box[4];
            if (!rs_synth_label_kept(box, L, opt)) continue;
            cJSON_AddItemToArray(jann, annotation(L, box, ann_id++, i + 1,
                                                  images[i].vehicle_ids ? images[i].vehicle_ids[L->index] : NULL));
        }
    }
    char *text = cJSON_PrintUnformatted(root);
    cJSON_Delete(root);
    if (!text) return rs_err_set(err, RS_ERR_NOMEM, "COCO: out of memory");
    char name[96], *adir = rs_io_join(dir, "annotations"), *path = NULL;
    snprintf(name, sizeof name, "instances_%s.json", split);
    if (adir) path = rs_io_join(adir, name);
    if (!path) st = rs_err_set(err, RS_ERR_NOMEM, "COCO: out of memory");
    if (!st) st = rs_io_mkdir_p(adir, err);
    char *idir = st ? NULL : rs_io_join(dir, split); // the image folder YOLOX expects
    if (!st && !idir) st = rs_err_set(err, RS_ERR_NOMEM, "COCO: out of memory");
    if (!st) st = rs_io_mkdir_p(idir, err);
    free(idir);
    if (!st) st = rs_io_write_file(path, text, strlen(text), err);
    free(text);
    free(adir);
    free(path);
    return st;
}

// "cam1_000001.png" -> "cam1_000001.txt" under folder; malloc'ed.
static char *txt_path(const char *folder, const char *file_name)
{
    const char *dot = strrchr(file_name, '.');
    int stem = dot && dot != file_name ? (int)(dot - file_name) : (int)strlen(file_name);
    char *name = malloc((size_t)stem + 5), *path = NULL;
    if (name) {
        snprintf(name, (size_t)stem + 5, "%.*s.txt", stem, file_name);
        path = rs_io_join(folder, name);
    }
    free(name);
    return path;
}

// Writes one text file per image into `folder`, the lines made by `line`.
typedef void (*line_fn)(FILE *f, const rs_synth_label *L, const double box[4], const rs_synth_label_image *im);

static rs_status write_text_files(const char *what, const char *folder, const rs_synth_label_image *images, int Nimages,
                                  const rs_synth_label_options *opt, line_fn line, rs_err *err)
{
    rs_status st = check_images(what, images, Nimages, err);
    if (!st) st = rs_io_mkdir_p(folder, err);
    for (int i = 0; i < Nimages && !st; i++) {
        char *path = txt_path(folder, images[i].file_name);
        if (!path) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", what);
        rs_io_atomic a = {0};
        st = rs_io_atomic_open(&a, path, err);
        free(path);
        if (st) break;
        for (int l = 0; l < images[i].Nlabels; l++) {
            double box[4];
            if (rs_synth_label_kept(box, &images[i].labels[l], opt)) line(a.f, &images[i].labels[l], box, &images[i]);
        }
        st = rs_io_atomic_commit(&a, err);
    }
    return st;
}

static void yolo_line(FILE *f, const rs_synth_label *L, const double b[4], const rs_synth_label_image *im)
{
    // 10 decimals: the line's box agrees with COCO's bbox within 1e-6 px up to 10,000 px wide
    fprintf(f, "%d %.10f %.10f %.10f %.10f\n", (int)L->cls, (0.5 * (b[0] + b[2]) + 0.5) / im->width,
            (0.5 * (b[1] + b[3]) + 0.5) / im->height, (b[2] - b[0]) / im->width, (b[3] - b[1]) / im->height);
}

rs_status rs_synth_labels_write_yolo(const char *dir, const char *split, const rs_synth_label_image *images,
                                     int Nimages, const rs_synth_label_options *opt, rs_err *err)
{
    if (!valid_split(split)) return rs_err_set(err, RS_ERR_INVALID, "YOLO: split must be [A-Za-z0-9_-]+");
    char *labels = rs_io_join(dir, "labels"), *folder = labels ? rs_io_join(labels, split) : NULL;
    rs_status st = folder ? write_text_files("YOLO", folder, images, Nimages, opt, yolo_line, err)
                          : rs_err_set(err, RS_ERR_NOMEM, "YOLO: out of memory");
    free(labels);
    free(folder);
    return st;
}

// y = R x for a (3,3) row-major R; R NULL: the identity.
static void rotate3(double y[3], const double *R, const double x[3])
{
    for (int i = 0; i < 3; i++) y[i] = R ? R[3 * i] * x[0] + R[3 * i + 1] * x[1] + R[3 * i + 2] * x[2] : x[i];
}

static void kitti_line(FILE *f, const rs_synth_label *L, const double b[4], const rs_synth_label_image *im)
{
    static const char *const types[RS_SYNTH_NCLASSES] = {"Car", "Car",   "Car",   "Car",  "Van",
                                                         "Bus", "Truck", "Truck", "Misc", "Cyclist"};
    const char *type = (int)L->cls >= 0 && L->cls < RS_SYNTH_NCLASSES ? types[L->cls] : "Misc";
    int occluded = !isfinite(L->visibility) ? 3 : L->visibility >= 0.8 ? 0 : L->visibility >= 0.4 ? 1 : 2;
    double x[3], fwd[3]; // location and forward axis in the rectified frame
    rotate3(x, im->R0_rect, L->bottom_center_cam_m);
    rotate3(fwd, im->R0_rect, L->forward_cam);
    const double rotation_y = atan2(-fwd[2], fwd[0]);
    double alpha = rotation_y - atan2(x[0], x[2]);
    alpha = atan2(sin(alpha), cos(alpha));
    fprintf(f, "%s %.4f %d %.4f %.2f %.2f %.2f %.2f %.4f %.4f %.4f %.4f %.4f %.4f %.4f\n", type, L->truncation,
            occluded, alpha, b[0], b[1], b[2], b[3], L->dims_m[2], L->dims_m[1], L->dims_m[0], x[0], x[1], x[2],
            rotation_y);
}

rs_status rs_synth_labels_write_kitti(const char *dir, const rs_synth_label_image *images, int Nimages,
                                      const rs_synth_label_options *opt, rs_err *err)
{
    char *folder = rs_io_join(dir, "label_2");
    rs_status st = folder ? write_text_files("KITTI", folder, images, Nimages, opt, kitti_line, err)
                          : rs_err_set(err, RS_ERR_NOMEM, "KITTI: out of memory");
    free(folder);
    return st;
}
