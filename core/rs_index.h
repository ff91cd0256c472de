// rs_index.h -- finding a row by its id in O(log n): a sorted index of string keys.
//
// Sites, their picks and lanes are looked up by id; a loop over every row per lookup made
// `site check` O(picks x landmarks) (100k landmarks and 100k picks: minutes). The index holds
// (key, row) pairs sorted by key and then row, so that a lookup returns the first row with the
// key, as a loop from the top would. Keys are borrowed: they must outlive the index, unchanged.
#pragma once
#include <stdbool.h>
#include <stddef.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    const char *key; // borrowed
    int row;
} rs_index_entry;

typedef struct {
    rs_index_entry *entries; // owned, (N,) sorted by key (strcmp, or strcasecmp when nocase), then row
    int N;
    bool nocase; // keys compared without case (ASCII letters)
} rs_index;

// Builds the index of keys[0..N) (a NULL key is left out). out: *ix, freed with rs_index_free.
// Errors: RS_ERR_NOMEM (then *ix is empty).
rs_status rs_index_init( // out
    rs_index *ix,
    // in
    const char *const *keys, int N, bool nocase, rs_err *err);

// The same from keys found at `stride` bytes apart from `first` (a field of an array of structs:
// rs_index_init_strided(&ix, &site->landmarks[0].id, sizeof *site->landmarks, N, ...)).
rs_status rs_index_init_strided( // out
    rs_index *ix,
    // in
    const char *const *first, size_t stride, int N, bool nocase, rs_err *err);

// The first row whose key equals `key` (in the index's comparison), or -1.
int rs_index_find(const rs_index *ix, const char *key);

// Frees the entries; accepts NULL and a zeroed index.
void rs_index_free(rs_index *ix);

#ifdef __cplusplus
}
#endif
