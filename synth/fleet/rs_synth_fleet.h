// rs_synth_fleet.h -- the vehicle fleet: procedural vehicles and user OBJ models as triangle
// meshes, written as POV-Ray mesh2 declarations. docs/fleet.md describes the shapes, the class
// ranges and the colour mix.
//
// Frames. A mesh is held in the vehicle frame of synth/fleet/rs_synth_vehicle.h (x_v forward, y_v left, z_v
// up, origin at the footprint centre on the ground, metres). It is WRITTEN in POV-Ray axes as
// the vehicle would stand at the ENU origin with yaw 0 (facing north):
//     x_pov = -y_v   (east),   y_pov = z_v   (up),   z_pov = x_v   (north)
// This is the vehicle->ENU rotation at yaw 0 followed by the fixed ENU->POV-Ray map <e, u, n>
// (docs/conventions.md), so the declared object is not mirrored. A scene places an instance with
//     object { NAME rotate <0, yaw_deg, 0> translate <e_m, up_m, n_m> }
// (rs_synth_fleet_write_placement): POV-Ray's rotate about y by +a maps north (0,0,1) to
// (sin a, 0, cos a), i.e. a compass heading a clockwise from north, as yaw_deg is defined.
#pragma once
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "core/rs_image.h"
#include "core/rs_status.h"
#include "synth/fleet/rs_synth_vehicle.h"

#ifdef __cplusplus
extern "C" {
#endif

// Surface parts; each has its own texture in a textured declaration.
typedef enum {
    RS_SYNTH_PART_PAINT = 0, // body panels, the vehicle's colour
    RS_SYNTH_PART_GLASS,     // glazing: dark, reflective
    RS_SYNTH_PART_HEADLIGHT, // front lights
    RS_SYNTH_PART_TAILLIGHT, // rear lights
    RS_SYNTH_PART_TYRE,      // tyres, black rubber
    RS_SYNTH_PART_RIM,       // wheel rims, grey metal
    RS_SYNTH_PART_TRIM,      // bumpers, grille, chassis, wheel-arch liners: dark plastic
    RS_SYNTH_PART_PLATE,     // number plates: white retro-reflective
    RS_SYNTH_PART_CHROME,    // grille bars, exhausts, handlebars: polished metal
    RS_SYNTH_PART_RIDER,     // a two-wheeler's rider: clothes
    RS_SYNTH_NPARTS
} rs_synth_part;

// A user model's material (rs_synth_obj_load), as assimp reads it from an OBJ's MTL (Kd, Ks, Ns,
// d, map_Kd) or a glTF 2.0 material (baseColorFactor, baseColorTexture, metallicFactor,
// roughnessFactor, alpha), written as a POV-Ray texture by rs_synth_fleet_write_parts /
// _instance (docs/fleet.md, "User models"). Colours are linear RGB (glTF's are by definition;
// an MTL's Kd is taken as linear too, as assimp hands it over).
typedef struct {
    char name[64];    // the model's material name, for matching paint_materials only (never
                      //   written into a scene)
    double rgb[3];    // diffuse / base colour, linear [0,1]; multiplies nothing when textured
    double opacity;   // 1 opaque .. 0 clear (MTL d, glTF alpha): < 1 is glass (Fresnel reflection)
    double specular;  // highlight strength [0,1] (MTL: mean of Ks; glTF: from roughness)
    double roughness; // POV-Ray highlight roughness (0, 1]: 1 / Ns (MTL) or from glTF roughness
    double metallic;  // [0,1]: glTF metallicFactor (MTL: 0)
    int texture;      // index into the mesh's textures (the diffuse / base colour image), or -1
    bool paint;       // painted with the vehicle's look (paint_materials) instead of the above
} rs_synth_material;

// A triangle mesh in the vehicle frame. Triangles are wound counter-clockwise seen from outside
// (the geometric normal (b-a)x(c-a) points outward). vn is optional: unit normals for smooth
// shading (NULL = flat shading), indexed like v when tri_n is NULL (user models), else by tri_n:
// corner k of triangle t has the normal vn[tri_n[t][k]] (procedural vehicles: smooth across
// round surfaces, sharp at creases; rs_synth_fleet_build). A user model also has materials
// (material != NULL: each triangle's, an index into materials), texture coordinates (uv,
// indexed like v) and its texture images. Owned arrays; rs_synth_mesh_free.
typedef struct {
    int Nv;          // number of vertices
    double (*v)[3];  // (Nv,3) vertices, vehicle frame, metres
    double (*vn)[3]; // (Nv,3) or (Nn,3) unit normals, or NULL
    int Ntri;        // number of triangles
    int (*tri)[3];   // (Ntri,3) vertex indices
    uint8_t *part;   // (Ntri,) rs_synth_part of each triangle
    int Nn;          // number of normals when tri_n != NULL
    int (*tri_n)[3]; // (Ntri,3) normal indices, or NULL (then vn is indexed like v)
    double (*uv)[2]; // (Nv,2) texture coordinates (u right, v up the image), or NULL
    int Nmaterials;
    rs_synth_material *materials; // (Nmaterials,) or NULL (procedural: the parts' textures)
    uint16_t *material;           // (Ntri,) material of each triangle, or NULL
    int Ntextures;
    rs_image *textures; // (Ntextures,) the texture images as read (RGB or RGBA, sRGB-encoded)
    char **texture_png; // (Ntextures,) owned, or NULL: the images already written as PNG
                        //   (rs_synth_fleet_cache_textures), linked rather than encoded again
} rs_synth_mesh;

void rs_synth_mesh_free(rs_synth_mesh *mesh); // NULL-safe; leaves *mesh zeroed

// A deep copy of `in` (every array, materials and texture images). out: *out (owned;
// rs_synth_mesh_free), zeroed on failure. Returns RS_ERR_NOMEM.
rs_status rs_synth_mesh_copy(rs_synth_mesh *out, const rs_synth_mesh *in, rs_err *err);

// Axis-aligned bounds of the mesh's vertices in the vehicle frame.
// out: lo, hi (3,) metres. An empty mesh gives lo = hi = 0.
void rs_synth_mesh_bounds(double lo[3], double hi[3], const rs_synth_mesh *mesh);

// Class names as used in vehicle files and labels: "sedan", "hatchback", "suv", "pickup", "van",
// "bus", "box_truck", "articulated_truck", "motorcycle", "bicycle" ("model" for
// RS_SYNTH_USER_MODEL). NULL if unknown.
const char *rs_synth_class_name(rs_synth_class cls);
// Inverse of rs_synth_class_name (exact, lower case). RS_ERR_NOT_FOUND names the valid ones.
rs_status rs_synth_class_from_name( // out
    rs_synth_class *cls,
    // in
    const char *name, rs_err *err);

// Realistic dimensions of a class, metres (docs/fleet.md gives the sources): a drawn dimension is
// normal with the given mean and standard deviation, truncated to [min, max] (redrawn).
typedef struct {
    double length_m[2], width_m[2], height_m[2]; // [min, max]
    double mean_m[3], sd_m[3];                   // length, width, height: before truncation
} rs_synth_class_range;
// Returns RS_ERR_INVALID for a class out of range (including RS_SYNTH_USER_MODEL).
rs_status rs_synth_class_range_get(rs_synth_class_range *out, rs_synth_class cls, rs_err *err);

// The default mix (docs/traffic.md, "Class mix", gives the reasoning and the sources): the two-
// wheelers at their shares of urban road traffic in Great Britain (DfT road traffic estimates:
// motorcycle 0.008, bicycle 0.017), the motor vehicles at an assumed mix scaled by 0.975 (sedan
// 0.234, hatchback 0.2145, suv 0.2925, pickup 0.02925, van 0.0975, bus 0.0195, box_truck
// 0.0585, articulated_truck 0.02925). The weights sum to 1.
void rs_synth_class_mix_default(rs_synth_class_mix *mix);

// Parses "class=weight,class=weight,...": the classes named get these weights, the others 0.
// RS_ERR_USAGE naming the item at fault (unknown class, bad or negative weight, all zero).
rs_status rs_synth_class_mix_parse( // out
    rs_synth_class_mix *mix,
    // in
    const char *text, rs_err *err);

// The class at u in [0, 1) of the mix's cumulative weights (weights normalised by their sum;
// classes of weight 0 are never returned). rs_synth_fleet_random and the traffic draw with it.
rs_synth_class rs_synth_class_mix_draw(const rs_synth_class_mix *mix, double u);

// Fills what a procedural vehicle left to chance, deterministically from in->variant: length,
// width and height when 0 (truncated normal of the class, rs_synth_class_range), paint when
// rgb[0] < 0 (drawn from the
// colour mix of docs/fleet.md, linear RGB). Everything else is copied. The same variant always
// gives the same vehicle; a given dimension or colour does not change the others.
// User models (RS_SYNTH_USER_MODEL): only the paint is filled; their box comes from the mesh.
// Returns RS_ERR_INVALID for an unknown class, a negative or non-finite dimension, or a given
// dimension outside [0.5, 30] m.
rs_status rs_synth_fleet_resolve( // out
    rs_synth_vehicle *out,
    // in
    const rs_synth_vehicle *in, rs_err *err);

// A random procedural vehicle: the class drawn from the default mix (rs_synth_class_mix_default), then
// resolved (rs_synth_fleet_resolve) with variant = seed; position and yaw are 0. Deterministic.
rs_status rs_synth_fleet_random( // out
    rs_synth_vehicle *out,
    // in
    uint64_t seed, rs_err *err);

// Builds the procedural mesh of a RESOLVED vehicle (rs_synth_fleet_resolve): a body lofted from
// a class side profile and plan shape (shape details drawn from v->variant), wheels, glazing,
// lights. The mesh's bounds equal x in [-L/2, L/2], y in [-W/2, W/2], z in [0, H] to 1e-9 m;
// every closed part is consistently wound outward; no triangle has zero area.
// out: *mesh (owned; rs_synth_mesh_free). Returns RS_ERR_INVALID for unresolved dimensions or a
// user model, RS_ERR_NOMEM.
rs_status rs_synth_fleet_build( // out
    rs_synth_mesh *mesh,
    // in
    const rs_synth_vehicle *v, rs_err *err);

// Levels of detail of a procedural vehicle (rs_synth_fleet_build_lod): uniform stations along
// the body and sides of a wheel. The side profile's control points are always stations, so the
// roof line and the bounds stay exact at every level; at every level the stations of a straight
// run of the body are dropped (RS_SYNTH_LOFT_TOLERANCE_M).
typedef enum {
    RS_SYNTH_LOD_FULL = 0,   // 56 stations, 20-gon wheels (a car: 3,000 - 3,500 triangles)
    RS_SYNTH_LOD_MEDIUM = 1, // 20 stations, 12-gon wheels: for vehicles up to ~120 px tall, two
                             //   thirds of the triangles (and of the scene text POV-Ray parses)
    RS_SYNTH_LOD_COARSE = 2, // 8 stations, octagonal wheels: vehicles a few pixels tall (and the
                             //   shadow pass), under half of the triangles
} rs_synth_lod;

// The same at a level of detail (docs/fleet.md, `roadside bench synth`).
rs_status rs_synth_fleet_build_lod( // out
    rs_synth_mesh *mesh,
    // in
    const rs_synth_vehicle *v, rs_synth_lod lod, rs_err *err);

// How far (m) a body's section may stray from the straight line between the stations kept on
// either side of it for the station to be dropped (rs_synth_fleet_build_lod): the middle of a
// body is ruled (its sections change linearly between the side profile's points), so one band
// spans it where the uniform stations cut it into many. 0.5 mm is 0.1 px at 5 m with a 1000 px
// focal length; a third to a half of a car's triangles go.
#define RS_SYNTH_LOFT_TOLERANCE_M 0.0005

// The same with the loft's tolerance given: loft_tolerance_m < 0 keeps every station (the
// bodies exactly as the uniform stations and the profile's points cut them).
rs_status rs_synth_fleet_build_loft( // out
    rs_synth_mesh *mesh,
    // in
    const rs_synth_vehicle *v, rs_synth_lod lod, double loft_tolerance_m, rs_err *err);

// How a user model is declared (a vehicles file's "model" entry, a --models library's entry;
// docs/povray.md, docs/fleet.md): its size and which of its axes point forward and up.
typedef struct {
    const char *path;                   // model file: OBJ (+ MTL + images), glTF 2.0 (.gltf, .glb)
    double scale;                       // metres per model unit, > 0; ignored when length_m > 0
    double length_m;                    // > 0: the model is scaled so that its box's length along forward is
                                        //   this (metres); 0: scale applies
    const char *forward;                // model axis pointing to the vehicle's front: "+x" "-x" "+y" "-y" "+z" "-z"
    const char *up;                     // model axis pointing up (must differ from forward's axis)
    const char *const *paint_materials; // (Npaint,) names of the materials painted with the
                                        //   vehicle's colour; may be NULL
    int Npaint;
    const rs_synth_mesh *loaded; // may be NULL; else the model as rs_synth_obj_load read it with
                                 //   this spec (a run's library, loaded once): rs_synth_prepare
                                 //   copies it instead of reading the file again
} rs_synth_obj_spec;

// Reads a user model with the Open Asset Import Library (assimp 5.2: OBJ with its MTL, glTF 2.0
// .gltf/.glb, and whatever else assimp reads), triangulated, vertices joined, the node
// transforms applied, points and lines dropped; maps it into the vehicle frame (scale or
// length, axes) and moves it so that its box's footprint centre is at the origin and its lowest
// point at z = 0. Zero-area triangles are dropped. All triangles are PAINT parts; each keeps
// its material (rs_synth_material) and the mesh its texture coordinates and images: a
// material's diffuse / base colour image (a file beside the model, or embedded in a glTF) is
// read with rs_image_read. A model without materials of its own (an OBJ without MTL: assimp's
// default material only) is painted whole, as are the materials named in paint_materials.
// Vertex normals are kept (mapped and normalised) when every mesh has them, else vn = NULL.
// Errors name the file: RS_ERR_IO (missing model; a texture image missing or unreadable,
// naming the material and the image), RS_ERR_PARSE (assimp's message: "model.obj: assimp:
// ..."), RS_ERR_INVALID (bad spec, no faces, degenerate triangles only, more than 65535
// materials), RS_ERR_NOMEM.
rs_status rs_synth_obj_load( // out
    rs_synth_mesh *mesh,
    // in
    const rs_synth_obj_spec *spec, rs_err *err);

// Writes the mesh's texture images as 8-bit PNG files DIR/rs_tex_<PREFIX>_<k>.png (k = 0 ..
// Ntextures-1, each atomically; hard links of mesh->texture_png's files when set): the only images a scene's mesh refers to, by these generated
// bare names, in the folder povray runs in (docs/povray.md, "Confinement"). prefix: the
// identifier the mesh's parts are declared under (rs_synth_fleet_write_parts / _instance), which
// names the images the instance's textures read. Returns RS_ERR_INVALID (prefix), RS_ERR_IO,
// RS_ERR_NOMEM.
rs_status rs_synth_fleet_write_textures(const char *dir, const char *prefix, const rs_synth_mesh *mesh, rs_err *err);

// Writes the mesh's texture images once as PNG files into dir (rs_tex_<prefix>_<k>.png, as
// rs_synth_fleet_write_textures names them) and records their paths in mesh->texture_png, so that
// rs_synth_fleet_write_textures then hard-links them (a copy where linking fails) instead of
// encoding each image again: a run's model library (synth/dataset) writes them once for all its
// images. dir must exist. Returns RS_ERR_IO / RS_ERR_NOMEM.
rs_status rs_synth_fleet_cache_textures(rs_synth_mesh *mesh, const char *dir, const char *prefix, rs_err *err);

// The file name of texture k of the mesh declared under prefix: "rs_tex_<prefix>_<k>.png"
// (rs_synth_fleet_write_textures writes it, the instance's textures read it). out: (n,) text.
void rs_synth_fleet_texture_name(char *out, size_t n, const char *prefix, int k);

// Declaration styles.
typedef enum {
    RS_SYNTH_DECLARE_TEXTURED = 0, // one mesh2 per part in a union, each with its texture; paint
                                   // from paint_rgb (linear RGB)
    RS_SYNTH_DECLARE_BARE          // one mesh2, no texture: the instance's texture applies to all
                                   // of it (object-ID pass, or one user model painted per use)
} rs_synth_declare_style;

// Writes "#declare NAME = union { mesh2 {...} ... }" (TEXTURED) or "#declare NAME = mesh2 {...}"
// (BARE) for `mesh` in POV-Ray axes (see the top of this file), vertices to 1e-6 m. Textures
// use only built-in POV-Ray keywords (no include files needed).
// in: name: a POV-Ray identifier chosen by the caller: [A-Za-z_][A-Za-z0-9_]*, at most 40
//     characters, not starting with a lower-case letter (POV-Ray reserves those for keywords);
//     anything else is RS_ERR_INVALID (input strings can never reach the scene this way).
//     paint_rgb: (3,) linear RGB in [0,1]; ignored (may be NULL) for BARE.
// Returns RS_ERR_IO when writing fails.
rs_status rs_synth_fleet_write_declare(FILE *f,
                                       // in
                                       const char *name, const rs_synth_mesh *mesh, rs_synth_declare_style style,
                                       const double paint_rgb[3], rs_err *err);

// How a vehicle's surfaces look, drawn from its variant (docs/fleet.md, "Materials").
typedef struct {
    double paint_rgb[3]; // linear RGB in [0,1]: the base coat under the clear coat
    double metallic;     // 0 solid .. 1 metallic flake: highlights tinted by the paint
    double dirt;         // 0 clean .. 1 dirty: a grey-brown film, densest on the sills
    // issue 40, conditions (synth/backdrop/rs_synth_condition.h; docs/conditions.md):
    bool lights_on; // head- and tail lights glowing (emission: RS_SYNTH_HEADLIGHT_EMISSION, ..)
    double snow;    // 0 none .. 1 full: a white layer on the paint where the surface faces up
} rs_synth_look;

// The light parts' glow when lights_on, linear radiance in the scene's units (a white surface
// under a sun at the zenith is 1): headlights far brighter than anything lit (a lamp's lens is
// about 1e4 cd/m^2 against an asphalt road's 1..2 at night), tail lights red.
#define RS_SYNTH_HEADLIGHT_EMISSION 4.0
#define RS_SYNTH_TAILLIGHT_EMISSION 0.8

// The look of a RESOLVED vehicle (paint = v->rgb; metallic and dirt from v->variant, the
// metallic share depending on the paint's colour family). Deterministic.
void rs_synth_fleet_look(rs_synth_look *look, const rs_synth_vehicle *v);

// As rs_synth_fleet_write_declare, TEXTURED with a full look: car paint with a clear coat
// (Fresnel reflection, ior 1.5, conserve_energy), reflective glass, chrome, plastic trims, dirt.
// look may be NULL for BARE.
rs_status rs_synth_fleet_write_declare_look(FILE *f,
                                            // in
                                            const char *name, const rs_synth_mesh *mesh, rs_synth_declare_style style,
                                            const rs_synth_look *look, rs_err *err);
// Writes "#declare NAME = mesh2 {...}": every triangle of `mesh` in ONE bare mesh2, compact
// (vertices to 1e-5 m), without normals: the geometry of the shadow pass, where neither the
// parts' textures nor smooth shading matter and one mesh2 traces faster than a union of one per
// part (issue 18's cost, docs/fleet.md). NAME as rs_synth_fleet_write_declare's.
// Returns RS_ERR_INVALID (name, empty mesh), RS_ERR_NOMEM, RS_ERR_IO.
rs_status rs_synth_fleet_write_merged(FILE *f, const char *name, const rs_synth_mesh *mesh, rs_err *err);

// The scene's shared geometry (issue 18's cost): writes "#declare PREFIX_k = mesh2 {...}" for each
// part k (rs_synth_part; a user model: material k, with its texture coordinates) the mesh uses, without texture, in POV-Ray axes, compact (vertices to
// 1e-5 m, one line per array) and with smooth normals on the body's paint and glass only (the
// other parts are a few pixels each and are flat-shaded). Written once per scene, before the
// passes; each pass then declares its vehicle with rs_synth_fleet_write_instance, which costs no
// geometry text. prefix: an identifier as for rs_synth_fleet_write_declare, at most 37
// characters (RS_ERR_INVALID otherwise). Returns RS_ERR_IO when writing fails.
rs_status rs_synth_fleet_write_parts(FILE *f,
                                     // in
                                     const char *prefix, const rs_synth_mesh *mesh, rs_err *err);

// Writes "#declare NAME = union { object { PREFIX_k TEXTURE } ... }" over the parts that
// rs_synth_fleet_write_parts declared for the same mesh: TEXTURED gives each part its texture
// as rs_synth_fleet_write_declare_look does (look required), BARE gives none, so that the
// instance's texture applies to all of it ("#declare NAME = object { PREFIX_k }" when the mesh
// has one part). The same geometry as rs_synth_fleet_write_declare_look's, so the same pixels.
// A user model (mesh->materials) has one group k per material instead of per part, each
// TEXTURED with its material (image textures read from rs_tex_<PREFIX>_<j>.png,
// rs_synth_fleet_write_textures); its paint materials get look's paint, or, with look NULL,
// no texture: the placed object's texture then applies to them only.
rs_status rs_synth_fleet_write_instance(FILE *f,
                                        // in
                                        const char *name, const char *prefix, const rs_synth_mesh *mesh,
                                        rs_synth_declare_style style, const rs_synth_look *look, rs_err *err);

// Writes " rotate <0, YAW, 0> translate <E, UP, N>" (a leading space, no newline): the
// placement of a declared vehicle whose footprint centre is at (v->e_m, v->n_m, up_m) ENU.
rs_status rs_synth_fleet_write_placement(FILE *f,
                                         // in
                                         const rs_synth_vehicle *v, double up_m, rs_err *err);

// Maps a vehicle-frame point into site ENU for a vehicle whose footprint centre is at ground
// height up_m: p_enu = (e, n, up) + x_v forward_enu + y_v left_enu + z_v (0,0,1).
// out: p_enu_m (3,); in: p_v_m (3,)
void rs_synth_vehicle_to_enu(double p_enu_m[3], const rs_synth_vehicle *v, double up_m, const double p_v_m[3]);

#ifdef __cplusplus
}
#endif
