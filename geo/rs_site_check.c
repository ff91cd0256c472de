// rs_site_check.c -- the plausibility checks of a site that need more than one value at a
// time: positions (range, swapped lat/lon, radians, distance, heights), observations (inside the
// image, duplicates, enough per camera) and ids unique across the site. They only check and
// report: the reader (rs_site_read.c, rs_site_read_camera.c) calls them while it reads; they
// call rs_site_report.c (rs_site__diag) and the geodesy (rs_geo_llh_to_enu), nothing else.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/rs_io.h"
#include "core/rs_units.h"
#include "geo/internal/rs_site_internal.h"

// A camera needs at least this many landmarks picked: the fewest that determine a pose without
// ambiguity (P3P has up to four solutions).
enum { MIN_OBSERVATIONS = 4 };
// Straight pieces within this angle of each other count as parallel (site check's warning).
#define PARALLEL_DEG 1.0

// ---- positions ----

// Distance of (lat, lon, h_ell) from the site origin; false if the point is not a valid
// geodetic position.
static bool distance_from_origin(double *d_m, double p_enu_m[3], const rs_site *site, double lat, double lon,
                                 double h_ell)
{
    if (!(lat >= -90 && lat <= 90 && lon >= -180 && lon <= 180)) return false;
    const double llh[3] = {lat, lon, h_ell};
    if (rs_geo_llh_to_enu(p_enu_m, &site->origin, llh, 1, NULL) != RS_OK) return false;
    *d_m = sqrt(p_enu_m[0] * p_enu_m[0] + p_enu_m[1] * p_enu_m[1] + p_enu_m[2] * p_enu_m[2]);
    return isfinite(*d_m);
}

static void format_distance(char *buf, size_t size, double d_m)
{
    if (d_m >= 10000)
        snprintf(buf, size, "%.0f km", d_m / 1000);
    else
        snprintf(buf, size, "%.1f m", d_m);
}

// How a corrected position should be written: as a GeoJSON triple or as lat/lon fields.
static void format_position(char *buf, size_t size, bool geojson_order, double lat, double lon, double h)
{
    if (geojson_order)
        snprintf(buf, size, "[%.9f, %.9f, %.3f]", lon, lat, h);
    else
        snprintf(buf, size, "lat %.9f, lon %.9f", lat, lon);
}

// Heights in two systems (an orthometric origin with ellipsoidal landmarks, or the other way
// round) put points tens of metres above or below the ground. Warns when a point lies more than
// HEIGHT_WARN_M above or below the origin and steeper than 1:2 from it.
static void check_height(rs_site__report *r, const char *file, int feature, const char *feature_id, const char *field,
                         const double p_enu_m[3])
{
    const double HEIGHT_WARN_M = 20;
    double horizontal = hypot(p_enu_m[0], p_enu_m[1]);
    if (fabs(p_enu_m[2]) <= HEIGHT_WARN_M || fabs(p_enu_m[2]) <= 0.5 * horizontal) return;
    rs_site__diag(r, RS_SITE_WARNING, RS_OK, file, 0, feature, feature_id, field,
                  "%.1f m %s the origin, %.1f m from it horizontally: if both are near the ground, "
                  "are their heights in the same system (ellipsoidal vs orthometric: \"heights\" "
                  "and its N)?",
                  fabs(p_enu_m[2]), p_enu_m[2] > 0 ? "above" : "below", horizontal);
}

bool rs_site__check_position(double llh[3], double p_enu_m[3], rs_site__report *r, const rs_site *site, bool origin_ok,
                             const char *file, int feature, const char *feature_id, const char *field,
                             bool geojson_order, const double given[3])
{
    const double lat = given[0], lon = given[1], h = given[2];
    const double h_ell = h + site->geoid_undulation_m;
    const double max_m = site->max_landmark_distance_m;
    const bool lat_ok = lat >= -90 && lat <= 90, lon_ok = lon >= -180 && lon <= 180;

    if (!(h >= RS_SITE_HEIGHT_MIN_M && h <= RS_SITE_HEIGHT_MAX_M)) {
        rs_site__diag(r, RS_SITE_ERROR, RS_ERR_INVALID, file, 0, feature, feature_id, field,
                      "height %.9g m is not near the Earth's surface ([%g, %g] m)", h, RS_SITE_HEIGHT_MIN_M,
                      RS_SITE_HEIGHT_MAX_M);
        return false;
    }
    double d = NAN, p[3];
    bool have_d = origin_ok && distance_from_origin(&d, p, site, lat, lon, h_ell);
    if (have_d && d <= max_m) {
        check_height(r, file, feature, feature_id, field, p);
        llh[0] = lat, llh[1] = lon, llh[2] = h_ell;
        memcpy(p_enu_m, p, sizeof p);
        return true;
    }

    char as_given[64] = "out of range", dist[32], fixed[128];
    if (have_d) format_distance(as_given, sizeof as_given, d);

    if (origin_ok) {
        double ds, ps[3];
        if (distance_from_origin(&ds, ps, site, lon, lat, h_ell) && ds <= max_m) {
            format_distance(dist, sizeof dist, ds);
            format_position(fixed, sizeof fixed, geojson_order, lon, lat, h);
            rs_site__diag(r, RS_SITE_ERROR, RS_ERR_INVALID, file, 0, feature, feature_id, field,
                          "looks like latitude and longitude are exchanged%s (as given: %s%s; "
                          "exchanged: %s from the origin): should it be %s?",
                          geojson_order ? " ([lat, lon] order; GeoJSON is [lon, lat, h])" : "", as_given,
                          have_d ? " from the origin" : "", dist, fixed);
            return false;
        }
        double dr, pr[3];
        if (distance_from_origin(&dr, pr, site, lat * RS_DEG_PER_RAD, lon * RS_DEG_PER_RAD, h_ell) && dr <= max_m) {
            format_distance(dist, sizeof dist, dr);
            format_position(fixed, sizeof fixed, geojson_order, lat * RS_DEG_PER_RAD, lon * RS_DEG_PER_RAD, h);
            rs_site__diag(r, RS_SITE_ERROR, RS_ERR_INVALID, file, 0, feature, feature_id, field,
                          "looks like radians (as given: %s%s; converted to degrees: %s from the "
                          "origin): should it be %s?",
                          as_given, have_d ? " from the origin" : "", dist, fixed);
            return false;
        }
    }
    if (!lat_ok) {
        rs_site__diag(r, RS_SITE_ERROR, RS_ERR_INVALID, file, 0, feature, feature_id, field,
                      "latitude %.9g is out of range [-90, 90]", lat);
        return false;
    }
    if (!lon_ok) {
        rs_site__diag(r, RS_SITE_ERROR, RS_ERR_INVALID, file, 0, feature, feature_id, field,
                      "longitude %.9g is out of range [-180, 180]", lon);
        return false;
    }
    if (!origin_ok) return false; // the origin is at fault, and reported as such
    if (!have_d) {                // cannot happen for a valid origin and a checked height; never silent
        rs_site__diag(r, RS_SITE_ERROR, RS_ERR_INVALID, file, 0, feature, feature_id, field,
                      "lat %.9g, lon %.9g, h %.9g m has no position in the site's ENU frame", lat, lon, h);
        return false;
    }
    format_distance(dist, sizeof dist, d);
    rs_site__diag(r, RS_SITE_WARNING, RS_OK, file, 0, feature, feature_id, field,
                  "%s from the origin, farther than max_landmark_distance_m (%g m)", dist, max_m);
    llh[0] = lat, llh[1] = lon, llh[2] = h_ell;
    memcpy(p_enu_m, p, sizeof p);
    return true;
}

// ---- observations ----

bool rs_site__check_observation(rs_site__report *r, const rs_site_camera *cam, const rs_site_observation *obs,
                                const rs_site *site, int *picked)
{
    const char *file = cam->observations_path;
    bool ok = true;
    if (cam->camera.width > 0 && cam->camera.height > 0) {
        const char *axis[2] = {"u", "v"};
        const int size[2] = {cam->camera.width, cam->camera.height};
        for (int k = 0; k < 2; k++) {
            if (obs->q_px[k] >= -0.5 && obs->q_px[k] <= size[k] - 0.5) continue;
            rs_site__diag(r, RS_SITE_ERROR, RS_ERR_INVALID, file, obs->line, -1, NULL, axis[k],
                          "%g is outside the image: valid %s in [-0.5, %.1f] (%s %d in %s)", obs->q_px[k], axis[k],
                          size[k] - 0.5, k ? "height" : "width", size[k], cam->model_path);
            ok = false;
        }
    }
    // a point, a pole's base and a pole's top are each picked at most once; `along` picks repeat
    if (obs->at == RS_SITE_AT_ALONG) return ok;
    const int slot = obs->at == RS_SITE_AT_TOP ? 2 : obs->at == RS_SITE_AT_BASE;
    int first = 0;
    if (picked)
        first = picked[3 * obs->ilandmark + slot];
    else
        for (int i = 0; i < cam->Nobservations && !first; i++)
            if (cam->observations[i].ilandmark == obs->ilandmark && cam->observations[i].at == obs->at)
                first = cam->observations[i].line > 0 ? cam->observations[i].line : -1;
    if (!first) {
        if (picked) picked[3 * obs->ilandmark + slot] = obs->line > 0 ? obs->line : -1;
        return ok;
    }
    if (obs->at == RS_SITE_AT_POINT)
        rs_site__diag(r, RS_SITE_ERROR, RS_ERR_INVALID, file, obs->line, -1, NULL, "landmark",
                      "'%s' is observed twice in this camera (first at line %d)", site->landmarks[obs->ilandmark].id,
                      first);
    else
        rs_site__diag(r, RS_SITE_ERROR, RS_ERR_INVALID, file, obs->line, -1, NULL, "at",
                      "'%s' is picked at its %s twice in this camera (first at line %d); only 'along' picks "
                      "may repeat",
                      site->landmarks[obs->ilandmark].id, rs_site_at_name(obs->at), first);
    return false;
    return ok;
}

// The straight pieces of a landmark: a pole 1 (vertical), a line Nvertices - 1. Zero for points.
static int segments(const rs_site_landmark *l)
{
    return l->shape == RS_SITE_POLE ? 1 : l->shape == RS_SITE_LINE && l->Nvertices > 1 ? l->Nvertices - 1 : 0;
}

// Unit direction of segment k of a pole or line into d (3,); false when unusable.
static bool segment_direction(double d[3], const rs_site_landmark *l, int k)
{
    if (l->shape == RS_SITE_POLE) {
        d[0] = d[1] = 0, d[2] = 1;
        return true;
    }
    const double *a = &l->vertices_enu_m[3 * k], *b = a + 3;
    for (int j = 0; j < 3; j++) d[j] = b[j] - a[j];
    const double n = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (!(n > 0) || !isfinite(n)) return false;
    for (int j = 0; j < 3; j++) d[j] /= n;
    return true;
}

static int cmp_int(const void *a, const void *b)
{
    const int x = *(const int *)a, y = *(const int *)b;
    return (x > y) - (x < y);
}

void rs_site__check_camera(rs_site__report *r, const rs_site_camera *cam, const rs_site *site)
{
    // Constraints: a pick of a point, a pole's base or top fixes 2 (u and v); an `along` pick 1
    // (its distance to the projected segment or polyline), and the along picks of one landmark at
    // most 2 per straight segment (the image of a straight segment is fixed by 2 numbers).
    int Nconstraints = 0, Nalong = 0, Nfixed = 0;
    int *along = malloc((size_t)(cam->Nobservations > 0 ? cam->Nobservations : 1) * sizeof *along);
    if (!along) {
        r->nomem = true;
        return;
    }
    for (int i = 0; i < cam->Nobservations; i++) {
        const rs_site_observation *o = &cam->observations[i];
        if (o->at != RS_SITE_AT_ALONG)
            Nconstraints += 2, Nfixed++;
        else
            along[Nalong++] = o->ilandmark;
    }
    // each landmark's along picks counted once: sorted, a run per landmark
    qsort(along, (size_t)Nalong, sizeof *along, cmp_int);
    for (int i = 0, n = 1; i < Nalong; i++, n++)
        if (i + 1 == Nalong || along[i + 1] != along[i]) {
            const int most = 2 * segments(&site->landmarks[along[i]]);
            Nconstraints += n < most ? n : most;
            n = 0;
        }
    free(along);
    if (Nalong == 0) {
        if (cam->Nobservations >= MIN_OBSERVATIONS) return;
        rs_site__diag(r, r->picking ? RS_SITE_WARNING : RS_SITE_ERROR, RS_ERR_INVALID, cam->observations_path, 0, -1,
                      NULL, NULL,
                      "camera '%s' has %d usable observation%s: it needs at least %d landmarks "
                      "picked to be calibrated",
                      cam->id, cam->Nobservations, cam->Nobservations == 1 ? "" : "s", MIN_OBSERVATIONS);
        return;
    }
    if (Nconstraints < 2 * MIN_OBSERVATIONS) {
        rs_site__diag(r, r->picking ? RS_SITE_WARNING : RS_SITE_ERROR, RS_ERR_INVALID, cam->observations_path, 0, -1,
                      NULL, NULL,
                      "camera '%s': its %d picks (%d along a pole or line) fix %d numbers (2 per point, base or top "
                      "pick; 1 per along pick, at most 2 per straight segment): it needs at least %d, as %d points "
                      "give, to be calibrated",
                      cam->id, cam->Nobservations, Nalong, Nconstraints, 2 * MIN_OBSERVATIONS, MIN_OBSERVATIONS);
        return;
    }
    // Only along picks, all on segments of one direction (parallel lane lines): nothing fixes
    // where the camera is along that direction.
    if (Nfixed > 0) return;
    double d0[3] = {0, 0, 0};
    bool have = false, parallel = true;
    for (int i = 0; i < cam->Nobservations && parallel; i++) {
        const rs_site_landmark *l = &site->landmarks[cam->observations[i].ilandmark];
        for (int k = 0; k < segments(l) && parallel; k++) {
            double d[3];
            if (!segment_direction(d, l, k)) continue;
            if (!have) {
                memcpy(d0, d, sizeof d0), have = true;
                continue;
            }
            const double cosine = fabs(d[0] * d0[0] + d[1] * d0[1] + d[2] * d0[2]);
            parallel = cosine >= cos(PARALLEL_DEG * M_PI / 180);
        }
    }
    if (have && parallel)
        rs_site__diag(r, RS_SITE_WARNING, RS_OK, cam->observations_path, 0, -1, NULL, NULL,
                      "camera '%s': every pick is 'along' a pole or line, and they all run in one direction (within "
                      "%g degrees, ENU (%.3f, %.3f, %.3f)): nothing fixes where the camera is along it; pick a "
                      "point, a pole's base or top, or a line across them",
                      cam->id, PARALLEL_DEG, d0[0], d0[1], d0[2]);
}

// ---- the whole site ----

typedef struct {
    const char *id;
    int index;
} id_index;

static int cmp_id_index(const void *a, const void *b)
{
    const id_index *x = a, *y = b;
    const int c = strcmp(x->id, y->id);
    return c ? c : (x->index > y->index) - (x->index < y->index);
}

typedef struct {
    long long cell[3]; // ENU position rounded to RS_SITE_COINCIDENT_M
    int index;
} cell_index;

static int cmp_cell_index(const void *a, const void *b)
{
    const cell_index *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x->cell[k] != y->cell[k]) return (x->cell[k] > y->cell[k]) - (x->cell[k] < y->cell[k]);
    return (x->index > y->index) - (x->index < y->index);
}

// Landmarks at the same position (ENU rounded to RS_SITE_COINCIDENT_M; a copied coordinate, most
// often): a warning each, against the first in file order, in O(N log N) like the ids. What calib
// does with them is said, so that the user can tell whether to act.
static void check_coincident(rs_site__report *r, const rs_site *site, const char *landmarks_path)
{
    const int N = site->Nlandmarks;
    cell_index *sorted = malloc((size_t)(N > 0 ? N : 1) * sizeof *sorted);
    if (!sorted) {
        r->nomem = true;
        return;
    }
    int n = 0;
    for (int k = 0; k < N; k++) {
        const double *p = site->landmarks[k].p_enu_m;
        // unusable positions (reported where they were read) and positions beyond 10^6 km
        // (refused there too) are not compared
        if (!(fabs(p[0]) < 1e9 && fabs(p[1]) < 1e9 && fabs(p[2]) < 1e9)) continue;
        cell_index *e = &sorted[n++];
        for (int j = 0; j < 3; j++) e->cell[j] = llround(p[j] / RS_SITE_COINCIDENT_M);
        e->index = k;
    }
    qsort(sorted, (size_t)n, sizeof *sorted, cmp_cell_index);
    for (int k = 1, first = 0; k < n; k++) {
        const long long *ck = sorted[k].cell, *cf = sorted[first].cell;
        if (ck[0] != cf[0] || ck[1] != cf[1] || ck[2] != cf[2]) {
            first = k;
            continue;
        }
        const rs_site_landmark *a = &site->landmarks[sorted[first].index], *b = &site->landmarks[sorted[k].index];
        rs_site__diag(r, RS_SITE_WARNING, RS_OK, landmarks_path, 0, b->feature, b->id, "coordinates",
                      "at the same position as '%s' (feature %d, within %g mm): a copied coordinate? calib keeps "
                      "both; a camera's initial pose uses only '%s', and the refinement flags whichever of the two "
                      "disagrees with its picks as an outlier",
                      a->id ? a->id : "?", a->feature, RS_SITE_COINCIDENT_M * 1e3, a->id ? a->id : "?");
    }
    free(sorted);
}

void rs_site__check_site(rs_site__report *r, const rs_site *site)
{
    char *landmarks_path = rs_io_join(site->dir, RS_SITE_LANDMARKS);
    char *site_path = rs_io_join(site->dir, RS_SITE_JSON);
    if (!landmarks_path || !site_path) {
        r->nomem = true;
        goto done;
    }
    // duplicate landmark ids in O(N log N): sorted by (id, index), each later member of a run of
    // equal ids refers to the run's first; reported in file order, as the pairwise loop did
    const int N = site->Nlandmarks;
    id_index *sorted = malloc((size_t)(N > 0 ? N : 1) * sizeof *sorted);
    int *first = malloc((size_t)(N > 0 ? N : 1) * sizeof *first);
    if (!sorted || !first) {
        r->nomem = true;
        free(sorted);
        free(first);
        goto done;
    }
    for (int k = 0; k < N; k++) // an id lost to a failed allocation (nomem is reported) compares as ""
        sorted[k] = (id_index){site->landmarks[k].id ? site->landmarks[k].id : "", k}, first[k] = -1;
    qsort(sorted, (size_t)N, sizeof *sorted, cmp_id_index);
    for (int k = 1; k < N; k++)
        if (!strcmp(sorted[k].id, sorted[k - 1].id))
            first[sorted[k].index] = first[sorted[k - 1].index] >= 0 ? first[sorted[k - 1].index] : sorted[k - 1].index;
    for (int j = 0; j < N; j++)
        if (first[j] >= 0)
            rs_site__diag(r, RS_SITE_ERROR, RS_ERR_INVALID, landmarks_path, 0, site->landmarks[j].feature,
                          site->landmarks[j].id, "properties.id", "duplicate id (already used by feature %d)",
                          site->landmarks[first[j]].feature);
    free(sorted);
    free(first);
    check_coincident(r, site, landmarks_path);
    for (int j = 1; j < site->Ncameras; j++)
        for (int i = 0; i < j; i++) {
            // without case: "Cam1" and "cam1" name one file on a case-insensitive file system
            if (strcasecmp(site->cameras[i].id, site->cameras[j].id)) continue;
            char field[64];
            snprintf(field, sizeof field, "cameras[%d].id", j);
            const bool same = !strcmp(site->cameras[i].id, site->cameras[j].id);
            rs_site__diag(r, RS_SITE_ERROR, RS_ERR_INVALID, site_path, 0, -1, NULL, field,
                          "duplicate camera id '%s' (already used by cameras[%d]%s%s%s)", site->cameras[j].id, i,
                          same ? "" : " as '", same ? "" : site->cameras[i].id,
                          same ? "" : "': camera ids are compared without case, as their files are on some disks");
            break;
        }
done:
    free(landmarks_path);
    free(site_path);
}
