// rs_synth_fleet_pov.c -- meshes as POV-Ray mesh2 declarations (one per part with its texture,
// or bare), the placement of a declared vehicle, and the vehicle frame -> site ENU map.
// The axes are explained at the top of synth/fleet/rs_synth_fleet.h.
#include "synth/fleet/rs_synth_fleet.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "synth/fleet/internal/rs_synth_fleet_internal.h"

static int valid_identifier(const char *s)
{
    if (!s || !*s || strlen(s) > 40) return 0;
    if (!((s[0] >= 'A' && s[0] <= 'Z') || s[0] == '_')) return 0;
    for (const char *p = s; *p; p++)
        if (!((*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') || *p == '_')) return 0;
    return 1;
}

// Built-in textures of the fixed parts (paint is written from the vehicle's look). The glass,
// lights and paint reflect with Fresnel's law (reflection { min, max fresnel on } with the
// object's interior ior 1.5): 4 % head-on, rising to 100 % at grazing angles; conserve_energy
// takes the reflected light out of the diffuse and transmitted parts. The glass transmits 75 %
// of what it does not reflect (issue 40): head-on a window shows the dark cabin behind it
// (INTERIOR_TEXTURE), at grazing angles the environment. Chrome and rims reflect like metals
// (tinted, no Fresnel). No ambient: the sky lights and the environment light everything.
static const char *const part_textures[RS_SYNTH_NPARTS] = {
    NULL,
    "pigment { rgbt <0.010, 0.012, 0.015, 0.75> } finish { ambient 0 diffuse 0.1 specular 0.9 roughness 0.001 "
    "reflection { 0.04, 1 fresnel on } conserve_energy }",
    "pigment { rgb <0.80, 0.80, 0.78> } finish { ambient 0 diffuse 0.3 specular 0.9 roughness 0.002 "
    "reflection { 0.25 metallic } }",
    "pigment { rgb <0.35, 0.010, 0.012> } finish { ambient 0 diffuse 0.5 specular 0.8 roughness 0.003 "
    "reflection { 0.04, 0.6 fresnel on } conserve_energy }",
    "pigment { rgb <0.018, 0.018, 0.02> } finish { ambient 0 diffuse 0.7 specular 0.03 roughness 0.1 }",
    "pigment { rgb <0.55, 0.56, 0.58> } finish { ambient 0 diffuse 0.4 specular 0.6 roughness 0.01 metallic "
    "reflection { 0.15 metallic } }",
    "pigment { rgb <0.03, 0.03, 0.035> } finish { ambient 0 diffuse 0.6 specular 0.15 roughness 0.04 }",
    "pigment { gradient x colour_map { [0 rgb <0.85, 0.85, 0.82>] [0.55 rgb <0.85, 0.85, 0.82>] "
    "[0.55 rgb 0.25] [0.75 rgb 0.25] [0.75 rgb <0.85, 0.85, 0.82>] } scale 0.07 } "
    "finish { ambient 0 diffuse 0.85 specular 0.1 }",
    "pigment { rgb <0.75, 0.75, 0.78> } finish { ambient 0 diffuse 0.05 specular 0.8 roughness 0.002 metallic "
    "reflection { 0.65 metallic } }",
    "pigment { rgb <0.06, 0.07, 0.10> } finish { ambient 0 diffuse 0.8 specular 0.05 roughness 0.08 }",
};
// The cabin seen through the glass (issue 40): the back side of every face of the body (its
// meshes are closed and wound outward, so a ray through a window meets the inside of a door,
// the floor, the roof or the far window), black: unlit, so POV-Ray spends no light or shadow
// ray on it (a dark grey lit interior, rgb 0.025 diffuse 0.6, cost 6 % more mesh tests in the
// colour pass for a cabin about 2 % as bright as the body: docs/benchmarks.md, issue 40).
#define INTERIOR_TEXTURE "interior_texture { pigment { rgb 0 } finish { ambient 0 diffuse 0 specular 0 } }"

// parts whose finish uses Fresnel reflection, which needs the object's index of refraction
static int needs_ior(int part)
{
    return part == RS_SYNTH_PART_PAINT || part == RS_SYNTH_PART_GLASS || part == RS_SYNTH_PART_TAILLIGHT;
}

// Car paint: a base coat (solid or metallic: highlights tinted by the paint, brilliance) under
// a clear coat (Fresnel reflection, untinted), and a film of dirt rising from the sills (a
// layered texture, transparent where clean).
static void write_paint(FILE *f, const rs_synth_look *look, double height_m)
{
    const double *c = look->paint_rgb, m = look->metallic;
    fprintf(f,
            "    texture { pigment { rgb <%.6f, %.6f, %.6f> } finish { ambient 0 diffuse 0.75 brilliance %.3f "
            "specular %.3f roughness %.4f metallic %.3f reflection { 0.03, 0.9 fresnel on } conserve_energy } }\n",
            c[0], c[1], c[2], 1 + 2 * m, 0.5 + 0.3 * m, 0.004 + 0.01 * m, m);
    if (look->dirt > 0.02) {
        const double d = look->dirt > 1 ? 1 : look->dirt;
        fprintf(f,
                "    texture { pigment { gradient y turbulence 0.25 colour_map { [0 rgbt <0.30, 0.27, 0.22, %.3f>] "
                "[0.3 rgbt <0.34, 0.31, 0.26, %.3f>] [0.65 rgbt <0.34, 0.31, 0.26, 1>] [1 rgbt <0.34, 0.31, 0.26, 1>] "
                "} scale <1, %.4f, 1> } finish { ambient 0 diffuse 0.7 specular 0 } }\n",
                1 - 0.85 * d, 1 - 0.45 * d, 0.999 * height_m);
    }
}

// Appends x with `decimals` (<= 9) digits after the point, trailing zeros and a leading "0"
// dropped (POV-Ray reads "-.25" and "3"), at p; returns the end. Integer arithmetic on
// x * 10^decimals rounded half away from zero: printf's "%.*f" rounds the exact binary value,
// so the two can differ only for x within about 1e-16 |x| of a half step (a real scene's
// 1.6 MB of meshes came out byte for byte the same). |x| >= 9e18 / 10^decimals is written as 0.
// Issue 18's cost: writing the meshes with printf was 3 to 4 % of `roadside synth`'s CPU.
static char *fmt_fixed(char *p, double x, int decimals)
{
    static const long long scale[10] = {1, 10, 100, 1000, 10000, 100000, 1000000, 10000000, 100000000, 1000000000};
    const double y = x * (double)scale[decimals];
    long long q = fabs(y) < 9e18 ? llround(y) : 0;
    if (q == 0) {
        *p++ = '0';
        return p;
    }
    if (q < 0) *p++ = '-', q = -q;
    long long ip = q / scale[decimals], fp = q % scale[decimals];
    char tmp[24];
    int n = 0;
    if (ip > 0) {
        do tmp[n++] = (char)('0' + ip % 10);
        while ((ip /= 10) > 0);
        while (n > 0) *p++ = tmp[--n];
    }
    if (fp > 0) {
        int d = decimals;
        while (fp % 10 == 0) fp /= 10, d--;
        *p++ = '.';
        for (int k = d - 1; k >= 0; k--) p[k] = (char)('0' + fp % 10), fp /= 10;
        p += d;
    }
    return p;
}

// Appends a non-negative integer at p; returns the end.
static char *fmt_int(char *p, int v)
{
    char tmp[12];
    int n = 0;
    do tmp[n++] = (char)('0' + v % 10);
    while ((v /= 10) > 0);
    while (n > 0) *p++ = tmp[--n];
    return p;
}

static void put_vec(FILE *f, double a, double b, double c, int decimals, bool compact)
{
    if (!compact) {
        fprintf(f, ",\n      <%.*f, %.*f, %.*f>", decimals, a, decimals, b, decimals, c);
        return;
    }
    char buf[128], *p = buf;
    *p++ = ',', *p++ = '<';
    p = fmt_fixed(p, a, decimals), *p++ = ',';
    p = fmt_fixed(p, b, decimals), *p++ = ',';
    p = fmt_fixed(p, c, decimals), *p++ = '>';
    fwrite(buf, 1, (size_t)(p - buf), f);
}

// One mesh2 of the triangles of `part` (< 0: all), its vertices renumbered. Compact (the
// scene's shared geometry): vectors on one line, vertices to 1e-5 m, normals to 1e-4, and
// normals only when `normals` (smooth shading where it shows); else one vector per line,
// vertices to 1e-6 m, normals to 1e-5, whenever the mesh has them.
static int write_mesh2(FILE *f, const rs_synth_mesh *m, int part, int *map, bool compact, bool normals)
{
    const int dv = compact ? 5 : 6, dn = compact ? 4 : 5;
    const char *sep = compact ? "" : "    ";
    int Nv = 0, Nt = 0;
    for (int i = 0; i < m->Nv; i++) map[i] = -1;
    for (int t = 0; t < m->Ntri; t++)
        if (part < 0 || m->part[t] == part) {
            Nt++;
            for (int k = 0; k < 3; k++)
                if (map[m->tri[t][k]] < 0) map[m->tri[t][k]] = Nv++;
        }
    if (Nt == 0) return 0;
    // vertices in the order of their new numbers
    int *inv = malloc((size_t)Nv * sizeof *inv);
    if (!inv) return -1;
    for (int i = 0; i < m->Nv; i++)
        if (map[i] >= 0) inv[map[i]] = i;
    fprintf(f, "  mesh2 {\n%svertex_vectors { %d", sep, Nv);
    for (int j = 0; j < Nv; j++) {
        const double *p = m->v[inv[j]];
        put_vec(f, -p[1], p[2], p[0], dv, compact);
    }
    fprintf(f, " }\n");
    // normals: per vertex (OBJ), or per corner through tri_n, renumbered like the vertices
    const bool with_n = m->vn && normals;
    int Nnorm = 0, *nmap = NULL, *ninv = NULL;
    if (with_n && m->tri_n) {
        nmap = malloc((size_t)(m->Nn > 0 ? m->Nn : 1) * sizeof *nmap);
        ninv = malloc((size_t)(m->Nn > 0 ? m->Nn : 1) * sizeof *ninv);
        if (!nmap || !ninv) {
            free(inv), free(nmap), free(ninv);
            return -1;
        }
        for (int i = 0; i < m->Nn; i++) nmap[i] = -1;
        for (int t = 0; t < m->Ntri; t++)
            if (part < 0 || m->part[t] == part)
                for (int k = 0; k < 3; k++)
                    if (nmap[m->tri_n[t][k]] < 0) ninv[Nnorm] = m->tri_n[t][k], nmap[m->tri_n[t][k]] = Nnorm++;
    } else if (with_n) {
        Nnorm = Nv;
    }
    if (with_n) {
        fprintf(f, "%snormal_vectors { %d", sep, Nnorm);
        for (int j = 0; j < Nnorm; j++) {
            const double *n = m->vn[ninv ? ninv[j] : inv[j]];
            put_vec(f, -n[1], n[2], n[0], dn, compact);
        }
        fprintf(f, " }\n");
    }
    free(inv);
    free(ninv);
    // The map (x,y,z)_v -> (-y, z, x) has determinant -1 and POV-Ray's frame is left-handed: a
    // triangle keeps its outward side, whatever the order; the order is kept.
    for (int pass = 0; pass < (with_n ? 2 : 1); pass++) {
        fprintf(f, "%s%s { %d", sep, pass ? "normal_indices" : "face_indices", Nt);
        for (int t = 0; t < m->Ntri; t++)
            if (part < 0 || m->part[t] == part) {
                const int *q = pass && nmap ? m->tri_n[t] : m->tri[t];
                const int *mp = pass && nmap ? nmap : map;
                if (compact) {
                    char buf[48], *p = buf;
                    *p++ = ',', *p++ = '<';
                    p = fmt_int(p, mp[q[0]]), *p++ = ',';
                    p = fmt_int(p, mp[q[1]]), *p++ = ',';
                    p = fmt_int(p, mp[q[2]]), *p++ = '>';
                    fwrite(buf, 1, (size_t)(p - buf), f);
                } else
                    fprintf(f, ",\n      <%d, %d, %d>", mp[q[0]], mp[q[1]], mp[q[2]]);
            }
        fprintf(f, " }\n");
    }
    free(nmap);
    return 1;
}

// A part's look, written inside its object: the paint (its height sets the dirt's gradient) or
// the part's texture, then glass's and chrome's interior.
static void write_part_look(FILE *f, const rs_synth_mesh *mesh, int part, const rs_synth_look *look)
{
    if (part == RS_SYNTH_PART_PAINT) {
        double lo[3], hi[3];
        rs_synth_mesh_bounds(lo, hi, mesh);
        write_paint(f, look, hi[2] > 0 ? hi[2] : 1);
    } else
        fprintf(f, "    texture { %s }\n", part_textures[part]);
    fprintf(f, "    %s\n", INTERIOR_TEXTURE);
    if (needs_ior(part)) fprintf(f, "    interior { ior 1.5 }\n");
    // the see-through glass casts no shadow in the colour pass (the sun's shadow rays would
    // otherwise be filtered through every window: 11 % more mesh tests); the shadow pass, of
    // bare opaque meshes, still has the whole vehicle's shadow
    if (part == RS_SYNTH_PART_GLASS) fprintf(f, "    no_shadow\n");
}

rs_status rs_synth_fleet_write_declare(FILE *f, const char *name, const rs_synth_mesh *mesh,
                                       rs_synth_declare_style style, const double paint_rgb[3], rs_err *err)
{
    rs_synth_look look = {{0, 0, 0}, 0, 0};
    if (paint_rgb)
        for (int c = 0; c < 3; c++) look.paint_rgb[c] = paint_rgb[c];
    else if (style == RS_SYNTH_DECLARE_TEXTURED)
        look.paint_rgb[0] = -1; // refused below
    return rs_synth_fleet_write_declare_look(f, name, mesh, style, &look, err);
}

rs_status rs_synth_fleet_write_declare_look(FILE *f, const char *name, const rs_synth_mesh *mesh,
                                            rs_synth_declare_style style, const rs_synth_look *look, rs_err *err)
{
    const double *paint_rgb = look ? look->paint_rgb : NULL;
    if (!valid_identifier(name))
        return rs_err_set(err, RS_ERR_INVALID,
                          "declare: name is not an upper-case POV-Ray identifier of at most 40 "
                          "characters");
    if (mesh->Ntri == 0) return rs_err_set(err, RS_ERR_INVALID, "declare %s: empty mesh", name);
    if (style == RS_SYNTH_DECLARE_TEXTURED &&
        !(paint_rgb && paint_rgb[0] >= 0 && paint_rgb[0] <= 1 && paint_rgb[1] >= 0 && paint_rgb[1] <= 1 &&
          paint_rgb[2] >= 0 && paint_rgb[2] <= 1))
        return rs_err_set(err, RS_ERR_INVALID, "declare %s: paint not in [0, 1]", name);
    int *map = malloc((size_t)(mesh->Nv > 0 ? mesh->Nv : 1) * sizeof *map);
    if (!map) return rs_err_set(err, RS_ERR_NOMEM, "declare %s: out of memory", name);
    int rc = 0;
    if (style == RS_SYNTH_DECLARE_BARE) {
        fprintf(f, "#declare %s =\n", name);
        rc = write_mesh2(f, mesh, -1, map, false, true);
        fprintf(f, "  }\n");
    } else {
        fprintf(f, "#declare %s = union {\n", name);
        for (int part = 0; part < RS_SYNTH_NPARTS && rc >= 0; part++) {
            rc = write_mesh2(f, mesh, part, map, false, true);
            if (rc <= 0) continue;
            write_part_look(f, mesh, part, look);
            fprintf(f, "  }\n");
        }
        fprintf(f, "}\n");
    }
    free(map);
    if (rc < 0) return rs_err_set(err, RS_ERR_NOMEM, "declare %s: out of memory", name);
    if (ferror(f)) return rs_err_set(err, RS_ERR_IO, "declare %s: write failed", name);
    return RS_OK;
}

// Smooth normals where they show at a vehicle's size in the image: the lofted body (paint) and
// its glazing. Wheels, lights, plates, trims, chrome and riders are flat-shaded facets of a few
// pixels each.
static bool part_smooth(int part) { return part == RS_SYNTH_PART_PAINT || part == RS_SYNTH_PART_GLASS; }

rs_status rs_synth_fleet_write_parts(FILE *f, const char *prefix, const rs_synth_mesh *mesh, rs_err *err)
{
    if (!valid_identifier(prefix) || strlen(prefix) > 37)
        return rs_err_set(err, RS_ERR_INVALID,
                          "parts: prefix is not an upper-case POV-Ray identifier of at most 37 characters");
    if (mesh->Ntri == 0) return rs_err_set(err, RS_ERR_INVALID, "parts %s: empty mesh", prefix);
    int *map = malloc((size_t)(mesh->Nv > 0 ? mesh->Nv : 1) * sizeof *map);
    if (!map) return rs_err_set(err, RS_ERR_NOMEM, "parts %s: out of memory", prefix);
    int rc = 0;
    for (int part = 0; part < RS_SYNTH_NPARTS && rc >= 0; part++) {
        bool used = false;
        for (int t = 0; t < mesh->Ntri && !used; t++) used = mesh->part[t] == part;
        if (!used) continue;
        fprintf(f, "#declare %s_%d =\n", prefix, part);
        rc = write_mesh2(f, mesh, part, map, true, part_smooth(part));
        fprintf(f, "  }\n");
    }
    free(map);
    if (rc < 0) return rs_err_set(err, RS_ERR_NOMEM, "parts %s: out of memory", prefix);
    if (ferror(f)) return rs_err_set(err, RS_ERR_IO, "parts %s: write failed", prefix);
    return RS_OK;
}

rs_status rs_synth_fleet_write_merged(FILE *f, const char *name, const rs_synth_mesh *mesh, rs_err *err)
{
    if (!valid_identifier(name))
        return rs_err_set(err, RS_ERR_INVALID, "merged: name is not an upper-case POV-Ray identifier");
    if (mesh->Ntri == 0) return rs_err_set(err, RS_ERR_INVALID, "merged %s: empty mesh", name);
    int *map = malloc((size_t)(mesh->Nv > 0 ? mesh->Nv : 1) * sizeof *map);
    if (!map) return rs_err_set(err, RS_ERR_NOMEM, "merged %s: out of memory", name);
    fprintf(f, "#declare %s =\n", name);
    const int rc = write_mesh2(f, mesh, -1, map, true, false);
    fprintf(f, "  }\n");
    free(map);
    if (rc < 0) return rs_err_set(err, RS_ERR_NOMEM, "merged %s: out of memory", name);
    if (ferror(f)) return rs_err_set(err, RS_ERR_IO, "merged %s: write failed", name);
    return RS_OK;
}

rs_status rs_synth_fleet_write_instance(FILE *f, const char *name, const char *prefix, const rs_synth_mesh *mesh,
                                        rs_synth_declare_style style, const rs_synth_look *look, rs_err *err)
{
    const double *paint_rgb = look ? look->paint_rgb : NULL;
    if (!valid_identifier(name) || !valid_identifier(prefix) || strlen(prefix) > 37)
        return rs_err_set(err, RS_ERR_INVALID, "instance: name or prefix is not an upper-case POV-Ray identifier");
    if (mesh->Ntri == 0) return rs_err_set(err, RS_ERR_INVALID, "instance %s: empty mesh", name);
    if (style == RS_SYNTH_DECLARE_TEXTURED &&
        !(paint_rgb && paint_rgb[0] >= 0 && paint_rgb[0] <= 1 && paint_rgb[1] >= 0 && paint_rgb[1] <= 1 &&
          paint_rgb[2] >= 0 && paint_rgb[2] <= 1))
        return rs_err_set(err, RS_ERR_INVALID, "instance %s: paint not in [0, 1]", name);
    int Nparts = 0;
    bool used[RS_SYNTH_NPARTS] = {false};
    for (int t = 0; t < mesh->Ntri; t++)
        if (mesh->part[t] < RS_SYNTH_NPARTS && !used[mesh->part[t]]) used[mesh->part[t]] = true, Nparts++;
    if (Nparts == 1 && style == RS_SYNTH_DECLARE_BARE) {
        for (int part = 0; part < RS_SYNTH_NPARTS; part++)
            if (used[part]) fprintf(f, "#declare %s = object { %s_%d }\n", name, prefix, part);
    } else {
        fprintf(f, "#declare %s = union {\n", name);
        for (int part = 0; part < RS_SYNTH_NPARTS; part++) {
            if (!used[part]) continue;
            fprintf(f, "  object { %s_%d", prefix, part);
            if (style == RS_SYNTH_DECLARE_TEXTURED) {
                fprintf(f, "\n");
                write_part_look(f, mesh, part, look);
                fprintf(f, " ");
            } else
                fprintf(f, " ");
            fprintf(f, "}\n");
        }
        fprintf(f, "}\n");
    }
    if (ferror(f)) return rs_err_set(err, RS_ERR_IO, "instance %s: write failed", name);
    return RS_OK;
}

rs_status rs_synth_fleet_write_placement(FILE *f, const rs_synth_vehicle *v, double up_m, rs_err *err)
{
    if (!(isfinite(v->yaw_deg) && isfinite(v->e_m) && isfinite(v->n_m) && isfinite(up_m)))
        return rs_err_set(err, RS_ERR_INVALID, "placement: non-finite yaw or position");
    fprintf(f, " rotate <0, %.9f, 0> translate <%.6f, %.6f, %.6f>", v->yaw_deg, v->e_m, up_m, v->n_m);
    if (ferror(f)) return rs_err_set(err, RS_ERR_IO, "placement: write failed");
    return RS_OK;
}

void rs_synth_vehicle_to_enu(double p_enu_m[3], const rs_synth_vehicle *v, double up_m, const double p_v_m[3])
{
    double y = v->yaw_deg * M_PI / 180, s = sin(y), c = cos(y);
    double x = p_v_m[0], l = p_v_m[1], z = p_v_m[2];
    p_enu_m[0] = v->e_m + x * s - l * c;
    p_enu_m[1] = v->n_m + x * c + l * s;
    p_enu_m[2] = up_m + z;
}
