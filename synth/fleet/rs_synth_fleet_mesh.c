// rs_synth_fleet_mesh.c -- rs_synth_mesh (freeing, bounds) and the growing mesh that the
// procedural builder fills (synth/fleet/internal/rs_synth_fleet_internal.h).
#include "synth/fleet/rs_synth_fleet.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "synth/fleet/internal/rs_synth_fleet_internal.h"

void rs_synth_mesh_free(rs_synth_mesh *mesh)
{
    if (!mesh) return;
    free(mesh->v);
    free(mesh->vn);
    free(mesh->tri);
    free(mesh->part);
    free(mesh->tri_n);
    free(mesh->uv);
    free(mesh->materials);
    free(mesh->material);
    for (int k = 0; k < mesh->Ntextures; k++) {
        rs_image_free(&mesh->textures[k]);
        if (mesh->texture_png) free(mesh->texture_png[k]);
    }
    free(mesh->texture_png);
    free(mesh->textures);
    memset(mesh, 0, sizeof *mesh);
}

// A copy of n bytes of p (NULL when p is NULL); *ok cleared when it fails.
static void *dup_bytes(const void *p, size_t n, bool *ok)
{
    if (!p) return NULL;
    void *q = malloc(n > 0 ? n : 1);
    if (!q)
        *ok = false;
    else
        memcpy(q, p, n);
    return q;
}

rs_status rs_synth_mesh_copy(rs_synth_mesh *out, const rs_synth_mesh *in, rs_err *err)
{
    bool ok = true;
    const size_t Nv = (size_t)in->Nv, Nt = (size_t)in->Ntri;
    *out = *in;
    out->v = dup_bytes(in->v, Nv * sizeof *in->v, &ok);
    out->vn = dup_bytes(in->vn, (in->tri_n ? (size_t)in->Nn : Nv) * sizeof *in->vn, &ok);
    out->tri = dup_bytes(in->tri, Nt * sizeof *in->tri, &ok);
    out->part = dup_bytes(in->part, Nt, &ok);
    out->tri_n = dup_bytes(in->tri_n, Nt * sizeof *in->tri_n, &ok);
    out->uv = dup_bytes(in->uv, Nv * sizeof *in->uv, &ok);
    out->materials = dup_bytes(in->materials, (size_t)in->Nmaterials * sizeof *in->materials, &ok);
    out->material = dup_bytes(in->material, Nt * sizeof *in->material, &ok);
    out->textures = in->Ntextures > 0 ? calloc((size_t)in->Ntextures, sizeof *out->textures) : NULL;
    out->Ntextures = out->textures ? in->Ntextures : 0;
    ok &= in->Ntextures == 0 || out->textures != NULL;
    out->texture_png = in->texture_png && out->textures ? calloc((size_t)in->Ntextures, sizeof(char *)) : NULL;
    ok &= !in->texture_png || out->texture_png != NULL || in->Ntextures == 0;
    for (int k = 0; k < out->Ntextures; k++) { // (every image zeroed or copied: freed safely)
        const rs_image *a = &in->textures[k];
        const size_t n = (size_t)a->width * a->height * a->channels * sizeof(float);
        out->textures[k] = *a;
        out->textures[k].data = ok ? dup_bytes(a->data, n, &ok) : NULL;
        if (out->texture_png && in->texture_png[k] && ok)
            ok = (out->texture_png[k] = strdup(in->texture_png[k])) != NULL;
    }
    if (!ok) {
        rs_synth_mesh_free(out);
        return rs_err_set(err, RS_ERR_NOMEM, "mesh copy: out of memory");
    }
    return RS_OK;
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

void rs_synth_fleet_orient(rs_synth_fleet_builder *b, int t0)
{
    if (b->failed) return;
    double vol = 0;
    for (int t = t0; t < b->m.Ntri; t++) {
        const double *p = b->m.v[b->m.tri[t][0]], *q = b->m.v[b->m.tri[t][1]], *r = b->m.v[b->m.tri[t][2]];
        vol += p[0] * (q[1] * r[2] - q[2] * r[1]) + p[1] * (q[2] * r[0] - q[0] * r[2]) +
               p[2] * (q[0] * r[1] - q[1] * r[0]);
    }
    if (vol < 0)
        for (int t = t0; t < b->m.Ntri; t++) {
            int tmp = b->m.tri[t][1];
            b->m.tri[t][1] = b->m.tri[t][2];
            b->m.tri[t][2] = tmp;
        }
}

// (b - a) x (c - a): twice the area times the unit normal.
static void tri_cross(double n[3], const double *a, const double *b, const double *c)
{
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    n[0] = u[1] * w[2] - u[2] * w[1];
    n[1] = u[2] * w[0] - u[0] * w[2];
    n[2] = u[0] * w[1] - u[1] * w[0];
}

void rs_synth_fleet_smooth(rs_synth_fleet_builder *b, double crease_deg)
{
    if (b->failed) return;
    rs_synth_mesh *m = &b->m;
    const int Nv = m->Nv, Nt = m->Ntri;
    double(*fn)[3] = malloc((size_t)(Nt ? Nt : 1) * sizeof *fn); // area-weighted face normals
    int *start = calloc((size_t)Nv + 1, sizeof *start), *adj = malloc((size_t)(3 * Nt + 1) * sizeof *adj);
    double(*vn)[3] = malloc((size_t)(3 * Nt + 1) * sizeof *vn);
    int(*tn)[3] = malloc((size_t)(Nt ? Nt : 1) * sizeof *tn);
    if (!fn || !start || !adj || !vn || !tn) {
        free(fn), free(start), free(adj), free(vn), free(tn);
        b->failed = 1;
        return;
    }
    for (int t = 0; t < Nt; t++) {
        tri_cross(fn[t], m->v[m->tri[t][0]], m->v[m->tri[t][1]], m->v[m->tri[t][2]]);
        for (int k = 0; k < 3; k++) start[m->tri[t][k] + 1]++;
    }
    for (int i = 0; i < Nv; i++) start[i + 1] += start[i];
    int *fill = malloc((size_t)(Nv ? Nv : 1) * sizeof *fill);
    if (!fill) {
        free(fn), free(start), free(adj), free(vn), free(tn);
        b->failed = 1;
        return;
    }
    memcpy(fill, start, (size_t)Nv * sizeof *fill);
    for (int t = 0; t < Nt; t++)
        for (int k = 0; k < 3; k++) adj[fill[m->tri[t][k]]++] = t;
    free(fill);
    const double cos_crease = cos(crease_deg * M_PI / 180);
    int Nn = 0;
    for (int t = 0; t < Nt; t++) {
        const double lt = sqrt(fn[t][0] * fn[t][0] + fn[t][1] * fn[t][1] + fn[t][2] * fn[t][2]);
        for (int k = 0; k < 3; k++) {
            const int v = m->tri[t][k];
            double s[3] = {0, 0, 0};
            for (int j = start[v]; j < start[v + 1]; j++) {
                const double *g = fn[adj[j]];
                const double lg = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
                if (g[0] * fn[t][0] + g[1] * fn[t][1] + g[2] * fn[t][2] >= cos_crease * lt * lg)
                    for (int c = 0; c < 3; c++) s[c] += g[c];
            }
            double ls = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
            if (!(ls > 0)) {
                for (int c = 0; c < 3; c++) s[c] = fn[t][c];
                ls = lt > 0 ? lt : 1;
            }
            for (int c = 0; c < 3; c++) s[c] /= ls;
            // the same normal already stored for this vertex by a neighbour's corner?
            int found = -1;
            for (int j = start[v]; j < start[v + 1] && found < 0; j++) {
                const int u = adj[j];
                if (u >= t) continue;
                for (int kk = 0; kk < 3; kk++)
                    if (m->tri[u][kk] == v) {
                        const double *q = vn[tn[u][kk]];
                        if (fabs(q[0] - s[0]) + fabs(q[1] - s[1]) + fabs(q[2] - s[2]) < 1e-9) found = tn[u][kk];
                    }
            }
            if (found < 0) {
                memcpy(vn[Nn], s, sizeof s);
                found = Nn++;
            }
            tn[t][k] = found;
        }
    }
    free(fn), free(start), free(adj);
    free(m->vn), free(m->tri_n);
    m->vn = vn;
    m->tri_n = tn;
    m->Nn = Nn;
}
