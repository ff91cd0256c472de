// roadside localise -- every detection to the road, with its covariance (docs/localise.md).
#define _POSIX_C_SOURCE 200809L // strdup
#include <dirent.h>
#include <getopt.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"
#include "core/rs_io.h"
#include "eval/localise/rs_localise.h"
#include "eval/localise/rs_localise_dataset.h"
#include "geo/rs_site.h"

static void usage(FILE *out)
{
    fprintf(out, "usage: roadside localise DETS.json --dataset DATASET [--split NAME] [--site SITE] [OPTIONS] -o OUT\n"
                 "       roadside localise DETS --site SITE --calib DIR --camera ID [--fps F] [OPTIONS] -o OUT\n"
                 "\n"
                 "Places every detection on the road: the ground-contact pixel of its box, through the\n"
                 "full lens model of its camera, met with the site's ground plane; with the 2x2\n"
                 "covariance of its (E, N) from the calibration's pose covariance and the detector's\n"
                 "pixel noise, Cov = J_pose C_pose J_pose^T + J_px (S^2 I) J_px^T (docs/localise.md).\n"
                 "\n"
                 "  DETS               COCO results JSON (a list of {image_id, category_id, bbox, score},\n"
                 "                     optionally camera, frame, time_s, file_name, bottom_center), MOT\n"
                 "                     Challenge CSV (frame,id,bb_left,bb_top,bb_width,bb_height,conf,...;\n"
                 "                     1-based frames and pixels) or a folder of Ultralytics txt files\n"
                 "                     (<image>.txt: class cx cy w h [conf], normalised); by its name:\n"
                 "                     a folder, *.json, anything else MOT\n"
                 "  --dataset DATASET  a roadside dataset: DETS.json's image ids are those of\n"
                 "                     DATASET/annotations/instances_<split>.json, each image's camera\n"
                 "                     model (SHA-256 checked), ground plane and pose covariance are the\n"
                 "                     ones the dataset records (COCO results only)\n"
                 "  --split NAME       the split (default: the dataset's only one)\n"
                 "  --site SITE        the site: its ground plane and origin (with --dataset: only the\n"
                 "                     origin, for lat_deg and lon_deg; without it they are empty)\n"
                 "  --calib DIR        DIR/<ID>.cameramodel and DIR/<ID>.json (the pose covariance) as\n"
                 "                     'roadside calib' writes them\n"
                 "  --camera ID        the camera that saw DETS\n"
                 "  --fps F            frames per second of MOT and Ultralytics input (time_s = frame / F)\n"
                 "  --point P          the box's ground-contact pixel: center (x + w/2, y + h/2; default\n"
                 "                     for COCO: roadside's footprint boxes), bottom (x + w/2, y + h;\n"
                 "                     default for MOT and Ultralytics: ordinary detectors' boxes) or\n"
                 "                     shift (x + w/2, y + h/2 + K h); a COCO bottom_center wins\n"
                 "  --shift K          K of --point shift (default 0.35, the paper's)\n"
                 "  --pixel-sigma S    the detector's pixel noise per axis, px (default 2)\n"
                 "  -o, --output OUT   the located detections: .csv, .jsonl or .geojson (written\n"
                 "                     atomically; columns in docs/localise.md)\n"
                 "\n"
                 "Detections whose ray misses the ground (above the horizon, behind the camera, outside\n"
                 "the lens's valid field) are not written; their count is printed. A camera whose\n"
                 "calibration carries no pose covariance gets a warning and pixel noise only.\n"
                 "Exit status: 0 ok, 1 bad input (the message names the file, line and field; nothing\n"
                 "is written), 2 usage error.\n");
}

typedef struct {
    const char *dets, *dataset, *split, *site, *calib, *camera, *out;
    double fps, shift, pixel_sigma;
    bool point_given;
    rs_localise_point point;
} localise_args;

static int parse_args(int argc, char **argv, localise_args *a)
{
    *a = (localise_args){.shift = RS_LOCALISE_SHIFT_DEFAULT, .pixel_sigma = RS_LOCALISE_PIXEL_SIGMA_PX};
    enum { O_DATASET = 256, O_SPLIT, O_SITE, O_CALIB, O_CAMERA, O_FPS, O_POINT, O_SHIFT, O_SIGMA };
    static const struct option options[] = {{"dataset", required_argument, NULL, O_DATASET},
                                            {"split", required_argument, NULL, O_SPLIT},
                                            {"site", required_argument, NULL, O_SITE},
                                            {"calib", required_argument, NULL, O_CALIB},
                                            {"camera", required_argument, NULL, O_CAMERA},
                                            {"fps", required_argument, NULL, O_FPS},
                                            {"point", required_argument, NULL, O_POINT},
                                            {"shift", required_argument, NULL, O_SHIFT},
                                            {"pixel-sigma", required_argument, NULL, O_SIGMA},
                                            {"output", required_argument, NULL, 'o'},
                                            {NULL, 0, NULL, 0}};
    opterr = 0;
    optind = 0;
    int c;
    while ((c = getopt_long(argc, argv, ":o:", options, NULL)) != -1) {
        switch (c) {
        case O_DATASET: a->dataset = optarg; break;
        case O_SPLIT: a->split = optarg; break;
        case O_SITE: a->site = optarg; break;
        case O_CALIB: a->calib = optarg; break;
        case O_CAMERA: a->camera = optarg; break;
        case 'o': a->out = optarg; break;
        case O_FPS:
            if (!rs_cli_parse_double(optarg, &a->fps) || !(a->fps > 0))
                return rs_cli_usage_error("localise", "--fps: '%s' is not a number > 0", optarg);
            break;
        case O_SHIFT:
            if (!rs_cli_parse_double(optarg, &a->shift))
                return rs_cli_usage_error("localise", "--shift: '%s' is not a finite number", optarg);
            break;
        case O_SIGMA:
            if (!rs_cli_parse_double(optarg, &a->pixel_sigma) || a->pixel_sigma < 0)
                return rs_cli_usage_error("localise", "--pixel-sigma: '%s' is not a number >= 0", optarg);
            break;
        case O_POINT:
            if (!rs_localise_point_parse(&a->point, optarg))
                return rs_cli_usage_error("localise", "--point: '%s' is not center, bottom or shift", optarg);
            a->point_given = true;
            break;
        case ':': return rs_cli_usage_error("localise", "%s needs a value", argv[optind - 1]);
        default: return rs_cli_usage_error("localise", "unknown option '%s'", argv[optind - 1]);
        }
    }
    if (argc - optind != 1)
        return rs_cli_usage_error("localise", "expected one detections file, got %d file argument(s)", argc - optind);
    a->dets = argv[optind];
    if (!a->out) return rs_cli_usage_error("localise", "-o OUT is required");
    if (a->dataset) {
        if (a->calib || a->camera || a->fps > 0)
            return rs_cli_usage_error("localise", "--dataset reads each image's camera from the dataset: "
                                                  "--calib, --camera and --fps belong to the --site way");
    } else {
        if (!a->site || !a->calib || !a->camera)
            return rs_cli_usage_error("localise", "give --dataset DATASET, or --site, --calib and --camera");
        if (a->split) return rs_cli_usage_error("localise", "--split needs --dataset");
    }
    return RS_EXIT_OK;
}

// The default point: center for COCO results (roadside's footprint boxes), bottom for MOT and
// Ultralytics (ordinary detectors' boxes).
static rs_localise_point default_point(const localise_args *a)
{
    if (a->point_given) return a->point;
    return rs_io_has_extension(a->dets, "json") ? RS_LOCALISE_POINT_CENTER : RS_LOCALISE_POINT_BOTTOM;
}

// DATASET/annotations/instances_<split>.json: the given split, or the only one. Prints and
// returns NULL on failure; the caller frees the path.
static char *find_split(const char *dataset, const char *split)
{
    char *dir = rs_io_join(dataset, "annotations");
    char name[512], found[512] = "", list[2048] = "";
    int n = 0;
    if (split) snprintf(name, sizeof name, "instances_%s.json", split);
    DIR *dp = dir ? opendir(dir) : NULL;
    if (!dp) {
        fprintf(stderr, "roadside localise: %s: not a roadside dataset (no annotations/ folder)\n", dataset);
        free(dir);
        return NULL;
    }
    for (struct dirent *e; (e = readdir(dp));) {
        size_t len = strlen(e->d_name);
        if (strncmp(e->d_name, "instances_", 10) != 0 || len <= 15 || strcmp(e->d_name + len - 5, ".json") != 0)
            continue;
        n++;
        snprintf(found, sizeof found, "%s", e->d_name);
        size_t used = strlen(list);
        snprintf(list + used, sizeof list - used, "%s%.*s", used ? ", " : "", (int)(len - 15), e->d_name + 10);
    }
    closedir(dp);
    char *path = NULL;
    if (split) {
        path = rs_io_join(dir, name);
        if (path && rs_io_check_regular(path, (size_t)-1, NULL) != RS_OK) {
            fprintf(stderr, "roadside localise: --split %s: no %s (the dataset's splits: %s)\n", split, path,
                    n ? list : "none");
            free(path);
            path = NULL;
        }
    } else if (n == 1)
        path = rs_io_join(dir, found);
    else
        fprintf(stderr, "roadside localise: %s has %d splits (%s): choose one with --split\n", dataset, n,
                n ? list : "none");
    free(dir);
    return path;
}

// One camera of the run: its model, covariance and ground plane.
typedef struct {
    rs_camera cam;
    double C[36];
    bool has_C;
    const char *model; // not owned
    rs_localise_view view;
} view_slot;

typedef struct {
    size_t Nread, Nlocated, Nmissed;
    int Nviews, Nwithout_cov;
} summary;

// Locates dets[k] through view_of[k] (an index into views) into rows; counts the misses.
static rs_status locate_all(rs_localise_row *rows, summary *s, const rs_localise_detection *dets, size_t N,
                            const view_slot *views, const int *view_of, const rs_localise_options *opt, rs_err *err)
{
    for (size_t k = 0; k < N; k++) {
        rs_err e = {0};
        rs_status st = rs_localise_detection_locate(&rows[s->Nlocated], &dets[k], &views[view_of[k]].view, opt, &e);
        if (st == RS_ERR_DEGENERATE)
            s->Nmissed++;
        else if (st) {
            *err = e;
            return st;
        } else
            s->Nlocated++;
    }
    return RS_OK;
}

static void warn_no_cov(const char *model)
{
    fprintf(stderr,
            "roadside localise: warning: %s: no pose covariance beside it (calib's <id>.json): the covariances "
            "hold the pixel noise only\n",
            model);
}

// Pairs (id, index) by id.
static int cmp_id(const void *x, const void *y)
{
    const long long *a = x, *b = y;
    return (a[0] > b[0]) - (a[0] < b[0]);
}

// --dataset: each image's camera as the dataset records it.
static int run_dataset(const localise_args *a, rs_localise_detection *dets, size_t N, const rs_llh *origin,
                       rs_localise_row *rows, summary *s)
{
    char *gt = find_split(a->dataset, a->split);
    if (!gt) return RS_EXIT_FAIL;
    rs_err err = {0};
    rs_localise_image *images = NULL;
    size_t Nimages = 0;
    rs_status st = rs_localise_images_read(&images, &Nimages, gt, &err);
    view_slot *views = calloc(Nimages ? Nimages : 1, sizeof *views);
    int *view_of_image = malloc((Nimages ? Nimages : 1) * sizeof *view_of_image);
    int *view_of = malloc((N ? N : 1) * sizeof *view_of);
    if (!st && (!views || !view_of_image || !view_of)) st = rs_err_set(&err, RS_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < Nimages && !st; i++) {
        const rs_localise_calibration *cal = &images[i].calibration;
        int v = -1; // one view per distinct model and plane
        for (int j = 0; j < s->Nviews && v < 0; j++)
            if (!strcmp(views[j].model, cal->camera_model) &&
                !memcmp(views[j].view.ground_normal_enu, cal->ground_normal_enu, sizeof cal->ground_normal_enu) &&
                views[j].view.ground_offset_m == cal->ground_offset_m)
                v = j;
        if (v < 0) {
            view_slot *w = &views[v = s->Nviews];
            if ((st = rs_localise_camera_read_checked(&w->cam, cal->camera_model, cal->camera_model_sha256,
                                                      images[i].id, &err)))
                break;
            s->Nviews++;
            if ((st = rs_localise_covariance_read(w->C, &w->has_C, cal->camera_model, &err))) break;
            w->model = cal->camera_model;
            w->view = rs_localise_view_make(&w->cam, w->has_C ? w->C : NULL, cal->ground_normal_enu,
                                            cal->ground_offset_m, origin);
            if (!w->has_C) {
                if (!s->Nwithout_cov) warn_no_cov(cal->camera_model);
                s->Nwithout_cov++;
            }
        }
        view_of_image[i] = v;
    }
    // every detection's image: by id (sorted ids, bisection)
    long long *ids = st ? NULL : malloc((Nimages ? Nimages : 1) * 2 * sizeof *ids);
    if (!st && !ids) st = rs_err_set(&err, RS_ERR_NOMEM, "out of memory");
    if (!st) {
        for (size_t i = 0; i < Nimages; i++) ids[2 * i] = images[i].id, ids[2 * i + 1] = (long long)i;
        qsort(ids, Nimages, 2 * sizeof *ids, cmp_id);
    }
    for (size_t k = 0; k < N && !st; k++) {
        size_t lo = 0, hi = Nimages;
        while (lo < hi) {
            size_t mid = lo + (hi - lo) / 2;
            if (ids[2 * mid] < dets[k].image_id)
                lo = mid + 1;
            else
                hi = mid;
        }
        if (lo == Nimages || ids[2 * lo] != dets[k].image_id) {
            st = rs_err_set(&err, RS_ERR_NOT_FOUND, "%s:%d: image_id: %lld is not an image of %s", a->dets,
                            dets[k].line, dets[k].image_id, gt);
            break;
        }
        const rs_localise_image *im = &images[ids[2 * lo + 1]];
        view_of[k] = view_of_image[ids[2 * lo + 1]];
        if (!dets[k].camera[0]) memcpy(dets[k].camera, im->camera, sizeof im->camera);
        if (isnan(dets[k].time_s)) dets[k].time_s = im->time_s;
        if (dets[k].frame < 0) dets[k].frame = im->frame;
    }
    const rs_localise_options opt = {.point = default_point(a), .shift = a->shift, .pixel_sigma_px = a->pixel_sigma};
    if (!st) st = locate_all(rows, s, dets, N, views, view_of, &opt, &err);
    free(ids);
    for (int j = 0; j < s->Nviews; j++) rs_camera_free(&views[j].cam);
    free(views);
    free(view_of_image);
    free(view_of);
    rs_localise_images_free(images, Nimages);
    free(gt);
    return st ? rs_cli_fail("localise", st, &err) : RS_EXIT_OK;
}

// --site --calib --camera: one camera for every detection. Reads the detections itself (the
// camera's image size scales Ultralytics' boxes).
static int run_site(const localise_args *a, const rs_site *site, rs_localise_detection **dets, size_t *N,
                    rs_localise_row **rows, summary *s)
{
    rs_err err = {0};
    view_slot w = {0};
    char model[4096];
    rs_status st = RS_OK;
    if (rs_site_find_camera(site, a->camera) < 0)
        return rs_cli_usage_error("localise", "--camera: no camera \"%s\" in %s", a->camera, a->site);
    if (!rs_camera_path(model, sizeof model, a->calib, a->camera, RS_CAMERA_EXT_CAMERAMODEL))
        st = rs_err_set(&err, RS_ERR_INVALID, "%s: path too long", a->calib);
    if (!st) st = rs_camera_read(&w.cam, NULL, model, &err);
    if (!st) st = rs_localise_covariance_read(w.C, &w.has_C, model, &err);
    if (!st) st = rs_localise_read_detections(dets, N, a->dets, w.cam.width, w.cam.height, a->fps, &err);
    if (!st && !(*rows = malloc((*N ? *N : 1) * sizeof **rows))) st = rs_err_set(&err, RS_ERR_NOMEM, "out of memory");
    int *view_of = st ? NULL : calloc(*N ? *N : 1, sizeof *view_of);
    if (!st && !view_of) st = rs_err_set(&err, RS_ERR_NOMEM, "out of memory");
    if (!st) {
        s->Nread = *N;
        s->Nviews = 1;
        if (!w.has_C) {
            warn_no_cov(model);
            s->Nwithout_cov = 1;
        }
        w.view = rs_localise_view_make(&w.cam, w.has_C ? w.C : NULL, site->ground_normal_enu, site->ground_offset_m,
                                       &site->origin);
        for (size_t k = 0; k < *N; k++) snprintf((*dets)[k].camera, sizeof(*dets)[k].camera, "%s", a->camera);
        const rs_localise_options opt = {
            .point = default_point(a), .shift = a->shift, .pixel_sigma_px = a->pixel_sigma};
        st = locate_all(*rows, s, *dets, *N, &w, view_of, &opt, &err);
    }
    free(view_of);
    rs_camera_free(&w.cam);
    return st ? rs_cli_fail("localise", st, &err) : RS_EXIT_OK;
}

int rs_cli_localise(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        usage(stdout);
        return RS_EXIT_OK;
    }
    localise_args a;
    int rc = parse_args(argc, argv, &a);
    if (rc) return rc;
    if (strlen(a.camera ? a.camera : "") >= RS_LOCALISE_ID_MAX)
        return rs_cli_usage_error("localise", "--camera: longer than %d bytes", RS_LOCALISE_ID_MAX - 1);
    if (!rs_io_has_extension(a.out, "csv") && !rs_io_has_extension(a.out, "jsonl") &&
        !rs_io_has_extension(a.out, "geojson"))
        return rs_cli_usage_error("localise", "-o %s: the extension must be .csv, .jsonl or .geojson", a.out);
    rs_site *site = NULL;
    if (a.site && !(site = rs_cli_load_site("localise", a.site))) return RS_EXIT_FAIL;
    rs_localise_detection *dets = NULL;
    rs_localise_row *rows = NULL;
    size_t N = 0;
    summary s = {0};
    rs_err err = {0};
    if (a.dataset) {
        if (!rs_io_has_extension(a.dets, "json"))
            rc = rs_cli_usage_error("localise", "--dataset takes COCO results (*.json), not %s", a.dets);
        rs_status st = rc ? RS_OK : rs_localise_read_detections(&dets, &N, a.dets, 0, 0, 0, &err);
        if (!rc && !st && !(rows = malloc((N ? N : 1) * sizeof *rows)))
            st = rs_err_set(&err, RS_ERR_NOMEM, "out of memory");
        if (!rc && st) rc = rs_cli_fail("localise", st, &err);
        s.Nread = N;
        if (!rc) rc = run_dataset(&a, dets, N, site ? &site->origin : NULL, rows, &s);
    } else
        rc = run_site(&a, site, &dets, &N, &rows, &s);
    if (!rc) {
        rs_status st = rs_localise_write(a.out, rows, s.Nlocated, &err);
        if (st) rc = rs_cli_fail("localise", st, &err);
    }
    if (!rc) {
        if (s.Nmissed)
            printf("%zu detection(s) miss the ground (above the horizon, behind the camera or outside the lens's "
                   "field): not written\n",
                   s.Nmissed);
        const char *point_name[] = {"center", "bottom", "shift"};
        printf("localise: %zu detection(s) read, %zu located, %zu missed; %d camera model(s), %d without pose "
               "covariance; point %s, pixel sigma %g px; wrote %s\n",
               s.Nread, s.Nlocated, s.Nmissed, s.Nviews, s.Nwithout_cov, point_name[default_point(&a)], a.pixel_sigma,
               a.out);
    }
    free(dets);
    free(rows);
    rs_site_free(site);
    return rc;
}
