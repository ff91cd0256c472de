// rs_synth_sumo.h -- traffic from SUMO (Eclipse SUMO, https://eclipse.dev/sumo/): a network
// built from the site's lanes with netconvert, flows for every manoeuvre, a seeded sumo run, and
// its floating car data (FCD) read back as vehicles in the site ENU frame. docs/traffic.md.
//
// FCD conventions (SUMO documentation, "Simulation/Output/FCDOutput"): a <vehicle>'s x, y is the
// middle of its FRONT BUMPER, in the network's projected coordinates (x, y) or, with
// --fcd-output.geo, as longitude, latitude (x = lon, y = lat); `angle` is the heading in degrees
// clockwise from north IN THE PROJECTED GRID (0 = grid north, 90 = grid east). Networks built
// here project with netconvert's --proj.utm (UTM zone of the network's centre; recorded in the
// net.xml's <location projParameter="+proj=utm +zone=Z ...">, netOffset = the shift from UTM
// to network coordinates). So, for each vehicle:
//   front (lon, lat)  = FCD x, y (geo), or UTM (x - netOffset.x, y - netOffset.y) -> lon, lat
//   true bearing      = angle + gamma, gamma = the meridian convergence of that UTM zone at the
//                       point (rs_geo_utm_convergence_deg: the clockwise angle from true north to
//                       grid north)
//   front ENU         = rs_geo_llh_to_enu(front) at the site origin
//   centre ENU        = front ENU - (length / 2) * (sin b, cos b), length = the vType's length
//   yaw_deg           = b.
// (The site ENU's north differs from true north at the vehicle by dlon * sin(lat): under 0.02
// degree within 1 km of the origin; this is neglected.)
#pragma once
#include <stdbool.h>
#include <stdint.h>

#include "core/rs_status.h"
#include "geo/rs_geo.h"
#include "synth/traffic/rs_synth_traffic.h"

#ifdef __cplusplus
extern "C" {
#endif

// A SUMO vehicle type as used by the FCD reader: its id and the box it stands for.
typedef struct {
    char id[48];
    rs_synth_class cls;
    double length_m, width_m, height_m;
} rs_synth_sumo_vtype;

// Where a SUMO network's coordinates are: read from net.xml's <location>.
typedef struct {
    int zone;               // UTM zone 1..60 of the projection (+proj=utm +zone=Z)
    bool north;             // false with "+south"
    double net_offset_m[2]; // network x, y = UTM easting, northing + net_offset_m
} rs_synth_sumo_location;

// Reads <location netOffset="X,Y" projParameter="+proj=utm +zone=Z [+south] ..."> of a net.xml
// (expat). RS_ERR_UNSUPPORTED for a network that is not projected with UTM ("!" or another
// projection), RS_ERR_PARSE naming the file, line and attribute, RS_ERR_NOT_FOUND without a
// <location>.
rs_status rs_synth_sumo_read_location( // out
    rs_synth_sumo_location *loc,
    // in
    const char *net_path, rs_err *err);

// One FCD time step.
typedef struct {
    double time_s;
    rs_synth_vehicle *v; // (N,) owned
    int N;
} rs_synth_sumo_frame;

typedef struct {
    rs_synth_sumo_frame *frame; // (N,) owned, in file order
    int N;
} rs_synth_sumo_frames;

void rs_synth_sumo_frames_free(rs_synth_sumo_frames *frames); // NULL-safe; leaves it empty

// Reads an FCD file (expat, streaming) and converts each vehicle as described at the top.
// in: geo: the file was written with --fcd-output.geo (x, y = lon, lat);
//     loc: the network's location (for gamma, and for x, y when !geo);
//     origin: the site origin; types (Ntypes,): the vTypes used (a vehicle's `type` must be one)
// A vehicle's lane index is that of an edge "e<K>" of rs_synth_sumo_run's networks (lane K of
// the site's lanes), else -1; speed from `speed`; variant from a hash of its id.
// Errors name the file and line: "fcd.xml:57: vehicle.type: 'x' is not a known vType".
rs_status rs_synth_sumo_read_fcd( // out
    rs_synth_sumo_frames *frames,
    // in
    const char *fcd_path, bool geo, const rs_synth_sumo_location *loc, const rs_llh *origin,
    const rs_synth_sumo_vtype *types, int Ntypes, rs_err *err);

typedef struct {
    uint64_t seed;          // sumo --seed (and the vType sizes)
    double duration_s;      // simulated time (default 300 s)
    double warmup_s;        // no frames before this time (default 60 s)
    double period_s;        // one frame every period_s (default 1 s; below 1 s SUMO steps by period_s)
    double flow_vph;        // vehicles per hour on every manoeuvre (default 200)
    rs_synth_class_mix mix; // vType distribution (default rs_synth_class_mix_default)
    const char *osm_path;   // an OpenStreetMap file to build the network from instead of the
                            // lanes (NULL: from the lanes)
    const char *work_dir;   // keep SUMO's input and output files here (created); NULL: a
                            // temporary folder, removed afterwards
    const char *sumo;       // programs (default "sumo", "netconvert", looked up on PATH)
    const char *netconvert;
} rs_synth_sumo_options;

void rs_synth_sumo_options_default(rs_synth_sumo_options *opt);

// The whole path: writes plain-XML nodes, edges and connections for the lanes (each lane that is
// not a "junction" lane becomes a one-lane edge "e<K>" with the lane's polyline as its shape and
// spreadType "center"; the lane ends joined through `next` and junction lanes meet at one node,
// a traffic light where three or more edges enter it, and the joins become <connection>s),
// runs netconvert --proj.utm (or on the OSM file), defines a vType distribution from the mix
// (three sizes per class) and one flow per manoeuvre (every path of connections from an edge
// without predecessor to one without successor; with --osm, one flow between each pair of
// distinct dead-end edges of the network, routed by sumo), runs sumo with the seed writing
// geo FCD every period_s, and reads it back (rs_synth_sumo_read_fcd).
// Programs run with posix_spawnp, arguments as an argv array (no shell), SUMO_HOME set to
// /usr/share/sumo when unset, XML validation off (nothing is fetched from the network), their
// output in work_dir/sumo.log. RS_ERR_NOT_FOUND if sumo or netconvert is missing,
// RS_ERR_EXTERNAL when one fails (the message ends with the last line of its log).
rs_status rs_synth_sumo_run( // out
    rs_synth_sumo_frames *frames,
    // in
    const rs_lanes *lanes, const rs_llh *origin, const rs_synth_sumo_options *opt, rs_err *err);

// Writes the frames of a SUMO run as `roadside traffic --sumo` does: dir/frame_NNNNNN.json per
// frame (rs_synth_traffic_write_json), each frame's vehicles first randomised
// (rs_synth_traffic_randomise with seed rnd->seed + frame index; with randomise false only the
// overlaps are resolved: no noise), and the index dir/frames.json ({file, time_s, vehicles} per
// frame). Every file is written atomically; dir is created. *Nvehicles: the vehicles written.
// The frames' vehicles are changed in place (randomised).
rs_status rs_synth_sumo_frames_write( // in
    const char *dir,
    // in,out
    rs_synth_sumo_frames *fr,
    // in
    const rs_synth_randomise_options *rnd, bool randomise,
    // out
    int *Nvehicles, rs_err *err);

// One entry of a frames index, DIR/frames.json (rs_synth_sumo_frames_write writes it).
typedef struct {
    char file[256]; // the frame's vehicles file: a plain name in DIR ("frame_000012.json")
    double time_s;  // its SUMO time, seconds
    int vehicles;   // the vehicles the index says the file holds (>= 0)
} rs_synth_sumo_frame_entry;

// Reads DIR/frames.json (cJSON): the JSON list of {"file", "time_s", "vehicles"} that
// rs_synth_sumo_frames_write writes, one reader for the one writer. A file must be a plain name
// inside DIR (no '/', not "." or ".."). The frames themselves are vehicles files
// (rs_synth_vehicles_read, synth/traffic/rs_synth_vehicles.h); this does not open them.
// out: *entries (N,) owned (free()), NULL when *N is 0 (an empty list is not an error here)
// Errors name the file and the field: RS_ERR_NOT_FOUND "DIR/frames.json: missing (...)",
// RS_ERR_IO (unreadable), RS_ERR_PARSE "DIR/frames.json:LINE: JSON syntax error near ...",
// RS_ERR_INVALID "DIR/frames.json: [3].vehicles: expected an integer >= 0".
rs_status rs_synth_sumo_frames_index_read( // out
    rs_synth_sumo_frame_entry **entries, int *N,
    // in
    const char *dir, rs_err *err);

#ifdef __cplusplus
}
#endif
