// rs_eval.c -- distance-threshold AP: max-dets, greedy nearest matching, all-point AP.
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "eval/internal/rs_eval_internal.h"

static const double default_thresholds_px[] = {2, 5, 10, 15, 20, 50};

// A detection's place in the evaluation order: key ascending = score descending.
typedef struct {
    uint64_t key;
    size_t index;
} scored;

// The key of a finite score: its IEEE-754 bits made to sort as unsigned integers in descending
// order of the score (-0 and +0 share one key, as they compare equal).
static uint64_t descending_key(double score)
{
    uint64_t u;
    if (score == 0) score = 0; // -0 -> +0
    memcpy(&u, &score, sizeof u);
    u = (u >> 63) ? ~u : u | (UINT64_C(1) << 63); // ascending order of the score
    return ~u;
}

// Stable LSD radix sort on key, 8 bits per pass, skipping the passes where every key has the same
// digit: O(N) per pass, and a stable sort of entries in input order keeps ties in input order.
// (qsort took 0.2 s of the 10^6-detection benchmark; this takes a few hundredths.)
// tmp: (N) scratch. The result is in s.
static void sort_scored(scored *s, scored *tmp, size_t N)
{
    for (int shift = 0; shift < 64; shift += 8) {
        size_t count[257] = {0};
        for (size_t i = 0; i < N; i++) count[((s[i].key >> shift) & 0xff) + 1]++;
        bool trivial = false;
        for (int b = 1; b <= 256; b++) trivial |= count[b] == N;
        if (trivial) continue;
        for (int b = 0; b < 256; b++) count[b + 1] += count[b];
        for (size_t i = 0; i < N; i++) tmp[count[(s[i].key >> shift) & 0xff]++] = s[i];
        memcpy(s, tmp, N * sizeof *s);
    }
}

// A detection kept by max-dets, filed under its image.
typedef struct {
    double u, v; // its point, pixels
    size_t rank; // position in the evaluation order (descending score, then input order)
    int category;
} slot;

// A ground truth or ignore region closer to a detection than the largest threshold.
typedef struct {
    double d2; // squared distance, pixels^2
    size_t gt; // annotation index
} candidate;

// The detections kept by max-dets, grouped by image (images in order; within an image in
// evaluation order), so that matching walks memory in order. Each has its candidates: the
// annotations of its image closer than the largest threshold, nearest first (equal distances:
// ground truths before ignore regions, then annotation order). Any threshold's nearest
// unmatched candidate closer than the threshold is among them, and when they are all matched
// the nearest one is at least the largest threshold away: a false positive at every threshold.
typedef struct {
    size_t Nkept;
    size_t *begin;          // (Nimages+1) slots of image m: begin[m] .. begin[m+1]-1
    slot *slots;            // (Nkept)
    size_t *cand_begin;     // (Nkept+1) candidates of slot j: cand_begin[j] .. cand_begin[j+1]-1
    candidate *cands;       // (cand_begin[Nkept])
    unsigned char *outcome; // (Nkept) by rank, scratch
    unsigned char *matched; // (Ngt) scratch
    double *tp_precision;   // (Nkept) scratch
} kept_dets;

enum { OUT_OF_SCOPE, TRUE_POSITIVE, FALSE_POSITIVE, DROPPED };

static void kept_free(kept_dets *k)
{
    free(k->begin);
    free(k->slots);
    free(k->cand_begin);
    free(k->cands);
    free(k->outcome);
    free(k->matched);
    free(k->tp_precision);
}

// Candidate order: nearer first; at equal distance a ground truth before an ignore region, then
// the earlier annotation.
static bool before(const rs_eval_data *d, const candidate *x, const candidate *y)
{
    if (x->d2 != y->d2) return x->d2 < y->d2;
    if (d->gt_crowd[x->gt] != d->gt_crowd[y->gt]) return !d->gt_crowd[x->gt];
    return x->gt < y->gt;
}

// Appends the candidates of detection e of image m to k->cands (insertion-sorted: lists are short).
static bool add_candidates(kept_dets *k, size_t *n, size_t *cap, const rs_eval_data *d, int m, const slot *e,
                           double theta_max_px)
{
    const size_t first = *n;
    for (size_t a = d->gt_begin[m]; a < d->gt_begin[m + 1]; a++) {
        const double du = d->gt_point[2 * a] - e->u, dv = d->gt_point[2 * a + 1] - e->v;
        const candidate c = {du * du + dv * dv, a};
        if (!(sqrt(c.d2) < theta_max_px)) continue;
        if (*n == *cap) {
            size_t grown = *cap ? 2 * *cap : 1024;
            candidate *p = realloc(k->cands, grown * sizeof *p);
            if (!p) return false;
            k->cands = p;
            *cap = grown;
        }
        size_t j = (*n)++;
        for (; j > first && before(d, &c, &k->cands[j - 1]); j--) k->cands[j] = k->cands[j - 1];
        k->cands[j] = c;
    }
    return true;
}

// Puts the detections in evaluation order, applies max-dets, files the kept ones by image and
// finds their candidates. On failure k holds what was allocated (kept_free).
static rs_status keep(kept_dets *k, const rs_eval_data *d, int max_dets, double theta_max_px, rs_err *err)
{
    size_t N = d->Ndets, M = (size_t)d->Nimages;
    scored *s = malloc((N ? N : 1) * sizeof *s), *tmp = malloc((N ? N : 1) * sizeof *tmp);
    size_t *next = calloc(M + 1, sizeof *next);
    k->begin = calloc(M + 1, sizeof *k->begin);
    k->slots = malloc((N ? N : 1) * sizeof *k->slots);
    k->cand_begin = malloc((N + 1) * sizeof *k->cand_begin);
    k->outcome = malloc(N ? N : 1);
    k->matched = malloc(d->Ngt ? d->Ngt : 1);
    k->tp_precision = malloc((N ? N : 1) * sizeof *k->tp_precision);
    if (!s || !tmp || !next || !k->begin || !k->slots || !k->cand_begin || !k->outcome || !k->matched ||
        !k->tp_precision)
        goto nomem;
    for (size_t i = 0; i < N; i++) s[i] = (scored){descending_key(d->det_score[i]), i};
    sort_scored(s, tmp, N);
    free(tmp);
    tmp = NULL;
    // max-dets: the first max_dets of each image in evaluation order
    size_t n = 0;
    for (size_t r = 0; r < N; r++) {
        int m = d->det_image[s[r].index];
        if (k->begin[m + 1] < (size_t)max_dets) {
            k->begin[m + 1]++;
            s[n++] = s[r];
        }
    }
    k->Nkept = n;
    for (size_t m = 0; m < M; m++) k->begin[m + 1] += k->begin[m];
    memcpy(next, k->begin, (M + 1) * sizeof *next);
    for (size_t r = 0; r < n; r++) {
        size_t i = s[r].index;
        k->slots[next[d->det_image[i]]++] = (slot){d->det_point[2 * i], d->det_point[2 * i + 1], r, d->det_category[i]};
    }
    size_t Ncands = 0, cap = 0;
    for (size_t m = 0; m < M; m++)
        for (size_t j = k->begin[m]; j < k->begin[m + 1]; j++) {
            k->cand_begin[j] = Ncands;
            if (!add_candidates(k, &Ncands, &cap, d, (int)m, &k->slots[j], theta_max_px)) goto nomem;
        }
    k->cand_begin[n] = Ncands;
    free(s);
    free(next);
    return RS_OK;
nomem:
    free(s);
    free(tmp);
    free(next);
    return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
}

// A scope: images of one group (group >= 0) and/or objects of one category (category >= 0).
typedef struct {
    int group, category;
} scope;

// Matches the detections of image m at threshold theta: fills k->outcome for them.
static void match_image(kept_dets *k, const rs_eval_data *d, int m, int category, double theta_px)
{
    memset(k->matched + d->gt_begin[m], 0, d->gt_begin[m + 1] - d->gt_begin[m]);
    for (size_t j = k->begin[m]; j < k->begin[m + 1]; j++) {
        const slot *e = &k->slots[j];
        if (category >= 0 && e->category != category) continue;
        // the nearest candidate not matched yet (ignore regions never are)
        unsigned char o = FALSE_POSITIVE;
        for (size_t c = k->cand_begin[j]; c < k->cand_begin[j + 1]; c++) {
            const size_t a = k->cands[c].gt;
            if (k->matched[a] || (category >= 0 && d->gt_category[a] != category)) continue;
            if (sqrt(k->cands[c].d2) < theta_px) {
                if (d->gt_crowd[a])
                    o = DROPPED;
                else {
                    o = TRUE_POSITIVE;
                    k->matched[a] = 1;
                }
            }
            break;
        }
        k->outcome[e->rank] = o;
    }
}

// Evaluates one scope.
static void evaluate_scope(rs_eval_metrics *out, kept_dets *k, const rs_eval_data *d, const double *theta_px, int T,
                           scope s)
{
    size_t num_gt = 0, num_det = 0;
    for (int m = 0; m < d->Nimages; m++) {
        if (s.group >= 0 && d->image_group[m] != s.group) continue;
        for (size_t a = d->gt_begin[m]; a < d->gt_begin[m + 1]; a++)
            num_gt += !d->gt_crowd[a] && (s.category < 0 || d->gt_category[a] == s.category);
        for (size_t j = k->begin[m]; j < k->begin[m + 1]; j++)
            num_det += s.category < 0 || k->slots[j].category == s.category;
    }
    out->num_gt = num_gt;
    out->num_det = num_det;
    double sum_ap = 0, sum_recall = 0;
    for (int t = 0; t < T; t++) {
        memset(k->outcome, OUT_OF_SCOPE, k->Nkept);
        for (int m = 0; m < d->Nimages; m++)
            if (s.group < 0 || d->image_group[m] == s.group) match_image(k, d, m, s.category, theta_px[t]);
        // the precision-recall points in evaluation order; dropped detections make none
        size_t tp = 0, fp = 0, dropped = 0;
        for (size_t r = 0; r < k->Nkept; r++) {
            switch (k->outcome[r]) {
            case TRUE_POSITIVE:
                tp++;
                k->tp_precision[tp - 1] = (double)tp / (double)(tp + fp);
                break;
            case FALSE_POSITIVE: fp++; break;
            case DROPPED: dropped++; break;
            default: break;
            }
        }
        out->num_dropped[t] = dropped;
        if (num_gt == 0) {
            out->ap[t] = out->recall[t] = NAN;
            continue;
        }
        // all-point interpolation: every true positive adds 1/num_gt of recall at the highest
        // precision reached at this recall or beyond
        double ap = 0, best_p = 0;
        for (size_t j = tp; j-- > 0;) {
            if (k->tp_precision[j] > best_p) best_p = k->tp_precision[j];
            ap += best_p;
        }
        out->ap[t] = ap / (double)num_gt;
        out->recall[t] = (double)tp / (double)num_gt;
        sum_ap += out->ap[t];
        sum_recall += out->recall[t];
    }
    out->map = num_gt ? sum_ap / T : NAN;
    out->ar = num_gt ? sum_recall / T : NAN;
}

static rs_status metrics_alloc(rs_eval_metrics *m, int T, const char *name)
{
    m->ap = malloc((size_t)T * sizeof *m->ap);
    m->recall = malloc((size_t)T * sizeof *m->recall);
    m->num_dropped = malloc((size_t)T * sizeof *m->num_dropped);
    m->name = name ? strdup(name) : NULL;
    return m->ap && m->recall && m->num_dropped && (!name || m->name) ? RS_OK : RS_ERR_NOMEM;
}

static void metrics_free(rs_eval_metrics *m)
{
    free(m->name);
    free(m->ap);
    free(m->recall);
    free(m->num_dropped);
}

void rs_eval_result_free(rs_eval_result *r)
{
    if (!r) return;
    free(r->thresholds);
    metrics_free(&r->all);
    for (int g = 0; r->groups && g < r->Ngroups; g++) metrics_free(&r->groups[g]);
    free(r->groups);
    for (int c = 0; r->classes && c < r->Nclasses; c++) metrics_free(&r->classes[c]);
    free(r->classes);
    free(r);
}

// Allocates and evaluates one row per group (groups) or per category (!groups), named by names.
// *Nrows counts the rows allocated so far, for rs_eval_result_free after a failure.
static rs_status evaluate_rows(rs_eval_metrics **rows, int *Nrows, int N, char *const *names, bool groups, kept_dets *k,
                               const rs_eval_data *d, const double *theta_px, int T)
{
    if (!(*rows = calloc((size_t)(N ? N : 1), sizeof **rows))) return RS_ERR_NOMEM;
    for (int i = 0; i < N; i++) {
        ++*Nrows;
        if (metrics_alloc(&(*rows)[i], T, names[i])) return RS_ERR_NOMEM;
        evaluate_scope(&(*rows)[i], k, d, theta_px, T, groups ? (scope){i, -1} : (scope){-1, i});
    }
    return RS_OK;
}

static rs_status check_options(const rs_eval_options *opt, const rs_eval_data *d, rs_err *err)
{
    if (opt->thresholds) {
        if (opt->Nthresholds < 1 || opt->Nthresholds > RS_EVAL_MAX_THRESHOLDS)
            return rs_err_set(err, RS_ERR_USAGE, "thresholds: need 1 to %d, not %d", RS_EVAL_MAX_THRESHOLDS,
                              opt->Nthresholds);
        for (int t = 0; t < opt->Nthresholds; t++) {
            double x = opt->thresholds[t];
            if (!isfinite(x) || x <= 0)
                return rs_err_set(err, RS_ERR_USAGE, "thresholds: %g is not a positive number", x);
            for (int u = 0; u < t; u++)
                if (opt->thresholds[u] == x) return rs_err_set(err, RS_ERR_USAGE, "thresholds: %g given twice", x);
        }
    }
    if (opt->max_dets < 0) return rs_err_set(err, RS_ERR_USAGE, "max-dets: %d is not positive", opt->max_dets);
    if (opt->by_group && !d->image_group)
        return rs_err_set(err, RS_ERR_USAGE, "by: the data was loaded without a group key");
    return RS_OK;
}

rs_status rs_eval_run(rs_eval_result **result, const rs_eval_data *d, const rs_eval_options *opt_in, rs_err *err)
{
    *result = NULL;
    const rs_eval_options defaults = {0};
    const rs_eval_options *opt = opt_in ? opt_in : &defaults;
    rs_status st = check_options(opt, d, err);
    if (st != RS_OK) return st;
    // nuScenes' centre-distance thresholds for ground distances, the seed paper's for pixels
    static const double default_thresholds_m[] = {0.5, 1, 2, 4};
    const double *theta = opt->thresholds ? opt->thresholds : d->metres ? default_thresholds_m : default_thresholds_px;
    const int T = opt->thresholds ? opt->Nthresholds
                  : d->metres     ? (int)(sizeof default_thresholds_m / sizeof(double))
                                  : (int)(sizeof default_thresholds_px / sizeof(double));

    rs_eval_result *r = calloc(1, sizeof *r);
    kept_dets k = {0};
    if (!r) goto nomem;
    r->Nthresholds = T;
    r->metres = d->metres;
    r->max_dets = opt->max_dets ? opt->max_dets : 100;
    if (!(r->thresholds = malloc((size_t)T * sizeof *theta))) goto nomem;
    memcpy(r->thresholds, theta, (size_t)T * sizeof *theta);
    double theta_max = 0;
    for (int t = 0; t < T; t++) theta_max = fmax(theta_max, theta[t]);
    if ((st = keep(&k, d, r->max_dets, theta_max, err))) goto fail;

    if (metrics_alloc(&r->all, T, NULL)) goto nomem;
    evaluate_scope(&r->all, &k, d, theta, T, (scope){-1, -1});
    if (opt->by_group && evaluate_rows(&r->groups, &r->Ngroups, d->Ngroups, d->group_names, true, &k, d, theta, T))
        goto nomem;
    if (opt->per_class) {
        if (evaluate_rows(&r->classes, &r->Nclasses, d->Ncategories, d->category_name, false, &k, d, theta, T))
            goto nomem;
        for (int c = 0; c < d->Ncategories; c++) r->classes[c].category_id = d->category_id[c];
    }
    kept_free(&k);
    *result = r;
    return RS_OK;
nomem:
    st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
fail:
    kept_free(&k);
    rs_eval_result_free(r);
    return st;
}
