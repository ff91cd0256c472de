// rs_synth_prepare.h -- vehicles ready for a scene: each resolved (rs_synth_fleet_resolve), its
// mesh built, a user model loaded once per distinct specification and shared by its instances.
#pragma once
#include <stdint.h>

#include "core/rs_status.h"
#include "synth/fleet/rs_synth_fleet.h"
#include "synth/fleet/rs_synth_vehicle.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    rs_synth_vehicle *v; // (N,) owned copies, resolved: dimensions > 0 (a user model's from its
                         // mesh bounds), paint set; strings still borrowed from the input
    int N;
    rs_synth_mesh *meshes; // (Nmeshes,) owned
    int Nmeshes;
    int *imesh; // (N,) owned: the mesh of each vehicle
} rs_synth_prepared;

// in: vehicles (N,); obj (N,) user models' specs (entries of procedural vehicles ignored), may be
//     NULL when there is no user model
// Errors are the fleet's, prefixed with "vehicle K (id ...): " (id sanitised).
rs_status rs_synth_prepare( // out
    rs_synth_prepared *out,
    // in
    const rs_synth_vehicle *vehicles, const rs_synth_obj_spec *obj, int N, rs_err *err);
void rs_synth_prepared_free(rs_synth_prepared *p); // NULL-safe; zeroes *p

// The same, with procedural vehicle i built at level of detail lod[i] (an rs_synth_lod,
// rs_synth_fleet_build_lod); lod may be NULL (every vehicle in full detail).
rs_status rs_synth_prepare_lod( // out
    rs_synth_prepared *out,
    // in
    const rs_synth_vehicle *vehicles, const rs_synth_obj_spec *obj, int N, const uint8_t *lod, rs_err *err);

#ifdef __cplusplus
}
#endif
