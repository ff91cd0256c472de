// rs_calib_site_run.c -- the outputs of a calibration run and its record (calib.run.json): which
// files each camera has, their removal, the record written and read back, and the summary the cli
// prints (rs_calib_site.h). Split from rs_calib_site.c, which writes and reads the outputs
// themselves.
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cjson/cJSON.h>

#include "calib/rs_calib_site.h"
#include "core/rs_io.h"

// ---------------------------------------------------------------- the outputs of a run, its record

rs_status rs_calib_site_outputs_remove(unsigned *removed, const char *out_dir, const char *id,
                                       const rs_calib_site_outputs *outputs, rs_err *err)
{
    if (removed) *removed = 0;
    rs_status first = RS_OK;
    for (int k = 0; k < outputs->Nsuffixes; k++) {
        char name[256];
        snprintf(name, sizeof name, "%s%s", id, outputs->suffixes[k]);
        if (!strcmp(name, "calib.run.json") || !strcmp(name, "audit.run.json")) continue; // a record, not an output
        rs_err e = {0};
        char *path = rs_io_child_path(out_dir, id, outputs->suffixes[k], &e);
        const bool named = path != NULL;
        bool was = false;
        rs_status st = named ? rs_io_remove_if_exists(path, &was, &e) : e.status;
        free(path);
        if (was && removed) *removed |= 1u << k;
        if (st && !first) first = rs_err_set(err, st, "%s", e.msg);
        if (!named) break; // an id that cannot name a file has no file here
    }
    return first;
}

char *rs_calib_site_outputs_names(const char *id, unsigned mask, const rs_calib_site_outputs *outputs)
{
    size_t n = 1;
    for (int k = 0; k < outputs->Nsuffixes; k++)
        if (mask & 1u << k) n += strlen(id) + strlen(outputs->suffixes[k]) + 2;
    char *s = malloc(n);
    if (!s) return NULL;
    size_t len = 0;
    s[0] = '\0';
    for (int k = 0; k < outputs->Nsuffixes; k++)
        if (mask & 1u << k)
            len += (size_t)snprintf(s + len, n - len, "%s%s%s", len ? ", " : "", id, outputs->suffixes[k]);
    return s;
}

static cJSON *names_array(const char *id, unsigned mask, const rs_calib_site_outputs *outputs)
{
    cJSON *a = cJSON_CreateArray();
    for (int k = 0; a && k < outputs->Nsuffixes; k++)
        if (mask & 1u << k) {
            char name[256];
            snprintf(name, sizeof name, "%s%s", id, outputs->suffixes[k]);
            cJSON_AddItemToArray(a, cJSON_CreateString(name));
        }
    return a;
}

// Appends s to the malloc'ed *text; false when out of memory.
static bool append_text(char **text, const char *s)
{
    const size_t n = strlen(*text), m = strlen(s);
    char *grown = realloc(*text, n + m + 1);
    if (!grown) return false;
    memcpy(grown + n, s, m + 1);
    *text = grown;
    return true;
}

static const char *const run_status_names[] = {"written", "failed", "not selected"};

// The outputs of camera `id` still in out_dir ("cam1.cameramodel, cam1.json"; "" when none), as a
// malloc'ed string; NULL when out of memory.
static char *stale_outputs(const char *out_dir, const char *id, const rs_calib_site_outputs *outputs)
{
    unsigned mask = 0;
    for (int k = 0; k < outputs->Nsuffixes; k++) {
        char *path = rs_io_child_path(out_dir, id, outputs->suffixes[k], NULL);
        struct stat sb;
        if (path && lstat(path, &sb) == 0) mask |= 1u << k;
        free(path);
    }
    return rs_calib_site_outputs_names(id, mask, outputs);
}

rs_status rs_calib_site_run_write(const char *out_dir, const rs_calib_site_outputs *outputs, const char *site_dir,
                                  const char *error, const rs_calib_site_run_camera *cameras, int N, rs_err *err)
{
    cJSON *root = cJSON_CreateObject();
    if (!root) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    char *site_abs = realpath(site_dir, NULL);
    cJSON_AddStringToObject(root, "command", outputs->command);
    cJSON_AddStringToObject(root, "site", site_abs ? site_abs : site_dir);
    free(site_abs);
    bool complete = !error;
    for (int i = 0; i < N; i++) complete &= cameras[i].status != RS_CALIB_SITE_RUN_FAILED;
    cJSON_AddBoolToObject(root, "complete", complete);
    if (error)
        cJSON_AddStringToObject(root, "error", error);
    else
        cJSON_AddNullToObject(root, "error");
    cJSON *list = cJSON_AddArrayToObject(root, "cameras");
    for (int i = 0; list && i < N; i++) {
        const rs_calib_site_run_camera *c = &cameras[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "id", c->id);
        cJSON_AddStringToObject(o, "status", run_status_names[c->status]);
        if (c->status == RS_CALIB_SITE_RUN_WRITTEN)
            cJSON_AddItemToObject(o, "files", names_array(c->id, c->files, outputs));
        if (c->status == RS_CALIB_SITE_RUN_FAILED) {
            if (c->error)
                cJSON_AddStringToObject(o, "error", c->error);
            else
                cJSON_AddNullToObject(o, "error");
            cJSON_AddItemToObject(o, "removed", names_array(c->id, c->files, outputs));
        }
        cJSON_AddItemToArray(list, o);
    }
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    char *path = rs_io_join(out_dir, outputs->record);
    rs_status st =
        text && path ? rs_io_write_file(path, text, strlen(text), err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    free(text);
    free(path);
    return st;
}

char *rs_calib_site_run_summary(const char *out_dir, const rs_calib_site_outputs *outputs,
                                const rs_calib_site_run_camera *cameras, int N)
{
    char *text = calloc(1, 1);
    bool ok = text != NULL;
    int Nwritten = 0, Nkept = 0;
    for (int i = 0; i < N; i++) {
        Nwritten += cameras[i].status == RS_CALIB_SITE_RUN_WRITTEN;
        Nkept += cameras[i].status == RS_CALIB_SITE_RUN_NOT_SELECTED;
    }
    if (Nwritten)
        ok = ok && append_text(&text, "written to ") && append_text(&text, out_dir) && append_text(&text, "/: ");
    else
        ok = ok && append_text(&text, "no camera written: ") && append_text(&text, out_dir) &&
             append_text(&text, "/ holds no output of this run\n");
    for (int i = 0, n = 0; ok && i < N; i++)
        if (cameras[i].status == RS_CALIB_SITE_RUN_WRITTEN)
            ok = append_text(&text, n++ ? ", " : "") && append_text(&text, cameras[i].id) &&
                 append_text(&text, n == Nwritten ? "\n" : "");
    for (int i = 0; ok && i < N; i++) {
        const rs_calib_site_run_camera *c = &cameras[i];
        if (c->status != RS_CALIB_SITE_RUN_FAILED) continue;
        char *names = rs_calib_site_outputs_names(c->id, c->files, outputs),
             *stale = stale_outputs(out_dir, c->id, outputs);
        ok = names && stale && append_text(&text, "not written: ") && append_text(&text, c->id) &&
             append_text(&text, ": failed (") && append_text(&text, c->error ? c->error : "no reason given") &&
             append_text(&text, "); ") && append_text(&text, names[0] ? "its earlier outputs removed: " : "") &&
             append_text(&text, names[0]   ? names
                                : stale[0] ? ""
                                           : "no earlier output of it was there");
        // what could not be removed (a read-only folder) is an earlier run's: said, never left to look valid
        if (ok && stale[0])
            ok = append_text(&text, names[0] ? "; " : "") &&
                 append_text(&text, "STALE, an earlier run's output that could not be removed (do not use it): ") &&
                 append_text(&text, stale);
        ok = ok && append_text(&text, "\n");
        free(names);
        free(stale);
    }
    if (ok && Nkept) ok = append_text(&text, "not selected, earlier outputs (if any) left as they were: ");
    for (int i = 0, n = 0; ok && i < N; i++)
        if (cameras[i].status == RS_CALIB_SITE_RUN_NOT_SELECTED)
            ok = append_text(&text, n++ ? ", " : "") && append_text(&text, cameras[i].id) &&
                 append_text(&text, n == Nkept ? "\n" : "");
    if (!ok) {
        free(text);
        return NULL;
    }
    return text;
}

// Appends ", names" (or "names") to *list; false when out of memory.
static bool append_names(char **list, const char *names)
{
    return !names[0] || (append_text(list, (*list)[0] ? ", " : "") && append_text(list, names));
}

rs_status rs_calib_site_run_abandon(char **removed, const char *out_dir, const rs_calib_site_outputs *outputs,
                                    const char *site_dir, const char *const *only, int Nonly, const char *error,
                                    rs_err *err)
{
    if (!(*removed = calloc(1, 1))) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    char *path = rs_io_join(out_dir, outputs->record), *text = NULL, *site_abs = realpath(site_dir, NULL);
    rs_err ignore = {0};
    cJSON *root = NULL;
    if (path && site_abs && !rs_io_read_file_max(&text, NULL, path, RS_IO_MAX_SMALL_FILE_BYTES, &ignore))
        root = cJSON_Parse(text);
    free(text);
    free(path);
    const cJSON *command = cJSON_GetObjectItemCaseSensitive(root, "command");
    const cJSON *site = cJSON_GetObjectItemCaseSensitive(root, "site");
    const cJSON *list = cJSON_GetObjectItemCaseSensitive(root, "cameras");
    // only a record of this command for this very site folder says which files are this site's
    const bool ours = cJSON_IsString(command) && !strcmp(command->valuestring, outputs->command) &&
                      cJSON_IsString(site) && !strcmp(site->valuestring, site_abs) && cJSON_IsArray(list);
    free(site_abs);
    const int N = ours ? cJSON_GetArraySize(list) : 0;
    rs_calib_site_run_camera *cameras = calloc((size_t)N + 1, sizeof *cameras);
    rs_status st = cameras ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    int n = 0;
    const cJSON *c;
    if (!st && ours) cJSON_ArrayForEach(c, list)
        {
            const cJSON *id = cJSON_GetObjectItemCaseSensitive(c, "id");
            const cJSON *status = cJSON_GetObjectItemCaseSensitive(c, "status");
            if (!cJSON_IsString(id) || rs_io_name_problem(id->valuestring) || !cJSON_IsString(status)) continue;
            bool selected = Nonly == 0;
            for (int i = 0; i < Nonly; i++) selected |= !strcmp(only[i], id->valuestring);
            rs_calib_site_run_camera *rc = &cameras[n++];
            rc->id = id->valuestring;
            rc->status = selected ? RS_CALIB_SITE_RUN_FAILED : RS_CALIB_SITE_RUN_NOT_SELECTED;
            rc->error = "the site could not be read";
            if (!selected || !strcmp(status->valuestring, run_status_names[RS_CALIB_SITE_RUN_FAILED])) continue;
            rs_err e = {0};
            rs_status rst = rs_calib_site_outputs_remove(&rc->files, out_dir, rc->id, outputs, &e);
            if (rst && !st) st = rs_err_set(err, rst, "%s", e.msg);
            char *names = rs_calib_site_outputs_names(rc->id, rc->files, outputs);
            if (!names || !append_names(removed, names)) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            free(names);
        }
    rs_status wst = ours ? rs_calib_site_run_write(out_dir, outputs, site_dir, error, cameras, n, &ignore) : RS_OK;
    if (wst && !st) st = rs_err_set(err, wst, "%s", ignore.msg);
    free(cameras);
    cJSON_Delete(root);
    return st;
}
