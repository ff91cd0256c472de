// rs_synth_dataset_internal.h -- what the files of `roadside synth` share
// (synth/dataset/rs_synth_dataset.h). Not installed, not for other modules.
//
// The files of a run, each calling only those below it (and none above):
//
//   rs_synth_dataset.c          the run: options, the site's cameras and backgrounds (from the
//                               site geo loaded), this shard's images here or in forked workers
//   rs_synth_dataset_coco.c     COCO: assembling DATASET's annotations from the finished
//                               images (and merge's index and writer)
//   rs_synth_dataset_check.c    resume: whether an image found finished is intact
//   rs_synth_dataset_image.c    one image: background, traffic, render, composite, labels, files
//   rs_synth_dataset_kitti.c    one image's KITTI copy: undistorted, labels in the levelled frame
//   rs_synth_dataset_frames.c   SUMO's frames (--traffic-frames): the index read once, checked
//   rs_synth_dataset_draws.c    what image k is from (seed, k) alone: its stream, background,
//                               split and file stem
//
//   rs_synth_dataset_sequence.c a sequence's DATASET/tracks_gt.csv, from the frames and the
//                               images' part files (after the images; calls draws.c's stems)
//
// Beside them, each calling only rs_synth_dataset_coco.c (and nothing of the run above it):
// rs_synth_dataset_merge.c (roadside synth merge), rs_synth_dataset_stats.c and
// rs_synth_dataset_view.c (roadside dataset stats / view).
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <sys/stat.h>

#include <cjson/cJSON.h>

#include "core/rs_camera.h"
#include "core/rs_image.h"
#include "core/rs_status.h"
#include "geo/rs_lanes.h"
#include "geo/rs_site.h"
#include "synth/backdrop/rs_synth_appearance.h"
#include "synth/backdrop/rs_synth_condition.h"
#include "synth/backdrop/rs_synth_light.h"
#include "synth/backdrop/rs_synth_sun.h"
#include "synth/dataset/rs_synth_dataset.h"
#include "synth/labels/rs_synth_labels.h"
#include "synth/povray/rs_synth_camera.h"
#include "synth/traffic/rs_synth_sumo.h"
#include "synth/traffic/rs_synth_vehicles.h"

// One background an image may be drawn over.
typedef struct {
    const rs_site_background *src; // the site's record (borrowed from the dataset's site)
    const char *time_iso;          // its "time" tag (borrowed), may be NULL
    bool overcast;                 // conditions cloudy, rain, snow, dusk or night: no sun, the sky's soft shadow
    bool night;                    // night: no shadow at all
    // issue 40: its condition (synth/backdrop/rs_synth_condition.h), from its tags; when they say
    // nothing (cond_known false) estimated from the image at first use (prepare_background)
    rs_synth_condition cond;
    bool cond_known;
    char cond_label[16]; // rs_synth_condition_label, once known
    // cache, filled at first use (rs_synth_dataset__prepare_background): the image at the
    // output size decoded from sRGB to linear light, its appearance
    rs_image linear;
    rs_synth_appearance app;
    bool app_ok; // the appearance could be estimated
    // issue 18: the light its road shows (rs_synth_light_from_background: the road in the lanes,
    // else the ground plane in view, else the lower image; dry conditions only: sunny, cloudy or
    // untagged), matched by the vehicles' lights (rs_synth_light_match)
    rs_synth_light_estimate light;
    bool light_tried, light_ok;
    // issue 18: without a time tag, the sun from the site's poles' shadows (rs_synth_sun_from_shadows)
    rs_synth_sun_estimate sun;
    bool sun_ok;
    // issue 40: the environment map the vehicles reflect (rs_synth_scene_env_map), made at its
    // first image once the scene is matched to the background (light_ok only; a worker makes
    // its own: 0.1 s per background and worker)
    rs_image env_map;
    bool env_map_tried;
} rs_synth_dataset__background;

// One camera images are made for.
typedef struct {
    const char *id;
    rs_camera cam;                    // at the output size
    char *calib_path;                 // owned: the calibration file read (calib_dir/<id>.cameramodel)
    char calib_sha256[65];            // its SHA-256, hex
    char model_sha256[65];            // SHA-256 of the copy at the output size, DATASET/cameras/<id>.cameramodel
    char model_rel[320];              // that copy, relative to a COCO file's folder: "../cameras/<id>.cameramodel"
    rs_synth_dataset__background *bg; // (Nbg,) owned: the backgrounds passing the filters
    int Nbg;
    // cache, filled at first use (rs_synth_dataset__prepare_camera): the POV-Ray canvas of the
    // lens and its resampling map
    bool have_canvas;
    rs_synth_canvas canvas;
    float *canvas_map; // owned; NULL when the canvas is the lens itself
    // KITTI's copy (rs_synth_dataset_kitti.c), filled by rs_synth_dataset__prepare_camera too:
    // the pinhole core of the camera (same pose and size) and, for a lens with distortion, the
    // map undistorting its images to that core (NULL: LENSMODEL_PINHOLE, the images as they are)
    bool have_kitti;
    rs_camera kitti_cam;
    float *kitti_map; // owned, (height, width, 2)
} rs_synth_dataset__camera;

typedef struct {
    const rs_synth_dataset_options *opt;
    rs_site *site;                  // owned
    rs_lanes lanes;                 // owned
    rs_synth_dataset__camera *cams; // (Ncams,) owned; image k is made for cams[k % Ncams]
    int Ncams;
    const char *split[2];              // the train and validation split names (opt)
    char *split_dir[2];                // owned: DATASET/<split> of each
    char *parts_dir, *work_root;       // owned: DATASET/parts, DATASET/work
    rs_synth_sumo_frame_entry *frames; // (Nframes,) owned: --traffic-frames' frames.json, read
    int Nframes;                       //   once (rs_synth_dataset__frames_load); NULL without
    rs_synth_vehicle_list models;      // --models' library (opt->models_path; N = 0 without),
    rs_synth_mesh *model_meshes;       // (models.N,) owned: each loaded once, before the workers
                                       //   fork (models.obj[i].loaded points here)
    char models_sha256[65];            // the library file's SHA-256, hex (run.json)
    int val_fallback;                  // rs_synth_dataset__val_fallback, set before any image
} rs_synth_dataset__run;

// Reads opt->models_path's library and loads every model once for the run (errors name the
// file, the entry and the field, or the model file).
rs_status rs_synth_dataset__models_load(rs_synth_dataset__run *d, rs_err *err);

// Writes the library's texture images once as PNG into DATASET/work/models/ (each image's render
// then links them into its folder: rs_synth_fleet_cache_textures); nothing without a library.
rs_status rs_synth_dataset__models_cache(rs_synth_dataset__run *d, rs_err *err);
// Removes that folder (the run's end).
void rs_synth_dataset__models_uncache(const rs_synth_dataset__run *d);

// Vehicle v (index i of image k's traffic) becomes one of the library's models of its class,
// drawn from image k's seed, when the library has any: cls RS_SYNTH_USER_MODEL, model_cls its
// class, its box the model's. out: *spec the model's spec (untouched, and false returned, when v
// stays procedural).
bool rs_synth_dataset__pick_model(rs_synth_vehicle *v, rs_synth_obj_spec *spec, const rs_synth_dataset__run *d, int k,
                                  int i);

// ---- SUMO's frames (rs_synth_dataset_frames.c) ----

// Reads opt->traffic_frames_dir's frames.json into d->frames once for the run and checks every
// frame as rs_synth_dataset_traffic_frames_check does (out: *info, its figures).
rs_status rs_synth_dataset__frames_load(rs_synth_dataset__run *d, rs_synth_traffic_frames_info *info, rs_err *err);

// The vehicles of image k from the loaded frames: frame r_frame mod Nframes (out: *iframe, its
// index in frames.json), each vehicle j's variant rs_rng_seed_derive(r_looks, j) >> 11 (53
// bits, as the built-in traffic draws them); in a sequence frame frame_first + k / Ncams, each
// vehicle's variant rs_rng_seed_derive(seed, the file's variant) >> 11. On error *list is left
// empty.
rs_status rs_synth_dataset__frame_vehicles(rs_synth_vehicle_list *list, int *iframe, const rs_synth_dataset__run *d,
                                           int k, uint64_t r_frame, uint64_t r_looks, rs_err *err);

// Which split image k goes to: 0 (opt->split) or 1 (opt->val_split), from k's own random stream
// (the fraction; in a sequence its frame's), its camera, or the background it is drawn over (the
// same draw as rs_synth_dataset__make_image's), so it depends on (seed, k), the count and the
// options only: shards, reruns and merges agree.
//
// The validation split is never empty by chance: with val_fraction > 0 and two images (frames)
// or more, when no draw of the run falls below the fraction (a small run), the image (frame)
// with the smallest draw goes to validation. rs_synth_dataset__val_fallback returns that key
// (an image index, or in a sequence a frame index; -1: none needed), computed once per run into
// d->val_fallback (O(count) draws).
int rs_synth_dataset__val_fallback(const rs_synth_dataset__run *d);
int rs_synth_dataset__image_split(const rs_synth_dataset__run *d, int k, const rs_synth_dataset__camera *c);

// The index of image k's background among c->bg (its stream's first draw), -1 when c has none.
int rs_synth_dataset__image_background(const rs_synth_dataset__run *d, int k, const rs_synth_dataset__camera *c);

static inline bool rs_synth_dataset__file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

// issue 40, run.json's "conditions" (rs_synth_dataset_coco.c): adds to mix one member per
// non-zero count, "<time>-<surface>": counts[time_of_day x 3 + surface], in that index order
// (mix may be NULL: nothing); and sums every shard's mix of a "conditions" object into counts
// (members that are not such labels are skipped).
void rs_synth_dataset__condition_mix_add(cJSON *mix, const int counts[9]);
void rs_synth_dataset__condition_mix_read(int counts[9], const cJSON *mixes);

// The file stem of image k: "%06d_<camera>" with every character but [A-Za-z0-9_-] as '_'.
void rs_synth_dataset__stem(char *stem, size_t n, int k, const char *camera_id);

// What the images of camera c share, computed once and kept in c: its POV-Ray canvas and
// resampling map (rs_synth_canvas_for_lens, rs_synth_canvas_map). Nothing to do when done
// already; on error nothing is kept. The parent of forked workers calls it before forking
// (rs_synth_dataset.c), so that the workers share one copy (copy-on-write) instead of each
// computing its own; rs_synth_dataset__make_image calls it too (then it costs nothing).
rs_status rs_synth_dataset__prepare_camera(rs_synth_dataset__camera *c, rs_err *err);

// What the images over background bm of camera c share, computed once and kept in bm: the
// image at the camera's size in linear light, its appearance, the light its road shows and
// (without a time tag) the sun its poles' shadows show. As rs_synth_dataset__prepare_camera:
// nothing to do when done already, nothing kept on error, called by the parent before forking
// and by rs_synth_dataset__make_image. Memory: 12 bytes per pixel (4.1 MB at 720x480).
rs_status rs_synth_dataset__prepare_background(const rs_synth_dataset__run *d, rs_synth_dataset__camera *c,
                                               rs_synth_dataset__background *bm, rs_err *err);

// DATASET/backgrounds.json (rs_synth_dataset_looks.c; docs/synth.md, "The camera's look"):
// {"applied": false with --no-appearance, "backgrounds": [{"background", "file", "look": {noise_a,
// noise_b, noise_sigma_at_0_5, noise_sigma, blur_sigma_px, jpeg_quality, jpeg_exact, blockiness,
// gain [3]} or null with "why"}]}, one entry per background file of the run's cameras, written
// atomically. The look is the run's cached estimate or made here from the file (the same).
rs_status rs_synth_dataset__write_looks(const rs_synth_dataset__run *d, rs_err *err);

// ---- whose folder it is (rs_synth_dataset_folder.c; issue 42) ----

#define RS_SYNTH_DATASET_MARKER ".roadside-dataset" // written into every folder synth or merge makes

// Makes `dir` a dataset folder of roadside's before anything is written or removed in it: a
// folder holding RS_SYNTH_DATASET_MARKER (a regular file) is roadside's already; a missing or
// empty folder is created and marked; a folder made by an older roadside synth (a run.json with
// a run record) is marked; any other folder (a site, a home folder) is refused with nothing
// created or changed: RS_ERR_INVALID "DIR: not empty (it holds NAME ...) and not a folder WHAT
// made (no .roadside-dataset): refused, nothing written; ...". what: e.g. "roadside synth".
rs_status rs_synth_dataset__claim_folder(const char *dir, const char *what, rs_err *err);

// Removes, in the dataset folder `dir` (held under its lock: no writer left), the temporaries
// of roadside's own file names in its own subfolders only: "<name>.tmp.XXXXXX" (core/rs_io.h)
// and "<name>.<pid>.lnk" (rs_synth_dataset__link_into) where <name> is a name synth writes in
// that folder (run.json, parts/<k>_<camera>.json, <split>/<k>_<camera>.png, ...); the splits
// (Nsplits,) name the per-split folders. Anything else -- a user's "x.tmp.AbC123", files in
// other subfolders -- is left alone. Best effort; returns how many were removed.
size_t rs_synth_dataset__remove_temporaries(const char *dir, const char *const *splits, int Nsplits);

// The run's last write into DATASET/run.json (rewritten atomically): issue 40's mix of
// conditions of this shard's images (Ncondition, time_of_day x 3 + surface) as "conditions":
// {"I/N": {"<time>-<surface>": images, ...}, ...} (one entry per shard run into the folder, this
// one's replaced; beside "run", so neither merge nor a rerun compares it; merge sums them; not
// with --labels-only), then issue 42's completion record: "I/N" added to "finished" (every image
// of the shard made and checked, its files in place, the COCO file assembled). `synth merge`
// refuses a shard without it (killed, or still running); a rerun withdraws it at its start
// (write_run_record) until it finishes.
rs_status rs_synth_dataset__write_completion(const rs_synth_dataset__run *d, const int Ncondition[9], rs_err *err);

// ---- KITTI's copy of an image (rs_synth_dataset_kitti.c) ----

// Camera c's KITTI pinhole core and undistortion map (c->kitti_cam, c->kitti_map): for every
// pixel u of the undistorted image, the lens pixel seeing the direction K^-1 (u, 1)
// (rs_lens_project). Nothing to do when done; nothing kept on error. Called by
// rs_synth_dataset__prepare_camera.
rs_status rs_synth_dataset__prepare_kitti(rs_synth_dataset__camera *c, rs_err *err);

// Image k's KITTI files: kitti/training/image_2/<k>.png (the composite undistorted to the
// pinhole core: OpenCV's remap, linear; hard-linked from `image` for a pinhole lens),
// label_2/<k>.txt (labels computed again through the pinhole core, so the 2D boxes are the
// undistorted image's -- with --bbox visible from the ID pass remapped nearest-neighbour, else
// by geometry alone with the run's visibility --; in the rectified frame of
// rs_synth_labels_kitti_rect), calib/<k>.txt. A vehicle is written when the run's labels keep it
// (kept[i], the other layouts' rule) and its box exists in the undistorted image.
// in: image: the composite's file; composite, ids: the render's (c's size; ids may be NULL);
//     lin: the labels' input for c->cam, run_labels (lin->Nvehicles,) its labels, kept (Nvehicles,)
rs_status rs_synth_dataset__kitti_files(const rs_synth_dataset__run *d, int k, const rs_synth_dataset__camera *c,
                                        const char *image, const rs_image *composite, const uint16_t *ids,
                                        const rs_synth_label_input *lin, const rs_synth_label *run_labels,
                                        const unsigned char *kept, rs_err *err);

// Makes image k (file stem `stem`) for camera c, its labels last (parts/<stem>.json marks it
// finished). out: *grey: rendered over the grey ground (no background); *condition: the
// background's condition as time_of_day x 3 + surface (rs_synth_condition.h), -1 none (the
// grey ground); *seconds_povray grows by the image's povray time.
rs_status rs_synth_dataset__make_image(rs_synth_dataset__run *d, int k, const char *stem, rs_synth_dataset__camera *c,
                                       bool *grey, int *condition, double *seconds_povray, rs_err *err);

// Hard-links src to DATASET/<rel> (replacing what is there, atomically: a link to a temporary
// name, then rename), or copies it when linking fails (another file system).
rs_status rs_synth_dataset__link_into(const rs_synth_dataset__run *d, const char *src, const char *rel, rs_err *err);

// What a rerun finds of an image.
typedef enum {
    RS_SYNTH_DATASET__ABSENT,   // no parts/<stem>.json: never finished
    RS_SYNTH_DATASET__FINISHED, // finished and intact: skipped
    RS_SYNTH_DATASET__DAMAGED,  // its parts/ file is there, but a file of the image is missing or corrupt
} rs_synth_dataset__state;

// Whether image `stem` of camera c is finished: parts/<stem>.json is a regular file holding the
// COCO file of the one image <stem>.png at the camera's (output) size, <split>/<stem>.png is a
// regular file that OpenCV decodes to that size, images/<split>/<stem>.png, labels/<split>/<stem>.txt,
// kitti/training/{image_2,label_2,calib}/<k>.* are regular files (split: 0 or 1, d->split[]). Links count as damage (the run writes none). Cost: one
// PNG decode per finished image.
// out: *state; why[n]: when DAMAGED, the first fault, "FILE: what is wrong"
// Errors: RS_ERR_NOMEM only (a fault of the files is a state, not an error).
rs_status rs_synth_dataset__check_finished(rs_synth_dataset__state *state, char *why, size_t n,
                                           // in
                                           const rs_synth_dataset__run *d, const char *stem,
                                           const rs_synth_dataset__camera *c, int split, rs_err *err);

// Whether `path` is a regular file (not a link) holding a complete PNG (ending with its IEND
// chunk) that OpenCV decodes to width x height; else why not into why[n] ("FILE: cut short (no
// PNG end chunk)", "FILE: 80x45 pixels, its record says 160x90", OpenCV's message). Resume's
// check and merge's (rs_synth_dataset_check.c).
bool rs_synth_dataset__image_intact(const char *path, int width, int height, char *why, size_t n);

// ---- the COCO writer (rs_synth_dataset_coco.c): one for the run's assembly and for merge ----

// One image of the index: its sort key and where it lives.
typedef struct {
    char *file_name;       // owned: the sort key
    int src, pos;          // the source file (rs_synth_dataset__coco_index.src) and the position in its images
    int seq;               // its place in the index as added: by (src, pos)
    double id;             // its id there (its annotations' image_id)
    int k;                 // what the caller numbers the image with (a run's k, merge's "index"), -1 none
    int Nanns;             // annotations naming it
    bool dropped;          // a repeated file name
    int new_id, ann_first; // its id in the output, its first annotation's id
    long img_off, ann_off; // its text in the scratch file
    size_t img_len, ann_len;
} rs_synth_dataset__coco_ref;

typedef struct {
    rs_synth_dataset__coco_ref *r; // (N,) owned
    int N, cap;
    char **src; // (Nsrc,) owned paths
    int Nsrc, cap_src;
    cJSON *info, *licenses, *categories; // owned, each from the first source holding it (may stay NULL)
} rs_synth_dataset__coco_index;

// Called for every image of a source as it is indexed (merge: its files checked and linked).
typedef rs_status (*rs_synth_dataset__coco_each_image)(void *ctx, const cJSON *image, const char *path, rs_err *err);

// Indexes the images of the COCO file at `path` (a new source), each numbered k (k < 0: its
// "index" member, -1 when absent); each (may be NULL) is called for every image. The file is
// parsed, indexed and freed. On error nothing of it stays in the index; errors name the file.
rs_status rs_synth_dataset__coco_index_add(rs_synth_dataset__coco_index *x, const char *path, int k,
                                           rs_synth_dataset__coco_each_image each, void *ctx, rs_err *err);
// Sorts the index by file name (repeated names dropped, the first added kept) and writes the COCO
// file `path` atomically, as a stream (memory bounded by the largest source). *Nimages, *Nanns
// grow by what it holds (NULL: not counted); with ks (x->N,) the kept images' k (>= 0) in
// file-name order, *Nks their count.
rs_status rs_synth_dataset__coco_index_write(rs_synth_dataset__coco_index *x, const char *path, int *Nimages,
                                             int *Nanns, int *ks, int *Nks, rs_err *err);
void rs_synth_dataset__coco_index_free(rs_synth_dataset__coco_index *x);
// YOLO's data.yaml (Ultralytics: train, val, names, the box type; no path: the file's folder is
// the root), KITTI's ImageSets/{train,val}.txt (an empty val.txt when no image is in val) for
// the splits' kept images ks[s] (Nks[s]), and README.md and kitti/README.md (the layouts, the
// splits, the box type `bbox`: rs_synth_bbox_kind), written atomically under out_dir.
rs_status rs_synth_dataset__write_trainer_files(const char *out_dir, const char *const split[2], int *const *ks,
                                                const int *Nks, int bbox, rs_err *err);

// Assembles DATASET/annotations/instances_<split>.json from every parts/ file present for k in
// 0 .. count-1. The images of other shards (made by other runs into this folder) are checked
// with rs_synth_dataset__check_finished (this shard's were, or were just made); a damaged one
// is left out, with a notice (opt->notice) naming the file and the fault, and so is a part file
// that is not a COCO file or lists an image missing from DATASET/<split>.
// out: *Nanns, the annotations in it; *Nleft_out, part files left out.
rs_status rs_synth_dataset__assemble(const rs_synth_dataset__run *d, int *Nanns, int *Nleft_out, rs_err *err);

// The splits of a dataset: the <split> of every DATASET/annotations/instances_<split>.json, sorted;
// names (max,) receives them (owned, free() each), *Nnames their count. Errors: RS_ERR_IO (no
// annotations folder, named), RS_ERR_NOT_FOUND (no instances file), RS_ERR_INVALID (more than
// max), RS_ERR_NOMEM; on error nothing is left allocated.
rs_status rs_synth_dataset__splits(char **names, int *Nnames, int max, const char *dataset_dir, rs_err *err);
