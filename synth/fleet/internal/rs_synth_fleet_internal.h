// rs_synth_fleet_internal.h -- what the fleet's files share (synth/fleet/rs_synth_fleet*.c): the
// variant's random streams and the growing mesh the procedural builder and the OBJ reader fill.
// Internal to synth; the API is synth/fleet/rs_synth_fleet.h.
//
//   rs_synth_fleet.c        classes, ranges, colour mix, resolving drawn values
//   rs_synth_fleet_mesh.c   rs_synth_mesh and the builder below
//   rs_synth_fleet_build.c  procedural vehicles: lofted bodies, caps, wheels, class shapes
//   rs_synth_fleet_model.c  user models (assimp: OBJ + MTL, glTF 2.0), their textures
//   rs_synth_fleet_pov.c    POV-Ray mesh2 declarations and placements
#pragma once
#include <stdint.h>

#include "core/rs_rng.h"
#include "synth/fleet/rs_synth_fleet.h"

// Independent streams per drawn quantity, so that giving one value never changes the others.
enum {
    RS_SYNTH_FLEET_STREAM_LENGTH = 1, // length, width, height: LENGTH + 0, 1, 2
    RS_SYNTH_FLEET_STREAM_WIDTH,
    RS_SYNTH_FLEET_STREAM_HEIGHT,
    RS_SYNTH_FLEET_STREAM_COLOUR,
    RS_SYNTH_FLEET_STREAM_SHAPE,
    RS_SYNTH_FLEET_STREAM_CLASS,
    RS_SYNTH_FLEET_STREAM_LOOK
};

// The generator of stream `which` (RS_SYNTH_FLEET_STREAM_*) of a vehicle's variant (or of the
// seed of rs_synth_fleet_random). Deterministic.
rs_rng rs_synth_fleet_stream(uint64_t variant, int which);

// A mesh being built: m grows as vertices and triangles are added. An allocation failure sets
// `failed` and makes every later add a no-op; the caller checks `failed` once at the end and
// then frees m (rs_synth_mesh_free) or hands it over. Start from a zeroed struct.
typedef struct {
    rs_synth_mesh m;  // owned until handed over
    int cap_v, cap_t; // allocated vertices, triangles
    int failed;
    int nseg, nwheel;  // procedural level of detail: uniform stations along a body, sides of a wheel
    double loft_tol_m; // stations of a body dropped where it is straight within this (< 0: none)
} rs_synth_fleet_builder;

// Appends the vertex (x, y, z) (vehicle frame, metres); returns its index (0 once failed).
int rs_synth_fleet_add_v(rs_synth_fleet_builder *b, double x, double y, double z);

// Appends the triangle (i, j, k), counter-clockwise seen from outside, of rs_synth_part `part`.
void rs_synth_fleet_add_t(rs_synth_fleet_builder *b, int i, int j, int k, int part);

// Makes the triangles from t0 on (one closed component) wind outward: reverses them all when
// their signed volume is negative.
void rs_synth_fleet_orient(rs_synth_fleet_builder *b, int t0);

// Smooth normals with creases (m.vn, m.tri_n): the normal at a triangle's corner is the
// area-weighted mean of the normals of the triangles sharing that vertex whose normal is within
// crease_deg of this triangle's; identical corner normals of a vertex are stored once.
void rs_synth_fleet_smooth(rs_synth_fleet_builder *b, double crease_deg);

// Whether s is an identifier rs_synth_fleet_write_declare accepts: [A-Z_][A-Za-z0-9_]*, at most
// 40 characters.
int rs_synth_fleet_valid_identifier(const char *s);
