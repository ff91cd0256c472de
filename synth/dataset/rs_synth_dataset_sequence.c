// rs_synth_dataset_sequence.c -- a sequence's ground-truth tracks, DATASET/tracks_gt.csv
// (rs_synth_dataset.h, "sequences"): every vehicle of each frame with the cameras that label it.
// Calls rs_synth_dataset_draws.c (the stems) and the frames' and parts' readers; nothing above.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "synth/dataset/internal/rs_synth_dataset_internal.h"
#include "synth/fleet/rs_synth_fleet.h"

// The vehicle_id of every annotation of parts/<stem>.json. out: *doc owns the strings ids (N,)
static rs_status part_vehicle_ids(cJSON **doc, const char **ids, int *N, int max, const char *dataset_dir,
                                  const char *stem, rs_err *err)
{
    char name[400];
    snprintf(name, sizeof(name), "parts/%s.json", stem);
    char *path = rs_io_join(dataset_dir, name), *text = NULL;
    *doc = NULL;
    *N = 0;
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = rs_synth_dataset__file_exists(path)
                       ? rs_io_read_file(&text, NULL, path, err)
                       : rs_err_set(err, RS_ERR_NOT_FOUND, "%s: missing (the image is not finished)", path);
    if (!st && !(*doc = cJSON_Parse(text))) st = rs_err_set(err, RS_ERR_PARSE, "%s: not JSON", path);
    const cJSON *a, *anns = st ? NULL : cJSON_GetObjectItemCaseSensitive(*doc, "annotations");
    cJSON_ArrayForEach(a, anns)
    {
        const cJSON *id = cJSON_GetObjectItemCaseSensitive(a, "vehicle_id");
        if (!cJSON_IsString(id)) {
            st = rs_err_set(err, RS_ERR_PARSE, "%s: annotations[%d].vehicle_id: missing", path, *N);
            break;
        }
        if (*N < max) ids[(*N)++] = id->valuestring;
    }
    free(text);
    free(path);
    return st;
}

// Writes one frame's rows. seen (Ncameras, max) the vehicle ids each camera labels, Nseen (Ncameras,)
static rs_status frame_rows(FILE *f, long *Nrows, const rs_synth_vehicle_list *list, double time_s,
                            const char *frame_path, const char *const *cameras, int Ncameras, const char ***seen,
                            const int *Nseen, const double ground_normal_enu[3], double ground_offset_m, rs_err *err)
{
    for (int j = 0; j < list->N; j++) {
        const rs_synth_vehicle *v = &list->v[j];
        if (strpbrk(v->id, ",\"\r\n") || !v->id[0])
            return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].id: empty, or a comma, quote or line break in it",
                              frame_path, j);
        // the labels' bottom_center_enu_m (rs_synth_labels.h): the footprint centre at ground height
        const double up = rs_synth_ground_up_m(ground_normal_enu, ground_offset_m, v->e_m, v->n_m);
        const double o[3] = {0, 0, 0};
        double p[3];
        rs_synth_vehicle_to_enu(p, v, up, o);
        double heading = fmod(v->yaw_deg, 360);
        if (heading < 0) heading += 360;
        if (heading >= 360) heading = 0;
        fprintf(f, "%.6f,%s,%s,%.10f,%.10f,%.4f,%.6f,", time_s, v->id, rs_synth_class_name(v->cls), p[0], p[1],
                v->speed_mps, heading);
        int Nlisted = 0;
        for (int c = 0; c < Ncameras; c++)
            for (int i = 0; i < Nseen[c]; i++)
                if (!strcmp(seen[c][i], v->id)) {
                    fprintf(f, "%s%s", Nlisted++ ? "+" : "", cameras[c]);
                    break;
                }
        fputc('\n', f);
        (*Nrows)++;
    }
    return RS_OK;
}

rs_status rs_synth_dataset_tracks_gt_write(long *Nrows_out, const char *dataset_dir, const char *frames_dir, int first,
                                           int end, const char *const *cameras, int Ncameras,
                                           const double ground_normal_enu[3], double ground_offset_m, rs_err *err)
{
    rs_synth_sumo_frame_entry *e = NULL;
    int Nframes = 0;
    long Nrows = 0;
    rs_status st = rs_synth_sumo_frames_index_read(&e, &Nframes, frames_dir, err);
    if (!st && (first < 0 || end > Nframes || first >= end))
        st = rs_err_set(err, RS_ERR_INVALID, "%s/frames.json: frames %d:%d asked, it has %d", frames_dir, first, end,
                        Nframes);
    char *out = rs_io_join(dataset_dir, "tracks_gt.csv");
    cJSON **docs = calloc((size_t)Ncameras, sizeof(cJSON *));
    const char ***seen = calloc((size_t)Ncameras, sizeof(char **));
    int *Nseen = calloc((size_t)Ncameras, sizeof(int));
    rs_io_atomic a = {0};
    if (!st && (!out || !docs || !seen || !Nseen)) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) st = rs_io_atomic_open(&a, out, err);
    if (!st) fputs("time_s,vehicle_id,class,e_m,n_m,speed_mps,heading_deg,cameras\n", a.f);
    for (int i = first; i < end && !st; i++) {
        rs_synth_vehicle_list list = {0};
        char *path = rs_io_join(frames_dir, e[i].file);
        if (!path) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            break;
        }
        st = rs_synth_vehicles_read(&list, path, err);
        const int max = list.N > 0 ? list.N : 1;
        for (int c = 0; c < Ncameras && !st; c++) {
            char stem[300];
            rs_synth_dataset__stem(stem, sizeof(stem), (i - first) * Ncameras + c, cameras[c]);
            if (!(seen[c] = malloc(sizeof(char *) * (size_t)max)))
                st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            else
                st = part_vehicle_ids(&docs[c], seen[c], &Nseen[c], max, dataset_dir, stem, err);
        }
        if (!st)
            st = frame_rows(a.f, &Nrows, &list, e[i].time_s, path, cameras, Ncameras, seen, Nseen, ground_normal_enu,
                            ground_offset_m, err);
        for (int c = 0; c < Ncameras; c++) {
            cJSON_Delete(docs[c]);
            free(seen[c]);
            docs[c] = NULL;
            seen[c] = NULL;
            Nseen[c] = 0;
        }
        rs_synth_vehicle_list_free(&list);
        free(path);
    }
    if (!st)
        st = rs_io_atomic_commit(&a, err);
    else
        rs_io_atomic_abort(&a);
    free(docs);
    free(seen);
    free(Nseen);
    free(out);
    free(e);
    if (!st && Nrows_out) *Nrows_out = Nrows;
    return st;
}
