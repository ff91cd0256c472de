// rs_geo_raster.c -- GeoTIFFs on a site's ENU grid, and bands over a camera's pixel grid (GeoTIFF,
// NumPy .npz zipped by GDAL's /vsizip/), through GDAL's C API (rs_geo_raster.h).
#include "geo/rs_geo_raster.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal.h>
#include <gdalwarper.h>
#include <ogr_srs_api.h>

#include "core/rs_io.h"

static rs_status gdal_fail(rs_err *err, const char *path, const char *what)
{
    const char *msg = CPLGetLastErrorMsg();
    return rs_err_set(err, RS_ERR_EXTERNAL, "%s: %s%s%s", path, what, msg && *msg ? ": " : "", msg ? msg : "");
}

static OGRSpatialReferenceH enu_srs(const rs_llh *origin)
{
    char proj[256];
    snprintf(proj, sizeof proj, "+proj=ortho +lat_0=%.10f +lon_0=%.10f +x_0=0 +y_0=0 +ellps=WGS84 +units=m +no_defs",
             origin->lat_deg, origin->lon_deg);
    OGRSpatialReferenceH s = OSRNewSpatialReference(NULL);
    if (s && OSRImportFromProj4(s, proj) != OGRERR_NONE) {
        OSRDestroySpatialReference(s);
        return NULL;
    }
    // a name a GIS shows (gdalsrsinfo, QGIS), not PROJ's "unknown", and the unit spelled out
    char name[160];
    snprintf(name, sizeof name, "roadside site ENU at %.7f, %.7f (orthographic on WGS84, metres)", origin->lat_deg,
             origin->lon_deg);
    OSRSetProjCS(s, name);
    OSRSetGeogCS(s, "WGS 84", "World Geodetic System 1984", "WGS 84", SRS_WGS84_SEMIMAJOR, SRS_WGS84_INVFLATTENING,
                 "Greenwich", 0, SRS_UA_DEGREE, 0.0174532925199433);
    OSRSetLinearUnits(s, SRS_UL_METER, 1.0);
    return s;
}

char *rs_geo_raster_enu_wkt(const rs_llh *origin)
{
    OGRSpatialReferenceH s = enu_srs(origin);
    if (!s) return NULL;
    char *wkt = NULL, *copy = NULL;
    if (OSRExportToWkt(s, &wkt) == OGRERR_NONE && wkt) copy = strdup(wkt);
    CPLFree(wkt);
    OSRDestroySpatialReference(s);
    return copy;
}

static void grid_geotransform(const rs_geo_grid *g, double gt[6])
{
    gt[0] = g->e0_m - g->cell_m / 2, gt[1] = g->cell_m, gt[2] = 0;
    gt[3] = g->n0_m + g->cell_m / 2, gt[4] = 0, gt[5] = -g->cell_m;
}

static bool grid_ok(const rs_geo_grid *g)
{
    return g->width > 0 && g->height > 0 && g->width <= 65536 && g->height <= 65536 && isfinite(g->e0_m) &&
           isfinite(g->n0_m) && isfinite(g->cell_m) && g->cell_m > 0;
}

rs_status rs_geo_gdal_output_open(rs_geo_gdal_output *o, const char *path, rs_err *err)
{
    static unsigned counter; // one folder per output of this process
    memset(o, 0, sizeof *o);
    struct stat sb;
    if (stat(path, &sb) == 0 && !S_ISREG(sb.st_mode))
        return rs_err_set(err, RS_ERR_IO,
                          "%s: exists and is not a regular file (a device, FIFO or folder): not written", path);
    const char *slash = strrchr(path, '/'), *name = slash ? slash + 1 : path;
    char dir[64];
    snprintf(dir, sizeof dir, "/vsimem/roadside-%ld-%u", (long)getpid(),
             __atomic_add_fetch(&counter, 1, __ATOMIC_RELAXED));
    o->vsi_dir = strdup(dir);
    o->vsi_path = o->vsi_dir ? rs_io_join(dir, *name ? name : "out") : NULL;
    o->path = strdup(path);
    if (o->vsi_dir && o->vsi_path && o->path) return RS_OK;
    rs_geo_gdal_output_abort(o);
    return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
}

rs_status rs_geo_gdal_output_commit(rs_geo_gdal_output *o, rs_err *err)
{
    vsi_l_offset len = 0;
    GByte *data = o->vsi_path ? VSIGetMemFileBuffer(o->vsi_path, &len, FALSE) : NULL;
    rs_status st = data ? rs_io_write_file(o->path, data, (size_t)len, err)
                        : rs_err_set(err, RS_ERR_IO, "%s: GDAL wrote nothing", o->path ? o->path : "output");
    rs_geo_gdal_output_abort(o);
    return st;
}

void rs_geo_gdal_output_abort(rs_geo_gdal_output *o)
{
    if (!o) return;
    if (o->vsi_dir) VSIRmdirRecursive(o->vsi_dir);
    free(o->vsi_dir);
    free(o->vsi_path);
    free(o->path);
    memset(o, 0, sizeof *o);
}

rs_status rs_geo_raster_write(int *width_out, int *height_out, const char *path, const rs_llh *origin,
                              const rs_geo_raster *r, rs_err *err)
{
    if (width_out) *width_out = 0;
    if (height_out) *height_out = 0;
    if (!rs_io_has_extension(path, "tif") && !rs_io_has_extension(path, "tiff"))
        return rs_err_set(err, RS_ERR_INVALID, "%s: expected a .tif (GeoTIFF) file name", path);
    if (!grid_ok(&r->grid) || (r->Nbands != 1 && r->Nbands != 3) || !r->data)
        return rs_err_set(err, RS_ERR_INVALID, "%s: a raster of %dx%d cells of %g m with %d bands cannot be written",
                          path, r->grid.width, r->grid.height, r->grid.cell_m, r->Nbands);
    GDALAllRegister();
    CPLErrorReset();
    CPLPushErrorHandler(CPLQuietErrorHandler); // GDAL's messages come back as rs_err
    GDALDriverH mem = GDALGetDriverByName("MEM"), gtiff = GDALGetDriverByName("GTiff");
    OGRSpatialReferenceH enu = enu_srs(origin), target = NULL;
    char *enu_wkt = NULL, *dst_wkt = NULL;
    GDALDatasetH src = NULL, out_src = NULL;
    rs_geo_gdal_output a = {0};
    const int W = r->grid.width, H = r->grid.height, B = r->Nbands;
    const GDALDataType type = r->type == RS_GEO_RASTER_BYTE ? GDT_Byte : GDT_Float32;
    const int esize = r->type == RS_GEO_RASTER_BYTE ? 1 : 4;
    rs_status st = RS_OK;
    if (!mem || !gtiff) st = gdal_fail(err, path, "GDAL has no MEM or GTiff driver");
    if (!st && (!enu || OSRExportToWkt(enu, &enu_wkt) != OGRERR_NONE))
        st = gdal_fail(err, path, "cannot define the site's ENU grid as a CRS");
    if (!st && r->crs) {
        target = OSRNewSpatialReference(NULL);
        if (!target || OSRSetFromUserInput(target, r->crs) != OGRERR_NONE)
            st = rs_err_set(err, RS_ERR_INVALID, "%s: CRS '%s': not a CRS GDAL knows (try EPSG:4326, EPSG:25832, ...)",
                            path, r->crs);
        else
            OSRExportToWkt(target, &dst_wkt);
    }
    if (!st) {
        src = GDALCreate(mem, "", W, H, B, type, NULL);
        if (!src) st = gdal_fail(err, path, "cannot create the grid in memory");
    }
    if (!st) {
        double gt[6];
        grid_geotransform(&r->grid, gt);
        GDALSetGeoTransform(src, gt);
        GDALSetProjection(src, enu_wkt);
        for (int b = 1; b <= B; b++) {
            GDALRasterBandH band = GDALGetRasterBand(src, b);
            if (r->nodata_nan && type == GDT_Float32) GDALSetRasterNoDataValue(band, NAN);
            if (B == 3) GDALSetRasterColorInterpretation(band, (GDALColorInterp)(GCI_RedBand + b - 1));
            if (b == 1 && r->description) GDALSetDescription(band, r->description);
        }
        // pixel-interleaved source: one call for all bands (pixel space B*esize, line space W*B*esize)
        if (GDALDatasetRasterIO(src, GF_Write, 0, 0, W, H, (void *)r->data, W, H, type, B, NULL, (GSpacing)B * esize,
                                (GSpacing)W * B * esize, esize) != CE_None)
            st = gdal_fail(err, path, "cannot fill the grid");
    }
    out_src = src;
    if (!st && dst_wkt) {
        out_src = GDALAutoCreateWarpedVRT(src, enu_wkt, dst_wkt, GRA_NearestNeighbour, 0.0, NULL);
        if (!out_src) st = gdal_fail(err, path, "cannot warp the grid into the requested CRS");
    }
    if (!st) st = rs_geo_gdal_output_open(&a, path, err);
    if (!st) {
        char **co = CSLSetNameValue(NULL, "COMPRESS", "DEFLATE");
        if (B == 3) co = CSLSetNameValue(co, "PHOTOMETRIC", "RGB");
        GDALDatasetH out = GDALCreateCopy(gtiff, a.vsi_path, out_src, FALSE, co, NULL, NULL);
        CSLDestroy(co);
        if (!out) st = gdal_fail(err, path, "cannot write the GeoTIFF");
        if (out) {
            if (width_out) *width_out = GDALGetRasterXSize(out);
            if (height_out) *height_out = GDALGetRasterYSize(out);
            CPLErrorReset();
            GDALClose(out); // GDAL 3.6's GDALClose returns nothing: its errors are read back
            if (CPLGetLastErrorType() >= CE_Failure && !st) st = gdal_fail(err, path, "cannot finish the GeoTIFF");
        }
    }
    if (!st) st = rs_geo_gdal_output_commit(&a, err);
    rs_geo_gdal_output_abort(&a);
    if (out_src && out_src != src) GDALClose(out_src);
    if (src) GDALClose(src);
    CPLFree(enu_wkt);
    CPLFree(dst_wkt);
    if (enu) OSRDestroySpatialReference(enu);
    if (target) OSRDestroySpatialReference(target);
    CPLPopErrorHandler();
    return st;
}

void rs_geo_gdal_quiet(void) { CPLSetErrorHandler(CPLQuietErrorHandler); }

void rs_geo_ortho_free(rs_geo_ortho *o)
{
    if (!o) return;
    free(o->rgb);
    free(o->crs_name);
    memset(o, 0, sizeof *o);
}

// ---- tiles: any raster read at the resolution a view needs ----

struct rs_geo_tiles {
    GDALDatasetH ds;   // the file
    GDALDatasetH view; // ds itself, or a warped VRT of it onto the site's grid
    int width, height; // the view's size, full-resolution pixels
    int Nbands;        // of the file (1: grey, 3: RGB, 4: RGBA)
    rs_geo_grid grid;  // the view's full-resolution grid
    int Nlevels;
    bool warped;
    char *crs_name; // owned
};

void rs_geo_tiles_close(rs_geo_tiles *t)
{
    if (!t) return;
    if (t->view && t->view != t->ds) GDALClose(t->view);
    if (t->ds) GDALClose(t->ds);
    free(t->crs_name);
    free(t);
}

const rs_geo_grid *rs_geo_tiles_grid(const rs_geo_tiles *t) { return &t->grid; }
int rs_geo_tiles_levels(const rs_geo_tiles *t) { return t->Nlevels; }
bool rs_geo_tiles_warped(const rs_geo_tiles *t) { return t->warped; }
const char *rs_geo_tiles_crs_name(const rs_geo_tiles *t) { return t->crs_name; }

rs_status rs_geo_tiles_open(rs_geo_tiles **out, const char *path, const rs_llh *origin, rs_err *err)
{
    *out = NULL;
    // a file reaches GDAL only when regular (a FIFO or a device would block its open forever);
    // folders, /vsi paths and "WMS:" strings are GDAL's to judge
    struct stat sb;
    if (stat(path, &sb) == 0 && !S_ISDIR(sb.st_mode)) {
        rs_status checked = rs_io_check_regular(path, SIZE_MAX, err);
        if (checked) return checked;
    }
    GDALAllRegister();
    CPLErrorReset();
    CPLPushErrorHandler(CPLQuietErrorHandler);
    rs_status st = RS_OK;
    rs_geo_tiles *t = calloc(1, sizeof *t);
    if (!t) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    OGRSpatialReferenceH enu = enu_srs(origin), file_srs = NULL;
    char *enu_wkt = NULL;
    // a path GDAL opens: a file, a GDAL XML (WMS, TMS/XYZ, WMTS), a /vsi path, a "WMS:" string
    if (!st && !(t->ds = GDALOpen(path, GA_ReadOnly)))
        st = rs_err_set(err, RS_ERR_IO, "%s: not a raster GDAL reads: %s", path, CPLGetLastErrorMsg());
    if (!st && (!enu || OSRExportToWkt(enu, &enu_wkt) != OGRERR_NONE))
        st = gdal_fail(err, path, "cannot define the site's ENU grid as a CRS");
    const char *wkt = st ? NULL : GDALGetProjectionRef(t->ds);
    double gt[6];
    if (!st && (!wkt || !*wkt))
        st = rs_err_set(err, RS_ERR_INVALID, "%s: the image has no CRS (an orthophoto needs a georeference)", path);
    if (!st && GDALGetGeoTransform(t->ds, gt) != CE_None)
        st = rs_err_set(err, RS_ERR_INVALID, "%s: the image has no geotransform (an orthophoto needs a georeference)",
                        path);
    if (!st && (t->Nbands = GDALGetRasterCount(t->ds)) < 1)
        st = rs_err_set(err, RS_ERR_INVALID, "%s: no raster band", path);
    if (!st && !(file_srs = OSRNewSpatialReference(wkt)))
        st = rs_err_set(err, RS_ERR_INVALID, "%s: its CRS cannot be read", path);
    if (!st) {
        const char *name = OSRGetName(file_srs);
        if (!(t->crs_name = strdup(name ? name : "unnamed CRS"))) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    if (!st) {
        const bool same =
            OSRIsSame(file_srs, enu) && gt[2] == 0 && gt[4] == 0 && gt[5] < 0 && fabs(gt[1] + gt[5]) <= 1e-9 * gt[1];
        if (same)
            t->view = t->ds;
        else {
            // a warped VRT: nothing read now; each window later is warped on demand, from the
            // source's overviews when the window is read decimated
            t->view = GDALAutoCreateWarpedVRT(t->ds, wkt, enu_wkt, GRA_Bilinear, 0.125, NULL);
            if (!t->view)
                st = rs_err_set(err, RS_ERR_INVALID, "%s: cannot reproject from %s to the site's grid: %s", path,
                                t->crs_name, CPLGetLastErrorMsg());
            t->warped = true;
        }
    }
    double vgt[6];
    if (!st) {
        t->width = GDALGetRasterXSize(t->view), t->height = GDALGetRasterYSize(t->view);
        if (GDALGetGeoTransform(t->view, vgt) != CE_None || t->width < 1 || t->height < 1 || !(vgt[1] > 0) ||
            fabs(vgt[1] + vgt[5]) > 1e-6 * vgt[1])
            st = rs_err_set(err, RS_ERR_INVALID, "%s: the reprojected image has no square north-up grid", path);
    }
    if (!st) {
        t->grid = (rs_geo_grid){.width = t->width,
                                .height = t->height,
                                .e0_m = vgt[0] + vgt[1] / 2,
                                .n0_m = vgt[3] + vgt[5] / 2,
                                .cell_m = vgt[1]};
        const int side = t->width > t->height ? t->width : t->height;
        t->Nlevels = 1;
        while (t->Nlevels < 31 && ((long long)RS_GEO_TILE_PX << (t->Nlevels - 1)) < side) t->Nlevels++;
    }
    CPLFree(enu_wkt);
    if (enu) OSRDestroySpatialReference(enu);
    if (file_srs) OSRDestroySpatialReference(file_srs);
    CPLPopErrorHandler();
    if (st) {
        rs_geo_tiles_close(t);
        return st;
    }
    *out = t;
    return RS_OK;
}

// Reads the view's pixels [x0, x0 + w) x [y0, y0 + h) into an (ow, oh) buffer of `Nout` 8-bit
// bands per pixel (pixel spacing `pixel` >= Nout bytes, line spacing `line`), averaged when decimated.
static rs_status read_window(rs_geo_tiles *t, int x0, int y0, int w, int h, unsigned char *buf, int ow, int oh,
                             int Nout, GSpacing pixel, GSpacing line, rs_err *err)
{
    const int Nb = t->Nbands;
    int bands[4] = {1, Nb >= 3 ? 2 : 1, Nb >= 3 ? 3 : 1, Nb >= 4 ? 4 : 1};
    GDALRasterIOExtraArg extra;
    INIT_RASTERIO_EXTRA_ARG(extra);
    extra.eResampleAlg = ow < w ? GRIORA_Average : GRIORA_NearestNeighbour;
    CPLErrorReset();
    CPLPushErrorHandler(CPLQuietErrorHandler);
    const CPLErr e = GDALDatasetRasterIOEx(t->view, GF_Read, x0, y0, w, h, buf, ow, oh, GDT_Byte, Nout, bands, pixel,
                                           line, 1, &extra);
    CPLPopErrorHandler();
    return e == CE_None ? RS_OK : gdal_fail(err, GDALGetDescription(t->ds), "cannot read the image");
}

rs_status rs_geo_tiles_read(rs_geo_tiles *t, int level, int tx, int ty, unsigned char *rgba, rs_err *err)
{
    const int T = RS_GEO_TILE_PX;
    if (level < 0 || level >= t->Nlevels)
        return rs_err_set(err, RS_ERR_INVALID, "tile level %d: not in [0, %d)", level, t->Nlevels);
    const long long span = (long long)T << level; // full-resolution pixels a tile covers
    const long long x0 = (long long)tx * span, y0 = (long long)ty * span;
    if (tx < 0 || ty < 0 || x0 >= t->width || y0 >= t->height)
        return rs_err_set(err, RS_ERR_NOT_FOUND, "tile %d/%d/%d: outside the %dx%d image", level, tx, ty, t->width,
                          t->height);
    const int w = (int)(x0 + span <= t->width ? span : t->width - x0);
    const int h = (int)(y0 + span <= t->height ? span : t->height - y0);
    const int ow = (int)((w + (1LL << level) - 1) >> level), oh = (int)((h + (1LL << level) - 1) >> level);
    memset(rgba, 0, (size_t)T * T * 4);
    // RGB(A) into the RGBA tile: 4 bytes a pixel whatever the source's band count
    rs_status st =
        read_window(t, (int)x0, (int)y0, w, h, rgba, ow, oh, t->Nbands >= 4 ? 4 : 3, 4, (GSpacing)T * 4, err);
    if (st || t->Nbands >= 4) return st;
    for (int j = 0; j < oh; j++) // opaque where the image is; the rest of an edge tile transparent
        for (int i = 0; i < ow; i++) rgba[((size_t)j * T + i) * 4 + 3] = 255;
    return RS_OK;
}

rs_status rs_geo_ortho_read(rs_geo_ortho *out, const char *path, const rs_llh *origin, int max_side, rs_err *err)
{
    memset(out, 0, sizeof *out);
    if (max_side < 16 || max_side > 16384)
        return rs_err_set(err, RS_ERR_INVALID, "%s: max_side %d is not in [16, 16384]", path, max_side);
    rs_geo_tiles *t = NULL;
    rs_status st = rs_geo_tiles_open(&t, path, origin, err);
    if (st) return st;
    // decimate so that neither side exceeds max_side: cells grow by the factor s
    const int vw = t->width, vh = t->height;
    const int s = (int)ceil((double)(vw > vh ? vw : vh) / max_side);
    const int ow = (vw + s - 1) / s, oh = (vh + s - 1) / s;
    const double cell = t->grid.cell_m * vw / ow; // the read covers the whole view
    const double cell_n = t->grid.cell_m * vh / oh;
    const double e_edge = t->grid.e0_m - t->grid.cell_m / 2, n_edge = t->grid.n0_m + t->grid.cell_m / 2;
    out->grid = (rs_geo_grid){
        .width = ow, .height = oh, .e0_m = e_edge + cell / 2, .n0_m = n_edge - cell_n / 2, .cell_m = cell};
    out->warped = t->warped;
    out->crs_name = strdup(t->crs_name);
    out->rgb = malloc((size_t)ow * oh * 3);
    if (!out->rgb || !out->crs_name) st = rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory for %dx%d", path, ow, oh);
    if (!st) st = read_window(t, 0, 0, vw, vh, out->rgb, ow, oh, 3, 3, (GSpacing)ow * 3, err);
    rs_geo_tiles_close(t);
    if (st) rs_geo_ortho_free(out);
    return st;
}

// ---- a camera's pixel grid ----

static rs_status pixel_bands_ok(const char *path, const rs_geo_pixel_bands *b, rs_err *err)
{
    if (b->width < 1 || b->height < 1 || b->width > 65536 || b->height > 65536 || b->Nbands < 1 || b->Nbands > 16)
        return rs_err_set(err, RS_ERR_INVALID, "%s: %d x %d pixels, %d bands: cannot be written", path, b->width,
                          b->height, b->Nbands);
    for (int k = 0; k < b->Nbands; k++) {
        const char *n = b->name[k];
        bool ok = n && *n && b->band[k];
        for (const char *c = n; ok && *c; c++)
            ok = (*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') || *c == '_';
        if (!ok) return rs_err_set(err, RS_ERR_INVALID, "%s: band %d: a name of [A-Za-z0-9_] and data needed", path, k);
    }
    return RS_OK;
}

rs_status rs_geo_pixel_bands_write_tiff(const char *path, const rs_geo_pixel_bands *b, rs_err *err)
{
    if (!rs_io_has_extension(path, "tif") && !rs_io_has_extension(path, "tiff"))
        return rs_err_set(err, RS_ERR_INVALID, "%s: expected a .tif (GeoTIFF) file name", path);
    rs_status st = pixel_bands_ok(path, b, err);
    if (st) return st;
    GDALAllRegister();
    CPLErrorReset();
    CPLPushErrorHandler(CPLQuietErrorHandler);
    GDALDriverH gtiff = GDALGetDriverByName("GTiff");
    rs_geo_gdal_output a = {0};
    if (!gtiff) st = gdal_fail(err, path, "GDAL has no GTiff driver");
    if (!st) st = rs_geo_gdal_output_open(&a, path, err);
    if (!st) {
        char **co = CSLSetNameValue(NULL, "COMPRESS", "DEFLATE");
        co = CSLSetNameValue(co, "INTERLEAVE", "BAND");
        GDALDatasetH out = GDALCreate(gtiff, a.vsi_path, b->width, b->height, b->Nbands, GDT_Float64, co);
        CSLDestroy(co);
        if (!out) st = gdal_fail(err, path, "cannot create the GeoTIFF");
        for (int k = 0; out && !st && k < b->Nbands; k++) {
            GDALRasterBandH band = GDALGetRasterBand(out, k + 1);
            GDALSetRasterNoDataValue(band, NAN);
            GDALSetDescription(band, b->name[k]);
            if (GDALRasterIO(band, GF_Write, 0, 0, b->width, b->height, (void *)b->band[k], b->width, b->height,
                             GDT_Float64, 0, 0) != CE_None)
                st = gdal_fail(err, path, "cannot write a band");
        }
        if (out) {
            CPLErrorReset();
            GDALClose(out);
            if (CPLGetLastErrorType() >= CE_Failure && !st) st = gdal_fail(err, path, "cannot finish the GeoTIFF");
        }
    }
    if (!st) st = rs_geo_gdal_output_commit(&a, err);
    rs_geo_gdal_output_abort(&a);
    CPLPopErrorHandler();
    return st;
}

// One .npy (format 1.0) of a (height, width) little-endian float64 array into the open file f.
static bool write_npy(VSILFILE *f, const double *x, int width, int height)
{
    char header[128];
    int n =
        snprintf(header, sizeof header, "{'descr': '<f8', 'fortran_order': False, 'shape': (%d, %d), }", height, width);
    int total = 10 + n + 1; // preamble, dict, '\n': padded with spaces to a multiple of 64
    int pad = (64 - total % 64) % 64;
    for (int k = 0; k < pad; k++) header[n++] = ' ';
    header[n++] = '\n';
    const unsigned char pre[10] = {
        0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0, (unsigned char)(n & 0xff), (unsigned char)(n >> 8)};
    const size_t N = (size_t)width * (size_t)height;
    return VSIFWriteL(pre, 1, 10, f) == 10 && VSIFWriteL(header, 1, (size_t)n, f) == (size_t)n &&
           VSIFWriteL(x, sizeof *x, N, f) == N;
}

rs_status rs_geo_pixel_bands_write_npz(const char *path, const rs_geo_pixel_bands *b, rs_err *err)
{
    if (!rs_io_has_extension(path, "npz"))
        return rs_err_set(err, RS_ERR_INVALID, "%s: expected a .npz (NumPy) file name", path);
    const uint16_t one = 1;
    if (*(const unsigned char *)&one != 1)
        return rs_err_set(err, RS_ERR_UNSUPPORTED, "%s: .npz is written little-endian only", path);
    rs_status st = pixel_bands_ok(path, b, err);
    if (st) return st;
    CPLErrorReset();
    CPLPushErrorHandler(CPLQuietErrorHandler);
    rs_geo_gdal_output a = {0};
    st = rs_geo_gdal_output_open(&a, path, err);
    for (int k = 0; !st && k < b->Nbands; k++) {
        char *entry = CPLStrdup(CPLSPrintf("/vsizip/{%s}/%s.npy", a.vsi_path, b->name[k]));
        VSILFILE *f = VSIFOpenL(entry, "wb");
        if (!f)
            st = gdal_fail(err, path, "cannot add an array to the zip");
        else {
            bool ok = write_npy(f, b->band[k], b->width, b->height);
            if (VSIFCloseL(f) != 0 || !ok) st = gdal_fail(err, path, "cannot write an array into the zip");
        }
        CPLFree(entry);
    }
    if (!st) st = rs_geo_gdal_output_commit(&a, err);
    rs_geo_gdal_output_abort(&a);
    CPLPopErrorHandler();
    return st;
}
