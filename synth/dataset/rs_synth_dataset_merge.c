// rs_synth_dataset_merge.c -- `roadside synth merge` (rs_synth_dataset_merge, synth/dataset/rs_synth_dataset.h):
// shards of one run merged into one dataset, every file checked, images hard-linked, the COCO
// files written by the one COCO writer (rs_synth_dataset_coco.c). Called by the cli; calls core/
// and cJSON.
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "core/rs_json.h"
#include "synth/dataset/internal/rs_synth_dataset_internal.h"
#include "synth/fleet/rs_synth_fleet.h"

// ---- merge ----

// Hard-links src to dst (a copy when linking fails), unless dst exists.
static rs_status link_or_copy(const char *src, const char *dst, rs_err *err)
{
    return rs_synth_dataset__file_exists(dst) ? RS_OK : rs_io_link_or_copy(src, dst, err);
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
        // every shard run into the input must have finished: its completion record, the last
        // thing a synth run writes (issue 42: a killed shard's images lack files or annotations)
        const cJSON *finished = cJSON_GetObjectItemCaseSensitive(*doc, "finished");
        cJSON_ArrayForEach(sh, cJSON_GetObjectItemCaseSensitive(*doc, "shards"))
        {
            int I = 0, N = 0, used = 0;
            if (st) break;
            if (!cJSON_IsString(sh) || sscanf(sh->valuestring, "%d/%d%n", &I, &N, &used) != 2 ||
                sh->valuestring[used] || N < 1 || I < 0 || I >= N) {
                st = rs_err_set(err, RS_ERR_PARSE, "merge: %s: shards: not \"I/N\"", path);
                break;
            }
            bool done = false;
            const cJSON *f;
            cJSON_ArrayForEach(f, finished) done =
                done || (cJSON_IsString(f) && !strcmp(f->valuestring, sh->valuestring));
            if (!done) {
                st = rs_err_set(err, RS_ERR_INVALID,
                                "merge: %s: shard %s did not finish (no completion record in %s: killed, failed or "
                                "still running; rerun that shard into %s to finish it): nothing merged",
                                in, sh->valuestring, path, in);
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

// A regular file (not a link) at in/rel; with out_dir, its copy (hard link) into out/rel (NULL:
// checked only).
static rs_status take_file(const char *in, const char *out_dir, const char *rel, const char *listed_in, rs_err *err)
{
    char *src = rs_io_join(in, rel), *dst = out_dir ? rs_io_join(out_dir, rel) : NULL;
    char *folder = dst ? strdup(dst) : NULL;
    rs_status st = RS_OK;
    struct stat sb;
    if (!src || (out_dir && (!dst || !folder)))
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    else if (lstat(src, &sb) != 0 || !S_ISREG(sb.st_mode))
        st = rs_err_set(err, RS_ERR_NOT_FOUND, "merge: %s: %s (listed in %s): nothing merged", src,
                        lstat(src, &sb) != 0 ? "missing" : "not a regular file", listed_in);
    else if (out_dir) {
        *strrchr(folder, '/') = 0;
        if (!(st = rs_io_mkdir_p(folder, err))) st = link_or_copy(src, dst, err);
    }
    free(src);
    free(dst);
    free(folder);
    return st;
}

// Where take_image takes an input's images from and to (out_dir NULL: the checking pass).
typedef struct {
    const char *in, *out_dir, *split;
} take_ctx;

// The lines of a text file (a YOLO label file: one label a line); -1 when it cannot be read.
static long count_lines(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return -1;
    long n = 0;
    int c, last = '\n';
    while ((c = getc(f)) != EOF) {
        if (c == '\n') n++;
        last = c;
    }
    fclose(f);
    return last == '\n' ? n : n + 1;
}

// Every file of one image (a COCO image object, its file_name checked) of an input's split: in
// the checking pass (t->out_dir NULL) the PNG decoded at the size the COCO file states
// (rs_synth_dataset__image_intact, as resume checks) and the others regular files; else linked
// into OUT (a rs_synth_dataset__coco_each_image).
static rs_status take_image(void *ctx, const cJSON *image, const char *listed_in, rs_err *err)
{
    const take_ctx *t = ctx;
    const char *in = t->in, *out_dir = t->out_dir, *split = t->split;
    char rel[1200];
    const char *fn = cJSON_GetObjectItemCaseSensitive(image, "file_name")->valuestring;
    const cJSON *jw = cJSON_GetObjectItemCaseSensitive(image, "width");
    const cJSON *jh = cJSON_GetObjectItemCaseSensitive(image, "height");
    const cJSON *jk = cJSON_GetObjectItemCaseSensitive(image, "index");
    const char *dot = strrchr(fn, '.');
    const int stem = dot ? (int)(dot - fn) : (int)strlen(fn);
    snprintf(rel, sizeof(rel), "%s/%s", split, fn);
    rs_status st = RS_OK;
    if (!out_dir) {
        char *src = rs_io_join(in, rel), why[1400];
        if (!src) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (!cJSON_IsNumber(jw) || !cJSON_IsNumber(jh))
            st = rs_err_set(err, RS_ERR_PARSE, "merge: %s: image %s: width or height missing", listed_in, fn);
        else if (!rs_synth_dataset__image_intact(src, jw->valueint, jh->valueint, why, sizeof(why)))
            st = rs_err_set(err, RS_ERR_INVALID, "merge: %s (listed in %s): nothing merged", why, listed_in);
        free(src);
        if (st) return st;
    }
    if ((st = take_file(in, out_dir, rel, listed_in, err))) return st;
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

// The checking pass over one input's split (its COCO file at `path`): every image intact, every
// file there, and every image's YOLO file holding one line per annotation of the image in the
// COCO file (every label accounted for). Nothing is written.
static rs_status check_input_split(const char *in, const char *split, const char *path, rs_err *err)
{
    rs_synth_dataset__coco_index a = {0};
    take_ctx t = {in, NULL, split};
    rs_status st = rs_synth_dataset__coco_index_add(&a, path, -1, take_image, &t, err);
    for (int i = 0; !st && i < a.N; i++) {
        const char *fn = a.r[i].file_name, *dot = strrchr(fn, '.');
        char rel[1200];
        snprintf(rel, sizeof(rel), "labels/%s/%.*s.txt", split, dot ? (int)(dot - fn) : (int)strlen(fn), fn);
        char *yolo = rs_io_join(in, rel);
        if (!yolo) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            break;
        }
        const long lines = count_lines(yolo);
        if (lines != a.r[i].Nanns)
            st = rs_err_set(err, RS_ERR_INVALID,
                            "merge: %s: %ld labels, but %s lists %d annotations of %s: nothing merged", yolo, lines,
                            path, a.r[i].Nanns, fn);
        free(yolo);
    }
    rs_synth_dataset__coco_index_free(&a);
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
    // Everything checked before OUT is touched (issue 42): every image decoded, every file
    // there, every label accounted for, and the files the end of the merge takes
    for (int s = 0; s < Nsplits && !st; s++) {
        char rel[600];
        snprintf(rel, sizeof(rel), "annotations/instances_%s.json", splits[s]);
        for (int i = 0; i < Ninputs && !st; i++) {
            char *path = rs_io_join(inputs[i], rel);
            if (!path)
                st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            else if (rs_synth_dataset__file_exists(path))
                st = check_input_split(inputs[i], splits[s], path, err);
            free(path);
        }
    }
    if (!st && Ninputs > 0) {
        const cJSON *c;
        cJSON_ArrayForEach(c, cJSON_GetObjectItemCaseSensitive(runs[0], "cameras"))
        {
            char rel[400];
            snprintf(rel, sizeof(rel), "cameras/%.300s" RS_CAMERA_EXT_CAMERAMODEL, c->string);
            if ((st = take_file(inputs[0], NULL, rel, "run.json", err))) break;
        }
    }
    // OUT is written by one process at a time (a synth run or another merge into it fails)
    rs_io_lock lock = {0};
    if (!st && Nsplits > 0 && !(st = rs_synth_dataset__claim_folder(out_dir, "roadside synth merge", err)))
        st = rs_io_lock_dir(&lock, out_dir, "roadside synth merge", err);
    if (!st && lock.path) // a killed writer's leftovers
        rs_synth_dataset__remove_temporaries(out_dir, (const char *const *)splits, Nsplits);
    int *ks[2] = {NULL, NULL}, Nks[2] = {0, 0};
    const char *split_names[2] = {NULL, NULL};
    for (int s = 0; s < Nsplits && !st; s++) {
        rs_synth_dataset__coco_index a = {0};
        char rel[600];
        snprintf(rel, sizeof(rel), "annotations/instances_%s.json", splits[s]);
        for (int i = 0; i < Ninputs && !st; i++) {
            char *path = rs_io_join(inputs[i], rel);
            take_ctx t = {inputs[i], out_dir, splits[s]};
            if (!path)
                st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            else if (rs_synth_dataset__file_exists(path))
                st = rs_synth_dataset__coco_index_add(&a, path, -1, take_image, &t, err);
            free(path);
        }
        char *out = rs_io_join(out_dir, rel);
        if (!st && !out) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (!st) {
            char *adir = rs_io_join(out_dir, "annotations");
            st = adir ? rs_io_mkdir_p(adir, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            free(adir);
        }
        // KITTI's ImageSets and YOLO's data.yaml: the run's split is "train", any other "val";
        // the kept images' "index" in file-name order
        const cJSON *rs = cJSON_GetObjectItemCaseSensitive(runs[0], "split");
        const int slot = cJSON_IsString(rs) && !strcmp(rs->valuestring, splits[s]) ? 0 : 1;
        const bool first = !split_names[slot];
        int *k = NULL, Nk = 0;
        if (!st && first && !(k = malloc(sizeof(int) * (size_t)(a.N ? a.N : 1))))
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (!st) st = rs_synth_dataset__coco_index_write(&a, out, Nimages, Nannotations, k, &Nk, err);
        if (!st && first) {
            split_names[slot] = splits[s];
            ks[slot] = k;
            Nks[slot] = Nk;
            k = NULL;
        }
        free(k);
        free(out);
        rs_synth_dataset__coco_index_free(&a);
    }
    if (!st && Nsplits == 0)
        st = rs_err_set(err, RS_ERR_NOT_FOUND, "merge: no annotations/instances_*.json in the inputs");
    // the cameras (the same in every shard: their checksums are part of the run) and the run record
    if (!st) {
        const cJSON *cams = cJSON_GetObjectItemCaseSensitive(runs[0], "cameras"), *c;
        cJSON_ArrayForEach(c, cams)
        {
            char rel[400];
            snprintf(rel, sizeof(rel), "cameras/%.300s" RS_CAMERA_EXT_CAMERAMODEL, c->string);
            if ((st = take_file(inputs[0], out_dir, rel, "run.json", err))) break;
            // calib's record beside it (the pose covariance), when the run copied one
            snprintf(rel, sizeof(rel), "cameras/%.300s.json", c->string);
            char *src = rs_io_join(inputs[0], rel);
            struct stat sb;
            const bool has = src && lstat(src, &sb) == 0 && S_ISREG(sb.st_mode);
            free(src);
            if (has && (st = take_file(inputs[0], out_dir, rel, "run.json", err))) break;
        }
    }
    // each background's camera look (rs_synth_dataset__write_looks: every shard writes all of
    // the run's backgrounds, the same), when the first input has it
    if (!st) {
        char *src = rs_io_join(inputs[0], "backgrounds.json");
        struct stat sb;
        const bool has = src && lstat(src, &sb) == 0 && S_ISREG(sb.st_mode);
        free(src);
        if (has) st = take_file(inputs[0], out_dir, "backgrounds.json", "run.json", err);
    }
    if (!st) {
        if (!split_names[0]) split_names[0] = split_names[1];
        cJSON *doc = cJSON_CreateObject();
        cJSON_AddItemToObject(doc, "run", cJSON_Duplicate(runs[0], 1));
        cJSON_AddItemToArray(cJSON_AddArrayToObject(doc, "shards"), cJSON_CreateString("0/1"));
        cJSON_AddItemToArray(cJSON_AddArrayToObject(doc, "finished"), cJSON_CreateString("0/1")); // complete
        // issue 40: the shards' mixes of conditions summed (a shard found in two inputs once)
        int counts[9] = {0};
        bool any = false;
        cJSON *seen = cJSON_CreateObject();
        for (int i = 0; i < Ninputs && seen; i++) {
            const cJSON *sh;
            cJSON_ArrayForEach(sh, cJSON_GetObjectItemCaseSensitive(docs[i], "conditions"))
            {
                if (!sh->string || cJSON_GetObjectItemCaseSensitive(seen, sh->string)) continue;
                cJSON *one = cJSON_CreateObject();
                cJSON_AddItemReferenceToObject(one, sh->string, (cJSON *)sh);
                rs_synth_dataset__condition_mix_read(counts, one);
                cJSON_Delete(one);
                cJSON_AddTrueToObject(seen, sh->string);
                any = true;
            }
        }
        cJSON_Delete(seen);
        if (any)
            rs_synth_dataset__condition_mix_add(
                cJSON_AddObjectToObject(cJSON_AddObjectToObject(doc, "conditions"), "0/1"), counts);
        char *text = cJSON_Print(doc), *path = rs_io_join(out_dir, "run.json");
        char *kdir = rs_io_join(out_dir, "kitti/ImageSets");
        st = text && path && kdir ? rs_io_mkdir_p(kdir, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (!st) st = rs_io_write_file(path, text, strlen(text), err);
        const cJSON *jb = cJSON_GetObjectItemCaseSensitive(runs[0], "bbox");
        if (!st)
            st = rs_synth_dataset__write_trainer_files(out_dir, split_names, ks, Nks,
                                                       cJSON_IsNumber(jb) ? jb->valueint : 0, err);
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
