// rs_synth_prepare.c -- vehicles ready for a scene: resolved, meshes built, a user model loaded once
// per distinct specification (synth/fleet/rs_synth_prepare.h).
#include "synth/fleet/rs_synth_prepare.h"

#include <stdlib.h>
#include <string.h>

// ---- prepared vehicles ----

void rs_synth_prepared_free(rs_synth_prepared *p)
{
    if (!p) return;
    for (int i = 0; i < p->Nmeshes; i++) rs_synth_mesh_free(&p->meshes[i]);
    free(p->meshes);
    free(p->v);
    free(p->imesh);
    memset(p, 0, sizeof(*p));
}

static bool same_spec(const rs_synth_obj_spec *a, const rs_synth_obj_spec *b)
{
    if (!(a->loaded == b->loaded && strcmp(a->path, b->path) == 0 && a->scale == b->scale &&
          a->length_m == b->length_m && strcmp(a->forward, b->forward) == 0 && strcmp(a->up, b->up) == 0 &&
          a->Npaint == b->Npaint))
        return false;
    for (int k = 0; k < a->Npaint; k++)
        if (strcmp(a->paint_materials[k], b->paint_materials[k]) != 0) return false;
    return true;
}

// Resolves vehicle i and gives it a mesh: its own procedural one, or the first identical user
// model's.
static rs_status prepare_one(rs_synth_prepared *out, int i, const rs_synth_vehicle *vehicles,
                             const rs_synth_obj_spec *obj, rs_synth_lod lod, rs_err *err)
{
    const rs_synth_vehicle *in = &vehicles[i];
    rs_synth_vehicle *v = &out->v[i];
    rs_status st = rs_synth_fleet_resolve(v, in, err);
    if (st) return st;
    if (in->cls != RS_SYNTH_USER_MODEL) {
        out->imesh[i] = out->Nmeshes;
        st = rs_synth_fleet_build_lod(&out->meshes[out->Nmeshes], v, lod, err);
        if (st == RS_OK) out->Nmeshes++;
        return st;
    }
    if (!obj || !obj[i].path) return rs_err_set(err, RS_ERR_INVALID, "a user model without an OBJ specification");
    int j = 0;
    while (j < i && !(vehicles[j].cls == RS_SYNTH_USER_MODEL && same_spec(&obj[j], &obj[i]))) j++;
    if (j < i) {
        out->imesh[i] = out->imesh[j];
    } else {
        out->imesh[i] = out->Nmeshes;
        st = obj[i].loaded ? rs_synth_mesh_copy(&out->meshes[out->Nmeshes], obj[i].loaded, err)
                           : rs_synth_obj_load(&out->meshes[out->Nmeshes], &obj[i], err);
        if (st) return st;
        out->Nmeshes++;
    }
    // The model's box is its mesh's (footprint centred at the origin, lowest point at z = 0).
    double lo[3], hi[3];
    rs_synth_mesh_bounds(lo, hi, &out->meshes[out->imesh[i]]);
    v->length_m = hi[0] - lo[0];
    v->width_m = hi[1] - lo[1];
    v->height_m = hi[2] - lo[2];
    return RS_OK;
}

rs_status rs_synth_prepare(rs_synth_prepared *out, const rs_synth_vehicle *vehicles, const rs_synth_obj_spec *obj,
                           int N, rs_err *err)
{
    return rs_synth_prepare_lod(out, vehicles, obj, N, NULL, err);
}

rs_status rs_synth_prepare_lod(rs_synth_prepared *out, const rs_synth_vehicle *vehicles, const rs_synth_obj_spec *obj,
                               int N, const uint8_t *lod, rs_err *err)
{
    memset(out, 0, sizeof(*out));
    const size_t n = (size_t)(N > 0 ? N : 1);
    out->v = calloc(n, sizeof(*out->v));
    out->imesh = calloc(n, sizeof(*out->imesh));
    out->meshes = calloc(n, sizeof(*out->meshes));
    if (!out->v || !out->imesh || !out->meshes) {
        rs_synth_prepared_free(out);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    out->N = N;
    for (int i = 0; i < N; i++) {
        rs_status st = prepare_one(out, i, vehicles, obj, lod ? (rs_synth_lod)lod[i] : RS_SYNTH_LOD_FULL, err);
        if (st) {
            char id[64];
            rs_synth_safe_text(id, sizeof(id), vehicles[i].id);
            rs_err_prefix(err, "vehicle %d (id \"%s\")", i, id);
            rs_synth_prepared_free(out);
            return st;
        }
    }
    return RS_OK;
}
