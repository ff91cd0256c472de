// rs_synth_sumo_xml.h -- reading SUMO's XML files with expat (synth/traffic/rs_synth_sumo_xml.c):
// a file streamed through a start-element callback, with errors that name the file, the line
// and the field. Internal to synth (the SUMO files: rs_synth_sumo.c, rs_synth_sumo_fcd.c).
#pragma once
#include <stdbool.h>

#include <expat.h>

#include "core/rs_status.h"

// A parse in progress: the caller creates the parser, sets its user data (a struct whose first
// member is this one) and handlers, and streams the file with rs_synth_sumo_xml_parse_file.
typedef struct {
    XML_Parser p;
    const char *path;
    rs_status st;
    rs_err *err;
} rs_synth_sumo_xml;

// The value of attribute `name` in expat's (name, value, ..., NULL) list, or NULL.
const char *rs_synth_sumo_xml_attr(const XML_Char **a, const char *name);

// Stops the parser with an error "PATH:LINE: FIELD: 'VALUE' WHAT" (value may be NULL); the first
// error is kept.
void rs_synth_sumo_xml_fail(rs_synth_sumo_xml *c, rs_status st, const char *field, const char *what, const char *value);

// Attribute `name` of element `elem` as a finite number; false (and the parser stopped) when it
// is missing or not a number.
bool rs_synth_sumo_xml_double(rs_synth_sumo_xml *c, const XML_Char **a, const char *elem, const char *name,
                              double *out);

// Streams c->path through c->p. Returns c->st: RS_ERR_IO, RS_ERR_PARSE or the first callback error.
rs_status rs_synth_sumo_xml_parse_file(rs_synth_sumo_xml *c);
