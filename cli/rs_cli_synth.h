// rs_cli_synth.h -- what `roadside scene` and `roadside render` share: their common options and
// loading the site, the calibrated camera, the vehicles, the sun and the pins
// (implemented in cmd_scene.c).
#pragma once
#include <stdbool.h>

#include "core/rs_camera.h"
#include "geo/rs_site.h"
#include "synth/backdrop/rs_synth_sun.h"
#include "synth/povray/rs_synth_scene.h"
#include "synth/traffic/rs_synth_vehicles.h"

typedef struct {
    // options
    const char *site_dir, *calib_dir, *camera_id, *vehicles_path, *output;
    bool pins;
    bool has_sun;
    double sun_az_deg, sun_el_deg;
    const char *time_iso;
    // loaded
    rs_site *site;
    rs_camera camera;
    rs_synth_vehicle_list list;
    rs_synth_prepared prepared;
    double *pins_enu_m; // (Npins,3) owned
    int Npins;
    rs_synth_scene_options scene; // sun and pins filled in
} rs_cli_synth_args;

// Handles option `opt` (a getopt_long value of the shared table below) with argument `arg`.
// Returns 0 when handled, RS_EXIT_USAGE after printing a usage error, -1 when not shared.
int rs_cli_synth_option(rs_cli_synth_args *s, const char *command, int opt, const char *arg);

// getopt_long values of the shared options.
enum {
    RS_CLI_SYNTH_CALIB = 1000,
    RS_CLI_SYNTH_CAMERA,
    RS_CLI_SYNTH_VEHICLES,
    RS_CLI_SYNTH_PINS,
    RS_CLI_SYNTH_SUN,
    RS_CLI_SYNTH_TIME
};
#define RS_CLI_SYNTH_LONGOPTS                                                                                         \
    {"calib", required_argument, NULL, RS_CLI_SYNTH_CALIB}, {"camera", required_argument, NULL, RS_CLI_SYNTH_CAMERA}, \
        {"vehicles", required_argument, NULL, RS_CLI_SYNTH_VEHICLES}, {"pins", no_argument, NULL, RS_CLI_SYNTH_PINS}, \
        {"sun", required_argument, NULL, RS_CLI_SYNTH_SUN}, {"time", required_argument, NULL, RS_CLI_SYNTH_TIME},     \
        {"output", required_argument, NULL, 'o'},                                                                     \
    {                                                                                                                 \
        "help", no_argument, NULL, 'h'                                                                                \
    }

// Takes the one positional argument (SITE) left after option parsing (argv[optind..]), checks
// the required options, then loads everything. Returns an exit code (RS_EXIT_OK on success;
// messages printed; on failure *s is freed).
int rs_cli_synth_load(rs_cli_synth_args *s, const char *command, int argc, char **argv, int optind);
void rs_cli_synth_free(rs_cli_synth_args *s); // NULL-safe

// Prints "COMMAND: note: povray runs unconfined: WHY ..." on stderr when Linux Landlock cannot
// confine povray here (synth/povray/rs_synth_sandbox.h); nothing otherwise. Implemented in
// cmd_render.c; used by `roadside render` and `roadside synth`.
void rs_cli_synth_sandbox_note(const char *command);
