// roadside traffic -- vehicles along a site's lanes (built-in, or from SUMO), randomised without
// overlaps, written as vehicles files for `roadside scene` (synth/traffic/rs_synth_traffic.h,
// synth/traffic/rs_synth_sumo.h, docs/traffic.md).
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cli/rs_cli.h"
#include "core/rs_io.h"
#include "geo/rs_site.h"
#include "synth/fleet/rs_synth_fleet.h"
#include "synth/traffic/rs_synth_sumo.h"
#include "synth/traffic/rs_synth_traffic.h"

static const char *const CMD = "traffic";

static void usage(FILE *out)
{
    fprintf(out, "usage: roadside traffic SITE -o OUT [options]\n"
                 "\n"
                 "Places vehicles along the site's lanes (SITE/lanes.geojson, docs/site-format.md) and writes\n"
                 "a vehicles file for `roadside scene`: a JSON list of {id, class, e, n, yaw_deg, length,\n"
                 "width, height, variant, speed_mps} in the site ENU frame (yaw clockwise from north).\n"
                 "\n"
                 "Built-in traffic (the default; OUT is a .json file):\n"
                 "  vehicles queue along every lane (junction lanes excluded) with time-headway gaps\n"
                 "  s0 + v T u, v = U(0, 1) x the lane's speed limit, u = U(0.5, 1.5) (docs/traffic.md).\n"
                 "  --count N          keep at most N vehicles (a random subset) [all that fit]\n"
                 "  --min-gap M        standstill gap s0, metres [2]\n"
                 "  --headway S        time headway T, seconds [1.5]\n"
                 "  --junction-lanes   fill junction lanes too (their vehicles may cross; overlaps dropped)\n"
                 "\n"
                 "SUMO (--sumo; OUT is a folder: frame_NNNNNN.json per time step, and frames.json listing\n"
                 "each frame's file and time):\n"
                 "  --sumo             build a network from the lanes (netconvert), a flow for every\n"
                 "                     manoeuvre, run sumo and read its floating car data\n"
                 "  --osm FILE         build the network from this OpenStreetMap file instead\n"
                 "  --duration S       simulated seconds [300]      --warmup S   no frames before [60]\n"
                 "  --period S         seconds between frames [1]   --flow VPH   vehicles/hour per manoeuvre [200]\n"
                 "  --keep DIR         keep SUMO's files (network, routes, fcd.xml, sumo.log) in DIR\n"
                 "\n"
                 "Both:\n"
                 "  --seed S           random seed, 0 .. 2^53 [0]\n"
                 "  --mix SPEC         class weights, e.g. sedan=3,suv=3,van=1,bus=0.2 (classes sedan,\n"
                 "                     hatchback, suv, pickup, van, bus, box_truck, articulated_truck,\n"
                 "                     motorcycle, bicycle: two-wheelers with their rider)\n"
                 "                     [sedan=0.234,hatchback=0.2145,suv=0.2925,pickup=0.02925,van=0.0975,\n"
                 "                     bus=0.0195,box_truck=0.0585,articulated_truck=0.02925,motorcycle=0.008,\n"
                 "                     bicycle=0.017: docs/traffic.md]\n"
                 "  --lanes FILE       lanes file [SITE/lanes.geojson]\n"
                 "  --sigma M          domain randomisation: normal offset along and across the lane,\n"
                 "                     metres [0.7071 = sqrt(0.5): variance 0.5 m^2]\n"
                 "  --yaw-jitter DEG   heading offset uniform in [-DEG, DEG] [5]\n"
                 "  --no-randomise     no offsets (overlapping vehicles are still dropped)\n"
                 "\n"
                 "No two footprints overlap: a vehicle is redrawn up to 20 times, then dropped.\n"
                 "Exit status: 0 written, 1 failed (nothing written), 2 bad arguments.\n");
}

typedef struct {
    const char *site_dir, *out, *lanes_path;
    bool sumo, randomise;
    const char *builtin_option, *sumo_option; // the last option given of each kind
    rs_synth_traffic_options traffic;
    rs_synth_randomise_options rnd;
    rs_synth_sumo_options so;
} traffic_args;

static int parse_args(traffic_args *t, int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--sumo")) {
            t->sumo = true;
            continue;
        }
        if (!strcmp(a, "--junction-lanes")) {
            t->traffic.junction_lanes = true;
            t->builtin_option = a;
            continue;
        }
        if (!strcmp(a, "--no-randomise")) {
            t->randomise = false;
            continue;
        }
        if (strncmp(a, "-", 1) != 0 || !strcmp(a, "--")) {
            if (!strcmp(a, "--") && i + 1 < argc) a = argv[++i];
            if (t->site_dir) return rs_cli_usage_error(CMD, "one site only: '%s' and '%s'", t->site_dir, a);
            t->site_dir = a;
            continue;
        }
        if (i + 1 >= argc) return rs_cli_usage_error(CMD, "%s: needs a value", a);
        const char *v = argv[++i];
        long n;
        double x;
        if (!strcmp(a, "--count") || !strcmp(a, "--min-gap") || !strcmp(a, "--headway")) t->builtin_option = a;
        if (!strcmp(a, "--osm") || !strcmp(a, "--keep") || !strcmp(a, "--duration") || !strcmp(a, "--warmup") ||
            !strcmp(a, "--period") || !strcmp(a, "--flow"))
            t->sumo_option = a;
        if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            t->out = v;
        } else if (!strcmp(a, "--lanes")) {
            t->lanes_path = v;
        } else if (!strcmp(a, "--osm")) {
            t->so.osm_path = v;
        } else if (!strcmp(a, "--keep")) {
            t->so.work_dir = v;
        } else if (!strcmp(a, "--seed")) {
            if (!rs_cli_parse_int(v, 0, 9007199254740992L, &n))
                return rs_cli_usage_error(CMD, "--seed: '%s' is not an integer in 0 .. 2^53", v);
            t->traffic.seed = t->so.seed = (uint64_t)n;
            t->rnd.seed = (uint64_t)n ^ 0x9e3779b97f4a7c15ULL;
        } else if (!strcmp(a, "--count")) {
            if (!rs_cli_parse_int(v, 1, 1000000, &n))
                return rs_cli_usage_error(CMD, "--count: '%s' is not an integer in 1..1000000", v);
            t->traffic.count = (int)n;
        } else if (!strcmp(a, "--mix")) {
            rs_err err = {0};
            if (rs_synth_class_mix_parse(&t->traffic.mix, v, &err)) return rs_cli_usage_error(CMD, "%s", err.msg);
            t->so.mix = t->traffic.mix;
        } else if (!strcmp(a, "--sigma")) {
            if (!rs_cli_parse_double(v, &x) || x < 0 || x > 10)
                return rs_cli_usage_error(CMD, "--sigma: '%s' is not a number of metres in [0, 10]", v);
            t->rnd.sigma_along_m = t->rnd.sigma_across_m = x;
        } else if (!strcmp(a, "--yaw-jitter")) {
            if (!rs_cli_parse_double(v, &x) || x < 0 || x > 180)
                return rs_cli_usage_error(CMD, "--yaw-jitter: '%s' is not a number of degrees in [0, 180]", v);
            t->rnd.yaw_range_deg = x;
        } else if (!strcmp(a, "--min-gap")) {
            if (!rs_cli_parse_double(v, &x) || x < 0 || x >= 100)
                return rs_cli_usage_error(CMD, "--min-gap: '%s' is not a number of metres in [0, 100)", v);
            t->traffic.s0_m = x;
        } else if (!strcmp(a, "--headway")) {
            if (!rs_cli_parse_double(v, &x) || x < 0 || x >= 100)
                return rs_cli_usage_error(CMD, "--headway: '%s' is not a number of seconds in [0, 100)", v);
            t->traffic.headway_s = x;
        } else if (!strcmp(a, "--duration") || !strcmp(a, "--warmup") || !strcmp(a, "--period") ||
                   !strcmp(a, "--flow")) {
            if (!rs_cli_parse_double(v, &x) || x < 0)
                return rs_cli_usage_error(CMD, "%s: '%s' is not a number >= 0", a, v);
            double *dst = !strcmp(a, "--duration") ? &t->so.duration_s
                          : !strcmp(a, "--warmup") ? &t->so.warmup_s
                          : !strcmp(a, "--period") ? &t->so.period_s
                                                   : &t->so.flow_vph;
            *dst = x;
        } else {
            return rs_cli_usage_error(CMD, "unknown option '%s'", a);
        }
    }
    if (!t->site_dir) return rs_cli_usage_error(CMD, "no site folder given");
    if (!t->out) return rs_cli_usage_error(CMD, "no output given (-o OUT)");
    if (!t->sumo && t->sumo_option) return rs_cli_usage_error(CMD, "%s needs --sumo", t->sumo_option);
    if (t->sumo && t->builtin_option)
        return rs_cli_usage_error(CMD, "%s is for the built-in traffic, not with --sumo", t->builtin_option);
    if (t->sumo && !(t->so.warmup_s < t->so.duration_s && t->so.period_s > 0 && t->so.flow_vph > 0))
        return rs_cli_usage_error(CMD, "--sumo: need --warmup < --duration, --period > 0, --flow > 0");
    return RS_EXIT_OK;
}

int rs_cli_traffic(int argc, char **argv)
{
    if (rs_cli_wants_help(argc, argv)) {
        usage(stdout);
        return RS_EXIT_OK;
    }
    traffic_args t = {0};
    t.randomise = true;
    rs_synth_traffic_options_default(&t.traffic);
    rs_synth_randomise_options_default(&t.rnd);
    rs_synth_sumo_options_default(&t.so);
    int rc = parse_args(&t, argc, argv);
    if (rc) return rc;

    rs_err err = {0};
    rs_site *site = NULL;
    rs_status st = rs_site_load(&site, t.site_dir, &err);
    if (st) return rs_cli_fail(t.site_dir, st, &err);
    char *lanes_path = t.lanes_path ? strdup(t.lanes_path) : rs_io_join(t.site_dir, RS_SITE_LANES);
    rs_lanes lanes = {0};
    rs_synth_vehicle *v = NULL;
    rs_synth_sumo_frames frames = {0};
    int N = 0;
    const char *what = "traffic";
    if (!lanes_path) {
        st = rs_err_set(&err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    if (!t.so.osm_path && (st = rs_lanes_read(&lanes, lanes_path, site, &err))) goto done;
    if (t.sumo) {
        what = "traffic --sumo";
        if ((st = rs_synth_sumo_run(&frames, &lanes, &site->origin, &t.so, &err))) goto done;
        if ((st = rs_synth_sumo_frames_write(t.out, &frames, &t.rnd, t.randomise, &N, &err))) goto done;
        printf("wrote %s: %d frames from SUMO (seed %llu), %d vehicles in all; index %s/frames.json\n", t.out, frames.N,
               (unsigned long long)t.so.seed, N, t.out);
    } else {
        if ((st = rs_synth_traffic_place(&v, &N, &lanes, &t.traffic, &err))) goto done;
        int placed = N;
        if (!t.randomise) t.rnd.sigma_along_m = t.rnd.sigma_across_m = t.rnd.yaw_range_deg = 0;
        if ((st = rs_synth_traffic_randomise(v, &N, &t.rnd, &err))) goto done;
        if ((st = rs_synth_traffic_write_json(t.out, v, N, &err))) goto done;
        printf("wrote %s: %d vehicles on %d lanes (seed %llu; %d placed, %d dropped as overlapping)\n", t.out, N,
               lanes.N, (unsigned long long)t.traffic.seed, placed, placed - N);
    }
done:
    free(lanes_path);
    free(v);
    rs_synth_sumo_frames_free(&frames);
    rs_lanes_free(&lanes);
    rs_site_free(site);
    return st ? rs_cli_fail(what, st, &err) : RS_EXIT_OK;
}
