// rs_synth_dataset_kitti.c -- the KITTI copy of `roadside synth`'s images
// (rs_synth_dataset_internal.h): KITTI's P2 is a pinhole, so an image through a lens with
// distortion is undistorted to the lens's pinhole core (same fx, fy, cx, cy and size) and
// labelled again through that core; the labels' 3D boxes go into the levelled (rectified) frame
// of rs_synth_labels_kitti_rect. Called by rs_synth_dataset_image.c; calls synth/labels,
// synth/backdrop's OpenCV shim (remap), core/.
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "core/rs_lens.h"
#include "synth/backdrop/rs_synth_opencv.h"
#include "synth/dataset/internal/rs_synth_dataset_internal.h"

rs_status rs_synth_dataset__prepare_kitti(rs_synth_dataset__camera *c, rs_err *err)
{
    if (c->have_kitti) return RS_OK;
    const rs_camera *cam = &c->cam;
    if (!mrcal_lensmodel_metadata(&cam->lensmodel).has_core)
        return rs_err_set(err, RS_ERR_UNSUPPORTED, "camera %s: KITTI: lens model without fx, fy, cx, cy", c->id);
    const mrcal_lensmodel_t pinhole = {.type = MRCAL_LENSMODEL_PINHOLE};
    rs_camera core = {0};
    rs_status st = rs_camera_init(&core, &pinhole, cam->intrinsics, cam->width, cam->height, err);
    if (st) return st;
    memcpy(core.rt_cam_enu, cam->rt_cam_enu, sizeof(core.rt_cam_enu));
    float *map = NULL;
    if (cam->lensmodel.type != MRCAL_LENSMODEL_PINHOLE) {
        const size_t n = (size_t)cam->width * (size_t)cam->height;
        mrcal_point3_t *v = malloc(n * sizeof(*v));
        mrcal_point2_t *q = malloc(n * sizeof(*q));
        map = malloc(2 * n * sizeof(float));
        const double *f = cam->intrinsics;
        if (!v || !q || !map) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        for (size_t i = 0; !st && i < n; i++) {
            const int u = (int)(i % (size_t)cam->width), w = (int)(i / (size_t)cam->width);
            v[i] = (mrcal_point3_t){.xyz = {(u - f[2]) / f[0], (w - f[3]) / f[1], 1}};
        }
        if (!st && !rs_lens_project(q, NULL, NULL, v, (int)n, &cam->lensmodel, cam->intrinsics))
            st = rs_err_set(err, RS_ERR_EXTERNAL, "camera %s: KITTI: mrcal_project failed", c->id);
        for (size_t i = 0; !st && i < n; i++) {
            map[2 * i] = (float)q[i].x;
            map[2 * i + 1] = (float)q[i].y;
        }
        free(v);
        free(q);
    }
    if (st) {
        free(map);
        rs_camera_free(&core);
        return st;
    }
    c->kitti_cam = core;
    c->kitti_map = map;
    c->have_kitti = true;
    return RS_OK;
}

// The ID pass undistorted like the image: nearest neighbour (IDs are labels, not intensities).
// out: *out (width x height) owned (free()); in: ids (height, width)
static rs_status undistort_ids(uint16_t **out, const rs_synth_dataset__camera *c, const uint16_t *ids, rs_err *err)
{
    const int W = c->cam.width, H = c->cam.height;
    const size_t n = (size_t)W * (size_t)H;
    rs_image src = {0}, dst = {0};
    rs_status st = rs_image_alloc(&src, W, H, 1, err);
    for (size_t i = 0; !st && i < n; i++) src.data[i] = (float)ids[i];
    if (!st) st = rs_synth_remap(&dst, &src, c->kitti_map, W, H, 0, err);
    *out = st ? NULL : malloc(n * sizeof(uint16_t));
    if (!st && !*out) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (size_t i = 0; !st && i < n; i++) (*out)[i] = (uint16_t)(dst.data[i] + 0.5f);
    rs_image_free(&src);
    rs_image_free(&dst);
    return st;
}

rs_status rs_synth_dataset__kitti_files(const rs_synth_dataset__run *d, int k, const rs_synth_dataset__camera *c,
                                        const char *image, const rs_image *composite, const uint16_t *ids,
                                        const rs_synth_label_input *lin, const rs_synth_label *run_labels,
                                        const unsigned char *kept, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    char rel[600], kitti_name[32];
    snprintf(kitti_name, sizeof(kitti_name), "%06d.png", k); // KITTI's numeric names
    rs_status st = c->have_kitti ? RS_OK : rs_err_set(err, RS_ERR_INVALID, "camera %s: KITTI not prepared", c->id);
    rs_image und = {0};
    uint16_t *und_ids = NULL;
    rs_synth_label *labels = NULL, *mine = NULL;
    double R0[9];
    // the image: undistorted to the pinhole core, or the composite itself
    snprintf(rel, sizeof(rel), "kitti/training/image_2/%s", kitti_name);
    char *kitti_image = rs_io_join(opt->out_dir, rel);
    if (!st && !kitti_image) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st && !c->kitti_map) st = rs_synth_dataset__link_into(d, image, rel, err);
    // the visible box needs the ID pass undistorted too; the other boxes come from geometry
    const bool visible_box = opt->bbox == RS_SYNTH_BBOX_VISIBLE;
    if (!st && c->kitti_map) {
        st = rs_synth_remap(&und, composite, c->kitti_map, c->cam.width, c->cam.height, 1, err);
        if (!st) st = rs_image_write(kitti_image, &und, 8, err);
        if (!st && ids && visible_box) st = undistort_ids(&und_ids, c, ids, err);
    }
    // the labels through the pinhole core (a pinhole lens: the run's labels are those). Without
    // the ID pass (not needed but for the visible box) no mesh is rasterised: the run's
    // visibility figures (of the same pixels, distorted) are kept instead
    rs_synth_label_input kin = *lin;
    kin.cam = &c->kitti_cam;
    kin.id_image = visible_box ? und_ids : NULL;
    kin.meshes = visible_box ? lin->meshes : NULL;
    kin.origin = NULL; // (latitude and longitude are not KITTI's)
    if (!st && c->kitti_map) st = rs_synth_labels_compute(&labels, &kin, err);
    const rs_synth_label *from = c->kitti_map ? labels : run_labels; // a pinhole: the run's own
    int Nmine = 0;
    if (!st && !(mine = malloc(sizeof(*mine) * (size_t)(lin->Nvehicles > 0 ? lin->Nvehicles : 1))))
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; !st && i < lin->Nvehicles; i++) {
        if (!kept[i]) continue;
        mine[Nmine] = from[i];
        if (c->kitti_map && !visible_box) { // (the run's: undistortion moves pixels, keeps vehicles)
            mine[Nmine].visible_px = run_labels[i].visible_px;
            mine[Nmine].full_px = run_labels[i].full_px;
            mine[Nmine].visibility = run_labels[i].visibility;
        }
        Nmine++;
    }
    if (!st) st = rs_synth_labels_kitti_rect(R0, NULL, &c->kitti_cam, err);
    const rs_synth_label_image kimg = {.file_name = kitti_name,
                                       .width = c->cam.width,
                                       .height = c->cam.height,
                                       .labels = mine,
                                       .Nlabels = Nmine,
                                       .R0_rect = R0};
    // the run's labels decided which vehicles; here only the box must exist in this image
    const rs_synth_label_options kopt = {.bbox = (rs_synth_bbox_kind)opt->bbox};
    char *kitti_dir = st ? NULL : rs_io_join(opt->out_dir, "kitti/training");
    if (!st && !kitti_dir) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) st = rs_synth_labels_write_kitti(kitti_dir, &kimg, 1, &kopt, err);
    snprintf(rel, sizeof(rel), "kitti/training/calib/%06d.txt", k);
    char *calib = st ? NULL : rs_io_join(opt->out_dir, rel);
    if (!st && !calib) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) st = rs_synth_labels_write_kitti_calib(calib, &c->kitti_cam, err);
    free(calib);
    free(kitti_dir);
    free(kitti_image);
    free(mine);
    free(labels);
    free(und_ids);
    rs_image_free(&und);
    return st;
}
