// rs_synth_dataset_check.c -- resuming `roadside synth` (synth/dataset/rs_synth_dataset.h): whether an
// image whose parts/ file is present really is finished. Its parts/ file must parse as the COCO
// file of that one image at the camera's size, and every file of the image must be a regular
// file: the PNG (decoded through OpenCV, at the size the part states), its YOLO and KITTI files.
// Called by rs_synth_dataset.c before skipping an image; calls core/ and cJSON.
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cjson/cJSON.h>

#include "core/rs_image.h"
#include "core/rs_io.h"
#include "synth/dataset/internal/rs_synth_dataset_internal.h"

// "" when `path` is a regular file (not followed if a link: a link is not the run's output),
// else why not, into why[n]. Returns whether it is.
static bool regular_file(const char *path, char *why, size_t n)
{
    struct stat sb;
    if (lstat(path, &sb) != 0)
        snprintf(why, n, "%s: %s", path, errno == ENOENT ? "missing" : strerror(errno));
    else if (!S_ISREG(sb.st_mode))
        snprintf(why, n, "%s: not a regular file", path);
    else
        return true;
    return false;
}

// Checks the part file's text: the COCO file of the one image `file_name` of width x height.
static bool part_ok(const char *part, const char *file_name, int width, int height, char *why, size_t n)
{
    char *text = NULL;
    rs_err e = {RS_OK, ""};
    if (rs_io_read_file_max(&text, NULL, part, RS_IO_MAX_SMALL_FILE_BYTES, &e)) {
        snprintf(why, n, "%s", e.msg);
        return false;
    }
    cJSON *doc = cJSON_Parse(text);
    free(text);
    const cJSON *images = cJSON_GetObjectItemCaseSensitive(doc, "images");
    const cJSON *im = cJSON_GetArrayItem(images, 0);
    const cJSON *fn = cJSON_GetObjectItemCaseSensitive(im, "file_name");
    const cJSON *w = cJSON_GetObjectItemCaseSensitive(im, "width"), *h = cJSON_GetObjectItemCaseSensitive(im, "height");
    bool ok = false;
    if (!doc)
        snprintf(why, n, "%s: not JSON (cut short or overwritten)", part);
    else if (!cJSON_IsArray(images) || cJSON_GetArraySize(images) != 1 ||
             !cJSON_IsArray(cJSON_GetObjectItemCaseSensitive(doc, "annotations")) || !cJSON_IsString(fn) ||
             strcmp(fn->valuestring, file_name) != 0 || !cJSON_IsNumber(w) || !cJSON_IsNumber(h))
        snprintf(why, n, "%s: not the COCO file of the one image %s (images, annotations)", part, file_name);
    else if (w->valuedouble != width || h->valuedouble != height)
        snprintf(why, n, "%s: the image is %gx%g, this run makes %dx%d (another --size?)", part, w->valuedouble,
                 h->valuedouble, width, height);
    else
        ok = true;
    cJSON_Delete(doc);
    return ok;
}

// Whether the PNG file ends with its IEND chunk (the 12 bytes every complete PNG ends with, PNG
// specification 11.2.5): a file cut short is told apart without handing it to libpng, which
// prints its own complaint on stderr.
static bool png_complete(const char *path, char *why, size_t n)
{
    static const unsigned char iend[12] = {0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xae, 0x42, 0x60, 0x82};
    unsigned char tail[12];
    FILE *f = fopen(path, "rb");
    const bool ok = f && fseek(f, -12, SEEK_END) == 0 && fread(tail, 1, 12, f) == 12 && !memcmp(tail, iend, 12);
    if (f) fclose(f);
    if (!ok) snprintf(why, n, "%s: cut short (no PNG end chunk)", path);
    return ok;
}

bool rs_synth_dataset__image_intact(const char *path, int width, int height, char *why, size_t n)
{
    if (!regular_file(path, why, n) || !png_complete(path, why, n)) return false;
    rs_image img = {0};
    rs_err e = {RS_OK, ""};
    if (rs_image_read(&img, path, &e)) {
        snprintf(why, n, "%s", e.msg);
        return false;
    }
    const bool ok = img.width == width && img.height == height;
    if (!ok) snprintf(why, n, "%s: %dx%d pixels, its record says %dx%d", path, img.width, img.height, width, height);
    rs_image_free(&img);
    return ok;
}

rs_status rs_synth_dataset__check_finished(rs_synth_dataset__state *state, char *why, size_t n,
                                           const rs_synth_dataset__run *d, const char *stem,
                                           const rs_synth_dataset__camera *c, int split, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    char name[600], file_name[320];
    why[0] = 0;
    *state = RS_SYNTH_DATASET__DAMAGED;
    snprintf(name, sizeof(name), "%s.json", stem);
    char *part = rs_io_join(d->parts_dir, name);
    snprintf(file_name, sizeof(file_name), "%s.png", stem);
    char *image = d->split_dir[split] ? rs_io_join(d->split_dir[split], file_name) : NULL;
    // the other files of the image: YOLO's image and labels, KITTI's image, labels and calib
    char *side[5] = {NULL};
    const int k = atoi(stem); // the stem starts with k, "%06d_<camera>"
    snprintf(name, sizeof(name), "images/%s/%s.png", d->split[split], stem);
    side[0] = rs_io_join(opt->out_dir, name);
    snprintf(name, sizeof(name), "labels/%s/%s.txt", d->split[split], stem);
    side[1] = rs_io_join(opt->out_dir, name);
    snprintf(name, sizeof(name), "kitti/training/image_2/%06d.png", k);
    side[2] = rs_io_join(opt->out_dir, name);
    snprintf(name, sizeof(name), "kitti/training/label_2/%06d.txt", k);
    side[3] = rs_io_join(opt->out_dir, name);
    snprintf(name, sizeof(name), "kitti/training/calib/%06d.txt", k);
    side[4] = rs_io_join(opt->out_dir, name);
    rs_status st = RS_OK;
    struct stat sb;
    bool have_all = part && image;
    for (int i = 0; i < 5; i++) have_all = have_all && side[i];
    if (!have_all)
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    else if (lstat(part, &sb) != 0 && errno == ENOENT)
        *state = RS_SYNTH_DATASET__ABSENT;
    else if (opt->labels_only) { // a sequence's labels alone: the part file is all there is
        if (regular_file(part, why, n) && part_ok(part, file_name, c->cam.width, c->cam.height, why, n))
            *state = RS_SYNTH_DATASET__FINISHED;
    } else if (regular_file(part, why, n) && part_ok(part, file_name, c->cam.width, c->cam.height, why, n) &&
               rs_synth_dataset__image_intact(image, c->cam.width, c->cam.height, why, n)) {
        bool ok = true;
        for (int i = 0; i < 5 && ok; i++) ok = regular_file(side[i], why, n);
        if (ok) *state = RS_SYNTH_DATASET__FINISHED;
    }
    free(part);
    free(image);
    for (int i = 0; i < 5; i++) free(side[i]);
    return st;
}
