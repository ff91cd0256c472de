// rs_site_import.c -- `roadside site import`: a site from point pairs and intrinsics
// (geo/rs_site_import.h). The point files are read by rs_site_import_read.c, converted to WGS84
// by geo/rs_geo_crs.h, written through geo/rs_site_write.h (site files) and core/rs_camera.h
// (camera models) into a temporary folder (rs_site__make_tmp, as `site init` does), checked by
// rs_site_check and renamed into place.
#include "geo/rs_site_import.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/rs_camera.h"
#include "core/rs_image.h"
#include "core/rs_io.h"
#include "core/rs_units.h"
#include "geo/internal/rs_site_import_points.h"
#include "geo/internal/rs_site_internal.h"
#include "geo/rs_geo_crs.h"
#include "geo/rs_site.h"
#include "geo/rs_site_write.h"

// The default landmark sigmas of each source (horizontal per axis, vertical), metres.
static const double source_sigma_m[3][2] = {{0.5, 0.5}, {0.05, 0.10}, {0.01, 0.02}};
static const char *const source_names[3] = {"map", "gnss", "survey"};
static const char *const source_words[3] = {"picked on a map or orthophoto", "RTK GNSS", "a survey"};

const char *rs_site_import_source_name(rs_site_import_source source)
{
    return (unsigned)source < 3 ? source_names[source] : NULL;
}

// Everything an import holds while it runs.
typedef struct {
    const rs_site_import_options *opt;
    rs_site__import_points *files; // (Ncameras,)
    char **camera_ids;             // (Ncameras,) owned
    char **images;                 // (Ncameras,) owned: camera c's frame, NULL when none
    rs_camera *cameras;            // (Ncameras,)
    rs_site_landmark *landmarks;   // (Nlandmarks,) id owned
    int Nlandmarks;
    rs_site_observation **obs; // (Ncameras,) each (files[c].N,)
    rs_site_height heights;    // site-wide landmark_heights
    rs_llh origin;             // in the declared heights
    double sigma_h_m, sigma_v_m, sigma_px, N_m;
    FILE *say; // the summary, one line per assumption
    char *said;
    size_t said_len;
} importer;

static void importer_free(importer *im)
{
    for (int c = 0; c < im->opt->Ncameras; c++) {
        if (im->files) rs_site__import_points_free(&im->files[c]);
        if (im->camera_ids) free(im->camera_ids[c]);
        if (im->images) free(im->images[c]);
        if (im->cameras) rs_camera_free(&im->cameras[c]);
        if (im->obs) free(im->obs[c]);
    }
    for (int i = 0; i < im->Nlandmarks; i++) free(im->landmarks[i].id);
    free(im->files), free(im->camera_ids), free(im->images), free(im->cameras), free(im->obs), free(im->landmarks);
    if (im->say) fclose(im->say);
    free(im->said);
}

// The file name of path without its folder and extension, into out (n bytes).
static void stem(char *out, size_t n, const char *path)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    const char *dot = strrchr(base, '.');
    const int len = dot && dot != base ? (int)(dot - base) : (int)strlen(base);
    snprintf(out, n, "%.*s", len, base);
}

// ---- coordinates ----

// files[c]'s points into WGS84 llh (N,3), heights as given (declared heights).
static rs_status to_llh(double *llh, const importer *im, int c, rs_err *err)
{
    const rs_site__import_points *f = &im->files[c];
    const char *path = im->opt->cameras[c].points, *crs = im->opt->crs;
    if (!crs && !f->geographic)
        return rs_err_set(err, RS_ERR_INVALID, "%s: header: e,n columns: give their CRS with --crs EPSG:NNNN", path);
    double *xyh = malloc((size_t)f->N * 3 * sizeof *xyh);
    if (!xyh) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; i < f->N; i++)
        xyh[3 * i] = f->points[i].x, xyh[3 * i + 1] = f->points[i].y, xyh[3 * i + 2] = f->points[i].h_m;
    rs_status st = RS_OK;
    bool geographic = f->geographic;
    int bad = -1;
    rs_err e = {0};
    if (crs)
        st = rs_geo_crs_to_llh(llh, &geographic, &bad, crs, xyh, f->N, &e);
    else
        for (int i = 0; i < f->N; i++)
            llh[3 * i] = xyh[3 * i + 1], llh[3 * i + 1] = xyh[3 * i], llh[3 * i + 2] = xyh[3 * i + 2];
    if (geographic != f->geographic) // the columns and the CRS disagree: that, before what PROJ made of it
        st = rs_err_set(err, RS_ERR_INVALID, "%s: header: %s columns, but --crs %s is a %s CRS (its columns are %s)",
                        path, f->geographic ? "lat,lon" : "e,n", crs, geographic ? "geographic" : "projected",
                        geographic ? "lat,lon" : "e,n");
    else if (st && bad >= 0)
        rs_err_set(err, st, "%s:%d: %s: %s", path, f->points[bad].line, f->geographic ? "lat,lon" : "e,n", e.msg);
    else if (st)
        rs_err_set(err, st, "%s: %s", path, e.msg);
    free(xyh);
    return st;
}

// The landmarks and observations of every file, the site-wide heights and the origin.
static rs_status gather(importer *im, rs_err *err)
{
    int total = 0;
    bool any_h = false;
    for (int c = 0; c < im->opt->Ncameras; c++) {
        total += im->files[c].N;
        for (int i = 0; i < im->files[c].N; i++) {
            any_h = any_h || isfinite(im->files[c].points[i].h_m);
        }
    }
    im->heights = !any_h                                  ? RS_SITE_HEIGHT_UNKNOWN
                  : im->opt->source == RS_SITE_IMPORT_MAP ? RS_SITE_HEIGHT_UNRELIABLE
                                                          : RS_SITE_HEIGHT_SURVEYED;
    if (!(im->landmarks = calloc((size_t)total, sizeof *im->landmarks)))
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    double sum[3] = {0, 0, 0};
    int Nh = 0;
    rs_status st = RS_OK;
    for (int c = 0; c < im->opt->Ncameras && st == RS_OK; c++) {
        const rs_site__import_points *f = &im->files[c];
        double *llh = malloc((size_t)f->N * 3 * sizeof *llh);
        im->obs[c] = calloc((size_t)f->N, sizeof *im->obs[c]);
        st = llh && im->obs[c] ? to_llh(llh, im, c, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        for (int i = 0; st == RS_OK && i < f->N; i++) {
            rs_site_landmark *l = &im->landmarks[im->Nlandmarks];
            const size_t n = strlen(im->camera_ids[c]) + strlen(f->points[i].id) + 2;
            if (!(l->id = malloc(n))) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            if (st) break;
            snprintf(l->id, n, im->opt->Ncameras > 1 ? "%s:%s" : "%.0s%s", im->camera_ids[c], f->points[i].id);
            l->llh = (rs_llh){llh[3 * i], llh[3 * i + 1], llh[3 * i + 2] + im->N_m};
            l->sigma_h_m = l->sigma_v_m = NAN;
            l->height = isfinite(l->llh.h_m) ? im->heights : RS_SITE_HEIGHT_UNKNOWN;
            l->height_stated = l->height == im->heights ? RS_SITE_HEIGHT_DEFAULT : RS_SITE_HEIGHT_UNKNOWN;
            sum[0] += l->llh.lat_deg, sum[1] += l->llh.lon_deg;
            if (isfinite(llh[3 * i + 2])) sum[2] += llh[3 * i + 2], Nh++;
            const double s = f->points[i].sigma_px;
            im->obs[c][i] = (rs_site_observation){.ilandmark = im->Nlandmarks++,
                                                  .q_px = {f->points[i].q_px[0], f->points[i].q_px[1]},
                                                  .sigma_px = isfinite(s) ? s : im->sigma_px,
                                                  .line = f->points[i].line};
        }
        free(llh);
    }
    im->origin = (rs_llh){sum[0] / total, sum[1] / total, Nh ? sum[2] / Nh : 0};
    return st;
}

// ---- cameras ----

// The image beside `points` with the same name, if any: into out (n bytes; "" when none).
static void image_beside(char *out, size_t n, const char *points)
{
    static const char *const exts[] = {".jpg", ".jpeg", ".png", ".tif", ".tiff", ".bmp", ".JPG", ".JPEG", ".PNG"};
    const char *dot = strrchr(points, '.'), *slash = strrchr(points, '/');
    const int len = dot && (!slash || dot > slash) ? (int)(dot - points) : (int)strlen(points);
    struct stat sb;
    for (size_t i = 0; i < sizeof exts / sizeof exts[0]; i++) {
        snprintf(out, n, "%.*s%s", len, points, exts[i]);
        if (stat(out, &sb) == 0 && S_ISREG(sb.st_mode)) return;
    }
    out[0] = '\0';
}

// Camera c's image size: its image's (given or beside its points; --image-size must agree), else
// --image-size, else 0 x 0.
static rs_status image_size(int *w, int *h, char *image, size_t n, const importer *im, int c, rs_err *err)
{
    const rs_site_import_camera *cam = &im->opt->cameras[c];
    *w = im->opt->width, *h = im->opt->height;
    if (cam->image)
        snprintf(image, n, "%s", cam->image);
    else
        image_beside(image, n, cam->points);
    if (!image[0]) return RS_OK;
    rs_image img;
    rs_status st = rs_image_read(&img, image, err);
    if (st) return st;
    if (*w > 0 && (img.width != *w || img.height != *h))
        st = rs_err_set(err, RS_ERR_INVALID, "%s: the image is %d x %d px, --image-size says %d x %d", image, img.width,
                        img.height, *w, *h);
    *w = img.width, *h = img.height;
    rs_image_free(&img);
    return st;
}

// Camera c's lens: the intrinsics file, or a nominal pinhole; its image size checked.
static rs_status make_camera(importer *im, int c, rs_err *err)
{
    char image[4096];
    int w, h;
    rs_status st = image_size(&w, &h, image, sizeof image, im, c, err);
    if (st) return st;
    if (image[0] && !(im->images[c] = strdup(image))) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_camera *cam = &im->cameras[c];
    const char *intr = im->opt->intrinsics, *id = im->camera_ids[c];
    if (!intr) {
        if (w < 1)
            return rs_err_set(err, RS_ERR_INVALID,
                              "camera '%s': no image size: give --image-size WxH, --image IMG, or an image beside %s",
                              id, im->opt->cameras[c].points);
        const double pinhole[4] = {w, w, (w - 1) / 2.0, (h - 1) / 2.0};
        const mrcal_lensmodel_t lm = {.type = MRCAL_LENSMODEL_PINHOLE};
        fprintf(im->say,
                "camera '%s': no intrinsics: a nominal pinhole for the image of %d x %d px%s%s%s: f = %d px (the "
                "image width: %.0f degrees across), centre the image's; calibrate with 'roadside calib SITE --refine "
                "focal'\n",
                id, w, h, image[0] ? " (the size of " : "", image, image[0] ? ")" : "", w,
                2 * atan(0.5) * RS_DEG_PER_RAD);
        return rs_camera_init(cam, &lm, pinhole, w, h, err);
    }
    if ((st = rs_camera_read(cam, NULL, intr, err))) return st;
    if (cam->width > 0 && w > 0 && (cam->width != w || cam->height != h))
        return rs_err_set(err, RS_ERR_INVALID, "%s: image size %d x %d, but camera '%s''s image %s is %d x %d", intr,
                          cam->width, cam->height, id, image[0] ? image : "(--image-size)", w, h);
    if (cam->width < 1 && w < 1)
        return rs_err_set(err, RS_ERR_INVALID, "%s: no image size: give --image-size WxH or an image", intr);
    if (cam->width < 1) cam->width = w, cam->height = h;
    fprintf(im->say, "camera '%s': lens %s from %s, image %d x %d px%s%s%s\n", id,
            mrcal_lensmodel_name_unconfigured(&cam->lensmodel), intr, cam->width, cam->height,
            image[0] ? " (the size of " : "", image, image[0] ? ")" : "");
    return RS_OK;
}

// ---- writing ----

// Camera c's files, relative to the site folder, into f[0..2] (n bytes each):
// "cameras/<id>.cameramodel", "observations/<id>.csv", "backgrounds/<id>".
static bool camera_files(char f[3][1024], const char *id)
{
    return rs_camera_path(f[0], 1024, RS_SITE_CAMERAS_DIR, id, RS_CAMERA_EXT_CAMERAMODEL) &&
           rs_camera_path(f[1], 1024, RS_SITE_OBSERVATIONS_DIR, id, RS_SITE_OBSERVATIONS_EXT) &&
           rs_camera_path(f[2], 1024, "backgrounds", id, "");
}

// The camera's frame copied to "backgrounds/<id>/frame.<ext>" (a PNG or JPEG: what the report
// shows; other images are not copied): *copied says whether it was.
static rs_status copy_frame(bool *copied, const char *image, const char *tmp, const char *bg_dir, rs_err *err)
{
    *copied = false;
    const char *ext = strrchr(image, '.'), *slash = strrchr(image, '/');
    if (!ext || (slash && ext < slash) ||
        !(rs_io_has_extension(image, "png") || rs_io_has_extension(image, "jpg") || rs_io_has_extension(image, "jpeg")))
        return RS_OK;
    char rel[1100];
    snprintf(rel, sizeof rel, "%s/frame%s", bg_dir, ext);
    char *dir = rs_io_join(tmp, bg_dir), *out = rs_io_join(tmp, rel), *data = NULL;
    size_t len = 0;
    rs_status st = dir && out ? rs_io_mkdir_p(dir, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (st == RS_OK) st = rs_io_read_file_max(&data, &len, image, RS_IO_MAX_FILE_BYTES, err);
    if (st == RS_OK) st = rs_io_write_file(out, data, len, err);
    *copied = st == RS_OK;
    free(dir), free(out), free(data);
    return st;
}

static rs_status write_site_json(const importer *im, const char *tmp, const char *name, rs_err *err)
{
    const int Nc = im->opt->Ncameras;
    rs_site_spec_camera *cams = calloc((size_t)Nc, sizeof *cams);
    char(*files)[3][1024] = calloc((size_t)Nc, sizeof *files), (*notes)[1200] = calloc((size_t)Nc, sizeof *notes);
    rs_status st = cams && files && notes ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int c = 0; st == RS_OK && c < Nc; c++) {
        if (!camera_files(files[c], im->camera_ids[c]))
            st = rs_err_set(err, RS_ERR_INVALID, "camera '%s': id too long for a file name", im->camera_ids[c]);
        snprintf(notes[c], sizeof notes[c], "imported from %s", im->opt->cameras[c].points);
        cams[c] = (rs_site_spec_camera){.id = im->camera_ids[c],
                                        .model = files[c][0],
                                        .observations = files[c][1],
                                        .backgrounds = im->images[c] ? files[c][2] : NULL,
                                        .note = notes[c]};
    }
    const rs_site_spec spec = {.name = name,
                               .origin = im->origin,
                               .geoid_undulation_m = im->opt->geoid_undulation_m,
                               .landmark_sigma_h_m = im->sigma_h_m,
                               .landmark_sigma_v_m = im->sigma_v_m,
                               .landmark_heights = im->heights,
                               .cameras = cams,
                               .Ncameras = Nc};
    if (st == RS_OK) st = rs_site_write_json(tmp, &spec, RS_SITE_LAYOUT_HAND, err);
    free(cams), free(files), free(notes);
    return st;
}

static rs_status write_site(importer *im, const char *tmp, const char *name, rs_err *err)
{
    rs_status st = RS_OK;
    const char *const dirs[2] = {RS_SITE_CAMERAS_DIR, RS_SITE_OBSERVATIONS_DIR};
    for (int i = 0; i < 2 && st == RS_OK; i++) {
        char *p = rs_io_join(tmp, dirs[i]);
        st = p ? rs_io_mkdir_p(p, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(p);
    }
    if (st == RS_OK) st = write_site_json(im, tmp, name, err);
    if (st == RS_OK)
        st = rs_site_write_landmarks(tmp, im->landmarks, im->Nlandmarks, im->N_m, RS_SITE_LAYOUT_HAND, err);
    for (int c = 0; st == RS_OK && c < im->opt->Ncameras; c++) {
        char f[3][1024];
        camera_files(f, im->camera_ids[c]);
        char *pm = rs_io_join(tmp, f[0]), *po = rs_io_join(tmp, f[1]);
        st = pm && po ? rs_camera_write_cameramodel(&im->cameras[c], pm, err)
                      : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (st == RS_OK) st = rs_site_write_observations(po, im->obs[c], im->files[c].N, im->landmarks, err);
        free(pm), free(po);
        bool copied = false;
        if (st == RS_OK && im->images[c]) st = copy_frame(&copied, im->images[c], tmp, f[2], err);
        if (copied)
            fprintf(im->say, "camera '%s': its frame %s copied into %s/ (the report shows it)\n", im->camera_ids[c],
                    im->images[c], f[2]);
    }
    return st;
}

// line with every occurrence of tmp replaced by dir, into out (n bytes).
static void as_named(char *out, size_t n, const char *line, const char *tmp, const char *dir)
{
    const size_t nt = strlen(tmp);
    size_t k = 0;
    for (const char *p = line; *p && k + 1 < n;) {
        if (!strncmp(p, tmp, nt)) {
            k += (size_t)snprintf(out + k, n - k, "%s", dir);
            p += nt;
        } else {
            out[k++] = *p++;
        }
        if (k >= n) k = n - 1;
    }
    out[k] = '\0';
}

// rs_site_check on the folder built: an error fails the import (files named as in `dir`), a
// warning goes into the summary.
static rs_status check_built(importer *im, const char *tmp, const char *dir, rs_err *err)
{
    rs_site_report *report = NULL;
    rs_status st = rs_site_check(&report, tmp, err);
    char line[2048], named[2048];
    for (int i = 0; st == RS_OK && i < report->N; i++) {
        rs_site_diag_format(line, sizeof line, &report->diags[i]);
        as_named(named, sizeof named, line, tmp, dir);
        if (report->diags[i].severity == RS_SITE_ERROR)
            st = rs_err_set(err, RS_ERR_INVALID, "the imported site would not pass 'site check': %s", named);
        else
            fprintf(im->say, "site check: %s\n", named);
    }
    rs_site_report_free(report);
    return st;
}

// Renames tmp into place as dir; with force, an existing site folder (it holds site.json) is
// moved aside first, and removed once the new one is in place.
static rs_status move_into_place(const char *tmp, const char *dir, bool exists, bool force, rs_err *err)
{
    if (!exists || !force) {
        if (rename(tmp, dir) == 0) return RS_OK;
        return rs_err_set(err, RS_ERR_IO, "%s: cannot rename %s into place: %s", dir, tmp, strerror(errno));
    }
    char *old = NULL;
    rs_status st = rs_site__make_tmp(&old, dir, err); // a free name next to it, for the old site
    if (st) return st;
    rmdir(old);
    if (rename(dir, old) != 0) {
        st = rs_err_set(err, RS_ERR_IO, "%s: cannot move the old site aside: %s", dir, strerror(errno));
    } else if (rename(tmp, dir) != 0) {
        st = rs_err_set(err, RS_ERR_IO, "%s: cannot rename %s into place: %s", dir, tmp, strerror(errno));
        rename(old, dir);
    } else {
        rs_io_remove_tree(old);
    }
    free(old);
    return st;
}

// dir may be replaced: it does not exist, is empty, or (with force) is a site folder.
static rs_status check_dir(bool *exists, const char *dir, bool force, rs_err *err)
{
    rs_err e = {0};
    rs_status st = rs_site__check_target(dir, exists, &e);
    if (st != RS_ERR_INVALID) return st == RS_OK ? RS_OK : rs_err_set(err, st, "%s", e.msg);
    struct stat sb;
    if (stat(dir, &sb) != 0 || !S_ISDIR(sb.st_mode)) return rs_err_set(err, st, "%s", e.msg); // not a folder
    char *json = rs_io_join(dir, RS_SITE_JSON);
    const bool site = json && stat(json, &sb) == 0 && S_ISREG(sb.st_mode);
    free(json);
    *exists = true;
    if (force && site) return RS_OK;
    return rs_err_set(err, RS_ERR_INVALID, "%s: exists and is not empty: not overwriting it%s", dir,
                      force ? " (--force replaces only a site folder, one with site.json)"
                            : " (--force replaces a site)");
}

// ---- the import ----

static void say_assumptions(importer *im)
{
    const rs_site_import_options *o = im->opt;
    fprintf(im->say, "coordinates: %s%s\n", o->crs ? o->crs : "WGS84 latitude, longitude (EPSG:4326)",
            o->crs ? ", converted to WGS84 by PROJ (through GDAL)" : "");
    fprintf(im->say, "origin: the centroid of the %d landmarks: lat %.9f, lon %.9f, h %.3f m%s\n", im->Nlandmarks,
            im->origin.lat_deg, im->origin.lon_deg, im->origin.h_m,
            im->heights == RS_SITE_HEIGHT_UNKNOWN ? " (nominal: no heights given)" : " (the mean given height)");
    if (im->heights == RS_SITE_HEIGHT_UNKNOWN)
        fprintf(im->say,
                "heights: none given: \"landmark_heights\": \"unknown\": every landmark is on the site's "
                "ground model, the level plane through the origin, sigma_v %g m\n",
                im->sigma_v_m);
    else
        fprintf(im->say, "heights: %s (%s); points without one get the ground model's\n",
                rs_site_height_name(im->heights),
                im->heights == RS_SITE_HEIGHT_UNRELIABLE ? "map heights: the ground model's plane replaces them"
                                                         : "used as given");
    fprintf(im->say, "landmark sigmas: %g m horizontal, %g m vertical (%s%s: %s)\n", im->sigma_h_m, im->sigma_v_m,
            o->sigma_h_m > 0 || o->sigma_v_m > 0 ? "given, else " : "", "source", source_words[o->source]);
    if (o->Ncameras > 1)
        fprintf(im->say, "landmark ids: <camera>:<id> (each file's ids are its own: a landmark two cameras see is "
                         "two landmarks, which site check names as at the same position)\n");
    fprintf(im->say,
            "picks: sigma %g px where a row gives none; pixels as given, (0, 0) the centre of the top-left "
            "pixel\n",
            im->sigma_px);
}

// Reads every file and makes every camera (nothing written yet).
static rs_status prepare(importer *im, rs_err *err)
{
    const rs_site_import_options *o = im->opt;
    rs_status st = RS_OK;
    for (int c = 0; st == RS_OK && c < o->Ncameras; c++) {
        char id[256];
        stem(id, sizeof id, o->cameras[c].points);
        const char *cid = o->cameras[c].id ? o->cameras[c].id : id, *bad = rs_io_name_problem(cid);
        if (bad) st = rs_err_set(err, RS_ERR_INVALID, "camera id '%.64s' %s (--camera ID names it)", cid, bad);
        for (int k = 0; st == RS_OK && k < c; k++)
            if (!strcmp(im->camera_ids[k], cid))
                st = rs_err_set(err, RS_ERR_INVALID, "camera id '%s' twice (--camera ID names each)", cid);
        if (st == RS_OK && !(im->camera_ids[c] = strdup(cid))) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        if (st == RS_OK) st = rs_site__import_read(&im->files[c], o->cameras[c].points, err);
        if (st == RS_OK)
            fprintf(im->say, "camera '%s': %d points from %s\n", cid, im->files[c].N, o->cameras[c].points);
    }
    for (int c = 0; st == RS_OK && c < o->Ncameras; c++) st = make_camera(im, c, err);
    if (st == RS_OK) st = gather(im, err);
    return st;
}

static rs_status import_into(importer *im, const char *dir, rs_err *err)
{
    const rs_site_import_options *o = im->opt;
    bool exists = false;
    rs_status st = check_dir(&exists, dir, o->force, err);
    if (st == RS_OK) st = prepare(im, err);
    if (st) return st;
    char name[256];
    stem(name, sizeof name, dir);
    char *tmp = NULL;
    if ((st = rs_site__make_tmp(&tmp, dir, err))) return st;
    st = write_site(im, tmp, o->name ? o->name : name, err);
    if (st == RS_OK) st = check_built(im, tmp, dir, err);
    if (st == RS_OK) st = move_into_place(tmp, dir, exists, o->force, err);
    if (st) rs_io_remove_tree(tmp);
    free(tmp);
    return st;
}

rs_status rs_site_import(char **summary, const char *dir, const rs_site_import_options *opt, rs_err *err)
{
    if (summary) *summary = NULL;
    if (!opt || opt->Ncameras < 1 || !opt->cameras || (unsigned)opt->source > RS_SITE_IMPORT_SURVEY)
        return rs_err_set(err, RS_ERR_USAGE, "rs_site_import: no point file");
    if (opt->geoid_undulation_m && !(fabs(*opt->geoid_undulation_m) < 120))
        return rs_err_set(err, RS_ERR_INVALID, "heights.orthometric: %g m is not a geoid undulation",
                          *opt->geoid_undulation_m);
    const int Nc = opt->Ncameras;
    importer im = {.opt = opt,
                   .files = calloc((size_t)Nc, sizeof *im.files),
                   .camera_ids = calloc((size_t)Nc, sizeof *im.camera_ids),
                   .images = calloc((size_t)Nc, sizeof *im.images),
                   .cameras = calloc((size_t)Nc, sizeof *im.cameras),
                   .obs = calloc((size_t)Nc, sizeof *im.obs),
                   .sigma_h_m = opt->sigma_h_m > 0 ? opt->sigma_h_m : source_sigma_m[opt->source][0],
                   .sigma_v_m = opt->sigma_v_m > 0 ? opt->sigma_v_m : source_sigma_m[opt->source][1],
                   .sigma_px = opt->sigma_px > 0 ? opt->sigma_px : RS_SITE_IMPORT_SIGMA_PX,
                   .N_m = opt->geoid_undulation_m ? *opt->geoid_undulation_m : 0};
    im.say = open_memstream(&im.said, &im.said_len);
    rs_status st = im.files && im.camera_ids && im.images && im.cameras && im.obs && im.say
                       ? import_into(&im, dir, err)
                       : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (st == RS_OK) say_assumptions(&im);
    if (im.say) fclose(im.say);
    im.say = NULL;
    if (st == RS_OK && summary) *summary = im.said, im.said = NULL;
    importer_free(&im);
    return st;
}
