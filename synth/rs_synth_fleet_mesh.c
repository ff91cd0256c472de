// rs_synth_fleet_mesh.c -- rs_synth_mesh (freeing, bounds) and the growing mesh that the
// procedural builder and the OBJ reader fill (synth/internal/rs_synth_fleet_internal.h).
#include "synth/rs_synth_fleet.h"

#include <stdlib.h>
#include <string.h>

#include "synth/internal/rs_synth_fleet_internal.h"

void rs_synth_mesh_free(rs_synth_mesh *mesh)
{
    if (!mesh) return;
    free(mesh->v);
    free(mesh->vn);
    free(mesh->tri);
    free(mesh->part);
    memset(mesh, 0, sizeof *mesh);
}

void rs_synth_mesh_bounds(double lo[3], double hi[3], const rs_synth_mesh *mesh)
{
    for (int k = 0; k < 3; k++) lo[k] = hi[k] = 0;
    for (int i = 0; i < mesh->Nv; i++)
        for (int k = 0; k < 3; k++) {
            double x = mesh->v[i][k];
            if (i == 0 || x < lo[k]) lo[k] = x;
            if (i == 0 || x > hi[k]) hi[k] = x;
        }
}

int rs_synth_fleet_add_v(rs_synth_fleet_builder *b, double x, double y, double z)
{
    if (b->failed) return 0;
    if (b->m.Nv == b->cap_v) {
        int cap = b->cap_v ? 2 * b->cap_v : 256;
        void *p = realloc(b->m.v, (size_t)cap * sizeof *b->m.v);
        if (!p) {
            b->failed = 1;
            return 0;
        }
        b->m.v = p;
        b->cap_v = cap;
    }
    b->m.v[b->m.Nv][0] = x;
    b->m.v[b->m.Nv][1] = y;
    b->m.v[b->m.Nv][2] = z;
    return b->m.Nv++;
}

void rs_synth_fleet_add_t(rs_synth_fleet_builder *b, int i, int j, int k, int part)
{
    if (b->failed) return;
    if (b->m.Ntri == b->cap_t) {
        int cap = b->cap_t ? 2 * b->cap_t : 512;
        void *p = realloc(b->m.tri, (size_t)cap * sizeof *b->m.tri);
        void *q = p ? realloc(b->m.part, (size_t)cap) : NULL;
        if (p) b->m.tri = p;
        if (!q) {
            b->failed = 1;
            return;
        }
        b->m.part = q;
        b->cap_t = cap;
    }
    b->m.tri[b->m.Ntri][0] = i;
    b->m.tri[b->m.Ntri][1] = j;
    b->m.tri[b->m.Ntri][2] = k;
    b->m.part[b->m.Ntri] = (uint8_t)part;
    b->m.Ntri++;
}
