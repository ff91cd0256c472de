// rs_detect_run.c -- a detector run over a list of inputs, written as the detections file
// (eval/detect/rs_detect.h, rs_detect_run).
#include <dirent.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "eval/detect/rs_detect.h"

static const char *const IMAGE_EXTENSIONS[] = {"png", "jpg", "jpeg", "bmp", "tif", "tiff", "webp", "ppm", "pgm"};

static bool is_image_name(const char *name)
{
    if (name[0] == '.') return false; // hidden files, "." and ".."
    for (size_t i = 0; i < sizeof IMAGE_EXTENSIONS / sizeof *IMAGE_EXTENSIONS; i++)
        if (rs_io_has_extension(name, IMAGE_EXTENSIONS[i])) return true;
    return false;
}

static int by_name(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

// The image files of folder `dir`, sorted by name. out: *paths (*Npaths,), each and the array
// malloc'ed (free_list).
static rs_status list_folder(char ***paths, int *Npaths, const char *dir, rs_err *err)
{
    *paths = NULL;
    *Npaths = 0;
    DIR *d = opendir(dir);
    if (!d) return rs_err_set(err, RS_ERR_IO, "%s: cannot list the folder: %s", dir, strerror(errno));
    rs_status st = RS_OK;
    int cap = 0;
    for (struct dirent *e; st == RS_OK && (e = readdir(d));) {
        if (!is_image_name(e->d_name)) continue;
        if (*Npaths == cap) {
            cap = cap ? 2 * cap : 64;
            char **grown = realloc(*paths, (size_t)cap * sizeof *grown);
            if (!grown) {
                st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", dir);
                break;
            }
            *paths = grown;
        }
        char *p = rs_io_join(dir, e->d_name);
        if (!p)
            st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", dir);
        else
            (*paths)[(*Npaths)++] = p;
    }
    closedir(d);
    if (st == RS_OK && *Npaths == 0) st = rs_err_set(err, RS_ERR_NOT_FOUND, "%s: a folder with no image files", dir);
    if (st == RS_OK) qsort(*paths, (size_t)*Npaths, sizeof **paths, by_name);
    return st;
}

static void free_list(char **paths, int N)
{
    for (int i = 0; paths && i < N; i++) free(paths[i]);
    free(paths);
}

// The last path component: what "file_name" records.
static const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash && slash[1] ? slash + 1 : path;
}

// The state a run threads through its inputs.
typedef struct {
    rs_detect_net *net;
    const rs_detect_run_options *opt;
    rs_io_atomic out;
    bool first;    // no detection written yet
    long image_id; // of the last frame detected in
    rs_detect_summary sum;
} run_state;

// One detection as a line of the output's JSON list.
static rs_status write_box(run_state *r, const rs_detect_box *b, long frame, double time_s, const char *file,
                           rs_err *err)
{
    cJSON *o = cJSON_CreateObject();
    cJSON *bbox = cJSON_CreateDoubleArray(b->bbox_px, 4);
    bool ok = o && bbox && cJSON_AddNumberToObject(o, "image_id", (double)r->image_id) &&
              cJSON_AddNumberToObject(o, "category_id", b->category_id);
    if (ok) {
        cJSON_AddItemToObject(o, "bbox", bbox);
        bbox = NULL;
        ok = cJSON_AddNumberToObject(o, "score", b->score) &&
             (!r->opt->camera_id || cJSON_AddStringToObject(o, "camera", r->opt->camera_id)) &&
             cJSON_AddNumberToObject(o, "frame", (double)frame) &&
             (time_s < 0 || cJSON_AddNumberToObject(o, "time_s", time_s)) &&
             cJSON_AddStringToObject(o, "file_name", file);
    }
    char *s = ok ? cJSON_PrintUnformatted(o) : NULL;
    cJSON_Delete(bbox);
    cJSON_Delete(o);
    if (!s) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    const int n = fprintf(r->out.f, "%s\n  %s", r->first ? "[" : ",", s);
    free(s);
    r->first = false;
    if (n < 0) return rs_err_set(err, RS_ERR_IO, "%s: cannot write: %s", r->out.path, strerror(errno));
    return RS_OK;
}

// Every frame of one input (a file or a stream, not a folder), numbered from frame0 (a folder's
// k-th image is frame k of the folder).
static rs_status run_input(run_state *r, const char *input, long frame0, rs_err *err)
{
    rs_detect_frames *frames = NULL;
    rs_status st = rs_detect_frames_open(&frames, input, err);
    if (st) return st;
    double fps = rs_detect_frames_fps(frames);
    if (fps <= 0) fps = r->opt->fps;
    const bool stream = strstr(input, "://") && strncmp(input, "file://", 7) != 0;
    const char *file = stream ? input : base_name(input); // a stream: its URL
    for (long frame = frame0;; frame++) {
        rs_detect_frame f;
        bool got;
        if ((st = rs_detect_frames_next(frames, &f, &got, err)) || !got) break;
        if (frame % r->opt->every) continue;
        if (f.width != r->opt->camera_width || f.height != r->opt->camera_height) {
            st = rs_err_set(err, RS_ERR_INVALID,
                            "%s: frame %ld is %dx%d, the camera %s's model is %dx%d: detections in a resized "
                            "frame would put every point in the wrong place",
                            input, frame, f.width, f.height, r->opt->camera_id ? r->opt->camera_id : "",
                            r->opt->camera_width, r->opt->camera_height);
            break;
        }
        rs_detect_box *boxes = NULL;
        int Nboxes = 0;
        rs_detect_timing t;
        if ((st = rs_detect_net_run(r->net, &boxes, &Nboxes, &t, &f, err))) {
            rs_err_prefix(err, "%s: frame %ld", input, frame);
            break;
        }
        r->image_id++;
        r->sum.Nframes++;
        r->sum.total.preprocess_ms += t.preprocess_ms;
        r->sum.total.forward_ms += t.forward_ms;
        r->sum.total.decode_ms += t.decode_ms;
        const double time_s = fps > 0 ? frame / fps : -1;
        for (int i = 0; st == RS_OK && i < Nboxes; i++) st = write_box(r, &boxes[i], frame, time_s, file, err);
        r->sum.Ndetections += Nboxes;
        free(boxes);
        if (st) break;
    }
    rs_detect_frames_close(frames);
    return st;
}

rs_status rs_detect_run(rs_detect_summary *summary, rs_detect_net *net, const char *const *inputs, int Ninputs,
                        const rs_detect_run_options *opt, const char *out_path, rs_err *err)
{
    if (summary) *summary = (rs_detect_summary){0};
    if (opt->every < 1) return rs_err_set(err, RS_ERR_INVALID, "every: %d is not >= 1", opt->every);
    run_state r = {.net = net, .opt = opt, .first = true};
    rs_status st = rs_io_atomic_open(&r.out, out_path, err);
    if (st) return st;
    long still = 0; // consecutive image files are one sequence, as a folder's: frames 0, 1, ...
    for (int i = 0; st == RS_OK && i < Ninputs; i++) {
        struct stat sb;
        const bool image = !strstr(inputs[i], "://") && is_image_name(base_name(inputs[i]));
        if (!image) still = 0;
        if (!strstr(inputs[i], "://") && stat(inputs[i], &sb) == 0 && S_ISDIR(sb.st_mode)) {
            char **paths = NULL;
            int Npaths = 0;
            st = list_folder(&paths, &Npaths, inputs[i], err);
            // a folder is one input: its images are its frames 0, 1, ... (time_s = frame / fps)
            for (int k = 0; st == RS_OK && k < Npaths; k++)
                if (k % opt->every == 0) st = run_input(&r, paths[k], k, err);
            free_list(paths, Npaths);
        } else if (image) {
            if (still++ % opt->every == 0) st = run_input(&r, inputs[i], still - 1, err);
        } else {
            st = run_input(&r, inputs[i], 0, err);
        }
    }
    if (st == RS_OK && fputs(r.first ? "[]\n" : "\n]\n", r.out.f) < 0)
        st = rs_err_set(err, RS_ERR_IO, "%s: cannot write: %s", out_path, strerror(errno));
    if (st == RS_OK)
        st = rs_io_atomic_commit(&r.out, err);
    else
        rs_io_atomic_abort(&r.out);
    if (summary && st == RS_OK) *summary = r.sum;
    return st;
}
