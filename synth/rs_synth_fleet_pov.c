// rs_synth_fleet_pov.c -- meshes as POV-Ray mesh2 declarations (one per part with its texture,
// or bare), the placement of a declared vehicle, and the vehicle frame -> site ENU map.
// The axes are explained at the top of synth/rs_synth_fleet.h.
#include "synth/rs_synth_fleet.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int valid_identifier(const char *s)
{
    if (!s || !*s || strlen(s) > 40) return 0;
    if (!((s[0] >= 'A' && s[0] <= 'Z') || s[0] == '_')) return 0;
    for (const char *p = s; *p; p++)
        if (!((*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') || *p == '_')) return 0;
    return 1;
}

// Built-in textures of the fixed parts (paint is written from the vehicle's colour).
static const char *const part_textures[RS_SYNTH_NPARTS] = {
    NULL,
    "pigment { rgb <0.015, 0.02, 0.025> } finish { specular 0.8 roughness 0.005 reflection 0.12 }",
    "pigment { rgb <0.85, 0.85, 0.80> } finish { specular 0.9 roughness 0.005 reflection 0.2 }",
    "pigment { rgb <0.45, 0.015, 0.02> } finish { specular 0.7 roughness 0.01 reflection 0.08 }",
    "pigment { rgb <0.018, 0.018, 0.02> } finish { specular 0.05 roughness 0.1 }",
    "pigment { rgb <0.30, 0.30, 0.32> } finish { specular 0.5 roughness 0.02 metallic }",
    "pigment { rgb <0.035, 0.035, 0.04> } finish { specular 0.2 roughness 0.05 }",
};

// One mesh2 of the triangles of `part` (< 0: all), its vertices renumbered.
static int write_mesh2(FILE *f, const rs_synth_mesh *m, int part, int *map)
{
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
    fprintf(f, "  mesh2 {\n    vertex_vectors { %d", Nv);
    for (int j = 0; j < Nv; j++) {
        const double *p = m->v[inv[j]];
        fprintf(f, ",\n      <%.6f, %.6f, %.6f>", -p[1], p[2], p[0]);
    }
    fprintf(f, " }\n");
    if (m->vn) {
        fprintf(f, "    normal_vectors { %d", Nv);
        for (int j = 0; j < Nv; j++) {
            const double *n = m->vn[inv[j]];
            fprintf(f, ",\n      <%.6f, %.6f, %.6f>", -n[1], n[2], n[0]);
        }
        fprintf(f, " }\n");
    }
    free(inv);
    // The map (x,y,z)_v -> (-y, z, x) has determinant -1 and POV-Ray's frame is left-handed: a
    // triangle keeps its outward side, whatever the order; the order is kept.
    for (int pass = 0; pass < (m->vn ? 2 : 1); pass++) {
        fprintf(f, "    %s { %d", pass ? "normal_indices" : "face_indices", Nt);
        for (int t = 0; t < m->Ntri; t++)
            if (part < 0 || m->part[t] == part)
                fprintf(f, ",\n      <%d, %d, %d>", map[m->tri[t][0]], map[m->tri[t][1]], map[m->tri[t][2]]);
        fprintf(f, " }\n");
    }
    return 1;
}

rs_status rs_synth_fleet_write_declare(FILE *f, const char *name, const rs_synth_mesh *mesh,
                                       rs_synth_declare_style style, const double paint_rgb[3], rs_err *err)
{
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
        rc = write_mesh2(f, mesh, -1, map);
        fprintf(f, "  }\n");
    } else {
        fprintf(f, "#declare %s = union {\n", name);
        for (int part = 0; part < RS_SYNTH_NPARTS && rc >= 0; part++) {
            rc = write_mesh2(f, mesh, part, map);
            if (rc <= 0) continue;
            if (part == RS_SYNTH_PART_PAINT)
                fprintf(f,
                        "    texture { pigment { rgb <%.6f, %.6f, %.6f> } finish { specular 0.6 "
                        "roughness 0.01 reflection 0.06 } }\n  }\n",
                        paint_rgb[0], paint_rgb[1], paint_rgb[2]);
            else
                fprintf(f, "    texture { %s }\n  }\n", part_textures[part]);
        }
        fprintf(f, "}\n");
    }
    free(map);
    if (rc < 0) return rs_err_set(err, RS_ERR_NOMEM, "declare %s: out of memory", name);
    if (ferror(f)) return rs_err_set(err, RS_ERR_IO, "declare %s: write failed", name);
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
