// rs_synth_sumo_fcd.c -- what comes back from SUMO: the network's <location> (net.xml), the
// floating car data (fcd.xml) as frames of vehicles, the frames written as vehicles files, and
// their index (frames.json) written and read back. See rs_synth_sumo.h and docs/traffic.md.
#include "synth/traffic/rs_synth_sumo.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cjson/cJSON.h>

#include "core/rs_io.h"
#include "core/rs_json.h"
#include "core/rs_units.h"
#include "synth/fleet/rs_synth_fleet.h"
#include "synth/traffic/internal/rs_synth_sumo_xml.h"

void rs_synth_sumo_frames_free(rs_synth_sumo_frames *frames)
{
    if (!frames) return;
    for (int i = 0; i < frames->N; i++) free(frames->frame[i].v);
    free(frames->frame);
    frames->frame = NULL;
    frames->N = 0;
}

// ---------------------------------------------------------------------------------------------
// net.xml <location>

typedef struct {
    rs_synth_sumo_xml x;
    rs_synth_sumo_location *loc;
    bool found;
} location_ctx;

static void XMLCALL location_start(void *ud, const XML_Char *name, const XML_Char **a)
{
    location_ctx *c = ud;
    if (c->found || c->x.st || strcmp(name, "location")) return;
    c->found = true;
    const char *off = rs_synth_sumo_xml_attr(a, "netOffset"), *proj = rs_synth_sumo_xml_attr(a, "projParameter");
    if (!off || sscanf(off, "%lf,%lf", &c->loc->net_offset_m[0], &c->loc->net_offset_m[1]) != 2)
        return rs_synth_sumo_xml_fail(&c->x, RS_ERR_PARSE, "location.netOffset", "is not X,Y", off);
    const char *z = proj ? strstr(proj, "+zone=") : NULL;
    if (!proj || !strstr(proj, "+proj=utm") || !z)
        return rs_synth_sumo_xml_fail(&c->x, RS_ERR_UNSUPPORTED, "location.projParameter",
                                      "is not a UTM projection (build the network with netconvert --proj.utm)", proj);
    c->loc->zone = atoi(z + 6);
    if (c->loc->zone < 1 || c->loc->zone > 60)
        return rs_synth_sumo_xml_fail(&c->x, RS_ERR_PARSE, "location.projParameter", "has no UTM zone 1..60", proj);
    c->loc->north = strstr(proj, "+south") == NULL;
}

rs_status rs_synth_sumo_read_location(rs_synth_sumo_location *loc, const char *net_path, rs_err *err)
{
    location_ctx c = {{XML_ParserCreate(NULL), net_path, RS_OK, err}, loc, false};
    if (!c.x.p) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    XML_SetUserData(c.x.p, &c);
    XML_SetStartElementHandler(c.x.p, location_start);
    rs_status st = rs_synth_sumo_xml_parse_file(&c.x);
    XML_ParserFree(c.x.p);
    if (!st && !c.found) st = rs_err_set(err, RS_ERR_NOT_FOUND, "%s: no <location> element", net_path);
    return st;
}

// ---------------------------------------------------------------------------------------------
// FCD

typedef struct {
    rs_synth_sumo_xml x;
    rs_synth_sumo_frames *out;
    int cap;  // frames allocated
    int vcap; // vehicles allocated in the current frame
    bool geo;
    const rs_synth_sumo_location *loc;
    const rs_llh *origin;
    const rs_synth_sumo_vtype *types;
    int Ntypes;
} fcd_ctx;

static uint64_t hash_id(const char *s)
{
    uint64_t h = 1469598103934665603ULL; // FNV-1a
    for (; *s; s++) h = (h ^ (unsigned char)*s) * 1099511628211ULL;
    return h >> 11;
}

static void fcd_vehicle(fcd_ctx *c, const XML_Char **a)
{
    if (c->out->N == 0) return rs_synth_sumo_xml_fail(&c->x, RS_ERR_PARSE, "vehicle", "outside a <timestep>", NULL);
    double x, y, angle, speed = 0;
    if (!rs_synth_sumo_xml_double(&c->x, a, "vehicle", "x", &x) ||
        !rs_synth_sumo_xml_double(&c->x, a, "vehicle", "y", &y) ||
        !rs_synth_sumo_xml_double(&c->x, a, "vehicle", "angle", &angle))
        return;
    if (rs_synth_sumo_xml_attr(a, "speed") && !rs_synth_sumo_xml_double(&c->x, a, "vehicle", "speed", &speed)) return;
    const char *id = rs_synth_sumo_xml_attr(a, "id"), *type = rs_synth_sumo_xml_attr(a, "type"),
               *lane = rs_synth_sumo_xml_attr(a, "lane");
    if (!id) return rs_synth_sumo_xml_fail(&c->x, RS_ERR_PARSE, "vehicle.id", "missing", NULL);
    if (!type) return rs_synth_sumo_xml_fail(&c->x, RS_ERR_PARSE, "vehicle.type", "missing", NULL);
    const rs_synth_sumo_vtype *t = NULL;
    for (int i = 0; i < c->Ntypes && !t; i++)
        if (!strcmp(c->types[i].id, type)) t = &c->types[i];
    if (!t) return rs_synth_sumo_xml_fail(&c->x, RS_ERR_NOT_FOUND, "vehicle.type", "is not a known vType", type);

    // Front bumper in geodetic coordinates.
    double llh[3] = {y, x, c->origin->h_m};
    rs_err e2;
    if (!c->geo) {
        double enh[3] = {x - c->loc->net_offset_m[0], y - c->loc->net_offset_m[1], c->origin->h_m};
        if (rs_geo_utm_to_llh(llh, c->loc->zone, c->loc->north, enh, 1, &e2))
            return rs_synth_sumo_xml_fail(&c->x, RS_ERR_INVALID, "vehicle.x", e2.msg, NULL);
    }
    double gamma, front[3];
    if (rs_geo_utm_convergence_deg(&gamma, c->loc->zone, c->loc->north, llh, 1, &e2) ||
        rs_geo_llh_to_enu(front, c->origin, llh, 1, &e2))
        return rs_synth_sumo_xml_fail(&c->x, RS_ERR_INVALID, c->geo ? "vehicle.x/y (lon/lat)" : "vehicle.x/y", e2.msg,
                                      NULL);
    double b = fmod(angle + gamma + 720.0, 360.0);

    rs_synth_sumo_frame *fr = &c->out->frame[c->out->N - 1];
    if (fr->N == c->vcap) {
        int cap = c->vcap ? 2 * c->vcap : 32;
        rs_synth_vehicle *g = realloc(fr->v, sizeof *g * (size_t)cap);
        if (!g) return rs_synth_sumo_xml_fail(&c->x, RS_ERR_NOMEM, "vehicle", "out of memory", NULL);
        fr->v = g;
        c->vcap = cap;
    }
    rs_synth_vehicle *v = &fr->v[fr->N++];
    *v = rs_synth_vehicle_init(t->cls);
    v->length_m = t->length_m;
    v->width_m = t->width_m;
    v->height_m = t->height_m;
    v->yaw_deg = b;
    v->e_m = front[0] - 0.5 * t->length_m * sin(b * RS_RAD_PER_DEG);
    v->n_m = front[1] - 0.5 * t->length_m * cos(b * RS_RAD_PER_DEG);
    v->speed_mps = speed;
    v->variant = hash_id(id);
    v->lane = -1;
    int k, used = 0;
    if (lane && sscanf(lane, "e%d_0%n", &k, &used) == 1 && used == (int)strlen(lane)) v->lane = k;
    snprintf(v->id, sizeof v->id, "%s", id);
}

static void XMLCALL fcd_start(void *ud, const XML_Char *name, const XML_Char **a)
{
    fcd_ctx *c = ud;
    if (c->x.st) return;
    if (!strcmp(name, "timestep")) {
        double t;
        if (!rs_synth_sumo_xml_double(&c->x, a, "timestep", "time", &t)) return;
        if (c->out->N == c->cap) {
            int cap = c->cap ? 2 * c->cap : 64;
            rs_synth_sumo_frame *g = realloc(c->out->frame, sizeof *g * (size_t)cap);
            if (!g) return rs_synth_sumo_xml_fail(&c->x, RS_ERR_NOMEM, "timestep", "out of memory", NULL);
            c->out->frame = g;
            c->cap = cap;
        }
        c->out->frame[c->out->N++] = (rs_synth_sumo_frame){t, NULL, 0};
        c->vcap = 0;
    } else if (!strcmp(name, "vehicle")) {
        fcd_vehicle(c, a);
    }
}

rs_status rs_synth_sumo_read_fcd(rs_synth_sumo_frames *frames, const char *fcd_path, bool geo,
                                 const rs_synth_sumo_location *loc, const rs_llh *origin,
                                 const rs_synth_sumo_vtype *types, int Ntypes, rs_err *err)
{
    frames->frame = NULL;
    frames->N = 0;
    fcd_ctx c = {{XML_ParserCreate(NULL), fcd_path, RS_OK, err}, frames, 0, 0, geo, loc, origin, types, Ntypes};
    if (!c.x.p) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    XML_SetUserData(c.x.p, &c);
    XML_SetStartElementHandler(c.x.p, fcd_start);
    rs_status st = rs_synth_sumo_xml_parse_file(&c.x);
    XML_ParserFree(c.x.p);
    if (st) rs_synth_sumo_frames_free(frames);
    return st;
}

rs_status rs_synth_sumo_frames_write(const char *dir, rs_synth_sumo_frames *fr, const rs_synth_randomise_options *rnd,
                                     bool randomise, int *Nvehicles, rs_err *err)
{
    rs_status st = rs_io_mkdir_p(dir, err);
    if (st) return st;
    char *index = rs_io_join(dir, "frames.json");
    if (!index) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_io_atomic a;
    st = rs_io_atomic_open(&a, index, err);
    free(index);
    if (st) return st;
    fprintf(a.f, "[\n");
    *Nvehicles = 0;
    for (int i = 0; i < fr->N && !st; i++) {
        rs_synth_sumo_frame *f = &fr->frame[i];
        rs_synth_randomise_options r = *rnd;
        r.seed += (uint64_t)i;
        if (!randomise) r.sigma_along_m = r.sigma_across_m = r.yaw_range_deg = 0;
        if ((st = rs_synth_traffic_randomise(f->v, &f->N, &r, err))) break;
        char name[32];
        snprintf(name, sizeof name, "frame_%06d.json", i);
        char *path = rs_io_join(dir, name);
        if (!path) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            break;
        }
        st = rs_synth_traffic_write_json(path, f->v, f->N, err);
        free(path);
        fprintf(a.f, "  {\"file\": \"%s\", \"time_s\": %.3f, \"vehicles\": %d}%s\n", name, f->time_s, f->N,
                i + 1 < fr->N ? "," : "");
        *Nvehicles += f->N;
    }
    fprintf(a.f, "]\n");
    if (st) {
        rs_io_atomic_abort(&a);
        return st;
    }
    return rs_io_atomic_commit(&a, err);
}

rs_status rs_synth_sumo_frames_index_read(rs_synth_sumo_frame_entry **entries, int *N, const char *dir, rs_err *err)
{
    *entries = NULL;
    *N = 0;
    char *path = rs_io_join(dir, "frames.json"), *text = NULL;
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    cJSON *root = NULL;
    rs_synth_sumo_frame_entry *e = NULL;
    rs_status st = RS_OK;
    struct stat sb;
    if (stat(path, &sb) != 0 && errno == ENOENT) {
        st = rs_err_set(err, RS_ERR_NOT_FOUND,
                        "%s: missing (%s is not a folder written by `roadside traffic --sumo -o DIR`)", path, dir);
        goto done;
    }
    size_t len = 0;
    if ((st = rs_io_read_file_max(&text, &len, path, RS_IO_MAX_SMALL_FILE_BYTES, err))) goto done;
    // syntax errors: RS_ERR_PARSE "PATH:LINE: JSON syntax error near '...'" (core/rs_json.h)
    if ((st = rs_json_parse(&root, text, 0, len, path, err))) goto done;
    if (!cJSON_IsArray(root)) {
        st = rs_err_set(err, RS_ERR_INVALID, "%s: expected a JSON list of {file, time_s, vehicles}", path);
        goto done;
    }
    const int n = cJSON_GetArraySize(root);
    if (n > 0 && !(e = calloc((size_t)n, sizeof(*e)))) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    int i = 0;
    const cJSON *o;
    cJSON_ArrayForEach(o, root)
    {
        const cJSON *f = cJSON_GetObjectItemCaseSensitive(o, "file"),
                    *t = cJSON_GetObjectItemCaseSensitive(o, "time_s"),
                    *v = cJSON_GetObjectItemCaseSensitive(o, "vehicles");
        const char *name = cJSON_IsString(f) ? f->valuestring : NULL;
        if (!cJSON_IsObject(o))
            st = rs_err_set(err, RS_ERR_INVALID, "%s: [%d]: expected an object {file, time_s, vehicles}", path, i);
        else if (!name || !*name || strchr(name, '/') || !strcmp(name, ".") || !strcmp(name, "..") ||
                 strlen(name) >= sizeof(e[i].file))
            st =
                rs_err_set(err, RS_ERR_INVALID, "%s: [%d].file: expected the plain name of a file in %s", path, i, dir);
        else if (!cJSON_IsNumber(t) || !isfinite(t->valuedouble))
            st = rs_err_set(err, RS_ERR_INVALID, "%s: [%d].time_s: expected a number of seconds", path, i);
        else if (!cJSON_IsNumber(v) || !(v->valuedouble >= 0) || v->valuedouble > 1e9 ||
                 v->valuedouble != floor(v->valuedouble))
            st = rs_err_set(err, RS_ERR_INVALID, "%s: [%d].vehicles: expected an integer >= 0", path, i);
        if (st) goto done;
        snprintf(e[i].file, sizeof(e[i].file), "%s", name);
        e[i].time_s = t->valuedouble;
        e[i].vehicles = (int)v->valuedouble;
        i++;
    }
    *entries = e;
    *N = n;
    e = NULL;
done:
    free(e);
    cJSON_Delete(root);
    free(text);
    free(path);
    return st;
}
