// rs_synth_vehicle.h -- the one vehicle type of the synthesis, from the traffic to the labels: a
// vehicle placed in a site, its box on the ground.
//
// Vehicle frame (docs/conventions.md, "Vehicles"): origin at the centre of the vehicle's
// footprint on the ground, x_v forward, y_v left, z_v up, metres. The vehicle's bounding box is
// x_v in [-length/2, length/2], y_v in [-width/2, width/2], z_v in [0, height].
// Placement in the site ENU frame: the footprint centre at (e_m, n_m) on the site's ground plane
// (its up coordinate is the ground plane's height there), the forward axis horizontal with
// compass heading yaw_deg, clockwise from north: forward_enu = (sin yaw, cos yaw, 0),
// left_enu = (-cos yaw, sin yaw, 0). (The ground is treated as level under one vehicle: a
// sloped ground plane lifts each vehicle to its height at (e, n) without tilting it.)
#pragma once
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

// Vehicle classes of the procedural fleet (synth/fleet/rs_synth_fleet.h gives their dimension ranges).
typedef enum {
    RS_SYNTH_SEDAN = 0,
    RS_SYNTH_HATCHBACK,
    RS_SYNTH_SUV,
    RS_SYNTH_PICKUP,
    RS_SYNTH_VAN,
    RS_SYNTH_BUS,
    RS_SYNTH_BOX_TRUCK,
    RS_SYNTH_ARTICULATED_TRUCK,
    RS_SYNTH_MOTORCYCLE, // with its rider (the box holds both)
    RS_SYNTH_BICYCLE,    // with its rider
    RS_SYNTH_NCLASSES,
    RS_SYNTH_USER_MODEL = 100 // a model given by the user (model_path; labelled as model_cls)
} rs_synth_class;

// Class mix: relative weights of the classes (any non-negative numbers, at least one > 0);
// the default, parsing and drawing: synth/fleet/rs_synth_fleet.h.
typedef struct {
    double weight[RS_SYNTH_NCLASSES];
} rs_synth_class_mix;

// One vehicle: the one type the synthesis carries from the traffic (built-in, SUMO or a vehicles
// file) through the scene and the render to the labels. model_path is borrowed (the caller owns
// it); everything else is held by value. rs_synth_vehicle_init gives the defaults.
typedef struct {
    rs_synth_class cls;
    const char *model_path;             // model file when cls == RS_SYNTH_USER_MODEL, else NULL
    char id[48];                        // free-form label: "v12" (built-in traffic), SUMO's vehicle
                                        //   id, a vehicles file's "id" (truncated to 47 bytes; never
                                        //   trusted in scene text: rs_synth_safe_text)
    double e_m, n_m;                    // footprint centre, site ENU, metres
    double yaw_deg;                     // compass heading of the forward axis, clockwise from north
    double length_m, width_m, height_m; // bounding box; 0 = drawn from the class's ranges
    double rgb[3];                      // paint in linear [0,1]; negative = drawn from the colour mix
    double speed_mps;                   // speed (built-in traffic: the one its gap was drawn for;
                                        //   SUMO: FCD speed; a vehicles file: 0)
    int lane;                           // index of the lane it was placed on, -1 if unknown
    uint64_t variant;                   // seeds the procedural shape and any drawn value
    rs_synth_class model_cls;           // a user model's label class (its description's "class"),
                                        //   RS_SYNTH_USER_MODEL when it gives none; else unused
} rs_synth_vehicle;

// A vehicle of class cls with nothing else known: no model, empty id, dimensions and paint to be
// drawn (0 and -1), speed 0, lane -1, variant 0, model_cls RS_SYNTH_USER_MODEL.
rs_synth_vehicle rs_synth_vehicle_init(rs_synth_class cls);

// The class a vehicle's label carries: cls, or a user model's model_cls.
rs_synth_class rs_synth_vehicle_label_class(const rs_synth_vehicle *v);

// ---- the vehicle on the ground ----

// The 8 corners of vehicle v's bounding box in ENU, metres, on the ground plane
// n . p = offset: corner k has x_v = +-L/2 (bit 0: +), y_v = +-W/2 (bit 1: +), z_v = 0 or H
// (bit 2: H). Requires v's length/width/height > 0 (resolve drawn dimensions first).
void rs_synth_vehicle_corners_enu( // out
    double corners_enu_m[8][3],
    // in
    const rs_synth_vehicle *v, const double ground_normal_enu[3], double ground_offset_m);

// Up coordinate of the ground plane n . p = offset at (e, n). n[2] must be non-zero.
double rs_synth_ground_up_m(const double ground_normal_enu[3], double ground_offset_m, double e_m, double n_m);

// ---- text from input files ----

// Copies at most n-1 characters of s (NULL: "") into out, keeping [A-Za-z0-9 _.:-] and replacing
// anything else by '_': the only form in which an input string (a vehicle's id, a time given on
// the command line) ever reaches a POV-Ray scene (inside a comment) or an error message.
void rs_synth_safe_text(char *out, size_t n, const char *s);

#ifdef __cplusplus
}
#endif
