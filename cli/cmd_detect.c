// roadside detect -- run an ONNX detector (YOLOX or Ultralytics) over images, folders, videos or
// streams of one calibrated camera, writing a COCO results list (eval/detect/rs_detect.h).
#include <getopt.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"
#include "cli/rs_cli_detect.h"
#include "core/rs_camera.h"
#include "eval/detect/rs_detect.h"

static void usage(FILE *out)
{
    fprintf(out, "usage: roadside detect SITE --calib DIR --camera ID --model MODEL.onnx -o DETS.json\n"
                 "                       [--family yolox|ultralytics|auto] [--size N | --size WxH]\n"
                 "                       [--conf C] [--nms-iou T] [--max-dets N] [--fps F] [--every K]\n"
                 "                       INPUT...\n"
                 "\n"
                 "Runs an ONNX object detector through OpenCV's DNN module (CPU) on the frames of one\n"
                 "camera and writes its detections as a COCO results list, the input of 'roadside\n"
                 "localise' and 'roadside eval'. Pre- and post-processing follow each family's own\n"
                 "inference code (docs/detect.md).\n"
                 "\n"
                 "  SITE               the site folder (the camera must be one of its cameras)\n"
                 "  --calib DIR        DIR/<ID>.cameramodel ('roadside calib'): every frame must have\n"
                 "                     its image size (a resized frame would misplace every point)\n"
                 "  --camera ID        the camera the inputs come from (written as \"camera\")\n"
                 "  --model MODEL.onnx the detector, exported to ONNX\n"
                 "  --family F         yolox: raw output (1, N, 5+C), letterbox top-left, BGR 0..255;\n"
                 "                     ultralytics: output (1, 4+C, N), letterbox centred, RGB /255;\n"
                 "                     auto (default): told apart by the output's shape\n"
                 "  --size N | WxH     the network's input, multiples of 32 (default 640)\n"
                 "  --conf C           keep scores > C (default: YOLOX 0.1, Ultralytics 0.25)\n"
                 "  --nms-iou T        NMS IoU threshold (default: YOLOX 0.45 class-agnostic,\n"
                 "                     Ultralytics 0.7 per class)\n"
                 "  --max-dets N       at most N per frame, best first (default: YOLOX all,\n"
                 "                     Ultralytics 300)\n"
                 "  --fps F            frame rate of image inputs (and of videos that do not say):\n"
                 "                     time_s = frame / F; without it images have no time_s\n"
                 "  --every K          detect in every K-th frame of each input (default 1)\n"
                 "  -o DETS.json       the output, written atomically\n"
                 "  INPUT              image files (consecutive ones are one sequence: frames 0, 1, ...\n"
                 "                     in the order given), folders (their images in name order:\n"
                 "                     frames 0, 1, ...), video files, stream URLs (rtsp://, http://,\n"
                 "                     file://)\n"
                 "\n"
                 "Each detection: image_id (1-based over the frames detected in), category_id (class\n"
                 "+ 1), bbox [x, y, w, h] in the frame's pixels, score, camera, frame (0-based within\n"
                 "its input), time_s, file_name. Prints frames, detections and ms per frame.\n"
                 "Exit status: 0 ok, 1 bad input (the message names the file), 2 usage error.\n");
}

int rs_cli_detect_parse_size(const char *s, int *w, int *h)
{
    double a, b;
    if (rs_cli_parse_pair(s, 'x', &a, &b)) {
        *w = (int)a;
        *h = (int)b;
        if (a != *w || b != *h) return 0;
    } else {
        long n;
        if (!rs_cli_parse_int(s, 32, 8192, &n)) return 0;
        *w = *h = (int)n;
    }
    return *w >= 32 && *h >= 32 && *w <= 8192 && *h <= 8192 && *w % 32 == 0 && *h % 32 == 0;
}

int rs_cli_detect_parse_family(const char *s, rs_detect_family *f)
{
    if (!strcmp(s, "yolox"))
        *f = RS_DETECT_YOLOX;
    else if (!strcmp(s, "ultralytics"))
        *f = RS_DETECT_ULTRALYTICS;
    else if (!strcmp(s, "auto"))
        *f = RS_DETECT_AUTO;
    else
        return 0;
    return 1;
}

typedef struct {
    const char *site, *calib, *camera, *model, *out;
    rs_detect_options opt;
    double fps;
    int every;
    const char *const *inputs;
    int Ninputs;
} detect_args;

static int parse_args(int argc, char **argv, detect_args *a)
{
    *a = (detect_args){.opt = {.width_px = 640, .height_px = 640, .conf = -1, .nms_iou = -1, .max_dets = -1},
                       .every = 1};
    enum { O_CALIB = 256, O_CAMERA, O_MODEL, O_FAMILY, O_SIZE, O_CONF, O_NMS, O_MAXDETS, O_FPS, O_EVERY };
    static const struct option options[] = {
        {"calib", required_argument, NULL, O_CALIB}, {"camera", required_argument, NULL, O_CAMERA},
        {"model", required_argument, NULL, O_MODEL}, {"family", required_argument, NULL, O_FAMILY},
        {"size", required_argument, NULL, O_SIZE},   {"conf", required_argument, NULL, O_CONF},
        {"nms-iou", required_argument, NULL, O_NMS}, {"max-dets", required_argument, NULL, O_MAXDETS},
        {"fps", required_argument, NULL, O_FPS},     {"every", required_argument, NULL, O_EVERY},
        {"output", required_argument, NULL, 'o'},    {NULL, 0, NULL, 0}};
    opterr = 0;
    optind = 0; // glibc: full re-initialisation
    int c;
    long n;
    double x;
    while ((c = getopt_long(argc, argv, ":o:", options, NULL)) != -1) {
        switch (c) {
        case O_CALIB: a->calib = optarg; break;
        case O_CAMERA: a->camera = optarg; break;
        case O_MODEL: a->model = optarg; break;
        case 'o': a->out = optarg; break;
        case O_FAMILY:
            if (!rs_cli_detect_parse_family(optarg, &a->opt.family))
                return rs_cli_usage_error("detect", "--family: '%s' is not yolox, ultralytics or auto", optarg);
            break;
        case O_SIZE:
            if (!rs_cli_detect_parse_size(optarg, &a->opt.width_px, &a->opt.height_px))
                return rs_cli_usage_error("detect", "--size: '%s' is not N or WxH, multiples of 32 in [32, 8192]",
                                          optarg);
            break;
        case O_CONF:
            if (!rs_cli_parse_double(optarg, &x) || x < 0 || x >= 1)
                return rs_cli_usage_error("detect", "--conf: '%s' is not a number in [0, 1)", optarg);
            a->opt.conf = x;
            break;
        case O_NMS:
            if (!rs_cli_parse_double(optarg, &x) || x <= 0 || x > 1)
                return rs_cli_usage_error("detect", "--nms-iou: '%s' is not a number in (0, 1]", optarg);
            a->opt.nms_iou = x;
            break;
        case O_MAXDETS:
            if (!rs_cli_parse_int(optarg, 1, 1000000, &n))
                return rs_cli_usage_error("detect", "--max-dets: '%s' is not a whole number in [1, 1e6]", optarg);
            a->opt.max_dets = (int)n;
            break;
        case O_FPS:
            if (!rs_cli_parse_double(optarg, &x) || !(x > 0) || x > 1e6)
                return rs_cli_usage_error("detect", "--fps: '%s' is not a number in (0, 1e6]", optarg);
            a->fps = x;
            break;
        case O_EVERY:
            if (!rs_cli_parse_int(optarg, 1, 1000000, &n))
                return rs_cli_usage_error("detect", "--every: '%s' is not a whole number in [1, 1e6]", optarg);
            a->every = (int)n;
            break;
        case ':': return rs_cli_usage_error("detect", "%s needs a value", argv[optind - 1]);
        default: return rs_cli_usage_error("detect", "unknown option '%s'", argv[optind - 1]);
        }
    }
    if (argc - optind < 2) return rs_cli_usage_error("detect", "expected SITE and at least one INPUT");
    if (!a->calib || !a->camera || !a->model || !a->out)
        return rs_cli_usage_error("detect", "--calib, --camera, --model and -o are required");
    a->site = argv[optind];
    a->inputs = (const char *const *)argv + optind + 1;
    a->Ninputs = argc - optind - 1;
    return RS_EXIT_OK;
}

int rs_cli_detect(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        usage(stdout);
        return RS_EXIT_OK;
    }
    detect_args a;
    int rc = parse_args(argc, argv, &a);
    if (rc) return rc;
    rs_site *site = rs_cli_load_site("detect", a.site);
    if (!site) return RS_EXIT_FAIL;
    rc = rs_cli_check_cameras("detect", site, &a.camera, 1);
    rs_site_free(site);
    if (rc) return rc;

    rs_err err = {0};
    rs_camera cam = {0};
    char path[4096];
    rs_status st = rs_camera_path(path, sizeof path, a.calib, a.camera, RS_CAMERA_EXT_CAMERAMODEL)
                       ? rs_camera_read(&cam, NULL, path, &err)
                       : rs_err_set(&err, RS_ERR_INVALID, "%s: path too long", a.calib);
    if (st) return rs_cli_fail("detect", st, &err);
    const rs_detect_run_options ro = {
        .camera_id = a.camera, .camera_width = cam.width, .camera_height = cam.height, .fps = a.fps, .every = a.every};
    rs_camera_free(&cam);

    rs_detect_net *net = NULL;
    st = rs_detect_net_open(&net, a.model, &a.opt, &err);
    if (st) return rs_cli_fail("detect", st, &err);
    rs_detect_summary sum;
    st = rs_detect_run(&sum, net, a.inputs, a.Ninputs, &ro, a.out, &err);
    const rs_detect_layout layout = *rs_detect_net_layout(net);
    rs_detect_net_free(net);
    if (st) return rs_cli_fail("detect", st, &err);

    const double nf = sum.Nframes ? (double)sum.Nframes : 1.0;
    printf("model %s: %s, %d classes, input %dx%d\n", a.model, rs_detect_family_name(layout.family), layout.Nclasses,
           a.opt.width_px, a.opt.height_px);
    printf("%ld frames, %ld detections -> %s\n", sum.Nframes, sum.Ndetections, a.out);
    printf("%.2f ms per frame (preprocess %.2f, forward %.2f, decode %.2f)\n",
           (sum.total.preprocess_ms + sum.total.forward_ms + sum.total.decode_ms) / nf, sum.total.preprocess_ms / nf,
           sum.total.forward_ms / nf, sum.total.decode_ms / nf);
    return RS_EXIT_OK;
}
