// rs_json.h -- reading large JSON one member at a time, each member parsed by cJSON.
#pragma once
#include <stddef.h>

#include "core/rs_status.h"

#ifdef __cplusplus
extern "C" {
#endif

// Streaming over one JSON container. cJSON builds a tree of about 900
// bytes per detection and takes ~3 s for 10^6 of them; parsing a list one element at a time
// (cJSON stops where a value ends) keeps memory at the input size and is 3-4x faster. Objects
// are cut into members by a scanner that only finds where each value ends (strings, escapes,
// nesting), so that the ground truth's "annotations" list can be streamed in turn.

struct cJSON;

// Calls each(ctx, index, item, offset) for every element of the JSON list that text[begin,
// end) holds (surrounding white space allowed, and a UTF-8 byte order mark when begin is 0); item is the element parsed by cJSON (deleted
// after the call), offset the byte offset of its text. Stops at the first non-OK return and
// returns it. Syntax errors: RS_ERR_PARSE, "NAME:LINE: what".
typedef rs_status (*rs_json_item_fn)(void *ctx, size_t index, const struct cJSON *item, size_t offset, rs_err *err);
rs_status rs_json_array(const char *text, size_t begin, size_t end, const char *name, rs_json_item_fn each, void *ctx,
                        rs_err *err);

// Calls each(ctx, key, begin, end) for every member of the JSON object that text[begin, end)
// holds, with its name (unescaped) and the span of its value's text, which is not parsed.
typedef rs_status (*rs_json_span_fn)(void *ctx, const char *key, size_t begin, size_t end, rs_err *err);
rs_status rs_json_object(const char *text, size_t begin, size_t end, const char *name, rs_json_span_fn each, void *ctx,
                         rs_err *err);

// Parses text[begin, end) with cJSON. out: *item, owned by the caller (cJSON_Delete).
rs_status rs_json_parse(struct cJSON **item, const char *text, size_t begin, size_t end, const char *name, rs_err *err);

// The first member name that an object of item (item itself or any object nested in it) holds
// twice, or NULL when every object's names are distinct (cJSON keeps both and its lookups find
// the first: a file with a repeated key means two things). O(n log n) in each object's members.
// out: *object_key, when not NULL: the name of the member holding that object ("" for item)
const char *rs_json_repeated_key(const struct cJSON *item, const char **object_key);

// 1-based line number of byte `offset` of text.
int rs_json_line(const char *text, size_t offset);

#ifdef __cplusplus
}
#endif
