// rs_site_init.c -- a skeleton site folder for a surveyor to fill in (rs_site_init, geo/rs_site.h):
// its folders and README here, its site.json, landmarks.geojson and header-only observations
// through geo's writer (rs_site_write.c), in the hand layout. Calls rs_site_write.c and core/.
//
// The folder is built under a temporary name next to `dir` and renamed into place at the end,
// so a failure never leaves a half-made site behind under the final name.
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/rs_io.h"
#include "geo/internal/rs_site_internal.h"
#include "geo/rs_site.h"
#include "geo/rs_site_write.h"

// The files and folders of a skeleton, relative to the site folder, in creation order.
static const char *const skeleton_dirs[] = {"cameras", "observations", "backgrounds", "backgrounds/cam1"};
static const char *const skeleton_files[] = {RS_SITE_JSON, RS_SITE_LANDMARKS,
                                             RS_SITE_OBSERVATIONS_DIR "/cam1" RS_SITE_OBSERVATIONS_EXT, "README.md"};
enum {
    NDIRS = sizeof skeleton_dirs / sizeof skeleton_dirs[0],
    NFILES = sizeof skeleton_files / sizeof skeleton_files[0]
};

static const char *const readme_format =
    "# Site '%s': what to fill in\n"
    "\n"
    "This folder was made by `roadside site init`. It becomes a usable site once it has\n"
    "landmarks, a lens model for every camera and at least 4 picked landmarks per camera.\n"
    "`roadside site check %s` lists exactly what is still missing or wrong; it exits 0 only\n"
    "when the site can be calibrated. The full format: docs/site-format.md.\n"
    "\n"
    "## 1. site.json\n"
    "\n"
    "- `origin`: the point the local east-north-up frame starts from, near the middle of the\n"
    "  site, on the ground: latitude and longitude in decimal degrees (WGS84), height in metres.\n"
    "- `heights`: `\"ellipsoidal\"` if your heights are above the WGS84 ellipsoid (raw GNSS), or\n"
    "  `{\"orthometric\": N}` if they are above sea level / a national height datum, with N the\n"
    "  geoid undulation at the site in metres (h_ellipsoidal = h_orthometric + N; e.g. about 47 m\n"
    "  in Bavaria, 36 m in Paris). Every height in the site (origin, landmarks, camera\n"
    "  positions) uses this one convention.\n"
    "- `landmark_sigma_m`: the 1-sigma accuracy of your landmark coordinates, horizontal and\n"
    "  vertical, in metres: about 0.02-0.05 for RTK GNSS, 0.1-0.3 for a good orthophoto or\n"
    "  cadastral map, 0.5-1 for a web map. A landmark can override it with `sigma_h_m` and\n"
    "  `sigma_v_m`. Too small a sigma makes the calibration over-confident.\n"
    "- `cameras`: one entry per camera. `cam1` is an example: rename it (the id is free text),\n"
    "  and point `model` and `observations` at its files. Optional: `backgrounds` (a folder of\n"
    "  images of the empty scene), `position_prior` ({lat, lon, h, sigma_m}: the surveyed\n"
    "  position of the camera, e.g. its pole) and `note`.\n"
    "- Optional: `ground_plane` ({\"normal_enu\": [0, 0, 1], \"offset_m\": 0}: n . p = offset in\n"
    "  ENU metres; default: the horizontal plane through the origin) and\n"
    "  `max_landmark_distance_m` (default 1000: check warns about landmarks farther away).\n"
    "\n"
    "## 2. landmarks.geojson\n"
    "\n"
    "One GeoJSON Point feature per landmark:\n"
    "\n"
    "    {\"type\": \"Feature\",\n"
    "     \"geometry\": {\"type\": \"Point\", \"coordinates\": [11.57512, 48.13706, 520.31]},\n"
    "     \"properties\": {\"id\": \"L01\", \"kind\": \"lane-marking-corner\"}}\n"
    "\n"
    "- Coordinates are **[longitude, latitude, height]** (RFC 7946 order: longitude first!),\n"
    "  decimal degrees (not degrees-minutes-seconds, not radians) and metres. `site check`\n"
    "  recognises swapped latitude/longitude and radians and says what the point should be.\n"
    "- `id`: a unique text, the name you use in the observation files.\n"
    "- Pick points that are sharp in the image and on the ground: corners of lane markings,\n"
    "  stop lines, zebra stripes, manhole covers, kerb corners, bases of poles. Not tops of\n"
    "  poles or trees (they move, and their height is hard to survey).\n"
    "- Spread them over the whole image and over a range of distances; 8-20 per camera is\n"
    "  good, 4 is the minimum. Avoid having them all on one straight line.\n"
    "\n"
    "## 3. cameras/<id>.cameramodel (or .yaml / .json)\n"
    "\n"
    "The lens of each camera, with the image size of the frames you pick pixels in:\n"
    "\n"
    "- an mrcal model: calibrate with a chessboard using `mrcal-calibrate-cameras`\n"
    "  (e.g. `--lensmodel LENSMODEL_OPENCV8`), or write one by hand for a known pinhole:\n"
    "  `{'lensmodel': 'LENSMODEL_PINHOLE', 'intrinsics': [fx, fy, cx, cy],\n"
    "  'imagersize': [width, height], 'extrinsics': [0, 0, 0, 0, 0, 0]}`;\n"
    "- or OpenCV intrinsics as written by `cv::FileStorage` (cv2.FileStorage) after\n"
    "  `calibrateCamera`: fields `image_width`, `image_height`, `camera_matrix` (3x3) and\n"
    "  `distortion_coefficients` (0, 4, 5, 8 or 12 values).\n"
    "\n"
    "## 4. observations/<id>.csv\n"
    "\n"
    "The pixel position of each landmark you can see, picked in a full-resolution frame:\n"
    "\n"
    "    landmark,u,v,sigma_px\n"
    "    L01,812.5,604.0,\n"
    "    L02,1190.25,655.5,2\n"
    "\n"
    "- `u` to the right, `v` down, in pixels; (0,0) is the CENTRE of the top-left pixel, so\n"
    "  subtract 0.5 from coordinates of tools that put (0,0) at the pixel's corner.\n"
    "- Decimal points, not commas. `sigma_px` (optional, default 1) is the pick uncertainty.\n"
    "\n"
    "## 5. backgrounds/<id>/\n"
    "\n"
    "Optional: images of the empty scene from that camera, for synthesising training data.\n";

// The example camera of the skeleton.
static const rs_site_spec_camera example_camera = {
    .id = "cam1",
    .model = RS_SITE_CAMERAS_DIR "/cam1" RS_CAMERA_EXT_CAMERAMODEL,
    .observations = RS_SITE_OBSERVATIONS_DIR "/cam1" RS_SITE_OBSERVATIONS_EXT,
    .backgrounds = "backgrounds/cam1",
    .note = "example camera: rename it, add its model and its picks (README.md)",
};

// The files of the skeleton (skeleton_files, in that order) into the folder `tmp`; `dir` is
// the name the README gives the folder.
static rs_status write_skeleton(const char *tmp, const char *dir, const char *name, const rs_llh *origin,
                                const double *geoid_undulation_m, rs_err *err)
{
    const rs_site_spec spec = {
        .name = name,
        .origin = *origin,
        .geoid_undulation_m = geoid_undulation_m,
        .landmark_sigma_h_m = 0.3,
        .landmark_sigma_v_m = 0.5,
        .max_landmark_distance_m = 1000,
        .cameras = &example_camera,
        .Ncameras = 1,
    };
    rs_status st = rs_site_write_json(tmp, &spec, RS_SITE_LAYOUT_HAND, err);
    if (st == RS_OK) st = rs_site_write_landmarks(tmp, NULL, 0, 0, RS_SITE_LAYOUT_HAND, err);
    char *obs = rs_io_join(tmp, example_camera.observations), *readme = rs_io_join(tmp, "README.md");
    if (st == RS_OK && (!obs || !readme)) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (st == RS_OK) st = rs_site_write_observations(obs, NULL, 0, NULL, err);
    if (st == RS_OK) {
        int len = snprintf(NULL, 0, readme_format, name, dir);
        char *text = len < 0 ? NULL : malloc((size_t)len + 1);
        if (text) snprintf(text, (size_t)len + 1, readme_format, name, dir);
        st = text ? rs_io_write_file(readme, text, (size_t)len, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(text);
    }
    free(obs);
    free(readme);
    return st;
}

rs_status rs_site__check_target(const char *dir, bool *exists, rs_err *err)
{
    struct stat sb;
    *exists = false;
    if (stat(dir, &sb) != 0) {
        if (errno == ENOENT) return RS_OK;
        return rs_err_set(err, RS_ERR_IO, "%s: %s", dir, strerror(errno));
    }
    if (!S_ISDIR(sb.st_mode))
        return rs_err_set(err, RS_ERR_INVALID, "%s: exists and is not a folder: not overwriting it", dir);
    DIR *d = opendir(dir);
    if (!d) return rs_err_set(err, RS_ERR_IO, "%s: %s", dir, strerror(errno));
    bool empty = true;
    for (struct dirent *e; empty && (e = readdir(d));) empty = !strcmp(e->d_name, ".") || !strcmp(e->d_name, "..");
    closedir(d);
    if (!empty) return rs_err_set(err, RS_ERR_INVALID, "%s: exists and is not empty: not overwriting it", dir);
    *exists = true;
    return RS_OK;
}

// Removes what a partial skeleton under `tmp` may hold (ignoring what is not there).
static void remove_skeleton(const char *tmp)
{
    for (int i = NFILES - 1; i >= 0; i--) {
        char *p = rs_io_join(tmp, skeleton_files[i]);
        if (p) unlink(p);
        free(p);
    }
    for (int i = NDIRS - 1; i >= 0; i--) {
        char *p = rs_io_join(tmp, skeleton_dirs[i]);
        if (p) rmdir(p);
        free(p);
    }
    rmdir(tmp);
}

rs_status rs_site__make_tmp(char **tmp_out, const char *dir, rs_err *err)
{
    *tmp_out = NULL;
    size_t n = strlen(dir);
    while (n > 1 && dir[n - 1] == '/') n--;
    char *tmp = malloc(n + sizeof ".tmp.XXXXXX");
    if (!tmp) return rs_err_set(err, RS_ERR_NOMEM, "%s: out of memory", dir);
    memcpy(tmp, dir, n);
    memcpy(tmp + n, ".tmp.XXXXXX", sizeof ".tmp.XXXXXX");
    rs_status st = RS_OK;
    char *slash = strrchr(tmp, '/');
    if (slash && slash != tmp) {
        *slash = '\0';
        st = rs_io_mkdir_p(tmp, err);
        *slash = '/';
    }
    if (st == RS_OK && !mkdtemp(tmp))
        st = rs_err_set(err, RS_ERR_IO, "%s: cannot create a temporary folder next to it: %s", dir, strerror(errno));
    if (st != RS_OK) {
        free(tmp);
        return st;
    }
    mode_t mask = umask(0); // mkdtemp makes 0700; a site is an ordinary folder
    umask(mask);
    chmod(tmp, 0777 & ~mask);
    *tmp_out = tmp;
    return RS_OK;
}

rs_status rs_site_init(const char *dir, const char *name, const rs_llh *origin, const double *geoid_undulation_m,
                       rs_err *err)
{
    if (!(isfinite(origin->lat_deg) && isfinite(origin->lon_deg) && isfinite(origin->h_m)) ||
        fabs(origin->lat_deg) > 90 || fabs(origin->lon_deg) > 180)
        return rs_err_set(err, RS_ERR_INVALID,
                          "origin: (%g, %g, %g) is not lat in [-90, 90], lon in [-180, 180], finite h", origin->lat_deg,
                          origin->lon_deg, origin->h_m);
    if (geoid_undulation_m && !(fabs(*geoid_undulation_m) <= 120))
        return rs_err_set(err, RS_ERR_INVALID, "heights.orthometric: %g m is not a geoid undulation",
                          *geoid_undulation_m);
    if (!name || !*name) return rs_err_set(err, RS_ERR_INVALID, "name: empty");
    bool exists;
    rs_status st = rs_site__check_target(dir, &exists, err);
    if (st != RS_OK) return st;

    // Build under "<dir>.tmp.XXXXXX" in the same parent, then rename: rename(2) replaces an
    // empty folder atomically.
    char *tmp = NULL;
    if ((st = rs_site__make_tmp(&tmp, dir, err)) != RS_OK) return st;

    char *path = NULL;
    for (int i = 0; i < NDIRS && st == RS_OK; i++) {
        path = rs_io_join(tmp, skeleton_dirs[i]);
        st = path ? rs_io_mkdir_p(path, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(path);
    }
    if (st == RS_OK) st = write_skeleton(tmp, dir, name, origin, geoid_undulation_m, err);
    if (st == RS_OK && rename(tmp, dir) != 0)
        st = rs_err_set(err, RS_ERR_IO, "%s: cannot rename %s into place: %s%s", dir, tmp, strerror(errno),
                        exists ? " (did the folder stop being empty?)" : "");
    if (st != RS_OK) remove_skeleton(tmp);
    free(tmp);
    return st;
}
