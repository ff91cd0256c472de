// rs_synth_dataset_view.c -- `roadside dataset view`: contact sheets of a dataset's images with
// their labels drawn (synth/dataset/rs_synth_dataset.h, rs_synth_dataset_view). Reads the dataset's own
// COCO files (the dataset contract, docs/labels.md), draws through the OpenCV shim
// (synth/backdrop/rs_synth_opencv.h), reads and writes images through core/rs_image.h.
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "core/rs_image.h"
#include "core/rs_io.h"
#include "core/rs_json.h"
#include "synth/backdrop/rs_synth_opencv.h"
#include "synth/dataset/internal/rs_synth_dataset_internal.h"
#include "synth/dataset/rs_synth_dataset.h"

// The colours of the legend (8-bit RGB / 255: exact in an 8-bit PNG).
#define C8(r, g, b)                              \
    {                                            \
        (r) / 255.0f, (g) / 255.0f, (b) / 255.0f \
    }
static const float col_footprint[3] = C8(0, 230, 0);
static const float col_body[3] = C8(255, 150, 0);
static const float col_visible[3] = C8(0, 170, 255);
static const float col_box3d[3] = C8(255, 255, 0);
static const float col_bottom[3] = C8(255, 0, 255);
static const float col_text[3] = C8(255, 255, 255);
static const float col_text_bg[3] = C8(0, 0, 0);
static const float col_page[3] = C8(38, 38, 38);

// What the legend lists, in order (docs/labels.md's fields).
static const struct {
    const char *name, *field;
    const float *rgb;
} legend[] = {
    {"footprint box", "footprint_bbox", col_footprint}, {"body box", "body_bbox", col_body},
    {"visible box", "visible_bbox", col_visible},       {"3D box", "corners_px", col_box3d},
    {"bottom centre", "bottom_center", col_bottom},     {"0.83 visibility", "visibility", col_text},
};

enum { GAP_PX = 6, CAPTION_PX = 14, LEGEND_PX = 22 };

typedef struct {
    const char *split;  // borrowed from the view's split names
    const cJSON *image; // borrowed from the split's document
    const cJSON **ann;  // borrowed, Nann
    int Nann, cap_ann;
    int page, x_px, y_px; // where its tile is (1-based page)
} view_item;

typedef struct {
    char *split_names[64];
    cJSON *docs[64];
    char *paths[64];
    int Nsplits;
    view_item *items;
    int Nitems;
} view_state;

static void view_free(view_state *v)
{
    for (int s = 0; s < v->Nsplits; s++) {
        free(v->split_names[s]);
        free(v->paths[s]);
        cJSON_Delete(v->docs[s]);
    }
    for (int i = 0; i < v->Nitems; i++) free((void *)v->items[i].ann);
    free(v->items);
}

// The number of o[key], or NaN when absent or not a number.
static double number_of(const cJSON *o, const char *key)
{
    const cJSON *x = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsNumber(x) ? x->valuedouble : NAN;
}

static const char *string_of(const cJSON *o, const char *key)
{
    const cJSON *x = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsString(x) ? x->valuestring : NULL;
}

// Reads a COCO box [x, y, w, h] a[key] into box (x0, y0, x1, y1). Returns 0 when absent or null,
// 1 when read, -1 when malformed.
static int read_box(double box[4], const cJSON *a, const char *key)
{
    const cJSON *x = cJSON_GetObjectItemCaseSensitive(a, key);
    if (!x || cJSON_IsNull(x)) return 0;
    if (!cJSON_IsArray(x) || cJSON_GetArraySize(x) != 4) return -1;
    double v[4];
    for (int i = 0; i < 4; i++) {
        const cJSON *e = cJSON_GetArrayItem(x, i);
        if (!cJSON_IsNumber(e) || !isfinite(e->valuedouble)) return -1;
        v[i] = e->valuedouble;
    }
    if (v[2] < 0 || v[3] < 0) return -1;
    box[0] = v[0];
    box[1] = v[1];
    box[2] = v[0] + v[2];
    box[3] = v[1] + v[3];
    return 1;
}

// Reads [u, v] a[key]; 0 absent/null, 1 read, -1 malformed.
static int read_point(double p[2], const cJSON *x)
{
    if (!x || cJSON_IsNull(x)) return 0;
    if (!cJSON_IsArray(x) || cJSON_GetArraySize(x) != 2) return -1;
    for (int i = 0; i < 2; i++) {
        const cJSON *e = cJSON_GetArrayItem(x, i);
        if (!cJSON_IsNumber(e)) return -1;
        p[i] = e->valuedouble;
    }
    return 1;
}

// Checks the fields the view draws, so that a malformed file is named, not half drawn.
static rs_status check_annotation(const cJSON *a, int index, const char *path, rs_err *err)
{
    static const char *boxes[] = {"footprint_bbox", "body_bbox", "visible_bbox"};
    double box[4], p[2];
    for (int b = 0; b < 3; b++)
        if (read_box(box, a, boxes[b]) < 0)
            return rs_err_set(err, RS_ERR_PARSE, "%s: annotations[%d].%s: expected [x, y, w, h] (w, h >= 0) or null",
                              path, index, boxes[b]);
    if (read_point(p, cJSON_GetObjectItemCaseSensitive(a, "bottom_center")) < 0)
        return rs_err_set(err, RS_ERR_PARSE, "%s: annotations[%d].bottom_center: expected [u, v] or null", path, index);
    const cJSON *c = cJSON_GetObjectItemCaseSensitive(a, "corners_px"), *e;
    if (c && !cJSON_IsNull(c)) {
        if (!cJSON_IsArray(c) || cJSON_GetArraySize(c) != 8)
            return rs_err_set(err, RS_ERR_PARSE, "%s: annotations[%d].corners_px: expected 8 corners", path, index);
        int i = 0;
        cJSON_ArrayForEach(e, c)
        {
            if (read_point(p, e) < 0)
                return rs_err_set(err, RS_ERR_PARSE, "%s: annotations[%d].corners_px[%d]: expected [u, v] or null",
                                  path, index, i);
            i++;
        }
    }
    const cJSON *vis = cJSON_GetObjectItemCaseSensitive(a, "visibility");
    if (vis && !cJSON_IsNull(vis) && !cJSON_IsNumber(vis))
        return rs_err_set(err, RS_ERR_PARSE, "%s: annotations[%d].visibility: expected a number", path, index);
    return RS_OK;
}

// Reads DATASET/annotations/instances_*.json (sorted by split name) and picks the first
// max_images images (0: all) with their annotations.
static rs_status view_load(view_state *v, const char *dataset_dir, int max_images, rs_err *err)
{
    rs_status st = rs_synth_dataset__splits(v->split_names, &v->Nsplits, 64, dataset_dir, err);
    char *adir = st ? NULL : rs_io_join(dataset_dir, "annotations");
    if (!st && !adir) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int s = 0; !st && s < v->Nsplits; s++) {
        char file[600];
        snprintf(file, sizeof(file), "instances_%s.json", v->split_names[s]);
        char *text = NULL;
        size_t len = 0;
        if (!(v->paths[s] = rs_io_join(adir, file))) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            break;
        }
        const char *path = v->paths[s];
        if ((st = rs_io_read_file(&text, &len, path, err))) break;
        st = rs_json_parse(&v->docs[s], text, 0, len, path, err);
        free(text);
        if (st) break;
        const cJSON *images = cJSON_GetObjectItemCaseSensitive(v->docs[s], "images");
        const cJSON *anns = cJSON_GetObjectItemCaseSensitive(v->docs[s], "annotations"), *x;
        if (!cJSON_IsObject(v->docs[s]) || !cJSON_IsArray(images) || !cJSON_IsArray(anns)) {
            st = rs_err_set(err, RS_ERR_PARSE, "%s: not a COCO file (an object with images and annotations lists)",
                            path);
            break;
        }
        const int first = v->Nitems;
        int index = 0;
        cJSON_ArrayForEach(x, images)
        {
            const char *fname = string_of(x, "file_name"), *problem = fname ? rs_io_name_problem(fname) : NULL;
            const double id = number_of(x, "id"), w = number_of(x, "width"), h = number_of(x, "height");
            if (!fname || problem) {
                st = rs_err_set(err, RS_ERR_PARSE, "%s: images[%d].file_name: %s", path, index,
                                fname ? problem : "missing");
                break;
            }
            if (!(id == floor(id)) || !(w >= 1 && w <= 65535 && w == floor(w)) ||
                !(h >= 1 && h <= 65535 && h == floor(h))) {
                st = rs_err_set(err, RS_ERR_PARSE, "%s: images[%d]: id, width and height must be integers (> 0)", path,
                                index);
                break;
            }
            index++;
            if (max_images > 0 && v->Nitems >= max_images) continue;
            view_item *grown = realloc(v->items, sizeof(view_item) * (size_t)(v->Nitems + 1));
            if (!grown) {
                st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
                break;
            }
            v->items = grown;
            v->items[v->Nitems++] = (view_item){.split = v->split_names[s], .image = x};
        }
        index = 0;
        cJSON_ArrayForEach(x, anns)
        {
            if (st) break;
            const double image_id = number_of(x, "image_id");
            if (isnan(image_id)) {
                st = rs_err_set(err, RS_ERR_PARSE, "%s: annotations[%d].image_id: missing", path, index);
                break;
            }
            if ((st = check_annotation(x, index, path, err))) break;
            for (int i = first; i < v->Nitems; i++) {
                view_item *it = &v->items[i];
                if (number_of(it->image, "id") != image_id) continue;
                if (it->Nann == it->cap_ann) {
                    const int cap = it->cap_ann ? 2 * it->cap_ann : 16;
                    const cJSON **g = realloc(it->ann, sizeof(cJSON *) * (size_t)cap);
                    if (!g) {
                        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
                        break;
                    }
                    it->ann = g;
                    it->cap_ann = cap;
                }
                it->ann[it->Nann++] = x;
                break;
            }
            index++;
        }
    }
    free(adir);
    if (!st && v->Nitems == 0) st = rs_err_set(err, RS_ERR_NOT_FOUND, "%s: the dataset has no image", dataset_dir);
    return st;
}

// A label coordinate (pixel-centre convention, docs/conventions.md) in the tile at scale s.
static double to_tile(double x, double s) { return (x + 0.5) * s - 0.5; }

// The outline of a box (x0, y0, x1, y1) in image coordinates, drawn on the tile at scale s
// through the outermost pixels whose centres lie inside it (a box narrower than a pixel: the
// pixel at its centre).
static void box_pixels(int out[4], const double box[4], double s, int tile_w, int tile_h)
{
    for (int a = 0; a < 2; a++) {
        const double lo = to_tile(box[a], s), hi = to_tile(box[a + 2], s);
        int i0 = (int)ceil(lo), i1 = (int)floor(hi);
        if (i0 > i1) i0 = i1 = (int)lround(0.5 * (lo + hi));
        const int n = a ? tile_h : tile_w;
        out[a] = i0 < 0 ? 0 : i0 > n - 1 ? n - 1 : i0;
        out[a + 2] = i1 < 0 ? 0 : i1 > n - 1 ? n - 1 : i1;
    }
}

// The tile of one image: the image at scale s with its labels drawn. out: *tile allocated.
static rs_status draw_tile(rs_image *tile, const view_item *it, const char *dataset_dir, double s, int tile_w,
                           int tile_h, rs_err *err)
{
    *tile = (rs_image){0};
    const char *fname = string_of(it->image, "file_name");
    char rel[1200];
    snprintf(rel, sizeof(rel), "%s/%s", it->split, fname);
    char *path = rs_io_join(dataset_dir, rel);
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_image img = {0}, rgb = {0};
    rs_status st = rs_image_read(&img, path, err);
    if (!st && (img.width != (int)number_of(it->image, "width") || img.height != (int)number_of(it->image, "height")))
        st = rs_err_set(err, RS_ERR_INVALID, "%s: %dx%d, the COCO file says %dx%d", path, img.width, img.height,
                        (int)number_of(it->image, "width"), (int)number_of(it->image, "height"));
    if (!st) st = rs_image_alloc(&rgb, img.width, img.height, 3, err);
    if (!st) {
        for (size_t p = 0; p < (size_t)img.width * img.height; p++)
            for (int c = 0; c < 3; c++) rgb.data[3 * p + c] = img.data[p * img.channels + (img.channels >= 3 ? c : 0)];
        if (tile_w == img.width && tile_h == img.height) {
            *tile = rgb;
            rgb = (rs_image){0};
        } else
            st = rs_synth_image_resize(tile, &rgb, tile_w, tile_h, err);
    }
    rs_image_free(&img);
    rs_image_free(&rgb);
    free(path);
    if (st) return st;

    double box[4], p[2], q[2];
    int r[4];
    // back to front: the 3D boxes, body and visible boxes, bottom centres, visibilities, and the
    // footprint boxes last (what the detector learns stays whole)
    for (int k = 0; k < it->Nann && !st; k++) {
        const cJSON *c = cJSON_GetObjectItemCaseSensitive(it->ann[k], "corners_px");
        if (!cJSON_IsArray(c)) continue;
        double corner[8][2];
        bool ok[8];
        for (int i = 0; i < 8; i++) {
            ok[i] = read_point(corner[i], cJSON_GetArrayItem(c, i)) == 1;
            if (ok[i])
                for (int a = 0; a < 2; a++) corner[i][a] = to_tile(corner[i][a], s);
        }
        // the 12 edges: corners that differ in one bit (docs/labels.md, corner numbering)
        for (int i = 0; i < 8 && !st; i++)
            for (int bit = 1; bit < 8 && !st; bit <<= 1)
                if (!(i & bit) && ok[i] && ok[i | bit])
                    st = rs_synth_draw_line(tile, corner[i], corner[i | bit], col_box3d, 1, err);
    }
    for (int k = 0; k < it->Nann && !st; k++) {
        if (read_box(box, it->ann[k], "body_bbox") == 1) {
            box_pixels(r, box, s, tile_w, tile_h);
            st = rs_synth_draw_rect(tile, r[0], r[1], r[2], r[3], col_body, 1, err);
        }
        if (!st && read_box(box, it->ann[k], "visible_bbox") == 1) {
            box_pixels(r, box, s, tile_w, tile_h);
            st = rs_synth_draw_rect(tile, r[0], r[1], r[2], r[3], col_visible, 1, err);
        }
    }
    for (int k = 0; k < it->Nann && !st; k++)
        if (read_point(p, cJSON_GetObjectItemCaseSensitive(it->ann[k], "bottom_center")) == 1) {
            q[0] = to_tile(p[0], s);
            q[1] = to_tile(p[1], s);
            st = rs_synth_draw_dot(tile, q, 1, col_bottom, err);
        }
    for (int k = 0; k < it->Nann && !st; k++) {
        const double vis = number_of(it->ann[k], "visibility");
        if (isnan(vis) || read_box(box, it->ann[k], "footprint_bbox") != 1) continue;
        char text[32];
        snprintf(text, sizeof(text), "%.2f", vis);
        box_pixels(r, box, s, tile_w, tile_h);
        st = rs_synth_draw_text(tile, r[0], r[1] > 9 ? r[1] - 2 : r[3] + 8, text, 5, col_text, col_text_bg, NULL, err);
    }
    for (int k = 0; k < it->Nann && !st; k++)
        if (read_box(box, it->ann[k], "footprint_bbox") == 1) {
            box_pixels(r, box, s, tile_w, tile_h);
            st = rs_synth_draw_rect(tile, r[0], r[1], r[2], r[3], col_footprint, 1, err);
        }
    if (st) rs_image_free(tile);
    return st;
}

static void paste(rs_image *page, const rs_image *tile, int x0, int y0)
{
    for (int y = 0; y < tile->height; y++)
        memcpy(page->data + 3 * ((size_t)(y0 + y) * page->width + x0), tile->data + 3 * (size_t)y * tile->width,
               sizeof(float) * 3 * (size_t)tile->width);
}

static rs_status draw_legend(rs_image *page, rs_err *err)
{
    int x = GAP_PX;
    rs_status st = RS_OK;
    for (size_t i = 0; i < sizeof(legend) / sizeof(legend[0]) && !st; i++) {
        int w = 0;
        if (i + 1 < sizeof(legend) / sizeof(legend[0])) {
            st = rs_synth_draw_rect(page, x, 7, x + 10, 15, legend[i].rgb, 2, err);
            x += 16;
        }
        if (!st) st = rs_synth_draw_text(page, x, 15, legend[i].name, 8, col_text, NULL, &w, err);
        x += w + 14;
    }
    return st;
}

// HTML-escapes s into f.
static void html_text(FILE *f, const char *s)
{
    for (; s && *s; s++) {
        if (*s == '<')
            fputs("&lt;", f);
        else if (*s == '>')
            fputs("&gt;", f);
        else if (*s == '&')
            fputs("&amp;", f);
        else if (*s == '"')
            fputs("&quot;", f);
        else
            fputc(*s, f);
    }
}

static rs_status write_html(const view_state *v, const rs_synth_view_summary *sum, const char *out_dir,
                            const char *dataset_dir, rs_err *err)
{
    char *path = rs_io_join(out_dir, "index.html");
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_io_atomic a = {0};
    rs_status st = rs_io_atomic_open(&a, path, err);
    free(path);
    if (st) return st;
    FILE *f = a.f;
    fputs("<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>dataset ", f);
    html_text(f, dataset_dir);
    fputs("</title>\n<style>body{font-family:sans-serif;background:#262626;color:#eee}"
          "td,th{padding:1px 8px;text-align:left}.sw{display:inline-block;width:12px;height:10px;"
          "border:2px solid;margin:0 4px 0 12px}</style></head><body>\n<h1>",
          f);
    html_text(f, dataset_dir);
    fprintf(f, "</h1>\n<p>%d images, %d labels, %d pages (roadside dataset view; fields: docs/labels.md)</p>\n<p>",
            sum->images, sum->labels, sum->pages);
    for (size_t i = 0; i < sizeof(legend) / sizeof(legend[0]); i++)
        fprintf(f, "<span class=\"sw\" style=\"border-color:rgb(%d,%d,%d)\"></span>%s (<code>%s</code>)\n",
                (int)lround(legend[i].rgb[0] * 255), (int)lround(legend[i].rgb[1] * 255),
                (int)lround(legend[i].rgb[2] * 255), legend[i].name, legend[i].field);
    fputs("</p>\n<p>The 3D box's edges join its projected corners with straight lines (a lens with distortion bends "
          "them; the labels' boxes follow the bent edges). The number above a footprint box is the label's "
          "visibility.</p>\n",
          f);
    for (int pg = 1; pg <= sum->pages; pg++) {
        fprintf(f, "<h2>page %d</h2>\n<img src=\"page_%03d.png\" alt=\"page %d\">\n", pg, pg, pg);
        fputs("<table><tr><th>index</th><th>split</th><th>file</th><th>camera</th><th>background</th>"
              "<th>weather</th><th>time of day</th><th>labels</th></tr>\n",
              f);
        for (int i = 0; i < v->Nitems; i++) {
            const view_item *it = &v->items[i];
            if (it->page != pg) continue;
            fprintf(f, "<tr><td>%.0f</td><td>", number_of(it->image, "index"));
            html_text(f, it->split);
            static const char *keys[] = {"file_name", "camera", "background", "weather", "time_of_day"};
            for (int k = 0; k < 5; k++) {
                fputs("</td><td>", f);
                const char *val = string_of(it->image, keys[k]);
                html_text(f, val ? val : "-");
            }
            fprintf(f, "</td><td>%d</td></tr>\n", it->Nann);
        }
        fputs("</table>\n", f);
    }
    fputs("</body></html>\n", f);
    if (ferror(f)) {
        rs_io_atomic_abort(&a);
        return rs_err_set(err, RS_ERR_IO, "%s/index.html: write failed", out_dir);
    }
    return rs_io_atomic_commit(&a, err);
}

// index.json: where each image's tile is (for tools and tests).
static rs_status write_index_json(const view_state *v, const rs_synth_view_summary *sum, const char *out_dir,
                                  rs_err *err)
{
    cJSON *root = cJSON_CreateObject(), *imgs = cJSON_AddArrayToObject(root, "images");
    cJSON_AddNumberToObject(root, "pages", sum->pages);
    cJSON_AddNumberToObject(root, "scale", sum->scale);
    cJSON_AddNumberToObject(root, "tile_width", sum->tile_width);
    cJSON_AddNumberToObject(root, "tile_height", sum->tile_height);
    for (int i = 0; i < v->Nitems; i++) {
        const view_item *it = &v->items[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "split", it->split);
        cJSON_AddStringToObject(o, "file_name", string_of(it->image, "file_name"));
        cJSON_AddNumberToObject(o, "image_id", number_of(it->image, "id"));
        cJSON_AddNumberToObject(o, "page", it->page);
        cJSON_AddNumberToObject(o, "x", it->x_px);
        cJSON_AddNumberToObject(o, "y", it->y_px);
        cJSON_AddNumberToObject(o, "labels", it->Nann);
        cJSON_AddItemToArray(imgs, o);
    }
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    if (!text) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    char *path = rs_io_join(out_dir, "index.json");
    rs_status st =
        path ? rs_io_write_file(path, text, strlen(text), err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    free(path);
    free(text);
    return st;
}

void rs_synth_view_options_default(rs_synth_view_options *opt)
{
    memset(opt, 0, sizeof(*opt));
    opt->max_images = 48;
    opt->per_page = 12;
    opt->columns = 4;
    opt->max_tile_width_px = 480;
}

rs_status rs_synth_dataset_view(rs_synth_view_summary *sum, const char *dataset_dir, const char *out_dir,
                                const rs_synth_view_options *opt, rs_err *err)
{
    memset(sum, 0, sizeof(*sum));
    if (opt->max_images < 0 || opt->per_page < 1 || opt->columns < 1 || opt->max_tile_width_px < 16)
        return rs_err_set(err, RS_ERR_USAGE, "view: max_images >= 0, per_page >= 1, columns >= 1, tile width >= 16");
    view_state v = {0};
    rs_status st = view_load(&v, dataset_dir, opt->max_images, err);
    rs_image page = {0}, tile = {0};
    if (st) goto done;
    // one tile size for the sheet: the first image's (synth makes every image of a dataset the same size)
    const int W = (int)number_of(v.items[0].image, "width"), H = (int)number_of(v.items[0].image, "height");
    const double s = W > opt->max_tile_width_px ? (double)opt->max_tile_width_px / W : 1.0;
    const int tw = (int)lround(W * s), th = (int)lround(H * s) < 1 ? 1 : (int)lround(H * s);
    for (int i = 1; i < v.Nitems; i++)
        if ((int)number_of(v.items[i].image, "width") != W || (int)number_of(v.items[i].image, "height") != H) {
            st = rs_err_set(err, RS_ERR_INVALID, "%s/%s: %.0fx%.0f, the first image is %dx%d: one size per dataset",
                            v.items[i].split, string_of(v.items[i].image, "file_name"),
                            number_of(v.items[i].image, "width"), number_of(v.items[i].image, "height"), W, H);
            goto done;
        }
    sum->scale = s;
    sum->tile_width = tw;
    sum->tile_height = th;
    if ((st = rs_io_mkdir_p(out_dir, err))) goto done;
    const int P = opt->per_page;
    for (int first = 0; first < v.Nitems && !st; first += P) {
        const int n = v.Nitems - first < P ? v.Nitems - first : P;
        const int cols = n < opt->columns ? n : opt->columns, rows = (n + cols - 1) / cols;
        int pw = GAP_PX + cols * (tw + GAP_PX), ph = LEGEND_PX + GAP_PX + rows * (th + CAPTION_PX + GAP_PX);
        if (pw < 720) pw = 720; // room for the legend
        if ((st = rs_image_alloc(&page, pw, ph, 3, err))) break;
        for (size_t p = 0; p < (size_t)pw * ph; p++)
            for (int c = 0; c < 3; c++) page.data[3 * p + c] = col_page[c];
        if ((st = draw_legend(&page, err))) break;
        sum->pages++;
        for (int j = 0; j < n && !st; j++) {
            view_item *it = &v.items[first + j];
            it->page = sum->pages;
            it->x_px = GAP_PX + (j % cols) * (tw + GAP_PX);
            it->y_px = LEGEND_PX + GAP_PX + (j / cols) * (th + CAPTION_PX + GAP_PX);
            if ((st = draw_tile(&tile, it, dataset_dir, s, tw, th, err))) break;
            paste(&page, &tile, it->x_px, it->y_px);
            rs_image_free(&tile);
            char caption[400];
            const char *bg = string_of(it->image, "background"), *fname = string_of(it->image, "file_name");
            const char *dot = strrchr(fname, '.');
            snprintf(caption, sizeof(caption), "%.*s %s", dot ? (int)(dot - fname) : (int)strlen(fname), fname,
                     bg ? bg : "");
            st = rs_synth_draw_text(&page, it->x_px, it->y_px + th + CAPTION_PX - 4, caption, 7, col_text, NULL, NULL,
                                    err);
            sum->images++;
            sum->labels += it->Nann;
        }
        if (!st) {
            char name[64];
            snprintf(name, sizeof(name), "page_%03d.png", sum->pages);
            char *path = rs_io_join(out_dir, name);
            st = path ? rs_image_write(path, &page, 8, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            free(path);
        }
        rs_image_free(&page);
    }
    if (!st) st = write_index_json(&v, sum, out_dir, err);
    if (!st) st = write_html(&v, sum, out_dir, dataset_dir, err);
done:
    rs_image_free(&page);
    rs_image_free(&tile);
    view_free(&v);
    return st;
}
