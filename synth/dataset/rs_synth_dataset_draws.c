// rs_synth_dataset_draws.c -- what image k of a run is, from (seed, k) and the options alone: its
// random stream, its background, its split and its file stem (rs_synth_dataset_internal.h). The
// bottom of the dataset's files: it calls none of them.
#include <stdio.h>
#include <string.h>

#include "core/rs_rng.h"
#include "synth/dataset/internal/rs_synth_dataset_internal.h"

// ---- the random stream of one image ----

// The stream of image k: splitmix64 (core/rs_rng.h) from rs_rng_seed_derive(seed, k), stepped
// by rs_rng_seed_next. Its draws, in order: rs_synth_dataset.h ("traffic from SUMO's frames").
uint64_t rs_synth_dataset_image_seed(uint64_t seed, int k) { return rs_rng_seed_derive(seed, (uint64_t)k); }

int rs_synth_dataset__image_background(const rs_synth_dataset__run *d, int k, const rs_synth_dataset__camera *c)
{
    if (c->Nbg <= 0) return -1;
    // a sequence: image k % Ncams's draw, the same background in every frame of a camera
    uint64_t rng = rs_synth_dataset_image_seed(d->opt->seed, d->opt->sequence ? k % d->Ncams : k);
    return (int)(rs_rng_seed_next(&rng) % (uint64_t)c->Nbg); // the stream's first draw
}

// The validation draw of image k: uniform in [0, 1) from a stream of its own (seed, key, "val"),
// so the images' streams stay as they were. The key is k, or in a sequence its frame (k / Ncams:
// every camera's view of a frame in one split, no frame seen in both).
static double val_draw(const rs_synth_dataset__run *d, int k)
{
    const int key = d->opt->sequence ? k / d->Ncams : k;
    const uint64_t h = rs_synth_dataset_image_seed(d->opt->seed ^ 0x76616c5f73706c74ULL, key);
    return (double)(h >> 11) * 0x1.0p-53;
}

int rs_synth_dataset__val_fallback(const rs_synth_dataset__run *d)
{
    const rs_synth_dataset_options *opt = d->opt;
    if (!(opt->val_fraction > 0)) return -1;
    const int step = opt->sequence ? d->Ncams : 1; // one key per frame in a sequence
    if (opt->count / step < 2) return -1;          // one image (frame): nothing to hold out
    int best = -1;
    double best_u = 2;
    for (int k = 0; k < opt->count; k += step) {
        const double u = val_draw(d, k);
        if (u < opt->val_fraction) return -1; // the draw gave the split an image
        if (u < best_u) best_u = u, best = k;
    }
    return opt->sequence ? best / d->Ncams : best;
}

int rs_synth_dataset__image_split(const rs_synth_dataset__run *d, int k, const rs_synth_dataset__camera *c)
{
    const rs_synth_dataset_options *opt = d->opt;
    if (opt->val_fraction > 0) {
        if (val_draw(d, k) < opt->val_fraction) return 1;
        if (d->val_fallback >= 0 && (opt->sequence ? k / d->Ncams : k) == d->val_fallback) return 1;
    }
    for (int i = 0; i < opt->Nval_cameras; i++)
        if (strcmp(opt->val_cameras[i], c->id) == 0) return 1;
    if (opt->Nval_bg > 0) {
        const int b = rs_synth_dataset__image_background(d, k, c);
        bool all = b >= 0;
        for (int f = 0; f < opt->Nval_bg && all; f++) {
            const char *v = rs_site_background_tag(c->bg[b].src, opt->val_bg_keys[f]);
            all = v && strcmp(v, opt->val_bg_values[f]) == 0;
        }
        if (all) return 1;
    }
    return 0;
}

void rs_synth_dataset__stem(char *stem, size_t n, int k, const char *camera_id)
{
    snprintf(stem, n, "%06d_%s", k, camera_id);
    for (char *p = stem; *p; p++)
        if (!((*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') || *p == '_' ||
              *p == '-'))
            *p = '_';
}
