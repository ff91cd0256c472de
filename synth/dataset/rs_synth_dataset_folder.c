// rs_synth_dataset_folder.c -- whose folder a dataset is and whether a shard finished (issue 42):
// `roadside synth -o DIR` and `synth merge -o DIR` write and clean up only in a folder roadside
// made, marked by DIR/.roadside-dataset, and remove only the temporaries of their own file names
// in their own subfolders; a run's completion record in DIR/run.json, which merge requires
// (rs_synth_dataset_internal.h). Called by rs_synth_dataset.c and rs_synth_dataset_merge.c;
// calls core/ and cJSON.
#include <dirent.h>
#include <errno.h>
#include <fnmatch.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "synth/dataset/internal/rs_synth_dataset_internal.h"

// Whether dir holds a run.json written by a roadside synth run or merge before the marker existed
// (a "run" object with the contract's version): such a dataset is adopted, not refused.
static bool older_dataset(const char *dir)
{
    char *path = rs_io_join(dir, "run.json"), *text = NULL;
    bool yes = false;
    if (path && rs_io_read_file_max(&text, NULL, path, RS_IO_MAX_SMALL_FILE_BYTES, NULL) == RS_OK) {
        cJSON *doc = cJSON_Parse(text);
        const cJSON *run = cJSON_GetObjectItemCaseSensitive(doc, "run");
        yes = cJSON_IsObject(run) && cJSON_IsString(cJSON_GetObjectItemCaseSensitive(run, "contract"));
        cJSON_Delete(doc);
    }
    free(text);
    free(path);
    return yes;
}

rs_status rs_synth_dataset__claim_folder(const char *dir, const char *what, rs_err *err)
{
    char *marker = rs_io_join(dir, RS_SYNTH_DATASET_MARKER);
    if (!marker) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    struct stat sb;
    rs_status st = RS_OK;
    if (lstat(marker, &sb) == 0) {
        if (!S_ISREG(sb.st_mode))
            st = rs_err_set(err, RS_ERR_INVALID, "%s: not a regular file: %s is not a folder %s made", marker, dir,
                            what);
        free(marker);
        return st;
    }
    DIR *d = opendir(dir);
    if (!d && errno != ENOENT) {
        st = rs_err_set(err, RS_ERR_IO, "%s: %s", dir, strerror(errno));
    } else if (d) {
        const struct dirent *de;
        const char *first = NULL;
        while (!first && (de = readdir(d)))
            if (strcmp(de->d_name, ".") != 0 && strcmp(de->d_name, "..") != 0) first = de->d_name;
        if (first && !older_dataset(dir))
            st = rs_err_set(err, RS_ERR_INVALID,
                            "%s: not empty (it holds %.200s ...) and not a folder %s made (no %s): refused, nothing "
                            "written; give a new or empty folder",
                            dir, first, what, RS_SYNTH_DATASET_MARKER);
        closedir(d);
    }
    if (!st) st = rs_io_mkdir_p(dir, err);
    static const char text[] = "roadside synth dataset: this folder was made by roadside synth (or synth merge),\n"
                               "which writes and cleans up only in folders holding this file.\n";
    if (!st) st = rs_io_write_file(marker, text, sizeof(text) - 1, err);
    free(marker);
    return st;
}

// The folders of a dataset and the names roadside writes in each (fnmatch patterns; "%s": a split).
static const struct {
    const char *folder;
    const char *names[6];
} own_names[] = {
    {"", {"run.json", "data.yaml", "README.md", "backgrounds.json", "tracks_gt.csv", RS_SYNTH_DATASET_MARKER}},
    {"parts", {"[0-9]*_*.json"}},
    {"annotations", {"instances_*.json"}},
    {"cameras", {"*.cameramodel", "*.json"}},
    {"%s", {"[0-9]*_*.png"}},
    {"images/%s", {"[0-9]*_*.png"}},
    {"labels/%s", {"[0-9]*_*.txt"}},
    {"kitti", {"README.md"}},
    {"kitti/ImageSets", {"train.txt", "val.txt"}},
    {"kitti/training/image_2", {"[0-9]*.png"}},
    {"kitti/training/label_2", {"[0-9]*.txt"}},
    {"kitti/training/calib", {"[0-9]*.txt"}},
};

// Whether base (a file name) is one of the names roadside writes in folder entry f.
static bool own_name(int f, const char *base)
{
    for (int i = 0; i < 6 && own_names[f].names[i]; i++)
        if (fnmatch(own_names[f].names[i], base, 0) == 0) return true;
    return false;
}

// The base of a temporary of roadside's into base[n]: "<name>.tmp.XXXXXX" (core's atomic writes)
// or "<name>.<pid>.lnk" (rs_synth_dataset__link_into); false for any other name.
static bool temporary_base(char *base, size_t n, const char *name)
{
    size_t len = rs_io_temporary_base_len(name);
    if (!len) {
        const size_t m = strlen(name);
        if (m < 6 || strcmp(name + m - 4, ".lnk") != 0) return false;
        const char *p = name + m - 5; // the pid's digits, then a dot
        while (p > name && *p >= '0' && *p <= '9') p--;
        if (p == name + m - 5 || *p != '.' || p == name) return false;
        len = (size_t)(p - name);
    }
    if (len >= n) return false;
    memcpy(base, name, len);
    base[len] = 0;
    return true;
}

size_t rs_synth_dataset__remove_temporaries(const char *dir, const char *const *splits, int Nsplits)
{
    size_t removed = 0;
    const int Nfolders = (int)(sizeof(own_names) / sizeof(own_names[0]));
    for (int f = 0; f < Nfolders; f++) {
        const bool per_split = strstr(own_names[f].folder, "%s") != NULL;
        for (int s = 0; s < (per_split ? Nsplits : 1); s++) {
            char rel[400], base[512];
            snprintf(rel, sizeof(rel), own_names[f].folder, per_split ? splits[s] : "");
            char *folder = rel[0] ? rs_io_join(dir, rel) : strdup(dir);
            DIR *d = folder ? opendir(folder) : NULL;
            const struct dirent *de;
            while (d && (de = readdir(d))) {
                if (!temporary_base(base, sizeof(base), de->d_name) || !own_name(f, base)) continue;
                char *path = rs_io_join(folder, de->d_name);
                struct stat sb;
                if (path && lstat(path, &sb) == 0 && (S_ISREG(sb.st_mode) || S_ISLNK(sb.st_mode)) && unlink(path) == 0)
                    removed++;
                free(path);
            }
            if (d) closedir(d);
            free(folder);
        }
    }
    return removed;
}

rs_status rs_synth_dataset__write_completion(const rs_synth_dataset__run *d, const int Ncondition[9], rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    char *path = rs_io_join(opt->out_dir, "run.json"), *text = NULL, *out = NULL;
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = rs_io_read_file(&text, NULL, path, err);
    cJSON *doc = st ? NULL : cJSON_Parse(text);
    if (!st && !doc) st = rs_err_set(err, RS_ERR_PARSE, "%s: not JSON", path);
    char shard[64];
    snprintf(shard, sizeof(shard), "%d/%d", opt->shard_index, opt->shard_count);
    if (!st && !opt->labels_only) {
        cJSON *mixes = cJSON_GetObjectItemCaseSensitive(doc, "conditions");
        if (!cJSON_IsObject(mixes)) {
            cJSON_DeleteItemFromObjectCaseSensitive(doc, "conditions");
            mixes = cJSON_AddObjectToObject(doc, "conditions");
        }
        cJSON_DeleteItemFromObjectCaseSensitive(mixes, shard);
        rs_synth_dataset__condition_mix_add(cJSON_AddObjectToObject(mixes, shard), Ncondition);
    }
    if (!st) {
        cJSON *done = cJSON_GetObjectItemCaseSensitive(doc, "finished");
        if (!cJSON_IsArray(done)) {
            cJSON_DeleteItemFromObjectCaseSensitive(doc, "finished");
            done = cJSON_AddArrayToObject(doc, "finished");
        }
        const cJSON *x;
        bool listed = false;
        cJSON_ArrayForEach(x, done) listed = listed || (cJSON_IsString(x) && !strcmp(x->valuestring, shard));
        if (!listed) cJSON_AddItemToArray(done, cJSON_CreateString(shard));
        if (!(out = cJSON_Print(doc))) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    if (!st) st = rs_io_write_file(path, out, strlen(out), err);
    cJSON_Delete(doc);
    free(out);
    free(text);
    free(path);
    return st;
}
