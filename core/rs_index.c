// rs_index.c -- the sorted index of core/rs_index.h (qsort and a binary search).
#include "core/rs_index.h"

#include <stdlib.h>
#include <string.h>
#include <strings.h>

static int cmp_case(const void *a, const void *b)
{
    const rs_index_entry *x = a, *y = b;
    const int c = strcmp(x->key, y->key);
    return c ? c : (x->row > y->row) - (x->row < y->row);
}

static int cmp_nocase(const void *a, const void *b)
{
    const rs_index_entry *x = a, *y = b;
    const int c = strcasecmp(x->key, y->key);
    return c ? c : (x->row > y->row) - (x->row < y->row);
}

rs_status rs_index_init_strided(rs_index *ix, const char *const *first, size_t stride, int N, bool nocase, rs_err *err)
{
    memset(ix, 0, sizeof *ix);
    ix->nocase = nocase;
    if (N <= 0) return RS_OK;
    ix->entries = malloc((size_t)N * sizeof *ix->entries);
    if (!ix->entries) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; i < N; i++) {
        const char *key = *(const char *const *)((const char *)first + (size_t)i * stride);
        if (key) ix->entries[ix->N++] = (rs_index_entry){key, i};
    }
    qsort(ix->entries, (size_t)ix->N, sizeof *ix->entries, nocase ? cmp_nocase : cmp_case);
    return RS_OK;
}

rs_status rs_index_init(rs_index *ix, const char *const *keys, int N, bool nocase, rs_err *err)
{
    return rs_index_init_strided(ix, keys, sizeof *keys, N, nocase, err);
}

int rs_index_find(const rs_index *ix, const char *key)
{
    if (!ix || !key) return -1;
    int lo = 0, hi = ix->N; // the first entry not below key, in [lo, hi]
    while (lo < hi) {
        const int mid = lo + (hi - lo) / 2;
        const int c = ix->nocase ? strcasecmp(ix->entries[mid].key, key) : strcmp(ix->entries[mid].key, key);
        if (c < 0)
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo == ix->N) return -1;
    const int c = ix->nocase ? strcasecmp(ix->entries[lo].key, key) : strcmp(ix->entries[lo].key, key);
    return c ? -1 : ix->entries[lo].row;
}

void rs_index_free(rs_index *ix)
{
    if (!ix) return;
    free(ix->entries);
    ix->entries = NULL;
    ix->N = 0;
}
