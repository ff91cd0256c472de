// rs_report_export.c -- `roadside export`: the site's calibration as GIS layers and the ground
// uncertainty map as a GeoTIFF, through GDAL/OGR's C API (see rs_report_export.h).
#include "report/rs_report_export.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <gdal.h>
#include <gdalwarper.h>
#include <ogr_api.h>
#include <ogr_srs_api.h>

#include "core/rs_io.h"
#include "core/rs_pose.h"
#include "geo/rs_geo.h"
#include "geo/rs_geo_raster.h"
#include "report/internal/rs_report_draw.h"
#include "report/internal/rs_report_export_style.h"

void rs_report_export_options_default(rs_report_export_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->range_m = 100;
    rs_audit_options_default(&opt->audit_options);
}

// ---- GDAL errors as rs_err ----

static rs_status gdal_fail(rs_err *err, const char *path, const char *what)
{
    const char *msg = CPLGetLastErrorMsg();
    return rs_err_set(err, RS_ERR_EXTERNAL, "%s: %s%s%s", path, what, msg && *msg ? ": " : "", msg ? msg : "");
}

// ---- coordinates ----

typedef struct {
    const rs_site *site;
    OGRSpatialReferenceH srs;       // the layers' CRS (axis order: x east / longitude first)
    OGRCoordinateTransformationH t; // WGS84 (lon, lat) -> srs; NULL: srs is WGS84 itself
} frame;

// ENU (E, N, U) -> (x, y, z) of the target CRS; z is the ellipsoidal height.
static bool to_crs(const frame *f, const double p_enu_m[3], double xyz[3])
{
    double llh[3];
    if (rs_geo_enu_to_llh(llh, &f->site->origin, p_enu_m, 1, NULL) != RS_OK) return false;
    xyz[0] = llh[1], xyz[1] = llh[0], xyz[2] = llh[2];
    if (f->t && !OCTTransform(f->t, 1, &xyz[0], &xyz[1], NULL)) return false;
    return isfinite(xyz[0]) && isfinite(xyz[1]);
}

static double ground_up(const rs_site *site, double e, double n)
{
    const double *nn = site->ground_normal_enu;
    return (site->ground_offset_m - nn[0] * e - nn[1] * n) / nn[2];
}

// ---- layers ----

typedef enum { L_CAMERAS, L_FOOTPRINTS, L_LANDMARKS, L_PICKS, L_LANES, NLAYERS } layer_kind;
static const char *const layer_names[NLAYERS] = {"cameras", "footprints", "landmarks", "picks", "lanes"};
// Each layer's description (GeoPackage: gpkg_contents.description; what a GIS shows for it).
static const char *const layer_descriptions[NLAYERS] = {
    "roadside cameras: position (site ENU and WGS84), height above the ground, heading, pitch, roll and their "
    "1-sigma from roadside calib; verdict of roadside audit against the need (pass / FAIL / not audited)",
    "The ground each camera sees within range_m, on the site's ground plane through the full lens model; "
    "coloured by the camera's verdict",
    "One point per surveyed landmark seen by a camera: surveyed position and sigmas, how many cameras picked it, "
    "how many kept it as an inlier, the worst leave-one-out ground error (metres) and the audit's flag",
    "One point per camera and pick, at the landmark's surveyed position: residual of the surveyed position "
    "reprojected through the calibration (px), normalised residual, inlier, leave-one-out errors, predicted "
    "1-sigma ground error (metres)",
    "Lane lines of SITE/lanes.geojson as the report draws them (lane edges, junction connectors)"};

typedef struct {
    const char *name;
    OGRFieldType type;
    unsigned layers; // bit k: the field is in layer k
} field_def;

enum {
    F_CAM = 1u << L_CAMERAS,
    F_FOOT = 1u << L_FOOTPRINTS,
    F_LM = 1u << L_LANDMARKS,
    F_PICK = 1u << L_PICKS,
    F_LANE = 1u << L_LANES,
    F_ALL = (1u << NLAYERS) - 1
};
static const field_def fields[] = {
    {"layer", OFTString, F_ALL},
    {"camera", OFTString, F_CAM | F_FOOT | F_PICK},
    {"east_m", OFTReal, F_CAM | F_LM},
    {"north_m", OFTReal, F_CAM | F_LM},
    {"up_m", OFTReal, F_CAM | F_LM},
    {"lat_deg", OFTReal, F_CAM},
    {"lon_deg", OFTReal, F_CAM},
    {"h_m", OFTReal, F_CAM},
    {"above_ground_m", OFTReal, F_CAM},
    {"heading_deg", OFTReal, F_CAM},
    {"pitch_deg", OFTReal, F_CAM},
    {"roll_deg", OFTReal, F_CAM},
    {"sigma_east_m", OFTReal, F_CAM},
    {"sigma_north_m", OFTReal, F_CAM},
    {"sigma_up_m", OFTReal, F_CAM},
    {"sigma_heading_deg", OFTReal, F_CAM},
    {"sigma_pitch_deg", OFTReal, F_CAM},
    {"sigma_roll_deg", OFTReal, F_CAM},
    {"rms_surveyed_px", OFTReal, F_CAM},
    {"verdict", OFTString, F_CAM | F_FOOT},
    {"need_ground_m", OFTReal, F_CAM},
    {"ground_sigma_median_m", OFTReal, F_CAM},
    {"ground_sigma_p90_m", OFTReal, F_CAM},
    {"loo_median_m", OFTReal, F_CAM},
    {"verdict_text", OFTString, F_CAM},
    {"enu_origin", OFTString, F_CAM},
    {"range_m", OFTReal, F_FOOT},
    {"landmark", OFTString, F_LM | F_PICK},
    {"sigma_h_m", OFTReal, F_LM},
    {"sigma_v_m", OFTReal, F_LM},
    {"cameras", OFTString, F_LM},
    {"n_picks", OFTInteger, F_LM},
    {"n_inliers", OFTInteger, F_LM},
    {"residual_u_px", OFTReal, F_PICK},
    {"residual_v_px", OFTReal, F_PICK},
    {"residual_px", OFTReal, F_PICK},
    {"normalised", OFTReal, F_PICK},
    {"inlier", OFTInteger, F_PICK},
    {"loo_ground_error_m", OFTReal, F_LM | F_PICK}, // landmarks: the worst over its picks
    {"loo_error_px", OFTReal, F_PICK},
    {"sigma_ground_m", OFTReal, F_PICK},
    {"flag", OFTString, F_LM | F_PICK},
    {"junction", OFTInteger, F_LANE},
};
#define NFIELDS (int)(sizeof fields / sizeof fields[0])

typedef struct {
    GDALDatasetH ds;
    OGRLayerH layers[NLAYERS]; // GeoJSON: the same layer five times
    const char *path;          // the final name, for messages
} vector_out;

static rs_status create_layers(vector_out *v, const frame *f, bool single, rs_err *err)
{
    static const OGRwkbGeometryType geom[NLAYERS] = {wkbPoint25D, wkbPolygon, wkbPoint25D, wkbPoint25D,
                                                     wkbLineString25D};
    for (int k = 0; k < NLAYERS; k++) {
        if (single && k > 0) {
            v->layers[k] = v->layers[0];
            continue;
        }
        char **lco = CSLSetNameValue(NULL, "DESCRIPTION",
                                     single ? "roadside export: cameras, footprints, landmarks, picks and lanes (the "
                                              "property 'layer' says which)"
                                            : layer_descriptions[k]);
        v->layers[k] = GDALDatasetCreateLayer(v->ds, single ? "roadside" : layer_names[k], f->srs,
                                              single ? wkbUnknown : geom[k], lco);
        CSLDestroy(lco);
        if (!v->layers[k]) return gdal_fail(err, v->path, "cannot create a layer");
        for (int i = 0; i < NFIELDS; i++) {
            if (!single && !(fields[i].layers & (1u << k))) continue;
            OGRFieldDefnH fd = OGR_Fld_Create(fields[i].name, fields[i].type);
            OGRErr e = OGR_L_CreateField(v->layers[k], fd, TRUE);
            OGR_Fld_Destroy(fd);
            if (e != OGRERR_NONE) return gdal_fail(err, v->path, "cannot create a field");
        }
    }
    return RS_OK;
}

static void set_real(OGRFeatureH ft, const char *name, double x)
{
    int i = OGR_F_GetFieldIndex(ft, name);
    if (i < 0) return;
    if (isfinite(x))
        OGR_F_SetFieldDouble(ft, i, x);
    else
        OGR_F_SetFieldNull(ft, i);
}

static void set_str(OGRFeatureH ft, const char *name, const char *s)
{
    int i = OGR_F_GetFieldIndex(ft, name);
    if (i >= 0) OGR_F_SetFieldString(ft, i, s ? s : "");
}

static void set_int(OGRFeatureH ft, const char *name, int x)
{
    int i = OGR_F_GetFieldIndex(ft, name);
    if (i >= 0) OGR_F_SetFieldInteger(ft, i, x);
}

// A new feature of layer k with its "layer" and "camera" fields.
static OGRFeatureH feature(const vector_out *v, layer_kind k, const char *camera)
{
    OGRFeatureH ft = OGR_F_Create(OGR_L_GetLayerDefn(v->layers[k]));
    if (!ft) return NULL;
    set_str(ft, "layer", layer_names[k]);
    if (camera) set_str(ft, "camera", camera);
    return ft;
}

// Writes the feature into layer k (taking the geometry g) and destroys it.
static rs_status put(vector_out *v, layer_kind k, OGRFeatureH ft, OGRGeometryH g, rs_err *err)
{
    if (!ft) {
        OGR_G_DestroyGeometry(g);
        return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", v->path);
    }
    if (g) OGR_F_SetGeometryDirectly(ft, g);
    OGRErr e = OGR_L_CreateFeature(v->layers[k], ft);
    OGR_F_Destroy(ft);
    return e == OGRERR_NONE ? RS_OK : gdal_fail(err, v->path, "cannot write a feature");
}

static OGRGeometryH point(const frame *f, const double p_enu_m[3])
{
    double xyz[3];
    if (!to_crs(f, p_enu_m, xyz)) return NULL;
    OGRGeometryH g = OGR_G_CreateGeometry(wkbPoint25D);
    if (g) OGR_G_SetPoint(g, 0, xyz[0], xyz[1], xyz[2]);
    return g;
}

static rs_status write_cameras(vector_out *v, const frame *f, const struct rs_report_ctx *rep,
                               rs_report_export_summary *sum, rs_err *err)
{
    const rs_site *site = rep->site;
    char origin[128];
    snprintf(origin, sizeof origin, "%.9f, %.9f, %.4f", site->origin.lat_deg, site->origin.lon_deg, site->origin.h_m);
    rs_status st = RS_OK;
    for (int c = 0; c < rep->Ncameras && !st; c++) {
        const rs_report_camera *cam = &rep->cameras[c];
        const char *id = site->cameras[cam->icam].id;
        const double *p = cam->position_enu_m, *s = cam->sigma_position_enu_m;
        OGRFeatureH ft = feature(v, L_CAMERAS, id);
        if (ft) {
            static const char *const names[] = {"east_m",
                                                "north_m",
                                                "up_m",
                                                "lat_deg",
                                                "lon_deg",
                                                "h_m",
                                                "heading_deg",
                                                "pitch_deg",
                                                "roll_deg",
                                                "sigma_east_m",
                                                "sigma_north_m",
                                                "sigma_up_m",
                                                "sigma_heading_deg",
                                                "sigma_pitch_deg",
                                                "sigma_roll_deg"};
            const double vals[] = {p[0],
                                   p[1],
                                   p[2],
                                   cam->position_llh[0],
                                   cam->position_llh[1],
                                   cam->position_llh[2],
                                   cam->yaw_pitch_roll_deg[0],
                                   cam->yaw_pitch_roll_deg[1],
                                   cam->yaw_pitch_roll_deg[2],
                                   s[0],
                                   s[1],
                                   s[2],
                                   cam->sigma_yaw_pitch_roll_deg[0],
                                   cam->sigma_yaw_pitch_roll_deg[1],
                                   cam->sigma_yaw_pitch_roll_deg[2]};
            for (size_t k = 0; k < sizeof vals / sizeof vals[0]; k++) set_real(ft, names[k], vals[k]);
            set_real(ft, "above_ground_m", p[2] - ground_up(site, p[0], p[1]));
            set_real(ft, "rms_surveyed_px", cam->rms_surveyed_px);
            set_str(ft, "enu_origin", origin);
            const rs_audit_result *a = cam->has_audit ? &cam->audit : NULL;
            set_str(ft, "verdict", a ? (a->pass ? "pass" : "FAIL") : "not audited");
            set_str(ft, "verdict_text", a ? a->verdict : cam->audit_error);
            set_real(ft, "need_ground_m", a ? a->thresholds.need_ground_m : NAN);
            set_real(ft, "ground_sigma_median_m", a ? a->ground_sigma_inside_median_m : NAN);
            set_real(ft, "ground_sigma_p90_m", a ? a->ground_sigma_inside_p90_m : NAN);
            set_real(ft, "loo_median_m", a ? a->loo_median_m : NAN);
        }
        st = put(v, L_CAMERAS, ft, point(f, p), err);
        sum->Ncameras += !st;
        // the footprint: the ground seen, a closed ring
        if (st || cam->Nfov < 3) continue;
        OGRGeometryH ring = OGR_G_CreateGeometry(wkbLinearRing), poly = OGR_G_CreateGeometry(wkbPolygon);
        bool ok = ring && poly;
        for (int i = 0; ok && i <= cam->Nfov; i++) {
            const double *en = &cam->fov_en_m[2 * (i % cam->Nfov)];
            double q[3] = {en[0], en[1], ground_up(site, en[0], en[1])}, xyz[3];
            ok = to_crs(f, q, xyz);
            if (ok) OGR_G_AddPoint_2D(ring, xyz[0], xyz[1]);
        }
        if (ok) ok = OGR_G_AddGeometryDirectly(poly, ring) == OGRERR_NONE, ring = NULL;
        OGR_G_DestroyGeometry(ring);
        if (!ok) {
            OGR_G_DestroyGeometry(poly);
            st = rs_err_set(err, RS_ERR_EXTERNAL, "%s: camera %s: its footprint cannot be transformed", v->path, id);
            break;
        }
        ft = feature(v, L_FOOTPRINTS, id);
        if (ft) set_real(ft, "range_m", rep->range_m);
        if (ft) set_str(ft, "verdict", cam->has_audit ? (cam->audit.pass ? "pass" : "FAIL") : "not audited");
        st = put(v, L_FOOTPRINTS, ft, poly, err);
    }
    return st;
}

static rs_status write_picks(vector_out *v, const frame *f, const struct rs_report_ctx *rep,
                             rs_report_export_summary *sum, rs_err *err)
{
    const rs_site *site = rep->site;
    rs_status st = RS_OK;
    for (int c = 0; c < rep->Ncameras && !st; c++) {
        const rs_report_camera *cam = &rep->cameras[c];
        const rs_site_camera *sc = &site->cameras[cam->icam];
        for (int i = 0; i < cam->N && !st; i++) {
            const rs_report_landmark *l = &cam->landmarks[i];
            if (l->ilandmark < 0) continue;
            // the audit's landmark i is the site camera's observation i
            const rs_audit_landmark *al = NULL;
            if (cam->has_audit && i < cam->audit.N && i < sc->Nobservations &&
                sc->observations[i].ilandmark == l->ilandmark)
                al = &cam->audit.landmarks[i];
            OGRFeatureH ft = feature(v, L_PICKS, sc->id);
            if (ft) {
                set_str(ft, "landmark", l->id);
                set_real(ft, "residual_u_px", l->residual_surveyed_px[0]);
                set_real(ft, "residual_v_px", l->residual_surveyed_px[1]);
                set_real(ft, "residual_px", hypot(l->residual_surveyed_px[0], l->residual_surveyed_px[1]));
                set_real(ft, "normalised", l->normalised);
                set_int(ft, "inlier", l->inlier);
                set_real(ft, "loo_ground_error_m", al && al->loo_ok ? al->loo_ground_error_m : NAN);
                set_real(ft, "loo_error_px", al && al->loo_ok ? al->loo_error_px : NAN);
                set_real(ft, "sigma_ground_m", al ? al->sigma_ground_m : NAN);
                set_str(ft, "flag", al ? al->reason : (l->inlier ? "" : "outlier"));
            }
            st = put(v, L_PICKS, ft, point(f, site->landmarks[l->ilandmark].p_enu_m), err);
            sum->Npicks += !st;
        }
    }
    return st;
}

// One feature per site landmark that a camera picked: its survey, the cameras and the worst
// leave-one-out ground error over its picks.
static rs_status write_landmarks(vector_out *v, const frame *f, const struct rs_report_ctx *rep,
                                 rs_report_export_summary *sum, rs_err *err)
{
    const rs_site *site = rep->site;
    rs_status st = RS_OK;
    for (int il = 0; il < site->Nlandmarks && !st; il++) {
        char cameras[512] = "", flag[512] = "";
        int Npicks = 0, Ninliers = 0;
        double worst_m = NAN;
        size_t n = 0;
        for (int c = 0; c < rep->Ncameras; c++) {
            const rs_report_camera *cam = &rep->cameras[c];
            const rs_site_camera *sc = &site->cameras[cam->icam];
            for (int i = 0; i < cam->N; i++) {
                if (cam->landmarks[i].ilandmark != il) continue;
                Npicks++;
                Ninliers += cam->landmarks[i].inlier;
                if (n + 1 < sizeof cameras)
                    n += (size_t)snprintf(cameras + n, sizeof cameras - n, "%s%s", n ? ", " : "", sc->id);
                const rs_audit_landmark *al =
                    cam->has_audit && i < cam->audit.N && i < sc->Nobservations && sc->observations[i].ilandmark == il
                        ? &cam->audit.landmarks[i]
                        : NULL;
                if (al && al->loo_ok && !(al->loo_ground_error_m <= worst_m)) worst_m = al->loo_ground_error_m;
                if (al && al->reason[0] && !flag[0]) snprintf(flag, sizeof flag, "%s: %s", sc->id, al->reason);
                if (!cam->landmarks[i].inlier && !flag[0]) snprintf(flag, sizeof flag, "%s: outlier", sc->id);
            }
        }
        if (!Npicks) continue;
        const rs_site_landmark *lm = &site->landmarks[il];
        OGRFeatureH ft = feature(v, L_LANDMARKS, NULL);
        if (ft) {
            set_str(ft, "landmark", lm->id);
            set_real(ft, "east_m", lm->p_enu_m[0]);
            set_real(ft, "north_m", lm->p_enu_m[1]);
            set_real(ft, "up_m", lm->p_enu_m[2]);
            set_real(ft, "sigma_h_m", lm->sigma_h_m);
            set_real(ft, "sigma_v_m", lm->sigma_v_m);
            set_str(ft, "cameras", cameras);
            set_int(ft, "n_picks", Npicks);
            set_int(ft, "n_inliers", Ninliers);
            set_real(ft, "loo_ground_error_m", worst_m);
            set_str(ft, "flag", flag);
        }
        st = put(v, L_LANDMARKS, ft, point(f, lm->p_enu_m), err);
        sum->Nlandmarks += !st;
    }
    return st;
}

static rs_status write_lanes(vector_out *v, const frame *f, const struct rs_report_ctx *rep,
                             rs_report_export_summary *sum, rs_err *err)
{
    const rs_report_lanes *lanes = &rep->lanes;
    rs_status st = RS_OK;
    for (int k = 0; k < lanes->Nlines && !st; k++) {
        OGRGeometryH g = OGR_G_CreateGeometry(wkbLineString25D);
        bool ok = g != NULL;
        for (int i = lanes->start[k]; ok && i < lanes->start[k + 1]; i++) {
            double xyz[3];
            ok = to_crs(f, &lanes->p_enu_m[3 * i], xyz);
            if (ok) OGR_G_AddPoint(g, xyz[0], xyz[1], xyz[2]);
        }
        if (!ok) {
            OGR_G_DestroyGeometry(g);
            return rs_err_set(err, RS_ERR_EXTERNAL, "%s: lane line %d cannot be transformed", v->path, k);
        }
        OGRFeatureH ft = feature(v, L_LANES, NULL);
        if (ft) set_int(ft, "junction", lanes->junction[k]);
        st = put(v, L_LANES, ft, g, err);
        sum->Nlanes += !st;
    }
    return st;
}

// ---- files ----

static rs_status write_vector(const char *path, const frame *f, const struct rs_report_ctx *rep,
                              rs_report_export_summary *sum, rs_err *err)
{
    const bool gpkg = rs_io_has_extension(path, "gpkg");
    const bool geojson = rs_io_has_extension(path, "geojson") || rs_io_has_extension(path, "json");
    if (!gpkg && !geojson)
        return rs_err_set(err, RS_ERR_INVALID, "%s: expected a .gpkg (GeoPackage) or .geojson file name", path);
    GDALDriverH drv = GDALGetDriverByName(gpkg ? "GPKG" : "GeoJSON");
    if (!drv) return gdal_fail(err, path, gpkg ? "GDAL has no GPKG driver" : "GDAL has no GeoJSON driver");
    rs_geo_gdal_output a = {0};
    rs_status st = rs_geo_gdal_output_open(&a, path, err);
    vector_out v = {.path = path};
    if (!st) {
        v.ds = GDALCreate(drv, a.vsi_path, 0, 0, 0, GDT_Unknown, NULL);
        if (!v.ds) st = gdal_fail(err, path, "cannot create");
    }
    if (!st) st = create_layers(&v, f, geojson, err);
    if (!st) st = write_cameras(&v, f, rep, sum, err);
    if (!st) st = write_landmarks(&v, f, rep, sum, err);
    if (!st) st = write_picks(&v, f, rep, sum, err);
    if (!st) st = write_lanes(&v, f, rep, sum, err);
    const double need_m = rep->audit_options ? rep->audit_options->need_ground_m : 1;
    if (!st && gpkg) st = rs_report_export_styles(v.ds, path, need_m, err);
    if (!st) rs_report_export_metadata(v.ds, rep->site, rep->calib_dir, need_m);
    if (v.ds) { // GDAL 3.6's GDALClose returns nothing: its errors are read back
        CPLErrorReset();
        GDALClose(v.ds);
        if (CPLGetLastErrorType() >= CE_Failure && !st) st = gdal_fail(err, path, "cannot finish");
    }
    if (!st) st = rs_geo_gdal_output_commit(&a, err);
    rs_geo_gdal_output_abort(&a);
    return st;
}

// The map as a GeoTIFF on the site's ENU grid, through geo's raster writer (geo/rs_geo_raster.h);
// crs: the target CRS (NULL: the site's grid CRS).
static rs_status write_raster(const char *path, const char *crs, const struct rs_report_ctx *rep,
                              rs_report_export_summary *sum, rs_err *err)
{
    const rs_audit_map *m = &rep->best_map;
    if (!m->sigma_m)
        return rs_err_set(err, RS_ERR_INVALID, "%s: no camera has an uncertainty map (no audit ran)", path);
    float *cells = malloc((size_t)m->nx * (size_t)m->ny * sizeof *cells);
    if (!cells) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
    // row 0 of the image is the northernmost row of cells; cell centres at (e0 + ix c, n0 + iy c)
    for (int r = 0; r < m->ny; r++)
        for (int x = 0; x < m->nx; x++)
            cells[(size_t)r * m->nx + x] = (float)m->sigma_m[(size_t)(m->ny - 1 - r) * (size_t)m->nx + x];
    const rs_geo_raster raster = {
        .grid = {.width = m->nx,
                 .height = m->ny,
                 .e0_m = m->e0_m,
                 .n0_m = m->n0_m + (m->ny - 1) * m->cell_m,
                 .cell_m = m->cell_m},
        .Nbands = 1,
        .type = RS_GEO_RASTER_FLOAT32,
        .data = cells,
        .nodata_nan = true,
        .description = "1-sigma horizontal ground error, metres",
        .crs = crs,
    };
    rs_status st = rs_geo_raster_write(&sum->raster_width, &sum->raster_height, path, &rep->site->origin, &raster, err);
    free(cells);
    return st;
}

rs_status rs_report_export(rs_report_export_summary *summary, const char *vector_path, const char *raster_path,
                           const rs_site *site, const rs_report_export_options *opt_in, rs_err *err)
{
    rs_err local = {0};
    if (!err) err = &local;
    rs_report_export_summary sum = {0};
    rs_report_export_options opt;
    if (opt_in)
        opt = *opt_in;
    else
        rs_report_export_options_default(&opt);
    if (!vector_path && !raster_path) return rs_err_set(err, RS_ERR_INVALID, "export: nothing to write");
    if (!(opt.range_m > 0)) return rs_err_set(err, RS_ERR_INVALID, "export: range_m = %g: must be > 0", opt.range_m);
    // outputs are files: a device (-o /dev/null), FIFO or folder there is refused, never replaced
    const char *paths[2] = {vector_path, raster_path};
    for (int i = 0; i < 2; i++) {
        struct stat sb;
        if (paths[i] && stat(paths[i], &sb) == 0 && !S_ISREG(sb.st_mode))
            return rs_err_set(err, RS_ERR_IO,
                              "%s: exists and is not a regular file (a device, FIFO or folder): not written", paths[i]);
    }
    // the folders the outputs go into are created, as calib's and report's are
    for (int i = 0; i < 2; i++) {
        const char *slash = paths[i] ? strrchr(paths[i], '/') : NULL;
        if (!slash || slash == paths[i]) continue;
        char *dir = strndup(paths[i], (size_t)(slash - paths[i]));
        rs_status st = dir ? rs_io_mkdir_p(dir, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(dir);
        if (st) return st;
    }
    // stale outputs first: an earlier export under these names is not this run's
    if (vector_path) (void)rs_io_remove_if_exists(vector_path, NULL, NULL);
    if (raster_path) (void)rs_io_remove_if_exists(raster_path, NULL, NULL);
    GDALAllRegister();
    CPLErrorReset();
    CPLPushErrorHandler(CPLQuietErrorHandler); // GDAL's messages come back as rs_err, not on stderr

    rs_report_options ropt;
    rs_report_options_default(&ropt);
    ropt.range_m = opt.range_m;
    ropt.audit_options = opt.audit_options;
    ropt.audit_options.range_m = opt.range_m;
    char *default_calib = opt.calib_dir ? NULL : rs_io_join(site->dir, "calib");
    struct rs_report_ctx rep = {.site = site, .range_m = opt.range_m, .grid_m = opt.range_m / 10};
    rep.calib_dir = opt.calib_dir ? opt.calib_dir : default_calib;
    rep.audit_options = &ropt.audit_options;
    rep.detection_sigma_px = ropt.audit_options.detection_sigma_px;
    rs_status st = rep.calib_dir ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "out of memory");

    frame f = {.site = site};
    OGRSpatialReferenceH target = NULL; // the CRS asked for; NULL: WGS84
    if (!st) {
        f.srs = OSRNewSpatialReference(NULL);
        if (!f.srs || OSRSetFromUserInput(f.srs, opt.crs ? opt.crs : "EPSG:4326") != OGRERR_NONE)
            st = rs_err_set(err, RS_ERR_INVALID, "--crs %s: not a CRS GDAL knows (try EPSG:4326, EPSG:25832, ...)",
                            opt.crs ? opt.crs : "EPSG:4326");
    }
    if (!st) {
        OSRSetAxisMappingStrategy(f.srs, OAMS_TRADITIONAL_GIS_ORDER);
        OGRSpatialReferenceH wgs84 = OSRNewSpatialReference(NULL);
        OSRSetFromUserInput(wgs84, "EPSG:4326");
        OSRSetAxisMappingStrategy(wgs84, OAMS_TRADITIONAL_GIS_ORDER);
        if (!OSRIsSame(wgs84, f.srs)) {
            f.t = OCTNewCoordinateTransformation(wgs84, f.srs);
            if (!f.t) st = rs_err_set(err, RS_ERR_INVALID, "--crs %s: no transformation from WGS84", opt.crs);
            target = f.srs;
        }
        OSRDestroySpatialReference(wgs84);
    }
    if (!st) st = rs_report_load_cameras(&rep, &ropt, err);
    if (!st && vector_path) st = write_vector(vector_path, &f, &rep, &sum, err);
    if (!st && raster_path) st = write_raster(raster_path, target ? opt.crs : NULL, &rep, &sum, err);
    if (st) { // all or nothing
        if (vector_path) (void)rs_io_remove_if_exists(vector_path, NULL, NULL);
        if (raster_path) (void)rs_io_remove_if_exists(raster_path, NULL, NULL);
    }
    rs_report_free_cameras(&rep);
    if (f.t) OCTDestroyCoordinateTransformation(f.t);
    if (f.srs) OSRDestroySpatialReference(f.srs);
    free(default_calib);
    CPLPopErrorHandler();
    if (summary) *summary = st ? (rs_report_export_summary){0} : sum;
    return st;
}
