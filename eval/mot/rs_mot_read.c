// rs_mot_read.c -- the tracks CSV and the ground-truth tracks CSV read into rs_mot_data
// (eval/mot/rs_mot.h): columns found by name in the header, ids made dense, rows grouped by
// time step (the ground truth's distinct times; 1e-6 s tolerance).
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "core/rs_text.h"
#include "eval/mot/internal/rs_mot_internal.h"

#define TIME_TOL_S 1e-6

// One CSV file split in place: its lines' fields.
typedef struct {
    const char *name;
    char **field; // (Nrows * Ncols,) pointers into the text
    int *line;    // (Nrows,) 1-based line numbers
    long Nrows;
    int Ncols;
    char **header; // (Ncols,)
} csv_table;

static void csv_free(csv_table *t)
{
    free(t->field);
    free(t->line);
    free(t->header);
    t->field = NULL;
    t->line = NULL;
    t->header = NULL;
}

// Splits line (NUL-terminated, modified) at commas into out (max,), trailing '\r' removed.
static int split_fields(char *line, char **out, int max)
{
    size_t len = strlen(line);
    if (len && line[len - 1] == '\r') line[--len] = 0;
    int n = 0;
    char *p = line;
    for (;;) {
        char *c = strchr(p, ',');
        if (n < max) out[n] = p;
        n++;
        if (!c) break;
        *c = 0;
        p = c + 1;
    }
    return n;
}

// The line at *next (NUL-terminated in place), *next moved past it (NULL after the last), *lineno
// counted; NULL when there is none.
static char *next_line(char **next, int *lineno)
{
    char *line = *next;
    if (!line) return NULL;
    char *nl = strchr(line, '\n');
    *next = nl ? nl + 1 : NULL;
    if (nl) *nl = 0;
    ++*lineno;
    return line;
}

// Parses text (modified in place) into t. Blank lines are skipped.
static rs_status csv_parse(csv_table *t, char *text, const char *name, rs_err *err)
{
    memset(t, 0, sizeof(*t));
    t->name = name;
    long Nlines = 1;
    for (const char *p = text; *p; p++) Nlines += *p == '\n';
    int lineno = 0;
    char *line, *next = text;
    // header: the first non-blank line
    while ((line = next_line(&next, &lineno)) && !line[strspn(line, " \t\r")]) {}
    if (!line) return rs_err_set(err, RS_ERR_PARSE, "%s: empty (no header line)", name);
    char *tmp[256];
    const int Ncols = split_fields(line, tmp, 256);
    if (Ncols > 256) return rs_err_set(err, RS_ERR_PARSE, "%s:%d: more than 256 columns", name, lineno);
    t->Ncols = Ncols;
    t->header = malloc(sizeof(char *) * (size_t)Ncols);
    t->field = malloc(sizeof(char *) * (size_t)Ncols * (size_t)Nlines);
    t->line = malloc(sizeof(int) * (size_t)Nlines);
    if (!t->header || !t->field || !t->line) {
        csv_free(t);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    memcpy(t->header, tmp, sizeof(char *) * (size_t)Ncols);
    while ((line = next_line(&next, &lineno))) {
        if (!line[strspn(line, " \t\r")]) continue;
        char **f = &t->field[(size_t)t->Nrows * Ncols];
        const int n = split_fields(line, f, Ncols);
        if (n != Ncols) {
            csv_free(t);
            return rs_err_set(err, RS_ERR_PARSE, "%s:%d: %d fields, the header has %d", name, lineno, n, Ncols);
        }
        t->line[t->Nrows++] = lineno;
    }
    return RS_OK;
}

// The column named `col`, -1 if absent (required: an error).
static rs_status csv_column(int *icol, const csv_table *t, const char *col, bool required, rs_err *err)
{
    *icol = -1;
    for (int c = 0; c < t->Ncols; c++)
        if (!strcmp(t->header[c], col)) {
            *icol = c;
            return RS_OK;
        }
    return required ? rs_err_set(err, RS_ERR_PARSE, "%s:1: no column \"%s\" in the header", t->name, col) : RS_OK;
}

static const char *cell(const csv_table *t, long r, int c) { return t->field[(size_t)r * t->Ncols + c]; }

// A finite number, or NaN for an empty optional cell.
static rs_status cell_number(double *x, const csv_table *t, long r, int c, bool optional, rs_err *err)
{
    const char *s = cell(t, r, c);
    *x = NAN;
    if (!*s && optional) return RS_OK;
    char *end;
    *x = strtod(s, &end);
    if (!*s || *end || !rs_text_is_decimal(s)) // (strtod would take 0x10, inf, nan)
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: %s: \"%s\" is not a number", t->name, t->line[r], t->header[c], s);
    if (!isfinite(*x))
        return rs_err_set(err, RS_ERR_INVALID, "%s:%d: %s: not finite", t->name, t->line[r], t->header[c]);
    return RS_OK;
}

// Dense ids: ids[r] = the rank of row r's string among the distinct strings. out: *Nids
typedef struct {
    const char *s;
    long r;
} id_ref;

static int cmp_id_ref(const void *a, const void *b)
{
    const id_ref *x = a, *y = b;
    const int c = strcmp(x->s, y->s);
    return c ? c : (x->r > y->r) - (x->r < y->r);
}

static rs_status dense_ids(int *ids, int *Nids, const csv_table *t, int c, rs_err *err)
{
    id_ref *refs = malloc(sizeof(id_ref) * (size_t)(t->Nrows > 0 ? t->Nrows : 1));
    if (!refs) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (long r = 0; r < t->Nrows; r++) {
        refs[r] = (id_ref){cell(t, r, c), r};
        if (!*refs[r].s) {
            free(refs);
            return rs_err_set(err, RS_ERR_INVALID, "%s:%d: %s: empty", t->name, t->line[r], t->header[c]);
        }
    }
    qsort(refs, (size_t)t->Nrows, sizeof(id_ref), cmp_id_ref);
    int n = 0;
    for (long i = 0; i < t->Nrows; i++) {
        if (i > 0 && strcmp(refs[i].s, refs[i - 1].s)) n++;
        ids[refs[i].r] = n;
    }
    *Nids = t->Nrows > 0 ? n + 1 : 0;
    free(refs);
    return RS_OK;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

// The step of time t: the index of the step time within TIME_TOL_S, -1 if none.
static int find_step(const double *t_s, int N, double t)
{
    int lo = 0, hi = N; // first index with t_s >= t - tol
    while (lo < hi) {
        const int mid = (lo + hi) / 2;
        if (t_s[mid] < t - TIME_TOL_S)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < N && fabs(t_s[lo] - t) <= TIME_TOL_S ? lo : -1;
}

typedef struct {
    rs_mot__row row;
    int line;
} line_row;

static int cmp_line_row(const void *a, const void *b)
{
    const rs_mot__row *x = &((const line_row *)a)->row, *y = &((const line_row *)b)->row;
    if (x->step != y->step) return x->step < y->step ? -1 : 1;
    return (x->id > y->id) - (x->id < y->id);
}

// Sorts rows by (step, id), refuses an id twice at one step, fills *out and first (Nsteps + 1,).
static rs_status group_rows(rs_mot__row **out, long *first, line_row *rows, long N, int Nsteps, const csv_table *t,
                            const char *what, rs_err *err)
{
    qsort(rows, (size_t)N, sizeof(line_row), cmp_line_row);
    *out = malloc(sizeof(rs_mot__row) * (size_t)(N > 0 ? N : 1));
    if (!*out) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (long i = 0; i < N; i++) {
        if (i > 0 && !cmp_line_row(&rows[i], &rows[i - 1]))
            return rs_err_set(err, RS_ERR_INVALID, "%s:%d: %s: the same %s at the time of line %d", t->name,
                              rows[i].line, what, what, rows[i - 1].line);
        (*out)[i] = rows[i].row;
    }
    long i = 0;
    for (int s = 0; s <= Nsteps; s++) {
        while (i < N && rows[i].row.step < s) i++;
        first[s] = i;
    }
    return RS_OK;
}

// Ground truth: times, steps, vehicles, camera sets.
static rs_status read_gt(rs_mot_data *d, const csv_table *t, rs_err *err)
{
    int ct, cid, ce, cn, ccam;
    rs_status st;
    if ((st = csv_column(&ct, t, "time_s", true, err)) || (st = csv_column(&cid, t, "vehicle_id", true, err)) ||
        (st = csv_column(&ce, t, "e_m", true, err)) || (st = csv_column(&cn, t, "n_m", true, err)) ||
        (st = csv_column(&ccam, t, "cameras", true, err)))
        return st;
    if (t->Nrows == 0) return rs_err_set(err, RS_ERR_INVALID, "%s: no ground-truth rows", t->name);
    const size_t n = (size_t)t->Nrows;
    double *times = malloc(sizeof(double) * n);
    int *ids = malloc(sizeof(int) * n);
    line_row *rows = calloc(n, sizeof(line_row));
    char *cam_names[RS_MOT__MAX_CAMERAS];
    int Ncams = 0;
    if (!times || !ids || !rows) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (long r = 0; r < t->Nrows && !st; r++) {
        rs_mot__row *w = &rows[r].row;
        rows[r].line = t->line[r];
        if ((st = cell_number(&times[r], t, r, ct, false, err)) || (st = cell_number(&w->e_m, t, r, ce, false, err)) ||
            (st = cell_number(&w->n_m, t, r, cn, false, err)))
            break;
        char *cams = (char *)cell(t, r, ccam);
        for (char *save = NULL, *tok = strtok_r(cams, "+", &save); tok && !st; tok = strtok_r(NULL, "+", &save)) {
            int c = 0;
            while (c < Ncams && strcmp(cam_names[c], tok)) c++;
            if (c == Ncams) {
                if (Ncams == RS_MOT__MAX_CAMERAS)
                    st = rs_err_set(err, RS_ERR_INVALID, "%s:%d: cameras: more than %d distinct camera ids", t->name,
                                    t->line[r], RS_MOT__MAX_CAMERAS);
                else
                    cam_names[Ncams++] = tok;
            }
            w->cams |= 1u << c;
        }
        w->seen = w->cams != 0;
        w->cov_en[0] = w->cov_en[1] = w->cov_en[2] = NAN;
    }
    if (!st) st = dense_ids(ids, &d->Nvehicles, t, cid, err);
    if (!st) {
        double *sorted = malloc(sizeof(double) * n);
        if (!sorted) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (!st) {
            memcpy(sorted, times, sizeof(double) * n);
            qsort(sorted, n, sizeof(double), cmp_double);
            int Nsteps = 0;
            for (size_t i = 0; i < n; i++)
                if (Nsteps == 0 || sorted[i] - sorted[Nsteps - 1] > TIME_TOL_S) sorted[Nsteps++] = sorted[i];
            d->t_s = sorted;
            d->Nsteps = Nsteps;
            d->Ncams = Ncams;
            for (long r = 0; r < t->Nrows; r++) {
                rows[r].row.id = ids[r];
                rows[r].row.step = find_step(d->t_s, Nsteps, times[r]);
            }
            d->gt_first = malloc(sizeof(long) * (size_t)(Nsteps + 1));
            if (!d->gt_first) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        }
    }
    if (!st) st = group_rows(&d->gt, d->gt_first, rows, t->Nrows, d->Nsteps, t, "vehicle_id", err);
    d->Ngt = t->Nrows;
    free(times);
    free(ids);
    free(rows);
    return st;
}

// Tracks: rows at a ground-truth step, with their covariance.
static rs_status read_tracks(rs_mot_data *d, const csv_table *t, rs_err *err)
{
    int ct, cid, ce, cn, cse, csn, cc;
    rs_status st;
    if ((st = csv_column(&ct, t, "time_s", true, err)) || (st = csv_column(&cid, t, "track_id", true, err)) ||
        (st = csv_column(&ce, t, "e_m", true, err)) || (st = csv_column(&cn, t, "n_m", true, err)) ||
        (st = csv_column(&cse, t, "sigma_e_m", false, err)) || (st = csv_column(&csn, t, "sigma_n_m", false, err)) ||
        (st = csv_column(&cc, t, "cov_en_m2", false, err)))
        return st;
    const size_t n = (size_t)(t->Nrows > 0 ? t->Nrows : 1);
    int *ids = malloc(sizeof(int) * n);
    line_row *rows = calloc(n, sizeof(line_row));
    long N = 0;
    if (!ids || !rows) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) st = dense_ids(ids, &d->Ntracks, t, cid, err);
    for (long r = 0; r < t->Nrows && !st; r++) {
        rs_mot__row w = {.id = ids[r]};
        double time, se = NAN, sn = NAN, c = NAN;
        if ((st = cell_number(&time, t, r, ct, false, err)) || (st = cell_number(&w.e_m, t, r, ce, false, err)) ||
            (st = cell_number(&w.n_m, t, r, cn, false, err)) ||
            (cse >= 0 && (st = cell_number(&se, t, r, cse, true, err))) ||
            (csn >= 0 && (st = cell_number(&sn, t, r, csn, true, err))) ||
            (cc >= 0 && (st = cell_number(&c, t, r, cc, true, err))))
            break;
        if (se < 0 || sn < 0) {
            st = rs_err_set(err, RS_ERR_INVALID, "%s:%d: %s: negative", t->name, t->line[r],
                            se < 0 ? "sigma_e_m" : "sigma_n_m");
            break;
        }
        w.cov_en[0] = se * se;
        w.cov_en[1] = c;
        w.cov_en[2] = sn * sn;
        w.step = find_step(d->t_s, d->Nsteps, time);
        if (w.step < 0) {
            d->Noff_step++;
            continue;
        }
        rows[N++] = (line_row){w, t->line[r]};
    }
    d->hyp_first = st ? NULL : malloc(sizeof(long) * (size_t)(d->Nsteps + 1));
    if (!st && !d->hyp_first) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) st = group_rows(&d->hyp, d->hyp_first, rows, N, d->Nsteps, t, "track_id", err);
    d->Nhyp = N;
    free(ids);
    free(rows);
    return st;
}

rs_status rs_mot_parse(rs_mot_data **data, const char *tracks_text, const char *tracks_name, const char *gt_text,
                       const char *gt_name, rs_err *err)
{
    *data = NULL;
    rs_mot_data *d = calloc(1, sizeof(*d));
    char *tt = strdup(tracks_text), *gg = strdup(gt_text);
    csv_table tt_t = {0}, gg_t = {0};
    rs_status st = RS_OK;
    if (!d || !tt || !gg) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st && !(st = csv_parse(&gg_t, gg, gt_name, err)) && !(st = read_gt(d, &gg_t, err)) &&
        !(st = csv_parse(&tt_t, tt, tracks_name, err)))
        st = read_tracks(d, &tt_t, err);
    csv_free(&tt_t);
    csv_free(&gg_t);
    free(tt);
    free(gg);
    if (st) {
        rs_mot_data_free(d);
        return st;
    }
    *data = d;
    return RS_OK;
}

rs_status rs_mot_load(rs_mot_data **data, const char *tracks_path, const char *gt_path, rs_err *err)
{
    *data = NULL;
    char *tt = NULL, *gg = NULL;
    size_t nt = 0, ng = 0;
    rs_status st = rs_io_read_file(&tt, &nt, tracks_path, err);
    if (!st) st = rs_text_check_no_nul(tt, nt, tracks_path, err);
    if (!st) st = rs_io_read_file(&gg, &ng, gt_path, err);
    if (!st) st = rs_text_check_no_nul(gg, ng, gt_path, err);
    if (!st) st = rs_mot_parse(data, tt, tracks_path, gg, gt_path, err);
    free(tt);
    free(gg);
    return st;
}

void rs_mot_data_free(rs_mot_data *d)
{
    if (!d) return;
    free(d->t_s);
    free(d->gt);
    free(d->gt_first);
    free(d->hyp);
    free(d->hyp_first);
    free(d);
}
