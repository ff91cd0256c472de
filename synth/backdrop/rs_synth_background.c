// rs_synth_background.c -- temporal-median backgrounds and the tags of every background
// (rs_synth_background.h, docs/backgrounds.md); site.json is read and written by geo
// (rs_site_record_background), never here.
#include "synth/backdrop/rs_synth_background.h"

#include <ctype.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "geo/rs_site_write.h"
#include "synth/backdrop/rs_synth_opencv.h"
#include "synth/backdrop/rs_synth_sun.h"

// ---- temporal median ----

size_t rs_synth_median_bytes_bound(int width, int height, int max_frames)
{
    return ((size_t)max_frames + 3) * (size_t)width * (size_t)height * 3;
}

void rs_synth_median_free(rs_synth_median *m)
{
    if (!m) return;
    free(m->rgb);
    memset(m, 0, sizeof(*m));
}

// The k-th smallest of a[0..n-1] (Hoare's selection; a is reordered).
static unsigned char select_kth(unsigned char *a, int n, int k)
{
    int lo = 0, hi = n - 1;
    while (lo < hi) {
        const unsigned char pivot = a[(lo + hi) / 2];
        int i = lo, j = hi;
        while (i <= j) {
            while (a[i] < pivot) i++;
            while (a[j] > pivot) j--;
            if (i <= j) {
                const unsigned char t = a[i];
                a[i++] = a[j];
                a[j--] = t;
            }
        }
        if (k <= j)
            hi = j;
        else if (k >= i)
            lo = i;
        else
            break;
    }
    return a[k];
}

rs_status rs_synth_background_median(rs_synth_median *out, const char *const *inputs, int Ninputs, int max_frames,
                                     rs_err *err)
{
    memset(out, 0, sizeof(*out));
    if (max_frames < 3 || max_frames > 255)
        return rs_err_set(err, RS_ERR_USAGE, "max_frames: %d is not in [3, 255]", max_frames);
    unsigned char *buf = NULL; // (max_frames, H, W, 3)
    size_t frame_bytes = 0;
    int n = 0, stride = 1, width = 0, height = 0;
    long index = 0;
    rs_status st = RS_OK;
    for (int in = 0; in < Ninputs && !st; in++) {
        rs_synth_frames *fr = NULL;
        if ((st = rs_synth_frames_open(&fr, inputs[in], err))) break;
        for (;;) {
            const unsigned char *rgb;
            int w, h, got;
            if ((st = rs_synth_frames_next(fr, &rgb, &w, &h, &got, err)) || !got) break;
            if (!buf) {
                width = w;
                height = h;
                frame_bytes = (size_t)w * h * 3;
                if (!(buf = malloc(frame_bytes * (size_t)max_frames))) {
                    st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory for %d frames of %dx%d", inputs[in],
                                    max_frames, w, h);
                    break;
                }
            } else if (w != width || h != height) {
                st = rs_err_set(err, RS_ERR_INVALID, "%s: frame %ld is %dx%d, the first frame was %dx%d", inputs[in],
                                index, w, h, width, height);
                break;
            }
            if (index % stride == 0) {
                if (n == max_frames) {
                    // full: keep buffer positions 0, 2, 4, ... and double the stride
                    int k = 0;
                    for (int i = 0; i < n; i += 2, k++)
                        if (k != i) memcpy(buf + k * frame_bytes, buf + i * frame_bytes, frame_bytes);
                    n = k;
                    stride *= 2;
                }
                if (index % stride == 0) memcpy(buf + (size_t)n++ * frame_bytes, rgb, frame_bytes);
            }
            index++;
        }
        rs_synth_frames_close(fr);
    }
    if (!st && n == 0) st = rs_err_set(err, RS_ERR_DEGENERATE, "no frame could be read from the %d input(s)", Ninputs);
    if (!st && !(out->rgb = malloc(frame_bytes))) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (st) {
        free(buf);
        memset(out, 0, sizeof(*out));
        return st;
    }
    unsigned char v[255];
    const int k = (n - 1) / 2;
    for (size_t p = 0; p < frame_bytes; p++) {
        for (int i = 0; i < n; i++) v[i] = buf[(size_t)i * frame_bytes + p];
        out->rgb[p] = select_kth(v, n, k);
    }
    free(buf);
    out->width = width;
    out->height = height;
    out->Nframes_read = index;
    out->Nframes_used = n;
    out->stride = stride;
    out->bytes_bound = rs_synth_median_bytes_bound(width, height, max_frames);
    return RS_OK;
}

// ---- tags and site.json ----

const char *const rs_synth_background_conditions[] = {"sunny", "cloudy", "rain", "snow", "night", "dusk", NULL};

static bool is_safe_name(const char *s, size_t max)
{
    if (!s || !*s || *s == '.' || strlen(s) > max) return false;
    for (; *s; s++)
        if (!isalnum((unsigned char)*s) && *s != '_' && *s != '.' && *s != '-') return false;
    return true;
}

bool rs_synth_background_name_ok(const char *s) { return is_safe_name(s, 100); }

rs_status rs_synth_background_tags_check(const rs_synth_background_tags *t, rs_err *err)
{
    if (!rs_synth_background_name_ok(t->name))
        return rs_err_set(err, RS_ERR_USAGE,
                          "name: '%s' must be 1..100 characters of [A-Za-z0-9_.-], not starting "
                          "with '.'",
                          t->name ? t->name : "");
    if (t->time_iso) {
        double unix_s;
        rs_status st = rs_synth_parse_iso8601(&unix_s, t->time_iso, "tag time", err);
        if (st) return st;
    }
    if (t->conditions) {
        bool ok = false;
        for (int i = 0; rs_synth_background_conditions[i]; i++)
            ok = ok || !strcmp(t->conditions, rs_synth_background_conditions[i]);
        if (!ok)
            return rs_err_set(err, RS_ERR_USAGE,
                              "tag conditions: '%s' is not one of sunny, cloudy, rain, snow, night, dusk",
                              t->conditions);
    }
    return RS_OK;
}

rs_status rs_synth_background_tag_parse(rs_synth_background_tags *t, const char **keys, const char **values, char *kv,
                                        rs_err *err)
{
    char *eq = strchr(kv, '=');
    if (!eq || eq == kv) return rs_err_set(err, RS_ERR_USAGE, "tag '%s': expected key=value", kv);
    *eq = 0;
    const char *key = kv, *value = eq + 1;
    if (!strcmp(key, "time"))
        t->time_iso = value;
    else if (!strcmp(key, "conditions"))
        t->conditions = value;
    else if (!strcmp(key, "synthetic") || !is_safe_name(key, 64)) {
        *eq = '=';
        return rs_err_set(err, RS_ERR_USAGE, "tag '%s': the key must be [A-Za-z0-9_.-]+ and not 'synthetic'", kv);
    } else {
        keys[t->Ntags] = key;
        values[t->Ntags] = value;
        t->Ntags++;
        t->keys = keys;
        t->values = values;
    }
    return RS_OK;
}

char *rs_synth_background_path(const char *site_dir, const char *camera_id, const char *name)
{
    char *rel = rs_site_background_file(camera_id, name);
    char *p = rel ? rs_io_join(site_dir, rel) : NULL;
    free(rel);
    return p;
}

rs_status rs_synth_background_record(const char *site_dir, const char *camera_id, const rs_synth_background_tags *t,
                                     const char *source_json, rs_err *err)
{
    // time and conditions first, then the free tags in the order given
    const char **keys = malloc(sizeof(char *) * (size_t)(t->Ntags + 2));
    const char **values = malloc(sizeof(char *) * (size_t)(t->Ntags + 2));
    int n = 0;
    rs_status st;
    if (!keys || !values) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    if (t->time_iso) keys[n] = "time", values[n++] = t->time_iso;
    if (t->conditions) keys[n] = "conditions", values[n++] = t->conditions;
    for (int i = 0; i < t->Ntags; i++) keys[n] = t->keys[i], values[n++] = t->values[i];
    st = rs_site_record_background(site_dir, camera_id, t->name, t->synthetic, keys, values, n, source_json, err);
done:
    free(keys);
    free(values);
    return st;
}

// ---- digital-twin backgrounds ----

rs_status rs_synth_background_save_median(char **path_out, const char *site_dir, const char *camera_id,
                                          const rs_synth_background_tags *tags, const rs_synth_median *med,
                                          const char *const *inputs, int Ninputs, rs_err *err)
{
    *path_out = NULL;
    rs_image img = {0};
    char *path = NULL, *dir = NULL, *source_json = NULL;
    cJSON *source = NULL;
    rs_status st = rs_image_alloc(&img, med->width, med->height, 3, err);
    if (st) return st;
    for (size_t p = 0; p < (size_t)med->width * med->height * 3; p++) img.data[p] = med->rgb[p] / 255.0f;
    path = rs_synth_background_path(site_dir, camera_id, tags->name);
    dir = path ? strdup(path) : NULL;
    source = cJSON_CreateObject();
    if (!path || !dir || !source) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    *strrchr(dir, '/') = 0;
    cJSON_AddStringToObject(source, "method", "temporal median");
    cJSON *in = cJSON_AddArrayToObject(source, "inputs");
    for (int i = 0; i < Ninputs; i++) cJSON_AddItemToArray(in, cJSON_CreateString(inputs[i]));
    cJSON_AddNumberToObject(source, "frames_read", (double)med->Nframes_read);
    cJSON_AddNumberToObject(source, "frames_used", med->Nframes_used);
    cJSON_AddNumberToObject(source, "stride", med->stride);
    if (!(source_json = cJSON_PrintUnformatted(source))) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    if ((st = rs_io_mkdir_p(dir, err)) || (st = rs_image_write(path, &img, 8, err)) ||
        (st = rs_synth_background_record(site_dir, camera_id, tags, source_json, err)))
        goto done;
    *path_out = path;
    path = NULL;
done:
    cJSON_Delete(source);
    cJSON_free(source_json);
    free(path);
    free(dir);
    rs_image_free(&img);
    return st;
}
