// rs_synth_dataset_frames.c -- traffic from SUMO's frames (--traffic-frames): the folder's index
// read once per run, every frame checked and hashed before DATASET is touched, one frame's
// vehicles for an image (rs_synth_dataset.h, rs_synth_dataset_internal.h).
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_hash.h"
#include "core/rs_io.h"
#include "core/rs_rng.h"
#include "synth/dataset/internal/rs_synth_dataset_internal.h"

// Frame i of DIR (index entry e) read as a vehicles file (rs_synth_vehicles_read: the one reader
// of that format) and checked for what synth needs: the count the index states, class vehicles
// with their box. On error *list is left empty.
static rs_status read_frame(rs_synth_vehicle_list *list, const char *dir, const rs_synth_sumo_frame_entry *e, int i,
                            rs_err *err)
{
    memset(list, 0, sizeof(*list));
    char *path = rs_io_join(dir, e->file);
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = rs_synth_vehicles_read(list, path, err);
    if (!st && list->N != e->vehicles)
        st = rs_err_set(err, RS_ERR_INVALID, "%s: %d vehicles, but %s/frames.json [%d].vehicles says %d", path, list->N,
                        dir, i, e->vehicles);
    for (int j = 0; !st && j < list->N; j++) {
        const rs_synth_vehicle *v = &list->v[j];
        const char *missing = !(v->length_m > 0) ? "length" : !(v->width_m > 0) ? "width" : "height";
        if (v->cls == RS_SYNTH_USER_MODEL)
            st = rs_err_set(err, RS_ERR_INVALID, "%s: [%d].model: a traffic frame holds class vehicles only", path, j);
        else if (!(v->length_m > 0 && v->width_m > 0 && v->height_m > 0))
            st = rs_err_set(err, RS_ERR_INVALID, "%s: [%d].%s: missing (a traffic frame gives every vehicle's box)",
                            path, j, missing);
    }
    if (st) rs_synth_vehicle_list_free(list);
    free(path);
    return st;
}

// Appends "<sha256 of DIR/name>  name\n" to the manifest f.
static rs_status manifest_line(FILE *f, const char *dir, const char *name, rs_err *err)
{
    char hex[65];
    char *path = rs_io_join(dir, name);
    rs_status st = path ? rs_hash_sha256_file(hex, NULL, path, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) fprintf(f, "%s  %s\n", hex, name);
    free(path);
    return st;
}

// The checks and the manifest of rs_synth_dataset_traffic_frames_check, over an index already
// read: the manifest is built in memory (open_memstream) and hashed there.
static rs_status frames_check(rs_synth_traffic_frames_info *info, const char *dir, const rs_synth_sumo_frame_entry *e,
                              int N, rs_err *err)
{
    memset(info, 0, sizeof(*info));
    char *manifest = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&manifest, &len);
    if (!f) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = manifest_line(f, dir, "frames.json", err);
    for (int i = 0; i < N && !st; i++) {
        rs_synth_vehicle_list list;
        if ((st = read_frame(&list, dir, &e[i], i, err))) break;
        info->Nvehicles += list.N;
        rs_synth_vehicle_list_free(&list);
        st = manifest_line(f, dir, e[i].file, err);
    }
    if (fclose(f) != 0 && !st) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) st = rs_hash_sha256_buffer(info->sha256, manifest, len, err);
    free(manifest);
    if (!st) info->Nframes = N;
    return st;
}

// DIR/frames.json with at least one frame.
static rs_status read_index(rs_synth_sumo_frame_entry **entries, int *N, const char *dir, rs_err *err)
{
    rs_status st = rs_synth_sumo_frames_index_read(entries, N, dir, err);
    if (!st && *N == 0)
        st = rs_err_set(err, RS_ERR_INVALID, "%s/frames.json: no frames (an empty list): no traffic to take", dir);
    return st;
}

rs_status rs_synth_dataset_traffic_frames_check(rs_synth_traffic_frames_info *info, const char *dir, rs_err *err)
{
    memset(info, 0, sizeof(*info));
    rs_synth_sumo_frame_entry *e = NULL;
    int N = 0;
    rs_status st = read_index(&e, &N, dir, err);
    if (!st) st = frames_check(info, dir, e, N, err);
    free(e);
    return st;
}

rs_status rs_synth_dataset__frames_load(rs_synth_dataset__run *d, rs_synth_traffic_frames_info *info, rs_err *err)
{
    const char *dir = d->opt->traffic_frames_dir;
    rs_status st = read_index(&d->frames, &d->Nframes, dir, err);
    if (!st) st = frames_check(info, dir, d->frames, d->Nframes, err);
    return st;
}

rs_status rs_synth_dataset__frame_vehicles(rs_synth_vehicle_list *list, int *iframe, const rs_synth_dataset__run *d,
                                           int k, uint64_t r_frame, uint64_t r_looks, rs_err *err)
{
    const rs_synth_dataset_options *opt = d->opt;
    const int i = opt->sequence ? opt->frame_first + k / d->Ncams : (int)(r_frame % (uint64_t)d->Nframes);
    *iframe = i;
    rs_status st = read_frame(list, opt->traffic_frames_dir, &d->frames[i], i, err);
    // a sequence: the looks from (seed, the file's variant, which SUMO's frames derive from the
    // vehicle's id), the same in every frame
    for (int j = 0; !st && j < list->N; j++)
        list->v[j].variant = (opt->sequence ? rs_rng_seed_derive(opt->seed, list->v[j].variant)
                                            : rs_rng_seed_derive(r_looks, (uint64_t)j)) >>
                             11;
    return st;
}
