// rs_synth_dataset_coco.c -- the COCO files of `roadside synth` (synth/dataset/rs_synth_dataset.h):
// one writer assembling a COCO file from others as a stream (an index of the images, memory
// bounded by the largest source: issue 17), used for DATASET's annotations/instances_<split>.json
// from the finished images' parts/ files, and by merge (rs_synth_dataset_merge.c); and the SUMO
// frame an image's vehicles came from, added to its own COCO file. Called by rs_synth_dataset.c
// and rs_synth_dataset_merge.c; calls core/ and cJSON.
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
#include "synth/labels/rs_synth_labels.h"

// ---- the COCO writer (run and merge): an index, then the file written as a stream ----
//
// Assembling a COCO file from many (a run's parts/ files, one image each) or a few large ones
// (merge's shards) in memory bounded by the largest source file, not their sum:
//  1. index: each source is parsed in turn and checked; per image the index keeps its sort key
//     (file_name), where it lives (source, position, id there) and how many annotations name it;
//     the document is freed before the next is read.
//  2. the index is sorted by file name (ties: the order added), repeated names are dropped
//     (the first added stays), images numbered 1.. and annotations 1.. in that order.
//  3. each source is parsed again, once: its kept images and their annotations are printed
//     with their new ids (one object a line) into a scratch file (unlinked at once, beside the
//     output), each image's text remembered as (offset, length).
//  4. the output is written under a temporary name: info and licenses (from the first source
//     having them), "images" and "annotations" copied from the scratch file in sorted order,
//     "categories"; then renamed into place.
// The values are those of one cJSON document holding everything (as before issue 17's fix):
// only the whitespace differs.

static void coco_index_truncate(rs_synth_dataset__coco_index *x, int first_ref, int first_src)
{
    for (int i = first_ref; i < x->N; i++) free(x->r[i].file_name);
    if (first_ref < x->N) x->N = first_ref;
    for (int s = first_src; s < x->Nsrc; s++) free(x->src[s]);
    if (first_src < x->Nsrc) x->Nsrc = first_src;
}

void rs_synth_dataset__coco_index_free(rs_synth_dataset__coco_index *x)
{
    coco_index_truncate(x, 0, 0);
    free(x->r);
    free(x->src);
    cJSON_Delete(x->info);
    cJSON_Delete(x->licenses);
    cJSON_Delete(x->categories);
    memset(x, 0, sizeof(*x));
}

// Reads and parses a COCO file: images and annotations must be lists. Errors name the file.
static rs_status coco_parse(cJSON **doc, const cJSON **images, const cJSON **anns, const char *path, rs_err *err)
{
    char *text = NULL;
    *doc = NULL;
    rs_status st = rs_io_read_file(&text, NULL, path, err);
    if (st) return st;
    *doc = cJSON_Parse(text);
    free(text);
    *images = cJSON_GetObjectItemCaseSensitive(*doc, "images");
    *anns = cJSON_GetObjectItemCaseSensitive(*doc, "annotations");
    if (cJSON_IsArray(*images) && cJSON_IsArray(*anns)) return RS_OK;
    cJSON_Delete(*doc);
    *doc = NULL;
    return rs_err_set(err, RS_ERR_PARSE, "%s: not a COCO file (images, annotations)", path);
}

// (image id, index of its ref) of one source, sorted by id: annotations find their image.
typedef struct {
    double id;
    int ref;
} coco_id_ref;

static int id_ref_cmp(const void *a, const void *b)
{
    const coco_id_ref *x = a, *y = b;
    return x->id < y->id ? -1 : x->id > y->id ? 1 : x->ref - y->ref;
}

// The first of the n entries of t whose id is `id`, or n.
static int id_ref_find(const coco_id_ref *t, int n, double id)
{
    int lo = 0, hi = n;
    while (lo < hi) {
        const int mid = lo + (hi - lo) / 2;
        if (t[mid].id < id)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < n && t[lo].id == id ? lo : n;
}

// Indexes the images of the COCO file at `path` (a new source), each numbered k (k < 0: its
// "index" member, -1 when absent). The file is parsed, indexed and freed. On error nothing of
// it stays in the index; errors name the file.
rs_status rs_synth_dataset__coco_index_add(rs_synth_dataset__coco_index *x, const char *path, int k,
                                           rs_synth_dataset__coco_each_image each, void *ctx, rs_err *err)
{
    cJSON *doc = NULL;
    const cJSON *images, *anns, *im, *an;
    rs_status st = coco_parse(&doc, &images, &anns, path, err);
    if (st) return st;
    const int first_ref = x->N, first_src = x->Nsrc;
    if (!x->categories) x->categories = cJSON_Duplicate(cJSON_GetObjectItemCaseSensitive(doc, "categories"), 1);
    if (!x->info) x->info = cJSON_Duplicate(cJSON_GetObjectItemCaseSensitive(doc, "info"), 1);
    if (!x->licenses) x->licenses = cJSON_Duplicate(cJSON_GetObjectItemCaseSensitive(doc, "licenses"), 1);
    if (x->Nsrc == x->cap_src) {
        const int cap = x->cap_src ? 2 * x->cap_src : 64;
        char **s = realloc(x->src, (size_t)cap * sizeof(*s));
        if (s) x->src = s, x->cap_src = cap;
    }
    if (x->Nsrc == x->cap_src || !(x->src[x->Nsrc] = strdup(path)))
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    else
        x->Nsrc++;
    int pos = 0;
    cJSON_ArrayForEach(im, images)
    {
        if (st) break;
        const cJSON *id = cJSON_GetObjectItemCaseSensitive(im, "id");
        const cJSON *fn = cJSON_GetObjectItemCaseSensitive(im, "file_name");
        const cJSON *jk = cJSON_GetObjectItemCaseSensitive(im, "index");
        if (!cJSON_IsNumber(id) || !cJSON_IsString(fn)) {
            st = rs_err_set(err, RS_ERR_PARSE, "%s: images[]: id or file_name missing", path);
            break;
        }
        if (x->N == x->cap) {
            const int cap = x->cap ? 2 * x->cap : 64;
            rs_synth_dataset__coco_ref *r = realloc(x->r, (size_t)cap * sizeof(*r));
            if (!r) {
                st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
                break;
            }
            x->r = r;
            x->cap = cap;
        }
        rs_synth_dataset__coco_ref *r = &x->r[x->N];
        *r = (rs_synth_dataset__coco_ref){.file_name = strdup(fn->valuestring),
                                          .src = first_src,
                                          .pos = pos++,
                                          .seq = x->N,
                                          .id = id->valuedouble,
                                          .k = k >= 0               ? k
                                               : cJSON_IsNumber(jk) ? jk->valueint
                                                                    : -1};
        if (!r->file_name) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            break;
        }
        x->N++;
        if (each) st = each(ctx, im, path, err);
    }
    // each annotation counts for every image of this file with its image_id
    const int n = x->N - first_ref;
    coco_id_ref *t = st || n == 0 ? NULL : malloc((size_t)n * sizeof(*t));
    if (!st && n > 0 && !t) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; t && i < n; i++) t[i] = (coco_id_ref){x->r[first_ref + i].id, first_ref + i};
    if (t) qsort(t, (size_t)n, sizeof(*t), id_ref_cmp);
    cJSON_ArrayForEach(an, anns)
    {
        const cJSON *iid = cJSON_GetObjectItemCaseSensitive(an, "image_id");
        if (!t || !cJSON_IsNumber(iid)) continue;
        for (int j = id_ref_find(t, n, iid->valuedouble); j < n && t[j].id == iid->valuedouble; j++)
            x->r[t[j].ref].Nanns++;
    }
    free(t);
    cJSON_Delete(doc);
    if (st) coco_index_truncate(x, first_ref, first_src);
    return st;
}

static int ref_name_cmp(const void *a, const void *b)
{
    const rs_synth_dataset__coco_ref *x = a, *y = b;
    const int c = strcmp(x->file_name, y->file_name);
    return c ? c : x->src != y->src ? x->src - y->src : x->pos - y->pos;
}

// Appends cJSON's text of `item` (with id and, for an annotation, image_id replaced), then the
// 4 bytes ",\n\t\t", to the scratch file f. *off, *len: where it went; *len grows (the texts of
// one image's annotations follow each other).
static rs_status scratch_put(FILE *f, const cJSON *item, int id, int image_id, long *off, size_t *len, rs_err *err)
{
    cJSON *c = cJSON_Duplicate(item, 1);
    if (c) {
        cJSON_ReplaceItemInObjectCaseSensitive(c, "id", cJSON_CreateNumber(id));
        if (image_id > 0) cJSON_ReplaceItemInObjectCaseSensitive(c, "image_id", cJSON_CreateNumber(image_id));
    }
    char *text = c ? cJSON_PrintUnformatted(c) : NULL;
    cJSON_Delete(c);
    if (!text) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    const size_t n = strlen(text);
    const long at = ftell(f);
    const bool ok = at >= 0 && fwrite(text, 1, n, f) == n && fputs(",\n\t\t", f) >= 0;
    free(text);
    if (!ok) return rs_err_set(err, RS_ERR_IO, "a COCO file's scratch file: write failed: %s", strerror(errno));
    if (*len == 0) *off = at;
    *len += n + 4;
    return RS_OK;
}

// Step 3: every source parsed once more, its kept images and their annotations printed into f.
// order (N,): the refs sorted by (src, pos).
static rs_status render_sources(rs_synth_dataset__coco_index *x, const int *order, FILE *f, rs_err *err)
{
    rs_status st = RS_OK;
    for (int o = 0; o < x->N && !st;) {
        const int s = x->r[order[o]].src;
        int end = o;
        while (end < x->N && x->r[order[end]].src == s) end++;
        cJSON *doc = NULL;
        const cJSON *images, *anns, *im, *an;
        if ((st = coco_parse(&doc, &images, &anns, x->src[s], err))) break;
        // the images, in the file's order; the annotations of each, in the file's order
        const int n = end - o;
        coco_id_ref *t = malloc((size_t)n * sizeof(*t));
        int *fill = calloc((size_t)n, sizeof(int)), total = 0;
        int *start = malloc((size_t)n * sizeof(int));
        if (!t || !fill || !start) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        int i = 0, pos = 0;
        cJSON_ArrayForEach(im, images)
        {
            if (st || i >= n) break;
            rs_synth_dataset__coco_ref *r = &x->r[order[o + i]];
            if (pos++ != r->pos) continue;
            const cJSON *id = cJSON_GetObjectItemCaseSensitive(im, "id");
            if (!cJSON_IsNumber(id) || id->valuedouble != r->id) {
                st = rs_err_set(err, RS_ERR_PARSE, "%s: changed while the COCO file was assembled", x->src[s]);
                break;
            }
            t[i] = (coco_id_ref){r->id, i};
            start[i] = total;
            total += r->dropped ? 0 : r->Nanns;
            if (!r->dropped) st = scratch_put(f, im, r->new_id, 0, &r->img_off, &r->img_len, err);
            i++;
        }
        if (!st && i != n)
            st = rs_err_set(err, RS_ERR_PARSE, "%s: changed while the COCO file was assembled", x->src[s]);
        const cJSON **mine = st ? NULL : malloc((size_t)(total ? total : 1) * sizeof(*mine));
        if (!st && !mine) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (!st) qsort(t, (size_t)n, sizeof(*t), id_ref_cmp);
        cJSON_ArrayForEach(an, anns)
        {
            const cJSON *iid = cJSON_GetObjectItemCaseSensitive(an, "image_id");
            if (st || !cJSON_IsNumber(iid)) continue;
            for (int j = id_ref_find(t, n, iid->valuedouble); j < n && t[j].id == iid->valuedouble; j++) {
                const rs_synth_dataset__coco_ref *r = &x->r[order[o + t[j].ref]];
                if (r->dropped) continue;
                if (fill[t[j].ref] >= r->Nanns) {
                    st = rs_err_set(err, RS_ERR_PARSE, "%s: changed while the COCO file was assembled", x->src[s]);
                    break;
                }
                mine[start[t[j].ref] + fill[t[j].ref]++] = an;
            }
        }
        for (int j = 0; j < n && !st; j++) {
            rs_synth_dataset__coco_ref *r = &x->r[order[o + j]];
            for (int a = 0; a < (r->dropped ? 0 : r->Nanns) && !st; a++)
                st = scratch_put(f, mine[start[j] + a], r->ann_first + a, r->new_id, &r->ann_off, &r->ann_len, err);
        }
        free(mine);
        free(t);
        free(fill);
        free(start);
        cJSON_Delete(doc);
        o = end;
    }
    return st;
}

// Copies len bytes at off of the scratch file (fd) to out.
static bool copy_range(FILE *out, int fd, long off, size_t len, char *buf, size_t nbuf)
{
    while (len > 0) {
        const ssize_t got = pread(fd, buf, len < nbuf ? len : nbuf, (off_t)off);
        if (got <= 0 || fwrite(buf, 1, (size_t)got, out) != (size_t)got) return false;
        off += got;
        len -= (size_t)got;
    }
    return true;
}

// Writes the value of `item` (NULL: `fallback`, or nothing) as member `name`.
static bool put_member(FILE *f, const char *name, const cJSON *item, const char *fallback, bool last)
{
    if (!item && !fallback) return true;
    char *text = item ? cJSON_PrintUnformatted(item) : NULL;
    if (item && !text) return false;
    const bool ok = fprintf(f, "\t\"%s\": %s%s\n", name, text ? text : fallback, last ? "" : ",") > 0;
    free(text);
    return ok;
}

// Steps 2-4: sorts the index, writes `path` atomically. *Nimages, *Nanns grow by what it holds
// (NULL: not counted); with ks (x->N,) the kept images' k (>= 0) in file-name order, *Nks their
// count. The index is left sorted, repeated names marked dropped.
rs_status rs_synth_dataset__coco_index_write(rs_synth_dataset__coco_index *x, const char *path, int *Nimages,
                                             int *Nanns, int *ks, int *Nks, rs_err *err)
{
    if (x->N > 0) qsort(x->r, (size_t)x->N, sizeof(rs_synth_dataset__coco_ref), ref_name_cmp);
    int ni = 0, na = 0;
    for (int i = 0; i < x->N; i++) {
        rs_synth_dataset__coco_ref *r = &x->r[i];
        r->dropped = i > 0 && strcmp(r->file_name, x->r[i - 1].file_name) == 0;
        if (r->dropped) continue;
        r->new_id = ++ni;
        r->ann_first = na + 1;
        na += r->Nanns;
        if (ks && r->k >= 0) ks[(*Nks)++] = r->k;
    }
    // the scratch file: beside the output, unlinked at once (nothing is left behind)
    const size_t plen = strlen(path);
    char *scratch = malloc(plen + sizeof(".scratch.XXXXXX"));
    int *order = malloc((size_t)(x->N ? x->N : 1) * sizeof(int));
    char *buf = malloc(1 << 16);
    FILE *f = NULL;
    rs_status st = scratch && order && buf ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) {
        memcpy(scratch, path, plen);
        memcpy(scratch + plen, ".scratch.XXXXXX", sizeof(".scratch.XXXXXX"));
        const int fd = mkstemp(scratch);
        if (fd >= 0) unlink(scratch);
        if (fd < 0 || !(f = fdopen(fd, "w+b"))) {
            if (fd >= 0) close(fd);
            st = rs_err_set(err, RS_ERR_IO, "%s: cannot create its scratch file: %s", path, strerror(errno));
        }
    }
    // by (src, pos), the order the refs were added in: each source parsed once
    for (int i = 0; !st && i < x->N; i++) order[x->r[i].seq] = i;
    if (!st) st = render_sources(x, order, f, err);
    if (!st && fflush(f) != 0)
        st = rs_err_set(err, RS_ERR_IO, "%s: its scratch file: write failed: %s", path, strerror(errno));
    rs_io_atomic a = {0};
    if (!st) st = rs_io_atomic_open(&a, path, err);
    if (!st) {
        const int fd = fileno(f);
        bool ok = fputs("{\n", a.f) >= 0 && put_member(a.f, "info", x->info, NULL, false) &&
                  put_member(a.f, "licenses", x->licenses, NULL, false);
        for (int pass = 0; pass < 2 && ok; pass++) {
            ok = fprintf(a.f, "\t\"%s\": [", pass == 0 ? "images" : "annotations") > 0;
            bool any = false;
            for (int i = 0; i < x->N && ok; i++) {
                const rs_synth_dataset__coco_ref *r = &x->r[i];
                const long off = pass == 0 ? r->img_off : r->ann_off;
                size_t len = pass == 0 ? r->img_len : r->ann_len;
                if (r->dropped || len == 0) continue;
                // the separator after the last item of the section is left out
                ok = (any || fputs("\n\t\t", a.f) >= 0) && (!any || fputs(",\n\t\t", a.f) >= 0) &&
                     copy_range(a.f, fd, off, len - 4, buf, 1 << 16);
                any = true;
            }
            ok = ok && fputs(any ? "\n\t],\n" : "],\n", a.f) >= 0;
        }
        ok = ok && put_member(a.f, "categories", x->categories, "[]", true) && fputs("}\n", a.f) >= 0;
        if (!ok) {
            rs_io_atomic_abort(&a);
            st = rs_err_set(err, RS_ERR_IO, "%s: write failed: %s", path, strerror(errno));
        } else
            st = rs_io_atomic_commit(&a, err);
    }
    if (f) fclose(f);
    free(scratch);
    free(order);
    free(buf);
    if (!st && Nimages) *Nimages += ni;
    if (!st && Nanns) *Nanns += na;
    return st;
}

// ---- assembling DATASET's COCO file ----

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

// Indexes the parts/ file of image k unless it is not a COCO file or lists an image missing
// from split_dir: then it is left out, with a notice. *added: it was indexed with an image.
// Errors: RS_ERR_NOMEM only.
static rs_status add_part(rs_synth_dataset__coco_index *x, bool *added, const char *part, int k, const char *split_dir,
                          const rs_synth_dataset_options *opt, int *Nleft_out, rs_err *err)
{
    const int first_ref = x->N, first_src = x->Nsrc;
    rs_err e = {RS_OK, ""};
    char why[1200] = "";
    *added = false;
    rs_status st = rs_synth_dataset__coco_index_add(x, part, k, NULL, NULL, &e);
    if (st == RS_ERR_NOMEM) return rs_err_set(err, st, "%s", e.msg);
    if (st) snprintf(why, sizeof(why), "%s", e.msg);
    for (int i = first_ref; i < x->N && !why[0] && !opt->labels_only; i++) { // (labels only: no image)
        char *image = rs_io_join(split_dir, x->r[i].file_name);
        struct stat sb;
        if (!image) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        const bool there = lstat(image, &sb) == 0;
        if (!there || !S_ISREG(sb.st_mode))
            snprintf(why, sizeof(why), "%s: lists %s, which is %s", part, image,
                     !there ? "missing" : "not a regular file");
        free(image);
    }
    if (!why[0]) {
        *added = x->N > first_ref;
        return RS_OK;
    }
    coco_index_truncate(x, first_ref, first_src);
    leave_out(opt, why, Nleft_out);
    return RS_OK;
}

// The KITTI part of the dataset's README (also kitti/README.md).
static void readme_kitti(FILE *f)
{
    fputs("## KITTI (kitti/)\n\n"
          "`kitti/training/image_2/<k>.png`, `label_2/<k>.txt`, `calib/<k>.txt` (k the image index, 6 digits),\n"
          "`kitti/ImageSets/train.txt` and `val.txt` (the indices of each split). KITTI's P2 is a pinhole, so\n"
          "the KITTI images are the dataset's images **undistorted** to the lens's pinhole core (same fx, fy,\n"
          "cx, cy and size; identical to the other layouts' images for a pinhole camera), and their 2D boxes\n"
          "are that image's. A roadside camera looks down: KITTI's 3D boxes (upright, rotation_y about the y\n"
          "axis) hold in the **rectified frame**, the camera frame levelled: `x_rect = R0_rect x_cam`, its y\n"
          "axis vertical (down), its z axis the optical axis made horizontal. Labels' location (the bottom\n"
          "centre of the 3D box) and rotation_y are in that frame; `P2 = [K R0_rect^T | 0]` maps it into the\n"
          "undistorted image (so P2[:, :3] is not upper triangular on a tilted camera: decompose it, e.g. RQ,\n"
          "for K), and `P2 R0_rect Tr_velo_to_cam` maps the site's ENU frame (KITTI's \"velodyne\") into it.\n"
          "Pixel (0, 0) is the centre of the top-left pixel. Types: Car (sedan, hatchback, suv, pickup),\n"
          "Van, Bus, Truck (box and articulated), Misc (motorcycle), Cyclist (bicycle).\n",
          f);
}

// DATASET/README.md (and kitti/README.md): what each layout holds, the splits and the box type.
static rs_status write_readme(const char *out_dir, const char *const split[2], const int *Nks, int bbox, rs_err *err)
{
    char *path = rs_io_join(out_dir, "README.md"), *kpath = rs_io_join(out_dir, "kitti/README.md");
    rs_io_atomic a = {0};
    rs_status st = path && kpath ? rs_io_atomic_open(&a, path, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) {
        FILE *f = a.f;
        fprintf(f,
                "# A roadside synth dataset\n\n"
                "Synthetic images of road traffic seen by calibrated roadside cameras, labelled from the\n"
                "cameras' own models (roadside's docs/labels.md, \"The dataset contract\"; docs/synth.md).\n\n"
                "## The boxes: %s\n\n%s.\n\n"
                "The same box is COCO's `bbox`, the YOLO line and KITTI's 2D box (`roadside synth --bbox`;\n"
                "COCO's annotations also carry the other boxes: footprint_bbox, body_bbox, visible_bbox).\n\n"
                "## Splits\n\n| split | images |\n|---|---|\n| %s (train) | %d |\n| %s (val) | %d |\n\n"
                "Each image is in one split only, drawn from (seed, image) (`--val-fraction`, default %.2g;\n"
                "`--val-camera`, `--val-backgrounds` hold out cameras or backgrounds). Shards and merges keep it.\n\n"
                "## COCO, as YOLOX and torchvision read it\n\n"
                "`<split>/<stem>.png` and `annotations/instances_<split>.json`: with the defaults `train2017/`,\n"
                "`val2017/`, `instances_train2017.json`, `instances_val2017.json`. `bbox` [x, y, w, h] and\n"
                "`segmentation` (the box's polygon) are in COCO's corner convention: (0, 0) is the top-left\n"
                "corner of the top-left pixel. roadside's own fields (footprint_bbox, bottom_center, corners_px,\n"
                "...) have (0, 0) at that pixel's centre (0.5 px less). Categories 1..10 (`info` repeats the box\n"
                "type: bbox_kind, bbox_meaning).\n\n"
                "## Ultralytics YOLO\n\n"
                "`data.yaml`: no `path` (Ultralytics then takes the file's own folder as the root, so the\n"
                "dataset can move), `train: images/<split>`, `val: images/<val split>`, names 0..9 (the\n"
                "category ids less 1). `labels/<split>/<stem>.txt`: `class cx cy w h` normalised by the image\n"
                "size, the same boxes as COCO's bbox.\n\n",
                rs_synth_bbox_kind_name((rs_synth_bbox_kind)bbox), rs_synth_bbox_kind_meaning((rs_synth_bbox_kind)bbox),
                split[0] ? split[0] : "train2017", Nks[0], split[1] ? split[1] : "val2017", Nks[1],
                RS_SYNTH_VAL_FRACTION_DEFAULT);
        readme_kitti(f);
        st = rs_io_atomic_commit(&a, err);
    }
    rs_io_atomic k = {0};
    if (!st) st = rs_io_atomic_open(&k, kpath, err);
    if (!st) {
        fputs("# KITTI layout of a roadside synth dataset (../README.md)\n\n", k.f);
        readme_kitti(k.f);
        st = rs_io_atomic_commit(&k, err);
    }
    free(path);
    free(kpath);
    return st;
}

// YOLO's data.yaml (Ultralytics: train, val, names; no path: the file's folder is the root) and
// KITTI's ImageSets/<split>.txt (numeric image names, one a line), the README, written atomically.
rs_status rs_synth_dataset__write_trainer_files(const char *out_dir, const char *const split[2], int *const *ks,
                                                const int *Nks, int bbox, rs_err *err)
{
    char *yaml = rs_io_join(out_dir, "data.yaml");
    rs_io_atomic a = {0};
    rs_status st = yaml ? rs_io_atomic_open(&a, yaml, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) {
        // a val split Ultralytics needs: the train images themselves when there is none (one image)
        fprintf(a.f,
                "# Ultralytics YOLO dataset (roadside synth; README.md, roadside's docs/labels.md)\n"
                "# No 'path': Ultralytics takes this file's folder as the dataset root (a relative 'path'\n"
                "# would be resolved against its own datasets_dir instead), so the folder can move.\n"
                "# Boxes: %s: %s.\n"
                "train: images/%s\nval: images/%s\nbox_type: %s\nnames:\n",
                rs_synth_bbox_kind_name((rs_synth_bbox_kind)bbox), rs_synth_bbox_kind_meaning((rs_synth_bbox_kind)bbox),
                split[0], Nks[1] > 0 ? split[1] : split[0], rs_synth_bbox_kind_name((rs_synth_bbox_kind)bbox));
        for (int c = 0; c < RS_SYNTH_NCLASSES; c++)
            fprintf(a.f, "  %d: %s\n", c, rs_synth_class_name((rs_synth_class)c));
        st = rs_io_atomic_commit(&a, err);
    }
    free(yaml);
    for (int s = 0; s < 2 && !st; s++) {
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
    if (!st) st = write_readme(out_dir, split, Nks, bbox, err);
    return st;
}

rs_status rs_synth_dataset__assemble(const rs_synth_dataset__run *d, int *Nanns, int *Nleft_out, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    rs_synth_dataset__coco_index a[2] = {{0}, {0}};
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
            bool added = false;
            st = add_part(&a[split], &added, part, k, d->split_dir[split], opt, Nleft_out, err);
            if (!st && added) ks[split][Nks[split]++] = k;
        }
        free(part);
    }
    for (int s = 0; s < 2 && !st; s++) {
        if (s == 1 && !d->split_dir[1]) break;
        snprintf(name, sizeof(name), "annotations/instances_%s.json", d->split[s]);
        free(path);
        if (!(path = rs_io_join(opt->out_dir, name))) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (!st) st = rs_synth_dataset__coco_index_write(&a[s], path, NULL, Nanns, NULL, NULL, err);
    }
    if (!st) st = rs_synth_dataset__write_trainer_files(opt->out_dir, d->split, ks, Nks, opt->bbox, err);
    free(path);
    rs_synth_dataset__coco_index_free(&a[0]);
    rs_synth_dataset__coco_index_free(&a[1]);
    free(ks[0]);
    free(ks[1]);
    return st;
}

// ---- the splits of a dataset ----

static int cmp_name(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

rs_status rs_synth_dataset__splits(char **names, int *Nnames, int max, const char *dataset_dir, rs_err *err)
{
    *Nnames = 0;
    char *adir = rs_io_join(dataset_dir, "annotations");
    if (!adir) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    DIR *dir = opendir(adir);
    if (!dir) {
        rs_status st = rs_err_set(err, RS_ERR_IO,
                                  "%s: %s (not a dataset made by roadside synth? docs/labels.md, \"The dataset "
                                  "contract\")",
                                  adir, strerror(errno));
        free(adir);
        return st;
    }
    rs_status st = RS_OK;
    struct dirent *de;
    while (!st && (de = readdir(dir))) {
        const size_t len = strlen(de->d_name);
        if (strncmp(de->d_name, "instances_", 10) != 0 || len <= 15 || strcmp(de->d_name + len - 5, ".json") != 0)
            continue;
        if (*Nnames == max) {
            st = rs_err_set(err, RS_ERR_INVALID, "%s: more than %d splits", adir, max);
            break;
        }
        if (!(names[*Nnames] = strndup(de->d_name + 10, len - 15)))
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        else
            (*Nnames)++;
    }
    closedir(dir);
    qsort(names, (size_t)*Nnames, sizeof(char *), cmp_name);
    if (!st && *Nnames == 0)
        st = rs_err_set(err, RS_ERR_NOT_FOUND, "%s: no instances_<split>.json (not a dataset made by roadside synth?)",
                        adir);
    free(adir);
    if (st) {
        for (int k = 0; k < *Nnames; k++) free(names[k]);
        *Nnames = 0;
    }
    return st;
}

void rs_synth_dataset__condition_mix_add(cJSON *mix, const int counts[9])
{
    for (int i = 0; mix && i < 9; i++) {
        const rs_synth_condition c = {.time_of_day = (rs_synth_time_of_day)(i / 3),
                                      .surface = (rs_synth_surface)(i % 3)};
        char label[16];
        rs_synth_condition_label(label, sizeof(label), &c);
        if (counts[i]) cJSON_AddNumberToObject(mix, label, counts[i]);
    }
}

void rs_synth_dataset__condition_mix_read(int counts[9], const cJSON *mixes)
{
    const cJSON *shard, *x;
    cJSON_ArrayForEach(shard, mixes)
    {
        cJSON_ArrayForEach(x, shard)
        {
            rs_synth_condition c;
            if (cJSON_IsNumber(x) && rs_synth_condition_parse(&c, x->string, NULL) == RS_OK)
                counts[3 * (int)c.time_of_day + (int)c.surface] += (int)x->valuedouble;
        }
    }
}
