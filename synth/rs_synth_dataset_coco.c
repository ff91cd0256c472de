// rs_synth_dataset_coco.c -- the COCO files of `roadside synth` (synth/rs_synth_dataset.h):
// an accumulator of images and their annotations read from COCO files, assembling DATASET's
// annotations/instances_<split>.json from the finished images' parts/ files, and merging
// datasets (shards) into one (rs_synth_dataset_merge), their images hard-linked. Called by
// rs_synth_dataset.c (and the cli, for merge); calls core/ and cJSON.
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "synth/internal/rs_synth_dataset_internal.h"

// ---- COCO assembly (run and merge) ----

typedef struct {
    const char *file_name; // borrowed from image
    cJSON *image;          // owned
    cJSON *anns;           // owned array
} coco_entry;

typedef struct {
    coco_entry *e;
    int N, cap;
    cJSON *categories; // owned, from the first document
} coco_acc;

static void coco_acc_free(coco_acc *a)
{
    for (int i = 0; i < a->N; i++) {
        cJSON_Delete(a->e[i].image);
        cJSON_Delete(a->e[i].anns);
    }
    free(a->e);
    cJSON_Delete(a->categories);
    memset(a, 0, sizeof(*a));
}

// Adds the images (with their annotations) of a COCO file to the accumulator.
static rs_status coco_add_file(coco_acc *a, const char *path, rs_err *err)
{
    char *text = NULL;
    rs_status st = rs_io_read_file(&text, NULL, path, err);
    if (st) return st;
    cJSON *doc = cJSON_Parse(text);
    free(text);
    const cJSON *images = cJSON_GetObjectItemCaseSensitive(doc, "images");
    const cJSON *anns = cJSON_GetObjectItemCaseSensitive(doc, "annotations"), *im, *an;
    if (!cJSON_IsArray(images) || !cJSON_IsArray(anns)) {
        cJSON_Delete(doc);
        return rs_err_set(err, RS_ERR_PARSE, "%s: not a COCO file (images, annotations)", path);
    }
    if (!a->categories) a->categories = cJSON_Duplicate(cJSON_GetObjectItemCaseSensitive(doc, "categories"), 1);
    cJSON_ArrayForEach(im, images)
    {
        const cJSON *id = cJSON_GetObjectItemCaseSensitive(im, "id");
        const cJSON *fn = cJSON_GetObjectItemCaseSensitive(im, "file_name");
        if (!cJSON_IsNumber(id) || !cJSON_IsString(fn)) {
            cJSON_Delete(doc);
            return rs_err_set(err, RS_ERR_PARSE, "%s: images[]: id or file_name missing", path);
        }
        if (a->N == a->cap) {
            int cap = a->cap ? 2 * a->cap : 64;
            coco_entry *e = realloc(a->e, (size_t)cap * sizeof(*e));
            if (!e) {
                cJSON_Delete(doc);
                return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            }
            a->e = e;
            a->cap = cap;
        }
        coco_entry *e = &a->e[a->N++];
        e->image = cJSON_Duplicate(im, 1);
        e->anns = cJSON_CreateArray();
        e->file_name = cJSON_GetObjectItemCaseSensitive(e->image, "file_name")->valuestring;
        cJSON_ArrayForEach(an, anns)
        {
            const cJSON *iid = cJSON_GetObjectItemCaseSensitive(an, "image_id");
            if (cJSON_IsNumber(iid) && iid->valuedouble == id->valuedouble)
                cJSON_AddItemToArray(e->anns, cJSON_Duplicate(an, 1));
        }
    }
    cJSON_Delete(doc);
    return RS_OK;
}

static int entry_cmp(const void *a, const void *b)
{
    return strcmp(((const coco_entry *)a)->file_name, ((const coco_entry *)b)->file_name);
}

// Sorts by file name, drops repeated names, renumbers, writes `path`. *Nimages, *Nanns out.
static rs_status coco_write(coco_acc *a, const char *path, int *Nimages, int *Nanns, rs_err *err)
{
    qsort(a->e, (size_t)a->N, sizeof(coco_entry), entry_cmp);
    cJSON *doc = cJSON_CreateObject();
    cJSON *images = cJSON_AddArrayToObject(doc, "images");
    cJSON *anns = cJSON_AddArrayToObject(doc, "annotations");
    cJSON_AddItemToObject(doc, "categories", a->categories ? cJSON_Duplicate(a->categories, 1) : cJSON_CreateArray());
    int ni = 0, na = 0;
    for (int i = 0; i < a->N; i++) {
        if (i > 0 && strcmp(a->e[i].file_name, a->e[i - 1].file_name) == 0) continue;
        ni++;
        cJSON *im = cJSON_Duplicate(a->e[i].image, 1);
        cJSON_ReplaceItemInObjectCaseSensitive(im, "id", cJSON_CreateNumber(ni));
        cJSON_AddItemToArray(images, im);
        cJSON *an;
        cJSON_ArrayForEach(an, a->e[i].anns)
        {
            cJSON *x = cJSON_Duplicate(an, 1);
            cJSON_ReplaceItemInObjectCaseSensitive(x, "id", cJSON_CreateNumber(++na));
            cJSON_ReplaceItemInObjectCaseSensitive(x, "image_id", cJSON_CreateNumber(ni));
            cJSON_AddItemToArray(anns, x);
        }
    }
    char *text = cJSON_Print(doc);
    cJSON_Delete(doc);
    if (!text) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = rs_io_write_file(path, text, strlen(text), err);
    free(text);
    if (Nimages) *Nimages += ni;
    if (Nanns) *Nanns += na;
    return st;
}

// ---- assembling DATASET's COCO file ----

// Drops the entries from `first` on (those of a file left out).
static void coco_acc_truncate(coco_acc *a, int first)
{
    for (int i = first; i < a->N; i++) {
        cJSON_Delete(a->e[i].image);
        cJSON_Delete(a->e[i].anns);
    }
    if (first < a->N) a->N = first;
}

// Leaves a part file out of the COCO file: counts it, and tells why.
static void leave_out(const rs_synth_dataset_options *opt, const char *why, int *Nleft_out)
{
    (*Nleft_out)++;
    if (opt->notice) {
        char msg[1400];
        snprintf(msg, sizeof(msg), "%.1200s: left out of the COCO file (a rerun of its shard remakes it)", why);
        opt->notice(opt->notice_ctx, msg);
    }
}

// Adds a parts/ file unless it is not a COCO file or lists an image missing from split_dir:
// then it is left out, with a notice. Errors: RS_ERR_NOMEM only.
static rs_status add_part(coco_acc *a, const char *part, const char *split_dir, const rs_synth_dataset_options *opt,
                          int *Nleft_out, rs_err *err)
{
    const int first = a->N;
    rs_err e = {RS_OK, ""};
    char why[1200] = "";
    rs_status st = coco_add_file(a, part, &e);
    if (st == RS_ERR_NOMEM) return rs_err_set(err, st, "%s", e.msg);
    if (st) snprintf(why, sizeof(why), "%s", e.msg);
    for (int i = first; i < a->N && !why[0]; i++) {
        char *image = rs_io_join(split_dir, a->e[i].file_name);
        struct stat sb;
        if (!image) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        const bool there = lstat(image, &sb) == 0;
        if (!there || !S_ISREG(sb.st_mode))
            snprintf(why, sizeof(why), "%s: lists %s, which is %s", part, image,
                     !there ? "missing" : "not a regular file");
        free(image);
    }
    if (!why[0]) return RS_OK;
    coco_acc_truncate(a, first);
    leave_out(opt, why, Nleft_out);
    return RS_OK;
}

rs_status rs_synth_dataset__assemble(const rs_synth_dataset__run *d, int *Nanns, int *Nleft_out, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    coco_acc a = {0};
    rs_status st = RS_OK;
    char name[600], *path = NULL;
    *Nleft_out = 0;
    for (int k = 0; k < opt->count && !st; k++) {
        char stem[300];
        rs_synth_dataset__stem(stem, sizeof(stem), k, d->cams[k % d->Ncams].id);
        snprintf(name, sizeof(name), "%s.json", stem);
        char *part = rs_io_join(d->parts_dir, name);
        struct stat sb;
        rs_synth_dataset__state state = RS_SYNTH_DATASET__FINISHED;
        char why[600];
        // another shard's image: checked as a rerun checks its own (this shard's were just now)
        if (part && lstat(part, &sb) == 0 && k % opt->shard_count != opt->shard_index)
            st = rs_synth_dataset__check_finished(&state, why, sizeof(why), d, stem, &d->cams[k % d->Ncams], err);
        if (!part)
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        else if (!st && state == RS_SYNTH_DATASET__DAMAGED)
            leave_out(opt, why, Nleft_out);
        else if (!st && lstat(part, &sb) == 0)
            st = add_part(&a, part, d->split_dir, opt, Nleft_out, err);
        free(part);
    }
    snprintf(name, sizeof(name), "annotations/instances_%s.json", opt->split);
    if (!st && !(path = rs_io_join(opt->out_dir, name))) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) st = coco_write(&a, path, NULL, Nanns, err);
    free(path);
    coco_acc_free(&a);
    return st;
}

// ---- merge ----

// Hard-links src to dst (a copy when linking fails), unless dst exists.
static rs_status link_or_copy(const char *src, const char *dst, rs_err *err)
{
    if (rs_synth_dataset__file_exists(dst) || link(src, dst) == 0) return RS_OK;
    char *data = NULL;
    size_t len = 0;
    rs_status st = rs_io_read_file(&data, &len, src, err);
    if (!st) st = rs_io_write_file(dst, data, len, err);
    free(data);
    return st;
}

// Links DIR/<sub>/<stem><ext> of an input into OUT when it exists.
static rs_status link_sidecar(const char *in_dir, const char *out_dir, const char *sub, const char *file_name,
                              const char *ext, rs_err *err)
{
    char rel[1200];
    const char *dot = strrchr(file_name, '.');
    const int stem_len = dot ? (int)(dot - file_name) : (int)strlen(file_name);
    snprintf(rel, sizeof(rel), "%s/%.*s%s", sub, stem_len, file_name, ext);
    char *src = rs_io_join(in_dir, rel), *dst = rs_io_join(out_dir, rel);
    char *folder = rs_io_join(out_dir, sub);
    rs_status st = RS_OK;
    if (!src || !dst || !folder)
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    else if (rs_synth_dataset__file_exists(src) && !(st = rs_io_mkdir_p(folder, err)))
        st = link_or_copy(src, dst, err);
    free(src);
    free(dst);
    free(folder);
    return st;
}

// Adds the <split> of every instances_<split>.json in `adir` not yet in splits.
static rs_status list_splits(const char *adir, char ***splits, int *Nsplits, rs_err *err)
{
    DIR *dir = opendir(adir);
    if (!dir) return rs_err_set(err, RS_ERR_IO, "%s: %s (not a dataset?)", adir, strerror(errno));
    struct dirent *de;
    rs_status st = RS_OK;
    while (!st && (de = readdir(dir))) {
        const char *n = de->d_name;
        const size_t len = strlen(n);
        if (strncmp(n, "instances_", 10) != 0 || len <= 15 || strcmp(n + len - 5, ".json") != 0) continue;
        char split[256];
        snprintf(split, sizeof(split), "%.*s", (int)(len - 15), n + 10);
        bool have = false;
        for (int s = 0; s < *Nsplits; s++) have = have || strcmp((*splits)[s], split) == 0;
        if (have) continue;
        char **grown = realloc(*splits, (size_t)(*Nsplits + 1) * sizeof(char *));
        if (!grown || !(grown[*Nsplits] = strdup(split))) {
            if (grown) *splits = grown;
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            break;
        }
        *splits = grown;
        (*Nsplits)++;
    }
    closedir(dir);
    return st;
}

rs_status rs_synth_dataset_merge(int *Nimages, int *Nannotations, const char *out_dir, const char *const *inputs,
                                 int Ninputs, rs_err *err)
{
    if (Nimages) *Nimages = 0;
    if (Nannotations) *Nannotations = 0;
    if (!out_dir || Ninputs < 1)
        return rs_err_set(err, RS_ERR_INVALID, "merge: an output and at least one input needed");
    // The splits: every annotations/instances_<split>.json of every input.
    char **splits = NULL;
    int Nsplits = 0;
    rs_status st = RS_OK;
    for (int i = 0; i < Ninputs && !st; i++) {
        char *adir = rs_io_join(inputs[i], "annotations");
        if (!adir) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        rs_status s2 = list_splits(adir, &splits, &Nsplits, err);
        free(adir);
        st = s2;
    }
    // OUT is written by one process at a time (a synth run or another merge into it fails)
    rs_io_lock lock = {0};
    if (!st && Nsplits > 0 && !(st = rs_io_mkdir_p(out_dir, err)))
        st = rs_io_lock_dir(&lock, out_dir, "roadside synth merge", err);
    for (int s = 0; s < Nsplits && !st; s++) {
        coco_acc a = {0};
        char rel[600];
        snprintf(rel, sizeof(rel), "annotations/instances_%s.json", splits[s]);
        for (int i = 0; i < Ninputs && !st; i++) {
            char *path = rs_io_join(inputs[i], rel);
            if (!path)
                st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            else if (rs_synth_dataset__file_exists(path)) {
                const int before = a.N;
                st = coco_add_file(&a, path, err);
                for (int e = before; e < a.N && !st; e++) {
                    char fr[900];
                    snprintf(fr, sizeof(fr), "%s/%s", splits[s], a.e[e].file_name);
                    char *src = rs_io_join(inputs[i], fr), *dst = rs_io_join(out_dir, fr);
                    char *folder = rs_io_join(out_dir, splits[s]);
                    if (!src || !dst || !folder)
                        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
                    else if (!rs_synth_dataset__file_exists(src))
                        st = rs_err_set(err, RS_ERR_NOT_FOUND, "%s: listed in %s but missing", src, path);
                    else if (!(st = rs_io_mkdir_p(folder, err)) && !(st = link_or_copy(src, dst, err))) {
                        char sub[700];
                        snprintf(sub, sizeof(sub), "labels/%s", splits[s]);
                        if (!(st = link_sidecar(inputs[i], out_dir, sub, a.e[e].file_name, ".txt", err)))
                            st = link_sidecar(inputs[i], out_dir, "label_2", a.e[e].file_name, ".txt", err);
                    }
                    free(src);
                    free(dst);
                    free(folder);
                }
            }
            free(path);
        }
        char *out = rs_io_join(out_dir, rel);
        if (!st && !out) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (!st) {
            char *adir = rs_io_join(out_dir, "annotations");
            st = adir ? rs_io_mkdir_p(adir, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            free(adir);
        }
        if (!st) st = coco_write(&a, out, Nimages, Nannotations, err);
        free(out);
        coco_acc_free(&a);
    }
    if (!st && Nsplits == 0)
        st = rs_err_set(err, RS_ERR_NOT_FOUND,
                        "merge: no annotations/instances_*.json in the "
                        "inputs");
    rs_io_unlock(&lock);
    for (int s = 0; s < Nsplits; s++) free(splits[s]);
    free(splits);
    return st;
}
