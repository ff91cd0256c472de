// roadside scene: parse arguments, write a POV-Ray scene (.pov + .ini) through synth/, print.
// Also the loading shared with roadside render (rs_cli_synth.h).
#include <getopt.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"
#include "cli/rs_cli_synth.h"
#include "core/rs_io.h"
#include "synth/povray/rs_synth_camera.h"

static const char scene_usage[] =
    "usage: roadside scene SITE --calib DIR --camera ID --vehicles FILE -o OUT.pov\n"
    "                      [--pins] [--sun AZ,EL | --time ISO8601]\n"
    "\n"
    "Writes a self-contained POV-Ray 3.7 scene of vehicles seen by a calibrated camera, and the\n"
    "matching OUT.ini (the camera's exact image size, no antialiasing, 16-bit linear PNG with\n"
    "alpha). Render it with 'povray OUT.ini' from OUT's folder, or use 'roadside render'.\n"
    "The camera is exact for the pinhole core of DIR/ID.cameramodel (docs/povray.md); a lens\n"
    "with distortion is rendered through a pinhole canvas by 'roadside render' only.\n"
    "\n"
    "Options:\n"
    "  --calib DIR        folder with ID.cameramodel (as written by 'roadside calib')\n"
    "  --camera ID        the camera\n"
    "  --vehicles FILE    JSON list of {class|model, e, n, yaw_deg, [length, width, height,\n"
    "                     colour, variant, id]} (docs/povray.md); yaw_deg is the compass\n"
    "                     heading of the vehicle's front, clockwise from north\n"
    "  -o, --output FILE  the .pov to write (its name: [A-Za-z0-9_.-]); the .ini goes next to it\n"
    "  --pins             white spheres (3 px radius) at the site's landmarks\n"
    "  --sun AZ,EL        sun azimuth (clockwise from north) and elevation, degrees\n"
    "                     (default 135,45)\n"
    "  --time ISO8601     sun position at the site at this time, e.g. 2024-06-21T14:00:00Z\n"
    "  -h, --help         this text\n"
    "\n"
    "Exit status: 0 written, 1 failed (nothing written), 2 usage error.\n";

int rs_cli_synth_option(rs_cli_synth_args *s, const char *command, int opt, const char *arg)
{
    switch (opt) {
    case RS_CLI_SYNTH_CALIB: s->calib_dir = arg; return 0;
    case RS_CLI_SYNTH_CAMERA: s->camera_id = arg; return 0;
    case RS_CLI_SYNTH_VEHICLES: s->vehicles_path = arg; return 0;
    case RS_CLI_SYNTH_PINS: s->pins = true; return 0;
    case 'o': s->output = arg; return 0;
    case RS_CLI_SYNTH_TIME: s->time_iso = arg; return 0;
    case RS_CLI_SYNTH_SUN: {
        char *comma = strchr(arg, ',');
        char buf[64];
        if (!comma || strlen(arg) >= sizeof(buf))
            return rs_cli_usage_error(command, "--sun: expected AZ,EL in degrees");
        strcpy(buf, arg);
        buf[comma - arg] = 0;
        if (!rs_cli_parse_double(buf, &s->sun_az_deg) ||
            !rs_cli_parse_double(buf + (comma - arg) + 1, &s->sun_el_deg) || s->sun_el_deg < -90 || s->sun_el_deg > 90)
            return rs_cli_usage_error(command, "--sun: expected AZ,EL in degrees, EL in [-90, 90]");
        s->has_sun = true;
        return 0;
    }
    default: return -1;
    }
}

void rs_cli_synth_free(rs_cli_synth_args *s)
{
    if (!s) return;
    rs_synth_prepared_free(&s->prepared);
    rs_synth_vehicle_list_free(&s->list);
    rs_camera_free(&s->camera);
    rs_site_free(s->site);
    free(s->pins_enu_m);
    s->site = NULL;
    s->pins_enu_m = NULL;
}

static int synth_load(rs_cli_synth_args *s, const char *command)
{
    if (!s->calib_dir || !s->camera_id || !s->vehicles_path || !s->output)
        return rs_cli_usage_error(command, "--calib, --camera, --vehicles and -o are required");
    if (s->has_sun && s->time_iso) return rs_cli_usage_error(command, "give --sun or --time, not both");
    rs_err err = {0};
    rs_status st;
    double t_s = 0;
    if (s->time_iso && (st = rs_synth_parse_iso8601(&t_s, s->time_iso, "--time", &err)))
        return rs_cli_usage_error(command, "%s", err.msg);
    if ((st = rs_site_load(&s->site, s->site_dir, &err))) return rs_cli_fail(command, st, &err);
    if (rs_site_find_camera(s->site, s->camera_id) < 0)
        return rs_cli_usage_error(command, "--camera: no camera \"%s\" in %s", s->camera_id, s->site_dir);
    char model[4096];
    if (!rs_camera_path(model, sizeof model, s->calib_dir, s->camera_id, RS_CAMERA_EXT_CAMERAMODEL))
        return rs_cli_usage_error(command, "--calib: path too long");
    st = rs_camera_read(&s->camera, NULL, model, &err);
    if (st) return rs_cli_fail(command, st, &err);
    if ((st = rs_synth_vehicles_read(&s->list, s->vehicles_path, &err))) return rs_cli_fail(command, st, &err);
    if ((st = rs_synth_prepare(&s->prepared, s->list.v, s->list.obj, s->list.N, &err)))
        return rs_cli_fail(command, st, &err);
    rs_synth_scene_options_default(&s->scene);
    if (s->has_sun) {
        s->scene.sun_azimuth_deg = s->sun_az_deg;
        s->scene.sun_elevation_deg = s->sun_el_deg;
    } else if (s->time_iso) {
        rs_synth_sun_position(&s->scene.sun_azimuth_deg, &s->scene.sun_elevation_deg, s->site->origin.lat_deg,
                              s->site->origin.lon_deg, t_s);
    }
    if (s->pins && s->site->Nlandmarks > 0) {
        s->pins_enu_m = malloc(sizeof(double) * 3 * (size_t)s->site->Nlandmarks);
        if (!s->pins_enu_m) return rs_cli_fail("out of memory", RS_ERR_NOMEM, NULL);
        for (int i = 0; i < s->site->Nlandmarks; i++)
            memcpy(&s->pins_enu_m[3 * i], s->site->landmarks[i].p_enu_m, 3 * sizeof(double));
        s->Npins = s->site->Nlandmarks;
        s->scene.pins_enu_m = s->pins_enu_m;
        s->scene.Npins = s->Npins;
    }
    return RS_EXIT_OK;
}

int rs_cli_synth_load(rs_cli_synth_args *s, const char *command, int argc, char **argv, int optind)
{
    if (optind + 1 != argc) return rs_cli_usage_error(command, "expected one SITE folder");
    s->site_dir = argv[optind];
    const int rc = synth_load(s, command);
    if (rc != RS_EXIT_OK) rs_cli_synth_free(s);
    return rc;
}

int rs_cli_scene(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(scene_usage, stdout);
        return RS_EXIT_OK;
    }
    static const struct option longopts[] = {RS_CLI_SYNTH_LONGOPTS, {NULL, 0, NULL, 0}};
    rs_cli_synth_args s = {0};
    int c, rc;
    optind = 1;
    opterr = 0;
    while ((c = getopt_long(argc, argv, "o:h", longopts, NULL)) != -1) {
        if (c == '?' || c == ':')
            return rs_cli_usage_error("scene", "unknown option or missing value: %s", argv[optind - 1]);
        if ((rc = rs_cli_synth_option(&s, "scene", c, optarg)) != 0)
            return rc > 0 ? rc : rs_cli_usage_error("scene", "unexpected option");
    }
    if ((rc = rs_cli_synth_load(&s, "scene", argc, argv, optind)) != RS_EXIT_OK) return rc;
    rs_err err = {0};
    rs_synth_povcam cam;
    rs_status st = RS_OK;
    char *ini = NULL;
    rs_io_atomic a = {0};
    if (s.camera.lensmodel.type != MRCAL_LENSMODEL_PINHOLE)
        fprintf(stderr, "roadside scene: note: the lens has distortion; the scene renders its "
                        "pinhole core (use 'roadside render' for the full lens)\n");
    const size_t len = strlen(s.output);
    if (len < 5 || strcmp(s.output + len - 4, ".pov") != 0) {
        rs_cli_synth_free(&s);
        return rs_cli_usage_error("scene", "-o: the output must end in .pov");
    }
    ini = strdup(s.output);
    if (!ini) {
        st = rs_err_set(&err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    strcpy(ini + len - 4, ".ini");
    if ((st = rs_synth_povcam_init(&cam, s.camera.intrinsics, s.camera.width, s.camera.height, s.camera.rt_cam_enu,
                                   &err)) ||
        (st = rs_io_atomic_open(&a, s.output, &err)))
        goto done;
    if ((st = rs_synth_scene_write(a.f, &cam, s.camera.intrinsics, s.site->ground_normal_enu, s.site->ground_offset_m,
                                   &s.prepared, &s.scene, &err))) {
        rs_io_atomic_abort(&a);
        goto done;
    }
    if ((st = rs_synth_scene_write_ini(ini, s.output, &cam, RS_SYNTH_PASS_COLOUR, 0, &err))) {
        rs_io_atomic_abort(&a);
        goto done;
    }
    if ((st = rs_io_atomic_commit(&a, &err))) {
        remove(ini);
        goto done;
    }
    printf("wrote %s and %s: %d vehicles, %d pins, %dx%d, sun azimuth %.2f elevation %.2f deg\n", s.output, ini,
           s.prepared.N, s.Npins, cam.width, cam.height, s.scene.sun_azimuth_deg, s.scene.sun_elevation_deg);
done:
    rc = st ? rs_cli_fail(s.output, st, &err) : RS_EXIT_OK;
    free(ini);
    rs_cli_synth_free(&s);
    return rc;
}
