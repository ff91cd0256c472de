// roadside -- git-style dispatcher: `roadside COMMAND [ARGS...]`.
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli/rs_cli.h"
#include "cli/rs_cli_detect.h"
#include "core/rs_io.h"
#include "geo/rs_geo_raster.h"

#ifndef RS_VERSION
#define RS_VERSION "unknown"
#endif

typedef struct {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *summary;
} command;

static const command commands[] = {
    {"site", rs_cli_site, "check, describe, initialise or simulate a site survey"},
    {"geo", rs_cli_geo, "convert coordinates: geodetic, UTM/UPS, site ENU"},
    {"calib", rs_cli_calib, "calibrate a site's cameras from its landmarks"},
    {"locate", rs_cli_locate, "map pixels to ground points through a calibrated camera"},
    {"audit", rs_cli_audit, "audit calibrations: cross-validation, outliers, coverage, uncertainty"},
    {"report", rs_cli_report, "a per-intersection calibration report (HTML and PDF)"},
    {"ortho", rs_cli_ortho, "an orthophoto of the site's digital twin as a GeoTIFF (POV-Ray, GDAL)"},
    {"pick", rs_cli_pick, "survey onboarding in the browser: pick landmarks, solved live"},
    {"export", rs_cli_export, "cameras, footprints, landmarks, lanes for GIS (GeoPackage, GeoJSON, GeoTIFF)"},
    {"scene", rs_cli_scene, "write a POV-Ray scene of vehicles seen by a calibrated camera"},
    {"render", rs_cli_render, "render a scene with POV-Ray and write its labels"},
    {"background", rs_cli_background, "background images of a camera: temporal median of video or frames"},
    {"traffic", rs_cli_traffic, "vehicle placements for a site: built-in lanes or SUMO"},
    {"synth", rs_cli_synth, "synthesise a labelled dataset: sharded, resumable, deterministic"},
    {"dataset", rs_cli_dataset, "what a synthetic dataset holds: splits, conditions, near-junction share"},
    {"detect", rs_cli_detect, "run an ONNX detector (YOLOX, Ultralytics) over images, videos or streams"},
    {"eval", rs_cli_eval, "distance-threshold AP of detections against ground truth"},
    {"localise", rs_cli_localise, "every detection to the road (ENU, lat/lon) with its covariance"},
    {"track", rs_cli_track, "track vehicles in metres over all the site's cameras (Kalman, Hungarian)"},
    {"bench", rs_cli_bench, "benchmarks: run time against error"},
};
static const int Ncommands = (int)(sizeof commands / sizeof commands[0]);

static void usage(FILE *out)
{
    fprintf(out, "usage: roadside [--version] [--help] COMMAND [ARGS...]\n"
                 "\n"
                 "Turns fixed roadside traffic cameras into calibrated, metric sensors.\n"
                 "\n"
                 "Commands:\n");
    for (int i = 0; i < Ncommands; i++) fprintf(out, "  %-8s %s\n", commands[i].name, commands[i].summary);
    fprintf(out, "\n"
                 "'roadside COMMAND --help' describes one command. Conventions: docs/conventions.md.\n");
}

// Where standard output began, when it is a regular file (`> FILE`, `>> FILE`): -1 otherwise.
static off_t stdout_start = -1;

static void note_stdout_start(void)
{
    struct stat sb;
    if (fstat(STDOUT_FILENO, &sb) != 0 || !S_ISREG(sb.st_mode)) return;
    const int flags = fcntl(STDOUT_FILENO, F_GETFL);
    stdout_start = flags >= 0 && (flags & O_APPEND) ? sb.st_size : lseek(STDOUT_FILENO, 0, SEEK_CUR);
}

// Every command's standard output checked to the end (once, here): what is still buffered is
// flushed and stdout closed; a failure anywhere -- an earlier printf that hit a full disk, the
// flush, the close -- turns exit status 0 into 1 with "roadside: disk full writing standard
// output" (or the error's own text) on stderr, and a regular file given as stdout is cut back to
// where this run began (`> res.json` is left empty, `>> log` as it was), so that no truncated
// output looks complete. A stdout the shell closed (`>&-`) is not an error.
static int finish_stdout(int rc)
{
    errno = 0;
    const bool had_error = ferror(stdout) != 0;
    int e = fflush(stdout) != 0 ? errno : 0;
    if (!e && had_error) e = EIO;
    if (e && stdout_start >= 0) (void)!ftruncate(STDOUT_FILENO, stdout_start);
    if (fclose(stdout) != 0 && !e && errno != EBADF) e = errno;
    if (!e) return rc;
    char text[512];
    fprintf(stderr, "roadside: %s\n", rs_io_write_problem(text, sizeof text, "standard output", e));
    return rc == RS_EXIT_OK ? RS_EXIT_FAIL : rc;
}

static int run(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return RS_EXIT_USAGE;
    }
    const char *cmd = argv[1];
    opterr = 0;          // one error line per mistake: each command names a bad option itself
    rs_geo_gdal_quiet(); // GDAL's messages reach the user through rs_err, never on stderr by themselves
    if (!strcmp(cmd, "--help") || !strcmp(cmd, "-h") || !strcmp(cmd, "help")) {
        if (argc > 2 && strcmp(cmd, "help") == 0) {
            for (int i = 0; i < Ncommands; i++)
                if (!strcmp(argv[2], commands[i].name)) {
                    char help[] = "--help";
                    char *av[] = {argv[2], help, NULL};
                    return commands[i].run(2, av);
                }
        }
        usage(stdout);
        return RS_EXIT_OK;
    }
    if (!strcmp(cmd, "--version")) {
        printf("roadside %s\n", RS_VERSION);
        return RS_EXIT_OK;
    }
    for (int i = 0; i < Ncommands; i++)
        if (!strcmp(cmd, commands[i].name)) return commands[i].run(argc - 1, argv + 1);
    fprintf(stderr, "roadside: '%s' is not a roadside command. See 'roadside --help'.\n", cmd);
    return RS_EXIT_USAGE;
}

int main(int argc, char **argv)
{
    note_stdout_start();
    return finish_stdout(run(argc, argv));
}
