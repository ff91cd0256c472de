// rs_synth_scene.c -- the sun and sky lights, and the POV-Ray scene writer (the vehicles file is
// read by rs_synth_vehicles_read.c)
// (rs_synth_scene.h, docs/povray.md).
#include "synth/povray/rs_synth_scene.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "core/rs_units.h"
#include "synth/povray/internal/rs_synth_scene_internal.h"

// ---- the scene ----

void rs_synth_scene_options_default(rs_synth_scene_options *opt)
{
    memset(opt, 0, sizeof(*opt));
    opt->pass = RS_SYNTH_PASS_COLOUR;
    opt->ground_visible = true;
    opt->sun_azimuth_deg = 135;
    opt->sun_elevation_deg = 45;
    opt->pin_radius_px = 3;
}

void rs_synth_scene_env_colours(double zenith_rgb[3], double horizon_rgb[3], double ground_rgb[3],
                                const rs_synth_scene_options *opt)
{
    if (!opt->env_given) {
        rs_synth_env_default(zenith_rgb, horizon_rgb, ground_rgb, opt->overcast);
        return;
    }
    for (int c = 0; c < 3; c++)
        zenith_rgb[c] = opt->env_zenith_rgb[c], horizon_rgb[c] = opt->env_horizon_rgb[c],
        ground_rgb[c] = opt->env_ground_rgb[c];
}

// The environment sphere of the colour pass (rs_synth_scene_options.env_*): 50 km round the
// site origin, hollow, emissive, invisible to the camera (no_image) and casting no shadow; the
// ground plane cuts it, so below the horizon the vehicles mostly reflect the ground itself.
static void write_environment(FILE *f, const rs_synth_scene_options *opt)
{
    if (opt->env_map) {
        // the background's own map (issue 40): a 16-bit PNG of linear values (gamma 1: no
        // decoding), POV-Ray's spherical mapping (rs_synth_env_map_direction), bilinear
        fprintf(f,
                "// the environment, seen in reflections only: the background's map\n"
                "sphere { 0, 1 hollow\n  texture { pigment { image_map { png \"%s\" gamma 1.0 map_type 1 "
                "interpolate 2 } }\n    finish { emission %.6g ambient 0 diffuse 0 specular 0 } }\n"
                "  scale 50000 no_image no_shadow }\n",
                RS_SYNTH_ENV_MAP_FILE, opt->env_map_scale > 0 ? opt->env_map_scale : 1.0);
        return;
    }
    double z[3], h[3], g[3];
    rs_synth_scene_env_colours(z, h, g, opt);
    fprintf(f,
            "// the environment, seen in reflections only\n"
            "sphere { 0, 1 hollow\n  texture { pigment { gradient y colour_map { [0 rgb <%.5f, %.5f, %.5f>] "
            "[0.5 rgb <%.5f, %.5f, %.5f>] [0.52 rgb <%.5f, %.5f, %.5f>] [1 rgb <%.5f, %.5f, %.5f>] } "
            "scale 2 translate -1*y }\n    finish { emission 1 ambient 0 diffuse 0 specular 0 } }\n"
            "  scale 50000 no_image no_shadow }\n",
            g[0], g[1], g[2], g[0], g[1], g[2], h[0], h[1], h[2], z[0], z[1], z[2]);
}

// The colour pass's irradiance on the ground plane per channel, as its light_source lines give
// it (write_body): the sun's colour (1, 0.97, 0.92), every light times light_rgb_scale when set.
static void ground_irradiance_rgb(double e_rgb[3], const rs_synth_scene_options *opt, const double ground_normal_enu[3])
{
    rs_synth_light lights[RS_SYNTH_SKY_LIGHTS + 1];
    const int Nlights = rs_synth_scene_lights(lights, opt);
    const int first_sky = Nlights - RS_SYNTH_SKY_LIGHTS;
    const double *ls = opt->light_rgb_scale, *g = ground_normal_enu;
    const bool matched = ls[0] > 0 || ls[1] > 0 || ls[2] > 0;
    const double sun_rgb[3] = {1.0, 0.97, 0.92};
    const double gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    for (int c = 0; c < 3; c++) {
        e_rgb[c] = 0;
        for (int j = 0; j < Nlights; j++) {
            const double *d = lights[j].dir_enu;
            const double cz = gn > 0 ? (g[0] * d[0] + g[1] * d[1] + g[2] * d[2]) / gn : 0;
            e_rgb[c] += (cz > 0 ? cz : 0) * lights[j].irradiance * (j < first_sky ? sun_rgb[c] : 1);
        }
        if (matched) e_rgb[c] *= ls[c];
    }
}

static void write_vec_enu(FILE *f, const double p_enu[3])
{
    double p[3];
    rs_synth_enu_to_pov(p, p_enu);
    fprintf(f, "<%.17g, %.17g, %.17g>", p[0], p[1], p[2]);
}

// The flat emissive texture of ID value `id` (1..65535): R + 256 G in 8-bit units.
static void write_id_texture(FILE *f, unsigned id)
{
    fprintf(f,
            "texture { pigment { rgb <%u/255, %u/255, 0> } finish { emission 1 ambient 0 "
            "diffuse 0 specular 0 } }",
            id & 255u, (id >> 8) & 255u);
}

static void write_pins(FILE *f, const rs_synth_povcam *cam, const double fxy[2], const rs_synth_scene_options *opt)
{
    // Unit optical axis (POV-Ray world) from direction, right and up: the normal of the image
    // plane is orthogonal to right and up.
    const double *r = cam->right, *u = cam->up;
    double z[3] = {r[1] * u[2] - r[2] * u[1], r[2] * u[0] - r[0] * u[2], r[0] * u[1] - r[1] * u[0]};
    double zn = sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2]);
    const double *d = cam->direction;
    if (z[0] * d[0] + z[1] * d[1] + z[2] * d[2] < 0) zn = -zn;
    for (int k = 0; k < 3; k++) z[k] /= zn;
    const double f_px = sqrt(fxy[0] * fxy[1]);
    for (int i = 0; i < opt->Npins; i++) {
        double p[3];
        rs_synth_enu_to_pov(p, &opt->pins_enu_m[3 * i]);
        const double dp[3] = {p[0] - cam->location[0], p[1] - cam->location[1], p[2] - cam->location[2]};
        // a fisheye sees behind its image plane: its pins are sized by their distance
        const double depth = cam->fisheye_deg > 0 ? sqrt(dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2])
                                                  : dp[0] * z[0] + dp[1] * z[1] + dp[2] * z[2];
        if (!(depth > 0)) continue; // behind the camera
        fprintf(f,
                "sphere { <%.17g, %.17g, %.17g>, %.9g\n  texture { pigment { rgb 1 } finish { "
                "emission 1 ambient 0 diffuse 0 specular 0 } } no_shadow }\n",
                p[0], p[1], p[2], opt->pin_radius_px * depth / f_px);
    }
}

int rs_synth_scene_lights(rs_synth_light *lights, const rs_synth_scene_options *opt)
{
    int n = 0;
    if (opt->sun_elevation_deg > 0 && !opt->overcast) {
        const double az = opt->sun_azimuth_deg * RS_RAD_PER_DEG, el = opt->sun_elevation_deg * RS_RAD_PER_DEG;
        lights[n++] = (rs_synth_light){{sin(az) * cos(el), cos(az) * cos(el), sin(el)}, 1.0};
    }
    const double sky = opt->overcast ? RS_SYNTH_SKY_OVERCAST : RS_SYNTH_SKY_CLEAR;
    // band shares of a uniform sky's irradiance on the ground: sin^2 of the band's edges
    const double edge = sin(40.0 * RS_RAD_PER_DEG) * sin(40.0 * RS_RAD_PER_DEG);
    const double zenith_deg[2] = {0, 60}, share[2] = {edge, 1.0 - edge};
    const int count[2] = {1, 6};
    for (int b = 0; b < 2; b++)
        for (int k = 0; k < count[b]; k++) {
            const double z = zenith_deg[b] * RS_RAD_PER_DEG, az = 60.0 * k * RS_RAD_PER_DEG;
            lights[n++] =
                (rs_synth_light){{sin(az) * sin(z), cos(az) * sin(z), cos(z)}, sky * share[b] / count[b] / cos(z)};
        }
    return n;
}

// The albedo of the shadow pass's ground. POV-Ray clamps what it writes to [0, 1]: with a white
// ground, open ground under a clear sky (0.35) and a sun higher than 40.5 deg (sin el + 0.35 > 1)
// was written as 1 and read back as a lit fraction of 1 / (sin el + 0.35) (0.74 at 90 deg): every
// open pixel of the background darkened. At 0.25 the sun and the brightest sky (1 + 1) give 0.5.
#define SHADOW_GROUND_ALBEDO 0.25

double rs_synth_scene_shadow_unlit(const rs_synth_light *lights, int Nlights, const double ground_normal_enu[3])
{
    const double *g = ground_normal_enu;
    const double gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    double sum = 0;
    for (int j = 0; j < Nlights; j++) {
        const double *d = lights[j].dir_enu;
        const double c = (g[0] * d[0] + g[1] * d[1] + g[2] * d[2]) / gn;
        sum += lights[j].irradiance * (c > 0 ? c : 0);
    }
    return SHADOW_GROUND_ALBEDO * sum;
}

static void write_head(FILE *f, const char *what)
{
    fprintf(f,
            "// Written by roadside (%s). POV-Ray world <x, y, z> = <east, up, north>,\n"
            "// metres (docs/conventions.md, docs/povray.md). Self-contained: no include files.\n"
            "#version 3.7;\n"
            "global_settings { assumed_gamma 1.0 max_trace_level 5 }\n",
            what);
}

// The meshes of every vehicle some pass includes, declared once for all passes (issue 18's
// cost: POV-Ray parses a scene's text again for every frame and scans the frames it skips, so
// each mesh written once instead of once per pass takes two thirds of the text away):
// "#declare RS_PART_<mesh>_<part> = mesh2 {...}" (rs_synth_fleet_write_parts). A scene without
// a colour pass (`merged`: ID and shadow passes) needs neither the parts' textures nor normals:
// one bare mesh2 per mesh, "#declare RS_MESH_<mesh> = mesh2 {...}" (rs_synth_fleet_write_merged),
// the same triangles; it parses and traces about 10 % faster than the union of parts.
static rs_status write_geometry(FILE *f, const rs_synth_prepared *vehicles, const rs_synth_scene_options *passes,
                                int Npasses, bool merged, rs_err *err)
{
    for (int m = 0; m < vehicles->Nmeshes; m++) {
        bool used = false;
        for (int i = 0; i < vehicles->N && !used; i++)
            if (vehicles->imesh[i] == m)
                for (int k = 0; k < Npasses && !used; k++) used = !passes[k].include || passes[k].include[i];
        if (!used) continue;
        char prefix[32];
        snprintf(prefix, sizeof(prefix), merged ? "RS_MESH_%d" : "RS_PART_%d", m);
        rs_status st = merged ? rs_synth_fleet_write_merged(f, prefix, &vehicles->meshes[m], err)
                              : rs_synth_fleet_write_parts(f, prefix, &vehicles->meshes[m], err);
        if (st) return st;
    }
    return RS_OK;
}

rs_status rs_synth_scene_write_textures(const char *dir, const rs_synth_prepared *vehicles, rs_err *err)
{
    for (int m = 0; m < vehicles->Nmeshes; m++) {
        if (vehicles->meshes[m].Ntextures == 0) continue;
        char prefix[32];
        snprintf(prefix, sizeof(prefix), "RS_PART_%d", m); // as write_geometry declares the parts
        rs_status st = rs_synth_fleet_write_textures(dir, prefix, &vehicles->meshes[m], err);
        if (st) return st;
    }
    return RS_OK;
}

void rs_synth_scene_remove_textures(const char *dir, const rs_synth_prepared *vehicles)
{
    for (int m = 0; m < vehicles->Nmeshes; m++)
        for (int k = 0; k < vehicles->meshes[m].Ntextures; k++) {
            char prefix[32], name[96];
            snprintf(prefix, sizeof(prefix), "RS_PART_%d", m);
            rs_synth_fleet_texture_name(name, sizeof name, prefix, k);
            char *p = rs_io_join(dir, name);
            if (p) (void)remove(p);
            free(p);
        }
}

// Andrew's monotone chain (A. M. Andrew, "Another efficient algorithm for convex hulls in two
// dimensions", Inf. Process. Lett. 9(5), 1979): the convex hull of p[0..n-1] counter-clockwise
// into h (at most n + 1 points), returns its size. Sorts p.
static int cmp_xy(const void *a, const void *b)
{
    const double *p = a, *q = b;
    return p[0] < q[0] ? -1 : p[0] > q[0] ? 1 : p[1] < q[1] ? -1 : p[1] > q[1] ? 1 : 0;
}
static double turn(const double *o, const double *a, const double *b)
{
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}
static int convex_hull(double (*h)[2], double (*p)[2], int n)
{
    qsort(p, (size_t)n, sizeof p[0], cmp_xy);
    int k = 0;
    for (int i = 0; i < n; i++) { // lower
        while (k >= 2 && turn(h[k - 2], h[k - 1], p[i]) <= 0) k--;
        h[k][0] = p[i][0], h[k][1] = p[i][1], k++;
    }
    for (int i = n - 2, lo = k + 1; i >= 0; i--) { // upper
        while (k >= lo && turn(h[k - 2], h[k - 1], p[i]) <= 0) k--;
        h[k][0] = p[i][0], h[k][1] = p[i][1], k++;
    }
    return k > 1 ? k - 1 : k; // the last point repeats the first
}

// The shadow pass needs the ground only where a vehicle can darken it (issue 18's cost: every
// ground pixel traces a shadow ray towards each of the 8 lights, most of them far from any
// vehicle). So its ground is not the whole plane but one patch per vehicle, in the plane: the
// convex hull of the box's footprint and of its top corners projected onto the ground along
// every light more than 3 deg above it (the rule of rs_synth_render's region), widened by 5 cm,
// as a fan of triangles. A box's shadow along a direction is the hull of its corners'
// projections, so no shadow is lost; the pixels outside are transparent, which the render reads
// as fully lit (lit fraction 1), as they were. Lights within 3 deg of the ground are left out
// here as in the region. Writes "mesh2 { ... " (no closing brace) and returns 1, or writes
// nothing and returns 0 when no vehicle is included (then the caller writes the plane).
static int write_shadow_ground(FILE *f, const rs_synth_prepared *vehicles, const rs_synth_scene_options *opt,
                               const double ground_normal_enu[3], double ground_offset_m)
{
    enum { MAXP = 4 + 4 * (RS_SYNTH_SKY_LIGHTS + 1) };
    rs_synth_light lights[RS_SYNTH_SKY_LIGHTS + 1];
    const int Nlights = rs_synth_scene_lights(lights, opt);
    const double *g = ground_normal_enu;
    const double gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    const int N = vehicles->N;
    double(*hull)[2] = malloc(sizeof(double[2]) * (size_t)(N > 0 ? N : 1) * (MAXP + 1));
    int *Nhull = calloc((size_t)(N > 0 ? N : 1), sizeof(int));
    int Nv = 0, Nt = 0;
    if (!hull || !Nhull) {
        free(hull), free(Nhull);
        return 0; // the plane then: slower, the same shadows
    }
    for (int i = 0; i < N; i++) {
        if (opt->include && !opt->include[i]) continue;
        double corners[8][3], p[MAXP][2], (*h)[2] = &hull[(size_t)i * (MAXP + 1)];
        rs_synth_vehicle_corners_enu(corners, &vehicles->v[i], ground_normal_enu, ground_offset_m);
        int n = 0;
        for (int k = 0; k < 4; k++) p[n][0] = corners[k][0], p[n][1] = corners[k][1], n++;
        for (int j = 0; j < Nlights; j++) {
            const double *d = lights[j].dir_enu;
            const double nd = (g[0] * d[0] + g[1] * d[1] + g[2] * d[2]) / gn;
            if (!(nd > 0.05)) continue;
            for (int k = 4; k < 8; k++) {
                const double *c = corners[k];
                const double s = ((g[0] * c[0] + g[1] * c[1] + g[2] * c[2]) / gn - ground_offset_m / gn) / nd;
                p[n][0] = c[0] - s * d[0], p[n][1] = c[1] - s * d[1], n++;
            }
        }
        const int Nh = convex_hull(h, p, n);
        if (Nh < 3) continue;
        double ce = 0, cn = 0;
        for (int k = 0; k < Nh; k++) ce += h[k][0] / Nh, cn += h[k][1] / Nh;
        for (int k = 0; k < Nh; k++) {
            const double de = h[k][0] - ce, dn = h[k][1] - cn, r = sqrt(de * de + dn * dn);
            if (r > 0) h[k][0] += 0.05 * de / r, h[k][1] += 0.05 * dn / r;
        }
        Nhull[i] = Nh;
        Nv += Nh;
        Nt += Nh - 2;
    }
    if (Nt > 0) {
        // POV-Ray's world <east, up, north>, each point on the ground plane
        fprintf(f, "mesh2 {\n  vertex_vectors { %d", Nv);
        for (int i = 0; i < N; i++)
            for (int k = 0; k < Nhull[i]; k++) {
                const double *q = hull[(size_t)i * (MAXP + 1) + k];
                fprintf(f, ",\n    <%.6f, %.6f, %.6f>", q[0],
                        rs_synth_ground_up_m(ground_normal_enu, ground_offset_m, q[0], q[1]), q[1]);
            }
        fprintf(f, " }\n  face_indices { %d", Nt);
        for (int i = 0, base = 0; i < N; base += Nhull[i], i++)
            for (int k = 1; k + 1 < Nhull[i]; k++) fprintf(f, ",\n    <%d, %d, %d>", base, base + k, base + k + 1);
        fprintf(f, " }\n");
    }
    free(hull);
    free(Nhull);
    return Nt > 0;
}

// The ID pass leaves the ground out where it hides nothing (issue 18's cost: the plane is hit by
// most of the region's pixels, about 0.03 s of an image's 0.15 s ID trace).
bool rs_synth_scene_ground_occludes(const rs_synth_povcam *cam, const rs_synth_prepared *vehicles,
                                    const rs_synth_scene_options *opt, const double g[3], double offset)
{
    const double gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    const double *c = cam->location; // POV-Ray world <e, u, n>
    if (!((g[0] * c[0] + g[1] * c[2] + g[2] * c[1] - offset) / gn > 1e-6)) return true;
    for (int i = 0; i < vehicles->N; i++) {
        if (opt->include && !opt->include[i]) continue;
        double corners[8][3];
        rs_synth_vehicle_corners_enu(corners, &vehicles->v[i], g, offset);
        for (int k = 0; k < 4; k++)
            if ((g[0] * corners[k][0] + g[1] * corners[k][1] + g[2] * corners[k][2] - offset) / gn < -1e-9) return true;
    }
    return false;
}

// The condition's lights of the colour pass (issue 40, rs_synth_scene_apply_condition): a
// spot light at each included vehicle's headlights (lights_on; only where another included
// vehicle's centre is within 40 m and 35 deg of the beam's axis) and the street lights, all
// shadowless, fading as 1/d^2 (fade_distance 1, fade_power 2: POV-Ray's 2 / (1 + d^2), so the
// colour is half the intensity at 1 m).
static void write_condition_lights(FILE *f, const rs_synth_prepared *vehicles, const rs_synth_scene_options *opt,
                                   const double g[3], double offset)
{
    const double I = opt->headlight_intensity > 0 ? opt->headlight_intensity : RS_SYNTH_HEADLIGHT_INTENSITY;
    for (int i = 0; opt->lights_on && i < vehicles->N; i++) {
        if (opt->include && !opt->include[i]) continue;
        const rs_synth_vehicle *v = &vehicles->v[i];
        double p[2][3], axis[3];
        rs_synth_scene_headlights(p, axis, v, rs_synth_ground_up_m(g, offset, v->e_m, v->n_m));
        // cost: a lamp lights only what its beam reaches; none of the others within 40 m and
        // 35 deg of its axis: no light_source (the road's light is rs_synth_headlight_ground's)
        bool lights_one = false;
        for (int j = 0; j < vehicles->N && !lights_one; j++) {
            if (j == i || (opt->include && !opt->include[j])) continue;
            const double de = vehicles->v[j].e_m - p[0][0], dn = vehicles->v[j].n_m - p[0][1];
            const double d = hypot(de, dn), ah = hypot(axis[0], axis[1]);
            lights_one = d < 40 && ah > 0 && (de * axis[0] + dn * axis[1]) / (d * ah) > cos(35 * RS_RAD_PER_DEG);
        }
        for (int k = 0; k < 2 && lights_one; k++) {
            const double at[3] = {p[k][0] + axis[0], p[k][1] + axis[1], p[k][2] + axis[2]};
            fprintf(f, "light_source { ");
            write_vec_enu(f, p[k]);
            fprintf(f, " color rgb <%.6g, %.6g, %.6g> spotlight point_at ", 0.5 * I, 0.5 * I * 0.96, 0.5 * I * 0.88);
            write_vec_enu(f, at);
            fprintf(f, " radius %g falloff %g tightness 0 fade_distance 1 fade_power 2 shadowless }\n",
                    RS_SYNTH_BEAM_FULL_DEG, RS_SYNTH_BEAM_EDGE_DEG);
        }
    }
    for (int j = 0; j < opt->Nstreet_lights; j++) {
        fprintf(f, "light_source { ");
        write_vec_enu(f, opt->street_lights_enu_m[j]);
        const double *c = opt->street_light_rgb;
        fprintf(f, " color rgb <%.6g, %.6g, %.6g> fade_distance 1 fade_power 2 shadowless }\n", c[0], c[1], c[2]);
    }
}

static const char *pass_name(rs_synth_pass pass)
{
    return pass == RS_SYNTH_PASS_ID ? "object-ID" : pass == RS_SYNTH_PASS_SHADOW ? "shadow" : "colour";
}

// The colour pass's sky: the ring of 6 lights at zenith 60 deg (rs_synth_scene_lights) as 3,
// each pair of neighbours one light between them (the mean azimuth, the same zenith angle, the
// sum of their irradiance). A shadowless light costs POV-Ray its shading at every hit, paint,
// dirt and reflection alike: 3 of the 7 were 5 % of a colour pass's instructions. Nothing
// diffuse changes on average: the ground's irradiance is the same, and a vertical face's swings
// between the same 0.87 and 1 of its mean as it turns (3 lights 120 deg apart ripple as 6 at 60
// do); glossy paint shows 3 faint highlights of the sky instead of 6 half as bright. The shadow
// pass keeps all 7 (the sky's shadows on the ground: rs_synth_light.h). lights (n,): the sky's
// RS_SYNTH_SKY_LIGHTS from first_sky, zenith first; returns the new count.
static int sky_ring_halved(rs_synth_light *lights, int n, int first_sky)
{
    const int ring = first_sky + 1, Nring = n - ring;
    if (Nring != 6) return n;
    for (int k = 0; k < 3; k++) {
        const rs_synth_light *a = &lights[ring + 2 * k], *b = &lights[ring + 2 * k + 1];
        double h[2] = {a->dir_enu[0] + b->dir_enu[0], a->dir_enu[1] + b->dir_enu[1]};
        const double hn = hypot(h[0], h[1]), sz = hypot(a->dir_enu[0], a->dir_enu[1]);
        rs_synth_light m = {{h[0] / hn * sz, h[1] / hn * sz, a->dir_enu[2]}, a->irradiance + b->irradiance};
        lights[ring + k] = m;
    }
    return ring + 3;
}

// Everything of one pass after the head: camera, lights, ground, meshes, vehicles, pins.
// `merged`: the geometry was declared as RS_MESH_<mesh> itself (write_geometry).
static rs_status write_body(FILE *f, const rs_synth_povcam *cam, const double fxy[2], const double ground_normal_enu[3],
                            double ground_offset_m, const rs_synth_prepared *vehicles, const rs_synth_scene_options *o,
                            bool merged, rs_err *err)
{
    const rs_synth_scene_options opt = *o;
    const bool id_pass = opt.pass == RS_SYNTH_PASS_ID;
    const bool shadow_pass = opt.pass == RS_SYNTH_PASS_SHADOW;
    rs_status st;
    if ((st = rs_synth_povcam_write(f, cam, err))) return st;
    fprintf(f, "background { rgbt <0, 0, 0, 1> }\n");
    if (!id_pass) {
        rs_synth_light lights[RS_SYNTH_SKY_LIGHTS + 1];
        int Nlights = rs_synth_scene_lights(lights, &opt);
        const int first_sky = Nlights - RS_SYNTH_SKY_LIGHTS;
        if (!shadow_pass) Nlights = sky_ring_halved(lights, Nlights, first_sky);
        fprintf(f, "// sun: azimuth %.6g deg, elevation %.6g deg%s; then the sky (%d lights%s)\n", opt.sun_azimuth_deg,
                opt.sun_elevation_deg,
                first_sky      ? ""
                : opt.overcast ? " (overcast: no sun)"
                               : " (below the horizon)",
                Nlights - first_sky, shadow_pass ? ", casting shadows" : ", shadowless");
        // lighting matched to the background (part B of issue 18): a per-channel scale
        const double *ls = opt.light_rgb_scale;
        const bool matched = !shadow_pass && (ls[0] > 0 || ls[1] > 0 || ls[2] > 0);
        const double k[3] = {matched ? ls[0] : 1, matched ? ls[1] : 1, matched ? ls[2] : 1};
        for (int j = 0; j < Nlights; j++) {
            double p[3];
            for (int c = 0; c < 3; c++) p[c] = 1e6 * lights[j].dir_enu[c];
            fprintf(f, "light_source { ");
            write_vec_enu(f, p);
            if (j < first_sky && !shadow_pass && !matched) // the sun, in colour
                fprintf(f, " color rgb <1.0, 0.97, 0.92> parallel point_at <0, 0, 0> }\n");
            else if (j < first_sky && matched)
                fprintf(f, " color rgb <%.9g, %.9g, %.9g> parallel point_at <0, 0, 0> }\n", 1.0 * k[0], 0.97 * k[1],
                        0.92 * k[2]);
            else if (matched)
                fprintf(f, " color rgb <%.9g, %.9g, %.9g> parallel point_at <0, 0, 0> shadowless }\n",
                        lights[j].irradiance * k[0], lights[j].irradiance * k[1], lights[j].irradiance * k[2]);
            else
                fprintf(f, " color rgb %.9g parallel point_at <0, 0, 0>%s }\n", lights[j].irradiance,
                        j >= first_sky && !shadow_pass ? " shadowless" : "");
        }
    }
    if (opt.pass == RS_SYNTH_PASS_COLOUR) write_condition_lights(f, vehicles, &opt, ground_normal_enu, ground_offset_m);
    // The ground: grey in the colour pass (left out of the image when compositing), an
    // occluder of value 0 in the ID pass where it can hide something, patches of the shadow
    // pass's albedo round the vehicles in the shadow pass.
    const double n_pov[3] = {ground_normal_enu[0], ground_normal_enu[2], ground_normal_enu[1]};
    const double nn = sqrt(n_pov[0] * n_pov[0] + n_pov[1] * n_pov[1] + n_pov[2] * n_pov[2]);
    const bool id_ground =
        id_pass && rs_synth_scene_ground_occludes(cam, vehicles, &opt, ground_normal_enu, ground_offset_m);
    if (id_pass && !id_ground)
        fprintf(f, "// no ground: every vehicle and the camera are above it, it would hide nothing\n");
    else if (!(shadow_pass && write_shadow_ground(f, vehicles, &opt, ground_normal_enu, ground_offset_m)))
        fprintf(f, "plane { <%.17g, %.17g, %.17g>, %.17g\n", n_pov[0] / nn, n_pov[1] / nn, n_pov[2] / nn,
                ground_offset_m / nn);
    if (id_ground)
        fprintf(f, "  texture { pigment { rgb 0 } finish { emission 0 ambient 0 diffuse 0 } }\n}\n");
    else if (shadow_pass) {
        fprintf(f,
                "  texture { pigment { rgb %.2f } finish { emission 0 ambient 0 diffuse 1 "
                "brilliance 1 specular 0 } }\n}\n",
                SHADOW_GROUND_ALBEDO);
    } else if (!id_pass && opt.env_given && !opt.ground_visible && !opt.env_off) {
        // compositing over a background with its environment (issue 18): the ground the vehicles
        // reflect is the photograph's ground, env_ground_rgb, where it is lit as the background
        // is (shadows, as the vehicles' own, darken it): pigment x 0.8 x the lights' irradiance on
        // the plane = env_ground_rgb.
        double e_rgb[3];
        ground_irradiance_rgb(e_rgb, &opt, ground_normal_enu);
        double pg[3];
        for (int c = 0; c < 3; c++) pg[c] = e_rgb[c] > 1e-9 ? opt.env_ground_rgb[c] / (0.8 * e_rgb[c]) : 0;
        fprintf(f, "  texture { pigment { rgb <%.6f, %.6f, %.6f> } finish { ambient 0 diffuse 0.8 } } no_image\n}\n",
                pg[0], pg[1], pg[2]);
    } else if (!id_pass)
        fprintf(f, "  texture { pigment { rgb 0.18 } finish { ambient 0 diffuse 0.8 } }%s\n}\n",
                opt.ground_visible ? "" : " no_image");
    if (opt.pass == RS_SYNTH_PASS_COLOUR && !opt.env_off) write_environment(f, &opt);
    // Meshes: textured per vehicle in the colour pass for procedural ones, bare otherwise.
    const int N = vehicles->N;
    for (int m = 0; m < vehicles->Nmeshes && !merged; m++) {
        int first = -1, users = 0;
        for (int i = 0; i < N; i++)
            if (vehicles->imesh[i] == m && (!opt.include || opt.include[i])) {
                if (first < 0) first = i;
                users++;
            }
        if (first < 0) continue;
        // a user model's own materials here; its paint materials take each vehicle's paint below
        const bool user = vehicles->v[first].cls == RS_SYNTH_USER_MODEL;
        const bool textured = opt.pass == RS_SYNTH_PASS_COLOUR;
        char name[32], prefix[32];
        snprintf(name, sizeof(name), "RS_MESH_%d", m);
        snprintf(prefix, sizeof(prefix), "RS_PART_%d", m);
        rs_synth_look look;
        rs_synth_fleet_look(&look, &vehicles->v[first]);
        look.lights_on = opt.lights_on; // issue 40: the condition's lights, snow and slush
        look.snow = opt.snow;
        look.dirt = fmin(1, look.dirt + opt.dirt_add);
        // the geometry is declared once before the passes (write_geometry): no mesh text here
        if ((st = rs_synth_fleet_write_instance(f, name, prefix, &vehicles->meshes[m],
                                                textured ? RS_SYNTH_DECLARE_TEXTURED : RS_SYNTH_DECLARE_BARE,
                                                user ? NULL : &look, err)))
            return st;
    }
    for (int i = 0; i < N; i++) {
        if (opt.include && !opt.include[i]) continue;
        const rs_synth_vehicle *v = &vehicles->v[i];
        char id[64];
        rs_synth_safe_text(id, sizeof(id), v->id);
        fprintf(f, "// vehicle %d: %s, id \"%s\"\nobject { RS_MESH_%d", i,
                rs_synth_class_name(v->cls) ? rs_synth_class_name(v->cls) : "?", id, vehicles->imesh[i]);
        if ((st = rs_synth_fleet_write_placement(
                 f, v, rs_synth_ground_up_m(ground_normal_enu, ground_offset_m, v->e_m, v->n_m), err)))
            return st;
        if (id_pass) {
            fprintf(f, "\n  ");
            write_id_texture(f, (unsigned)i + 1u);
            fprintf(f, " no_shadow");
        } else if (shadow_pass) { // seen as a green mark: no shadow rays spent on the ground it hides
            fprintf(f, "\n  texture { pigment { rgb <0, 1, 0> } finish { emission 1 ambient 0 diffuse 0 specular 0 } }"
                       " no_reflection");
        } else if (v->cls == RS_SYNTH_USER_MODEL) {
            fprintf(f,
                    "\n  texture { pigment { rgb <%.6f, %.6f, %.6f> } finish { ambient 0 "
                    "diffuse 0.7 specular 0.3 roughness 0.02 } }",
                    v->rgb[0], v->rgb[1], v->rgb[2]);
        }
        fprintf(f, " }\n");
    }
    if (opt.pass == RS_SYNTH_PASS_COLOUR && opt.Npins > 0) write_pins(f, cam, fxy, &opt);
    return RS_OK;
}

rs_status rs_synth_scene_write(FILE *f, const rs_synth_povcam *cam, const double fxy[2],
                               const double ground_normal_enu[3], double ground_offset_m,
                               const rs_synth_prepared *vehicles, const rs_synth_scene_options *opt_in, rs_err *err)
{
    rs_synth_scene_options opt;
    if (opt_in)
        opt = *opt_in;
    else
        rs_synth_scene_options_default(&opt);
    char what[32];
    snprintf(what, sizeof(what), "%s pass", pass_name(opt.pass));
    write_head(f, what);
    const bool merged = opt.pass != RS_SYNTH_PASS_COLOUR;
    rs_status st = write_geometry(f, vehicles, &opt, 1, merged, err);
    if (!st) st = write_body(f, cam, fxy, ground_normal_enu, ground_offset_m, vehicles, &opt, merged, err);
    if (!st && ferror(f)) st = rs_err_set(err, RS_ERR_IO, "writing the scene: stream error");
    return st;
}

rs_status rs_synth_scene_write_frames(FILE *f, const rs_synth_povcam *cam, const double fxy[2],
                                      const double ground_normal_enu[3], double ground_offset_m,
                                      const rs_synth_prepared *vehicles, const rs_synth_scene_options *passes,
                                      int Npasses, rs_err *err)
{
    if (Npasses < 1 || Npasses > 9)
        return rs_err_set(err, RS_ERR_USAGE, "rs_synth_scene_write_frames: %d passes (1..9)", Npasses);
    char what[96] = "passes as frames:";
    for (int k = 0; k < Npasses; k++) {
        const size_t len = strlen(what);
        snprintf(what + len, sizeof(what) - len, " %d %s", k + 1, pass_name(passes[k].pass));
    }
    write_head(f, what);
    bool merged = true;
    for (int k = 0; k < Npasses; k++) merged = merged && passes[k].pass != RS_SYNTH_PASS_COLOUR;
    rs_status gst = write_geometry(f, vehicles, passes, Npasses, merged, err);
    if (gst) return gst;
    fprintf(f, "#switch (frame_number)\n");
    for (int k = 0; k < Npasses; k++) {
        fprintf(f, "#case (%d) // %s pass\n", k + 1, pass_name(passes[k].pass));
        rs_status st = write_body(f, cam, fxy, ground_normal_enu, ground_offset_m, vehicles, &passes[k], merged, err);
        if (st) return st;
        fprintf(f, "#break\n");
    }
    fprintf(f, "#end\n");
    if (ferror(f)) return rs_err_set(err, RS_ERR_IO, "writing the scene: stream error");
    return RS_OK;
}

rs_status rs_synth_scene_write_ini(const char *ini_path, const char *pov_path, const rs_synth_povcam *cam,
                                   rs_synth_pass pass, int antialias, rs_err *err)
{
    const char *base = strrchr(pov_path, '/');
    base = base ? base + 1 : pov_path;
    char out_name[4096];
    snprintf(out_name, sizeof(out_name), "%s", base);
    char *dot = strrchr(out_name, '.');
    if (dot) *dot = 0;
    for (const char *c = base; *c; c++)
        if (!(isalnum((unsigned char)*c) || *c == '_' || *c == '.' || *c == '-'))
            return rs_err_set(err, RS_ERR_INVALID, "%s: the scene's file name may only use [A-Za-z0-9_.-]", pov_path);
    char ini_base[256];
    rs_synth_safe_text(ini_base, sizeof(ini_base), strrchr(ini_path, '/') ? strrchr(ini_path, '/') + 1 : ini_path);
    char text[8192];
    const bool id_pass = pass == RS_SYNTH_PASS_ID;
    const int len = snprintf(text, sizeof(text),
                             "; Written by roadside: renders %s (%s pass) at the camera's exact size.\n"
                             "; Run from this folder: povray %s\n"
                             "Input_File_Name=%s\nOutput_File_Name=%s.png\nOutput_File_Type=N\n"
                             "Width=%d\nHeight=%d\nAntialias=Off\nJitter=Off\nOutput_Alpha=%s\nBits_Per_Color=%d\n"
                             "File_Gamma=1.0\nDisplay=Off\nPause_When_Done=Off\nVerbose=Off\n",
                             base, id_pass ? "object-ID" : "colour", ini_base, base, out_name, cam->width, cam->height,
                             id_pass ? "Off" : "On", id_pass ? 8 : 16);
    if (len < 0 || (size_t)len >= sizeof(text)) return rs_err_set(err, RS_ERR_INVALID, "%s: name too long", ini_path);
    int total = len;
    if (antialias >= 2 && !id_pass)
        total += snprintf(text + len, sizeof(text) - (size_t)len,
                          "Antialias=On\nSampling_Method=1\nAntialias_Threshold=0.0\n"
                          "Antialias_Depth=%d\n",
                          antialias > 9 ? 9 : antialias);
    return rs_io_write_file(ini_path, text, (size_t)total, err);
}

rs_status rs_synth_scene_write_ini_frames(const char *ini_path, const char *pov_path, const rs_synth_povcam *cam,
                                          int Nframes, int antialias, rs_err *err)
{
    if (Nframes < 1 || Nframes > 9)
        return rs_err_set(err, RS_ERR_USAGE, "rs_synth_scene_write_ini_frames: %d frames (1..9)", Nframes);
    const char *base = strrchr(pov_path, '/');
    base = base ? base + 1 : pov_path;
    for (const char *c = base; *c; c++)
        if (!(isalnum((unsigned char)*c) || *c == '_' || *c == '.' || *c == '-'))
            return rs_err_set(err, RS_ERR_INVALID, "%s: the scene's file name may only use [A-Za-z0-9_.-]", pov_path);
    char out_name[256];
    snprintf(out_name, sizeof(out_name), "%s", base);
    char *dot = strrchr(out_name, '.');
    if (dot) *dot = 0;
    char text[4096];
    int len = snprintf(text, sizeof(text),
                       "; Written by roadside: renders the %d frames of %s (one pass each) at the\n"
                       "; camera's exact size, as %s1.png .. %s%d.png.\n"
                       "Input_File_Name=%s\nOutput_File_Name=%s.png\nOutput_File_Type=N\n"
                       "Width=%d\nHeight=%d\nAntialias=Off\nJitter=Off\nOutput_Alpha=On\n"
                       "Bits_Per_Color=16\nFile_Gamma=1.0\nDisplay=Off\nPause_When_Done=Off\n"
                       "Verbose=Off\nInitial_Frame=1\nFinal_Frame=%d\nCyclic_Animation=Off\n",
                       Nframes, base, out_name, out_name, Nframes, base, out_name, cam->width, cam->height, Nframes);
    if (len < 0 || (size_t)len >= sizeof(text)) return rs_err_set(err, RS_ERR_INVALID, "%s: name too long", ini_path);
    if (antialias >= 2)
        len += snprintf(text + len, sizeof(text) - (size_t)len,
                        "Antialias=On\nSampling_Method=1\nAntialias_Threshold=0.0\n"
                        "Antialias_Depth=%d\n",
                        antialias > 9 ? 9 : antialias);
    return rs_io_write_file(ini_path, text, (size_t)len, err);
}
