// roadside bench detect -- inference time per frame of an ONNX detector through OpenCV's DNN
// module (eval/detect/rs_detect.h): preprocess, forward and decode separately, for each input
// size, on one thread and on OpenCV's default threads. Parses, calls the library, prints.
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"
#include "cli/rs_cli_detect.h"
#include "core/rs_io.h"
#include "core/rs_stats.h"

static const char bench_detect_usage[] =
    "usage: roadside bench detect --model M.onnx [--family F] [--sizes 416,640] [--frames N]\n"
    "                             [--frame WxH] [--csv FILE]\n"
    "\n"
    "Times an ONNX detector through OpenCV's DNN module (CPU) on a synthetic frame (a colour\n"
    "gradient): the median over N frames of the preprocessing (letterbox, blob), the forward pass\n"
    "and the decoding (NMS included), for each input size, with one thread\n"
    "(cv::setNumThreads(1)) and with OpenCV's default. One untimed frame first (warm-up).\n"
    "\n"
    "  --model M.onnx   the detector (YOLOX or Ultralytics, as 'roadside detect' runs it)\n"
    "  --family F       yolox, ultralytics or auto (default)\n"
    "  --sizes LIST     input sizes, N or WxH, comma-separated (default 640)\n"
    "  --frames N       timed frames per configuration (default 20)\n"
    "  --frame WxH      the synthetic frame's size (default 1920x1080)\n"
    "  --csv FILE       one row per configuration, written atomically\n"
    "\n"
    "Exit status: 0 ok, 1 failure, 2 usage error. Figures: docs/detect.md.\n";

#define MAX_SIZES 16

typedef struct {
    int net_w, net_h, threads;               // threads: 1, or -1 for OpenCV's default
    double pre_ms, fwd_ms, dec_ms, total_ms; // medians
} bench_row;

// Times one configuration: N frames of `bgr` (w x h). False (message printed) on failure.
static bool time_one(bench_row *row, const char *model, rs_detect_family family, const unsigned char *bgr, int w, int h,
                     int frames)
{
    rs_detect_set_threads(row->threads);
    const rs_detect_options opt = {
        .family = family, .width_px = row->net_w, .height_px = row->net_h, .conf = -1, .nms_iou = -1, .max_dets = -1};
    rs_err err = {0};
    rs_detect_net *net = NULL;
    rs_status st = rs_detect_net_open(&net, model, &opt, &err);
    double *t = calloc(4 * (size_t)frames, sizeof *t);
    if (st == RS_OK && !t) st = rs_err_set(&err, RS_ERR_NOMEM, "out of memory");
    for (int k = -1; st == RS_OK && k < frames; k++) {
        rs_detect_box *boxes = NULL;
        int Nboxes;
        rs_detect_timing tm;
        const rs_detect_frame frame = {bgr, w, h};
        st = rs_detect_net_run(net, &boxes, &Nboxes, &tm, &frame, &err);
        free(boxes);
        if (k < 0 || st) continue; // the warm-up is not timed
        t[k] = tm.preprocess_ms;
        t[frames + k] = tm.forward_ms;
        t[2 * frames + k] = tm.decode_ms;
        t[3 * frames + k] = tm.preprocess_ms + tm.forward_ms + tm.decode_ms;
    }
    rs_detect_net_free(net);
    if (st == RS_OK) {
        row->pre_ms = rs_stats_median(t, frames);
        row->fwd_ms = rs_stats_median(t + frames, frames);
        row->dec_ms = rs_stats_median(t + 2 * frames, frames);
        row->total_ms = rs_stats_median(t + 3 * frames, frames);
    }
    free(t);
    rs_detect_set_threads(-1);
    if (st) rs_cli_fail("bench detect", st, &err);
    return st == RS_OK;
}

static int write_csv(const char *path, const bench_row *rows, int N)
{
    rs_err err = {0};
    rs_io_atomic a;
    rs_status st = rs_io_atomic_open(&a, path, &err);
    if (st) return rs_cli_fail("bench detect", st, &err);
    fprintf(a.f, "net_w,net_h,threads,preprocess_ms,forward_ms,decode_ms,total_ms\n");
    for (int i = 0; i < N; i++)
        fprintf(a.f, "%d,%d,%s,%.4f,%.4f,%.4f,%.4f\n", rows[i].net_w, rows[i].net_h,
                rows[i].threads == 1 ? "1" : "default", rows[i].pre_ms, rows[i].fwd_ms, rows[i].dec_ms,
                rows[i].total_ms);
    st = rs_io_atomic_commit(&a, &err);
    return st ? rs_cli_fail("bench detect", st, &err) : RS_EXIT_OK;
}

int rs_cli_bench_detect(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(bench_detect_usage, stdout);
        return RS_EXIT_OK;
    }
    enum { O_MODEL = 3300, O_FAMILY, O_SIZES, O_FRAMES, O_FRAME, O_CSV };
    static const struct option options[] = {{"model", required_argument, NULL, O_MODEL},
                                            {"family", required_argument, NULL, O_FAMILY},
                                            {"sizes", required_argument, NULL, O_SIZES},
                                            {"frames", required_argument, NULL, O_FRAMES},
                                            {"frame", required_argument, NULL, O_FRAME},
                                            {"csv", required_argument, NULL, O_CSV},
                                            {NULL, 0, NULL, 0}};
    const char *model = NULL, *csv = NULL;
    rs_detect_family family = RS_DETECT_AUTO;
    int sizes[2 * MAX_SIZES] = {640, 640}, Nsizes = 1, frames = 20, fw = 1920, fh = 1080;
    opterr = 0;
    optind = 0;
    int c;
    long n;
    double a, b;
    while ((c = getopt_long(argc, argv, ":", options, NULL)) != -1) {
        switch (c) {
        case O_MODEL: model = optarg; break;
        case O_CSV: csv = optarg; break;
        case O_FAMILY:
            if (!rs_cli_detect_parse_family(optarg, &family))
                return rs_cli_usage_error("bench detect", "--family: '%s' is not yolox, ultralytics or auto", optarg);
            break;
        case O_SIZES: {
            char buf[512];
            if (strlen(optarg) >= sizeof buf) return rs_cli_usage_error("bench detect", "--sizes: too long");
            strcpy(buf, optarg);
            Nsizes = 0;
            char *save = NULL;
            for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
                if (Nsizes == MAX_SIZES || !rs_cli_detect_parse_size(tok, &sizes[2 * Nsizes], &sizes[2 * Nsizes + 1]))
                    return rs_cli_usage_error(
                        "bench detect", "--sizes: '%s' is not a list of up to %d sizes N or WxH (multiples of 32)",
                        optarg, MAX_SIZES);
                Nsizes++;
            }
            if (!Nsizes) return rs_cli_usage_error("bench detect", "--sizes: empty");
            break;
        }
        case O_FRAMES:
            if (!rs_cli_parse_int(optarg, 1, 100000, &n))
                return rs_cli_usage_error("bench detect", "--frames: '%s' is not a whole number in [1, 1e5]", optarg);
            frames = (int)n;
            break;
        case O_FRAME:
            if (!rs_cli_parse_pair(optarg, 'x', &a, &b) || a < 1 || b < 1 || a > 8192 || b > 8192 || a != (int)a ||
                b != (int)b)
                return rs_cli_usage_error("bench detect", "--frame: '%s' is not WxH in [1, 8192]", optarg);
            fw = (int)a;
            fh = (int)b;
            break;
        case ':': return rs_cli_usage_error("bench detect", "%s needs a value", argv[optind - 1]);
        default: return rs_cli_usage_error("bench detect", "unknown option '%s'", argv[optind - 1]);
        }
    }
    if (!model) return rs_cli_usage_error("bench detect", "--model is required");
    if (optind != argc) return rs_cli_usage_error("bench detect", "unexpected argument '%s'", argv[optind]);

    unsigned char *bgr = malloc((size_t)fw * fh * 3);
    bench_row rows[2 * MAX_SIZES];
    if (!bgr) return rs_cli_fail("bench detect", RS_ERR_NOMEM, NULL);
    for (int y = 0; y < fh; y++)
        for (int x = 0; x < fw; x++) {
            unsigned char *p = bgr + 3 * ((size_t)y * fw + x);
            p[0] = (unsigned char)(255 * x / fw);
            p[1] = (unsigned char)(255 * y / fh);
            p[2] = (unsigned char)((x + y) & 255);
        }
    printf("model %s, frame %dx%d, median over %d frames (ms)\n", model, fw, fh, frames);
    printf("%-10s %-8s %11s %9s %9s %9s\n", "input", "threads", "preprocess", "forward", "decode", "total");
    int Nrows = 0, rc = RS_EXIT_OK;
    for (int s = 0; s < Nsizes && rc == RS_EXIT_OK; s++)
        for (int th = 0; th < 2 && rc == RS_EXIT_OK; th++) {
            bench_row *r = &rows[Nrows];
            *r = (bench_row){.net_w = sizes[2 * s], .net_h = sizes[2 * s + 1], .threads = th == 0 ? 1 : -1};
            if (!time_one(r, model, family, bgr, fw, fh, frames)) {
                rc = RS_EXIT_FAIL;
                break;
            }
            char in[32];
            snprintf(in, sizeof in, "%dx%d", r->net_w, r->net_h);
            printf("%-10s %-8s %11.3f %9.3f %9.3f %9.3f\n", in, th == 0 ? "1" : "default", r->pre_ms, r->fwd_ms,
                   r->dec_ms, r->total_ms);
            Nrows++;
        }
    free(bgr);
    if (rc == RS_EXIT_OK && csv) rc = write_csv(csv, rows, Nrows);
    return rc;
}
