// rs_synth_dataset.h -- labelled synthetic datasets (`roadside synth`): the per-image pipeline,
// shards, resuming, and merging shards into one COCO dataset (docs/synth.md, docs/scale-out.md).
//
// Per image index k (0 <= k < count; a shard I/N takes the k with k % N == I):
//   camera      cameras[k % Ncameras] (the site's, or the ones asked for)
//   randomness  one stream seeded by splitmix64(seed, k) only, so an image does not depend on
//               which shard or which run made it: reruns and shard splits give identical files
//   background  drawn uniformly among the camera's tagged backgrounds (site.json
//               "background_images" as geo reads them: rs_site_camera.background_images,
//               rs_site_background_tag) that match every TAG=VALUE filter;
//               with none, a neutral grey ground is rendered by POV-Ray instead (the
//               site's ground plane, lit by the default sun)
//   sun         from the background's "time" tag and the site's origin (rs_synth_sun.h), else
//               the scene default (azimuth 135, elevation 45 degrees)
//   vehicles    the built-in traffic along SITE/lanes.geojson (rs_synth_traffic_place) then
//               domain randomisation (rs_synth_traffic_randomise); or, with traffic_frames_dir,
//               the vehicles of one frame of a `roadside traffic --sumo` folder, where SUMO put
//               them (rs_synth_dataset_traffic_frames_check, below); of those the camera sees, at
//               most `vehicles`
//   render      rs_synth_render (culling, region, alpha, composite, ID pass), labels through
//               mrcal (rs_synth_labels_compute)
//   shadows     over any background but a night one: differential rendering (the ground with
//               and without the vehicles under the same sun and sky, as one shadow pass of
//               the render, rs_synth_scene.h; the background times their ratio on non-vehicle
//               pixels; docs/synth.md): the sun's shadow when sunny (or untagged) with the
//               sun up, the sky's soft shadow under and beside each vehicle always
//   povray      one process per image, the colour pass; the ID and shadow passes rasterised
//               meanwhile (rs_synth_raster.h)
//   appearance  the vehicle layer matched to the background (rs_synth_appearance.h: gains,
//               blur, noise, JPEG quality), estimated once per background per process
// Layout of DATASET (YOLOX's COCO layout plus YOLO and KITTI, docs/labels.md):
//   <split>/<stem>.png                    the composite, stem = "%06d_<camera>" (k first, so
//                                         names sort in index order)
//   labels/<split>/<stem>.txt, label_2/<stem>.txt   YOLO and KITTI
//   parts/<stem>.json                     the image's own COCO file: written LAST, atomically;
//                                         its presence marks the image finished (resume)
//   annotations/instances_<split>.json    assembled at the end from every parts/ file present
//   .lock                                 while a run is on: its pid (core's rs_io_lock_dir)
// Each file is written atomically (core/rs_io.h), so an interrupted run leaves finished images
// and no half-written file; the per-image work folder work/<stem>/ is removed once done.
// One run at a time: a run locks DATASET (flock, released by the kernel however the run ends); a
// second run into it fails at once, naming the holder's pid, and changes nothing there.
// Resume: an image whose parts/ file is present is checked before it is skipped (the part
// parses and lists the image at the output size, the PNG decodes at that size, the YOLO and
// KITTI files are regular files); a damaged one is made again, with a notice naming the file
// and the fault.
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/rs_status.h"
#include "synth/backdrop/rs_synth_appearance.h"

#ifdef __cplusplus
extern "C" {
#endif

// The share of images in the validation split by default (`roadside synth --val-fraction`).
#define RS_SYNTH_VAL_FRACTION_DEFAULT 0.1

typedef struct {
    const char *site_dir;  // the site folder (site.json, lanes.geojson, backgrounds)
    const char *calib_dir; // folder of calibrated <camera>.cameramodel files
    const char *out_dir;   // DATASET, created if missing
    int count;             // images in the whole dataset (all shards), >= 1
    uint64_t seed;
    int shard_index, shard_count; // this process makes the k with k % shard_count == shard_index
    const char *const *cameras;   // (Ncameras,) camera ids; NULL / 0: every camera of the site
    int Ncameras;
    const char *const *filter_keys;   // (Nfilters,) background tag filters key == value
    const char *const *filter_values; // (Nfilters,)
    int Nfilters;
    int width, height; // output size; 0: the camera's own (intrinsics are scaled)
    int vehicles;      // at most this many vehicles per image's traffic (default 10)
    const char *split; // COCO split name (default "train2017")
    // Validation split: image k goes to val_split when any of these holds (else to split):
    //   a uniform draw of its own stream (a sequence: of its frame) is below val_fraction (0..1;
    //   default RS_SYNTH_VAL_FRACTION_DEFAULT; with 2 images or more never an empty split: the
    //   image with the smallest draw when none falls below),
    //   its camera is one of val_cameras, its background matches every val_bg_key = value
    //   (Nval_bg > 0; rs_site_background_tag, so "name=..." holds a background out).
    const char *val_split; // default "val2017"
    double val_fraction;
    const char *const *val_cameras; // (Nval_cameras,)
    int Nval_cameras;
    const char *const *val_bg_keys;   // (Nval_bg,)
    const char *const *val_bg_values; // (Nval_bg,)
    int Nval_bg;
    // Labels (synth/labels/rs_synth_labels.h): which box is COCO's bbox, YOLO's and KITTI's 2D box
    // (default footprint), the least visibility kept (default 0), and whether a vehicle with no
    // visible pixel gets a label (default false: it does not).
    int bbox; // rs_synth_bbox_kind
    double min_visibility;
    bool keep_invisible;
    bool junction_traffic; // vehicles on the junction's lanes too (turning movements; default
                           // on): rs_synth_traffic_options.junction_lanes
    // NULL (default): the built-in traffic. Else a folder written by `roadside traffic --sumo -o
    // DIR` (frames.json and its frame files): image k takes the vehicles of one frame, drawn from
    // k's stream, instead (the section "traffic from SUMO's frames" below).
    const char *traffic_frames_dir;
    // NULL (default): procedural vehicles only. Else a model library (`roadside synth --models
    // FILE`, synth/traffic/rs_synth_vehicles.h: rs_synth_models_read): a vehicle of a class the
    // library has becomes one of its models of that class, drawn from the image's seed (its
    // label the model's class, its box the model's); the other classes stay procedural.
    const char *models_path;
    // A sequence (`roadside synth --sequence`, the section "sequences" below): with
    // traffic_frames_dir, image k shows frame frame_first + k / Ncameras to camera k % Ncameras,
    // every vehicle the camera sees; count is then set by the run ((frame_end - frame_first) x
    // Ncameras; the count given is ignored). frame_end -1: every frame from frame_first on.
    bool sequence;
    int frame_first, frame_end; // frames [frame_first, frame_end) of frames.json
    bool labels_only;           // sequences only: labels without POV-Ray, no image files
    bool shadows;               // differential-rendering shadows over backgrounds (default on)
    bool separate_processes;    // one povray process per pass (benchmarks; default off)
    bool full_frame;            // no culling, no region: povray renders the whole image
                                // (benchmarks; default off)
    int coarse_below_px;        // a vehicle whose box is fewer pixels tall than this in the image
                                // gets the coarse mesh (rs_synth_fleet_build_lod; default 40;
                                // 0: none)
    int medium_below_px;        // .. than this, the medium one (RS_SYNTH_LOD_MEDIUM; default 120;
                                // 0: none; both 0: every vehicle in full detail)
    int jobs;                   // worker processes (default 1): worker j makes the images at
                                // positions j, j + jobs, .. of this shard; povray spends much of
                                // its time waiting on itself, so jobs > cores pays (bench synth)
    const char *povray;         // NULL: $ROADSIDE_POVRAY, else povray on PATH
    // Called after each image of this shard (made or skipped); may be NULL.
    void (*progress)(void *ctx, int done, int total, int skipped);
    void *progress_ctx;
    // Called with a one-line message ("FILE: fault: image remade", "FILE: fault: left out of the
    // COCO file") for each image found damaged on resume and each part file left out of the
    // COCO file; may be NULL.
    void (*notice)(void *ctx, const char *msg);
    void *notice_ctx;
    bool no_appearance; // the vehicles composited clean and sharp over backgrounds (default off:
                        // the camera's look, synth/povray/rs_synth_composite.h)
} rs_synth_dataset_options;

void rs_synth_dataset_options_default(rs_synth_dataset_options *opt);

typedef struct {
    int Nimages;         // images of this shard
    int Nmade, Nskipped; // made now / found finished (and intact)
    int Nremade;         // of Nmade: found finished but damaged, made again
    int Nleft_out;       // part files left out of the COCO file (another shard's, damaged)
    int Nannotations;    // annotations in the assembled COCO file
    int Ngrey;           // images rendered over the grey ground (no matching background)
    bool tracks_gt;      // a sequence's DATASET/tracks_gt.csv was written (every image finished)
    double seconds;      // wall time
    double seconds_povray;
    // issue 40: this shard's images (made now or found finished) by their background's
    // condition, index time_of_day x 3 + surface (synth/backdrop/rs_synth_condition.h: day, dusk,
    // night x dry, wet, snow); the grey ground's images are in none, and so are finished images
    // over an untagged background not decoded by this run. Also in DATASET/run.json's "conditions".
    int Ncondition[9];
} rs_synth_dataset_summary;

// Makes (or completes) this shard's images (with jobs > 1 in forked workers, each reporting
// every image through a pipe; after a worker's error the others finish their share),
// then assembles DATASET's COCO file from every
// finished image in DATASET. Returns RS_ERR_USAGE / RS_ERR_INVALID for bad options (an unknown
// camera, an output size of another aspect than the camera's by more than 1 %, no lanes),
// RS_ERR_EXTERNAL when povray fails, RS_ERR_IO / RS_ERR_PARSE for the files, RS_ERR_IO
// "DATASET is in use by roadside synth (pid N) since TIME ..." when another run holds DATASET.
// out: summary may be NULL
rs_status rs_synth_dataset_run(rs_synth_dataset_summary *summary,
                               // in
                               const rs_synth_dataset_options *opt, rs_err *err);

// The CPUs this process may use: the smallest of its affinity mask (sched_getaffinity), its
// cgroup v2 quota (cpu.max "quota period" of its own cgroup, rounded up; "max" is no limit) and
// $SLURM_CPUS_PER_TASK when set; at least 1. The default of `roadside synth --jobs`.
// out: why[n] (may be NULL): which of them decided, e.g. "affinity mask: 2 CPUs"
int rs_synth_dataset_usable_cpus(char *why, size_t n);

// Splitmix64 mixing of (seed, k): the seed of image k's random stream.
uint64_t rs_synth_dataset_image_seed(uint64_t seed, int k);

// ---- traffic from SUMO's frames (opt->traffic_frames_dir, `roadside synth --traffic-frames`) ----
//
// Image k's stream (rs_synth_dataset_image_seed(seed, k), stepped by splitmix64: draw j is
// rs_rng_seed_derive(image seed, j - 1)) gives, in order: 1 the background; 2 the traffic: the
// built-in placement's seed, or the frame, draw 2 mod Nframes (index into frames.json); 3 the
// built-in randomisation's seed, or the frame's looks: vehicle i of the frame (file order) gets
// variant rs_rng_seed_derive(draw 3, i) >> 11 (paint, metallic, dirt and shape details are drawn
// from it by the fleet, as for built-in vehicles; a "colour" in the file is kept); 4 the pick
// among the vehicles the camera sees; 5 the look of the composite. So images depend on (seed,
// k) and the inputs only. A frame's vehicles are placed exactly where its file says (centre
// e, n, yaw_deg, length, width, height): no positional randomisation in synth, as `roadside
// traffic` already randomised the frames it wrote (unless --no-randomise), with no overlaps.
typedef struct {
    int Nframes;     // frames listed in DIR/frames.json, >= 1
    long Nvehicles;  // vehicles in all the frames
    char sha256[65]; // SHA-256 of the manifest "<sha256 of frames.json>  frames.json\n" then
                     // "<sha256 of FILE>  FILE\n" per frame in index order: what
                     // `cd DIR && sha256sum frames.json FILE... | sha256sum` prints
} rs_synth_traffic_frames_info;

// Reads DIR/frames.json (rs_synth_sumo_frames_index_read) and every frame file it lists
// (rs_synth_vehicles_read), and checks what synth needs: at least one frame, each file holding
// the number of vehicles the index states, class vehicles only (no "model"), each with its
// length, width and height. Reads nothing else and writes nothing (the manifest's hash goes
// through a temporary file in $TMPDIR, removed).
// Errors name the file and the field: RS_ERR_NOT_FOUND "DIR/frames.json: missing (...)",
// RS_ERR_INVALID "DIR/frames.json: no frames", RS_ERR_PARSE "DIR/frame_000003.json:7: JSON syntax
// error near ...", RS_ERR_INVALID "DIR/frame_000003.json: [2].length: missing ...", RS_ERR_IO.
rs_status rs_synth_dataset_traffic_frames_check( // out
    rs_synth_traffic_frames_info *info,
    // in
    const char *dir, rs_err *err);

// ---- sequences (opt->sequence, `roadside synth --sequence`; docs/synth.md, "Sequences and
// labels without rendering") ----
//
// Image k is frame i = frame_first + k / Ncameras of frames.json (in order, not drawn) seen by
// camera k % Ncameras: every camera sees every frame, the same vehicles with their ids, placed
// where the frame's file says. What differs from drawn frames: every vehicle the camera sees is
// rendered and labelled (no pick of at most `vehicles`); a vehicle's looks are drawn from (seed,
// its id), the same in every frame; image k's background is drawn from the stream of image
// k % Ncameras, the same for every frame of a camera. The other draws of image k's stream are
// as above. With labels_only no POV-Ray runs: the visibility comes from the rasterised ID pass
// (rs_synth_render_ids: exact where the ground hides no part of a vehicle), and only the labels
// are written (parts/, annotations/; no PNG, YOLO or KITTI files).
// After the images, when every image of the sequence is finished, DATASET/tracks_gt.csv
// (rs_synth_dataset_tracks_gt_write): one row per vehicle of each frame.

// Writes DATASET/tracks_gt.csv (atomically) for frames [first, end) of `frames_dir`, seen by the
// cameras `cameras` (Ncameras,) in image order: header
// time_s,vehicle_id,class,e_m,n_m,speed_mps,heading_deg,cameras; per frame (in order) each
// vehicle of its file (in file order): the frame's time, its id, class, the ground point under
// its footprint centre (exactly the labels' bottom_center_enu_m: rs_synth_vehicle_to_enu at the
// ground height of the site's plane), SUMO's FCD speed, its heading (yaw, clockwise from north,
// in [0, 360)) and the ids of the cameras whose image of that frame (image k = (frame - first)
// x Ncameras + camera) has an annotation with its vehicle_id (parts/<stem>.json), joined by '+'.
// Errors: RS_ERR_IO / RS_ERR_PARSE naming a frame or part file, RS_ERR_NOT_FOUND (a part file
// missing: an unfinished image), RS_ERR_NOMEM.
// out: *Nrows (may be NULL): rows written
rs_status rs_synth_dataset_tracks_gt_write(long *Nrows,
                                           // in
                                           const char *dataset_dir, const char *frames_dir, int first, int end,
                                           const char *const *cameras, int Ncameras, const double ground_normal_enu[3],
                                           double ground_offset_m, rs_err *err);

// Joins datasets (shards) into one: for every split found (annotations/instances_<split>.json),
// images from all inputs are sorted by file name (a name present twice is kept once: shards of
// one run name an image the same), image and annotation ids renumbered from 1, categories of
// the first input; image files are hard-linked into OUT (copied across file systems), with
// their YOLO and KITTI files when present. Writes OUT/annotations/instances_<split>.json.
// OUT is locked while merging (as a synth run locks DATASET): RS_ERR_IO "OUT is in use by ...".
// out: *Nimages, *Nannotations may be NULL (totals over splits)
rs_status rs_synth_dataset_merge(int *Nimages, int *Nannotations,
                                 // in
                                 const char *out_dir, const char *const *inputs, int Ninputs, rs_err *err);

// ---- what a dataset holds (rs_synth_dataset_stats.c) ----

#define RS_SYNTH_STATS_MAX 64 // distinct values counted per field (more are not listed)

typedef struct {
    char value[96]; // the split, camera, weather or time of day ("(missing)" when absent)
    int images;
    int labels; // (splits and conditions only)
} rs_synth_dataset_count;

// One background's camera look as DATASET/backgrounds.json records it.
typedef struct {
    char background[96]; // its file, relative to the site (or its name in older datasets)
    bool ok;             // the look was estimated (else why holds the reason)
    rs_synth_appearance look;
    char why[160];
} rs_synth_dataset_look;

typedef struct {
    int images, labels;
    rs_synth_dataset_count splits[RS_SYNTH_STATS_MAX], cameras[RS_SYNTH_STATS_MAX], weather[RS_SYNTH_STATS_MAX],
        time_of_day[RS_SYNTH_STATS_MAX];
    int Nsplits, Ncameras, Nweather, Ntime_of_day;
    int labels_located; // labels with a bottom_center_enu_m
    int labels_near;    // of those, closer than radius_m to the centre (east-north distance)
    double distance_sum_m;
    int visibility_hist[10]; // labels by visibility in [0, 0.1), .., [0.9, 1]
    int invisible;           // labels with no visible pixel (visible_pixels 0)
    // issue 40: images and labels by the images' "condition" (docs/conditions.md:
    // "<time_of_day>-<surface>"; "(missing)" for images made before it or over the grey ground)
    rs_synth_dataset_count conditions[RS_SYNTH_STATS_MAX];
    int Nconditions;
    // DATASET/backgrounds.json (docs/synth.md, "The camera's look"); none in older datasets
    rs_synth_dataset_look looks[RS_SYNTH_STATS_MAX];
    int Nlooks;
    bool looks_found;   // the file is there
    bool looks_applied; // its "applied" (false: made with --no-appearance)
} rs_synth_dataset_stats_result;

// The junction's centre on the site: the mean of the vertices of the lanes whose kind is
// "junction" (SITE/lanes.geojson), or the ENU origin when there are none. out: centre (E, N) m.
rs_status rs_synth_junction_centre(double centre_enu_m[2], const char *site_dir, rs_err *err);

// Counts what DATASET/annotations/instances_*.json hold (docs/labels.md's fields).
// in: centre_enu_m (2,), radius_m: "near" is an east-north distance below radius_m.
rs_status rs_synth_dataset_stats(rs_synth_dataset_stats_result *r, const char *dataset_dir,
                                 const double centre_enu_m[2], double radius_m, rs_err *err);

// ---- contact sheets (rs_synth_dataset_view.c, `roadside dataset view`) ----

typedef struct {
    int max_images;        // the first N images (splits in name order, images in file order); 0: all
    int per_page;          // images per page (>= 1)
    int columns;           // tiles per row (>= 1)
    int max_tile_width_px; // wider images are shrunk to this width (cv::resize, INTER_AREA)
} rs_synth_view_options;

// Defaults: 48 images, 12 per page, 4 columns, tiles at most 480 px wide.
void rs_synth_view_options_default(rs_synth_view_options *opt);

typedef struct {
    int images, labels, pages;
    double scale;                // tile pixels per image pixel (<= 1)
    int tile_width, tile_height; // px
} rs_synth_view_summary;

// Draws DATASET's images with their labels (docs/labels.md) onto contact sheets:
// OUT/page_001.png, ... (each `per_page` tiles under a legend), OUT/index.html (the pages, a
// legend and a table of the images) and OUT/index.json (each image's page and tile origin).
// On each tile, in the tile's pixels (pixel (0,0) the centre of the top-left pixel; a label
// coordinate x maps to (x + 0.5) s - 0.5 at scale s): the 3D box's 12 edges (straight
// segments between projected corners), the body and visible boxes, the bottom centre (a dot),
// the visibility (text above the footprint box) and, drawn last, the footprint box. A box's
// outline goes through the outermost tile pixels whose centres lie inside the box. Colours:
// the legend in rs_synth_dataset_view.c (footprint RGB (0, 230, 0)). Files are written
// atomically; OUT is created. Errors: RS_ERR_IO / RS_ERR_NOT_FOUND (no annotations folder, no
// instances_*.json, an image file missing), RS_ERR_PARSE ("FILE:LINE: ..." for JSON syntax,
// "FILE: annotations[i].FIELD: ..." for a malformed field), RS_ERR_INVALID (an image's size
// differs from its record, or images of different sizes).
// out: *sum; in: dataset_dir, out_dir, opt
rs_status rs_synth_dataset_view(rs_synth_view_summary *sum,
                                // in
                                const char *dataset_dir, const char *out_dir, const rs_synth_view_options *opt,
                                rs_err *err);

#ifdef __cplusplus
}
#endif
