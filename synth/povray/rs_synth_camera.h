// rs_synth_camera.h -- the POV-Ray camera of a calibrated camera, and the pinhole canvas that
// carries a distorted lens.
//
// POV-Ray's world in roadside is <x, y, z> = <east, up, north> (docs/conventions.md), left-handed
// as POV-Ray is. The camera is written with explicit location, right, up and direction vectors
// (never look_at or angle) so that an off-centre principal point and fx != fy are exact.
//
// Method (docs/povray.md derives it and tests/synth/povray/test_pins.py checks it with the real povray):
// POV-Ray 3.7's perspective camera shoots, for the pixel in column i (0..W-1, left to right) and
// row j (0..H-1, top to bottom), without antialiasing, the ray
//     D = direction + x_s right + y_s up,  x_s = (i + 0.5)/W - 0.5,  y_s = 0.5 - (j + 0.5)/H.
// mrcal's pinhole pixel (u, v) = (i, j) (pixel (0,0) = centre of the top-left pixel) looks along
// v_cam = ((u - cx)/fx, (v - cy)/fy, 1). Matching the two for every (i, j):
//     right     = (W/fx)  x_cam
//     up        = -(H/fy) y_cam
//     direction = z_cam + ((W-1)/2 - cx)/fx x_cam + ((H-1)/2 - cy)/fy y_cam
// where x_cam, y_cam, z_cam are the camera axes in ENU (the rows of R(r_cam_enu)), converted to
// <e, u, n>; location = the camera centre -R^T t. Exact (to double rounding) for the pinhole core.
#pragma once
#include <stdio.h>

#include <mrcal/mrcal.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// A POV-Ray camera, vectors in POV-Ray's world <e, u, n>, metres: perspective (fisheye_deg = 0),
// or POV-Ray's fisheye (rs_synth_povcam_init_fisheye).
typedef struct {
    double location[3];  // (3,) camera centre
    double right[3];     // (3,) see above
    double up[3];        // (3,)
    double direction[3]; // (3,)
    int width, height;   // image size the vectors were derived for, pixels
    double fisheye_deg;  // 0: perspective; > 0: POV-Ray's fisheye camera of this full angle
} rs_synth_povcam;

// ENU <-> POV-Ray world: p_pov = (e, u, n). In-place safe.
void rs_synth_enu_to_pov(double p_pov[3], const double p_enu[3]);

// The POV-Ray camera that renders exactly what the pinhole (fx, fy, cx, cy) at pose rt_cam_enu
// sees in a width x height image.
// out: *cam
// in:  fxycxy (4,): fx, fy (> 0), cx, cy, pixels; width, height > 0; rt_cam_enu (6,)
// Returns RS_ERR_INVALID for non-positive or non-finite focal lengths or sizes.
rs_status rs_synth_povcam_init( // out
    rs_synth_povcam *cam,
    // in
    const double fxycxy[4], int width, int height, const double rt_cam_enu[6], rs_err *err);

// POV-Ray 3.7's fisheye camera looking along the camera's z axis, for a size x size image.
// Method (POV-Ray 3.7's tracepixel.cpp, checked by tests/synth/povray/test_pins.py): with unit
// right = x_cam, up = -y_cam, direction = z_cam, the pixel in column i, row j is traced along
//     x0 = 2 ((i + 0.5)/size - 0.5),  y0 = 2 (0.5 - (j + 0.5)/size),  rad = |(x0, y0)| <= 1
//     theta = rad angle/2,  v = sin(theta) (x0, y0)/rad . (right, up) + cos(theta) direction,
// i.e. the equidistant lens (rs_synth_canvas_project) with f = size / angle (radians) and the centre
// ((size - 1)/2, (size - 1)/2); pixels with rad > 1 are not traced (transparent).
// in:  angle_deg in (0, 360]; size > 0; rt_cam_enu (6,)
rs_status rs_synth_povcam_init_fisheye( // out
    rs_synth_povcam *cam,
    // in
    double angle_deg, int size, const double rt_cam_enu[6], rs_err *err);

// The perspective camera `in` cut to the rectangle `region` (x0, y0, x1, y1 inclusive, pixels of
// in's image, within it): a (x1 - x0 + 1) x (y1 - y0 + 1) image whose pixel (i, j) is traced along
// in's ray for pixel (x0 + i, y0 + j). From the ray formula above, with W' and H' the cut's size:
//     right' = (W'/W) right,  up' = (H'/H) up,
//     direction' = direction + (x0/W - 1/2 + W'/(2W)) right + (1/2 - y0/H - H'/(2H)) up.
// POV-Ray then traces and writes only the cut (its +SC/+EC region still writes the whole frame).
// out: *out; in: in (perspective, not fisheye), region (4,)
void rs_synth_povcam_crop(rs_synth_povcam *out, const rs_synth_povcam *in, const int region[4]);

// Writes "camera { perspective location ... right ... up ... direction ... }" (or "fisheye" with
// its "angle") with 17 significant digits. Returns RS_ERR_IO if the stream reports an error.
rs_status rs_synth_povcam_write(FILE *f, const rs_synth_povcam *cam, rs_err *err);

// The canvas that a distorted lens is rendered on before it is resampled into the lens: a pinhole,
// or for a lens that sees 80 degrees or more off its axis an equidistant fisheye (POV-Ray's
// fisheye camera, rs_synth_povcam_init_fisheye): pixel q = c + f theta (v_x, v_y)/|(v_x, v_y)| for
// a camera-frame direction v at theta off the axis, f = fxycxy[0] = fxycxy[1], c = fxycxy[2..3].
typedef struct {
    double fxycxy[4];   // (4,) canvas pinhole: the lens's fx, fy times `scale`; its own cx, cy
                        // (fisheye: f, f, (size - 1)/2, (size - 1)/2)
    int width, height;  // canvas size, pixels
    double scale;       // canvas pixels per pinhole-core pixel (>= 1: supersampled)
    int identity;       // 1 if the lens is LENSMODEL_PINHOLE and scale = 1: no resampling needed
    double fisheye_deg; // 0: a pinhole canvas; > 0: a fisheye canvas of this full angle, degrees
} rs_synth_canvas;

// The canvas pixel that sees the camera-frame direction v (any length): false when the canvas
// does not (behind a pinhole canvas, more than fisheye_deg/2 off a fisheye canvas's axis).
// out: q (2,); in: canvas, v (3,)
bool rs_synth_canvas_project(double q[2], const rs_synth_canvas *canvas, const double v[3]);

// The POV-Ray camera that renders `canvas` from the pose rt_cam_enu: perspective
// (rs_synth_povcam_init) or fisheye (rs_synth_povcam_init_fisheye).
rs_status rs_synth_povcam_for_canvas( // out
    rs_synth_povcam *cam,
    // in
    const rs_synth_canvas *canvas, const double rt_cam_enu[6], rs_err *err);

// Chooses the canvas that covers every pixel of the real lens: unprojects (rs_lens_unproject) the
// border of the width x height image densely (every pixel along the four edges, plus the
// centre) and takes the bounding box of their pinhole projections with a margin of 2 canvas
// pixels. For LENSMODEL_PINHOLE with scale 1 the canvas is the camera itself (identity = 1).
// A lens that maps part of the image more than 80 degrees off its axis (or behind the camera:
// a fisheye) gets a fisheye canvas instead: its angle twice the largest angle off the axis of
// the image's pixels (its border and a grid every 8 pixels; 180 degrees when a pixel has no
// direction: the lens's circle lies inside the image) plus 3 canvas pixels, at most 360; its f
// the largest of scale fx, scale fy and scale times the lens's radial pixels per radian over
// those pixels, its size even (docs/povray.md, "Fisheye lenses").
// in:  lensmodel, intrinsics (Nintrinsics,), width, height: the real camera
//      scale: canvas pixels per core pixel, >= 1 (1 is fine for the test suite; 2 gives sharper
//      resampling)
// Returns RS_ERR_UNSUPPORTED if the canvas would exceed 16384 pixels on a side.
rs_status rs_synth_canvas_for_lens( // out
    rs_synth_canvas *canvas,
    // in
    const mrcal_lensmodel_t *lensmodel, const double *intrinsics, int width, int height, double scale, rs_err *err);

// The resampling map: for every pixel (u, v) of the real image, the canvas pixel that sees the
// same direction: its unprojection through the real lens, then the canvas pinhole. Coordinates
// follow mrcal/OpenCV (pixel (0,0) = centre of the top-left pixel); a pixel without a direction
// the canvas sees gets (-1e6, -1e6) (remap gives 0 there). A fisheye canvas interpolates the
// unit direction (x, y, z) instead of (x/z, y/z).
// Method (issue 18's cost: mrcal_unproject is iterative, 0.28 s for every pixel of 720x480):
// mrcal_unproject on a grid of nodes every RS_SYNTH_CANVAS_MAP_STEP pixels (from one step
// before the image to two past it), the direction's tangent-plane coordinates (x/z, y/z)
// interpolated between them by Catmull-Rom cubic convolution (Keys 1981), separably; then every
// pixel is checked by projecting its direction back through the lens (mrcal_project, closed
// form): one that lands more than RS_SYNTH_CANVAS_MAP_CHECK_PX from itself, or whose nodes have
// no direction, is unprojected on its own by mrcal_unproject.
// Accuracy: every pixel reprojects within RS_SYNTH_CANVAS_MAP_CHECK_PX (1e-4 px) of itself;
// against mrcal_unproject pixel by pixel, the map differs by at most 6e-5 canvas px over the
// demo site's four OPENCV8 cameras at 720x480 (float rounding included), and by less than
// 0.01 px for the lenses of tests/synth/povray/test_canvas_map.c, which asserts it.
// Cost: about 0.012 s at 720x480 (5,859 unprojections, 345,600 projections; 0.28 s before).
// out: *map_xy, (height, width, 2) float, owned by the caller (free())
// in:  canvas (rs_synth_canvas_for_lens), the real lens; width, height > 0
// Returns RS_ERR_EXTERNAL when mrcal cannot project or unproject with this lens, RS_ERR_NOMEM.
#define RS_SYNTH_CANVAS_MAP_STEP     8    // pixels between the grid's nodes
#define RS_SYNTH_CANVAS_MAP_CHECK_PX 1e-4 // a pixel's direction must reproject this close, pixels
rs_status rs_synth_canvas_map(            // out
    float **map_xy,
    // in
    const rs_synth_canvas *canvas, const mrcal_lensmodel_t *lensmodel, const double *intrinsics, int width, int height,
    rs_err *err);

#ifdef __cplusplus
}
#endif
