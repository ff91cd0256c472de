// rs_synth_render.c -- rendering a scene with povray: culling, regions, the colour, ID and shadow
// passes as povray processes at once (synth/povray/rs_synth_povray.c runs them), resampling into the
// real lens, compositing (rs_synth_render.h, docs/povray.md, docs/fleet.md "Cost").
#include "synth/povray/rs_synth_render.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

#include <mrcal/poseutils.h>

#include "core/rs_color.h"
#include "core/rs_io.h"
#include "synth/backdrop/rs_synth_appearance.h"
#include "synth/backdrop/rs_synth_condition.h"
#include "synth/povray/internal/rs_synth_povray.h"
#include "synth/povray/internal/rs_synth_render_internal.h"
#include "synth/povray/internal/rs_synth_scene_internal.h"
#include "synth/povray/rs_synth_raster.h"

void rs_synth_render_options_default(rs_synth_render_options *opt)
{
    memset(opt, 0, sizeof(*opt));
    opt->canvas_scale = 1;
    opt->write_files = true;
    rs_synth_scene_options_default(&opt->scene);
}

void rs_synth_render_result_free(rs_synth_render_result *r)
{
    if (!r) return;
    rs_image_free(&r->rgba);
    rs_image_free(&r->composite);
    free(r->ids);
    free(r->visible);
    free(r->shadow);
    rs_image_free(&r->mirror);
    free(r->headlight_irradiance);
    memset(r, 0, sizeof(*r));
}

// ---- culling: rs_synth_vehicle_rect (synth/povray/rs_synth_render_cull.c) ----

// Widens rect (x0, y0, x1, y1; empty when x1 < x0) by the canvas rectangle of vehicle v's
// shadows: its bottom corners and its top corners projected onto the ground along each light
// higher than 3 deg above the ground.
static void widen_by_shadows(int rect[4], const rs_synth_canvas *canvas, const double rt_cam_enu[6],
                             const double corners[8][3], const double ground_normal_enu[3], double ground_offset_m,
                             const rs_synth_light *lights, int Nlights)
{
    const double *g = ground_normal_enu;
    const double gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    for (int j = 0; j < Nlights; j++) {
        const double *d = lights[j].dir_enu;
        const double nd = (g[0] * d[0] + g[1] * d[1] + g[2] * d[2]) / gn;
        if (!(nd > 0.05)) continue;
        double pts[8][3];
        for (int k = 0; k < 4; k++) {
            memcpy(pts[k], corners[k], sizeof(pts[k]));
            const double *p = corners[4 + k];
            const double t = ((g[0] * p[0] + g[1] * p[1] + g[2] * p[2]) / gn - ground_offset_m / gn) / nd;
            for (int c = 0; c < 3; c++) pts[4 + k][c] = p[c] - t * d[c];
        }
        int r[4];
        if (rs_synth_vehicle_rect(r, canvas, rt_cam_enu, (const double(*)[3])pts, 0.05)) rs_synth_rect_grow(rect, r);
    }
}

// The colour pass read from 16-bit PPM (RGB) made RGBA: alpha 1 where the ID pass (R + 256 G in
// 8-bit units) shows a vehicle, else 0 (rs_synth_scene_ground_occludes says when that is exact).
static rs_status alpha_from_ids(rs_image *rgba, const rs_image *ids, rs_err *err)
{
    rs_image out = {0};
    rs_status st = rs_image_alloc(&out, rgba->width, rgba->height, 4, err);
    if (st) return st;
    const size_t n = (size_t)rgba->width * rgba->height;
    for (size_t i = 0; i < n; i++) {
        const float *id = &ids->data[i * (size_t)ids->channels];
        const bool vehicle = id[0] > 0.5f / 255 || (ids->channels >= 3 && id[1] > 0.5f / 255);
        for (int c = 0; c < 3; c++) out.data[4 * i + c] = vehicle ? rgba->data[i * (size_t)rgba->channels + c] : 0;
        out.data[4 * i + 3] = vehicle;
    }
    rs_image_free(rgba);
    *rgba = out;
    return RS_OK;
}

// ---- the shadow pass: coarse meshes, half resolution (issue 18's cost, docs/fleet.md) ----

// The shadow pass's vehicles: `in`'s, with each included procedural vehicle's mesh rebuilt
// coarse (rs_synth_fleet_build_lod: 8 stations along the body instead of 56, octagonal wheels;
// the box and the roof line exact), user models as they are. out->v and out->imesh are
// in's (borrowed); out->meshes[m] is owned when owned[m] (free_shadow_vehicles).
static rs_status shadow_vehicles(rs_synth_prepared *out, uint8_t **owned, const rs_synth_prepared *in,
                                 const uint8_t *include, rs_err *err)
{
    *out = *in;
    out->meshes = calloc((size_t)(in->Nmeshes > 0 ? in->Nmeshes : 1), sizeof(rs_synth_mesh));
    *owned = calloc((size_t)(in->Nmeshes > 0 ? in->Nmeshes : 1), 1);
    if (!out->meshes || !*owned) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int m = 0; m < in->Nmeshes; m++) {
        int first = -1;
        for (int i = 0; i < in->N && first < 0; i++)
            if (in->imesh[i] == m && include[i]) first = i;
        if (first >= 0 && in->v[first].cls != RS_SYNTH_USER_MODEL) {
            rs_status st = rs_synth_fleet_build_lod(&out->meshes[m], &in->v[first], RS_SYNTH_LOD_COARSE, err);
            if (st) return st;
            (*owned)[m] = 1;
        } else {
            out->meshes[m] = in->meshes[m]; // shallow: borrowed arrays
        }
    }
    return RS_OK;
}

static void free_shadow_vehicles(rs_synth_prepared *sv, uint8_t *owned)
{
    for (int m = 0; sv->meshes && owned && m < sv->Nmeshes; m++)
        if (owned[m]) rs_synth_mesh_free(&sv->meshes[m]);
    free(sv->meshes);
    free(owned);
}

// The lit fraction at every canvas pixel from the half-resolution shadow pass `lo` (RGBA: the
// ground lit as rs_synth_scene_shadow_unlit says, transparent where not rendered, the vehicles
// green marks): value / unlit clamped to [0, 1], 1 where transparent. lo was rendered through the
// canvas pinhole scaled by 1/2 (fx/2, fy/2, (cx - 0.5)/2, (cy - 0.5)/2): its pixel i is centred on
// canvas x = 2 i + 0.5, so canvas pixel x reads it at (x - 0.5)/2, bilinearly (clamped at the
// borders) over its ground pixels only (the weights of marks dropped, the rest renormalised);
// with no ground among the 4, the nearest ground pixel within 2, else 1. (Canvas pixels that
// only marks surround are the vehicles' own, which compositing leaves unshaded.)
static rs_status shadow_fraction(rs_image *out, rs_image *lo, double unlit, int width, int height, rs_err *err)
{
    rs_status st = rs_image_alloc(out, width, height, 1, err);
    if (st) return st;
    const int c = lo->channels, Wl = lo->width, Hl = lo->height;
    if (c < 4) return rs_err_set(err, RS_ERR_EXTERNAL, "the shadow pass has %d channels, not RGBA", c);
    for (size_t i = 0; i < (size_t)Wl * Hl; i++) { // in place: channel 0 the fraction, 1 ground or not
        float *px = &lo->data[(size_t)c * i];
        const double v = px[3] <= 0 ? 1.0 : (unlit > 0 ? px[0] / unlit : 1.0);
        const bool mark = px[3] > 0 && px[1] - px[0] > 0.5f;
        px[0] = (float)(v < 0 ? 0 : v > 1 ? 1 : v), px[1] = !mark;
    }
    for (int y = 0; y < height; y++) {
        const double v = fmin(fmax((y - 0.5) / 2, 0), Hl - 1);
        const int y0 = (int)v, y1 = y0 + 1 < Hl ? y0 + 1 : y0;
        const float ty = (float)(v - y0);
        for (int x = 0; x < width; x++) {
            const double u = fmin(fmax((x - 0.5) / 2, 0), Wl - 1);
            const int x0 = (int)u, x1 = x0 + 1 < Wl ? x0 + 1 : x0;
            const float tx = (float)(u - x0), w[4] = {(1 - ty) * (1 - tx), (1 - ty) * tx, ty * (1 - tx), ty * tx};
            const float *p[4] = {&lo->data[((size_t)y0 * Wl + x0) * c], &lo->data[((size_t)y0 * Wl + x1) * c],
                                 &lo->data[((size_t)y1 * Wl + x0) * c], &lo->data[((size_t)y1 * Wl + x1) * c]};
            float sum = 0, sw = 0;
            for (int k = 0; k < 4; k++) sum += w[k] * p[k][1] * p[k][0], sw += w[k] * p[k][1];
            float f = sw > 1e-6f ? sum / sw : 1;
            for (int r = 1, best = 99; sw <= 1e-6f && r <= 2; r++) // the nearest ground pixel
                for (int dy = -r; dy <= r; dy++)
                    for (int dx = -r; dx <= r; dx++) {
                        const int yy = y0 + dy, xx = x0 + dx, d = dx * dx + dy * dy;
                        if (yy < 0 || yy >= Hl || xx < 0 || xx >= Wl || d >= best) continue;
                        const float *q = &lo->data[((size_t)yy * Wl + xx) * c];
                        if (q[1] > 0) f = q[0], best = d;
                    }
            out->data[(size_t)y * width + x] = f;
        }
    }
    return RS_OK;
}

// The environment map of opt->env_map written into the work folder under its generated name,
// scaled to its maximum (a 16-bit PNG holds [0, 1]), and the colour pass told to show it.
static rs_status write_env_map(rs_synth_render_options *opt, const char *out_dir, rs_err *err)
{
    const rs_image *m = opt->env_map;
    if (!m) return RS_OK;
    if (m->channels != 3 || m->width != 2 * m->height || m->height < 4)
        return rs_err_set(err, RS_ERR_INVALID, "environment map: %dx%dx%d, want (h, 2h, 3)", m->width, m->height,
                          m->channels);
    const size_t n = (size_t)m->width * m->height * 3;
    double top = 0;
    for (size_t i = 0; i < n; i++) top = m->data[i] > top ? m->data[i] : top;
    rs_image scaled = {0};
    rs_status st = rs_image_alloc(&scaled, m->width, m->height, 3, err);
    char *path = st ? NULL : rs_io_join(out_dir, RS_SYNTH_ENV_MAP_FILE);
    if (!st && !path) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) {
        for (size_t i = 0; i < n; i++) scaled.data[i] = top > 0 ? (float)(m->data[i] / top) : 0;
        st = rs_image_write(path, &scaled, 16, err);
    }
    if (!st) opt->scene.env_map = true, opt->scene.env_map_scale = top > 0 ? top : 1;
    free(path);
    rs_image_free(&scaled);
    return st;
}

// Resamples the canvas passes into the real lens: colour through premultiplied linear
// interpolation, IDs nearest-neighbour.
static rs_status to_lens(rs_image *rgba, rs_image *ids, const float *map, int width, int height, rs_err *err)
{
    const size_t Nc = (size_t)rgba->width * rgba->height;
    for (size_t i = 0; i < Nc; i++)
        for (int k = 0; k < 3; k++) rgba->data[4 * i + k] *= rgba->data[4 * i + 3];
    rs_image out_rgba = {0}, out_ids = {0};
    rs_status st = rs_synth_remap(&out_rgba, rgba, map, width, height, 1, err);
    if (!st) st = rs_synth_remap(&out_ids, ids, map, width, height, 0, err);
    if (st) {
        rs_image_free(&out_rgba);
        return st;
    }
    const size_t N = (size_t)width * height;
    for (size_t i = 0; i < N; i++) {
        const float a = out_rgba.data[4 * i + 3];
        for (int k = 0; k < 3; k++) out_rgba.data[4 * i + k] = a > 0 ? out_rgba.data[4 * i + k] / a : 0;
    }
    rs_image_free(rgba);
    rs_image_free(ids);
    *rgba = out_rgba;
    *ids = out_ids;
    return RS_OK;
}

// Decodes the ID pass (R + 256 G in 8-bit units) into out->ids; values above N become 0.
static void decode_ids(rs_synth_render_result *out, const rs_image *ids, int N)
{
    const size_t Npx = (size_t)out->width * out->height;
    for (size_t i = 0; i < Npx; i++) {
        const float *px = &ids->data[i * (size_t)ids->channels];
        const long v = lroundf(px[0] * 255.0f) + 256 * lroundf(px[1] * 255.0f);
        out->ids[i] = (uint16_t)(v >= 0 && v <= N ? v : 0);
    }
}

// out->composite = rgba over the background (rs_synth_composite_background, with the shadows,
// the condition's ground terms -- the headlights' light, a wet road's mirror image -- and the
// look of opt) or over black.
static rs_status composite(rs_synth_render_result *out, const rs_image *bg, const rs_synth_render_options *opt,
                           rs_err *err)
{
    const size_t Npx = (size_t)out->width * out->height;
    if (!bg) {
        for (size_t i = 0; i < Npx; i++) {
            const float *c = &out->rgba.data[4 * i];
            for (int k = 0; k < 3; k++) out->composite.data[3 * i + k] = (float)rs_color_srgb_encode(c[3] * c[k]);
        }
        return RS_OK;
    }
    rs_image lin = {0}, comp = {0};
    rs_status st = rs_image_alloc(&lin, out->width, out->height, 3, err);
    if (st) return st;
    for (size_t i = 0; i < Npx; i++)
        for (int k = 0; k < 3; k++)
            lin.data[3 * i + k] = (float)rs_color_srgb_decode(bg->data[i * bg->channels + (bg->channels >= 3 ? k : 0)]);
    const rs_synth_composite_options copt = {.look = opt->look,
                                             .layer_blur_sigma_px = 0,
                                             .seed = opt->look_seed,
                                             .light_matched = opt->light_matched,
                                             .headlight_irradiance = out->headlight_irradiance,
                                             .mirror = out->mirror.data ? &out->mirror : NULL,
                                             .ids = out->ids};
    if (!(st = rs_synth_composite_background(&comp, &out->rgba, &lin, out->shadow, &copt, err))) {
        rs_image_free(&out->composite);
        out->composite = comp;
    }
    rs_image_free(&lin);
    return st;
}

static rs_status write_outputs(const char *out_dir, const rs_synth_render_result *out, rs_err *err)
{
    rs_image ids = {0};
    rs_status st = rs_image_alloc(&ids, out->width, out->height, 1, err);
    if (st) return st;
    const size_t Npx = (size_t)out->width * out->height;
    for (size_t i = 0; i < Npx; i++) ids.data[i] = out->ids[i] / 65535.0f;
    const char *names[3] = {"image.png", "rgba.png", "ids.png"};
    const rs_image *imgs[3] = {&out->composite, &out->rgba, &ids};
    const int bits[3] = {8, 16, 16};
    for (int k = 0; k < 3 && !st; k++) {
        char *p = rs_io_join(out_dir, names[k]);
        st = p ? rs_image_write(p, imgs[k], bits[k], err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(p);
    }
    if (!st && out->shadow) {
        const rs_image sh = {.width = out->width, .height = out->height, .channels = 1, .data = out->shadow};
        char *p = rs_io_join(out_dir, "shadow.png");
        st = p ? rs_image_write(p, &sh, 16, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(p);
    }
    rs_image_free(&ids);
    return st;
}

// The state of one rs_synth_render call, shared by its stages.
typedef struct {
    rs_synth_render_options opt;
    const char *out_dir, *povray;
    const rs_camera *camera;
    const double *ground_normal_enu;
    double ground_offset_m;
    const rs_synth_prepared *vehicles;
    rs_synth_canvas canvas;
    rs_synth_povcam cam;
    rs_synth_light lights[RS_SYNTH_SKY_LIGHTS + 1];
    int Nlights;
    uint8_t *include;                      // (N,) owned: 0 = culled
    int (*rects)[4];                       // (N, 4) owned: each included vehicle's canvas rectangle
    int (*reach)[4];                       // (N, 4) owned: the same widened by its shadows
    int region[4], sregion[4], mregion[4]; // canvas rectangles: colour/ID, shadow, mirror passes
    bool ground_drawn;                     // the ground is drawn (no background to composite onto)
    rs_image mirror, headlights;           // issue 40: the canvas's mirror pass, headlights' irradiance
    rs_synth_prepared svehicles;           // the shadow pass's (shadow_vehicles)
    uint8_t *sowned;
} render_state;

// 1-2. Culling and the regions: the vehicles' boxes (colour and ID), with their shadows. The
// caller's rectangles (opt.vehicle_rects) stand for the test when given.
static void render_cull(render_state *s, rs_synth_render_result *out)
{
    const rs_synth_render_options *opt = &s->opt;
    const rs_synth_canvas *canvas = &s->canvas;
    const double *rt_cam_enu = s->camera->rt_cam_enu;
    const int N = s->vehicles->N;
    s->Nlights = rs_synth_scene_lights(s->lights, &opt->scene);
    for (int k = 0; k < 3; k++) {
        int *r = k == 2 ? s->mregion : k ? s->sregion : s->region;
        r[0] = canvas->width, r[1] = canvas->height, r[2] = r[3] = -1;
    }
    for (int i = 0; i < N; i++) {
        double corners[8][3];
        int rect[4];
        rs_synth_vehicle_corners_enu(corners, &s->vehicles->v[i], s->ground_normal_enu, s->ground_offset_m);
        bool in;
        if (opt->vehicle_rects) {
            memcpy(rect, opt->vehicle_rects[i], sizeof(rect));
            in = true;
        } else {
            in = rs_synth_vehicle_rect(rect, canvas, rt_cam_enu, (const double(*)[3])corners, 0.05);
        }
        s->include[i] = opt->full_frame || in;
        out->visible[i] = s->include[i];
        s->rects[i][0] = s->reach[i][0] = 0, s->rects[i][2] = s->reach[i][2] = -1; // empty
        if (!in) continue;
        out->Nrendered++;
        rs_synth_rect_grow(s->region, rect);
        memcpy(s->rects[i], rect, sizeof(rect));
        memcpy(s->reach[i], rect, sizeof(rect));
        widen_by_shadows(s->reach[i], canvas, rt_cam_enu, (const double(*)[3])corners, s->ground_normal_enu,
                         s->ground_offset_m, s->lights, s->Nlights);
        int mrect[4];
        if (opt->mirror && rs_synth_mirror_rect(mrect, canvas, rt_cam_enu, (const double(*)[3])corners,
                                                s->ground_normal_enu, s->ground_offset_m))
            rs_synth_rect_grow(s->mregion, mrect);
        if (opt->shadow) rs_synth_rect_grow(s->sregion, s->reach[i]);
    }
    // Pins, and the ground when there is no background to composite onto, are part of the
    // picture too: they widen the region to the whole canvas.
    s->ground_drawn = !opt->background_path && opt->scene.ground_visible;
    for (int pass = 0; pass < 2; pass++) {
        int *r = pass ? s->sregion : s->region;
        if (opt->full_frame || (!pass && (opt->scene.Npins > 0 || s->ground_drawn))) {
            r[0] = r[1] = 0;
            r[2] = canvas->width - 1;
            r[3] = canvas->height - 1;
        }
    }
    if (opt->full_frame) out->Nrendered = N;
}

// A cluster's vehicles (include, N flags) joined by every included vehicle within
// REFLECT_REACH_M of one of them (footprints' bounding circles): what its paint and glass
// reflect (a neighbour's dark side in a side window), as in one scene of every vehicle.
#define REFLECT_REACH_M 4.0
static void add_reflected(uint8_t *include, const render_state *s)
{
    const int N = s->vehicles->N;
    const rs_synth_vehicle *v = s->vehicles->v;
    for (int j = 0; j < N; j++) {
        if (include[j] || !s->include[j]) continue;
        for (int i = 0; i < N && !include[j]; i++) {
            if (include[i] != 1 || i == j) continue;
            const double d = hypot(v[i].e_m - v[j].e_m, v[i].n_m - v[j].n_m) - hypot(v[i].length_m, v[i].width_m) / 2 -
                             hypot(v[j].length_m, v[j].width_m) / 2;
            if (d < REFLECT_REACH_M) include[j] = 2; // (2: added here, not a source of more)
        }
    }
    for (int j = 0; j < N; j++) include[j] = include[j] != 0;
}

// A cluster's guests (there for its reflections and the shadows they cast on its vehicles) whose
// rectangle misses the cluster's are seen there only in paint, glass and shadows: they take
// their coarse mesh (s->svehicles's, made here when no shadow or mirror pass made it). out:
// cveh (Nclusters,): s->vehicles's arrays but the meshes, *cmeshes (owned, NULL: none coarse).
static rs_status guests_coarse(rs_synth_prepared cveh[], rs_synth_mesh **cmeshes, render_state *s, const int crect[][4],
                               const uint8_t *cinclude, int Nclusters, rs_err *err)
{
    const rs_synth_prepared *V = s->vehicles;
    const int N = V->N, M = V->Nmeshes;
    *cmeshes = NULL;
    if (M == 0) return RS_OK;
    // coarse[c * M + m]: every user of mesh m in cluster c a procedural guest outside its rectangle
    uint8_t *coarse = calloc((size_t)Nclusters * (size_t)M, 1);
    if (!coarse) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    bool any = false;
    for (int c = 0; c < Nclusters; c++)
        for (int m = 0; m < M; m++) {
            int users = 0, guests = 0;
            for (int i = 0; i < N; i++) {
                if (V->imesh[i] != m || !cinclude[(size_t)c * N + i]) continue;
                users++;
                guests += !rs_synth_rects_meet(s->rects[i], crect[c]) && V->v[i].cls != RS_SYNTH_USER_MODEL;
            }
            coarse[(size_t)c * M + m] = users > 0 && guests == users;
            any |= users > 0 && guests == users;
        }
    rs_status st = RS_OK;
    if (any && !s->svehicles.meshes) st = shadow_vehicles(&s->svehicles, &s->sowned, s->vehicles, s->include, err);
    if (any && !st && !(*cmeshes = malloc(sizeof(rs_synth_mesh) * (size_t)Nclusters * (size_t)M)))
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int c = 0; any && !st && c < Nclusters; c++) {
        cveh[c] = *V;
        cveh[c].meshes = &(*cmeshes)[(size_t)c * M];
        for (int m = 0; m < M; m++)
            cveh[c].meshes[m] = coarse[(size_t)c * M + m] ? s->svehicles.meshes[m] : V->meshes[m];
    }
    free(coarse);
    return st;
}

// The passes: colour; ID and shadow when vehicles are rendered. out: passes (3,), *i_id and
// *i_shadow (-1: none); returns their count.
static int render_passes(rs_synth_scene_options passes[4], int *i_id, int *i_shadow, int *i_mirror,
                         const render_state *s, const rs_synth_render_result *out)
{
    int Npasses = 0;
    *i_id = *i_shadow = *i_mirror = -1;
    passes[Npasses] = s->opt.scene;
    passes[Npasses].include = s->include;
    passes[Npasses].pass = RS_SYNTH_PASS_COLOUR;
    passes[Npasses].ground_visible = s->opt.background_path ? false : s->opt.scene.ground_visible;
    Npasses++;
    if (out->Nrendered > 0) {
        passes[Npasses] = passes[0];
        passes[Npasses].pass = RS_SYNTH_PASS_ID;
        passes[Npasses].Npins = 0;
        *i_id = Npasses++;
        if (s->opt.shadow) {
            passes[Npasses] = passes[*i_id];
            passes[Npasses].pass = RS_SYNTH_PASS_SHADOW;
            *i_shadow = Npasses++;
        }
        if (s->opt.mirror && s->mregion[2] >= 0 && !(s->canvas.fisheye_deg > 0)) { // issue 40: a wet road's mirror
            passes[Npasses] = passes[0];
            passes[Npasses].Npins = 0;
            *i_mirror = Npasses++;
        }
    }
    return Npasses;
}

// The passes rendered on the canvas: one povray process per pass (docs/fleet.md, "Cost"): the
// colour pass; the ID pass on the same meshes, each merged into one mesh2 without normals; the
// shadow pass at half resolution on coarse meshes. They run at once, unless
// separate_processes (one after the other: the benchmark's "separate"). The ID and shadow
// passes are rasterised here instead (rs_synth_raster.h) unless the caller asks for POV-Ray's.
// out: *rgba, *idimg (the canvas's; idimg empty without an ID pass), *frac (the lit fraction,
// empty without a shadow pass)
static rs_status render_canvas(rs_image *rgba, rs_image *idimg, rs_image *frac, render_state *s,
                               rs_synth_render_result *out, rs_err *err)
{
    const rs_synth_render_options *opt = &s->opt;
    const rs_synth_canvas *canvas = &s->canvas;
    const double *rt_cam_enu = s->camera->rt_cam_enu;
    rs_synth_scene_options passes[4];
    int i_id, i_shadow, i_mirror;
    const int Npasses = render_passes(passes, &i_id, &i_shadow, &i_mirror, s, out);
    memcpy(out->region, s->region, sizeof(s->region)); // rendered: the union of the regions
    if (i_shadow >= 0) rs_synth_rect_grow(out->region, s->sregion);
    rs_synth_povray_job jobs[4 + RS_SYNTH_MAX_CLUSTERS - 1];
    rs_synth_povcam scam, mcam; // the shadow and mirror passes: half resolution, coarse meshes
    const int W2 = (canvas->width + 1) / 2, H2 = (canvas->height + 1) / 2;
    rs_status st = RS_OK;
    if (i_shadow >= 0 || i_mirror >= 0) {
        // (a fisheye canvas's size is even: the same angle on half the size has the same relation)
        const double *f = canvas->fxycxy;
        const double half[4] = {f[0] / 2, f[1] / 2, (f[2] - 0.5) / 2, (f[3] - 0.5) / 2};
        if ((st = canvas->fisheye_deg > 0
                      ? rs_synth_povcam_init_fisheye(&scam, canvas->fisheye_deg, W2, rt_cam_enu, err)
                      : rs_synth_povcam_init(&scam, half, W2, H2, rt_cam_enu, err)) ||
            (st = shadow_vehicles(&s->svehicles, &s->sowned, s->vehicles, s->include, err)))
            return st;
        rs_synth_povcam_mirror(&mcam, &scam, s->ground_normal_enu, s->ground_offset_m);
    }
    // Without pins, drawn ground, antialiasing or a ground hiding part of a vehicle
    // (rs_synth_scene_ground_occludes) the colour pass covers exactly the ID pass's vehicle
    // pixels (the same rays meet the same triangles): its alpha is taken from the ID pass and
    // it is written as 16-bit PPM, 0.05 s cheaper per image than RGBA PNG to write and read.
    const bool ground_hides = i_id >= 0 && rs_synth_scene_ground_occludes(&s->cam, s->vehicles, &passes[i_id],
                                                                          s->ground_normal_enu, s->ground_offset_m);
    const bool ids_alpha =
        i_id >= 0 && opt->antialias < 2 && opt->scene.Npins == 0 && !s->ground_drawn && !ground_hides;
    // The ID pass is POV-Ray's too where the ground may hide part of a vehicle; both are
    // POV-Ray's on a fisheye canvas (the rasteriser draws straight edges: a pinhole's).
    const bool fisheye = canvas->fisheye_deg > 0;
    const bool ids_here = i_id >= 0 && !ground_hides && !opt->povray_passes && !fisheye;
    const bool shadow_here = i_shadow >= 0 && !opt->povray_passes && !fisheye;
    static const char *const names[4] = {"pass_colour", "pass_ids", "pass_shadow", "pass_mirror"};
    static const char *const logs[4] = {"povray.log", "pass_ids.log", "pass_shadow.log", "pass_mirror.log"};
    for (int k = 0; k < Npasses; k++) {
        const bool sh = k == i_shadow;
        const int name = k == i_mirror ? 3 : k == i_shadow ? 2 : k;
        jobs[k] = (rs_synth_povray_job){.name = names[name],
                                        .cam = sh              ? &scam
                                               : k == i_mirror ? &mcam
                                                               : &s->cam,
                                        .vehicles = sh || k == i_mirror ? &s->svehicles : s->vehicles,
                                        .pass = &passes[k],
                                        .antialias = k ? 0 : opt->antialias,
                                        .region = {s->region[0], s->region[1], s->region[2], s->region[3]},
                                        .ppm = k == 0 && ids_alpha,
                                        .log = logs[name]};
        if (sh || k == i_mirror) {
            const int *sr = sh ? s->sregion : s->mregion;
            const int r2[4] = {(int)fmax(0, floor((sr[0] - 0.5) / 2)), (int)fmax(0, floor((sr[1] - 0.5) / 2)),
                               (int)fmin(W2 - 1, ceil((sr[2] - 0.5) / 2)), (int)fmin(H2 - 1, ceil((sr[3] - 0.5) / 2))};
            memcpy(jobs[k].region, r2, sizeof(r2));
        }
    }
    // the colour pass in clusters, where they pay (the ID pass gives the alpha: no pins, no
    // drawn ground, no antialiasing; a pinhole canvas)
    int crect[RS_SYNTH_MAX_CLUSTERS][4], Nclusters = 0, Njobs = Npasses;
    uint8_t *cinclude = NULL;
    rs_synth_scene_options cpasses[RS_SYNTH_MAX_CLUSTERS];
    static const char *const cnames[RS_SYNTH_MAX_CLUSTERS] = {"pass_colour", "pass_colour_2", "pass_colour_3",
                                                              "pass_colour_4"};
    static const char *const clogs[RS_SYNTH_MAX_CLUSTERS] = {"povray.log", "pass_colour_2.log", "pass_colour_3.log",
                                                             "pass_colour_4.log"};
    if (ids_alpha && !fisheye && !opt->full_frame && s->vehicles->N > 1 &&
        (cinclude = malloc((size_t)RS_SYNTH_MAX_CLUSTERS * (size_t)s->vehicles->N)))
        Nclusters = rs_synth_colour_clusters(crect, cinclude, s->vehicles->N, s->include, s->rects, s->reach,
                                             s->canvas.width, s->canvas.height, s->region);
    for (int c = 0; c < Nclusters; c++) add_reflected(&cinclude[(size_t)c * s->vehicles->N], s);
    rs_synth_prepared cveh[RS_SYNTH_MAX_CLUSTERS];
    rs_synth_mesh *cmeshes = NULL;
    if (Nclusters > 0 && !st) st = guests_coarse(cveh, &cmeshes, s, crect, cinclude, Nclusters, err);
    for (int c = 0; c < Nclusters; c++) {
        cpasses[c] = passes[0];
        cpasses[c].include = &cinclude[(size_t)c * s->vehicles->N];
        rs_synth_povray_job *j = c ? &jobs[Njobs++] : &jobs[0];
        if (c) *j = jobs[0];
        j->name = cnames[c];
        j->log = clogs[c];
        j->pass = &cpasses[c];
        if (cmeshes) j->vehicles = &cveh[c];
        memcpy(j->region, crect[c], sizeof(crect[c]));
    }
    rs_image imgs[4] = {{0}};
    // (pins are sized in real-image pixels: the lens's fx, fy, not the canvas's)
    const bool together = !opt->separate_processes;
    for (int k = 0; k < Njobs; k++) {
        if ((k == i_id && ids_here) || (k == i_shadow && shadow_here)) continue;
        if (!st)
            st = rs_synth_povray_job_start(&jobs[k], s->out_dir, s->povray, s->camera->intrinsics, s->ground_normal_enu,
                                           s->ground_offset_m, err);
        if (!together) {
            rs_status st2 = rs_synth_povray_job_finish(&jobs[k], &imgs[k < Npasses ? k : 0], s->out_dir, s->povray,
                                                       &out->seconds_povray, err);
            st = st ? st : st2;
        }
    }
    if (!st && ids_here) // while povray renders the colour pass
        st = rs_synth_raster_ids(&imgs[i_id], canvas->fxycxy, canvas->width, canvas->height, rt_cam_enu, s->vehicles,
                                 s->include, s->ground_normal_enu, s->ground_offset_m, s->region, err);
    if (!st && shadow_here)
        st = rs_synth_raster_shadow(frac, canvas->fxycxy, canvas->width, canvas->height, rt_cam_enu, &s->svehicles,
                                    s->include, s->ground_normal_enu, s->ground_offset_m, s->lights, s->Nlights, err);
    if (!st && opt->headlights && out->Nrendered > 0) // issue 40: the road lit by the headlights
        st = rs_synth_headlight_ground(&s->headlights, canvas, rt_cam_enu, s->ground_normal_enu, s->ground_offset_m,
                                       s->vehicles, s->include, opt->scene.headlight_intensity, err);
    for (int k = 0; k < Njobs && together; k++) { // every started one waited for, the first error kept
        rs_err e2 = {0};
        rs_status st2 = rs_synth_povray_job_finish(&jobs[k], &imgs[k < Npasses ? k : 0], s->out_dir, s->povray,
                                                   &out->seconds_povray, st ? &e2 : err);
        st = st ? st : st2;
    }
    free(cinclude);
    free(cmeshes);
    out->Npovray = Njobs - (ids_here ? 1 : 0) - (shadow_here ? 1 : 0);
    out->Npasses = Npasses;
    *rgba = imgs[0];
    if (i_id >= 0) *idimg = imgs[1];
    if (!st && jobs[0].ppm) st = alpha_from_ids(rgba, idimg, err);
    if (!st && i_shadow >= 0 && !shadow_here)
        st = shadow_fraction(frac, &imgs[i_shadow],
                             rs_synth_scene_shadow_unlit(s->lights, s->Nlights, s->ground_normal_enu), canvas->width,
                             canvas->height, err);
    if (i_shadow >= 0) rs_image_free(&imgs[i_shadow]);
    if (!st && i_id < 0) st = rs_image_alloc(idimg, canvas->width, canvas->height, 3, err);
    if (i_mirror >= 0) {
        if (!st) st = rs_synth_mirror_weight(&imgs[i_mirror], canvas, rt_cam_enu, s->ground_normal_enu, err);
        s->mirror = imgs[i_mirror];
    }
    return st;
}

// 3. From the canvas into the real lens: the passes resampled (a distorted lens), the IDs
// decoded, the shadow fraction handed to out. rgba, idimg and frac are consumed.
static rs_status render_into_lens(rs_synth_render_result *out, rs_image *rgba, rs_image *idimg, rs_image *frac,
                                  render_state *s, rs_err *err)
{
    const rs_camera *camera = s->camera;
    const int width = camera->width, height = camera->height;
    float *map = NULL;
    const float *use = s->opt.canvas_map;
    rs_status st = RS_OK;
    if (!s->canvas.identity) {
        if (!use &&
            !(st = rs_synth_canvas_map(&map, &s->canvas, &camera->lensmodel, camera->intrinsics, width, height, err)))
            use = map;
        if (!st) st = to_lens(rgba, idimg, use, width, height, err);
        if (!st && frac->data) {
            rs_image lens = {0};
            st = rs_synth_remap(&lens, frac, use, width, height, 1, err);
            rs_image_free(frac);
            *frac = lens;
        }
    }
    if (!st) st = rs_synth_condition_into_lens(out, &s->mirror, &s->headlights, s->canvas.identity ? NULL : use, err);
    free(map);
    if (st) {
        rs_image_free(frac);
        return st;
    }
    out->shadow = frac->data; // owned by out now
    *frac = (rs_image){0};
    out->rgba = *rgba;
    *rgba = (rs_image){0};
    decode_ids(out, idimg, s->vehicles->N);
    // the shadow pass does not look under the vehicles (its green marks): 1 on their pixels
    for (size_t i = 0; out->shadow && i < (size_t)width * height; i++)
        if (out->ids[i]) out->shadow[i] = 1;
    return RS_OK;
}

// The state's camera, canvas, background and buffers. out: *bg (the background, may stay empty)
static rs_status render_setup(render_state *s, rs_image *bg, rs_synth_render_result *out, rs_err *err)
{
    const rs_camera *camera = s->camera;
    const int width = camera->width, height = camera->height, N = s->vehicles->N;
    rs_status st;
    if (s->opt.canvas)
        s->canvas = *s->opt.canvas;
    else if ((st = rs_synth_canvas_for_lens(&s->canvas, &camera->lensmodel, camera->intrinsics, width, height,
                                            s->opt.canvas_scale > 1 ? s->opt.canvas_scale : 1, err)))
        return st;
    if ((st = rs_synth_povcam_for_canvas(&s->cam, &s->canvas, camera->rt_cam_enu, err))) return st;
    if (s->opt.background_path) {
        if ((st = rs_image_read(bg, s->opt.background_path, err))) return st;
        if (bg->width != width || bg->height != height)
            return rs_err_set(err, RS_ERR_INVALID, "%s: the background is %dx%d, the camera %dx%d",
                              s->opt.background_path, bg->width, bg->height, width, height);
    }
    out->width = width;
    out->height = height;
    out->Nvehicles = N;
    out->ids = calloc((size_t)width * height, sizeof(uint16_t));
    out->visible = calloc((size_t)(N > 0 ? N : 1), 1);
    s->include = calloc((size_t)(N > 0 ? N : 1), 1);
    s->rects = calloc((size_t)(N > 0 ? N : 1), sizeof(*s->rects));
    s->reach = calloc((size_t)(N > 0 ? N : 1), sizeof(*s->reach));
    if (!out->ids || !out->visible || !s->include || !s->rects || !s->reach)
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    return rs_image_alloc(&out->composite, width, height, 3, err);
}

rs_status rs_synth_render(rs_synth_render_result *out, const char *out_dir, const rs_camera *camera,
                          const double ground_normal_enu[3], double ground_offset_m, const rs_synth_prepared *vehicles,
                          const rs_synth_render_options *opt_in, rs_err *err)
{
    memset(out, 0, sizeof(*out));
    render_state s = {.out_dir = out_dir,
                      .camera = camera,
                      .ground_normal_enu = ground_normal_enu,
                      .ground_offset_m = ground_offset_m,
                      .vehicles = vehicles};
    if (opt_in)
        s.opt = *opt_in;
    else
        rs_synth_render_options_default(&s.opt);
    s.povray = rs_synth_povray_exe(s.opt.povray);
    rs_image bg = {0}, rgba = {0}, idimg = {0}, frac = {0};
    rs_status st = render_setup(&s, &bg, out, err);
    if (st) goto done;
    render_cull(&s, out);
    const bool run = out->Nrendered > 0 || s.opt.scene.Npins > 0 || s.ground_drawn;
    if (!run) {
        for (int k = 0; k < 4; k++) out->region[k] = -1;
        if ((st = rs_image_alloc(&out->rgba, camera->width, camera->height, 4, err))) goto done;
    } else {
        if ((st = rs_io_mkdir_p(out_dir, err)) || (st = rs_synth_povray_write_conf(out_dir, err)) ||
            (st = rs_synth_scene_write_textures(out_dir, vehicles, err)) ||
            (st = write_env_map(&s.opt, out_dir, err)) || (st = render_canvas(&rgba, &idimg, &frac, &s, out, err)) ||
            (st = render_into_lens(out, &rgba, &idimg, &frac, &s, err)))
            goto done;
    }
    // 4. Composite
    if ((st = composite(out, s.opt.background_path ? &bg : NULL, &s.opt, err))) goto done;
    if (s.opt.write_files && ((st = rs_io_mkdir_p(out_dir, err)) || (st = write_outputs(out_dir, out, err)))) goto done;
done:
    if (!s.opt.keep_files) rs_synth_povray_remove_work(out_dir), rs_synth_scene_remove_textures(out_dir, vehicles);
    free_shadow_vehicles(&s.svehicles, s.sowned);
    rs_image_free(&s.mirror);
    rs_image_free(&s.headlights);
    rs_image_free(&bg);
    rs_image_free(&rgba);
    rs_image_free(&idimg);
    rs_image_free(&frac);
    free(s.include);
    free(s.rects);
    free(s.reach);
    if (st) rs_synth_render_result_free(out);
    return st;
}

rs_status rs_synth_render_ids(uint16_t **ids, const rs_camera *camera, const rs_synth_canvas *canvas,
                              const float *canvas_map, const double ground_normal_enu[3], double ground_offset_m,
                              const rs_synth_prepared *vehicles, rs_err *err)
{
    *ids = NULL;
    if (canvas->fisheye_deg > 0)
        return rs_err_set(err, RS_ERR_INVALID, "the ID pass without POV-Ray needs a pinhole canvas, not a fisheye one");
    if (!canvas->identity && !canvas_map)
        return rs_err_set(err, RS_ERR_INVALID, "rs_synth_render_ids: a distorted lens needs its canvas map");
    const int region[4] = {0, 0, canvas->width - 1, canvas->height - 1};
    rs_image img = {0}, lens = {0};
    rs_synth_render_result r = {.width = camera->width, .height = camera->height};
    rs_status st = rs_synth_raster_ids(&img, canvas->fxycxy, canvas->width, canvas->height, camera->rt_cam_enu,
                                       vehicles, NULL, ground_normal_enu, ground_offset_m, region, err);
    if (!st && !canvas->identity) st = rs_synth_remap(&lens, &img, canvas_map, camera->width, camera->height, 0, err);
    if (!st && !(r.ids = calloc((size_t)camera->width * camera->height, sizeof(uint16_t))))
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) decode_ids(&r, canvas->identity ? &img : &lens, vehicles->N);
    rs_image_free(&img);
    rs_image_free(&lens);
    *ids = r.ids;
    return st;
}

rs_status rs_synth_render_write_labels(const char *out_dir, const rs_synth_render_result *r, const char *split,
                                       const rs_synth_label_options *lopt, const rs_camera *cam,
                                       const double ground_normal_enu[3], double ground_offset_m,
                                       const rs_synth_prepared *prepared, rs_err *err)
{
    const int N = prepared->N;
    const size_t n = (size_t)(N > 0 ? N : 1);
    double *up = malloc(n * sizeof(double));
    rs_synth_mesh *meshes = malloc(n * sizeof(rs_synth_mesh));
    const char **ids = malloc(n * sizeof(char *));
    rs_synth_label *labels = NULL;
    char *folder = NULL, *image = NULL;
    rs_status st = RS_OK;
    if (!up || !meshes || !ids) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    for (int i = 0; i < N; i++) {
        const rs_synth_vehicle *v = &prepared->v[i];
        up[i] = rs_synth_ground_up_m(ground_normal_enu, ground_offset_m, v->e_m, v->n_m);
        meshes[i] = prepared->meshes[prepared->imesh[i]]; // shallow: borrowed arrays
        ids[i] = v->id;
    }
    const rs_synth_label_input lin = {
        .cam = cam, .vehicles = prepared->v, .Nvehicles = N, .up_m = up, .meshes = meshes, .id_image = r->ids};
    if ((st = rs_synth_labels_compute(&labels, &lin, err))) goto done;
    const rs_synth_label_image img = {.file_name = "image.png",
                                      .width = r->width,
                                      .height = r->height,
                                      .labels = labels,
                                      .Nlabels = N,
                                      .vehicle_ids = ids};
    if ((st = rs_synth_labels_write_coco(out_dir, split, &img, 1, lopt, err)) ||
        (st = rs_synth_labels_write_yolo(out_dir, split, &img, 1, lopt, err)) ||
        (st = rs_synth_labels_write_kitti(out_dir, &img, 1, lopt, err)))
        goto done;
    folder = rs_io_join(out_dir, split);
    image = folder ? rs_io_join(folder, "image.png") : NULL;
    st = image ? rs_image_write(image, &r->composite, 8, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
done:
    free(up);
    free(meshes);
    free(ids);
    free(labels);
    free(folder);
    free(image);
    return st;
}
