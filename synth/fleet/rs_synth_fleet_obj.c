// rs_synth_fleet_obj.c -- OBJ user models (rs_synth_obj_load): v, vn and f read line by line,
// polygons triangulated as fans, mapped into the vehicle frame and stood on the ground.
#include "synth/fleet/rs_synth_fleet.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "synth/fleet/internal/rs_synth_fleet_internal.h"

// "+x" -> axis 0, sign +1, ...; returns 0 when not an axis.
static int parse_axis(const char *s, int *axis, double *sign)
{
    if (!s || strlen(s) != 2 || (s[0] != '+' && s[0] != '-') || s[1] < 'x' || s[1] > 'z') return 0;
    *axis = s[1] - 'x';
    *sign = s[0] == '+' ? 1 : -1;
    return 1;
}

typedef struct {
    double (*a)[3];
    int n, cap;
} vec3_list;

static int vec3_push(vec3_list *l, const double x[3])
{
    if (l->n == l->cap) {
        int cap = l->cap ? 2 * l->cap : 256;
        void *p = realloc(l->a, (size_t)cap * sizeof *l->a);
        if (!p) return 0;
        l->a = p;
        l->cap = cap;
    }
    memcpy(l->a[l->n++], x, sizeof(double[3]));
    return 1;
}

// One face corner "v", "v/vt", "v//vn" or "v/vt/vn" -> 0-based v and vn (-1 if absent).
static int parse_corner(const char *tok, int nv, int nvn, int *iv, int *ivn)
{
    char *end;
    long a = strtol(tok, &end, 10);
    if (end == tok) return 0;
    long n = 0;
    if (*end == '/') {
        end++;
        if (*end != '/') (void)strtol(end, &end, 10); // texture index: ignored
        if (*end == '/') {
            char *e2;
            n = strtol(end + 1, &e2, 10);
            if (e2 == end + 1) return 0;
            end = e2;
        }
    }
    if (*end) return 0;
    a = a < 0 ? nv + a : a - 1;
    if (a < 0 || a >= nv) return -1;
    if (n != 0) {
        n = n < 0 ? nvn + n : n - 1;
        if (n < 0 || n >= nvn) return -1;
    } else
        n = -1;
    *iv = (int)a;
    *ivn = (int)n;
    return 1;
}

static void rotate3(double y[3], const double R[3][3], const double x[3], double scale)
{
    for (int r = 0; r < 3; r++) y[r] = scale * (R[r][0] * x[0] + R[r][1] * x[1] + R[r][2] * x[2]);
}

// Drops zero-area triangles, moves the box's footprint centre to the origin and its bottom to
// z = 0, normalises the normals.
static rs_status obj_finish(rs_synth_fleet_builder *b, const char *path, rs_err *err)
{
    int Nt = 0;
    for (int t = 0; t < b->m.Ntri; t++) {
        const double *a = b->m.v[b->m.tri[t][0]], *p = b->m.v[b->m.tri[t][1]], *c = b->m.v[b->m.tri[t][2]];
        double u[3], w[3], n[3];
        for (int k = 0; k < 3; k++) u[k] = p[k] - a[k], w[k] = c[k] - a[k];
        n[0] = u[1] * w[2] - u[2] * w[1];
        n[1] = u[2] * w[0] - u[0] * w[2];
        n[2] = u[0] * w[1] - u[1] * w[0];
        if (n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 1e-24) {
            memcpy(b->m.tri[Nt], b->m.tri[t], sizeof b->m.tri[t]);
            b->m.part[Nt++] = b->m.part[t];
        }
    }
    b->m.Ntri = Nt;
    if (Nt == 0) return rs_err_set(err, RS_ERR_INVALID, "%s: no face with a non-zero area", path);
    double lo[3], hi[3];
    rs_synth_mesh_bounds(lo, hi, &b->m);
    double c[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), lo[2]};
    for (int i = 0; i < b->m.Nv; i++) {
        for (int k = 0; k < 3; k++) b->m.v[i][k] -= c[k];
        if (b->m.vn) {
            double *n = b->m.vn[i], l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (l > 0)
                for (int k = 0; k < 3; k++) n[k] /= l;
        }
    }
    return RS_OK;
}

rs_status rs_synth_obj_load(rs_synth_mesh *mesh, const rs_synth_obj_spec *spec, rs_err *err)
{
    memset(mesh, 0, sizeof *mesh);
    int fa, ua;
    double fs, us;
    if (!spec || !spec->path) return rs_err_set(err, RS_ERR_INVALID, "model: no path");
    if (!(spec->scale > 0 && isfinite(spec->scale)))
        return rs_err_set(err, RS_ERR_INVALID, "%s: scale: %g is not a positive number", spec->path, spec->scale);
    if (!parse_axis(spec->forward, &fa, &fs))
        return rs_err_set(err, RS_ERR_INVALID, "%s: forward: not one of +x -x +y -y +z -z", spec->path);
    if (!parse_axis(spec->up, &ua, &us) || ua == fa)
        return rs_err_set(err, RS_ERR_INVALID, "%s: up: not one of +x -x +y -y +z -z, or the same axis as forward",
                          spec->path);
    // Rows of the OBJ -> vehicle rotation: x_v = forward, z_v = up, y_v = z_v x x_v.
    double R[3][3] = {{0}};
    R[0][fa] = fs;
    R[2][ua] = us;
    R[1][0] = R[2][1] * R[0][2] - R[2][2] * R[0][1];
    R[1][1] = R[2][2] * R[0][0] - R[2][0] * R[0][2];
    R[1][2] = R[2][0] * R[0][1] - R[2][1] * R[0][0];

    char *text = NULL;
    rs_status st = rs_io_read_file(&text, NULL, spec->path, err);
    if (st) return st;
    vec3_list V = {0}, VN = {0}, outn = {0}; // outn: the normal of each output vertex
    rs_synth_fleet_builder b = {0};
    int *cv = NULL, *cn = NULL, ccap = 0, all_normals = 1, line = 0;
    for (char *p = text; *p && !st;) {
        char *eol = strchr(p, '\n');
        if (eol) *eol = 0;
        line++;
        char *s = p;
        p = eol ? eol + 1 : p + strlen(p);
        char *hash = strchr(s, '#');
        if (hash) *hash = 0;
        char *save = NULL, *kw = strtok_r(s, " \t\r", &save);
        if (!kw) continue;
        if (strcmp(kw, "v") == 0 || strcmp(kw, "vn") == 0) {
            double x[3];
            for (int k = 0; k < 3 && !st; k++) {
                char *tok = strtok_r(NULL, " \t\r", &save), *end = NULL;
                x[k] = tok ? strtod(tok, &end) : NAN;
                if (!tok || *end || !isfinite(x[k]))
                    st = rs_err_set(err, RS_ERR_PARSE, "%s:%d: %s: coordinate %d is not a number", spec->path, line, kw,
                                    k + 1);
            }
            if (!st && !vec3_push(kw[1] ? &VN : &V, x))
                st = rs_err_set(err, RS_ERR_NOMEM, "%s:%d: out of memory", spec->path, line);
        } else if (strcmp(kw, "f") == 0) {
            int n = 0;
            for (char *tok; !st && (tok = strtok_r(NULL, " \t\r", &save)); n++) {
                if (n == ccap) {
                    ccap = ccap ? 2 * ccap : 16;
                    int *a = realloc(cv, (size_t)ccap * sizeof *cv);
                    if (a) cv = a;
                    int *c = a ? realloc(cn, (size_t)ccap * sizeof *cn) : NULL;
                    if (c) cn = c;
                    if (!c) {
                        st = rs_err_set(err, RS_ERR_NOMEM, "%s:%d: out of memory", spec->path, line);
                        break;
                    }
                }
                int r = parse_corner(tok, V.n, VN.n, &cv[n], &cn[n]);
                if (r == 0)
                    st = rs_err_set(err, RS_ERR_PARSE,
                                    "%s:%d: f: corner %d '%.40s' is not v, "
                                    "v/vt, v//vn or v/vt/vn",
                                    spec->path, line, n + 1, tok);
                else if (r < 0)
                    st = rs_err_set(err, RS_ERR_PARSE,
                                    "%s:%d: f: corner %d: index out of range "
                                    "(%d vertices, %d normals so far)",
                                    spec->path, line, n + 1, V.n, VN.n);
                else if (cn[n] < 0)
                    all_normals = 0;
            }
            if (!st && n < 3)
                st = rs_err_set(err, RS_ERR_PARSE, "%s:%d: f: %d corners, at least 3 needed", spec->path, line, n);
            // Every corner becomes its own vertex (positions and normals may pair differently).
            int base = b.m.Nv;
            for (int k = 0; k < n && !st; k++) {
                double y[3], nn[3] = {0, 0, 0};
                rotate3(y, R, V.a[cv[k]], spec->scale);
                rs_synth_fleet_add_v(&b, y[0], y[1], y[2]);
                if (cn[k] >= 0) rotate3(nn, R, VN.a[cn[k]], 1);
                if (!vec3_push(&outn, nn)) b.failed = 1;
            }
            for (int k = 1; k + 1 < n && !st; k++) rs_synth_fleet_add_t(&b, base, base + k, base + k + 1, 0);
            if (!st && b.failed) st = rs_err_set(err, RS_ERR_NOMEM, "%s:%d: out of memory", spec->path, line);
        }
    }
    free(text);
    free(cv);
    free(cn);
    free(V.a);
    free(VN.a);
    if (!st && b.m.Ntri == 0) st = rs_err_set(err, RS_ERR_INVALID, "%s: no faces", spec->path);
    if (!st && all_normals) {
        b.m.vn = outn.a;
        outn.a = NULL;
    }
    free(outn.a);
    if (!st) st = obj_finish(&b, spec->path, err);
    if (st) {
        rs_synth_mesh_free(&b.m);
        return st;
    }
    *mesh = b.m;
    return RS_OK;
}
