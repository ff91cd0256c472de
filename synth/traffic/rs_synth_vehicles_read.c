// rs_synth_vehicles_read.c -- the vehicles file (`roadside scene --vehicles`, rs_synth_vehicles.h:
// rs_synth_vehicles_read), read with cJSON; every problem named by file, vehicle index and field.
#include "synth/traffic/rs_synth_vehicles.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "core/rs_color.h"
#include "core/rs_io.h"
#include "core/rs_json.h"

// ---- the vehicles file ----

static char *list_keep(rs_synth_vehicle_list *list, const char *s)
{
    char **grown = realloc(list->strings, (size_t)(list->Nstrings + 1) * sizeof(char *));
    if (!grown) return NULL;
    list->strings = grown;
    char *copy = strdup(s);
    if (!copy) return NULL;
    list->strings[list->Nstrings++] = copy;
    return copy;
}

void rs_synth_vehicle_list_free(rs_synth_vehicle_list *list)
{
    if (!list) return;
    for (int i = 0; i < list->Nstrings; i++) free(list->strings[i]);
    free(list->strings);
    free(list->v);
    free(list->obj);
    memset(list, 0, sizeof(*list));
}

// Reads number member `name` of o into *out. Missing: *out untouched and RS_OK unless required.
static rs_status get_number(double *out, const cJSON *o, const char *name, bool required, const char *path, int i,
                            rs_err *err)
{
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(o, name);
    if (!m) {
        if (required) return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].%s: missing", path, i, name);
        return RS_OK;
    }
    if (!cJSON_IsNumber(m) || !isfinite(m->valuedouble))
        return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].%s: not a finite number", path, i, name);
    *out = m->valuedouble;
    return RS_OK;
}

static const char *get_string(const cJSON *o, const char *name)
{
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(o, name);
    return cJSON_IsString(m) ? m->valuestring : NULL;
}

static rs_status parse_colour(double rgb[3], const cJSON *m, const char *path, int i, rs_err *err)
{
    if (cJSON_IsString(m)) {
        const char *s = m->valuestring;
        unsigned int r, g, b;
        char tail;
        if (strlen(s) == 7 && s[0] == '#' && sscanf(s + 1, "%2x%2x%2x%c", &r, &g, &b, &tail) == 3) {
            rgb[0] = rs_color_srgb_decode_exact(r / 255.0);
            rgb[1] = rs_color_srgb_decode_exact(g / 255.0);
            rgb[2] = rs_color_srgb_decode_exact(b / 255.0);
            return RS_OK;
        }
    } else if (cJSON_IsArray(m) && cJSON_GetArraySize(m) == 3) {
        for (int k = 0; k < 3; k++) {
            const cJSON *c = cJSON_GetArrayItem(m, k);
            if (!cJSON_IsNumber(c) || !(c->valuedouble >= 0 && c->valuedouble <= 1)) goto bad;
            rgb[k] = c->valuedouble;
        }
        return RS_OK;
    }
bad:
    return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].colour: expected [r, g, b] in [0,1] (linear) or \"#rrggbb\"", path,
                      i);
}

rs_status rs_synth_model_spec_read(rs_synth_obj_spec *spec, const char **model_path, rs_synth_vehicle_list *list,
                                   const cJSON *o, const char *path, int i, const char *dir, rs_err *err)
{
    const char *model = get_string(o, "model");
    if (!model) return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].model: missing or not a string", path, i);
    char *joined = rs_io_join(dir, model);
    if (!joined) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    *model_path = list_keep(list, joined);
    free(joined);
    if (!*model_path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    memset(spec, 0, sizeof *spec);
    spec->path = *model_path;
    spec->scale = 1;
    rs_status st;
    if ((st = get_number(&spec->scale, o, "scale", false, path, i, err)) ||
        (st = get_number(&spec->length_m, o, "length", false, path, i, err)))
        return st;
    if (!(spec->scale > 0)) return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].scale: must be > 0", path, i);
    if (cJSON_GetObjectItemCaseSensitive(o, "length") && !(spec->length_m > 0))
        return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].length: must be > 0", path, i);
    const char *fwd = get_string(o, "forward"), *up = get_string(o, "up");
    spec->forward = list_keep(list, fwd ? fwd : "+x");
    spec->up = list_keep(list, up ? up : "+z");
    if (!spec->forward || !spec->up) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    const cJSON *pm = cJSON_GetObjectItemCaseSensitive(o, "paint_materials");
    if (pm) {
        const int n = cJSON_GetArraySize(pm);
        if (!cJSON_IsArray(pm))
            return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].paint_materials: expected a list of material names", path,
                              i);
        // the list of names is kept as one of the list's strings (freed with them)
        const char **names = calloc((size_t)(n > 0 ? n : 1), sizeof *names);
        char **grown = names ? realloc(list->strings, (size_t)(list->Nstrings + 1) * sizeof(char *)) : NULL;
        if (!grown) {
            free(names);
            return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        }
        list->strings = grown;
        list->strings[list->Nstrings++] = (char *)names;
        for (int k = 0; k < n; k++) {
            const cJSON *e = cJSON_GetArrayItem(pm, k);
            if (!cJSON_IsString(e))
                return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].paint_materials[%d]: not a string", path, i, k);
            if (!(names[k] = list_keep(list, e->valuestring))) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        }
        spec->paint_materials = names;
        spec->Npaint = n;
    }
    return RS_OK;
}

static rs_status read_vehicle(rs_synth_vehicle_list *list, int i, const cJSON *o, const char *path, const char *dir,
                              rs_err *err)
{
    rs_synth_vehicle *v = &list->v[i];
    rs_synth_obj_spec *obj = &list->obj[i];
    rs_status st;
    if (!cJSON_IsObject(o)) return rs_err_set(err, RS_ERR_INVALID, "%s: [%d]: expected an object", path, i);
    *v = rs_synth_vehicle_init(RS_SYNTH_SEDAN); // the class is set below
    v->variant = (uint64_t)i;
    const char *cls = get_string(o, "class"), *model = get_string(o, "model");
    if (!cls && !model)
        return rs_err_set(err, RS_ERR_INVALID,
                          "%s: [%d]: give \"class\" (a string) or \"model\" (a model file, with an optional "
                          "\"class\")",
                          path, i);
    rs_synth_class c = RS_SYNTH_USER_MODEL;
    if (cls) {
        rs_err e2 = {0};
        if (rs_synth_class_from_name(&c, cls, &e2))
            return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].class: %s", path, i, e2.msg);
    }
    if (!model)
        v->cls = c;
    else {
        v->cls = RS_SYNTH_USER_MODEL;
        v->model_cls = c;
        if ((st = rs_synth_model_spec_read(obj, &v->model_path, list, o, path, i, dir, err))) return st;
    }
    if ((st = get_number(&v->e_m, o, "e", true, path, i, err)) ||
        (st = get_number(&v->n_m, o, "n", true, path, i, err)) ||
        (st = get_number(&v->yaw_deg, o, "yaw_deg", true, path, i, err)) ||
        (st = get_number(&v->length_m, o, "length", false, path, i, err)) ||
        (st = get_number(&v->width_m, o, "width", false, path, i, err)) ||
        (st = get_number(&v->height_m, o, "height", false, path, i, err)) ||
        (st = get_number(&v->speed_mps, o, "speed_mps", false, path, i, err)))
        return st;
    if (model) {
        v->length_m = 0; // the box comes from the model (its "length" scaled it)
        if (cJSON_GetObjectItemCaseSensitive(o, "width") || cJSON_GetObjectItemCaseSensitive(o, "height"))
            return rs_err_set(err, RS_ERR_INVALID,
                              "%s: [%d].width/height: a model's box is its mesh's; give \"length\" to scale it", path,
                              i);
    }
    const char *dims[3] = {"length", "width", "height"};
    const double dval[3] = {v->length_m, v->width_m, v->height_m};
    for (int k = 0; k < 3 && !model; k++) // (a model's length: rs_synth_model_spec_read)
        if (cJSON_GetObjectItemCaseSensitive(o, dims[k]) && !(dval[k] > 0))
            return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].%s: must be > 0", path, i, dims[k]);
    const cJSON *colour = cJSON_GetObjectItemCaseSensitive(o, "colour");
    if (colour && (st = parse_colour(v->rgb, colour, path, i, err))) return st;
    const cJSON *variant = cJSON_GetObjectItemCaseSensitive(o, "variant");
    if (variant) {
        if (!cJSON_IsNumber(variant) || !(variant->valuedouble >= 0) || variant->valuedouble > 9007199254740992.0 ||
            variant->valuedouble != floor(variant->valuedouble))
            return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].variant: expected an integer >= 0", path, i);
        v->variant = (uint64_t)variant->valuedouble;
    }
    const cJSON *id = cJSON_GetObjectItemCaseSensitive(o, "id");
    if (id) {
        if (!cJSON_IsString(id)) return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].id: expected a string", path, i);
        snprintf(v->id, sizeof v->id, "%s", id->valuestring);
    }
    return RS_OK;
}

typedef rs_status (*entry_reader)(rs_synth_vehicle_list *list, int i, const cJSON *o, const char *path, const char *dir,
                                  rs_err *err);

// Reads the JSON list at path (at least Nmin entries, `what` naming them in errors), each entry by
// read_entry with the file's folder for relative paths. On error *list is left empty.
static rs_status read_list(rs_synth_vehicle_list *list, const char *path, const char *what, int Nmin,
                           entry_reader read_entry, rs_err *err)
{
    memset(list, 0, sizeof(*list));
    char *text = NULL, *dir = NULL;
    cJSON *root = NULL;
    size_t len = 0;
    rs_status st = rs_io_read_file(&text, &len, path, err);
    if (st) return st;
    // syntax errors: RS_ERR_PARSE "PATH:LINE: JSON syntax error near '...'" (core/rs_json.h)
    if ((st = rs_json_parse(&root, text, 0, len, path, err))) goto done;
    if (!cJSON_IsArray(root) || cJSON_GetArraySize(root) < Nmin) {
        st = rs_err_set(err, RS_ERR_INVALID, "%s: expected a JSON list of %s%s", path, what,
                        Nmin > 0 ? " (at least one)" : "");
        goto done;
    }
    const int N = cJSON_GetArraySize(root);
    dir = strdup(path);
    list->v = calloc((size_t)(N > 0 ? N : 1), sizeof(*list->v));
    list->obj = calloc((size_t)(N > 0 ? N : 1), sizeof(*list->obj));
    if (!dir || !list->v || !list->obj) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    char *slash = strrchr(dir, '/');
    if (slash)
        slash[1] = 0;
    else
        strcpy(dir, ".");
    int i = 0;
    const cJSON *o;
    cJSON_ArrayForEach(o, root)
    {
        if ((st = read_entry(list, i, o, path, dir, err))) goto done;
        i++;
    }
    list->N = N;
done:
    cJSON_Delete(root);
    free(text);
    free(dir);
    if (st) rs_synth_vehicle_list_free(list);
    return st;
}

rs_status rs_synth_vehicles_read(rs_synth_vehicle_list *list, const char *path, rs_err *err)
{
    return read_list(list, path, "vehicles", 0, read_vehicle, err);
}

// ---- a model library (`roadside synth --models`) ----

// Entry i of a model library: a user model with its label class.
static rs_status read_model(rs_synth_vehicle_list *lib, int i, const cJSON *o, const char *path, const char *dir,
                            rs_err *err)
{
    rs_synth_vehicle *v = &lib->v[i];
    *v = rs_synth_vehicle_init(RS_SYNTH_USER_MODEL);
    if (!cJSON_IsObject(o)) return rs_err_set(err, RS_ERR_INVALID, "%s: [%d]: expected an object", path, i);
    const char *cls = get_string(o, "class");
    rs_err e2 = {0};
    if (!cls)
        return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].class: missing (the class the model stands for)", path, i);
    if (rs_synth_class_from_name(&v->model_cls, cls, &e2))
        return rs_err_set(err, RS_ERR_INVALID, "%s: [%d].class: %s", path, i, e2.msg);
    snprintf(v->id, sizeof v->id, "model %d", i);
    return rs_synth_model_spec_read(&lib->obj[i], &v->model_path, lib, o, path, i, dir, err);
}

rs_status rs_synth_models_read(rs_synth_vehicle_list *lib, const char *path, rs_err *err)
{
    return read_list(lib, path, "model descriptions", 1, read_model, err);
}
