// rs_synth_ortho.c -- the digital twin seen from above by POV-Ray's orthographic camera
// (rs_synth_ortho.h). The world is the twin backgrounds' own (rs_synth_twin_world_write).
#include "synth/povray/rs_synth_ortho.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/rs_io.h"
#include "geo/rs_lanes.h"
#include "synth/povray/internal/rs_synth_twin_world.h"
#include "synth/povray/rs_synth_render.h"
#include "synth/povray/rs_synth_scene.h"

void rs_synth_ortho_options_default(rs_synth_ortho_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->cell_m = 0.05;
    opt->margin_m = 10;
    opt->weather = "cloudy";
    opt->marking_width_m = 0.15;
    opt->max_side = 8192;
}

static void grow(double box[4], double e, double n)
{
    if (e < box[0]) box[0] = e;
    if (n < box[1]) box[1] = n;
    if (e > box[2]) box[2] = e;
    if (n > box[3]) box[3] = n;
}

rs_status rs_synth_ortho_render(rs_image *image, rs_geo_grid *grid, const char *work_dir, const rs_site *site,
                                const char *lanes_path, const rs_synth_ortho_options *opt_in, rs_err *err)
{
    memset(image, 0, sizeof *image);
    memset(grid, 0, sizeof *grid);
    rs_synth_ortho_options opt;
    if (opt_in)
        opt = *opt_in;
    else
        rs_synth_ortho_options_default(&opt);
    if (!(opt.cell_m >= 0.005 && opt.cell_m <= 10))
        return rs_err_set(err, RS_ERR_INVALID, "gsd: %g m is not in [0.005, 10]", opt.cell_m);
    if (!(opt.margin_m >= 0 && opt.margin_m <= 1000))
        return rs_err_set(err, RS_ERR_INVALID, "margin: %g m is not in [0, 1000]", opt.margin_m);
    if (opt.max_side < 16) opt.max_side = 16;
    const char *povray = rs_synth_povray_exe(opt.povray);

    rs_lanes lanes = {0};
    rs_status st = lanes_path ? rs_lanes_read(&lanes, lanes_path, site, err) : RS_OK;
    if (st) return st;
    // the extent: every lane's edges and every landmark
    double box[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < lanes.N; i++)
        for (int k = 0; k < lanes.lane[i].Npoints; k++) {
            const double *p = lanes.lane[i].p_enu_m[k], w = lanes.lane[i].width_m;
            grow(box, p[0] - w, p[1] - w);
            grow(box, p[0] + w, p[1] + w);
        }
    for (int i = 0; i < site->Nlandmarks; i++)
        for (int k = 0; k < site->landmarks[i].Nvertices; k++)
            grow(box, site->landmarks[i].vertices_enu_m[3 * k], site->landmarks[i].vertices_enu_m[3 * k + 1]);
    if (!(box[0] <= box[2])) {
        rs_lanes_free(&lanes);
        return rs_err_set(err, RS_ERR_DEGENERATE, "%s: no lane and no landmark: nothing to draw", site->dir);
    }
    const double m = opt.margin_m, c = opt.cell_m;
    const double ext_e = box[2] - box[0] + 2 * m, ext_n = box[3] - box[1] + 2 * m;
    const int W = (int)ceil(ext_e / c), H = (int)ceil(ext_n / c);
    if (W > opt.max_side || H > opt.max_side) {
        const double fit = fmax(ext_e, ext_n) / opt.max_side;
        rs_lanes_free(&lanes);
        return rs_err_set(err, RS_ERR_INVALID,
                          "gsd: %g m gives %dx%d pixels for the site's %.0f x %.0f m, more than %d on a side; "
                          "use --gsd %.3g or more",
                          c, W, H, ext_e, ext_n, opt.max_side, ceil(fit * 1000) / 1000);
    }
    // centre of the image: the centre of the extent; the camera above the highest ground corner
    const double ec = 0.5 * (box[0] + box[2]), nc = 0.5 * (box[1] + box[3]);
    double top = -INFINITY;
    for (int k = 0; k < 4; k++) {
        const double e = ec + ((k & 1) ? 0.5 : -0.5) * W * c, n = nc + ((k & 2) ? 0.5 : -0.5) * H * c;
        top = fmax(top, rs_synth_ground_up_m(site->ground_normal_enu, site->ground_offset_m, e, n));
    }
    top += 100;
    *grid = (rs_geo_grid){
        .width = W, .height = H, .e0_m = ec - 0.5 * (W - 1) * c, .n0_m = nc + 0.5 * (H - 1) * c, .cell_m = c};

    char *pov = rs_io_join(work_dir, "ortho.pov"), *png = rs_io_join(work_dir, "ortho.png"),
         *log = rs_io_join(work_dir, "povray.log");
    if (!pov || !png || !log) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st) st = rs_io_mkdir_p(work_dir, err);
    if (!st) st = rs_image_alloc(image, W, H, 3, err);
    // in tiles of at most TILE pixels a side, one povray run each: Debian 12's povray 3.7, confined
    // by Landlock (rs_synth_sandbox.h), fails on images much above 2000 x 2000 (measured: 1865^2
    // renders, 2600^2 stops with "Unknown error code")
    enum { TILE = 1024 };
    for (int r0 = 0; !st && r0 < H; r0 += TILE)
        for (int c0 = 0; !st && c0 < W; c0 += TILE) {
            const int tw = W - c0 < TILE ? W - c0 : TILE, th = H - r0 < TILE ? H - r0 : TILE;
            // the tile's centre: pixel (c0 + (tw-1)/2, r0 + (th-1)/2) of the grid
            const double te = grid->e0_m + (c0 + 0.5 * (tw - 1)) * c, tn = grid->n0_m - (r0 + 0.5 * (th - 1)) * c;
            rs_io_atomic a = {0};
            if ((st = rs_io_atomic_open(&a, pov, err))) break;
            fprintf(a.f,
                    "// Written by roadside ortho: the digital twin seen from above, orthographic.\n"
                    "// POV-Ray world <x, y, z> = <east, up, north>, metres. No include files.\n"
                    "#version 3.7;\n"
                    "global_settings { assumed_gamma 1.0 max_trace_level 5 }\n"
                    "camera { orthographic location <%.17g, %.17g, %.17g>\n"
                    "  right <%.17g, 0, 0> up <0, 0, %.17g> direction <0, -1, 0> }\n",
                    te, top, tn, tw * c, th * c);
            // the sun only matters for the sunny look: high in the south, short shadows; the sky
            // casts none (an orthophoto for picking: 40% less trace time)
            st = rs_synth_twin_world_write(a.f, site, &lanes, opt.weather, 180, 60, opt.marking_width_m, false, err);
            if ((st = rs_io_atomic_finish(&a, st, err))) break;
            char w[32], h[32];
            snprintf(w, sizeof w, "+W%d", tw);
            snprintf(h, sizeof h, "+H%d", th);
            const char *args[] = {"+Iortho.pov", "+Oortho.png", w, h, "-D", "+FN8", "File_Gamma=sRGB", "-A", "+WT1"};
            rs_image tile = {0};
            st = rs_synth_povray_run(povray, work_dir, args, (int)(sizeof args / sizeof args[0]), NULL, err);
            if (!st) st = rs_image_read(&tile, png, err);
            if (!st && (tile.width != tw || tile.height != th || tile.channels < 3))
                st = rs_err_set(err, RS_ERR_EXTERNAL, "%s: povray wrote %dx%dx%d, expected %dx%dx3", png, tile.width,
                                tile.height, tile.channels, tw, th);
            for (int y = 0; !st && y < th; y++)
                for (int x = 0; x < tw; x++)
                    for (int k = 0; k < 3; k++)
                        image->data[((size_t)(r0 + y) * W + c0 + x) * 3 + k] =
                            tile.data[((size_t)y * tw + x) * tile.channels + k];
            rs_image_free(&tile);
        }
    if (!st) {
        remove(pov);
        remove(png);
        remove(log);
        rmdir(work_dir);
    } else {
        rs_image_free(image);
        memset(grid, 0, sizeof *grid);
    }
    free(pov);
    free(png);
    free(log);
    rs_lanes_free(&lanes);
    return st;
}
