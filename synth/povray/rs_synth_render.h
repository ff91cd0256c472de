// rs_synth_render.h -- rendering a scene with the real POV-Ray: culling, region rendering,
// compositing onto a background, the object-ID pass (`roadside render`).
//
// Steps (docs/povray.md):
// 1. Frustum culling: each vehicle's bounding box is clipped to z_cam >= 0.05 m and projected
//    through the canvas pinhole (rs_synth_camera.h; a fisheye canvas: the box's sampled
//    segments, rs_synth_vehicle_rect); a vehicle whose projection misses the canvas
//    is left out. With no vehicle left (and no pins), povray is not run when compositing onto a
//    background: the image is the background and the ID image is all 0. Limitation: a culled
//    vehicle's shadow or reflection, which could fall into the view, is lost.
// 2. Region: povray renders only the canvas rectangle covered by the remaining vehicles' boxes
//    (+ 1 px), with +SC/+EC/+SR/+ER; the rest of the canvas stays transparent. Pins, or the
//    ground drawn when there is no background, make the region the whole canvas. The shadow
//    pass's region also covers each vehicle's shadows: its box's top corners projected onto
//    the ground along every light of the pass.
// 2b. Passes: roadside rasterises the ID pass (the pixels POV-Ray would give; by POV-Ray where
//    the ground may hide part of a vehicle) and the shadow pass (exact at full resolution, on
//    coarse meshes) while one povray process renders the colour pass (rs_synth_raster.h;
//    docs/fleet.md, "Cost", D). With povray_passes, one povray process per pass instead, all
//    started at once (one after the other with separate_processes), the shadow pass at half
//    the canvas's resolution on coarse meshes, interpolated. A fisheye canvas has both passes
//    rendered by POV-Ray (the rasteriser draws straight edges). Each povray process spends about
//    0.6 s waiting between its threads besides its work (docs/povray.md).
// 3. Colour pass with alpha over a transparent background (+UA), 16-bit linear PNG
//    (File_Gamma 1), no antialiasing unless asked; without pins, drawn ground, antialiasing or
//    a ground hiding part of a vehicle, 16-bit PPM with the alpha of the ID pass (the same);
//    a distorted lens is resampled from the canvas
//    into the real lens (linear interpolation of premultiplied colour, rs_synth_opencv.h).
// 4. Composite: out = fg + (1 - a) bg in linear light (straight alpha: fg = a * colour), the
//    background decoded from sRGB and the result encoded to sRGB 8-bit; over a background
//    through rs_synth_composite_background (rs_synth_composite.h: the shadows, and with
//    opt->look the camera's gain, blur, noise and JPEG), as `roadside synth` does.
// 5. ID pass (rasterised by roadside where the ground hides nothing, else POV-Ray's): no lights,
//    flat emissive colours, no antialiasing, 8-bit PNG with File_Gamma 1:
//    per-pixel vehicle index 0 = background, k+1 = vehicle k (16-bit); resampled with
//    nearest-neighbour into the real lens.
// povray runs in the output folder with HOME set to it (POVINC/POVINI unset), its output going
// to OUT/povray.log. What confines it (docs/povray.md, "Confinement"):
//  1. the scene text: roadside's scenes hold no file operation and no input text outside
//     sanitised comments (rs_synth_scene.h; tests/synth/povray/test_scene_cli.py,
//     test_povray_sandbox.py);
//  2. Linux Landlock (rs_synth_sandbox.h): povray may read the system's files under /usr,
//     /etc/povray, and read and write only the folder it runs in; everything else is refused
//     by the kernel. Where Landlock is unavailable povray runs unconfined (the cli says so).
// The OUT/.povray/3.7/povray.conf written there ("restricted", only "." permitted) is NOT a
// defence: measured with Debian 12's POV-Ray 3.7.0.10, reads anywhere and writes to /tmp,
// /var/tmp and OUT/.. pass through it (tests/synth/povray/test_povray_sandbox.py shows both).
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include <mrcal/mrcal.h>

#include "core/rs_camera.h"
#include "core/rs_status.h"
#include "synth/backdrop/rs_synth_opencv.h"
#include "synth/fleet/rs_synth_vehicle.h"
#include "synth/labels/rs_synth_labels.h"
#include "synth/povray/rs_synth_composite.h"
#include "synth/povray/rs_synth_scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    const char *povray;            // executable; NULL: $ROADSIDE_POVRAY, else "povray" on PATH
    const char *background_path;   // image of the camera's size to composite onto; may be NULL
    bool full_frame;               // no culling, no region: render the whole canvas (benchmarks)
    bool keep_files;               // keep the .pov/.ini/.png intermediates in the output folder
    int antialias;                 // 0: none; n >= 2: +A0 +AM1 +R(n) on the colour pass only
    double canvas_scale;           // distorted lenses: canvas pixels per core pixel (default 1)
    const rs_synth_canvas *canvas; // precomputed for this lens, size and canvas_scale
    const float *canvas_map;       //   (rs_synth_canvas_for_lens, rs_synth_canvas_map; both
                                   //   borrowed): a caller rendering many images of one camera
                                   //   computes them once; NULL: computed here
    bool shadow;                   // also the shadow pass (rs_synth_scene.h): out->shadow
    bool write_files;              // write image.png, rgba.png, ids.png (default true)
    bool separate_processes;       // the passes' povray processes one after the other
                                   // (default false: all at once)
    bool povray_passes;            // the ID and shadow passes rendered by POV-Ray, which roadside
                                   // otherwise rasterises (rs_synth_raster.h; default false: the
                                   // tests' oracle)
    rs_synth_scene_options scene;  // sun, pins, ground (pass and include are set per pass)
    const int (*vehicle_rects)[4]; // (Nvehicles,) each vehicle's canvas rectangle
                                   // (rs_synth_vehicle_rect on opt->canvas, near 0.05 m), all in
                                   // view: a caller that culled them already (roadside synth)
                                   // gives them and render does not cull again; NULL: culled here
    // issue 40, the condition's passes (docs/conditions.md; rs_synth_scene_apply_condition sets
    // the scene's lights):
    bool mirror;                     // a wet road: the mirror pass (out->mirror), one more povray process: the
                                     // colour pass seen by the camera mirrored in the ground plane
    bool headlights;                 // the headlights' irradiance on the ground (out->headlight_irradiance),
                                     // rasterised, at scene.headlight_intensity (0: RS_SYNTH_HEADLIGHT_INTENSITY)
    const rs_image *env_map;         // (h, 2h, 3) linear light, may be NULL (borrowed): the
                                     // environment the vehicles reflect (issue 40,
                                     // rs_synth_env_map), written as OUT/RS_SYNTH_ENV_MAP_FILE
                                     // (16-bit, scaled to its maximum) and shown by the colour
                                     // pass's sphere (rs_synth_scene_options.env_map)
                                     // gives them and render does not cull again; NULL: culled here
    const rs_synth_appearance *look; // over background_path: the camera's look the vehicles and
                                     // their shadows take (rs_synth_composite.h; borrowed);
                                     // NULL (default): clean, sharp vehicles
    uint64_t look_seed;              // the look's noise generator
    bool light_matched;              // scene.light_rgb_scale was matched to background_path: the
                                     // look's gain is not applied on top (rs_synth_composite.h)
} rs_synth_render_options;

void rs_synth_render_options_default(rs_synth_render_options *opt);

// A rendered view. Images are in the real camera's size.
typedef struct {
    int width, height;
    rs_image rgba;      // (H, W, 4): the colour pass, linear light, straight alpha
    rs_image composite; // (H, W, 3) sRGB-encoded [0,1]: over the background (or black)
    uint16_t *ids;      // (H, W) owned: 0 = background, k+1 = vehicle k
    uint8_t *visible;   // (Nvehicles,) owned: 1 = survived culling (may still be hidden)
    int Nvehicles;
    int Nrendered;         // vehicles sent to povray (0: povray was not run)
    int region[4];         // canvas rectangle rendered: x0, y0, x1, y1 inclusive (pixels);
                           // all -1 when nothing was rendered
    float *shadow;         // (H, W) owned, when the shadow pass ran (else NULL): the fraction
                           // of the ground's light reaching each pixel, 1 in the open and
                           // on the vehicles' own pixels (ids != 0)
    double seconds_povray; // wall time spent in povray (every pass)
    int Npovray;           // povray processes run
    int Npasses;           // passes rendered
    // issue 40 (opt.mirror, opt.headlights; composited by rs_synth_condition_add_wet and
    // rs_synth_condition_add_headlights, synth/backdrop/rs_synth_condition.h):
    rs_image mirror;             // (H, W, 4) premultiplied, linear: the vehicles' mirror image in
                                 // a wet road times Fresnel's reflectance (rgb = R a L, alpha = R a);
                                 // empty without opt.mirror
    float *headlight_irradiance; // (H, W) owned, or NULL: the headlights' irradiance on the ground
} rs_synth_render_result;

void rs_synth_render_result_free(rs_synth_render_result *r); // NULL-safe; zeroes *r

// The povray executable to run: `given` when not NULL (an empty one: "povray"), else $ROADSIDE_POVRAY when set and not
// empty, else "povray" (found on PATH). The one place that reads $ROADSIDE_POVRAY; every
// option struct's NULL `povray` means this.
const char *rs_synth_povray_exe(const char *given);

// Runs the real POV-Ray: `povray ARGS...` (no shell) in folder `dir`, with HOME = dir (so that
// dir/.povray/3.7/povray.conf, if written, is the configuration it reads) and POVINC/POVINI
// unset, confined by Landlock to reading the system's files and reading and writing `dir`
// (rs_synth_sandbox.h; unconfined where Landlock is unavailable); its output is appended to
// dir/povray.log. seconds (may be NULL) accumulates the wall time. Errors: RS_ERR_EXTERNAL
// "cannot run" when the program is missing (exit 127), "cannot confine povray" when Landlock is
// there but fails (povray is then not run), else the exit status and the log's last line.
rs_status rs_synth_povray_run(const char *povray, const char *dir, const char *const *args,
                              int Nargs,       // (Nargs,) at most 30
                              double *seconds, // may be NULL
                              rs_err *err);

// Renders N vehicles seen by the camera into out_dir (created if missing). Writes
//   out_dir/image.png  the composite (8-bit sRGB; with the shadow pass the background is
//   shaded by it on non-vehicle pixels),  out_dir/rgba.png  the colour pass
//   (16-bit linear RGBA, real lens),  out_dir/ids.png  the ID pass (16-bit grey, value k+1),
//   out_dir/shadow.png  with the shadow pass, the lit fraction (16-bit grey, 1 = open ground),
// each atomically; with keep_files also the scene files and povray's own outputs.
// in: camera: the calibrated camera (core/rs_camera.h); ground plane; the prepared vehicles
//     (synth/fleet/rs_synth_prepare.h); opt may be NULL (defaults)
// Returns RS_ERR_EXTERNAL when povray is missing or fails (the message quotes povray.log's
// last line), RS_ERR_IO for the files.
rs_status rs_synth_render( // out
    rs_synth_render_result *out,
    // in
    const char *out_dir,
    const rs_camera *camera, // calibrated: lens, intrinsics, size, pose
    const double ground_normal_enu[3], double ground_offset_m, const rs_synth_prepared *vehicles,
    const rs_synth_render_options *opt, rs_err *err);

// The canvas rectangle (x0, y0, x1, y1 inclusive, clipped to the canvas) covered by vehicle v's
// bounding box clipped to z_cam >= near_m; returns false if it misses the canvas or lies behind.
// A fisheye canvas (rs_synth_camera.h): the box's edges sampled, with a margin, and no near plane;
// a box reaching out of the canvas's angle gets the whole canvas.
bool rs_synth_vehicle_rect( // out
    int rect[4],
    // in
    const rs_synth_canvas *canvas, const double rt_cam_enu[6], const double corners_enu_m[8][3], double near_m);

// The object-ID pass alone, without POV-Ray (`roadside synth --labels-only`): every vehicle's
// mesh rasterised over the whole canvas (rs_synth_raster_ids), resampled with nearest neighbour
// into the real lens through canvas_map (as rs_synth_render's step 5) and decoded. It equals
// rs_synth_render's ID image but where the ground could hide part of a vehicle: rs_synth_render
// then has POV-Ray render the pass with the ground plane, this ignores the ground (a flat site's
// ground hides nothing above it). A fisheye canvas is refused (the rasteriser draws a pinhole's
// straight edges).
// out: *ids (height, width) of the camera, 0 = no vehicle, k + 1 = vehicle k; owned (free())
// in:  canvas, canvas_map: the camera's (rs_synth_canvas_for_lens, rs_synth_canvas_map; map
//      NULL when canvas->identity); the ground plane; the prepared vehicles
// Errors: RS_ERR_INVALID (a fisheye canvas, more than 65,534 vehicles), RS_ERR_NOMEM.
rs_status rs_synth_render_ids( // out
    uint16_t **ids,
    // in
    const rs_camera *camera, const rs_synth_canvas *canvas, const float *canvas_map, const double ground_normal_enu[3],
    double ground_offset_m, const rs_synth_prepared *vehicles, rs_err *err);

// The labels of a rendered image (synth/labels/rs_synth_labels.h): every prepared vehicle's label
// computed through `cam` with its visibility from r->ids, written as COCO and YOLO under
// out_dir/<split> and KITTI under out_dir, and the composite copied to
// out_dir/<split>/image.png. Each file is written atomically. `roadside render --labels`.
rs_status rs_synth_render_write_labels( // in
    const char *out_dir, const rs_synth_render_result *r, const char *split, const rs_synth_label_options *lopt,
    const rs_camera *cam, const double ground_normal_enu[3], double ground_offset_m, const rs_synth_prepared *prepared,
    rs_err *err);

#ifdef __cplusplus
}
#endif
