// rs_synth_fleet_model.c -- user models (rs_synth_obj_load) read by the Open Asset Import Library
// (assimp's C API: OBJ + MTL, glTF 2.0, ...): triangles, normals, texture coordinates, materials
// and their images, mapped into the vehicle frame and stood on the ground; and the images written
// as the PNG files a scene refers to (rs_synth_fleet_write_textures).
#include "synth/fleet/rs_synth_fleet.h"

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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

static void rotate3(double y[3], const double R[3][3], const double x[3], double scale)
{
    for (int r = 0; r < 3; r++) y[r] = scale * (R[r][0] * x[0] + R[r][1] * x[1] + R[r][2] * x[2]);
}

static double clamp01(double x) { return x < 0 ? 0 : x > 1 ? 1 : x; }

// An embedded texture ("*N", or a name assimp's glTF reader gave it). NULL when not embedded.
static const struct aiTexture *embedded_texture(const struct aiScene *sc, const char *name)
{
    if (name[0] == '*') {
        char *end;
        long k = strtol(name + 1, &end, 10);
        return !*end && k >= 0 && k < (long)sc->mNumTextures ? sc->mTextures[k] : NULL;
    }
    for (unsigned k = 0; k < sc->mNumTextures; k++)
        if (strcmp(sc->mTextures[k]->mFilename.data, name) == 0) return sc->mTextures[k];
    return NULL;
}

// Reads an embedded texture: raw BGRA texels (mHeight > 0), or a compressed file (PNG, JPEG:
// mHeight == 0, mWidth bytes) decoded by rs_image_read from a private temporary copy.
static rs_status read_embedded(rs_image *img, const struct aiTexture *t, const char *path, rs_err *err)
{
    if (t->mHeight > 0) {
        rs_status st = rs_image_alloc(img, (int)t->mWidth, (int)t->mHeight, 4, err);
        if (st) return st;
        for (size_t i = 0; i < (size_t)t->mWidth * t->mHeight; i++) {
            const struct aiTexel *p = &t->pcData[i];
            float *q = &img->data[4 * i];
            q[0] = p->r / 255.0f, q[1] = p->g / 255.0f, q[2] = p->b / 255.0f, q[3] = p->a / 255.0f;
        }
        return RS_OK;
    }
    char dir[] = "/tmp/roadside-tex-XXXXXX";
    if (!mkdtemp(dir)) return rs_err_set(err, RS_ERR_IO, "%s: embedded texture: cannot make a temporary folder", path);
    char file[64];
    snprintf(file, sizeof file, "%s/t.%s", dir, strcmp(t->achFormatHint, "jpg") == 0 ? "jpg" : "png");
    rs_status st = rs_io_write_file(file, t->pcData, t->mWidth, err);
    if (!st) st = rs_image_read(img, file, err);
    unlink(file);
    rmdir(dir);
    if (st) rs_err_prefix(err, "%s: embedded texture", path);
    return st;
}

// The diffuse / base colour image of material `mat` into mesh->textures (once per image name):
// its index, or -1 when the material has none.
static rs_status load_texture(int *index, rs_synth_mesh *mesh, char (*names)[1024], const struct aiScene *sc,
                              const struct aiMaterial *mat, const char *mat_name, const char *path, const char *dir,
                              rs_err *err)
{
    *index = -1;
    struct aiString tp;
    if (aiGetMaterialTexture(mat, aiTextureType_DIFFUSE, 0, &tp, NULL, NULL, NULL, NULL, NULL, NULL) !=
            aiReturn_SUCCESS &&
        aiGetMaterialTexture(mat, aiTextureType_BASE_COLOR, 0, &tp, NULL, NULL, NULL, NULL, NULL, NULL) !=
            aiReturn_SUCCESS)
        return RS_OK;
    for (int k = 0; k < mesh->Ntextures; k++)
        if (strcmp(names[k], tp.data) == 0) {
            *index = k;
            return RS_OK;
        }
    rs_image *img = &mesh->textures[mesh->Ntextures];
    const struct aiTexture *emb = embedded_texture(sc, tp.data);
    rs_status st;
    if (emb)
        st = read_embedded(img, emb, path, err);
    else {
        char *file = rs_io_join(dir, tp.data);
        if (!file) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        st = rs_image_read(img, file, err);
        free(file);
    }
    if (st) {
        char safe[128];
        rs_synth_safe_text(safe, sizeof safe, mat_name);
        return rs_err_prefix(err, "%s: material \"%s\": texture \"%.200s\"", path, safe, tp.data);
    }
    if (img->channels == 1) { // grey: as RGB
        rs_image rgb;
        if ((st = rs_image_alloc(&rgb, img->width, img->height, 3, err))) return st;
        for (size_t i = 0; i < (size_t)img->width * img->height; i++)
            rgb.data[3 * i] = rgb.data[3 * i + 1] = rgb.data[3 * i + 2] = img->data[i];
        rs_image_free(img);
        *img = rgb;
    }
    snprintf(names[mesh->Ntextures], sizeof names[0], "%.1023s", tp.data);
    *index = mesh->Ntextures++;
    return RS_OK;
}

// A material's values (rs_synth_material): MTL's Phong (Kd, Ks, Ns, d) or glTF's metallic-
// roughness (base colour, metallic, roughness, alpha). Phong's exponent Ns is POV-Ray's
// 1 / roughness; glTF's roughness r is taken to Blinn-Phong's exponent 2 / r^4 - 2 (Walter et
// al. 2007's usual match of GGX), specular 1 - r scaled for dielectrics.
static void read_material(rs_synth_material *out, const struct aiMaterial *mat)
{
    struct aiString name;
    out->name[0] = 0;
    if (aiGetMaterialString(mat, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS)
        snprintf(out->name, sizeof out->name, "%.63s", name.data);
    struct aiColor4D c;
    out->rgb[0] = out->rgb[1] = out->rgb[2] = 0.6;
    if (aiGetMaterialColor(mat, AI_MATKEY_BASE_COLOR, &c) == aiReturn_SUCCESS ||
        aiGetMaterialColor(mat, AI_MATKEY_COLOR_DIFFUSE, &c) == aiReturn_SUCCESS)
        out->rgb[0] = clamp01(c.r), out->rgb[1] = clamp01(c.g), out->rgb[2] = clamp01(c.b);
    ai_real x;
    out->opacity = aiGetMaterialFloatArray(mat, AI_MATKEY_OPACITY, &x, NULL) == aiReturn_SUCCESS ? clamp01(x) : 1;
    ai_real metal = 0, rough = -1;
    const bool pbr = aiGetMaterialFloatArray(mat, AI_MATKEY_ROUGHNESS_FACTOR, &rough, NULL) == aiReturn_SUCCESS;
    if (pbr) {
        (void)aiGetMaterialFloatArray(mat, AI_MATKEY_METALLIC_FACTOR, &metal, NULL);
        const double r = fmax(0.02, clamp01(rough)), n = 2 / (r * r * r * r) - 2;
        out->metallic = clamp01(metal);
        out->roughness = fmin(1, 1 / fmax(n, 1));
        out->specular = (1 - r) * (0.3 + 0.7 * out->metallic);
    } else {
        out->metallic = 0;
        out->specular = 0;
        if (aiGetMaterialColor(mat, AI_MATKEY_COLOR_SPECULAR, &c) == aiReturn_SUCCESS)
            out->specular = clamp01((c.r + c.g + c.b) / 3);
        ai_real ns = 0;
        (void)aiGetMaterialFloatArray(mat, AI_MATKEY_SHININESS, &ns, NULL);
        out->roughness = fmin(1, 1 / fmax(ns, 1));
    }
    out->texture = -1;
    out->paint = false;
}

// Reads the materials: each one's values and image; the paint rule (paint_materials, or a model
// with assimp's default material only). dir: the model's folder.
static rs_status read_materials(rs_synth_mesh *mesh, const struct aiScene *sc, const rs_synth_obj_spec *spec,
                                const char *dir, rs_err *err)
{
    const int N = (int)sc->mNumMaterials;
    if (N > 65535) return rs_err_set(err, RS_ERR_INVALID, "%s: %d materials (at most 65535)", spec->path, N);
    mesh->materials = calloc((size_t)(N > 0 ? N : 1), sizeof *mesh->materials);
    mesh->textures = calloc((size_t)(N > 0 ? N : 1), sizeof *mesh->textures);
    char(*names)[1024] = calloc((size_t)(N > 0 ? N : 1), sizeof *names);
    if (!mesh->materials || !mesh->textures || !names) {
        free(names);
        return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", spec->path);
    }
    mesh->Nmaterials = N;
    rs_status st = RS_OK;
    int Nown = 0; // materials other than assimp's default
    for (int k = 0; k < N && !st; k++) {
        rs_synth_material *m = &mesh->materials[k];
        read_material(m, sc->mMaterials[k]);
        Nown += strcmp(m->name, AI_DEFAULT_MATERIAL_NAME) != 0;
        st = load_texture(&m->texture, mesh, names, sc, sc->mMaterials[k], m->name, spec->path, dir, err);
        for (int j = 0; j < spec->Npaint; j++) m->paint |= strcmp(spec->paint_materials[j], m->name) == 0;
    }
    free(names);
    if (Nown == 0)
        for (int k = 0; k < N; k++) mesh->materials[k].paint = true;
    return st;
}

// Copies the scene's triangles (mapped by R and scale) into the mesh: vertices with their
// normals and texture coordinates, one material per triangle; zero-area triangles dropped.
static rs_status copy_meshes(rs_synth_mesh *mesh, const struct aiScene *sc, const double R[3][3], double scale,
                             const char *path, rs_err *err)
{
    size_t Nv = 0, Nt = 0;
    bool normals = true, uvs = false;
    for (unsigned i = 0; i < sc->mNumMeshes; i++) {
        const struct aiMesh *am = sc->mMeshes[i];
        if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
        Nv += am->mNumVertices;
        Nt += am->mNumFaces;
        normals &= am->mNormals != NULL;
        uvs |= am->mTextureCoords[0] != NULL;
    }
    if (Nt == 0) return rs_err_set(err, RS_ERR_INVALID, "%s: no faces", path);
    if (Nv > 100000000 || Nt > 100000000) return rs_err_set(err, RS_ERR_INVALID, "%s: too large", path);
    mesh->v = malloc(Nv * sizeof *mesh->v);
    mesh->vn = normals ? malloc(Nv * sizeof *mesh->vn) : NULL;
    mesh->uv = uvs ? calloc(Nv, sizeof *mesh->uv) : NULL;
    mesh->tri = malloc(Nt * sizeof *mesh->tri);
    mesh->part = calloc(Nt, 1); // RS_SYNTH_PART_PAINT
    mesh->material = malloc(Nt * sizeof *mesh->material);
    if (!mesh->v || (normals && !mesh->vn) || (uvs && !mesh->uv) || !mesh->tri || !mesh->part || !mesh->material)
        return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    for (unsigned i = 0; i < sc->mNumMeshes; i++) {
        const struct aiMesh *am = sc->mMeshes[i];
        if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
        const int base = mesh->Nv;
        for (unsigned j = 0; j < am->mNumVertices; j++) {
            const struct aiVector3D *p = &am->mVertices[j];
            const double x[3] = {p->x, p->y, p->z};
            rotate3(mesh->v[mesh->Nv], R, x, scale);
            if (normals) {
                const struct aiVector3D *n = &am->mNormals[j];
                const double y[3] = {n->x, n->y, n->z};
                double *o = mesh->vn[mesh->Nv];
                rotate3(o, R, y, 1);
                const double l = sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
                if (l > 0)
                    for (int k = 0; k < 3; k++) o[k] /= l;
            }
            if (uvs && am->mTextureCoords[0])
                mesh->uv[mesh->Nv][0] = am->mTextureCoords[0][j].x, mesh->uv[mesh->Nv][1] = am->mTextureCoords[0][j].y;
            mesh->Nv++;
        }
        for (unsigned t = 0; t < am->mNumFaces; t++) {
            const struct aiFace *fc = &am->mFaces[t];
            if (fc->mNumIndices != 3) continue;
            int *tri = mesh->tri[mesh->Ntri];
            for (int k = 0; k < 3; k++) tri[k] = base + (int)fc->mIndices[k];
            const double *a = mesh->v[tri[0]], *b = mesh->v[tri[1]], *c = mesh->v[tri[2]];
            double u[3], w[3];
            for (int k = 0; k < 3; k++) u[k] = b[k] - a[k], w[k] = c[k] - a[k];
            const double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
            if (!(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 1e-24)) continue; // zero area
            mesh->material[mesh->Ntri++] = (uint16_t)am->mMaterialIndex;
        }
    }
    if (mesh->Ntri == 0) return rs_err_set(err, RS_ERR_INVALID, "%s: no face with a non-zero area", path);
    return RS_OK;
}

// Scales to the box length asked for (length_m > 0), then moves the box's footprint centre to the
// origin and its bottom to z = 0.
static void stand(rs_synth_mesh *mesh, double length_m)
{
    double lo[3], hi[3];
    rs_synth_mesh_bounds(lo, hi, mesh);
    const double s = length_m > 0 && hi[0] > lo[0] ? length_m / (hi[0] - lo[0]) : 1;
    const double c[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), lo[2]};
    for (int i = 0; i < mesh->Nv; i++)
        for (int k = 0; k < 3; k++) mesh->v[i][k] = s * (mesh->v[i][k] - c[k]);
}

rs_status rs_synth_obj_load(rs_synth_mesh *mesh, const rs_synth_obj_spec *spec, rs_err *err)
{
    memset(mesh, 0, sizeof *mesh);
    int fa, ua;
    double fs, us;
    if (!spec || !spec->path) return rs_err_set(err, RS_ERR_INVALID, "model: no path");
    if (!(spec->length_m >= 0 && isfinite(spec->length_m)))
        return rs_err_set(err, RS_ERR_INVALID, "%s: length: %g is not a positive number", spec->path, spec->length_m);
    if (!(spec->length_m > 0) && !(spec->scale > 0 && isfinite(spec->scale)))
        return rs_err_set(err, RS_ERR_INVALID, "%s: scale: %g is not a positive number", spec->path, spec->scale);
    if (!parse_axis(spec->forward, &fa, &fs))
        return rs_err_set(err, RS_ERR_INVALID, "%s: forward: not one of +x -x +y -y +z -z", spec->path);
    if (!parse_axis(spec->up, &ua, &us) || ua == fa)
        return rs_err_set(err, RS_ERR_INVALID, "%s: up: not one of +x -x +y -y +z -z, or the same axis as forward",
                          spec->path);
    // Rows of the model -> vehicle rotation: x_v = forward, z_v = up, y_v = z_v x x_v.
    double R[3][3] = {{0}};
    R[0][fa] = fs;
    R[2][ua] = us;
    R[1][0] = R[2][1] * R[0][2] - R[2][2] * R[0][1];
    R[1][1] = R[2][2] * R[0][0] - R[2][0] * R[0][2];
    R[1][2] = R[2][0] * R[0][1] - R[2][1] * R[0][0];

    // assimp reports a missing file as an unknown format: check it first, for a clear message.
    rs_status st = rs_io_check_regular(spec->path, (size_t)1 << 31, err);
    if (st) return st;
    const struct aiScene *sc = aiImportFile(spec->path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                                            aiProcess_PreTransformVertices | aiProcess_SortByPType |
                                                            aiProcess_ValidateDataStructure);
    if (!sc) return rs_err_set(err, RS_ERR_PARSE, "%s: assimp: %s", spec->path, aiGetErrorString());
    char *dir = strdup(spec->path);
    if (!dir) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) {
        char *slash = strrchr(dir, '/');
        if (slash)
            slash[1] = 0;
        else
            strcpy(dir, ".");
        st = copy_meshes(mesh, sc, R, spec->length_m > 0 ? 1 : spec->scale, spec->path, err);
    }
    if (!st) st = read_materials(mesh, sc, spec, dir, err);
    free(dir);
    aiReleaseImport(sc);
    if (!st) stand(mesh, spec->length_m);
    if (st) rs_synth_mesh_free(mesh);
    return st;
}

static rs_status write_textures(const char *dir, const char *prefix, const rs_synth_mesh *mesh, bool cached,
                                char **paths, rs_err *err)
{
    if (!rs_synth_fleet_valid_identifier(prefix) || strlen(prefix) > 37)
        return rs_err_set(err, RS_ERR_INVALID, "textures: prefix is not an upper-case POV-Ray identifier");
    for (int k = 0; k < mesh->Ntextures; k++) {
        char name[64];
        rs_synth_fleet_texture_name(name, sizeof name, prefix, k);
        char *path = rs_io_join(dir, name);
        if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        rs_status st = cached && mesh->texture_png && mesh->texture_png[k]
                           ? ((void)unlink(path), rs_io_link_or_copy(mesh->texture_png[k], path, err))
                           : rs_image_write(path, &mesh->textures[k], 8, err);
        if (!st && paths)
            paths[k] = path;
        else
            free(path);
        if (st) return st;
    }
    return RS_OK;
}

rs_status rs_synth_fleet_write_textures(const char *dir, const char *prefix, const rs_synth_mesh *mesh, rs_err *err)
{
    return write_textures(dir, prefix, mesh, true, NULL, err);
}

rs_status rs_synth_fleet_cache_textures(rs_synth_mesh *mesh, const char *dir, const char *prefix, rs_err *err)
{
    if (mesh->Ntextures == 0) return RS_OK;
    char **paths = calloc((size_t)mesh->Ntextures, sizeof *paths);
    if (!paths) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = write_textures(dir, prefix, mesh, false, paths, err);
    if (st) {
        for (int k = 0; k < mesh->Ntextures; k++) free(paths[k]);
        free(paths);
        return st;
    }
    mesh->texture_png = paths;
    return RS_OK;
}
