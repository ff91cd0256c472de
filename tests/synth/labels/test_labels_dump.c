// tests/synth/labels/test_labels_dump.c -- runs rs_synth_labels_compute and the writers for
// tests/synth/labels/test_labels.py (which checks them against mrcal's Python and brute force).
// usage: test_labels_dump MODEL.cameramodel VEHICLES.txt OUTDIR [IDS.u16|-] [BBOX] [MIN_VIS] [mesh]
//   VEHICLES.txt: one vehicle a line: "class e n yaw_deg length width height up variant"
//   IDS.u16: the object-ID image, width*height little-endian uint16, row-major
//   mesh: pass the procedural meshes (else the labels use the boxes)
// Writes OUTDIR/labels.json (every field of every label) and the COCO (split "val2017"), YOLO
// and KITTI outputs under OUTDIR.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "synth/labels/rs_synth_labels.h"

static void num(FILE *f, double x)
{
    if (isfinite(x))
        fprintf(f, "%.17g", x);
    else
        fprintf(f, "null");
}

static void nums(FILE *f, const char *key, const double *x, int n)
{
    fprintf(f, "\"%s\": [", key);
    for (int i = 0; i < n; i++) {
        if (i) fprintf(f, ", ");
        num(f, x[i]);
    }
    fprintf(f, "]");
}

static int fail(const char *what, const rs_err *err)
{
    fprintf(stderr, "test_labels_dump: %s: %s\n", what, err->msg);
    return 1;
}

int main(int argc, char **argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: test_labels_dump MODEL VEHICLES OUTDIR [IDS|-] [BBOX] [MIN_VIS] [mesh]\n");
        return 2;
    }
    rs_err err = {0};
    rs_camera cam;
    if (rs_camera_read(&cam, NULL, argv[1], &err)) return fail("camera", &err);
    FILE *vf = fopen(argv[2], "r");
    if (!vf) return 1;
    rs_synth_vehicle v[256];
    double up[256];
    char cls[64], ids_buf[256][16];
    const char *ids[256];
    int N = 0;
    unsigned long long variant;
    while (N < 256 && fscanf(vf, "%63s %lf %lf %lf %lf %lf %lf %lf %llu", cls, &v[N].e_m, &v[N].n_m, &v[N].yaw_deg,
                             &v[N].length_m, &v[N].width_m, &v[N].height_m, &up[N], &variant) == 9) {
        if (rs_synth_class_from_name(&v[N].cls, cls, &err)) return fail("class", &err);
        v[N].variant = variant;
        v[N].rgb[0] = v[N].rgb[1] = v[N].rgb[2] = -1;
        if (rs_synth_fleet_resolve(&v[N], &v[N], &err)) return fail("resolve", &err);
        snprintf(ids_buf[N], sizeof ids_buf[N], "veh%d", N);
        ids[N] = ids_buf[N];
        N++;
    }
    fclose(vf);
    uint16_t *id_image = NULL;
    if (argc > 4 && strcmp(argv[4], "-") != 0) {
        char *data = NULL;
        size_t len = 0;
        if (rs_io_read_file(&data, &len, argv[4], &err)) return fail("ids", &err);
        if (len != (size_t)cam.width * cam.height * 2) {
            fprintf(stderr, "ids: %zu bytes, want %d\n", len, cam.width * cam.height * 2);
            return 1;
        }
        id_image = malloc(len);
        for (size_t i = 0; i < len / 2; i++)
            id_image[i] = (uint16_t)((unsigned char)data[2 * i] | (unsigned char)data[2 * i + 1] << 8);
        free(data);
    }
    rs_synth_label_options opt = {RS_SYNTH_BBOX_FOOTPRINT, 0, false}; // every label, visible or not
    if (argc > 5 && rs_synth_bbox_kind_parse(&opt.bbox, argv[5], &err)) return fail("bbox", &err);
    if (argc > 6) opt.min_visibility = atof(argv[6]);
    rs_synth_mesh meshes[256];
    int with_mesh = argc > 7 && strcmp(argv[7], "mesh") == 0;
    for (int k = 0; with_mesh && k < N; k++)
        if (rs_synth_fleet_build(&meshes[k], &v[k], &err)) return fail("build", &err);
    rs_synth_label *labels = NULL;
    if (rs_synth_labels_compute(&labels,
                                &(rs_synth_label_input){.cam = &cam,
                                                        .vehicles = v,
                                                        .Nvehicles = N,
                                                        .up_m = up,
                                                        .meshes = with_mesh ? meshes : NULL,
                                                        .id_image = id_image},
                                &err))
        return fail("labels", &err);

    char *path = rs_io_join(argv[3], "labels.json");
    rs_io_atomic a;
    if (rs_io_atomic_open(&a, path, &err)) return fail("labels.json", &err);
    fprintf(a.f, "[\n");
    for (int k = 0; k < N; k++) {
        const rs_synth_label *L = &labels[k];
        fprintf(a.f, "{\"index\": %d, \"in_image\": %d", L->index, L->in_image);
        const struct {
            const char *key;
            const double *x;
            int n;
        } fields[] = {
            {"center_enu_m", L->center_enu_m, 3},      {"dims_m", L->dims_m, 3},
            {"corners_px", &L->corners_px[0][0], 16},  {"body_box_full", L->body_box_full_px, 4},
            {"body_box", L->body_box_px, 4},           {"footprint_box_full", L->footprint_box_full_px, 4},
            {"footprint_box", L->footprint_box_px, 4}, {"footprint_center", L->footprint_center_px, 2},
            {"bottom_center", L->bottom_center_px, 2}, {"bottom_center_cam_m", L->bottom_center_cam_m, 3},
            {"truncation", &L->truncation, 1},         {"rotation_y", &L->rotation_y_rad, 1},
            {"visibility", &L->visibility, 1},         {"visible_box", L->visible_box_px, 4},
        };
        for (size_t i = 0; i < sizeof fields / sizeof fields[0]; i++) {
            fprintf(a.f, ", ");
            if (fields[i].n == 1) {
                fprintf(a.f, "\"%s\": ", fields[i].key);
                num(a.f, fields[i].x[0]);
            } else
                nums(a.f, fields[i].key, fields[i].x, fields[i].n);
        }
        fprintf(a.f, ", \"visible_px\": %ld, \"full_px\": %ld", L->visible_px, L->full_px);
        fprintf(a.f, "}%s\n", k + 1 < N ? "," : "");
    }
    fprintf(a.f, "]\n");
    free(path);
    if (rs_io_atomic_commit(&a, &err)) return fail("labels.json", &err);

    rs_synth_label_image im = {"frame_000001.png", cam.width, cam.height, labels, N, ids, NULL, NULL};
    if (rs_synth_labels_write_coco(argv[3], "val2017", &im, 1, &opt, &err)) return fail("coco", &err);
    if (rs_synth_labels_write_yolo(argv[3], "val2017", &im, 1, &opt, &err)) return fail("yolo", &err);
    if (rs_synth_labels_write_kitti(argv[3], &im, 1, &opt, &err)) return fail("kitti", &err);
    free(labels);
    free(id_image);
    for (int k = 0; with_mesh && k < N; k++) rs_synth_mesh_free(&meshes[k]);
    rs_camera_free(&cam);
    return 0;
}
