// rs_synth_raster.h -- the object-ID and shadow passes without POV-Ray: the vehicles' meshes
// rasterised at the canvas's pixel centres (issue 18's cost: those two povray processes were
// 0.3 of the 0.86 CPU s of a dataset image; docs/fleet.md, "Cost", D).
//
// The object-ID pass. POV-Ray's (rs_synth_scene.h, RS_SYNTH_PASS_ID) shoots one ray per pixel
// centre through the canvas pinhole (rs_synth_camera.h: pixel (i, j) looks along mrcal's pinhole
// ray of (u, v) = (i, j)) and takes the first triangle it meets: its vehicle's index + 1 as 8-bit
// R + 256 G. Here every triangle of each included vehicle's mesh, with its vertices and placement
// rounded exactly as the scene text writes them (vertices to 1e-5 m, yaw to 1e-9 deg, position
// to 1e-6 m: rs_synth_fleet_write_merged, rs_synth_fleet_write_placement), is clipped to
// z_cam >= 1e-6 m, projected through the same pinhole and filled at the pixel centres inside it
// (edges inclusive), the nearest surface winning (1/z interpolated in the image, exact for a
// plane). The two agree except where a pixel centre lies within rounding (about 1e-10 px) of a
// silhouette edge, or two vehicles' surfaces are equally near: tests/synth/povray/test_ids_raster.c
// compares them with the real POV-Ray. No ground: where the ground can hide part of a vehicle
// (rs_synth_scene_ground_occludes) the caller has POV-Ray render the pass, with the ground plane.
//
// The shadow pass. What POV-Ray's shadow pass gives (rs_synth_scene.h: the lit fraction of the
// ground, sum of irradiance x max(0, n . d) over the lights whose ray from the ground point is not
// blocked by a vehicle, over the same sum with none blocked), computed exactly at every canvas
// pixel: a parallel light's shadow of a closed mesh on a plane is the union of its triangles'
// shadows, so each triangle is projected onto the ground plane along the light (a vertex below
// the plane taken where it is; no culling of the faces turned away, for open user meshes), that
// ground triangle projected into the canvas
// and filled, marking the pixels whose ground point that light does not reach. Full resolution,
// no region: POV-Ray's pass was rendered at half resolution in a region and interpolated.
#pragma once
#include <stdint.h>

#include "core/rs_image.h"
#include "core/rs_status.h"
#include "synth/povray/rs_synth_scene.h"

#ifdef __cplusplus
extern "C" {
#endif

// The object-ID pass.
// out: *ids, (height, width, 3) float as rs_image_read returns the ID pass's 8-bit PNG: R = (k+1)
//      & 255 over 255, G = (k+1) >> 8 over 255 for vehicle k, 0 elsewhere; pixels outside region
//      are 0 (as the region render leaves them). Allocated here; free with rs_image_free.
// in:  fxycxy (4,) the canvas pinhole, width x height its size; rt_cam_enu (6,) the pose;
//      vehicles (prepared), include (N,) or NULL (all); the ground plane that places them
//      (rs_synth_ground_up_m); region (4,) x0, y0, x1, y1 inclusive, canvas pixels.
// Errors: RS_ERR_NOMEM, RS_ERR_INVALID (more than 65,534 vehicles, a bad size).
rs_status rs_synth_raster_ids( // out
    rs_image *ids,
    // in
    const double fxycxy[4], int width, int height, const double rt_cam_enu[6], const rs_synth_prepared *vehicles,
    const uint8_t *include, const double ground_normal_enu[3], double ground_offset_m, const int region[4],
    rs_err *err);

// The shadow pass.
// out: *frac, (height, width, 1): the lit fraction of the ground seen at each canvas pixel, in
//      [0, 1]; 1 where no shadow falls (and above the horizon). Free with rs_image_free.
// in:  as above; lights (Nlights <= 8,) the scene's (rs_synth_scene_lights); ground plane
//      n . p = offset (ENU, n any length). The vehicles are the shadow pass's (coarse meshes).
// Errors: RS_ERR_NOMEM, RS_ERR_INVALID (more than 8 lights).
rs_status rs_synth_raster_shadow( // out
    rs_image *frac,
    // in
    const double fxycxy[4], int width, int height, const double rt_cam_enu[6], const rs_synth_prepared *vehicles,
    const uint8_t *include, const double ground_normal_enu[3], double ground_offset_m, const rs_synth_light *lights,
    int Nlights, rs_err *err);

#ifdef __cplusplus
}
#endif
