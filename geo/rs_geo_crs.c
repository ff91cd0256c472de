// rs_geo_crs.c -- any CRS into WGS84 through GDAL's OGR (rs_geo_crs.h).
#include "geo/rs_geo_crs.h"

#include <math.h>
#include <stdlib.h>

#include <cpl_error.h>
#include <ogr_srs_api.h>

rs_status rs_geo_crs_to_llh(double *llh, bool *geographic, int *bad_row, const char *crs, const double *xyh, int N,
                            rs_err *err)
{
    if (bad_row) *bad_row = -1;
    if (N < 0 || (N > 0 && (!llh || !xyh)) || !crs)
        return rs_err_set(err, RS_ERR_USAGE, "rs_geo_crs_to_llh: bad arguments");
    OGRSpatialReferenceH from = OSRNewSpatialReference(NULL), wgs84 = OSRNewSpatialReference(NULL);
    OGRCoordinateTransformationH t = NULL;
    double *x = malloc(((size_t)N + 1) * sizeof *x), *y = malloc(((size_t)N + 1) * sizeof *y);
    int *ok = malloc(((size_t)N + 1) * sizeof *ok);
    rs_status st = RS_OK;
    CPLPushErrorHandler(CPLQuietErrorHandler); // the library never prints: GDAL's messages go into err
    CPLErrorReset();
    if (!from || !wgs84 || !x || !y || !ok) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    } else if (OSRSetFromUserInput(from, crs) != OGRERR_NONE) {
        st = rs_err_set(err, RS_ERR_INVALID, "--crs %s: not a CRS GDAL knows (try EPSG:4326, EPSG:25832, ...)", crs);
    } else {
        if (geographic) *geographic = OSRIsGeographic(from);
        OSRSetFromUserInput(wgs84, "EPSG:4326");
        OSRSetAxisMappingStrategy(from, OAMS_TRADITIONAL_GIS_ORDER);
        OSRSetAxisMappingStrategy(wgs84, OAMS_TRADITIONAL_GIS_ORDER);
        t = OCTNewCoordinateTransformation(from, wgs84);
        if (!t)
            st = rs_err_set(err, RS_ERR_EXTERNAL, "--crs %s: GDAL found no transformation to WGS84: %s", crs,
                            CPLGetLastErrorMsg());
    }
    for (int i = 0; st == RS_OK && i < N; i++) x[i] = xyh[3 * i], y[i] = xyh[3 * i + 1];
    if (st == RS_OK && N > 0 && !OCTTransformEx(t, N, x, y, NULL, ok))
        for (int i = 0; i < N; i++) ok[i] = ok[i] && isfinite(x[i]) && isfinite(y[i]);
    for (int i = 0; st == RS_OK && i < N; i++) {
        if (!ok[i] || !isfinite(x[i]) || !isfinite(y[i]) || fabs(y[i]) > 90) {
            st = rs_err_set(err, RS_ERR_INVALID, "(%.17g, %.17g) of %s: PROJ cannot transform it to WGS84", xyh[3 * i],
                            xyh[3 * i + 1], crs);
            if (bad_row) *bad_row = i;
        }
        llh[3 * i] = y[i], llh[3 * i + 1] = x[i], llh[3 * i + 2] = xyh[3 * i + 2];
    }
    if (t) OCTDestroyCoordinateTransformation(t);
    if (from) OSRDestroySpatialReference(from);
    if (wgs84) OSRDestroySpatialReference(wgs84);
    free(x), free(y), free(ok);
    CPLPopErrorHandler();
    return st;
}
