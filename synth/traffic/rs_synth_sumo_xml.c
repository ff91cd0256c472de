// rs_synth_sumo_xml.c -- SUMO's XML files through expat. See internal/rs_synth_sumo_xml.h.
#include "synth/traffic/internal/rs_synth_sumo_xml.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *rs_synth_sumo_xml_attr(const XML_Char **a, const char *name)
{
    for (int i = 0; a[i]; i += 2)
        if (!strcmp(a[i], name)) return a[i + 1];
    return NULL;
}

// Stops the parser with an error naming the file and the current line.
void rs_synth_sumo_xml_fail(rs_synth_sumo_xml *c, rs_status st, const char *field, const char *what, const char *value)
{
    if (c->st) return;
    c->st = rs_err_set(c->err, st, "%s:%lu: %s: %s%s%s%s", c->path, (unsigned long)XML_GetCurrentLineNumber(c->p),
                       field, value ? "'" : "", value ? value : "", value ? "' " : "", what);
    XML_StopParser(c->p, XML_FALSE);
}

bool rs_synth_sumo_xml_double(rs_synth_sumo_xml *c, const XML_Char **a, const char *elem, const char *name, double *out)
{
    const char *s = rs_synth_sumo_xml_attr(a, name);
    char field[64];
    snprintf(field, sizeof field, "%s.%s", elem, name);
    if (!s) {
        rs_synth_sumo_xml_fail(c, RS_ERR_PARSE, field, "missing", NULL);
        return false;
    }
    char *end;
    errno = 0;
    *out = strtod(s, &end);
    if (end == s || *end || errno || !isfinite(*out)) {
        rs_synth_sumo_xml_fail(c, RS_ERR_PARSE, field, "is not a number", s);
        return false;
    }
    return true;
}

// Streams `path` through parser c->p (whose user data and handlers the caller has set).
rs_status rs_synth_sumo_xml_parse_file(rs_synth_sumo_xml *c)
{
    FILE *f = fopen(c->path, "rb");
    if (!f) return rs_err_set(c->err, RS_ERR_IO, "%s: cannot open: %s", c->path, strerror(errno));
    char buf[65536];
    for (bool done = false; !done && !c->st;) {
        size_t n = fread(buf, 1, sizeof buf, f);
        done = n < sizeof buf;
        if (done && ferror(f)) {
            c->st = rs_err_set(c->err, RS_ERR_IO, "%s: read error", c->path);
            break;
        }
        if (XML_Parse(c->p, buf, (int)n, done) == XML_STATUS_ERROR && !c->st)
            c->st = rs_err_set(c->err, RS_ERR_PARSE, "%s:%lu: %s", c->path,
                               (unsigned long)XML_GetCurrentLineNumber(c->p), XML_ErrorString(XML_GetErrorCode(c->p)));
    }
    fclose(f);
    return c->st;
}
