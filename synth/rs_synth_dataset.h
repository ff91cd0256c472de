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
//   vehicles    the built-in traffic along SITE/lanes.geojson (rs_synth_traffic_place, at most
//               `vehicles` of them) then domain randomisation (rs_synth_traffic_randomise)
//   render      rs_synth_render (culling, region, alpha, composite, ID pass), labels through
//               mrcal (rs_synth_labels_compute)
//   shadows     over any background but a night one: differential rendering (the ground with
//               and without the vehicles under the same sun and sky, as one shadow pass of
//               the render, rs_synth_scene.h; the background times their ratio on non-vehicle
//               pixels; docs/synth.md): the sun's shadow when sunny (or untagged) with the
//               sun up, the sky's soft shadow under and beside each vehicle always
//   povray      one process per image, the colour, ID and shadow passes as its frames
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
#include <stdint.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

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
    int width, height;       // output size; 0: the camera's own (intrinsics are scaled)
    int vehicles;            // at most this many vehicles per image's traffic (default 10)
    const char *split;       // COCO split name (default "train2017")
    bool shadows;            // differential-rendering shadows over backgrounds (default on)
    bool separate_processes; // one povray process per pass (benchmarks; default off)
    bool full_frame;         // no culling, no region: povray renders the whole image
                             // (benchmarks; default off)
    int coarse_below_px;     // a vehicle whose box is fewer pixels tall than this in the image
                             // gets the coarse mesh (rs_synth_fleet_build_lod; default 40;
                             // 0: every vehicle in full detail)
    int jobs;                // worker processes (default 1): worker j makes the images at
                             // positions j, j + jobs, .. of this shard; povray spends much of
                             // its time waiting on itself, so jobs > cores pays (bench synth)
    const char *povray;      // NULL: $ROADSIDE_POVRAY, else povray on PATH
    // Called after each image of this shard (made or skipped); may be NULL.
    void (*progress)(void *ctx, int done, int total, int skipped);
    void *progress_ctx;
    // Called with a one-line message ("FILE: fault: image remade", "FILE: fault: left out of the
    // COCO file") for each image found damaged on resume and each part file left out of the
    // COCO file; may be NULL.
    void (*notice)(void *ctx, const char *msg);
    void *notice_ctx;
} rs_synth_dataset_options;

void rs_synth_dataset_options_default(rs_synth_dataset_options *opt);

typedef struct {
    int Nimages;         // images of this shard
    int Nmade, Nskipped; // made now / found finished (and intact)
    int Nremade;         // of Nmade: found finished but damaged, made again
    int Nleft_out;       // part files left out of the COCO file (another shard's, damaged)
    int Nannotations;    // annotations in the assembled COCO file
    int Ngrey;           // images rendered over the grey ground (no matching background)
    double seconds;      // wall time
    double seconds_povray;
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

// Splitmix64 mixing of (seed, k): the seed of image k's random stream.
uint64_t rs_synth_dataset_image_seed(uint64_t seed, int k);

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

#ifdef __cplusplus
}
#endif
