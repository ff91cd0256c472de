// rs_report_export_style.c -- the GeoPackage's embedded QGIS styles (the layer_styles table) and
// its metadata (report/internal/rs_report_export_style.h).
#include "report/internal/rs_report_export_style.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cpl_error.h>
#include <cpl_string.h>
#include <ogr_api.h>

// ---- QML ----

// One symbol of a renderer: a fill (polygons) or a circle marker (points) of colour rgb (0..255)
// and opacity alpha; outline in the same colour, opaque.
static void qml_symbol(FILE *f, int index, bool fill, const int rgb[3], double alpha)
{
    fprintf(f, "   <symbol type=\"%s\" name=\"%d\" alpha=\"%g\" clip_to_extent=\"1\" force_rhr=\"0\">\n",
            fill ? "fill" : "marker", index, alpha);
    fprintf(f, "    <layer class=\"%s\" enabled=\"1\" pass=\"0\" locked=\"0\">\n     <Option type=\"Map\">\n",
            fill ? "SimpleFill" : "SimpleMarker");
    fprintf(f, "      <Option name=\"color\" type=\"QString\" value=\"%d,%d,%d,255\"/>\n", rgb[0], rgb[1], rgb[2]);
    fprintf(f, "      <Option name=\"outline_color\" type=\"QString\" value=\"%d,%d,%d,255\"/>\n", rgb[0] / 2,
            rgb[1] / 2, rgb[2] / 2);
    fprintf(f, "      <Option name=\"outline_width\" type=\"QString\" value=\"%s\"/>\n", fill ? "0.6" : "0.2");
    if (fill)
        fprintf(f, "      <Option name=\"style\" type=\"QString\" value=\"solid\"/>\n");
    else
        fprintf(f, "      <Option name=\"name\" type=\"QString\" value=\"circle\"/>\n"
                   "      <Option name=\"size\" type=\"QString\" value=\"3\"/>\n");
    fprintf(f, "     </Option>\n    </layer>\n   </symbol>\n");
}

static void qml_begin(FILE *f) { fprintf(f, "<!DOCTYPE qgis PUBLIC 'http://mrcc.com/qgis.dtd' 'SYSTEM'>\n"); }

// Features coloured by their verdict: pass green, FAIL red, not audited grey.
static void qml_by_verdict(FILE *f, bool fill)
{
    static const char *const value[3] = {"pass", "FAIL", "not audited"};
    static const int rgb[3][3] = {{26, 150, 65}, {215, 25, 28}, {150, 150, 150}};
    qml_begin(f);
    fprintf(f, "<qgis version=\"3.22.0\" styleCategories=\"Symbology|Labeling\">\n"
               " <renderer-v2 type=\"categorizedSymbol\" attr=\"verdict\" symbollevels=\"0\" enableorderby=\"0\" "
               "forceraster=\"0\">\n  <categories>\n");
    for (int k = 0; k < 3; k++)
        fprintf(f, "   <category value=\"%s\" symbol=\"%d\" label=\"%s\" render=\"true\"/>\n", value[k], k, value[k]);
    fprintf(f, "  </categories>\n  <symbols>\n");
    for (int k = 0; k < 3; k++) qml_symbol(f, k, fill, rgb[k], fill ? 0.35 : 1);
    fprintf(f, "  </symbols>\n </renderer-v2>\n");
    fprintf(f, " <labeling type=\"simple\">\n  <settings calloutType=\"simple\">\n"
               "   <text-style fieldName=\"camera\" fontSize=\"9\" textColor=\"0,0,0,255\"/>\n"
               "  </settings>\n </labeling>\n</qgis>\n");
}

// Points coloured by a metre-valued field on a ramp anchored at the need: green below need/2,
// yellow to the need, orange to twice the need, red beyond.
static void qml_ramp(FILE *f, const char *field, double need_m)
{
    static const int rgb[4][3] = {{26, 150, 65}, {255, 255, 64}, {253, 141, 60}, {215, 25, 28}};
    const double edge[5] = {0, need_m / 2, need_m, 2 * need_m, 1e9};
    qml_begin(f);
    fprintf(f,
            "<qgis version=\"3.22.0\" styleCategories=\"Symbology\">\n"
            " <renderer-v2 type=\"graduatedSymbol\" attr=\"%s\" graduatedMethod=\"GraduatedColor\" "
            "symbollevels=\"0\" enableorderby=\"0\" forceraster=\"0\">\n  <ranges>\n",
            field);
    for (int k = 0; k < 4; k++) {
        char label[64];
        if (k < 3)
            snprintf(label, sizeof label, "%g - %g m%s", edge[k], edge[k + 1], k == 1 ? " (the need)" : "");
        else
            snprintf(label, sizeof label, "over %g m", edge[k]);
        fprintf(f, "   <range lower=\"%g\" upper=\"%g\" symbol=\"%d\" label=\"%s\" render=\"true\"/>\n", edge[k],
                edge[k + 1], k, label);
    }
    fprintf(f, "  </ranges>\n  <symbols>\n");
    for (int k = 0; k < 4; k++) qml_symbol(f, k, false, rgb[k], 1);
    fprintf(f, "  </symbols>\n </renderer-v2>\n</qgis>\n");
}

// ---- layer_styles ----

typedef struct {
    const char *table, *name, *description;
    int kind; // 0: by verdict, points; 1: by verdict, polygons; 2: ramp of loo_ground_error_m
} style_def;

rs_status rs_report_export_styles(GDALDatasetH ds, const char *path, double need_m, rs_err *err)
{
    // the table as QGIS creates it (its "Save style in database"), so QGIS applies the default
    // style of each layer when it opens the file
    char **lco = CSLSetNameValue(NULL, "FID", "id");
    lco = CSLSetNameValue(lco, "DESCRIPTION", "QGIS layer styles (QML) of this file's layers");
    OGRLayerH t = GDALDatasetCreateLayer(ds, "layer_styles", NULL, wkbNone, lco);
    CSLDestroy(lco);
    if (!t) return rs_err_set(err, RS_ERR_EXTERNAL, "%s: cannot create layer_styles: %s", path, CPLGetLastErrorMsg());
    static const char *const text_fields[] = {"f_table_catalog", "f_table_schema",
                                              "f_table_name",    "f_geometry_column",
                                              "styleName",       "styleQML",
                                              "styleSLD",        "description",
                                              "owner",           "ui"};
    bool ok = true;
    for (size_t k = 0; k < sizeof text_fields / sizeof text_fields[0] && ok; k++) {
        OGRFieldDefnH fd = OGR_Fld_Create(text_fields[k], OFTString);
        ok = OGR_L_CreateField(t, fd, TRUE) == OGRERR_NONE;
        OGR_Fld_Destroy(fd);
        if (k == 7 && ok) { // useAsDefault between styleSLD and description, as QGIS has it
            OGRFieldDefnH b = OGR_Fld_Create("useAsDefault", OFTInteger);
            OGR_Fld_SetSubType(b, OFSTBoolean);
            ok = OGR_L_CreateField(t, b, TRUE) == OGRERR_NONE;
            OGR_Fld_Destroy(b);
        }
    }
    OGRFieldDefnH ut = OGR_Fld_Create("update_time", OFTDateTime);
    ok = ok && OGR_L_CreateField(t, ut, TRUE) == OGRERR_NONE;
    OGR_Fld_Destroy(ut);
    static const style_def styles[] = {
        {"cameras", "roadside: cameras by verdict", "cameras coloured by roadside audit's verdict", 0},
        {"footprints", "roadside: footprints by verdict", "the ground each camera sees, coloured by its verdict", 1},
        {"landmarks", "roadside: leave-one-out ground error",
         "landmarks coloured by the worst leave-one-out ground error, on a ramp anchored at the need", 2},
        {"picks", "roadside: leave-one-out ground error",
         "picks coloured by their leave-one-out ground error, on a ramp anchored at the need", 2},
    };
    for (size_t k = 0; k < sizeof styles / sizeof styles[0] && ok; k++) {
        char *qml = NULL;
        size_t len = 0;
        FILE *f = open_memstream(&qml, &len);
        if (!f) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", path);
        if (styles[k].kind == 2)
            qml_ramp(f, "loo_ground_error_m", need_m);
        else
            qml_by_verdict(f, styles[k].kind == 1);
        fclose(f);
        OGRFeatureH ft = OGR_F_Create(OGR_L_GetLayerDefn(t));
        ok = ft && qml;
        if (ok) {
            OGR_F_SetFieldString(ft, OGR_F_GetFieldIndex(ft, "f_table_catalog"), "");
            OGR_F_SetFieldString(ft, OGR_F_GetFieldIndex(ft, "f_table_schema"), "");
            OGR_F_SetFieldString(ft, OGR_F_GetFieldIndex(ft, "f_table_name"), styles[k].table);
            OGR_F_SetFieldString(ft, OGR_F_GetFieldIndex(ft, "f_geometry_column"), "geom");
            OGR_F_SetFieldString(ft, OGR_F_GetFieldIndex(ft, "styleName"), styles[k].name);
            OGR_F_SetFieldString(ft, OGR_F_GetFieldIndex(ft, "styleQML"), qml);
            OGR_F_SetFieldString(ft, OGR_F_GetFieldIndex(ft, "styleSLD"), "");
            OGR_F_SetFieldInteger(ft, OGR_F_GetFieldIndex(ft, "useAsDefault"), 1);
            OGR_F_SetFieldString(ft, OGR_F_GetFieldIndex(ft, "description"), styles[k].description);
            OGR_F_SetFieldString(ft, OGR_F_GetFieldIndex(ft, "owner"), "roadside");
            OGR_F_SetFieldString(ft, OGR_F_GetFieldIndex(ft, "ui"), "");
            ok = OGR_L_CreateFeature(t, ft) == OGRERR_NONE;
        }
        OGR_F_Destroy(ft);
        free(qml);
    }
    return ok ? RS_OK
              : rs_err_set(err, RS_ERR_EXTERNAL, "%s: cannot write layer_styles: %s", path, CPLGetLastErrorMsg());
}

void rs_report_export_metadata(GDALDatasetH ds, const rs_site *site, const char *calib_dir, double need_m)
{
    char buf[512];
    GDALSetMetadataItem(ds, "DESCRIPTION", "roadside export: a site's camera calibration for GIS", NULL);
    GDALSetMetadataItem(ds, "ROADSIDE_SITE", site->name ? site->name : "", NULL);
    GDALSetMetadataItem(ds, "ROADSIDE_SITE_DIR", site->dir, NULL);
    GDALSetMetadataItem(ds, "ROADSIDE_CALIB_DIR", calib_dir, NULL);
    snprintf(buf, sizeof buf, "%.9f, %.9f, %.4f (latitude, longitude in degrees, WGS84 ellipsoidal height, m)",
             site->origin.lat_deg, site->origin.lon_deg, site->origin.h_m);
    GDALSetMetadataItem(ds, "ROADSIDE_ENU_ORIGIN", buf, NULL);
    snprintf(buf, sizeof buf, "%g", need_m);
    GDALSetMetadataItem(ds, "ROADSIDE_NEED_GROUND_M", buf, NULL);
}
