// rs_synth_dataset_looks.c -- DATASET/backgrounds.json: the camera look estimated from each
// background the run's images may be drawn over (docs/synth.md, "The camera's look"), written
// by rs_synth_dataset_run after the images, read back by rs_synth_dataset_stats. Calls
// backdrop's rs_synth_appearance_estimate (or the run's cached estimate), core/ and cJSON.
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "synth/dataset/internal/rs_synth_dataset_internal.h"

// The look of one background as JSON (the fields of rs_synth_appearance).
static cJSON *look_json(const rs_synth_appearance *a)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "noise_a", a->noise_a);
    cJSON_AddNumberToObject(o, "noise_b", a->noise_b);
    cJSON_AddNumberToObject(o, "noise_sigma_at_0_5", rs_synth_appearance_noise_sigma(a, 0.5));
    cJSON_AddNumberToObject(o, "noise_sigma", a->noise_sigma);
    cJSON_AddNumberToObject(o, "blur_sigma_px", a->blur_sigma_px);
    cJSON_AddNumberToObject(o, "jpeg_quality", a->jpeg_quality);
    cJSON_AddBoolToObject(o, "jpeg_exact", a->jpeg_exact);
    cJSON_AddNumberToObject(o, "blockiness", a->blockiness);
    cJSON *g = cJSON_AddArrayToObject(o, "gain");
    for (int c = 0; c < 3; c++) cJSON_AddItemToArray(g, cJSON_CreateNumber(a->gain[c]));
    return o;
}

rs_status rs_synth_dataset__write_looks(const rs_synth_dataset__run *d, rs_err *err)
{
    cJSON *doc = cJSON_CreateObject();
    cJSON_AddBoolToObject(doc, "applied", !d->opt->no_appearance);
    cJSON *list = cJSON_AddArrayToObject(doc, "backgrounds");
    for (int i = 0; i < d->Ncams; i++)
        for (int b = 0; b < d->cams[i].Nbg; b++) {
            const rs_synth_dataset__background *bg = &d->cams[i].bg[b];
            bool seen = false; // one entry per background file: the look is the file's
            for (int j = 0; j <= i && !seen; j++)
                for (int c = 0; c < (j < i ? d->cams[j].Nbg : b) && !seen; c++) seen = d->cams[j].bg[c].src == bg->src;
            if (seen) continue;
            cJSON *e = cJSON_CreateObject();
            cJSON_AddStringToObject(e, "background", bg->src->name ? bg->src->name : bg->src->file);
            cJSON_AddStringToObject(e, "file", bg->src->file);
            // the run's estimate when this process made it (the parent prepares its workers'
            // backgrounds), else made here: the same, deterministic, from the file alone
            rs_synth_appearance a = bg->app;
            rs_err lerr = {0};
            const bool ok = (bg->linear.data && bg->app_ok) ||
                            rs_synth_appearance_estimate(&a, bg->src->path, NULL, NULL, &lerr) == RS_OK;
            if (ok)
                cJSON_AddItemToObject(e, "look", look_json(&a));
            else {
                cJSON_AddNullToObject(e, "look");
                cJSON_AddStringToObject(e, "why", lerr.msg);
            }
            cJSON_AddItemToArray(list, e);
        }
    char *path = rs_io_join(d->opt->out_dir, "backgrounds.json"), *text = cJSON_Print(doc);
    rs_status st =
        path && text ? rs_io_write_file(path, text, strlen(text), err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    free(path);
    free(text);
    cJSON_Delete(doc);
    return st;
}
