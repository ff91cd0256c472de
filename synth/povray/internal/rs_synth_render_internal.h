// rs_synth_render_internal.h -- the condition's passes (synth/povray/rs_synth_render_condition.c)
// that the renderer (synth/povray/rs_synth_render.c) runs beside the colour pass (issue 40,
// docs/conditions.md). Internal to synth/povray; the API is synth/povray/rs_synth_render.h.
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "core/rs_image.h"
#include "core/rs_status.h"
#include "synth/povray/rs_synth_camera.h"
#include "synth/povray/rs_synth_render.h"
#include "synth/povray/rs_synth_scene.h"

// The POV-Ray camera mirrored in the ground plane n . p_enu = offset_m: its location, right, up
// and direction reflected. Pixel (u, v) of the mirrored camera sees, beyond the ground, what the
// real camera's pixel (u, v) sees reflected in the ground (the ground itself is no_image in a
// colour pass over a background, so the rays pass it). out: *m; in: cam, g_enu (3,), offset_m
void rs_synth_povcam_mirror(rs_synth_povcam *m, const rs_synth_povcam *cam, const double g_enu[3], double offset_m);

// The canvas rectangle of a vehicle's mirror image: its box's corners reflected in the ground
// plane (rs_synth_vehicle_rect of those). false when it misses the canvas.
// out: rect (4,); in: canvas, rt_cam_enu (6,), corners_enu_m (8,3), g_enu (3,), offset_m
bool rs_synth_mirror_rect(int rect[4], const rs_synth_canvas *canvas, const double rt_cam_enu[6],
                          const double corners_enu_m[8][3], const double g_enu[3], double offset_m);

// The mirror pass (rendered at half the canvas's resolution: a reflection is soft, and the pass
// costs a second colour trace) made premultiplied, resized to the canvas (linear), weighted by
// Fresnel's reflectance of water at each canvas pixel's angle of incidence on the ground
// (rs_synth_fresnel_water; 0 where the ray does not meet the ground): rgb = R a L, alpha = R a;
// and blurred by 1 px (ripples).
// in,out: mirror (half canvas (H+1)/2, (W+1)/2, 4) straight alpha in, (canvas H, W, 4)
// premultiplied out; in: canvas (pinhole), rt_cam_enu (6,), g_enu (3,)
rs_status rs_synth_mirror_weight(rs_image *mirror, const rs_synth_canvas *canvas, const double rt_cam_enu[6],
                                 const double g_enu[3], rs_err *err);

// The headlights' irradiance on the ground plane at every canvas pixel whose ray meets it (0
// elsewhere): the sum over every included vehicle's two lamps (rs_synth_scene_headlights) of
// intensity x beam(angle off the axis) x cos(incidence) / d^2, computed at half the canvas's
// resolution and resized (linear). No shadows (a vehicle in the beam does not darken the road
// behind it).
// out: *irr (canvas H, W, 1); in: canvas (pinhole), rt_cam_enu, ground plane, vehicles,
// include (N,) or NULL, intensity (<= 0: RS_SYNTH_HEADLIGHT_INTENSITY)
rs_status rs_synth_headlight_ground(rs_image *irr, const rs_synth_canvas *canvas, const double rt_cam_enu[6],
                                    const double g_enu[3], double offset_m, const rs_synth_prepared *vehicles,
                                    const uint8_t *include, double intensity, rs_err *err);

// The condition's canvas images into the real lens (map: the canvas map, NULL when the canvas is
// the lens; linear interpolation, the mirror pass being premultiplied) and handed to out
// (out->mirror, out->headlight_irradiance); *mirror and *headlights are left empty.
// in,out: mirror (canvas H, W, 4) and headlights (canvas H, W, 1), either may be empty
rs_status rs_synth_condition_into_lens(rs_synth_render_result *out, rs_image *mirror, rs_image *headlights,
                                       const float *map, rs_err *err);

// rect (x0, y0, x1, y1 inclusive; empty when x1 < x0) grown to hold r (4,).
void rs_synth_rect_grow(int rect[4], const int r[4]);

// Whether rectangles a and b (x0, y0, x1, y1, inclusive) share a pixel.
bool rs_synth_rects_meet(const int a[4], const int b[4]);

// The colour pass in clusters (synth/povray/rs_synth_render_cull.c says how they are made): at
// most RS_SYNTH_MAX_CLUSTERS canvas rectangles, each rendered by its own povray process with the
// vehicles include[c * N + i] flags.
// out: rect (RS_SYNTH_MAX_CLUSTERS, 4), include (RS_SYNTH_MAX_CLUSTERS * N)
// in:  N vehicles; included (N,) the culling's flags; rects (N, 4) each included vehicle's canvas
//      rectangle (empty: x1 < x0); reach (N, 4) the same widened by its shadows; the canvas's
//      W x H; region (4,) the union of the rectangles
// Returns the number of clusters, 0 when one rectangle is as good (or out of memory).
#define RS_SYNTH_MAX_CLUSTERS 4
int rs_synth_colour_clusters( // out
    int rect[RS_SYNTH_MAX_CLUSTERS][4], uint8_t *include,
    // in
    int N, const uint8_t *included, const int (*rects)[4], const int (*reach)[4], int W, int H, const int region[4]);

// One povray process: one pass of `vehicles` seen by `cam`, rendered in `region` (x0, y0, x1,
// y1 inclusive, pixels of cam's image) from OUT/NAME.pov into OUT/NAME.png.
typedef struct {
    const char *name;
    const rs_synth_povcam *cam;
    const rs_synth_prepared *vehicles;
    const rs_synth_scene_options *pass;
    int antialias;
    int region[4];
    bool ppm;        // 16-bit PPM without alpha (+FP16 -UA) instead of the .ini's PNG
    const char *log; // povray's output: "povray.log" for the colour pass, NAME.log for others
    pid_t pid;       // 0: not started
    double t0;
    rs_synth_povcam crop; // a perspective cam cut to the region (rs_synth_povcam_crop): povray
    bool cropped;         //   traces and writes that rectangle alone; else the region's +SC/+EC
} rs_synth_povray_job;

// Starts job j (rs_synth_render_job.c says what it writes and how povray is run), without
// waiting. in: out_dir, povray (the executable), fxy (2,) the lens's focal lengths (pins),
// ground_normal_enu (3,), ground_offset_m
rs_status rs_synth_povray_job_start(rs_synth_povray_job *j, const char *out_dir, const char *povray,
                                    const double fxy[2], const double ground_normal_enu[3], double ground_offset_m,
                                    rs_err *err);

// Waits for job j (if started), adds its wall time to *seconds and reads its image into *img:
// the whole canvas, transparent (zero) outside the region; a cut region is pasted into *img
// (allocated, zeroed, when empty), so that several jobs can fill one image.
rs_status rs_synth_povray_job_finish(rs_synth_povray_job *j, rs_image *img, const char *out_dir, const char *povray,
                                     double *seconds, rs_err *err);
