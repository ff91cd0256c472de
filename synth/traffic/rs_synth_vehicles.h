// rs_synth_vehicles.h -- the vehicles file `roadside scene` and `roadside render` read
// (--vehicles), as `roadside traffic` writes it (rs_synth_traffic_write_json).
#pragma once
#include <cjson/cJSON.h>

#include "core/rs_status.h"
#include "synth/fleet/rs_synth_fleet.h"
#include "synth/fleet/rs_synth_vehicle.h"

#ifdef __cplusplus
extern "C" {
#endif

// A vehicles file read into memory. `v[i]`'s strings point into this list's storage.
typedef struct {
    rs_synth_vehicle *v; // (N,) owned
    int N;
    char **strings; // owned: every string v[] points to (the user models' paths)
    int Nstrings;
    rs_synth_obj_spec *obj; // (N,) owned: user models' specs (obj[i].path == v[i].model_path)
} rs_synth_vehicle_list;

// Reads a vehicles file: a JSON list of objects
//   {"class": "sedan" (rs_synth_class_name) and/or "model": "path" (a user model:
//    rs_synth_model_spec_read's fields; "class" is then the class its label carries),
//    "e": m, "n": m, "yaw_deg": deg,
//    "length": m, "width": m, "height": m,   (optional, > 0; default: drawn from the class; a
//    model's "length" scales it, and its width and height are its mesh's)
//    "colour": [r, g, b] linear in [0,1] or "#rrggbb" sRGB (optional; default: drawn),
//    "variant": integer >= 0 (optional, default: the index), "id": string (optional; kept to
//    its first 47 bytes, rs_synth_vehicle.id), "speed_mps": m/s (optional, default 0: SUMO's
//    frames carry FCD's speed, which a sequence's tracks_gt.csv reports)}
// yaw_deg is the compass heading of the vehicle's forward axis, clockwise from north.
// A relative "model" path is taken relative to the vehicles file's folder.
// Errors name the file, the list index and the field: "FILE: [3].yaw_deg: not a number".
rs_status rs_synth_vehicles_read( // out
    rs_synth_vehicle_list *list,
    // in
    const char *path, rs_err *err);
void rs_synth_vehicle_list_free(rs_synth_vehicle_list *list); // NULL-safe

// A user model's description, read from JSON object o (entry i of file `path`) into *spec: "model"
// (the file, relative to dir), "length" (metres: the model scaled so its box's length along
// forward is this) or "scale" (metres per model unit, default 1), "forward" and "up" (model axes,
// default "+x", "+z"), "paint_materials" (names of the materials painted in the vehicle's colour;
// default none). The strings are kept in list's storage (freed with it). The vehicles file and
// `roadside synth --models` (synth/dataset) share it. Errors name path, [i] and the field.
rs_status rs_synth_model_spec_read( // out
    rs_synth_obj_spec *spec, const char **model_path,
    // in,out
    rs_synth_vehicle_list *list,
    // in
    const cJSON *o, const char *path, int i, const char *dir, rs_err *err);

// Reads a model library (`roadside synth --models FILE`; docs/fleet.md, "User models"): a JSON
// list (at least one) of model descriptions, each rs_synth_model_spec_read's fields with
// "class" required (the class the model stands for and its labels carry). out: lib->v[i] a
// user model (cls RS_SYNTH_USER_MODEL, model_cls, model_path, id "model i"), lib->obj[i] its
// spec. Errors name FILE, the entry index and the field: "FILE: [2].class: missing ...".
rs_status rs_synth_models_read( // out
    rs_synth_vehicle_list *lib,
    // in
    const char *path, rs_err *err);

#ifdef __cplusplus
}
#endif
