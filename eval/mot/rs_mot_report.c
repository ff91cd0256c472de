// rs_mot_report.c -- an rs_mot_result as JSON (cJSON), written atomically (eval/mot/rs_mot.h).
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "eval/mot/rs_mot.h"

// key: x, or null for NaN. False when out of memory.
static bool put(cJSON *o, const char *key, double x)
{
    return (isnan(x) ? cJSON_AddNullToObject(o, key) : cJSON_AddNumberToObject(o, key, x)) != NULL;
}

// key: {"0.05": x[0], .., "0.95": x[18]}
static bool put_alpha(cJSON *o, const char *key, const double *x)
{
    cJSON *m = cJSON_AddObjectToObject(o, key);
    bool ok = m != NULL;
    for (int k = 0; k < RS_MOT_NALPHA && ok; k++) {
        char name[16];
        snprintf(name, sizeof name, "%.2f", 0.05 * (k + 1));
        ok = put(m, name, x[k]);
    }
    return ok;
}

char *rs_mot_result_json(const rs_mot_result *r)
{
    cJSON *o = cJSON_CreateObject();
    cJSON *c = o ? cJSON_AddObjectToObject(o, "crossings") : NULL;
    bool ok = c && put(o, "threshold_m", r->threshold_m) && cJSON_AddBoolToObject(o, "all_gt", r->all_gt) &&
              put(o, "steps", r->Nsteps) && put(o, "rows_off_step", (double)r->Nrows_off_step) &&
              put(o, "ignored", (double)r->Nignored) && put(o, "num_gt", (double)r->Ngt) &&
              put(o, "num_hyp", (double)r->Nhyp) && put(o, "vehicles", r->Nvehicles) && put(o, "tracks", r->Ntracks) &&
              put(o, "MOTA", r->mota) && put(o, "MOTP_m", r->motp_m) && put(o, "matches", (double)r->matches) &&
              put(o, "FP", (double)r->fp) && put(o, "FN", (double)r->fn) && put(o, "IDSW", (double)r->idsw) &&
              put(o, "Frag", (double)r->frag) && put(o, "IDF1", r->idf1) && put(o, "IDP", r->idp) &&
              put(o, "IDR", r->idr) && put(o, "IDTP", (double)r->idtp) && put(o, "IDFP", (double)r->idfp) &&
              put(o, "IDFN", (double)r->idfn) && put(o, "HOTA", r->hota) && put(o, "DetA", r->deta) &&
              put(o, "AssA", r->assa) && put(o, "LocA", r->loca) && put_alpha(o, "HOTA_alpha", r->hota_alpha) &&
              put_alpha(o, "DetA_alpha", r->deta_alpha) && put_alpha(o, "AssA_alpha", r->assa_alpha) &&
              put_alpha(o, "LocA_alpha", r->loca_alpha) && put(o, "rmse_m", r->rmse_m) &&
              put(o, "predicted_rms_m", r->predicted_rms_m) && put(o, "NEES", r->nees) &&
              put(o, "num_nees", (double)r->Nnees) && put(c, "count", (double)r->crossings) &&
              put(c, "kept", (double)r->crossings_kept) && put(c, "share", r->crossings_share);
    char *s = ok ? cJSON_Print(o) : NULL;
    cJSON_Delete(o);
    return s;
}

rs_status rs_mot_result_write_json(const rs_mot_result *r, const char *path, rs_err *err)
{
    char *s = rs_mot_result_json(r);
    if (!s) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = rs_io_write_file(path, s, strlen(s), err);
    free(s);
    return st;
}
