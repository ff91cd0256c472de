// rs_site_json.c -- reading the members of a site's JSON files with the messages the site
// reader gives (geo/internal/rs_site_internal.h): the field's full name, what was expected, what
// was found; and the JSON-level checks every site file gets (repeated keys). Called by
// rs_site_read.c; calls rs_site_report.c.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "geo/internal/rs_site_internal.h"

// Parses JSON text; reports a syntax error with its line and column.
static cJSON *parse_json(rs_site__reader *c, const char *text)
{
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithOpts(text, &end, 1);
    if (root) return root;
    if (!c->r->nomem && !*text) {
        ERR(c, RS_ERR_PARSE, NULL, "invalid JSON: the file is empty");
        return NULL;
    }
    int line = 1, column = 1;
    for (const char *p = text; end && p < end && *p; p++) {
        if (*p == '\n')
            line++, column = 1;
        else
            column++;
    }
    char near[32] = "";
    int n = 0;
    for (const char *p = end; p && *p && n < 20; p++) near[n++] = (*p == '\n' || *p == '\r' || *p == '\t') ? ' ' : *p;
    near[n] = '\0';
    if (n)
        ERR_AT(c, RS_ERR_PARSE, line, NULL, "invalid JSON at column %d, near '%s'", column, near);
    else
        ERR_AT(c, RS_ERR_PARSE, line, NULL, "invalid JSON at column %d: unexpected end of file", column);
    return NULL;
}

// Reads and parses the JSON file `name` of the site folder, reporting what is wrong with it.
// c->file is *path (owned by the caller, free() it and reset c->file) until the caller is done.
cJSON *rs_site__read_json_file(rs_site__reader *c, char **path, const char *name, const char *why, size_t max_bytes)
{
    *path = rs_site__join(c, c->site->dir, name);
    if (!*path) return NULL;
    c->file = *path;
    char *text = rs_site__read_file(c, why, max_bytes, NULL);
    const char *json = text && !strncmp(text, "\xEF\xBB\xBF", 3) ? text + 3 : text; // UTF-8 BOM
    cJSON *root = json ? parse_json(c, json) : NULL;
    free(text);
    return root;
}

// "prefix.key" (or "key") into buf, truncated to fit. Called for every member read (a million
// times for a million landmarks): no printf.
const char *rs_site__field_name(char *buf, size_t size, const char *prefix, const char *key)
{
    size_t n = 0;
    for (const char *part[3] = {prefix, prefix ? "." : NULL, key}, **p = part; p < part + 3; p++)
        for (const char *t = *p; t && *t && n + 1 < size; t++) buf[n++] = *t;
    if (size) buf[n < size ? n : size - 1] = '\0';
    return buf;
}

// A short rendering of a JSON value for messages: the value itself, truncated.
void rs_site__json_excerpt(char *buf, size_t size, const cJSON *item)
{
    char *s = cJSON_PrintUnformatted(item);
    snprintf(buf, size, "%s", s ? s : "?");
    if (s && strlen(s) >= size && size > 4) strcpy(buf + size - 4, "...");
    cJSON_free(s);
}

// Looks up obj[key], writing its full name ("prefix.key") into field. A missing member is
// reported if required ("missing (EXPECTED)"); returns NULL then.
const cJSON *rs_site__member(rs_site__reader *c, const cJSON *obj, const char *prefix, const char *key, bool required,
                             const char *expected, char *field, size_t size)
{
    rs_site__field_name(field, size, prefix, key);
    const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!it && required) ERR(c, RS_ERR_PARSE, field, "missing (%s)", expected);
    return it;
}

// Reports a member of the wrong JSON type, quoting what was found.
void rs_site__wrong_type(rs_site__reader *c, const char *field, const cJSON *it, const char *expected)
{
    char got[64];
    rs_site__json_excerpt(got, sizeof got, it);
    ERR(c, RS_ERR_PARSE, field, "not %s (%s)", expected, got);
}

// Reads obj[key] as a finite number. Reports a missing required field, a wrong type or a
// non-finite value; returns false then (and for a missing optional field).
bool rs_site__get_number(rs_site__reader *c, const cJSON *obj, const char *prefix, const char *key, bool required,
                         double *out)
{
    char field[256];
    const cJSON *it = rs_site__member(c, obj, prefix, key, required, "a number", field, sizeof field);
    if (!it) return false;
    if (!cJSON_IsNumber(it)) {
        rs_site__wrong_type(c, field, it, "a number");
        return false;
    }
    if (!isfinite(it->valuedouble)) {
        ERR(c, RS_ERR_INVALID, field, "not a finite number");
        return false;
    }
    *out = it->valuedouble;
    return true;
}

// get_number, and the value must be > 0.
bool rs_site__get_positive(rs_site__reader *c, const cJSON *obj, const char *prefix, const char *key, bool required,
                           double *out)
{
    double v;
    if (!rs_site__get_number(c, obj, prefix, key, required, &v)) return false;
    if (v <= 0) {
        char field[256];
        ERR(c, RS_ERR_INVALID, rs_site__field_name(field, sizeof field, prefix, key), "%g must be > 0", v);
        return false;
    }
    *out = v;
    return true;
}

// get_positive, and the value must lie in [lo, hi] (a physical range: geo/rs_site.h), `what`
// saying what the bounds mean.
bool rs_site__get_in_range(rs_site__reader *c, const cJSON *obj, const char *prefix, const char *key, bool required,
                           double lo, double hi, const char *unit, const char *what, double *out)
{
    double v;
    if (!rs_site__get_positive(c, obj, prefix, key, required, &v)) return false;
    if (!(v >= lo && v <= hi)) {
        char field[256];
        ERR(c, RS_ERR_INVALID, rs_site__field_name(field, sizeof field, prefix, key),
            "%g %s is outside [%g, %g] %s: %s", v, unit, lo, hi, unit, what);
        return false;
    }
    *out = v;
    return true;
}

// Reads obj[key] as a non-empty string (pointer into the JSON tree).
bool rs_site__get_string(rs_site__reader *c, const cJSON *obj, const char *prefix, const char *key, bool required,
                         const char **out)
{
    char field[256];
    const cJSON *it = rs_site__member(c, obj, prefix, key, required, "a string", field, sizeof field);
    if (!it) return false;
    if (!cJSON_IsString(it)) {
        rs_site__wrong_type(c, field, it, "a string in double quotes");
        return false;
    }
    if (!it->valuestring[0]) {
        ERR(c, RS_ERR_INVALID, field, "empty");
        return false;
    }
    *out = it->valuestring;
    return true;
}

// Reads obj[key] as a JSON object; NULL if missing (reported if required) or not an object.
const cJSON *rs_site__get_object(rs_site__reader *c, const cJSON *obj, const char *prefix, const char *key,
                                 bool required, const char *expected)
{
    char field[256];
    const cJSON *it = rs_site__member(c, obj, prefix, key, required, expected, field, sizeof field);
    if (it && !cJSON_IsObject(it)) {
        ERR(c, RS_ERR_PARSE, field, "not an object (expected %s)", expected);
        return NULL;
    }
    return it;
}

// Warns about members of obj not in `known` (NULL-terminated): most often a misspelt name.
void rs_site__warn_unknown_keys(rs_site__reader *c, const cJSON *obj, const char *prefix, const char *const *known)
{
    for (const cJSON *it = obj ? obj->child : NULL; it; it = it->next) {
        bool found = false;
        for (int i = 0; known[i] && !found; i++) found = it->string && !strcmp(it->string, known[i]);
        if (found) continue;
        char field[256];
        WARN(c, rs_site__field_name(field, sizeof field, prefix, it->string ? it->string : "?"),
             "unknown field, ignored (misspelt?)");
    }
}

int rs_site__cmp_key(const void *a, const void *b) { return strcmp(*(const char *const *)a, *(const char *const *)b); }

// JSON leaves repeated keys to the reader: cJSON keeps both and finds the first, other tools
// take the last, so the same file would mean two things. Every object in `item` (recursively;
// cJSON bounds the nesting) is checked, each repeated key reported once, in O(k log k) for k
// keys. prefix: the field name of item (NULL at the top).
void rs_site__check_duplicate_keys(rs_site__reader *c, const cJSON *item, const char *prefix)
{
    char sub[256];
    if (cJSON_IsArray(item)) {
        int j = 0;
        for (const cJSON *e = item->child; e; e = e->next, j++) {
            if (!cJSON_IsArray(e) && !cJSON_IsObject(e)) continue;
            snprintf(sub, sizeof sub, "%s[%d]", prefix ? prefix : "", j);
            rs_site__check_duplicate_keys(c, e, sub);
        }
        return;
    }
    if (!cJSON_IsObject(item)) return;
    int n = 0;
    for (const cJSON *e = item->child; e; e = e->next) n++;
    if (n >= 2) {
        const char **keys = malloc((size_t)n * sizeof *keys);
        if (!keys) {
            c->r->nomem = true;
            return;
        }
        int k = 0;
        for (const cJSON *e = item->child; e; e = e->next) keys[k++] = e->string ? e->string : "";
        qsort(keys, (size_t)n, sizeof *keys, rs_site__cmp_key);
        for (k = 1; k < n; k++)
            if (!strcmp(keys[k], keys[k - 1]) && (k == 1 || strcmp(keys[k], keys[k - 2])))
                ERR(c, RS_ERR_PARSE, rs_site__field_name(sub, sizeof sub, prefix, keys[k]),
                    "appears more than once in the same object: JSON readers disagree on which one counts "
                    "(roadside would take the first); keep one");
        free(keys);
    }
    for (const cJSON *e = item->child; e; e = e->next)
        if (cJSON_IsArray(e) || cJSON_IsObject(e))
            rs_site__check_duplicate_keys(c, e,
                                          rs_site__field_name(sub, sizeof sub, prefix, e->string ? e->string : "?"));
}
