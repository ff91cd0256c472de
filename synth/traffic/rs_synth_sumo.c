// rs_synth_sumo.c -- SUMO networks from lanes, flows and routes, running netconvert and sumo. What
// comes back (location, FCD frames) is read in rs_synth_sumo_fcd.c. See rs_synth_sumo.h, docs/traffic.md.
#define _XOPEN_SOURCE 700 // nftw()
#include "synth/traffic/rs_synth_sumo.h"

#include <errno.h>
#include <expat.h>
#include <fcntl.h>
#include <ftw.h>
#include <math.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "core/rs_io.h"
#include "core/rs_rng.h"
#include "core/rs_units.h"
#include "synth/fleet/rs_synth_fleet.h"
#include "synth/traffic/internal/rs_synth_sumo_xml.h"

extern char **environ;

void rs_synth_sumo_options_default(rs_synth_sumo_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->duration_s = 300.0;
    opt->warmup_s = 60.0;
    opt->period_s = 1.0;
    opt->flow_vph = 200.0;
    rs_synth_class_mix_default(&opt->mix);
    opt->sumo = "sumo";
    opt->netconvert = "netconvert";
}

// ---------------------------------------------------------------------------------------------
// running programs

// Runs argv[0] (looked up on PATH) with stdout and stderr appended to log_path; no shell.
static rs_status run_program(char *const argv[], const char *log_path, rs_err *err)
{
    posix_spawn_file_actions_t fa;
    if (posix_spawn_file_actions_init(&fa)) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    posix_spawn_file_actions_addopen(&fa, 1, log_path, O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    // The environment, with SUMO_HOME=/usr/share/sumo added when unset (SUMO reads its data
    // from there; with validation off it needs nothing from the network).
    size_t ne = 0;
    while (environ[ne]) ne++;
    char **env = malloc(sizeof *env * (ne + 2));
    if (!env) {
        posix_spawn_file_actions_destroy(&fa);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    memcpy(env, environ, sizeof *env * ne);
    static char sumo_home[] = "SUMO_HOME=/usr/share/sumo";
    if (!getenv("SUMO_HOME")) env[ne++] = sumo_home;
    env[ne] = NULL;
    pid_t pid;
    int rc = posix_spawnp(&pid, argv[0], &fa, NULL, argv, env);
    posix_spawn_file_actions_destroy(&fa);
    free(env);
    if (rc == ENOENT)
        return rs_err_set(err, RS_ERR_NOT_FOUND,
                          "%s: not found on PATH (SUMO is needed for --sumo: on Debian, apt install sumo)", argv[0]);
    if (rc) return rs_err_set(err, RS_ERR_EXTERNAL, "%s: cannot run: %s", argv[0], strerror(rc));
    int status;
    while (waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) return rs_err_set(err, RS_ERR_EXTERNAL, "%s: waitpid: %s", argv[0], strerror(errno));
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return RS_OK;
    if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
        return rs_err_set(err, RS_ERR_NOT_FOUND, "%s: not found on PATH (on Debian, apt install sumo)", argv[0]);
    // The last non-empty line of the log says why.
    char last[512] = "";
    FILE *f = fopen(log_path, "r");
    if (f) {
        char line[512];
        while (fgets(line, sizeof line, f))
            if (line[0] != '\n') snprintf(last, sizeof last, "%s", line);
        fclose(f);
    }
    last[strcspn(last, "\n")] = '\0';
    return rs_err_set(err, RS_ERR_EXTERNAL, "%s failed (%s %d); see %s: %s", argv[0],
                      WIFEXITED(status) ? "exit status" : "signal",
                      WIFEXITED(status) ? WEXITSTATUS(status) : WTERMSIG(status), log_path, last);
}

// netconvert with the given input options (Ninputs <= 8) into `net`: UTM projection, no XML
// validation, no U-turns.
static rs_status run_netconvert(const char *netconvert, const char *const *inputs, int Ninputs, const char *net,
                                const char *log_path, rs_err *err)
{
    static const char *const common[] = {"--proj.utm",       "true", "--xml-validation", "never",
                                         "--no-turnarounds", "true", "--output-file"};
    char *argv[1 + 8 + 7 + 2];
    int k = 0;
    argv[k++] = (char *)netconvert;
    for (int i = 0; i < Ninputs && i < 8; i++) argv[k++] = (char *)inputs[i];
    for (size_t i = 0; i < sizeof common / sizeof common[0]; i++) argv[k++] = (char *)common[i];
    argv[k++] = (char *)net;
    argv[k] = NULL;
    return run_program(argv, log_path, err);
}

// ---------------------------------------------------------------------------------------------
// the network from the lanes

static bool is_junction(const rs_lane *l) { return l->kind && !strcmp(l->kind, "junction"); }

static int uf_find(int *parent, int i)
{
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
}

static void uf_join(int *parent, int a, int b)
{
    a = uf_find(parent, a), b = uf_find(parent, b);
    if (a != b) parent[b < a ? a : b] = b < a ? b : a;
}

typedef struct {
    int from, to; // lane (edge) indices
} connection;

typedef struct {
    int *parent; // (2 Nlanes,) union-find over lane ends: 2K start, 2K+1 end
    connection *con;
    int Ncon, capcon;
    int Nedges;
} network;

static bool add_connection(network *n, int from, int to)
{
    for (int i = 0; i < n->Ncon; i++)
        if (n->con[i].from == from && n->con[i].to == to) return true;
    if (n->Ncon == n->capcon) {
        int cap = n->capcon ? 2 * n->capcon : 64;
        connection *g = realloc(n->con, sizeof *g * (size_t)cap);
        if (!g) return false;
        n->con = g;
        n->capcon = cap;
    }
    n->con[n->Ncon++] = (connection){from, to};
    return true;
}

// Connects edge `from` to every non-junction lane reached from lane j through junction lanes.
static bool connect_through(network *n, const rs_lanes *lanes, int from, int j, int depth)
{
    if (depth > 8) return true;
    if (!is_junction(&lanes->lane[j])) {
        uf_join(n->parent, 2 * from + 1, 2 * j);
        return add_connection(n, from, j);
    }
    for (int k = 0; k < lanes->lane[j].Nnext; k++)
        if (!connect_through(n, lanes, from, lanes->lane[j].next[k], depth + 1)) return false;
    return true;
}

// Opens dir/name for atomic writing.
static rs_status atomic_open_in(rs_io_atomic *a, const char *dir, const char *name, rs_err *err)
{
    char *path = rs_io_join(dir, name);
    if (!path) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_status st = rs_io_atomic_open(a, path, err);
    free(path);
    return st;
}

// Commits a file written without error, else removes it; returns the first error.
static rs_status atomic_finish(rs_io_atomic *a, rs_status st, rs_err *err)
{
    if (!st) return rs_io_atomic_commit(a, err);
    rs_io_atomic_abort(a);
    return st;
}

static rs_status enu_to_lonlat(double lonlat[2], const rs_llh *origin, const double p_enu[2], rs_err *err)
{
    double enu[3] = {p_enu[0], p_enu[1], 0}, llh[3];
    rs_status st = rs_geo_enu_to_llh(llh, origin, enu, 1, err);
    lonlat[0] = llh[1];
    lonlat[1] = llh[0];
    return st;
}

static rs_status write_network_files(const char *dir, const rs_lanes *lanes, const rs_llh *origin, network *n,
                                     rs_err *err)
{
    int L = lanes->N;
    n->parent = malloc(sizeof *n->parent * 2 * (size_t)L);
    if (!n->parent) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; i < 2 * L; i++) n->parent[i] = i;
    for (int i = 0; i < L; i++) {
        if (is_junction(&lanes->lane[i])) continue;
        n->Nedges++;
        for (int k = 0; k < lanes->lane[i].Nnext; k++)
            if (!connect_through(n, lanes, i, lanes->lane[i].next[k], 0))
                return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    if (n->Nedges == 0) return rs_err_set(err, RS_ERR_INVALID, "lanes: every lane is a junction lane: no edges");

    rs_status st;
    rs_io_atomic a = {0};
    if ((st = atomic_open_in(&a, dir, "nodes.nod.xml", err))) return st;
    fprintf(a.f, "<nodes>\n");
    for (int r = 0; r < 2 * L && !st; r++) {
        if (is_junction(&lanes->lane[r / 2]) || uf_find(n->parent, r) != r) continue;
        // The node at the mean of its lane ends; a traffic light where 3 or more edges enter.
        double p[2] = {0, 0};
        int m = 0, in = 0;
        for (int q = 0; q < 2 * L; q++) {
            const rs_lane *l = &lanes->lane[q / 2];
            if (is_junction(l) || uf_find(n->parent, q) != r) continue;
            const double *e = l->p_enu_m[q % 2 ? l->Npoints - 1 : 0];
            p[0] += e[0], p[1] += e[1], m++;
            in += q % 2;
        }
        p[0] /= m, p[1] /= m;
        double ll[2];
        if ((st = enu_to_lonlat(ll, origin, p, err))) break;
        fprintf(a.f, "  <node id=\"n%d\" x=\"%.9f\" y=\"%.9f\" type=\"%s\"/>\n", r, ll[0], ll[1],
                in >= 3 ? "traffic_light" : "priority");
    }
    fprintf(a.f, "</nodes>\n");
    if ((st = atomic_finish(&a, st, err))) return st;

    if ((st = atomic_open_in(&a, dir, "edges.edg.xml", err))) return st;
    fprintf(a.f, "<edges>\n");
    for (int i = 0; i < L && !st; i++) {
        const rs_lane *l = &lanes->lane[i];
        if (is_junction(l)) continue;
        fprintf(a.f,
                "  <edge id=\"e%d\" from=\"n%d\" to=\"n%d\" numLanes=\"1\" speed=\"%.3f\" width=\"%.3f\" "
                "spreadType=\"center\" shape=\"",
                i, uf_find(n->parent, 2 * i), uf_find(n->parent, 2 * i + 1),
                isfinite(l->speed_mps) ? l->speed_mps : 13.89, l->width_m);
        for (int k = 0; k < l->Npoints && !st; k++) {
            double ll[2];
            st = enu_to_lonlat(ll, origin, l->p_enu_m[k], err);
            fprintf(a.f, "%s%.9f,%.9f", k ? " " : "", ll[0], ll[1]);
        }
        fprintf(a.f, "\"/>\n");
    }
    fprintf(a.f, "</edges>\n");
    if ((st = atomic_finish(&a, st, err))) return st;

    if ((st = atomic_open_in(&a, dir, "connections.con.xml", err))) return st;
    fprintf(a.f, "<connections>\n");
    for (int i = 0; i < n->Ncon; i++)
        fprintf(a.f, "  <connection from=\"e%d\" to=\"e%d\" fromLane=\"0\" toLane=\"0\"/>\n", n->con[i].from,
                n->con[i].to);
    fprintf(a.f, "</connections>\n");
    return rs_io_atomic_commit(&a, err);
}

// ---------------------------------------------------------------------------------------------
// routes: vTypes and flows

static const char *vclass_of(rs_synth_class c)
{
    switch (c) {
    case RS_SYNTH_VAN: return "delivery";
    case RS_SYNTH_BUS: return "bus";
    case RS_SYNTH_BOX_TRUCK: return "truck";
    case RS_SYNTH_ARTICULATED_TRUCK: return "trailer";
    case RS_SYNTH_MOTORCYCLE: return "motorcycle";
    case RS_SYNTH_BICYCLE: return "bicycle";
    default: return "passenger";
    }
}

// Three sizes per class with a weight > 0: dimensions at 1/6, 1/2 and 5/6 of each range, the
// order of the three quantiles shuffled per dimension by the seed.
static int make_vtypes(rs_synth_sumo_vtype *t, double *prob, const rs_synth_class_mix *mix, uint64_t seed)
{
    rs_rng rng;
    rs_rng_seed(&rng, seed ^ 0x5u);
    double total = 0;
    for (int c = 0; c < RS_SYNTH_NCLASSES; c++) total += mix->weight[c];
    int n = 0;
    for (int c = 0; c < RS_SYNTH_NCLASSES; c++) {
        if (!(mix->weight[c] > 0)) continue;
        rs_synth_class_range cr;
        rs_synth_class_range_get(&cr, (rs_synth_class)c, NULL);
        const double *r[3] = {cr.length_m, cr.width_m, cr.height_m};
        int perm[3][3];
        for (int d = 0; d < 3; d++) {
            int p[3] = {0, 1, 2};
            for (int k = 2; k > 0; k--) {
                int j = (int)(rs_rng_uniform(&rng) * (k + 1)), tmp = p[k];
                p[k] = p[j], p[j] = tmp;
            }
            memcpy(perm[d], p, sizeof p);
        }
        for (int k = 0; k < 3; k++, n++) {
            snprintf(t[n].id, sizeof t[n].id, "%s_%d", rs_synth_class_name((rs_synth_class)c), k + 1);
            t[n].cls = (rs_synth_class)c;
            double *dim[3] = {&t[n].length_m, &t[n].width_m, &t[n].height_m};
            for (int d = 0; d < 3; d++) *dim[d] = r[d][0] + (r[d][1] - r[d][0]) * (1 + 2 * perm[d][k]) / 6.0;
            prob[n] = mix->weight[c] / total / 3.0;
        }
    }
    return n;
}

// Appends every path of connections from edge e to an edge without successors.
static bool write_paths(FILE *f, const network *n, int *path, int depth, int *Nroutes)
{
    int e = path[depth - 1];
    bool any = false;
    for (int i = 0; i < n->Ncon; i++) {
        if (n->con[i].from != e) continue;
        bool loop = false;
        for (int k = 0; k < depth; k++) loop |= path[k] == n->con[i].to;
        if (loop || depth >= 32) continue;
        any = true;
        path[depth] = n->con[i].to;
        if (!write_paths(f, n, path, depth + 1, Nroutes)) return false;
    }
    if (!any && depth > 1) {
        fprintf(f, "  <route id=\"r%d\" edges=\"", (*Nroutes)++);
        for (int k = 0; k < depth; k++) fprintf(f, "%se%d", k ? " " : "", path[k]);
        fprintf(f, "\"/>\n");
    }
    return *Nroutes < 4096;
}

static rs_status write_routes(const char *dir, const rs_lanes *lanes, const network *n, const char *const *osm_from,
                              const char *const *osm_to, int Nosm, const rs_synth_sumo_vtype *t, const double *prob,
                              int Nt, const rs_synth_sumo_options *o, rs_err *err)
{
    rs_io_atomic a;
    rs_status st = atomic_open_in(&a, dir, "routes.rou.xml", err);
    if (st) return st;
    fprintf(a.f, "<routes>\n  <vTypeDistribution id=\"mix\">\n");
    for (int i = 0; i < Nt; i++)
        fprintf(a.f,
                "    <vType id=\"%s\" vClass=\"%s\" length=\"%.4f\" width=\"%.4f\" height=\"%.4f\" minGap=\"2.0\" "
                "probability=\"%.6f\"/>\n",
                t[i].id, vclass_of(t[i].cls), t[i].length_m, t[i].width_m, t[i].height_m, prob[i]);
    fprintf(a.f, "  </vTypeDistribution>\n");
    int Nroutes = 0;
    if (lanes) {
        int *pathbuf = malloc(sizeof *pathbuf * 33);
        if (!pathbuf) {
            rs_io_atomic_abort(&a);
            return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        }
        for (int e = 0; e < lanes->N; e++) {
            if (is_junction(&lanes->lane[e])) continue;
            bool has_pred = false;
            for (int i = 0; i < n->Ncon; i++) has_pred |= n->con[i].to == e;
            if (has_pred) continue;
            pathbuf[0] = e;
            write_paths(a.f, n, pathbuf, 1, &Nroutes);
        }
        free(pathbuf);
        for (int r = 0; r < Nroutes; r++)
            fprintf(a.f,
                    "  <flow id=\"m%d\" type=\"mix\" route=\"r%d\" begin=\"0\" end=\"%.3f\" vehsPerHour=\"%.3f\" "
                    "departLane=\"best\" departSpeed=\"max\"/>\n",
                    r, r, o->duration_s, o->flow_vph);
    } else {
        for (int r = 0; r < Nosm; r++, Nroutes++)
            fprintf(
                a.f,
                "  <flow id=\"m%d\" type=\"mix\" from=\"%s\" to=\"%s\" begin=\"0\" end=\"%.3f\" vehsPerHour=\"%.3f\" "
                "departLane=\"best\" departSpeed=\"max\"/>\n",
                r, osm_from[r], osm_to[r], o->duration_s, o->flow_vph);
    }
    fprintf(a.f, "</routes>\n");
    if (Nroutes == 0)
        st = rs_err_set(err, RS_ERR_INVALID,
                        "lanes: no manoeuvre: no path of lanes (through `next`) from an entry to an exit");
    return atomic_finish(&a, st, err);
}

// ---------------------------------------------------------------------------------------------
// OpenStreetMap networks: flows between dead ends of the built network

typedef struct {
    rs_synth_sumo_xml x;
    char **id, **from, **to;
    int N, cap;
} edges_ctx;

static char *xml_id(const char *s)
{
    // Edge ids are written back into a routes file as attributes: keep only characters that need
    // no escaping and that SUMO allows in ids; others fail the copy (NULL).
    for (const char *p = s; *p; p++)
        if (strchr("<>&\"' \t\n\r", *p)) return NULL;
    return strdup(s);
}

static void XMLCALL edges_start(void *ud, const XML_Char *name, const XML_Char **a)
{
    edges_ctx *c = ud;
    if (c->x.st || strcmp(name, "edge") || rs_synth_sumo_xml_attr(a, "function")) return;
    const char *id = rs_synth_sumo_xml_attr(a, "id"), *from = rs_synth_sumo_xml_attr(a, "from"),
               *to = rs_synth_sumo_xml_attr(a, "to");
    if (!id || !from || !to) return;
    if (c->N == c->cap) {
        int cap = c->cap ? 2 * c->cap : 256;
        char **i2 = realloc(c->id, sizeof *i2 * (size_t)cap);
        if (i2) c->id = i2;
        char **f2 = realloc(c->from, sizeof *f2 * (size_t)cap);
        if (f2) c->from = f2;
        char **t2 = realloc(c->to, sizeof *t2 * (size_t)cap);
        if (t2) c->to = t2;
        if (!i2 || !f2 || !t2) return rs_synth_sumo_xml_fail(&c->x, RS_ERR_NOMEM, "edge", "out of memory", NULL);
        c->cap = cap;
    }
    char *i = xml_id(id), *f = strdup(from), *t = strdup(to);
    if (!i || !f || !t) {
        free(i), free(f), free(t);
        return;
    }
    c->id[c->N] = i, c->from[c->N] = f, c->to[c->N] = t;
    c->N++;
}

static void edges_free(edges_ctx *c)
{
    for (int i = 0; i < c->N; i++) free(c->id[i]), free(c->from[i]), free(c->to[i]);
    free(c->id), free(c->from), free(c->to);
}

// Entry edges: their from-node has no other edge entering it than from their own to-node; exit
// edges likewise. Pairs (entry, exit) not between the same two nodes, at most 64.
static rs_status osm_pairs(edges_ctx *c, const char ***from, const char ***to, int *N, rs_err *err)
{
    int cap = 64;
    *from = malloc(sizeof **from * (size_t)cap);
    *to = malloc(sizeof **to * (size_t)cap);
    *N = 0;
    if (!*from || !*to) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; i < c->N && *N < cap; i++) {
        bool entry = true;
        for (int k = 0; k < c->N && entry; k++)
            entry = !(strcmp(c->to[k], c->from[i]) == 0 && strcmp(c->from[k], c->to[i]) != 0);
        if (!entry) continue;
        for (int j = 0; j < c->N && *N < cap; j++) {
            if (j == i || !strcmp(c->to[j], c->from[i])) continue;
            bool exit = true;
            for (int k = 0; k < c->N && exit; k++)
                exit = !(strcmp(c->from[k], c->to[j]) == 0 && strcmp(c->to[k], c->from[j]) != 0);
            if (!exit) continue;
            (*from)[*N] = c->id[i];
            (*to)[*N] = c->id[j];
            (*N)++;
        }
    }
    if (*N == 0)
        return rs_err_set(err, RS_ERR_INVALID,
                          "the OpenStreetMap network has no pair of dead-end edges to drive between");
    return RS_OK;
}

// Road types for netconvert's OSM import (Debian's sumo package does not ship SUMO's
// data/typemap): the car-carrying highway values, lanes per direction and speed limits of
// urban defaults; pedestrians and bicycles are not simulated.
static rs_status write_osm_types(const char *path, rs_err *err)
{
    static const struct {
        const char *highway;
        int priority, lanes;
        double speed_mps;
        bool oneway;
    } types[] = {
        {"motorway", 14, 2, 33.33, true},     {"motorway_link", 9, 1, 22.22, true},
        {"trunk", 13, 2, 27.78, false},       {"trunk_link", 8, 1, 22.22, false},
        {"primary", 12, 2, 13.89, false},     {"primary_link", 7, 1, 13.89, false},
        {"secondary", 11, 1, 13.89, false},   {"secondary_link", 6, 1, 13.89, false},
        {"tertiary", 10, 1, 13.89, false},    {"tertiary_link", 5, 1, 13.89, false},
        {"unclassified", 5, 1, 13.89, false}, {"residential", 4, 1, 8.33, false},
        {"living_street", 3, 1, 2.78, false}, {"service", 2, 1, 5.56, false},
    };
    rs_io_atomic a;
    rs_status st = rs_io_atomic_open(&a, path, err);
    if (st) return st;
    fprintf(a.f, "<types>\n");
    for (size_t i = 0; i < sizeof types / sizeof *types; i++)
        fprintf(
            a.f,
            "  <type id=\"highway.%s\" priority=\"%d\" numLanes=\"%d\" speed=\"%.2f\" oneway=\"%s\" "
            "disallow=\"%s\"/>\n",
            types[i].highway, types[i].priority, types[i].lanes, types[i].speed_mps, types[i].oneway ? "true" : "false",
            // bicycles (in the default mix) ride on the roads, not on motorways and trunks
            !strncmp(types[i].highway, "motorway", 8) || !strncmp(types[i].highway, "trunk", 5) ? "pedestrian bicycle"
                                                                                                : "pedestrian");
    fprintf(a.f, "</types>\n");
    return rs_io_atomic_commit(&a, err);
}

// ---------------------------------------------------------------------------------------------
// the run

static rs_status run_in(const char *dir, rs_synth_sumo_frames *frames, const rs_lanes *lanes, const rs_llh *origin,
                        const rs_synth_sumo_options *o, rs_err *err)
{
    char *net = rs_io_join(dir, "net.net.xml"), *nod = rs_io_join(dir, "nodes.nod.xml"),
         *edg = rs_io_join(dir, "edges.edg.xml"), *con = rs_io_join(dir, "connections.con.xml"),
         *rou = rs_io_join(dir, "routes.rou.xml"), *fcd = rs_io_join(dir, "fcd.xml"),
         *log = rs_io_join(dir, "sumo.log"), *typ = rs_io_join(dir, "osm.typ.xml");
    network n = {0};
    edges_ctx ec = {{0}, NULL, NULL, NULL, 0, 0};
    const char **osm_from = NULL, **osm_to = NULL;
    int Nosm = 0;
    rs_synth_sumo_vtype types[3 * RS_SYNTH_NCLASSES];
    double prob[3 * RS_SYNTH_NCLASSES];
    rs_status st = RS_OK;
    if (!net || !nod || !edg || !con || !rou || !fcd || !log || !typ) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    // SUMO reads its file options as comma-separated lists, with no escape: a comma in a path
    // would become two file names (netconvert: "file 'a' not found")
    const char *comma = strchr(dir, ',') ? dir : o->osm_path && strchr(o->osm_path, ',') ? o->osm_path : NULL;
    if (comma) {
        st = rs_err_set(err, RS_ERR_INVALID,
                        "%s: contains a comma, which SUMO (netconvert, sumo) reads as a separator between file "
                        "names: rename or move it",
                        comma);
        goto done;
    }
    remove(log);
    if (o->osm_path) {
        if ((st = write_osm_types(typ, err))) goto done;
        const char *inputs[] = {"--osm-files", o->osm_path, "--type-files", typ};
        if ((st = run_netconvert(o->netconvert, inputs, 4, net, log, err))) goto done;
        ec.x = (rs_synth_sumo_xml){XML_ParserCreate(NULL), net, RS_OK, err};
        if (!ec.x.p) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            goto done;
        }
        XML_SetUserData(ec.x.p, &ec);
        XML_SetStartElementHandler(ec.x.p, edges_start);
        st = rs_synth_sumo_xml_parse_file(&ec.x);
        XML_ParserFree(ec.x.p);
        if (st || (st = osm_pairs(&ec, &osm_from, &osm_to, &Nosm, err))) goto done;
    } else {
        if ((st = write_network_files(dir, lanes, origin, &n, err))) goto done;
        const char *inputs[] = {"--node-files", nod, "--edge-files", edg, "--connection-files", con};
        if ((st = run_netconvert(o->netconvert, inputs, 6, net, log, err))) goto done;
    }
    int Nt = make_vtypes(types, prob, &o->mix, o->seed);
    if ((st = write_routes(dir, o->osm_path ? NULL : lanes, &n, osm_from, osm_to, Nosm, types, prob, Nt, o, err)))
        goto done;
    char seed[32], end[32], begin[32], period[32], step[32];
    snprintf(seed, sizeof seed, "%llu", (unsigned long long)(o->seed % 2147483647ULL));
    snprintf(end, sizeof end, "%.3f", o->duration_s);
    snprintf(begin, sizeof begin, "%.3f", o->warmup_s);
    snprintf(period, sizeof period, "%.3f", o->period_s);
    // SUMO's step (default 1 s) bounds the FCD period from below: a finer period needs a finer step
    snprintf(step, sizeof step, "%.3f", o->period_s < 1 ? o->period_s : 1.0);
    char *argv[] = {(char *)o->sumo,
                    "--net-file",
                    net,
                    "--route-files",
                    rou,
                    "--seed",
                    seed,
                    "--begin",
                    "0",
                    "--end",
                    end,
                    "--fcd-output",
                    fcd,
                    "--fcd-output.geo",
                    "true",
                    "--precision.geo", // 1e-8 degrees, about 1 mm (SUMO's default 1e-6: 0.1 m)
                    "8",
                    "--step-length",
                    step,
                    "--device.fcd.period",
                    period,
                    "--device.fcd.begin",
                    begin,
                    "--xml-validation",
                    "never",
                    "--xml-validation.net",
                    "never",
                    "--no-step-log",
                    "true",
                    "--duration-log.disable",
                    "true",
                    NULL};
    if ((st = run_program(argv, log, err))) goto done;
    rs_synth_sumo_location loc;
    if ((st = rs_synth_sumo_read_location(&loc, net, err))) goto done;
    st = rs_synth_sumo_read_fcd(frames, fcd, true, &loc, origin, types, Nt, err);
done:
    free(net), free(nod), free(edg), free(con), free(rou), free(fcd), free(log), free(typ);
    free(n.parent), free(n.con);
    edges_free(&ec);
    free(osm_from), free(osm_to);
    return st;
}

rs_status rs_synth_sumo_run(rs_synth_sumo_frames *frames, const rs_lanes *lanes, const rs_llh *origin,
                            const rs_synth_sumo_options *o, rs_err *err)
{
    frames->frame = NULL;
    frames->N = 0;
    if (!(o->duration_s > 0 && o->duration_s <= 86400) || !(o->warmup_s >= 0 && o->warmup_s < o->duration_s) ||
        !(o->period_s > 0) || !(o->flow_vph > 0 && o->flow_vph <= 10000))
        return rs_err_set(err, RS_ERR_INVALID,
                          "sumo options: need 0 < duration <= 86400 s, 0 <= warm-up < duration, period > 0, "
                          "0 < flow <= 10000 vehicles/hour");
    if (!o->osm_path && (!lanes || lanes->N == 0)) return rs_err_set(err, RS_ERR_INVALID, "no lanes and no OSM file");
    rs_status st;
    if (o->work_dir) {
        if ((st = rs_io_mkdir_p(o->work_dir, err))) return st;
        return run_in(o->work_dir, frames, lanes, origin, o, err);
    }
    const char *tmp = getenv("TMPDIR");
    char *dir = rs_io_join(tmp && *tmp ? tmp : "/tmp", "roadside-sumo.XXXXXX");
    if (!dir) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!mkdtemp(dir)) {
        st = rs_err_set(err, RS_ERR_IO, "%s: cannot create a temporary folder: %s", dir, strerror(errno));
        free(dir);
        return st;
    }
    st = run_in(dir, frames, lanes, origin, o, err);
    rs_io_remove_tree(dir);
    free(dir);
    return st;
}
