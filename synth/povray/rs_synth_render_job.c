// rs_synth_render_job.c -- one povray process of a pass: its scene and .ini written, povray started
// on the pass's region (a perspective camera cut to it), waited for, its image read back in place
// (synth/povray/internal/rs_synth_render_internal.h; the renderer: rs_synth_render.c).
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_io.h"
#include "synth/povray/internal/rs_synth_povray.h"
#include "synth/povray/internal/rs_synth_render_internal.h"

// Zeroes (transparent) everything outside the rendered rectangle: povray leaves it opaque black.
static void mask_outside(rs_image *img, const int region[4])
{
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++)
            if (x < region[0] || x > region[2] || y < region[1] || y > region[3])
                memset(&img->data[((size_t)y * img->width + x) * img->channels], 0,
                       sizeof(float) * (size_t)img->channels);
}

// The region's image `crop` (x1 - x0 + 1 by y1 - y0 + 1) put in place in the W x H image *full:
// made transparent (zero) first when empty; the colour pass's clusters each paste theirs.
static rs_status paste_region(rs_image *full, const rs_image *crop, int W, int H, const int region[4], rs_err *err)
{
    rs_status st;
    if (!full->data && (st = rs_image_alloc(full, W, H, crop->channels, err))) return st;
    if (full->width != W || full->height != H || full->channels != crop->channels)
        return rs_err_set(err, RS_ERR_INVALID, "the colour pass's clusters differ in size or channels");
    const size_t row = sizeof(float) * (size_t)crop->channels * crop->width;
    for (int y = 0; y < crop->height; y++)
        memcpy(&full->data[((size_t)(region[1] + y) * W + region[0]) * crop->channels],
               &crop->data[(size_t)y * crop->width * crop->channels], row);
    return RS_OK;
}

// Starts job j: writes NAME.pov (rs_synth_scene_write) and NAME.ini (the ID pass 8-bit PNG
// without alpha, the others 16-bit RGBA PNG, or j->ppm), then povray with one render thread,
// without waiting. A perspective camera is cut to the region (the image povray writes is the
// region's: 2.4 MB of 16-bit PPM less to write and read for a 769 x 515 canvas); a fisheye is
// rendered in the region (+SC/+EC/+SR/+ER) of its whole frame.
rs_status rs_synth_povray_job_start(rs_synth_povray_job *j, const char *out_dir, const char *povray,
                                    const double fxy[2], const double ground_normal_enu[3], double ground_offset_m,
                                    rs_err *err)
{
    const int *r = j->region, W = j->cam->width, H = j->cam->height;
    j->cropped =
        !(j->cam->fisheye_deg > 0) && r[0] >= 0 && r[1] >= 0 && r[2] >= r[0] && r[3] >= r[1] && r[2] < W && r[3] < H;
    if (j->cropped) rs_synth_povcam_crop(&j->crop, j->cam, r);
    const rs_synth_povcam *cam = j->cropped ? &j->crop : j->cam;
    char file[64], sc[32], ec[32], sr[32], er[32];
    snprintf(file, sizeof(file), "%s.pov", j->name);
    char *pov = rs_io_join(out_dir, file);
    snprintf(file, sizeof(file), "%s.ini", j->name);
    char *ini = rs_io_join(out_dir, file);
    rs_io_atomic a = {0};
    rs_status st = RS_OK;
    if (!pov || !ini) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    if ((st = rs_io_atomic_open(&a, pov, err))) goto done;
    st = rs_synth_scene_write(a.f, cam, fxy, ground_normal_enu, ground_offset_m, j->vehicles, j->pass, err);
    if ((st = rs_io_atomic_finish(&a, st, err)) ||
        (st = rs_synth_scene_write_ini(ini, pov, cam, j->pass->pass, j->antialias, err)))
        goto done;
    // POV-Ray counts columns and rows from 1, inclusive; a value of exactly 1 would read as a
    // fraction (the whole width), so the region starts at fraction 0.0 in that case and ends at
    // least at column/row 2.
    snprintf(sc, sizeof(sc), r[0] == 0 ? "+SC0.0" : "+SC%d", r[0] + 1);
    snprintf(sr, sizeof(sr), r[1] == 0 ? "+SR0.0" : "+SR%d", r[1] + 1);
    snprintf(ec, sizeof(ec), "+EC%d", r[2] + 1 < 2 ? (W > 1 ? 2 : 1) : r[2] + 1);
    snprintf(er, sizeof(er), "+ER%d", r[3] + 1 < 2 ? (H > 1 ? 2 : 1) : r[3] + 1);
    snprintf(file, sizeof(file), "%s.ini", j->name);
    char ppm[64];
    snprintf(ppm, sizeof(ppm), "+O%s.ppm", j->name);
    const char *whole[] = {file, sc, ec, sr, er, "+WT1", "+FP16", "-UA", ppm};
    const char *cut[] = {file, "+WT1", "+FP16", "-UA", ppm};
    j->t0 = rs_synth_povray_now_s();
    st = j->cropped ? rs_synth_povray_spawn(&j->pid, povray, out_dir, j->log, cut, j->ppm ? 5 : 2, err)
                    : rs_synth_povray_spawn(&j->pid, povray, out_dir, j->log, whole, j->ppm ? 9 : 6, err);
done:
    free(pov);
    free(ini);
    return st;
}

// Waits for job j (if started), adds its wall time to *seconds and reads NAME.png (.ppm) into
// *img, transparent (black) outside the region.
rs_status rs_synth_povray_job_finish(rs_synth_povray_job *j, rs_image *img, const char *out_dir, const char *povray,
                                     double *seconds, rs_err *err)
{
    if (j->pid <= 0) return RS_OK;
    char file[64];
    rs_status st = rs_synth_povray_reap(j->pid, povray, out_dir, j->log, err);
    j->pid = 0;
    *seconds += rs_synth_povray_now_s() - j->t0;
    if (st) return st;
    snprintf(file, sizeof(file), "%s.%s", j->name, j->ppm ? "ppm" : "png");
    char *png = rs_io_join(out_dir, file);
    if (!png) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    const rs_synth_povcam *cam = j->cropped ? &j->crop : j->cam;
    rs_image got = {0};
    if ((st = rs_image_read(&got, png, err)) == RS_OK && (got.width != cam->width || got.height != cam->height))
        st = rs_err_set(err, RS_ERR_EXTERNAL, "%s: povray wrote %dx%d, expected %dx%d", png, got.width, got.height,
                        cam->width, cam->height);
    else if (!st && j->cropped)
        st = paste_region(img, &got, j->cam->width, j->cam->height, j->region, err);
    else if (!st) {
        mask_outside(&got, j->region);
        rs_image_free(img);
        *img = got;
        got = (rs_image){0};
    }
    rs_image_free(&got);
    free(png);
    return st;
}
