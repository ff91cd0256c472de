// rs_synth_ids.h -- the object-ID pass without POV-Ray: the vehicles' meshes rasterised with a
// depth buffer at the canvas's pixel centres, the image the ID pass's povray process would
// write (issue 18's cost: that process was a fifth of the CPU of a dataset image; docs/fleet.md,
// "Cost", D).
//
// Method. POV-Ray's ID pass (rs_synth_scene.h, RS_SYNTH_PASS_ID) shoots one ray per pixel
// centre through the canvas pinhole (rs_synth_camera.h: pixel (i, j) looks along mrcal's
// pinhole ray of (u, v) = (i, j)) and takes the first triangle it meets: its vehicle's index + 1
// as 8-bit R + 256 G. Here every triangle of each included vehicle's mesh, with its vertices and
// placement rounded exactly as the scene text writes them (vertices to 1e-5 m, yaw to 1e-9 deg,
// position to 1e-6 m: rs_synth_fleet_write_merged, rs_synth_fleet_write_placement), is clipped to
// z_cam >= 1e-6 m, projected through the same pinhole and filled at the pixel centres inside it
// (edges inclusive), the nearest surface winning (1/z interpolated in the image, exact for a
// plane). The two agree except where a pixel centre lies within rounding (about 1e-10 px) of a
// silhouette edge, or two vehicles' surfaces are equally near: tests/synth/test_ids_raster.c
// compares them with the real POV-Ray.
//
// Limits: no ground. Where the ground can hide part of a vehicle (rs_synth_scene_ground_occludes)
// the caller renders the ID pass with POV-Ray instead, whose scene then holds the ground plane.
#pragma once
#include <stdint.h>

#include "core/rs_image.h"
#include "core/rs_status.h"
#include "synth/rs_synth_scene.h"

#ifdef __cplusplus
extern "C" {
#endif

// out: *ids, (height, width, 3) float as rs_image_read returns the ID pass's 8-bit PNG: R = (k+1)
//      & 255 over 255, G = (k+1) >> 8 over 255 for vehicle k, 0 elsewhere; pixels outside region
//      are 0 (as the region render leaves them). Allocated here; free with rs_image_free.
// in:  fxycxy (4,) the canvas pinhole, width x height its size; rt_cam_enu (6,) the pose;
//      vehicles (prepared), include (N,) or NULL (all); the ground plane that places them
//      (rs_synth_ground_up_m); region (4,) x0, y0, x1, y1 inclusive, canvas pixels.
// Errors: RS_ERR_NOMEM, RS_ERR_INVALID (more than 65,534 vehicles, a bad size).
rs_status rs_synth_ids_raster( // out
    rs_image *ids,
    // in
    const double fxycxy[4], int width, int height, const double rt_cam_enu[6], const rs_synth_prepared *vehicles,
    const uint8_t *include, const double ground_normal_enu[3], double ground_offset_m, const int region[4],
    rs_err *err);

#ifdef __cplusplus
}
#endif
