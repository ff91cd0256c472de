// rs_eval_ground.c -- metric thresholds: every point to the ground through its image's camera.
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_camera.h"
#include "core/rs_io.h"
#include "eval/internal/rs_eval_internal.h"
#include "eval/localise/rs_localise_dataset.h"
#include "geo/rs_site.h"

// Points whose rays miss the ground are parked far away, detections and ground truths on
// opposite sides, so that they match nothing (the distance squared stays finite: 4e300).
static const double MISSED_DET = 1e150, MISSED_GT = -1e150;

// Replaces q (2,) by its ground (E, N), or by (missed, missed) when the ray misses the ground
// plane n . p_enu = offset.
static bool to_ground_plane(double *q, const rs_camera *cam, const double n_enu[3], double offset_m, double missed)
{
    double p[3];
    if (rs_camera_locate_ground(p, cam, q, n_enu, offset_m, NULL) != RS_OK) {
        q[0] = q[1] = missed;
        return false;
    }
    q[0] = p[0];
    q[1] = p[1];
    return true;
}

static bool to_ground(double *q, const rs_camera *cam, const rs_site *site, double missed)
{
    return to_ground_plane(q, cam, site->ground_normal_enu, site->ground_offset_m, missed);
}

rs_status rs_eval_data_to_ground(rs_eval_data *d, const rs_site *site, const char *calib_dir, size_t *Nmissed,
                                 rs_err *err)
{
    if (Nmissed) *Nmissed = 0;
    if (!d->image_camera) return rs_err_set(err, RS_ERR_INVALID, "the ground truth was loaded without a camera field");
    if (d->metres) return rs_err_set(err, RS_ERR_INVALID, "the points are on the ground already");
    // one camera model per distinct camera name, loaded on first use
    int *cam_of_image = malloc((size_t)(d->Nimages ? d->Nimages : 1) * sizeof *cam_of_image);
    rs_camera *cams = calloc((size_t)(site->Ncameras ? site->Ncameras : 1), sizeof *cams);
    bool *loaded = calloc((size_t)(site->Ncameras ? site->Ncameras : 1), sizeof *loaded);
    rs_status st = cam_of_image && cams && loaded ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; st == RS_OK && i < d->Nimages; i++) {
        int c = rs_site_find_camera(site, d->image_camera[i]);
        if (c < 0) {
            st = rs_err_set(err, RS_ERR_NOT_FOUND, "image %lld: camera '%s' is not a camera of the site %s",
                            d->image_id[i], d->image_camera[i], site->dir);
            break;
        }
        cam_of_image[i] = c;
        if (loaded[c]) continue;
        char path[4096];
        st = rs_camera_path(path, sizeof path, calib_dir, site->cameras[c].id, RS_CAMERA_EXT_CAMERAMODEL)
                 ? rs_camera_read(&cams[c], NULL, path, err)
                 : rs_err_set(err, RS_ERR_INVALID, "%s: path too long", calib_dir);
        loaded[c] = st == RS_OK;
    }
    size_t missed = 0;
    if (st == RS_OK) {
        for (int i = 0; i < d->Nimages; i++)
            for (size_t a = d->gt_begin[i]; a < d->gt_begin[i + 1]; a++)
                missed += !to_ground(&d->gt_point[2 * a], &cams[cam_of_image[i]], site, MISSED_GT);
        for (size_t k = 0; k < d->Ndets; k++)
            missed += !to_ground(&d->det_point[2 * k], &cams[cam_of_image[d->det_image[k]]], site, MISSED_DET);
        d->metres = true;
    }
    if (cams)
        for (int c = 0; c < site->Ncameras; c++) rs_camera_free(&cams[c]);
    free(cams);
    free(loaded);
    free(cam_of_image);
    if (Nmissed) *Nmissed = missed;
    return st;
}

rs_status rs_eval_data_to_ground_recorded(rs_eval_data *d, size_t *Nmissed, rs_err *err)
{
    if (Nmissed) *Nmissed = 0;
    if (!d->image_model || d->Nrecorded != d->Nimages)
        return rs_err_set(err, RS_ERR_INVALID, "the ground truth was loaded without its recorded calibration");
    if (d->metres) return rs_err_set(err, RS_ERR_INVALID, "the points are on the ground already");
    // one camera per distinct model path, loaded (and its checksum checked) on first use
    const size_t N = (size_t)(d->Nimages ? d->Nimages : 1);
    int *cam_of_image = malloc(N * sizeof *cam_of_image);
    rs_camera *cams = calloc(N, sizeof *cams);
    int *first_image = malloc(N * sizeof *first_image); // (Ncams) an image of each distinct model
    int Ncams = 0;
    rs_status st = cam_of_image && cams && first_image ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    for (int i = 0; st == RS_OK && i < d->Nimages; i++) {
        int c = -1; // the distinct models so far (a dataset has a few cameras)
        for (int j = 0; j < Ncams && c < 0; j++)
            if (!strcmp(d->image_model[first_image[j]], d->image_model[i])) c = j;
        if (c < 0) {
            first_image[Ncams] = i;
            c = Ncams;
            if ((st = rs_localise_camera_read_checked(&cams[c], d->image_model[i], d->image_model_sha256[i],
                                                      d->image_id[i], err)))
                break;
            Ncams++;
        }
        cam_of_image[i] = c;
    }
    size_t missed = 0;
    if (st == RS_OK) {
        for (int i = 0; i < d->Nimages; i++)
            for (size_t a = d->gt_begin[i]; a < d->gt_begin[i + 1]; a++)
                missed += !to_ground_plane(&d->gt_point[2 * a], &cams[cam_of_image[i]], &d->image_ground[4 * i],
                                           d->image_ground[4 * i + 3], MISSED_GT);
        for (size_t k = 0; k < d->Ndets; k++) {
            const int i = d->det_image[k];
            missed += !to_ground_plane(&d->det_point[2 * k], &cams[cam_of_image[i]], &d->image_ground[4 * i],
                                       d->image_ground[4 * i + 3], MISSED_DET);
        }
        d->metres = true;
    }
    for (int c = 0; c < Ncams; c++) rs_camera_free(&cams[c]);
    free(cams);
    free(cam_of_image);
    free(first_image);
    if (Nmissed) *Nmissed = missed;
    return st;
}
