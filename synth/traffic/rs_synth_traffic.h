// rs_synth_traffic.h -- traffic for synthetic scenes: a site's lanes (lanes.geojson), vehicles
// placed along them (the built-in traffic, no SUMO needed), domain randomisation of any
// vehicles (built-in or from SUMO, synth/traffic/rs_synth_sumo.h) with no two footprints overlapping,
// and the vehicles file that `roadside scene` reads. docs/traffic.md describes the models.
//
// Frames: lanes and vehicles are in the site ENU frame (east, north; metres), vehicles as in
// synth/fleet/rs_synth_vehicle.h: footprint centre (e_m, n_m) and yaw_deg, the compass heading of the forward
// axis, clockwise from north.
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "core/rs_status.h"
#include "geo/rs_geo.h"
#include "geo/rs_lanes.h"
#include "synth/fleet/rs_synth_vehicle.h"

#ifdef __cplusplus
extern "C" {
#endif

// ---- vehicles ----

// Vehicles of the traffic are synth/fleet/rs_synth_vehicle.h's rs_synth_vehicle: the built-in
// traffic and SUMO fill cls, e_m, n_m, yaw_deg (in [0, 360)), length/width/height (> 0),
// speed_mps, lane, variant and id, and leave the paint to be drawn (rgb -1) and model_path NULL.

// A bicycle's top speed in the built-in traffic: 20 km/h, SUMO's default bicycle speed (as we
// recall DEFAULT_BICYCLE_SPEED; its bicycle-lane type map uses 5.56 m/s; docs/traffic.md).
#define RS_SYNTH_BICYCLE_MAX_SPEED_MPS 5.56
// The highest speed of a class in the built-in traffic (m/s): RS_SYNTH_BICYCLE_MAX_SPEED_MPS for a
// bicycle, INFINITY (the lane's limit) for the others.
double rs_synth_class_max_speed_mps(rs_synth_class cls);

// The built-in traffic model.
typedef struct {
    uint64_t seed;
    int count; // keep at most this many vehicles (a random subset); 0 = all that fit
    rs_synth_class_mix mix;
    double s0_m;              // standstill gap, bumper to bumper (default 2.0 m)
    double headway_s;         // time headway T (default 1.5 s)
    double headway_jitter;    // the gap's v*T part is scaled by U(1 - j, 1 + j) (default 0.5)
    double speed_fraction[2]; // each vehicle's speed: U(a, b) x the lane's speed limit (a
                              //   bicycle's: x rs_synth_class_max_speed_mps when lower)
                              // (default [0, 1]; 13.89 m/s when the lane gives none)
    bool junction_lanes;      // also fill lanes whose kind is "junction" (default false: their
                              // vehicles would cross; SUMO handles junctions)
} rs_synth_traffic_options;

void rs_synth_traffic_options_default(rs_synth_traffic_options *opt);

// Places vehicles along the lanes: on each lane, walking upstream from its end, the first
// vehicle's front bumper at a gap drawn as below from the end, then each next vehicle's front
// at its leader's rear minus the gap s0 + v T u (v its speed, u ~ U(1 - j, 1 + j)): the
// time-headway (constant time gap) spacing of car-following models (Treiber, Hennecke and
// Helbing, "Congested traffic states in empirical observations and microscopic simulations",
// Phys. Rev. E 62, 2000: s0 = 2 m, T = 1.5 s). A vehicle lies wholly on its lane (centre, yaw
// from the polyline at the centre's arc length); "both" lanes get a random direction per lane.
// Class from the mix, dimensions uniform in the class's ranges (rs_synth_class_range_get),
// variant from the seed.
// With count > 0, a uniformly drawn subset of count vehicles is kept (in placement order).
// out: *vehicles (N,) owned (free()), *N. Returns RS_ERR_INVALID for bad options, RS_ERR_NOMEM.
rs_status rs_synth_traffic_place( // out
    rs_synth_vehicle **vehicles, int *N,
    // in
    const rs_lanes *lanes, const rs_synth_traffic_options *opt, rs_err *err);

// ---- domain randomisation ----

typedef struct {
    uint64_t seed;
    double sigma_along_m;  // normal offset along the vehicle's heading (default sqrt(0.5) m)
    double sigma_across_m; // normal offset across it (default sqrt(0.5) m)
    double yaw_range_deg;  // heading offset uniform in [-r, r] (default 5 degrees)
    int tries;             // draws per vehicle before it is dropped (default 20)
} rs_synth_randomise_options;

void rs_synth_randomise_options_default(rs_synth_randomise_options *opt);

// Domain randomisation: each vehicle, in order, is moved by a normal offset along and across
// its heading and turned by a uniform heading offset, drawn again (up to `tries` times) while
// its footprint overlaps one of the vehicles already kept; a vehicle that still overlaps is
// dropped. (The seed paper's "variance of 0.5 m" is read as a variance of 0.5 m^2, sigma =
// 0.707 m; docs/traffic.md.) The kept vehicles are compacted to the front in their order.
// in,out: vehicles (N,), *N (the number kept)
rs_status rs_synth_traffic_randomise( // in,out
    rs_synth_vehicle *vehicles, int *N,
    // in
    const rs_synth_randomise_options *opt, rs_err *err);

// Whether the footprints (oriented rectangles length x width at (e, n), yaw) of two vehicles
// overlap: separating axis theorem over the four edge normals; rectangles that only touch do
// not overlap.
bool rs_synth_footprints_overlap(const rs_synth_vehicle *a, const rs_synth_vehicle *b);

// ---- output ----

// Writes the vehicles file `roadside scene` reads (synth/traffic/rs_synth_vehicles.h,
// rs_synth_vehicles_read): a JSON list of {"id", "class", "e", "n", "yaw_deg", "length",
// "width", "height", "variant", "speed_mps"}, lengths to 1e-4 m, angles to 1e-4 degree. Written
// atomically (core/rs_io.h).
rs_status rs_synth_traffic_write_json(const char *path,
                                      // in
                                      const rs_synth_vehicle *vehicles, int N, rs_err *err);

#ifdef __cplusplus
}
#endif
