// tests/synth/povray/test_shadow_coarse.c -- issue 18's speed bar: the savings of the ID and shadow
// passes keep the labels and the shadows right. Real POV-Ray, pinhole 640 x 400, seven
// vehicles of every size (car to bus, a motorcycle) on flat ground, sun at azimuth 100 and
// elevation 35 deg (shadows across the view) under a clear sky.
//
// The oracles are the renders as they were before the savings, made here with the same scene
// writer:
//   shadow  the shadow pass rendered at the canvas's full resolution on every vehicle's FULL
//           mesh, the vehicles invisible (rs_synth_scene_write, then the vehicles' green marks
//           made no_image again), turned into the lit fraction as rs_synth_render does.
//           rs_synth_render's shadow (rasterised by roadside on the coarse meshes at full
//           resolution, synth/povray/rs_synth_raster.h; before, POV-Ray's pass at half resolution,
//           interpolated) must agree with it: no pixel changes side of the sun's shadow more
//           than 1 px from the reference's boundary; the sun's shadow covers the same area
//           within 1 %; more than 2 px from that boundary at most 0.05 % of the ground pixels
//           differ by more than a sky light's share (0.1: the coarse meshes' sky shadows); the
//           mean |difference| over the ground is below 0.002. (Measured: 36 pixels change side,
//           none more than 0 px from the boundary; 0.30 %; 0.002 %; 0.00024. POV-Ray's half-
//           resolution pass gave 562, 1 px; 0.41 %; 0.107 %; 0.0049, under bounds of 2 %,
//           0.2 %, 0.01.)
//   colour  the colour pass as a frame before it (16-bit RGBA PNG): rs_synth_render's (16-bit PPM,
//           its alpha from the ID pass) must give the same alpha everywhere and the same colours
//           within 1e-3 on all but 0.2 % of the vehicle pixels (POV-Ray's own irreproducibility,
//           as in test_render.py).
//   ids     the ID pass rendered on the union of each vehicle's parts with normals, as a frame
//           after the colour pass (rs_synth_scene_write_frames, 16-bit PNG), with the ground
//           plane as an occluder: rs_synth_render's ID pass (rasterised by roadside from the
//           same triangles, synth/povray/rs_synth_raster.h) must be identical, pixel for pixel.
// Exit 77 when povray is missing. usage: test_shadow_coarse OUTDIR
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "core/rs_pose.h"
#include "synth/povray/rs_synth_render.h"
#include "synth/povray/rs_synth_scene.h"
#include "tests/synth/test_fleet_check.h"

enum { W = 640, H = 400 };
#define SUN_AZ  100.0
#define SUN_EL  35.0
#define TOL     0.1 // lit fraction: more than a sky light's share (0.074 here)
#define EDGE_PX 1   // pixels

// Runs povray on DIR/NAME.ini (written by the caller) over the whole image.
static int run(const char *dir, const char *ini)
{
    const char *povray = rs_synth_povray_exe(NULL);
    const char *args[] = {ini, "+WT1"};
    rs_err err = {0};
    if (rs_synth_povray_run(povray, dir, args, 2, NULL, &err)) {
        fprintf(stderr, "povray: %s\n", err.msg);
        return 1;
    }
    return 0;
}

// Writes DIR/NAME.pov with `passes` (one: rs_synth_scene_write; more: frames) and its .ini.
static int write_scene(const char *dir, const char *name, const rs_synth_povcam *pc, const double fxy[2],
                       const rs_synth_prepared *prep, const rs_synth_scene_options *passes, int Npasses)
{
    char pov[4096], ini[4096];
    snprintf(pov, sizeof pov, "%s/%s.pov", dir, name);
    snprintf(ini, sizeof ini, "%s/%s.ini", dir, name);
    const double normal[3] = {0, 0, 1};
    rs_err err = {0};
    FILE *f = fopen(pov, "w");
    if (!f) return 1;
    rs_status st = Npasses == 1 ? rs_synth_scene_write(f, pc, fxy, normal, 0, prep, &passes[0], &err)
                                : rs_synth_scene_write_frames(f, pc, fxy, normal, 0, prep, passes, Npasses, &err);
    fclose(f);
    if (!st)
        st = Npasses == 1 ? rs_synth_scene_write_ini(ini, pov, pc, passes[0].pass, 0, &err)
                          : rs_synth_scene_write_ini_frames(ini, pov, pc, Npasses, 0, &err);
    if (st) fprintf(stderr, "%s: %s\n", name, err.msg);
    return st != RS_OK;
}

// Puts back into DIR/NAME what the scene writer wrote before the savings: every `from` (at least
// one) replaced by `to`.
static int as_it_was(const char *dir, const char *name, const char *from, const char *to)
{
    char path[4200], *text = NULL;
    size_t len = 0;
    rs_err err = {0};
    snprintf(path, sizeof path, "%s/%s", dir, name);
    if (rs_io_read_file(&text, &len, path, &err)) return fprintf(stderr, "%s\n", err.msg), 1;
    CHECK(strstr(text, from), "%s: \"%s\" expected", name, from);
    FILE *f = fopen(path, "w");
    for (char *p = text, *at; f && *p; p = at ? at + strlen(from) : p + strlen(p)) {
        at = strstr(p, from);
        fwrite(p, 1, at ? (size_t)(at - p) : strlen(p), f);
        if (at) fputs(to, f);
    }
    if (f) fclose(f);
    free(text);
    return !f;
}

// The ID pass's ground plane, an occluder of value 0, which the writer now leaves out where it
// hides nothing; the shadow pass's vehicles, invisible (no_image), now green marks.
#define NO_GROUND "// no ground: every vehicle and the camera are above it, it would hide nothing\n"
#define GROUND    "plane { <0, 1, 0>, 0\n  texture { pigment { rgb 0 } finish { emission 0 ambient 0 diffuse 0 } }\n}\n"
#define MARK \
    "\n  texture { pigment { rgb <0, 1, 0> } finish { emission 1 ambient 0 diffuse 0 specular 0 } } no_reflection"
#define INVISIBLE " no_image no_reflection"

int main(int argc, char **argv)
{
    const char *out = argc > 1 ? argv[1] : ".";
    if (system("command -v povray > /dev/null 2>&1") != 0) {
        fprintf(stderr, "povray missing: skipped\n");
        return 77;
    }
    char dir[4096], rdir[4096];
    snprintf(dir, sizeof dir, "%s/shadow_coarse", out);
    snprintf(rdir, sizeof rdir, "%s/shadow_coarse/render", out);
    rs_err err = {0};
    if (rs_io_mkdir_p(dir, &err)) return 1;
    double intr[4] = {520, 520, (W - 1) / 2.0, (H - 1) / 2.0};
    rs_camera cam = {0};
    cam.lensmodel.type = MRCAL_LENSMODEL_PINHOLE;
    cam.intrinsics = intr;
    cam.Nintrinsics = 4;
    cam.width = W, cam.height = H;
    // a camera 7 m up, 14 m south of the vehicles, looking north 22 degrees down
    rs_pose_rt_from_ypr(cam.rt_cam_enu, (const double[3]){0, -22, 0}, (const double[3]){0, -14, 7});
    const rs_synth_vehicle v[] = {
        {.cls = RS_SYNTH_SEDAN, .e_m = -5.5, .n_m = -2, .yaw_deg = 90, .variant = 1, .rgb = {0.5, 0.5, 0.5}},
        {.cls = RS_SYNTH_SUV, .e_m = 0.5, .n_m = -2.5, .yaw_deg = 80, .variant = 2, .rgb = {0.2, 0.3, 0.6}},
        {.cls = RS_SYNTH_VAN, .e_m = 6, .n_m = -1, .yaw_deg = 120, .variant = 3, .rgb = {0.8, 0.8, 0.8}},
        {.cls = RS_SYNTH_BUS, .e_m = -4, .n_m = 6, .yaw_deg = 95, .variant = 4, .rgb = {0.7, 0.2, 0.1}},
        {.cls = RS_SYNTH_PICKUP, .e_m = 5, .n_m = 6, .yaw_deg = 260, .variant = 5, .rgb = {0.1, 0.1, 0.1}},
        {.cls = RS_SYNTH_MOTORCYCLE, .e_m = -1.5, .n_m = 2, .yaw_deg = 30, .variant = 6, .rgb = {0.6, 0.1, 0.1}},
        {.cls = RS_SYNTH_HATCHBACK, .e_m = 1.5, .n_m = 11, .yaw_deg = 180, .variant = 7, .rgb = {0.9, 0.9, 0.9}},
    };
    const int N = (int)(sizeof v / sizeof v[0]);
    rs_synth_prepared prep = {0};
    if (rs_synth_prepare(&prep, v, NULL, N, &err)) {
        fprintf(stderr, "prepare: %s\n", err.msg);
        return 1;
    }
    // rs_synth_render's passes (shadow and ids rasterised by roadside, colour by POV-Ray)
    rs_synth_render_options ropt;
    rs_synth_render_options_default(&ropt);
    ropt.write_files = false;
    ropt.shadow = true;
    ropt.scene.ground_visible = false;
    ropt.scene.sun_azimuth_deg = SUN_AZ;
    ropt.scene.sun_elevation_deg = SUN_EL;
    const double normal[3] = {0, 0, 1};
    rs_synth_render_result r = {0};
    if (rs_synth_render(&r, rdir, &cam, normal, 0, &prep, &ropt, &err)) {
        fprintf(stderr, "render: %s\n", err.msg);
        return 1;
    }
    CHECK(r.Nrendered == N && r.shadow, "%d of %d vehicles rendered, shadow %s", r.Nrendered, N,
          r.shadow ? "made" : "missing");
    // the references, as before the savings
    rs_synth_povcam pc;
    if (rs_synth_povcam_init(&pc, intr, W, H, cam.rt_cam_enu, &err)) return 1;
    rs_synth_scene_options passes[2];
    passes[0] = ropt.scene;
    passes[0].pass = RS_SYNTH_PASS_COLOUR;
    passes[1] = ropt.scene;
    passes[1].pass = RS_SYNTH_PASS_ID;
    rs_synth_scene_options sh = ropt.scene;
    sh.pass = RS_SYNTH_PASS_SHADOW;
    if (write_scene(dir, "ref_shadow", &pc, intr, &prep, &sh, 1) ||
        write_scene(dir, "ref_frames", &pc, intr, &prep, passes, 2) ||
        as_it_was(dir, "ref_frames.pov", NO_GROUND, GROUND) || as_it_was(dir, "ref_shadow.pov", MARK, INVISIBLE) ||
        run(dir, "ref_shadow.ini") || run(dir, "ref_frames.ini"))
        return 1;
    rs_image ref = {0}, refid = {0}, refrgb = {0};
    char path[4200];
    snprintf(path, sizeof path, "%s/ref_shadow.png", dir);
    if (rs_image_read(&ref, path, &err)) return fprintf(stderr, "%s\n", err.msg), 1;
    snprintf(path, sizeof path, "%s/ref_frames2.png", dir);
    if (rs_image_read(&refid, path, &err)) return fprintf(stderr, "%s\n", err.msg), 1;
    snprintf(path, sizeof path, "%s/ref_frames1.png", dir);
    if (rs_image_read(&refrgb, path, &err)) return fprintf(stderr, "%s\n", err.msg), 1;
    // colour: the same values and the same alpha. POV-Ray itself is not bit-reproducible at a few
    // pixels (its shadow cache depends on the order of the pixels: region and full-frame renders
    // differ there), so as in test_render.py up to 0.2 % of the vehicle pixels may differ.
    long rgb_diff = 0, alpha_diff = 0, opaque = 0;
    for (int i = 0; i < W * H; i++) {
        const float *a = &refrgb.data[4 * (size_t)i], *b = &r.rgba.data[4 * (size_t)i];
        alpha_diff += a[3] != b[3];
        opaque += a[3] > 0;
        rgb_diff +=
            a[3] > 0 && (fabsf(a[0] - b[0]) > 1e-3f || fabsf(a[1] - b[1]) > 1e-3f || fabsf(a[2] - b[2]) > 1e-3f);
    }
    printf("colour: %ld alpha values differ from the colour pass as it was (16-bit RGBA PNG), %ld of %ld colours by "
           "more than 1e-3\n",
           alpha_diff, rgb_diff, opaque);
    CHECK(alpha_diff == 0, "%ld alpha values differ", alpha_diff);
    CHECK(rgb_diff <= 0.002 * opaque, "%ld of %ld colours differ", rgb_diff, opaque);
    // ids: identical
    long id_diff = 0, vehicle_px = 0;
    for (int i = 0; i < W * H; i++) {
        const float *px = &refid.data[(size_t)refid.channels * i];
        const long k = lroundf(px[0] * 255) + 256 * lroundf(px[1] * 255);
        id_diff += k != r.ids[i];
        vehicle_px += r.ids[i] != 0;
    }
    printf("ids: %ld vehicle pixels, %ld differ from the ID pass as it was (parts' meshes, ground plane)\n", vehicle_px,
           id_diff);
    CHECK(vehicle_px > 5000, "only %ld vehicle pixels", vehicle_px);
    CHECK(id_diff == 0, "%ld ID pixels differ", id_diff);
    // shadow: the reference's lit fraction (rs_synth_render's rule: value / unlit, 1 where transparent)
    rs_synth_light lights[RS_SYNTH_SKY_LIGHTS + 1];
    const int Nl = rs_synth_scene_lights(lights, &ropt.scene);
    const double unlit = rs_synth_scene_shadow_unlit(lights, Nl, normal);
    float *f = malloc(sizeof(float) * W * H);
    unsigned char *edge = calloc(W * H, 1);
    if (!f || !edge) return 1;
    for (int i = 0; i < W * H; i++) {
        const float *px = &ref.data[(size_t)ref.channels * i];
        const double x = px[3] <= 0 ? 1 : px[0] / unlit;
        f[i] = (float)(x < 0 ? 0 : x > 1 ? 1 : x);
    }
    // the boundary of the reference's sun shadow (lit fraction < 0.5): a pixel with a 4-neighbour
    // on the other side
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const bool in = f[y * W + x] < 0.5f;
            edge[y * W + x] =
                (x > 0 && (f[y * W + x - 1] < 0.5f) != in) || (x + 1 < W && (f[y * W + x + 1] < 0.5f) != in) ||
                (y > 0 && (f[(y - 1) * W + x] < 0.5f) != in) || (y + 1 < H && (f[(y + 1) * W + x] < 0.5f) != in);
        }
    long ground = 0, sun_ref = 0, sun_test = 0, disagree = 0, far_off = 0, soft = 0, soft_off = 0, boundary = 0;
    double sum_abs = 0, soft_max = 0;
    int max_dist = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            const int i = y * W + x;
            boundary += edge[i];
            if (r.ids[i] != 0) continue; // under a vehicle the shadow is never used
            const double d = fabs(r.shadow[i] - f[i]);
            ground++;
            sum_abs += d;
            sun_ref += f[i] < 0.5f, sun_test += r.shadow[i] < 0.5f;
            int dist = 0; // Chebyshev distance to the reference's sun boundary, up to 3 px
            for (bool found = false; !found && dist <= 3; dist += !found)
                for (int dy = -dist; dy <= dist && !found; dy++)
                    for (int dx = -dist; dx <= dist && !found; dx++) {
                        const int yy = y + dy, xx = x + dx;
                        found = yy >= 0 && yy < H && xx >= 0 && xx < W && edge[yy * W + xx];
                    }
            if (dist > 2) soft++, soft_off += d > TOL, soft_max = fmax(soft_max, d);
            if ((f[i] < 0.5f) == (r.shadow[i] < 0.5f)) continue;
            disagree++;
            max_dist = dist > max_dist ? dist : max_dist;
            far_off += dist > EDGE_PX;
        }
    const double area = sun_ref ? fabs((double)sun_test - sun_ref) / sun_ref : 1;
    printf("shadow: %ld ground pixels; sun shadow %ld px (reference) vs %ld (%.2f %%), boundary %ld px, %ld pixels "
           "on the other side, %ld of them more than %d px from the boundary (max %d); more than 2 px from it, %ld of "
           "%ld pixels (%.3f %%) differ by more than %.2f (max %.3f); mean |difference| %.5f\n",
           ground, sun_ref, sun_test, 100 * area, boundary, disagree, far_off, EDGE_PX, max_dist, soft_off, soft,
           soft ? 100.0 * soft_off / soft : 0, TOL, soft_max, ground ? sum_abs / ground : 0);
    CHECK(sun_ref > 2000 && soft > 100000, "only %ld pixels in the sun's shadow, %ld away from it", sun_ref, soft);
    CHECK(far_off == 0, "%ld pixels change sides of the sun's shadow more than %d px from its boundary", far_off,
          EDGE_PX);
    CHECK(area < 0.01, "the sun's shadow covers %ld px instead of %ld", sun_test, sun_ref);
    CHECK(soft && soft_off < 0.0005 * soft, "%ld of %ld pixels away from the sun's edge differ by more than %.2f",
          soft_off, soft, TOL);
    CHECK(ground && sum_abs / ground < 0.002, "mean |difference| %.5f", ground ? sum_abs / ground : 0);
    free(f);
    free(edge);
    rs_image_free(&ref);
    rs_image_free(&refid);
    rs_image_free(&refrgb);
    rs_synth_render_result_free(&r);
    rs_synth_prepared_free(&prep);
    return failures ? 1 : 0;
}
