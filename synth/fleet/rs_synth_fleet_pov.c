// rs_synth_fleet_pov.c -- meshes as POV-Ray mesh2 declarations (one per part with its texture,
// or bare), the placement of a declared vehicle, and the vehicle frame -> site ENU map.
// The axes are explained at the top of synth/fleet/rs_synth_fleet.h.
#include "synth/fleet/rs_synth_fleet.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "synth/fleet/internal/rs_synth_fleet_internal.h"

int rs_synth_fleet_valid_identifier(const char *s)
{
    if (!s || !*s || strlen(s) > 40) return 0;
    if (!((s[0] >= 'A' && s[0] <= 'Z') || s[0] == '_')) return 0;
    for (const char *p = s; *p; p++)
        if (!((*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') || *p == '_')) return 0;
    return 1;
}

void rs_synth_fleet_texture_name(char *out, size_t n, const char *prefix, int k)
{
    snprintf(out, n, "rs_tex_%s_%d.png", prefix, k);
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
// layered texture, transparent where clean; its turbulence in 3 octaves, not POV-Ray's 6: the
// finer three, 12 % of its amplitude at 4.5 - 18 cm, cost 2 % of a colour pass's instructions
// at every hit for detail a pixel does not hold).
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
                "    texture { pigment { gradient y turbulence 0.25 octaves 3 colour_map { [0 rgbt <0.30, 0.27, 0.22, "
                "%.3f>] "
                "[0.3 rgbt <0.34, 0.31, 0.26, %.3f>] [0.65 rgbt <0.34, 0.31, 0.26, 1>] [1 rgbt <0.34, 0.31, 0.26, 1>] "
                "} scale <1, %.4f, 1> } finish { ambient 0 diffuse 0.7 specular 0 } }\n",
                1 - 0.85 * d, 1 - 0.45 * d, 0.999 * height_m);
    }
    if (look->snow > 0.02) { // issue 40: snow where the surface faces up (slope y: 1 up, 0.5 vertical)
        const double s = look->snow > 1 ? 1 : look->snow;
        fprintf(f,
                "    texture { pigment { slope y colour_map { [0 rgbt <0.92, 0.93, 0.95, 1>] [%.3f rgbt <0.92, 0.93, "
                "0.95, 1>] [%.3f rgbt <0.92, 0.93, 0.95, %.3f>] [1 rgbt <0.92, 0.93, 0.95, %.3f>] } } "
                "finish { ambient 0 diffuse 0.9 specular 0.05 roughness 0.1 } }\n",
                0.80, 0.88, 1 - 0.7 * s, 1 - 0.97 * s);
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

// Whether triangle t is in the group written: part `part` (< 0: any) and material `mat` (< 0:
// any; a mesh with materials only).
static bool selected(const rs_synth_mesh *m, int t, int part, int mat)
{
    return (part < 0 || m->part[t] == part) && (mat < 0 || m->material[t] == mat);
}

// One mesh2 of the triangles of `part` and `mat` (< 0: all), its vertices renumbered. Compact (the
// scene's shared geometry): vectors on one line, vertices to 1e-5 m, normals to 1e-4, and
// normals only when `normals` (smooth shading where it shows); else one vector per line,
// vertices to 1e-6 m, normals to 1e-5, whenever the mesh has them. A textured material's
// triangles also get their texture coordinates (uv_vectors, 6 digits, numbered as the vertices;
// uv_indices in the long form only: without them POV-Ray takes face_indices, the same numbers,
// and the compact form saves a third of a textured model's text).
static int write_mesh2(FILE *f, const rs_synth_mesh *m, int part, int mat, int *map, bool compact, bool normals)
{
    const int dv = compact ? 5 : 6, dn = compact ? 4 : 5;
    const char *sep = compact ? "" : "    ";
    int Nv = 0, Nt = 0;
    for (int i = 0; i < m->Nv; i++) map[i] = -1;
    for (int t = 0; t < m->Ntri; t++)
        if (selected(m, t, part, mat)) {
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
            if (selected(m, t, part, mat))
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
    const bool with_uv = m->uv && mat >= 0 && m->materials[mat].texture >= 0;
    if (with_uv) {
        fprintf(f, "%suv_vectors { %d", sep, Nv);
        for (int j = 0; j < Nv; j++) {
            const double *uv = m->uv[inv[j]];
            if (compact)
                fprintf(f, ",<%.6g,%.6g>", uv[0], uv[1]);
            else
                fprintf(f, ",\n      <%.6f, %.6f>", uv[0], uv[1]);
        }
        fprintf(f, " }\n");
    }
    free(inv);
    free(ninv);
    // The map (x,y,z)_v -> (-y, z, x) has determinant -1 and POV-Ray's frame is left-handed: a
    // triangle keeps its outward side, whatever the order; the order is kept.
    // face_indices, then normal_indices and uv_indices when written
    for (int pass = 0; pass < 3; pass++) {
        if ((pass == 1 && !with_n) || (pass == 2 && !(with_uv && !compact))) continue;
        fprintf(f, "%s%s { %d", sep, pass == 1 ? "normal_indices" : pass == 2 ? "uv_indices" : "face_indices", Nt);
        for (int t = 0; t < m->Ntri; t++)
            if (selected(m, t, part, mat)) {
                const int *q = pass == 1 && nmap ? m->tri_n[t] : m->tri[t];
                const int *mp = pass == 1 && nmap ? nmap : map;
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
    } else if (look && look->lights_on && (part == RS_SYNTH_PART_HEADLIGHT || part == RS_SYNTH_PART_TAILLIGHT)) {
        // issue 40: lights on, their lens glowing (emission adds to what the finish reflects)
        const bool head = part == RS_SYNTH_PART_HEADLIGHT;
        const double e = head ? RS_SYNTH_HEADLIGHT_EMISSION : RS_SYNTH_TAILLIGHT_EMISSION;
        fprintf(f,
                "    texture { %s }\n    texture { pigment { rgbt <%.4f, %.4f, %.4f, 0.3> } finish { emission 1 "
                "ambient 0 diffuse 0 specular 0 } }\n",
                part_textures[part], e, e * (head ? 0.96 : 0.04), e * (head ? 0.88 : 0.03));
    } else
        fprintf(f, "    texture { %s }\n", part_textures[part]);
    fprintf(f, "    %s\n", INTERIOR_TEXTURE);
    if (needs_ior(part)) fprintf(f, "    interior { ior 1.5 }\n");
    // the see-through glass casts no shadow in the colour pass (the sun's shadow rays would
    // otherwise be filtered through every window: 11 % more mesh tests); the shadow pass, of
    // bare opaque meshes, still has the whole vehicle's shadow
    if (part == RS_SYNTH_PART_GLASS) fprintf(f, "    no_shadow\n");
}

// A mesh's groups, one mesh2 each: its materials (a user model) or its parts.
static int n_groups(const rs_synth_mesh *m) { return m->materials ? m->Nmaterials : RS_SYNTH_NPARTS; }
static int group_part(const rs_synth_mesh *m, int g) { return m->materials ? -1 : g; }
static int group_mat(const rs_synth_mesh *m, int g) { return m->materials ? g : -1; }

// A user model's material as a POV-Ray texture (rs_synth_material): its image through the
// texture coordinates (uv_mapping image_map, the PNG rs_synth_fleet_write_textures writes under
// `prefix`) or its colour, a Phong highlight, metals reflecting tinted, and below full opacity
// a clear surface reflecting with Fresnel's law (glass; interior ior 1.5).
static void write_material(FILE *f, const rs_synth_material *mt, const char *prefix)
{
    const double t = 1 - mt->opacity;
    if (mt->texture >= 0) {
        char name[96];
        rs_synth_fleet_texture_name(name, sizeof name, prefix, mt->texture);
        fprintf(f, "    texture { uv_mapping pigment { image_map { png \"%s\" interpolate 2", name);
        if (t > 0) fprintf(f, " transmit all %.4f", t);
        fprintf(f, " } }");
    } else
        fprintf(f, "    texture { pigment { rgbt <%.6f, %.6f, %.6f, %.4f> }", mt->rgb[0], mt->rgb[1], mt->rgb[2], t);
    fprintf(f, " finish { ambient 0 diffuse %.3f specular %.4f roughness %.5f", 0.8 * (1 - 0.9 * mt->metallic),
            mt->specular, mt->roughness > 1e-5 ? mt->roughness : 1e-5);
    if (mt->metallic > 0) fprintf(f, " metallic %.4f reflection { %.4f metallic }", mt->metallic, 0.8 * mt->metallic);
    if (t > 0) fprintf(f, " reflection { 0.04, 1 fresnel on } conserve_energy");
    fprintf(f, " } }\n");
    if (t > 0) fprintf(f, "    interior { ior 1.5 }\n");
}

// Group g's look, written inside its object: a part's (write_part_look) or a material's; a paint
// material gets the vehicle's paint, or no texture when look is NULL (the instance's applies).
static void write_group_look(FILE *f, const rs_synth_mesh *mesh, int g, const rs_synth_look *look, const char *prefix)
{
    if (!mesh->materials) {
        write_part_look(f, mesh, g, look);
        return;
    }
    if (!mesh->materials[g].paint)
        write_material(f, &mesh->materials[g], prefix);
    else if (look)
        write_part_look(f, mesh, RS_SYNTH_PART_PAINT, look);
}

// Whether look's paint is a colour in [0, 1]; a user model may go without (look NULL: its paint
// materials take the instance's texture).
static bool paint_ok(const rs_synth_mesh *mesh, const rs_synth_look *look)
{
    if (!look) return mesh->materials != NULL;
    const double *c = look->paint_rgb;
    return c[0] >= 0 && c[0] <= 1 && c[1] >= 0 && c[1] <= 1 && c[2] >= 0 && c[2] <= 1;
}

rs_status rs_synth_fleet_write_declare(FILE *f, const char *name, const rs_synth_mesh *mesh,
                                       rs_synth_declare_style style, const double paint_rgb[3], rs_err *err)
{
    rs_synth_look look = {{0, 0, 0}, 0, 0, false, 0};
    if (paint_rgb)
        for (int c = 0; c < 3; c++) look.paint_rgb[c] = paint_rgb[c];
    else if (style == RS_SYNTH_DECLARE_TEXTURED)
        look.paint_rgb[0] = -1; // refused below
    return rs_synth_fleet_write_declare_look(f, name, mesh, style, &look, err);
}

rs_status rs_synth_fleet_write_declare_look(FILE *f, const char *name, const rs_synth_mesh *mesh,
                                            rs_synth_declare_style style, const rs_synth_look *look, rs_err *err)
{
    if (!rs_synth_fleet_valid_identifier(name))
        return rs_err_set(err, RS_ERR_INVALID,
                          "declare: name is not an upper-case POV-Ray identifier of at most 40 "
                          "characters");
    if (mesh->Ntri == 0) return rs_err_set(err, RS_ERR_INVALID, "declare %s: empty mesh", name);
    if (style == RS_SYNTH_DECLARE_TEXTURED && !paint_ok(mesh, look))
        return rs_err_set(err, RS_ERR_INVALID, "declare %s: paint not in [0, 1]", name);
    int *map = malloc((size_t)(mesh->Nv > 0 ? mesh->Nv : 1) * sizeof *map);
    if (!map) return rs_err_set(err, RS_ERR_NOMEM, "declare %s: out of memory", name);
    int rc = 0;
    if (style == RS_SYNTH_DECLARE_BARE) {
        fprintf(f, "#declare %s =\n", name);
        rc = write_mesh2(f, mesh, -1, -1, map, false, true);
        fprintf(f, "  }\n");
    } else {
        fprintf(f, "#declare %s = union {\n", name);
        for (int g = 0; g < n_groups(mesh) && rc >= 0; g++) {
            rc = write_mesh2(f, mesh, group_part(mesh, g), group_mat(mesh, g), map, false, true);
            if (rc <= 0) continue;
            write_group_look(f, mesh, g, look, name);
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
    if (!rs_synth_fleet_valid_identifier(prefix) || strlen(prefix) > 37)
        return rs_err_set(err, RS_ERR_INVALID,
                          "parts: prefix is not an upper-case POV-Ray identifier of at most 37 characters");
    if (mesh->Ntri == 0) return rs_err_set(err, RS_ERR_INVALID, "parts %s: empty mesh", prefix);
    int *map = malloc((size_t)(mesh->Nv > 0 ? mesh->Nv : 1) * sizeof *map);
    if (!map) return rs_err_set(err, RS_ERR_NOMEM, "parts %s: out of memory", prefix);
    int rc = 0;
    for (int g = 0; g < n_groups(mesh) && rc >= 0; g++) {
        const int part = group_part(mesh, g), mat = group_mat(mesh, g);
        bool used = false;
        for (int t = 0; t < mesh->Ntri && !used; t++) used = selected(mesh, t, part, mat);
        if (!used) continue;
        fprintf(f, "#declare %s_%d =\n", prefix, g);
        rc = write_mesh2(f, mesh, part, mat, map, true, part < 0 || part_smooth(part));
        fprintf(f, "  }\n");
    }
    free(map);
    if (rc < 0) return rs_err_set(err, RS_ERR_NOMEM, "parts %s: out of memory", prefix);
    if (ferror(f)) return rs_err_set(err, RS_ERR_IO, "parts %s: write failed", prefix);
    return RS_OK;
}

rs_status rs_synth_fleet_write_merged(FILE *f, const char *name, const rs_synth_mesh *mesh, rs_err *err)
{
    if (!rs_synth_fleet_valid_identifier(name))
        return rs_err_set(err, RS_ERR_INVALID, "merged: name is not an upper-case POV-Ray identifier");
    if (mesh->Ntri == 0) return rs_err_set(err, RS_ERR_INVALID, "merged %s: empty mesh", name);
    int *map = malloc((size_t)(mesh->Nv > 0 ? mesh->Nv : 1) * sizeof *map);
    if (!map) return rs_err_set(err, RS_ERR_NOMEM, "merged %s: out of memory", name);
    fprintf(f, "#declare %s =\n", name);
    const int rc = write_mesh2(f, mesh, -1, -1, map, true, false);
    fprintf(f, "  }\n");
    free(map);
    if (rc < 0) return rs_err_set(err, RS_ERR_NOMEM, "merged %s: out of memory", name);
    if (ferror(f)) return rs_err_set(err, RS_ERR_IO, "merged %s: write failed", name);
    return RS_OK;
}

rs_status rs_synth_fleet_write_instance(FILE *f, const char *name, const char *prefix, const rs_synth_mesh *mesh,
                                        rs_synth_declare_style style, const rs_synth_look *look, rs_err *err)
{
    if (!rs_synth_fleet_valid_identifier(name) || !rs_synth_fleet_valid_identifier(prefix) || strlen(prefix) > 37)
        return rs_err_set(err, RS_ERR_INVALID, "instance: name or prefix is not an upper-case POV-Ray identifier");
    if (mesh->Ntri == 0) return rs_err_set(err, RS_ERR_INVALID, "instance %s: empty mesh", name);
    if (style == RS_SYNTH_DECLARE_TEXTURED && !paint_ok(mesh, look))
        return rs_err_set(err, RS_ERR_INVALID, "instance %s: paint not in [0, 1]", name);
    const int G = n_groups(mesh);
    bool *used = calloc((size_t)G, sizeof *used);
    if (!used) return rs_err_set(err, RS_ERR_NOMEM, "instance %s: out of memory", name);
    int Nused = 0;
    for (int t = 0; t < mesh->Ntri; t++) {
        const int g = mesh->materials ? mesh->material[t] : mesh->part[t];
        if (g < G && !used[g]) used[g] = true, Nused++;
    }
    if (Nused == 1 && style == RS_SYNTH_DECLARE_BARE) {
        for (int g = 0; g < G; g++)
            if (used[g]) fprintf(f, "#declare %s = object { %s_%d }\n", name, prefix, g);
    } else {
        fprintf(f, "#declare %s = union {\n", name);
        for (int g = 0; g < G; g++) {
            if (!used[g]) continue;
            fprintf(f, "  object { %s_%d", prefix, g);
            if (style == RS_SYNTH_DECLARE_TEXTURED) {
                fprintf(f, "\n");
                write_group_look(f, mesh, g, look, prefix);
            }
            fprintf(f, " }\n");
        }
        fprintf(f, "}\n");
    }
    free(used);
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
