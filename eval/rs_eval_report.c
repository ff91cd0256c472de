// rs_eval_report.c -- an rs_eval_result as JSON (cJSON), written atomically.
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "eval/rs_eval.h"

// A number, or null for NaN. Returns false when out of memory.
static bool add_number(cJSON *o, const char *key, double x)
{
    return isnan(x) ? cJSON_AddNullToObject(o, key) != NULL : cJSON_AddNumberToObject(o, key, x) != NULL;
}

// {"<theta>": x[t], ...}
static bool add_per_threshold(cJSON *o, const char *key, const rs_eval_result *r, const double *x, const size_t *n)
{
    cJSON *m = cJSON_AddObjectToObject(o, key);
    if (!m) return false;
    for (int t = 0; t < r->Nthresholds; t++) {
        char name[32];
        snprintf(name, sizeof name, "%.15g", r->thresholds[t]);
        if (!add_number(m, name, x ? x[t] : (double)n[t])) return false;
    }
    return true;
}

static bool add_metrics(cJSON *o, const rs_eval_result *r, const rs_eval_metrics *m)
{
    return add_per_threshold(o, "AP", r, m->ap, NULL) && add_number(o, "mAP", m->map) && add_number(o, "AR", m->ar) &&
           add_per_threshold(o, "recall", r, m->recall, NULL) && add_number(o, "num_gt", (double)m->num_gt) &&
           add_number(o, "num_det", (double)m->num_det) && add_per_threshold(o, "num_dropped", r, NULL, m->num_dropped);
}

char *rs_eval_result_json(const rs_eval_result *r)
{
    cJSON *o = cJSON_CreateObject();
    bool ok = o &&
              cJSON_AddItemToObject(o, r->metres ? "thresholds_m" : "thresholds_px",
                                    cJSON_CreateDoubleArray(r->thresholds, r->Nthresholds)) &&
              add_number(o, "max_dets", r->max_dets) && add_metrics(o, r, &r->all);
    if (ok && r->groups) {
        cJSON *g = cJSON_AddObjectToObject(o, "groups");
        ok = g != NULL;
        for (int i = 0; ok && i < r->Ngroups; i++) {
            cJSON *one = cJSON_AddObjectToObject(g, r->groups[i].name);
            ok = one && add_metrics(one, r, &r->groups[i]);
        }
    }
    if (ok && r->classes) {
        cJSON *c = cJSON_AddObjectToObject(o, "classes");
        ok = c != NULL;
        for (int i = 0; ok && i < r->Nclasses; i++) {
            char id[32];
            snprintf(id, sizeof id, "%lld", r->classes[i].category_id);
            cJSON *one = cJSON_AddObjectToObject(c, id);
            ok = one && cJSON_AddStringToObject(one, "name", r->classes[i].name) && add_metrics(one, r, &r->classes[i]);
        }
    }
    char *s = ok ? cJSON_Print(o) : NULL;
    cJSON_Delete(o);
    return s;
}

rs_status rs_eval_result_write_json(const rs_eval_result *r, const char *path, rs_err *err)
{
    char *s = rs_eval_result_json(r);
    if (!s) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    size_t n = strlen(s);
    s[n] = '\n'; // replaces the terminator: the length is known
    rs_status st = rs_io_write_file(path, s, n + 1, err);
    free(s);
    return st;
}
