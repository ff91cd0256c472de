// rs_json.c -- cutting a JSON array or object into its members, each parsed by cJSON
// (core/rs_json.h).
#include "core/rs_json.h"

#include <cjson/cJSON.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

int rs_json_line(const char *text, size_t offset)
{
    int line = 1;
    for (const char *p = text, *e = text + offset; (p = memchr(p, '\n', (size_t)(e - p))); p++) line++;
    return line;
}

static bool is_space(char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; }

static size_t skip_space(const char *t, size_t i, size_t end)
{
    while (i < end && is_space(t[i])) i++;
    return i;
}

// Past a UTF-8 byte order mark at the very start of the text (Windows editors write one; RFC 8259
// lets a parser ignore it).
static size_t skip_bom(const char *t, size_t i, size_t end)
{
    return i == 0 && end >= 3 && !memcmp(t, "\xEF\xBB\xBF", 3) ? 3 : i;
}

// End of the string whose opening quote is at t[i]: the index just past its closing quote, or
// `end` if it is unterminated.
static size_t skip_string(const char *t, size_t i, size_t end)
{
    for (i++; i < end; i++) {
        if (t[i] == '\\')
            i++;
        else if (t[i] == '"')
            return i + 1;
    }
    return end;
}

// Index of the ',' or closing bracket that ends the value starting at t[i] (nesting and strings
// skipped), or `end` if there is none.
static size_t skip_value(const char *t, size_t i, size_t end)
{
    int depth = 0;
    while (i < end) {
        char c = t[i];
        if (c == '"') {
            i = skip_string(t, i, end);
            continue;
        }
        if (c == '{' || c == '[')
            depth++;
        else if (c == '}' || c == ']') {
            if (depth == 0) return i;
            depth--;
        } else if (c == ',' && depth == 0)
            return i;
        i++;
    }
    return end;
}

static rs_status syntax(const char *t, size_t at, const char *name, const char *what, rs_err *err)
{
    return rs_err_set(err, RS_ERR_PARSE, "%s:%d: JSON syntax: %s", name, rs_json_line(t, at), what);
}

// Parses the value starting at text[begin] with cJSON, which stops where the value ends.
// out: *item (caller deletes), *stop: the index just past the value.
static rs_status parse_value(cJSON **item, size_t *stop, const char *text, size_t begin, size_t end, const char *name,
                             rs_err *err)
{
    const char *after = NULL;
    *item = cJSON_ParseWithLengthOpts(text + begin, end - begin, &after, false);
    if (!*item) {
        size_t at = after && after >= text + begin ? (size_t)(after - text) : begin;
        if (at > end) at = end;
        char near[24] = {0};
        size_t n = end - at < sizeof near - 1 ? end - at : sizeof near - 1;
        for (size_t k = 0; k < n; k++) near[k] = text[at + k] == '\n' ? ' ' : text[at + k];
        return rs_err_set(err, RS_ERR_PARSE, "%s:%d: JSON syntax error near '%s'", name, rs_json_line(text, at), near);
    }
    *stop = (size_t)(after - text);
    return RS_OK;
}

rs_status rs_json_parse(cJSON **item, const char *text, size_t begin, size_t end, const char *name, rs_err *err)
{
    size_t stop = 0;
    rs_status st = parse_value(item, &stop, text, begin, end, name, err);
    if (st != RS_OK) return st;
    size_t after = skip_space(text, stop, end);
    if (after != end) {
        cJSON_Delete(*item);
        *item = NULL;
        return syntax(text, after, name, "unexpected text after a value", err);
    }
    return RS_OK;
}

// The end of a container: only white space may follow its closing bracket at text[i].
static rs_status closed(const char *text, size_t i, size_t end, const char *name, rs_err *err)
{
    return skip_space(text, i + 1, end) == end ? RS_OK
                                               : syntax(text, i + 1, name, "unexpected text after the end", err);
}

rs_status rs_json_array(const char *text, size_t begin, size_t end, const char *name, rs_json_item_fn each, void *ctx,
                        rs_err *err)
{
    size_t i = skip_space(text, skip_bom(text, begin, end), end);
    if (i == end || text[i] != '[') return syntax(text, i, name, "expected a list '['", err);
    i = skip_space(text, i + 1, end);
    if (i < end && text[i] == ']') return closed(text, i, end, name, err);
    for (size_t index = 0;; index++) {
        cJSON *item = NULL;
        size_t stop = 0;
        rs_status st = parse_value(&item, &stop, text, i, end, name, err);
        if (st != RS_OK) return st;
        st = each(ctx, index, item, i, err);
        cJSON_Delete(item);
        if (st != RS_OK) return st;
        i = skip_space(text, stop, end);
        if (i < end && text[i] == ',') {
            i = skip_space(text, i + 1, end);
            continue;
        }
        if (i < end && text[i] == ']') return closed(text, i, end, name, err);
        return syntax(text, i, name, i < end ? "expected ',' or ']'" : "unterminated list", err);
    }
}

rs_status rs_json_object(const char *text, size_t begin, size_t end, const char *name, rs_json_span_fn each, void *ctx,
                         rs_err *err)
{
    size_t i = skip_space(text, skip_bom(text, begin, end), end);
    if (i == end || text[i] != '{') return syntax(text, i, name, "expected an object '{'", err);
    i = skip_space(text, i + 1, end);
    if (i < end && text[i] == '}') return closed(text, i, end, name, err);
    for (;;) {
        if (i == end || text[i] != '"') return syntax(text, i, name, "expected a member name", err);
        size_t kend = skip_string(text, i, end);
        cJSON *k = NULL;
        rs_status st = rs_json_parse(&k, text, i, kend, name, err);
        if (st != RS_OK) return st;
        char *key = cJSON_IsString(k) ? strdup(k->valuestring) : NULL;
        cJSON_Delete(k);
        if (!key) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", name);
        i = skip_space(text, kend, end);
        if (i == end || text[i] != ':') {
            free(key);
            return syntax(text, i, name, "expected ':' after a member name", err);
        }
        i = skip_space(text, i + 1, end);
        size_t vend = skip_value(text, i, end);
        size_t trimmed = vend;
        while (trimmed > i && is_space(text[trimmed - 1])) trimmed--;
        if (vend == end || trimmed == i) {
            free(key);
            return syntax(text, i, name, vend == end ? "unterminated object" : "expected a value", err);
        }
        st = each(ctx, key, i, trimmed, err);
        free(key);
        if (st != RS_OK) return st;
        if (text[vend] == ',') {
            i = skip_space(text, vend + 1, end);
            continue;
        }
        if (text[vend] != '}') return syntax(text, vend, name, "mismatched bracket", err);
        return closed(text, vend, end, name, err);
    }
}

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

const char *rs_json_repeated_key(const cJSON *item, const char **object_key)
{
    if (!item || !(cJSON_IsObject(item) || cJSON_IsArray(item))) return NULL;
    size_t n = 0;
    for (const cJSON *m = item->child; m; m = m->next) n++;
    if (cJSON_IsObject(item) && n > 1) {
        const char **names = malloc(n * sizeof *names);
        if (names) { // (out of memory: the names go unchecked, as cJSON would take them)
            size_t k = 0;
            for (const cJSON *m = item->child; m; m = m->next) names[k++] = m->string ? m->string : "";
            qsort(names, n, sizeof *names, compare_names);
            const char *twice = NULL;
            for (k = 1; k < n && !twice; k++)
                if (!strcmp(names[k - 1], names[k])) twice = names[k];
            free(names);
            if (twice) {
                if (object_key) *object_key = item->string ? item->string : "";
                return twice;
            }
        }
    }
    for (const cJSON *m = item->child; m; m = m->next) {
        const char *twice = rs_json_repeated_key(m, object_key);
        if (twice) return twice;
    }
    return NULL;
}
