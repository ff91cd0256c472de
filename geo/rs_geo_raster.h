// rs_geo_raster.h -- georeferenced rasters (GeoTIFF) on a site's ENU grid, both ways, through
// GDAL's C API (gdal.h, ogr_srs_api.h, gdalwarper.h): the one owner of raster GIS files.
// `roadside ortho` writes the digital twin's orthophoto with it, `roadside export` the ground
// uncertainty map, and `roadside pick` reads any orthophoto back onto the site's grid.
//
// The grid: north-up, square cells of cell_m metres; pixel (i, j) (column i from the west, row j
// from the north; pixel (0,0) is the centre of the top-left pixel, docs/conventions.md) has its
// centre at E = e0_m + i cell_m, N = n0_m - j cell_m. GDAL's geotransform (which names the
// top-left CORNER) is then {e0 - cell/2, cell, 0, n0 + cell/2, 0, -cell}.
//
// The site's ENU grid as a CRS: "+proj=ortho" centred on the site's origin on WGS84 (PROJ's
// ellipsoidal orthographic projection is the tangent plane at the origin), so its (x, y) are
// the ENU (E, N) of points on the ellipsoid; for points at the site's height h they differ by
// about h d / R (9 mm at d = 100 m for h = 560 m), far below a cell of a few centimetres for
// sites of a few hundred metres.
//
// Accuracy of the reader: the file is warped into that grid by GDAL's warper (bilinear), whose
// approximate transformer keeps within 0.125 px of the exact reprojection (GDAL's default error
// threshold); a file already in the site's grid CRS is read as it is (no resampling).
#pragma once
#include <stdbool.h>

#include "core/rs_status.h"
#include "geo/rs_geo.h"

#ifdef __cplusplus
extern "C" {
#endif

// A north-up grid on the site's ENU (E, N), see above.
typedef struct {
    int width, height; // pixels, > 0
    double e0_m, n0_m; // E, N of the centre of pixel (0,0) (the north-west one), metres
    double cell_m;     // cell size (ground sampling distance), metres, > 0
} rs_geo_grid;

typedef enum {
    RS_GEO_RASTER_BYTE,    // 8-bit unsigned per band
    RS_GEO_RASTER_FLOAT32, // 32-bit float per band
} rs_geo_raster_type;

// What to write.
typedef struct {
    rs_geo_grid grid;
    int Nbands;              // 1 (grey or a measurement) or 3 (RGB, written PHOTOMETRIC=RGB)
    rs_geo_raster_type type; //
    const void *data;        // (height, width, Nbands) interleaved per pixel, row 0 north: uint8_t
                             //   or float by `type`
    bool nodata_nan;         // FLOAT32 only: NaN is the bands' nodata
    const char *description; // band 1's description (GDAL metadata); may be NULL
    const char *crs;         // target CRS (any text OSRSetFromUserInput takes, "EPSG:25832");
                             //   NULL: the site's grid CRS itself (no resampling). Else the grid is
                             //   warped into it (nearest neighbour)
} rs_geo_raster;

// The site's grid CRS as WKT (see above). Caller frees with free(). NULL on failure.
char *rs_geo_raster_enu_wkt(const rs_llh *origin);

// Writes a GeoTIFF (DEFLATE compressed) atomically: under a temporary name, renamed into place.
// out: width_out, height_out (may be NULL): the size written (other than the grid's when warped)
// in:  path (.tif / .tiff), origin (the site's ENU origin), r
// Errors: RS_ERR_INVALID (extension, a bad grid, a CRS GDAL does not know, naming it),
// RS_ERR_EXTERNAL (GDAL failed: its message), RS_ERR_IO, RS_ERR_NOMEM.
rs_status rs_geo_raster_write( // out
    int *width_out, int *height_out,
    // in
    const char *path, const rs_llh *origin, const rs_geo_raster *r, rs_err *err);

// ---- files a GDAL driver writes ----

// An output file a GDAL driver (GTiff, GPKG, GeoJSON, /vsizip/) writes, checked to the end. GDAL's
// drivers do not all check their writes (on a full disk the GeoJSON driver closed a truncated
// file without an error; GPKG's SQLite said "no such table: gpkg_geometry_columns"): so the
// driver writes into GDAL's memory file system (/vsimem/, a folder of its own for any side files
// such as SQLite's journal), and rs_geo_gdal_output_commit writes the finished bytes to `path`
// through core/rs_io.h's atomic write: every write checked, "disk full writing PATH" on ENOSPC,
// nothing under `path` unless complete. The whole file is held in memory meanwhile.
typedef struct {
    char *vsi_dir;  // owned: "/vsimem/roadside-<pid>-<n>"
    char *vsi_path; // owned: vsi_dir/<path's file name>: give this to GDAL
    char *path;     // owned: the final name
} rs_geo_gdal_output;

// out: *o, to be finished with rs_geo_gdal_output_commit or _abort. Errors: RS_ERR_NOMEM;
// RS_ERR_IO when `path` is a folder, a device or a FIFO (never replaced).
rs_status rs_geo_gdal_output_open(rs_geo_gdal_output *o,
                                  // in
                                  const char *path, rs_err *err);
// Writes what GDAL wrote at o->vsi_path to o->path atomically (rs_io_write_file), then frees
// the memory file and o's strings whatever the outcome. Call after GDALClose. Errors: RS_ERR_IO
// (nothing was written at vsi_path; the write, naming `path`), RS_ERR_NOMEM.
rs_status rs_geo_gdal_output_commit(rs_geo_gdal_output *o, rs_err *err);
// Frees the memory files and o's strings; accepts NULL, a zeroed or a finished o.
void rs_geo_gdal_output_abort(rs_geo_gdal_output *o);

// An orthophoto read onto the site's grid.
typedef struct {
    rs_geo_grid grid;
    unsigned char *rgb; // (height, width, 3) owned: sRGB as stored (one band: grey repeated;
                        //   16-bit or float bands are clamped to 0..255 by GDAL)
    bool warped;        // the file was in another CRS and was reprojected
    char *crs_name;     // owned: the file's CRS name as GDAL gives it
} rs_geo_ortho;

// Reads a whole georeferenced image (any format and CRS GDAL reads: GeoTIFF, JPEG2000, ...)
// reprojected onto the site's grid (bilinear), decimated (GDAL's averaging overview read) so
// that neither side exceeds max_side pixels: the view of rs_geo_tiles_open read at once. For a
// small raster; `roadside pick` reads tiles instead.
// in: path, origin, max_side in [16, 16384]
// Errors: RS_ERR_IO (unreadable), RS_ERR_INVALID (no georeference or CRS, no transformation to
// WGS84, naming the file), RS_ERR_EXTERNAL (GDAL), RS_ERR_NOMEM.
rs_status rs_geo_ortho_read( // out
    rs_geo_ortho *out,
    // in
    const char *path, const rs_llh *origin, int max_side, rs_err *err);
void rs_geo_ortho_free(rs_geo_ortho *o); // NULL-safe; zeroes *o

// Turns GDAL's default error handler (which prints "ERROR 1: ..." to stderr, from any thread) into
// a silent one for the whole process. Every GDAL failure that matters comes back as an rs_err
// with GDAL's message (CPLGetLastErrorMsg); warnings a call survives (e.g. PROJ's "Point outside
// of projection domain" while an extent is sampled) are not printed. For programs (cli/main.c).
void rs_geo_gdal_quiet(void);

// ---- tiles: a raster of any size read at the resolution a view needs (roadside pick) ----

// A tile's side, pixels.
#define RS_GEO_TILE_PX 256

// An orthophoto source opened, nothing read yet: a file or anything GDAL opens (a GeoTIFF of any
// size, a GDAL XML description of a WMS, WMTS or TMS/XYZ tile service, JPEG2000, ...), in any
// CRS. Its "view" is the source on the site's grid: the file itself when it is already in the
// site's grid CRS (north-up, square cells: read as it is, no resampling), else a warped VRT
// (GDAL's warper, bilinear, within 0.125 px) built lazily window by window. Level L of the
// pyramid has cells of 2^L full-resolution cells; tile (tx, ty) of level L covers the view's
// full-resolution pixels [tx 256 2^L, (tx + 1) 256 2^L) x [ty 256 2^L, ...), read decimated
// (GDAL's averaging RasterIO, which takes the source's overviews when it has them). Not
// thread-safe: one reader at a time.
typedef struct rs_geo_tiles rs_geo_tiles;

// out: *t (rs_geo_tiles_close)
// in: path (anything GDAL opens), origin (the site's ENU origin)
// Errors: RS_ERR_IO (GDAL cannot open it), RS_ERR_INVALID (no georeference or CRS, no
// transformation onto the site's grid, naming the file), RS_ERR_EXTERNAL, RS_ERR_NOMEM.
rs_status rs_geo_tiles_open( // out
    rs_geo_tiles **t,
    // in
    const char *path, const rs_llh *origin, rs_err *err);
void rs_geo_tiles_close(rs_geo_tiles *t); // NULL-safe

// The view's full-resolution grid on the site's ENU; the number of levels (level Nlevels - 1
// fits the whole view in one tile); whether the source was reprojected; its CRS name.
const rs_geo_grid *rs_geo_tiles_grid(const rs_geo_tiles *t);
int rs_geo_tiles_levels(const rs_geo_tiles *t);
bool rs_geo_tiles_warped(const rs_geo_tiles *t);
const char *rs_geo_tiles_crs_name(const rs_geo_tiles *t);

// Reads tile (tx, ty) of `level` (see above).
// out: rgba (RS_GEO_TILE_PX, RS_GEO_TILE_PX, 4) 8-bit: grey repeated for one band, the source's
//      alpha for four bands, else opaque; transparent where the tile runs past the image's edge
// Errors: RS_ERR_INVALID (level out of range), RS_ERR_NOT_FOUND (tile outside the image),
// RS_ERR_EXTERNAL (GDAL: a read or a tile service failed, its message).
rs_status rs_geo_tiles_read( // out
    rs_geo_tiles *t, int level, int tx, int ty, unsigned char *rgba,
    // in
    rs_err *err);

// ---- a camera's pixel grid (roadside export --pixel-map; docs/localise.md, "Pixel map") ----

// Bands over an image's pixel grid: value (row v, column u) is pixel (u, v) of the image (pixel
// (0,0) the centre of the top-left pixel). Not georeferenced: the values are the coordinates.
typedef struct {
    int width, height;         // pixels, 1..65536
    int Nbands;                // 1..16
    const double *const *band; // (Nbands,) each (height, width) row-major; NaN: no value
    const char *const *name;   // (Nbands,) band descriptions (GeoTIFF) / array names (.npz):
                               //   [A-Za-z0-9_]+
} rs_geo_pixel_bands;

// Writes the bands as a GeoTIFF of Float64 bands (DEFLATE, NaN the nodata, each band's
// description its name, no georeference), atomically.
// Errors: RS_ERR_INVALID (extension, sizes, names), RS_ERR_EXTERNAL (GDAL), RS_ERR_IO.
rs_status rs_geo_pixel_bands_write_tiff(const char *path, const rs_geo_pixel_bands *b, rs_err *err);

// Writes the bands as a NumPy .npz: one array <name>.npy per band, float64 of shape (height,
// width) in NumPy's .npy format 1.0 (written here: a 10-byte preamble and a dict header), zipped
// by GDAL's /vsizip/ (no zip code of ours), under a temporary name renamed into place.
// numpy.load(path)["<name>"] reads it.
// Errors: RS_ERR_INVALID (extension, sizes, names), RS_ERR_UNSUPPORTED (a big-endian host),
// RS_ERR_EXTERNAL (GDAL's zip writer), RS_ERR_IO.
rs_status rs_geo_pixel_bands_write_npz(const char *path, const rs_geo_pixel_bands *b, rs_err *err);

#ifdef __cplusplus
}
#endif
