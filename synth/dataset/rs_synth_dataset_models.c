// rs_synth_dataset_models.c -- `roadside synth --models FILE`: the run's model library, loaded once
// before the workers fork, and the draw that makes a vehicle one of its models
// (rs_synth_dataset_internal.h).
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_hash.h"
#include "core/rs_io.h"
#include "core/rs_rng.h"
#include "synth/dataset/internal/rs_synth_dataset_internal.h"

rs_status rs_synth_dataset__models_load(rs_synth_dataset__run *d, rs_err *err)
{
    rs_status st = rs_synth_models_read(&d->models, d->opt->models_path, err);
    if (!st) st = rs_hash_sha256_file(d->models_sha256, NULL, d->opt->models_path, err);
    if (st) return st;
    d->model_meshes = calloc((size_t)d->models.N, sizeof *d->model_meshes);
    if (!d->model_meshes) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; i < d->models.N; i++) {
        if ((st = rs_synth_obj_load(&d->model_meshes[i], &d->models.obj[i], err)))
            return rs_err_prefix(err, "%s: [%d].model", d->opt->models_path, i);
        d->models.obj[i].loaded = &d->model_meshes[i];
    }
    return RS_OK;
}

rs_status rs_synth_dataset__models_cache(rs_synth_dataset__run *d, rs_err *err)
{
    if (d->models.N == 0) return RS_OK;
    char *dir = rs_io_join(d->work_root, "models");
    if (!dir) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_io_remove_tree(dir); // a previous, interrupted run's
    rs_status st = rs_io_mkdir_p(dir, err);
    for (int i = 0; i < d->models.N && !st; i++) {
        char prefix[32];
        snprintf(prefix, sizeof prefix, "RS_LIBRARY_%d", i);
        st = rs_synth_fleet_cache_textures(&d->model_meshes[i], dir, prefix, err);
    }
    free(dir);
    return st;
}

void rs_synth_dataset__models_uncache(const rs_synth_dataset__run *d)
{
    if (d->models.N == 0) return;
    char *dir = rs_io_join(d->work_root, "models");
    if (dir) rs_io_remove_tree(dir);
    free(dir);
}

bool rs_synth_dataset__pick_model(rs_synth_vehicle *v, rs_synth_obj_spec *spec, const rs_synth_dataset__run *d, int k,
                                  int i)
{
    if (v->cls == RS_SYNTH_USER_MODEL) return false;
    int n = 0;
    for (int j = 0; j < d->models.N; j++) n += d->models.v[j].model_cls == v->cls;
    if (n == 0) return false;
    // a stream of its own (seed, k, "models", i): the images' other draws stay as they were
    const uint64_t h =
        rs_rng_seed_derive(rs_synth_dataset_image_seed(d->opt->seed ^ 0x6d6f64656c73ULL, k), (uint64_t)i);
    int pick = (int)(h % (uint64_t)n);
    for (int j = 0; j < d->models.N; j++)
        if (d->models.v[j].model_cls == v->cls && pick-- == 0) {
            double lo[3], hi[3];
            rs_synth_mesh_bounds(lo, hi, &d->model_meshes[j]);
            v->model_cls = v->cls;
            v->cls = RS_SYNTH_USER_MODEL;
            v->model_path = d->models.v[j].model_path;
            v->length_m = hi[0] - lo[0];
            v->width_m = hi[1] - lo[1];
            v->height_m = hi[2] - lo[2];
            *spec = d->models.obj[j];
            return true;
        }
    return false;
}
