// roadside render: parse arguments, render through synth/ with the real POV-Ray, print.
#include <ctype.h>
#include <getopt.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/rs_cli.h"
#include "cli/rs_cli_synth.h"
#include "core/rs_io.h"
#include "synth/backdrop/rs_synth_sun.h"
#include "synth/labels/rs_synth_labels.h"
#include "synth/povray/rs_synth_render.h"
#include "synth/povray/rs_synth_sandbox.h"

static const char render_usage[] =
    "usage: roadside render SITE --calib DIR --camera ID --vehicles FILE -o OUTDIR\n"
    "                       [--background IMAGE] [--pins] [--sun AZ,EL | --time ISO8601]\n"
    "                       [--full-frame] [--antialias N] [--canvas-scale S] [--keep]\n"
    "                       [--shadows [--overcast]] [--separate-processes] [--no-match-light]\n"
    "                       [--condition TIME-SURFACE]\n"
    "                       [--no-appearance]\n"
    "                       [--labels [--split NAME] [--bbox KIND] [--min-visibility V]]\n"
    "\n"
    "Renders vehicles seen by a calibrated camera with POV-Ray 3.7 (docs/povray.md):\n"
    "vehicles that cannot appear are culled (povray is not run when none is left), only the\n"
    "image rectangle the others cover is rendered, with alpha over a transparent background,\n"
    "a distorted lens is resampled from a pinhole canvas through mrcal's projection, and the\n"
    "result is composited onto the background in linear light. An object-ID pass gives each\n"
    "vehicle's visible pixels.\n"
    "\n"
    "povray is confined by Linux Landlock (docs/povray.md, \"Confinement\"): it may read\n"
    "and run the files under /usr (and /bin, /sbin, /lib*), /etc/povray, /etc/ld.so.cache\n"
    "and its own executable, write /dev/null, and read and write OUTDIR (all of it: give it\n"
    "a folder of its own); any other file is refused, and so are TCP connections on Linux\n"
    ">= 6.7. POV-Ray's own I/O restriction (the povray.conf roadside writes) does not hold in\n"
    "POV-Ray 3.7.0.10. Without Landlock (Linux before 5.13, a container that filters it, or\n"
    "$ROADSIDE_POVRAY_SANDBOX=off) povray runs unconfined, with a note on stderr, and the\n"
    "only defence is that roadside's scenes hold no file operation and no input text.\n"
    "\n"
    "Writes into OUTDIR: image.png (8-bit sRGB composite), rgba.png (16-bit linear RGBA,\n"
    "straight alpha), ids.png (16-bit: 0 background, k+1 = vehicle k of the file).\n"
    "\n"
    "Options (SITE, --calib, --camera, --vehicles, --pins, --sun, --time: see roadside scene):\n"
    "  -o, --output DIR     output folder (created if needed)\n"
    "  --background IMAGE   photograph of the camera's size to composite onto (the ground\n"
    "                       plane is then left out of the render). The lights and the\n"
    "                       environment the vehicles reflect are matched to it, as roadside\n"
    "                       synth does (docs/fleet.md): the light level and colour from its\n"
    "                       road (SITE/lanes.geojson; without lanes in view the ground plane\n"
    "                       within 60 m, else the image's lower half; the road assumed dry),\n"
    "                       the sky and surroundings they reflect: a map of every direction\n"
    "                       made from the image's pixels (OUTDIR/rs_env.png while povray\n"
    "                       runs); the sun's direction stays the one of --sun or --time\n"
    "  --no-match-light     keep the default lights and environment over a background\n"
    "  --no-appearance      over a background, composite the vehicles clean and sharp; by\n"
    "                       default they and their shadows take the camera's look estimated\n"
    "                       from the background (docs/appearance.md): its gain, blur, noise\n"
    "                       as a function of brightness, and JPEG quality\n"
    "  --full-frame         no culling, no region: render the whole image (for comparison)\n"
    "  --antialias N        N x N supersampling of the colour pass (default off)\n"
    "  --canvas-scale S     distorted lenses: canvas pixels per pixel, >= 1 (default 1)\n"
    "  --keep               keep the scene files, povray's outputs and log in OUTDIR\n"
    "  --shadows            also the shadow pass (differential rendering, docs/synth.md):\n"
    "                       the background is shaded by the vehicles' sun and sky shadows;\n"
    "                       writes OUTDIR/shadow.png (16-bit lit fraction, 1 = open ground)\n"
    "  --overcast           no sun: the sky alone (its soft shadow under each vehicle)\n"
    "  --condition C        the background's condition (docs/conditions.md): TIME day, dusk or\n"
    "                       night, SURFACE dry, wet or snow (e.g. night-wet): lights on and\n"
    "                       their light on the road (dusk, night), street lights (night), the\n"
    "                       vehicles mirrored in a wet road, snow on them (default day-dry)\n"
    "  --separate-processes the passes' povray processes one after the other (default:\n"
    "                       all at once)\n"
    "  --labels             also write the labels of this image (docs/labels.md), computed\n"
    "                       through mrcal with visibility from the ID pass: COCO in YOLOX's\n"
    "                       layout (OUTDIR/annotations/instances_SPLIT.json, the image copied\n"
    "                       to OUTDIR/SPLIT/image.png), YOLO (OUTDIR/labels/SPLIT/image.txt)\n"
    "                       and KITTI (OUTDIR/label_2/image.txt)\n"
    "  --split NAME         COCO/YOLO split name (default train2017)\n"
    "  --bbox KIND          the box written as bbox: footprint (default), body, visible\n"
    "  --min-visibility V   drop vehicles less visible than V in [0, 1] (default 0)\n"
    "  $ROADSIDE_POVRAY     the povray executable (default: povray on PATH)\n"
    "  $ROADSIDE_POVRAY_SANDBOX=off   run povray without Landlock (a povray outside /usr\n"
    "                       that needs files of its own)\n"
    "  -h, --help           this text\n"
    "\n"
    "Prints one line: vehicles, rendered, region, seconds in povray; over a background whose\n"
    "light was matched, a second: the road pixels, the lights' factor, the light level and\n"
    "where it was read (a note on stderr when not from the lanes); over a background, the\n"
    "camera's look applied (\"look: ...\") or a note why not.\n"
    "Exit status: 0 rendered, 1 failed (a clear message if povray is missing), 2 usage error.\n";

enum {
    OPT_BACKGROUND = 2000,
    OPT_FULL,
    OPT_AA,
    OPT_SCALE,
    OPT_KEEP,
    OPT_LABELS,
    OPT_SPLIT,
    OPT_BBOX,
    OPT_MINVIS,
    OPT_CONDITION,
    OPT_SHADOWS,
    OPT_NOMATCH,
    OPT_OVERCAST,
    OPT_SEPARATE,
    OPT_NOLOOK
};

void rs_cli_synth_sandbox_note(const char *command)
{
    rs_synth_sandbox_info box;
    rs_synth_sandbox_probe(&box);
    if (box.abi == 0)
        fprintf(stderr,
                "%s: note: povray runs unconfined: %s; the scenes roadside writes hold no file operation "
                "(docs/povray.md, \"Confinement\")\n",
                command, box.why);
}

int rs_cli_render(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        fputs(render_usage, stdout);
        return RS_EXIT_OK;
    }
    static const struct option longopts[] = {RS_CLI_SYNTH_LONGOPTS,
                                             {"background", required_argument, NULL, OPT_BACKGROUND},
                                             {"full-frame", no_argument, NULL, OPT_FULL},
                                             {"antialias", required_argument, NULL, OPT_AA},
                                             {"canvas-scale", required_argument, NULL, OPT_SCALE},
                                             {"keep", no_argument, NULL, OPT_KEEP},
                                             {"shadows", no_argument, NULL, OPT_SHADOWS},
                                             {"overcast", no_argument, NULL, OPT_OVERCAST},
                                             {"separate-processes", no_argument, NULL, OPT_SEPARATE},
                                             {"labels", no_argument, NULL, OPT_LABELS},
                                             {"no-match-light", no_argument, NULL, OPT_NOMATCH},
                                             {"no-appearance", no_argument, NULL, OPT_NOLOOK},
                                             {"split", required_argument, NULL, OPT_SPLIT},
                                             {"bbox", required_argument, NULL, OPT_BBOX},
                                             {"min-visibility", required_argument, NULL, OPT_MINVIS},
                                             {"condition", required_argument, NULL, OPT_CONDITION},
                                             {NULL, 0, NULL, 0}};
    rs_cli_synth_args s = {0};
    rs_synth_render_options ropt;
    rs_synth_render_options_default(&ropt);
    int c, rc;
    long aa;
    bool labels = false, overcast = false, match_light = true, want_look = true;
    rs_synth_condition cond = {0}; // day, dry
    const char *split = "train2017";
    rs_synth_label_options lopt = {.bbox = RS_SYNTH_BBOX_FOOTPRINT, .min_visibility = 0};
    rs_err perr = {0};
    optind = 1;
    opterr = 0;
    while ((c = getopt_long(argc, argv, "o:h", longopts, NULL)) != -1) {
        switch (c) {
        case OPT_BACKGROUND: ropt.background_path = optarg; continue;
        case OPT_FULL: ropt.full_frame = true; continue;
        case OPT_KEEP: ropt.keep_files = true; continue;
        case OPT_SHADOWS: ropt.shadow = true; continue;
        case OPT_OVERCAST: overcast = true; continue;
        case OPT_NOMATCH: match_light = false; continue;
        case OPT_NOLOOK: want_look = false; continue;
        case OPT_SEPARATE: ropt.separate_processes = true; continue;
        case OPT_LABELS: labels = true; continue;
        case OPT_CONDITION:
            if (rs_synth_condition_parse(&cond, optarg, &perr))
                return rs_cli_usage_error("render", "--condition: %s", perr.msg);
            continue;
        case OPT_SPLIT:
            for (const char *p = optarg; *p; p++)
                if (!(isalnum((unsigned char)*p) || *p == '_' || *p == '-'))
                    return rs_cli_usage_error("render", "--split: use only [A-Za-z0-9_-]");
            if (!*optarg) return rs_cli_usage_error("render", "--split: empty");
            split = optarg;
            continue;
        case OPT_BBOX:
            if (rs_synth_bbox_kind_parse(&lopt.bbox, optarg, &perr))
                return rs_cli_usage_error("render", "--bbox: %s", perr.msg);
            continue;
        case OPT_MINVIS:
            if (!rs_cli_parse_double(optarg, &lopt.min_visibility) || lopt.min_visibility < 0 ||
                lopt.min_visibility > 1)
                return rs_cli_usage_error("render", "--min-visibility: expected a number in [0, 1]");
            continue;
        case OPT_AA:
            if (!rs_cli_parse_int(optarg, 0, 9, &aa) || aa == 1)
                return rs_cli_usage_error("render", "--antialias: expected 0 or 2..9");
            ropt.antialias = (int)aa;
            continue;
        case OPT_SCALE:
            if (!rs_cli_parse_double(optarg, &ropt.canvas_scale) || ropt.canvas_scale < 1 || ropt.canvas_scale > 8)
                return rs_cli_usage_error("render", "--canvas-scale: expected a number in [1, 8]");
            continue;
        case '?':
        case ':': return rs_cli_usage_error("render", "unknown option or missing value: %s", argv[optind - 1]);
        default:
            if ((rc = rs_cli_synth_option(&s, "render", c, optarg)) != 0)
                return rc > 0 ? rc : rs_cli_usage_error("render", "unexpected option");
        }
    }
    if ((rc = rs_cli_synth_load(&s, "render", argc, argv, optind)) != RS_EXIT_OK) return rc;
    rs_cli_synth_sandbox_note("render");
    ropt.scene = s.scene;
    ropt.scene.overcast = overcast;
    rs_err err = {0};
    rs_synth_render_result r = {0};
    rs_status st = RS_OK;
    rs_synth_light_estimate light;
    rs_image env_map = {0};
    bool matched = false;
    if (ropt.background_path && match_light) {
        // the background's light and environment (docs/fleet.md, "Reflections of the scene")
        rs_lanes lanes = {0};
        char *lanes_path = rs_io_join(s.site_dir, RS_SITE_LANES);
        if (!lanes_path)
            st = rs_err_set(&err, RS_ERR_NOMEM, "out of memory");
        else if (access(lanes_path, F_OK) == 0)
            st = rs_lanes_read(&lanes, lanes_path, s.site, &err);
        if (!st)
            st = rs_synth_scene_match_background_file(&ropt.scene, &light, &env_map, ropt.background_path, &s.camera,
                                                      s.site, &lanes, &err);
        if (!st) {
            matched = true;
            ropt.light_matched = true; // the look's gain is not applied on top
            ropt.env_map = &env_map;
            if (light.source != RS_SYNTH_LIGHT_FROM_LANES)
                fprintf(stderr, "render: note: background: no lane in view: light from %s (%d pixels)\n",
                        rs_synth_light_source_name(light.source), light.Nroad_px);
        }
        free(lanes_path);
        rs_lanes_free(&lanes);
    }
    if (!st) { // issue 40: the condition's lights, street lights and snow; its passes
        rs_synth_scene_apply_condition(&ropt.scene, &cond, s.site, &s.prepared);
        ropt.headlights = ropt.scene.lights_on;
        ropt.mirror = cond.surface == RS_SYNTH_SURFACE_WET && ropt.background_path;
    }
    rs_synth_appearance look;
    if (!st && ropt.background_path && want_look) {
        // the camera's look (docs/appearance.md): noise, blur, JPEG, colour cast of the background
        rs_err lerr = {0};
        if (rs_synth_appearance_estimate(&look, ropt.background_path, NULL, NULL, &lerr) == RS_OK)
            ropt.look = &look;
        else
            fprintf(stderr, "render: note: the camera's look not estimated (%s): vehicles composited clean\n",
                    lerr.msg);
    }
    if (!st)
        st = rs_synth_render(&r, s.output, &s.camera, s.site->ground_normal_enu, s.site->ground_offset_m, &s.prepared,
                             &ropt, &err);
    if (st == RS_OK && labels)
        st = rs_synth_render_write_labels(s.output, &r, split, &lopt, &s.camera, s.site->ground_normal_enu,
                                          s.site->ground_offset_m, &s.prepared, &err);
    if (st) {
        rc = rs_cli_fail("render", st, &err);
    } else {
        printf("vehicles %d rendered %d region %d %d %d %d povray_s %.3f passes %d processes %d -> %s\n", r.Nvehicles,
               r.Nrendered, r.region[0], r.region[1], r.region[2], r.region[3], r.seconds_povray, r.Npasses, r.Npovray,
               s.output);
        if (matched)
            printf("light matched to the background: %d road pixels, light x %.3f %.3f %.3f (level %.3f), from %s\n",
                   light.Nroad_px, ropt.scene.light_rgb_scale[0], ropt.scene.light_rgb_scale[1],
                   ropt.scene.light_rgb_scale[2], light.level, rs_synth_light_source_name(light.source));
        if (ropt.look)
            printf("look: noise variance %.3g + %.3g v (sigma %.4f at v 0.5), blur %.2f px, jpeg quality %d%s, "
                   "blockiness %.3f, gain %.3f %.3f %.3f\n",
                   look.noise_a, look.noise_b, rs_synth_appearance_noise_sigma(&look, 0.5), look.blur_sigma_px,
                   look.jpeg_quality, look.jpeg_quality && !look.jpeg_exact ? " (nearest IJG)" : "", look.blockiness,
                   look.gain[0], look.gain[1], look.gain[2]);
        rc = RS_EXIT_OK;
    }
    rs_synth_render_result_free(&r);
    rs_image_free(&env_map);
    rs_cli_synth_free(&s);
    return rc;
}
