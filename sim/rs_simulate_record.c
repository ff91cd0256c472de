// rs_simulate_record.c -- the record of the files `site simulate` wrote into a site
// (sim/internal/rs_simulate_internal.h, RS_SIMULATE_RECORD), so that --force replaces a folder
// only when it holds nothing else (issue 42, item 7: any folder with a site.json counted as a
// simulated site, and a real survey with its notes went with it).
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "core/rs_io.h"
#include "sim/internal/rs_simulate_internal.h"

static const char RECORD_HEADER[] = "# written by roadside site simulate: the files it wrote in this site";

typedef struct {
    char **path; // owned, relative to the walk's root
    int N, cap;
    bool failed; // out of memory or unreadable
} file_list;

static void add(file_list *l, const char *rel)
{
    if (l->N == l->cap) {
        int cap = l->cap ? 2 * l->cap : 64;
        char **p = realloc(l->path, sizeof *p * (size_t)cap);
        if (!p) {
            l->failed = true;
            return;
        }
        l->path = p, l->cap = cap;
    }
    if (!(l->path[l->N] = strdup(rel)))
        l->failed = true;
    else
        l->N++;
}

// Every entry under root/rel that is not a folder (a link is listed, not followed), into l.
static void walk(file_list *l, const char *root, const char *rel, int depth)
{
    char *dir = rel[0] ? rs_io_join(root, rel) : strdup(root);
    DIR *d = dir && depth < 16 ? opendir(dir) : NULL;
    if (!d) {
        l->failed = true;
        free(dir);
        return;
    }
    for (struct dirent *e; (e = readdir(d));) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        char *r = rel[0] ? rs_io_join(rel, e->d_name) : strdup(e->d_name), *full = r ? rs_io_join(root, r) : NULL;
        struct stat sb;
        if (!r || !full || lstat(full, &sb) != 0)
            l->failed = true;
        else if (S_ISDIR(sb.st_mode))
            walk(l, root, r, depth + 1);
        else
            add(l, r);
        free(r);
        free(full);
    }
    closedir(d);
    free(dir);
}

static void list_free(file_list *l)
{
    for (int i = 0; i < l->N; i++) free(l->path[i]);
    free(l->path);
}

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

rs_status rs_simulate__record_write(const char *dir, rs_err *err)
{
    file_list l = {0};
    walk(&l, dir, "", 0);
    add(&l, RS_SIMULATE_RECORD);
    size_t len = sizeof RECORD_HEADER + 1;
    for (int i = 0; i < l.N; i++) len += strlen(l.path[i]) + 1;
    char *text = l.failed ? NULL : malloc(len);
    rs_status st = text ? RS_OK : rs_err_set(err, RS_ERR_IO, "%s: cannot list the files written", dir);
    if (text) {
        qsort(l.path, (size_t)l.N, sizeof *l.path, cmp_str);
        size_t n = (size_t)snprintf(text, len, "%s\n", RECORD_HEADER);
        for (int i = 0; i < l.N; i++) n += (size_t)snprintf(text + n, len - n, "%s\n", l.path[i]);
        char *path = rs_io_join(dir, RS_SIMULATE_RECORD);
        st = path ? rs_io_write_file(path, text, n, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(path);
    }
    free(text);
    list_free(&l);
    return st;
}

bool rs_simulate__record_matches(char *why, size_t n, const char *dir)
{
    char *path = rs_io_join(dir, RS_SIMULATE_RECORD), *text = NULL;
    if (!path || rs_io_read_file_max(&text, NULL, path, RS_IO_MAX_SMALL_FILE_BYTES, NULL) != RS_OK ||
        strncmp(text, RECORD_HEADER, sizeof RECORD_HEADER - 1)) {
        snprintf(why, n, "holds no %s record of roadside site simulate (a site it did not write)", RS_SIMULATE_RECORD);
        free(path);
        free(text);
        return false;
    }
    free(path);
    // the record's lines, sorted as written
    file_list listed = {0}, found = {0};
    for (char *save = NULL, *line = strtok_r(text, "\n", &save); line; line = strtok_r(NULL, "\n", &save))
        if (line[0] != '#') add(&listed, line);
    qsort(listed.path, (size_t)listed.N, sizeof *listed.path, cmp_str);
    walk(&found, dir, "", 0);
    bool ok = !listed.failed && !found.failed;
    if (!ok) snprintf(why, n, "cannot be listed in full");
    for (int i = 0; ok && i < found.N; i++)
        if (!bsearch(&found.path[i], listed.path, (size_t)listed.N, sizeof *listed.path, cmp_str)) {
            snprintf(why, n, "holds '%.200s', which roadside site simulate did not write", found.path[i]);
            ok = false;
        }
    list_free(&listed);
    list_free(&found);
    free(text);
    return ok;
}
