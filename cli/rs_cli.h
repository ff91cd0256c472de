// rs_cli.h -- the roadside command line: one function per subcommand, and the few helpers they
// share. The cli only parses arguments, calls the libraries and prints; it owns exit codes.
#pragma once
#include <stdbool.h>
#include <stdio.h>

#include "calib/rs_calib_site.h"
#include "core/rs_status.h"
#include "geo/rs_geo.h"
#include "geo/rs_site.h"

// Exit codes: 0 success, 1 the work failed (bad input, a check failed), 2 usage error.
enum { RS_EXIT_OK = 0, RS_EXIT_FAIL = 1, RS_EXIT_USAGE = 2 };

// Each subcommand gets argv with argv[0] = its own name ("geo", "site", ...).
int rs_cli_geo(int argc, char **argv);
int rs_cli_site(int argc, char **argv);
int rs_cli_calib(int argc, char **argv);
int rs_cli_locate(int argc, char **argv);
int rs_cli_audit(int argc, char **argv);
int rs_cli_report(int argc, char **argv);
int rs_cli_export(int argc, char **argv);
int rs_cli_scene(int argc, char **argv);
int rs_cli_render(int argc, char **argv);
int rs_cli_background(int argc, char **argv);
// `roadside site render-backgrounds`, living with `roadside background` in cmd_background.c
int rs_cli_site_render_backgrounds(int argc, char **argv);
int rs_cli_traffic(int argc, char **argv);
int rs_cli_synth(int argc, char **argv);
int rs_cli_eval(int argc, char **argv);
int rs_cli_localise(int argc, char **argv);
int rs_cli_track(int argc, char **argv);
int rs_cli_bench(int argc, char **argv);
int rs_cli_ortho(int argc, char **argv);
int rs_cli_pick(int argc, char **argv);
int rs_cli_dataset(int argc, char **argv);
// Sub-subcommands living in their own files: `roadside site simulate`, `roadside site import`,
// `roadside bench calib`.
int rs_cli_site_simulate(int argc, char **argv);
int rs_cli_site_import(int argc, char **argv);
int rs_cli_bench_calib(int argc, char **argv);
int rs_cli_bench_synth(int argc, char **argv);
int rs_cli_bench_site(int argc, char **argv);
int rs_cli_bench_pick(int argc, char **argv);
int rs_cli_bench_sparse(int argc, char **argv);
int rs_cli_bench_track(int argc, char **argv);
// `roadside eval --tracks` (tracking metrics), in cmd_eval_tracks.c; rs_cli_eval hands over to it.
int rs_cli_eval_tracks(int argc, char **argv);

// Prints "roadside: <what>: <detail or strerror>" on stderr and returns RS_EXIT_FAIL
// (RS_EXIT_USAGE for RS_ERR_USAGE).
int rs_cli_fail(const char *what, rs_status st, const rs_err *err);

// Prints "roadside COMMAND: message" and "Try 'roadside COMMAND --help'." on stderr; returns
// RS_EXIT_USAGE.
int rs_cli_usage_error(const char *command, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

// Loads the site folder `dir` for `command`. On failure prints "roadside COMMAND: <the first
// problem>" and the hint to run 'roadside site check' (which lists them all), and returns NULL.
// The caller frees the site with rs_site_free.
rs_site *rs_cli_load_site(const char *command, const char *dir);

// Checks that every id names a camera of the site; prints a usage error for the first that does
// not and returns RS_EXIT_USAGE, else RS_EXIT_OK.
int rs_cli_check_cameras(const char *command, const rs_site *site, const char *const *ids, int N);

// Loads SITE for `command` (calib, audit). When it cannot be read, prints why (and the hint to
// run `site check`), removes what an earlier run of that command wrote for this site folder into
// out_dir (rs_calib_site_run_abandon; `what` names those files in the message) and returns NULL.
rs_site *rs_cli_load_site_or_abandon(const char *command, const char *what, const char *site_dir, const char *out_dir,
                                     const rs_calib_site_outputs *outputs, const char *const *only, int Nonly);

// True if argv holds -h or --help before any "--".
bool rs_cli_wants_help(int argc, char **argv);

// Parses "LAT,LON,H" (degrees, degrees, metres). False on any malformed or non-finite part, or a
// latitude outside [-90, 90].
bool rs_cli_parse_llh(const char *s, rs_llh *out);

// Parses a finite double / an int in [lo, hi]; false if s is not entirely a number.
bool rs_cli_parse_double(const char *s, double *out);
bool rs_cli_parse_int(const char *s, long lo, long hi, long *out);

// Parses "A<sep>B" (1920x1080, 0.05,0.08) into two finite numbers; false when malformed.
bool rs_cli_parse_pair(const char *s, char sep, double *a, double *b);

// A comma-separated list of up to max integers in [lo, hi] (the benches' --landmarks N[,N...]):
// out (max,) and *n. False (out, *n undefined) when malformed, empty or too long.
bool rs_cli_parse_int_list(const char *s, long lo, long hi, int *out, int max, int *n);

// A fresh scratch folder under $TMPDIR (else /tmp) named roadside-<what>-XXXXXX, created in
// tmpl (4096 bytes). Returns tmpl, or NULL (with a message on stderr naming `what`).
char *rs_cli_scratch_dir(char tmpl[4096], const char *what);
