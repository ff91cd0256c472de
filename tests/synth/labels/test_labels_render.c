// tests/synth/labels/test_labels_render.c -- labels against the real POV-Ray's object-ID pass (issue 6,
// "Done when"): a scene of procedural vehicles rendered by rs_synth_render (SCENE's code), its
// ID image fed to rs_synth_labels_compute with the same meshes. Checked for a pinhole, an
// OPENCV8 camera and a 1280x960 fisheye (CAHVORE at linearity 0, f = 340 px, Kannala-Brandt k1
// 0.02, k2 -0.004: rendered on the fisheye canvas, synth/povray/rs_synth_camera.h):
//   - every visible box equals the bounding box of its vehicle's ID pixels (counted here);
//   - the visible box lies inside the projected 3D box (body box) within 1 px: POV-Ray's camera
//     and mrcal's projection agree;
//   - a car hidden behind a bus: 0 visible pixels, visibility 0, no visible box;
//   - unoccluded vehicles: ID pixels / mesh pixels rasterised through mrcal within 0.2 % of 1
//     (pinhole; measured: equal) or 3 % (OPENCV8, whose ID image is resampled nearest-neighbour
//     from a pinhole canvas; measured <= 1.3 %), i.e. the labels' own silhouette agrees with
//     what POV-Ray drew, which also proves the mesh is not mirrored or misplaced;
//   - a vehicle cut by the image border has truncation > 0; on the fisheye instead, a vehicle
//     whose footprint centre lies behind the image plane (z_cam < 0, more than 90 degrees off
//     the axis) is labelled and its visible box is its ID pixels' box.
// Exit 77 when povray is missing. usage: test_labels_render OUTDIR
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/rs_pose.h"
#include "synth/labels/rs_synth_labels.h"
#include "synth/povray/rs_synth_render.h"
#include "synth/povray/rs_synth_scene.h"
#include "tests/synth/test_fleet_check.h"

enum { PINHOLE, OPENCV8, FISHEYE };

static int run(const char *outdir, const char *lens_name, int lens)
{
    const int opencv8 = lens != PINHOLE; // the distorted lenses' tolerances
    double intr[12] = {400, 402, 161.5, 118.5, -0.08, 0.03, 2e-4, -1e-4, 0, 0, 0, 0};
    const double fisheye[12] = {340, 340, 641.3, 478.2, 0, 0, 0, 0.02, -0.004, 0, 0, 0};
    rs_camera cam = {0};
    cam.lensmodel.type = lens == OPENCV8 ? MRCAL_LENSMODEL_OPENCV8 : MRCAL_LENSMODEL_PINHOLE;
    cam.intrinsics = intr;
    cam.Nintrinsics = lens == OPENCV8 ? 12 : 4;
    cam.width = 320, cam.height = 240;
    if (lens == FISHEYE) {
        memcpy(intr, fisheye, sizeof(intr));
        cam.lensmodel.type = MRCAL_LENSMODEL_CAHVORE;
        cam.lensmodel.LENSMODEL_CAHVORE__config.linearity = 0;
        cam.Nintrinsics = 12;
        cam.width = 1280, cam.height = 960;
    }
    double C[3] = {0, 0, 8};
    rs_pose_rt_from_ypr(cam.rt_cam_enu, (const double[3]){10, lens == FISHEYE ? -30 : -20, 0},
                        C); // 8 m up, yaw 10, 20 (fisheye 30) deg down

    // bus broadside at n = 20; a sedan right behind it (hidden); free vehicles; one cut by the
    // left border
    rs_synth_vehicle v[6] = {
        {.cls = RS_SYNTH_BUS,
         .e_m = 3,
         .n_m = 20,
         .yaw_deg = 90,
         .length_m = 12,
         .width_m = 2.5,
         .height_m = 3.2,
         .variant = 1},
        {.cls = RS_SYNTH_SEDAN,
         .e_m = 3,
         .n_m = 26,
         .yaw_deg = 90,
         .length_m = 4.2,
         .width_m = 1.8,
         .height_m = 1.45,
         .variant = 2},
        {.cls = RS_SYNTH_SUV, .e_m = 9, .n_m = 14, .yaw_deg = 20, .variant = 3},
        {.cls = RS_SYNTH_HATCHBACK, .e_m = -1, .n_m = 13, .yaw_deg = 200, .variant = 4},
        {.cls = RS_SYNTH_VAN, .e_m = 17, .n_m = 27, .yaw_deg = 300, .variant = 5},
        {.cls = RS_SYNTH_SEDAN, .e_m = -5.2, .n_m = 17, .yaw_deg = 0, .variant = 6},
    };
    int N = 6;
    if (lens == FISHEYE) // to the side and behind the camera: more than 90 degrees off the axis
        v[5].e_m = 9, v[5].n_m = -7, v[5].yaw_deg = 0;
    for (int k = 0; k < N; k++) v[k].rgb[0] = v[k].rgb[1] = v[k].rgb[2] = -1;
    rs_err err = {0};
    rs_synth_prepared prep = {0};
    if (rs_synth_prepare(&prep, v, NULL, N, &err)) {
        fprintf(stderr, "prepare: %s\n", err.msg);
        return 1;
    }
    double normal[3] = {0, 0, 1}, offset = 0, up[6];
    rs_synth_mesh meshes[6];
    for (int k = 0; k < N; k++) {
        up[k] = rs_synth_ground_up_m(normal, offset, prep.v[k].e_m, prep.v[k].n_m);
        meshes[k] = prep.meshes[prep.imesh[k]];
    }
    rs_synth_render_options ropt;
    rs_synth_render_options_default(&ropt);
    rs_synth_render_result r = {0};
    char dir[4096];
    snprintf(dir, sizeof dir, "%s/%s", outdir, lens_name);
    rs_status st = rs_synth_render(&r, dir, &cam, normal, offset, &prep, &ropt, &err);
    if (st) {
        fprintf(stderr, "render: %s\n", err.msg);
        rs_synth_prepared_free(&prep);
        return 1;
    }
    rs_synth_label *labels = NULL;
    st = rs_synth_labels_compute(
        &labels,
        &(rs_synth_label_input){
            .cam = &cam, .vehicles = prep.v, .Nvehicles = N, .up_m = up, .meshes = meshes, .id_image = r.ids},
        &err);
    CHECK(st == RS_OK, "labels: %s", err.msg);
    for (int k = 0; k < N && labels; k++) {
        const rs_synth_label *L = &labels[k];
        long n = 0;
        int bb[4] = {cam.width, cam.height, -1, -1};
        for (int j = 0; j < cam.height; j++)
            for (int i = 0; i < cam.width; i++)
                if (r.ids[j * cam.width + i] == k + 1) {
                    n++;
                    if (i < bb[0]) bb[0] = i;
                    if (j < bb[1]) bb[1] = j;
                    if (i > bb[2]) bb[2] = i;
                    if (j > bb[3]) bb[3] = j;
                }
        CHECK(L->visible_px == n, "%s vehicle %d: visible_px %ld, ID pixels %ld", lens_name, k, L->visible_px, n);
        if (n > 0) {
            double want[4] = {bb[0] - 0.5, bb[1] - 0.5, bb[2] + 0.5, bb[3] + 0.5};
            CHECK(memcmp(want, L->visible_box_px, sizeof want) == 0,
                  "%s vehicle %d: visible box (%g %g %g %g) vs ID pixels (%g %g %g %g)", lens_name, k,
                  L->visible_box_px[0], L->visible_box_px[1], L->visible_box_px[2], L->visible_box_px[3], want[0],
                  want[1], want[2], want[3]);
            CHECK(L->visible_box_px[0] >= L->body_box_px[0] - 1 && L->visible_box_px[1] >= L->body_box_px[1] - 1 &&
                      L->visible_box_px[2] <= L->body_box_px[2] + 1 && L->visible_box_px[3] <= L->body_box_px[3] + 1,
                  "%s vehicle %d: visible box (%g %g %g %g) outside the body box (%g %g %g %g)", lens_name, k,
                  L->visible_box_px[0], L->visible_box_px[1], L->visible_box_px[2], L->visible_box_px[3],
                  L->body_box_px[0], L->body_box_px[1], L->body_box_px[2], L->body_box_px[3]);
        }
        const double *b = L->bottom_center_cam_m;
        printf("%s vehicle %d (%s): visible %ld of %ld px, visibility %.4f, truncation %.3f, %.1f deg off the axis\n",
               lens_name, k, rs_synth_class_name(L->cls), L->visible_px, L->full_px, L->visibility, L->truncation,
               atan2(hypot(b[0], b[1]), b[2]) * 180 / M_PI);
    }
    if (labels) {
        CHECK(labels[1].visible_px == 0 && labels[1].visibility == 0 && isnan(labels[1].visible_box_px[0]),
              "%s: the sedan behind the bus is visible (%ld px)", lens_name, labels[1].visible_px);
        for (int k = 2; k <= 4; k++)
            CHECK(fabs(labels[k].visibility - 1) < (opencv8 ? 0.03 : 0.002) &&
                      labels[k].visible_px <= labels[k].full_px * (opencv8 ? 1.03 : 1.002),
                  "%s vehicle %d: unoccluded, visibility %.4f (ID %ld px, mesh %ld px)", lens_name, k,
                  labels[k].visibility, labels[k].visible_px, labels[k].full_px);
        if (lens != FISHEYE)
            CHECK(labels[5].truncation > 0 && labels[5].in_image,
                  "%s: vehicle 5 should be cut by the left border (truncation %g)", lens_name, labels[5].truncation);
        else
            CHECK(labels[5].bottom_center_cam_m[2] < 0 && labels[5].in_image && labels[5].visible_px > 100 &&
                      isfinite(labels[5].bottom_center_px[0]),
                  "%s: vehicle 5 behind the image plane (z_cam %g m) should be seen: in image %d, %ld px", lens_name,
                  labels[5].bottom_center_cam_m[2], labels[5].in_image, labels[5].visible_px);
    }
    free(labels);
    rs_synth_render_result_free(&r);
    rs_synth_prepared_free(&prep);
    return 0;
}

int main(int argc, char **argv)
{
    const char *outdir = argc > 1 ? argv[1] : ".";
    const char *povray = getenv("ROADSIDE_POVRAY");
    if (!povray && system("command -v povray > /dev/null 2>&1") != 0) {
        printf("povray missing: skipped\n");
        return 77;
    }
    int rc = run(outdir, "labels_render_pinhole", PINHOLE);
    if (!rc) rc = run(outdir, "labels_render_opencv8", OPENCV8);
    if (!rc) rc = run(outdir, "labels_render_fisheye", FISHEYE);
    if (failures) fprintf(stderr, "%d failures (fixed scene, no randomness)\n", failures);
    return rc || failures ? 1 : 0;
}
