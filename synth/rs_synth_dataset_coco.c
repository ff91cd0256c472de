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
#include "synth/rs_synth_fleet.h"

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
    cJSON *info;       // owned, from the first document (may stay NULL)
    cJSON *licenses;   // owned, likewise
} coco_acc;

static void coco_acc_free(coco_acc *a)
{
    for (int i = 0; i < a->N; i++) {
        cJSON_Delete(a->e[i].image);
        cJSON_Delete(a->e[i].anns);
    }
    free(a->e);
    cJSON_Delete(a->categories);
    cJSON_Delete(a->info);
    cJSON_Delete(a->licenses);
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
    if (!a->info) a->info = cJSON_Duplicate(cJSON_GetObjectItemCaseSensitive(doc, "info"), 1);
    if (!a->licenses) a->licenses = cJSON_Duplicate(cJSON_GetObjectItemCaseSensitive(doc, "licenses"), 1);
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
    if (a->info) cJSON_AddItemToObject(doc, "info", cJSON_Duplicate(a->info, 1));
    if (a->licenses) cJSON_AddItemToObject(doc, "licenses", cJSON_Duplicate(a->licenses, 1));
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

// YOLO's data.yaml (Ultralytics: path, train, val, names) and KITTI's ImageSets/<split>.txt
// (numeric image names, one a line), written atomically beside the COCO files.
static rs_status write_trainer_files(const char *out_dir, const char *const split[2], int *const *ks, const int *Nks,
                                     rs_err *err)
{
    char *root = realpath(out_dir, NULL);
    if (!root) return rs_err_set(err, RS_ERR_IO, "%s: %s", out_dir, strerror(errno));
    char *yaml = rs_io_join(out_dir, "data.yaml");
    rs_io_atomic a = {0};
    rs_status st = yaml ? rs_io_atomic_open(&a, yaml, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) {
        // a val split Ultralytics needs: the train images themselves when there is none
        fprintf(a.f,
                "# Ultralytics YOLO dataset (roadside synth, docs/labels.md)\npath: %s\ntrain: images/%s\n"
                "val: images/%s\nnames:\n",
                root, split[0], Nks[1] > 0 ? split[1] : split[0]);
        for (int c = 0; c < RS_SYNTH_NCLASSES; c++)
            fprintf(a.f, "  %d: %s\n", c, rs_synth_class_name((rs_synth_class)c));
        st = rs_io_atomic_commit(&a, err);
    }
    free(yaml);
    free(root);
    for (int s = 0; s < 2 && !st; s++) {
        if (s == 1 && Nks[1] == 0) break;
        char name[400];
        snprintf(name, sizeof(name), "kitti/ImageSets/%s.txt", s == 0 ? "train" : "val");
        char *path = rs_io_join(out_dir, name);
        rs_io_atomic f = {0};
        st = path ? rs_io_atomic_open(&f, path, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(path);
        if (st) break;
        for (int i = 0; i < Nks[s]; i++) fprintf(f.f, "%06d\n", ks[s][i]);
        st = rs_io_atomic_commit(&f, err);
    }
    return st;
}

rs_status rs_synth_dataset__assemble(const rs_synth_dataset__run *d, int *Nanns, int *Nleft_out, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    coco_acc a[2] = {{0}, {0}};
    int *ks[2] = {NULL, NULL}, Nks[2] = {0, 0};
    rs_status st = RS_OK;
    char name[600], *path = NULL;
    *Nleft_out = 0;
    *Nanns = 0;
    ks[0] = malloc(sizeof(int) * (size_t)opt->count);
    ks[1] = malloc(sizeof(int) * (size_t)opt->count);
    if (!ks[0] || !ks[1]) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int k = 0; k < opt->count && !st; k++) {
        char stem[300];
        const rs_synth_dataset__camera *c = &d->cams[k % d->Ncams];
        const int split = rs_synth_dataset__image_split(d, k, c);
        rs_synth_dataset__stem(stem, sizeof(stem), k, c->id);
        snprintf(name, sizeof(name), "%s.json", stem);
        char *part = rs_io_join(d->parts_dir, name);
        struct stat sb;
        rs_synth_dataset__state state = RS_SYNTH_DATASET__FINISHED;
        char why[600];
        // another shard's image: checked as a rerun checks its own (this shard's were just now)
        if (part && lstat(part, &sb) == 0 && k % opt->shard_count != opt->shard_index)
            st = rs_synth_dataset__check_finished(&state, why, sizeof(why), d, stem, c, split, err);
        if (!part)
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        else if (!st && state == RS_SYNTH_DATASET__DAMAGED)
            leave_out(opt, why, Nleft_out);
        else if (!st && lstat(part, &sb) == 0) {
            const int before = a[split].N, left = *Nleft_out;
            st = add_part(&a[split], part, d->split_dir[split], opt, Nleft_out, err);
            if (!st && *Nleft_out == left && a[split].N > before) ks[split][Nks[split]++] = k;
        }
        free(part);
    }
    for (int s = 0; s < 2 && !st; s++) {
        if (s == 1 && !d->split_dir[1]) break;
        snprintf(name, sizeof(name), "annotations/instances_%s.json", d->split[s]);
        free(path);
        if (!(path = rs_io_join(opt->out_dir, name))) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (!st) st = coco_write(&a[s], path, NULL, Nanns, err);
    }
    if (!st) st = write_trainer_files(opt->out_dir, d->split, ks, Nks, err);
    free(path);
    coco_acc_free(&a[0]);
    coco_acc_free(&a[1]);
    free(ks[0]);
    free(ks[1]);
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

// ---- merge: one run's shards, every file checked ----

// An input's run.json: its "run" (options) and the shards run into it; marks the images they
// cover in covered (count,). Errors name the file.
static rs_status read_run(cJSON **doc, const cJSON **run, unsigned char **covered, int *count, int *N_common,
                          const char *in, rs_err *err)
{
    char *path = rs_io_join(in, "run.json"), *text = NULL;
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = RS_OK;
    if (!rs_synth_dataset__file_exists(path))
        st = rs_err_set(err, RS_ERR_NOT_FOUND, "merge: %s: missing: %s is not a roadside synth dataset (shard)", path,
                        in);
    else if (!(st = rs_io_read_file(&text, NULL, path, err))) {
        *doc = cJSON_Parse(text);
        *run = cJSON_GetObjectItemCaseSensitive(*doc, "run");
        const cJSON *jc = cJSON_GetObjectItemCaseSensitive(*run, "count"), *sh;
        if (!cJSON_IsObject(*run) || !cJSON_IsNumber(jc) || jc->valueint < 1)
            st = rs_err_set(err, RS_ERR_PARSE, "merge: %s: not a run record (run, count)", path);
        else if (!*covered) {
            *count = jc->valueint;
            if (!(*covered = calloc((size_t)*count, 1))) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        }
        cJSON_ArrayForEach(sh, cJSON_GetObjectItemCaseSensitive(*doc, "shards"))
        {
            int I = 0, N = 0, used = 0;
            if (st) break;
            if (!cJSON_IsString(sh) || sscanf(sh->valuestring, "%d/%d%n", &I, &N, &used) != 2 ||
                sh->valuestring[used] || N < 1 || I < 0 || I >= N) {
                st = rs_err_set(err, RS_ERR_PARSE, "merge: %s: shards: not \"I/N\"", path);
                break;
            }
            *N_common = *N_common == 0 ? N : *N_common == N ? N : -1;
            for (int k = I; k < *count && jc->valueint == *count; k += N) (*covered)[k] = 1;
        }
    }
    free(text);
    free(path);
    return st;
}

// The first member where two runs differ, for the message: "count 4 vs 8".
static void run_difference(char *out, size_t n, const cJSON *a, const cJSON *b)
{
    snprintf(out, n, "options differ");
    const cJSON *x;
    cJSON_ArrayForEach(x, a)
    {
        const cJSON *y = cJSON_GetObjectItemCaseSensitive(b, x->string);
        if (y && cJSON_Compare(x, y, 1)) continue;
        char *sx = cJSON_PrintUnformatted(x), *sy = y ? cJSON_PrintUnformatted(y) : NULL;
        snprintf(out, n, "%s %.200s vs %.200s", x->string, sx ? sx : "?", sy ? sy : "(absent)");
        free(sx);
        free(sy);
        return;
    }
    cJSON_ArrayForEach(x, b) if (!cJSON_GetObjectItemCaseSensitive(a, x->string))
    {
        snprintf(out, n, "%s only in the second", x->string);
        return;
    }
}

// Width and height from a PNG's IHDR chunk; false when the file is not a PNG.
static bool png_size(const char *path, int *w, int *h)
{
    unsigned char b[24];
    FILE *f = fopen(path, "rb");
    if (!f) return false;
    const bool ok =
        fread(b, 1, 24, f) == 24 && memcmp(b, "\x89PNG\r\n\x1a\n", 8) == 0 && memcmp(b + 12, "IHDR", 4) == 0;
    fclose(f);
    if (!ok) return false;
    *w = (int)((unsigned)b[16] << 24 | (unsigned)b[17] << 16 | (unsigned)b[18] << 8 | b[19]);
    *h = (int)((unsigned)b[20] << 24 | (unsigned)b[21] << 16 | (unsigned)b[22] << 8 | b[23]);
    return true;
}

// A regular file (not a link) at in/rel; its copy (hard link) into out/rel.
static rs_status take_file(const char *in, const char *out_dir, const char *rel, const char *listed_in, rs_err *err)
{
    char *src = rs_io_join(in, rel), *dst = rs_io_join(out_dir, rel);
    char *folder = dst ? strdup(dst) : NULL;
    rs_status st = RS_OK;
    struct stat sb;
    if (!src || !dst || !folder)
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    else if (lstat(src, &sb) != 0 || !S_ISREG(sb.st_mode))
        st = rs_err_set(err, RS_ERR_NOT_FOUND, "merge: %s: %s (listed in %s)", src,
                        lstat(src, &sb) != 0 ? "missing" : "not a regular file", listed_in);
    else {
        *strrchr(folder, '/') = 0;
        if (!(st = rs_io_mkdir_p(folder, err))) st = link_or_copy(src, dst, err);
    }
    free(src);
    free(dst);
    free(folder);
    return st;
}

// Every file of one image of an input (COCO entry e of split), checked and linked into OUT.
static rs_status take_image(const char *in, const char *out_dir, const char *split, const coco_entry *e,
                            const char *listed_in, rs_err *err)
{
    char rel[1200];
    const char *fn = e->file_name;
    const cJSON *jw = cJSON_GetObjectItemCaseSensitive(e->image, "width");
    const cJSON *jh = cJSON_GetObjectItemCaseSensitive(e->image, "height");
    const cJSON *jk = cJSON_GetObjectItemCaseSensitive(e->image, "index");
    const char *dot = strrchr(fn, '.');
    const int stem = dot ? (int)(dot - fn) : (int)strlen(fn);
    snprintf(rel, sizeof(rel), "%s/%s", split, fn);
    char *src = rs_io_join(in, rel);
    int w = 0, h = 0;
    if (!src) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    const bool png = png_size(src, &w, &h);
    rs_status st = RS_OK;
    if (!png)
        st = rs_err_set(err, RS_ERR_NOT_FOUND, "merge: %s: missing or not a PNG (listed in %s)", src, listed_in);
    else if (!cJSON_IsNumber(jw) || !cJSON_IsNumber(jh) || w != jw->valueint || h != jh->valueint)
        st = rs_err_set(err, RS_ERR_INVALID, "merge: %s: %dx%d pixels, %s says otherwise", src, w, h, listed_in);
    free(src);
    if (st || (st = take_file(in, out_dir, rel, listed_in, err))) return st;
    const char *const fmt[2] = {"images/%s/%s", "labels/%s/%.*s.txt"};
    snprintf(rel, sizeof(rel), fmt[0], split, fn);
    if ((st = take_file(in, out_dir, rel, listed_in, err))) return st;
    snprintf(rel, sizeof(rel), fmt[1], split, stem, fn);
    if ((st = take_file(in, out_dir, rel, listed_in, err))) return st;
    if (!cJSON_IsNumber(jk)) return rs_err_set(err, RS_ERR_PARSE, "merge: %s: image %s: index missing", listed_in, fn);
    const char *const kitti[3] = {"kitti/training/image_2/%06d.png", "kitti/training/label_2/%06d.txt",
                                  "kitti/training/calib/%06d.txt"};
    for (int i = 0; i < 3 && !st; i++) {
        snprintf(rel, sizeof(rel), kitti[i], jk->valueint);
        st = take_file(in, out_dir, rel, listed_in, err);
    }
    return st;
}

rs_status rs_synth_dataset_merge(int *Nimages, int *Nannotations, const char *out_dir, const char *const *inputs,
                                 int Ninputs, rs_err *err)
{
    if (Nimages) *Nimages = 0;
    if (Nannotations) *Nannotations = 0;
    if (!out_dir || Ninputs < 1)
        return rs_err_set(err, RS_ERR_INVALID, "merge: an output and at least one input needed");
    // One run: the same run record everywhere, shards 0..N-1 each once.
    cJSON **docs = calloc((size_t)Ninputs, sizeof(cJSON *));
    const cJSON **runs = calloc((size_t)Ninputs, sizeof(cJSON *));
    unsigned char *covered = NULL; // (count,) images some input's shards made
    int count = 0, N_common = 0;
    char **splits = NULL;
    int Nsplits = 0;
    rs_status st = docs && runs ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; i < Ninputs && !st; i++) {
        if ((st = read_run(&docs[i], &runs[i], &covered, &count, &N_common, inputs[i], err))) break;
        char diff[600];
        if (i > 0 && !cJSON_Compare(runs[0], runs[i], 1)) {
            run_difference(diff, sizeof(diff), runs[0], runs[i]);
            st = rs_err_set(err, RS_ERR_INVALID, "merge: %s and %s are not shards of one run: %s", inputs[0], inputs[i],
                            diff);
        }
    }
    if (!st) {
        // every image of the run made by one of the inputs' shards; else name what is missing
        char missing[1000] = "";
        int Nmissing = 0, Nuncovered = 0;
        for (int k = 0; k < count; k++) {
            if (covered[k]) continue;
            Nuncovered++;
            const size_t len = strlen(missing);
            // with one shard count N, image k belongs to shard k mod N: name shards, else images
            if (N_common > 0 && k >= N_common) continue;
            if (Nmissing++ < 20) {
                if (N_common > 0)
                    snprintf(missing + len, sizeof(missing) - len, "%sshard %d/%d", len ? ", " : "", k, N_common);
                else
                    snprintf(missing + len, sizeof(missing) - len, "%simage %d", len ? ", " : "", k);
            }
        }
        if (Nmissing)
            st = rs_err_set(err, RS_ERR_NOT_FOUND, "merge: missing: %s%s (the inputs hold %d of the run's %d images)",
                            missing, Nmissing > 20 ? ", ..." : "", count - Nuncovered, count);
    }
    // The splits: every annotations/instances_<split>.json of every input.
    for (int i = 0; i < Ninputs && !st; i++) {
        char *adir = rs_io_join(inputs[i], "annotations");
        st = adir ? list_splits(adir, &splits, &Nsplits, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(adir);
    }
    // OUT is written by one process at a time (a synth run or another merge into it fails)
    rs_io_lock lock = {0};
    if (!st && Nsplits > 0 && !(st = rs_io_mkdir_p(out_dir, err)))
        st = rs_io_lock_dir(&lock, out_dir, "roadside synth merge", err);
    int *ks[2] = {NULL, NULL}, Nks[2] = {0, 0};
    const char *split_names[2] = {NULL, NULL};
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
                for (int e = before; e < a.N && !st; e++)
                    st = take_image(inputs[i], out_dir, splits[s], &a.e[e], path, err);
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
        // KITTI's ImageSets and YOLO's data.yaml: the run's split is "train", any other "val"
        const cJSON *rs = cJSON_GetObjectItemCaseSensitive(runs[0], "split");
        const int slot = cJSON_IsString(rs) && !strcmp(rs->valuestring, splits[s]) ? 0 : 1;
        if (!st && !split_names[slot]) {
            split_names[slot] = splits[s];
            ks[slot] = malloc(sizeof(int) * (size_t)(a.N ? a.N : 1));
            if (!ks[slot]) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            for (int e = 0; e < a.N && !st; e++) {
                const cJSON *jk = cJSON_GetObjectItemCaseSensitive(a.e[e].image, "index");
                if (cJSON_IsNumber(jk) && (e == 0 || strcmp(a.e[e].file_name, a.e[e - 1].file_name)))
                    ks[slot][Nks[slot]++] = jk->valueint;
            }
        }
        free(out);
        coco_acc_free(&a);
    }
    if (!st && Nsplits == 0)
        st = rs_err_set(err, RS_ERR_NOT_FOUND, "merge: no annotations/instances_*.json in the inputs");
    // the cameras (the same in every shard: their checksums are part of the run) and the run record
    if (!st) {
        const cJSON *cams = cJSON_GetObjectItemCaseSensitive(runs[0], "cameras"), *c;
        cJSON_ArrayForEach(c, cams)
        {
            char rel[400];
            snprintf(rel, sizeof(rel), "cameras/%.300s.cameramodel", c->string);
            if ((st = take_file(inputs[0], out_dir, rel, "run.json", err))) break;
        }
    }
    if (!st) {
        if (!split_names[0]) split_names[0] = split_names[1];
        cJSON *doc = cJSON_CreateObject();
        cJSON_AddItemToObject(doc, "run", cJSON_Duplicate(runs[0], 1));
        cJSON_AddItemToArray(cJSON_AddArrayToObject(doc, "shards"), cJSON_CreateString("0/1"));
        char *text = cJSON_Print(doc), *path = rs_io_join(out_dir, "run.json");
        char *kdir = rs_io_join(out_dir, "kitti/ImageSets");
        st = text && path && kdir ? rs_io_mkdir_p(kdir, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (!st) st = rs_io_write_file(path, text, strlen(text), err);
        if (!st) st = write_trainer_files(out_dir, split_names, ks, Nks, err);
        free(text);
        free(path);
        free(kdir);
        cJSON_Delete(doc);
    }
    rs_io_unlock(&lock);
    free(ks[0]);
    free(ks[1]);
    for (int s = 0; s < Nsplits; s++) free(splits[s]);
    free(splits);
    for (int i = 0; docs && i < Ninputs; i++) cJSON_Delete(docs[i]);
    free(docs);
    free(runs);
    free(covered);
    return st;
}
