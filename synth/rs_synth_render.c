// rs_synth_render.c -- running povray on a scene: culling, region, colour and ID passes,
// resampling into the real lens, compositing (rs_synth_render.h, docs/povray.md).
#include "synth/rs_synth_render.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <mrcal/poseutils.h>

#include "core/rs_io.h"
#include "synth/rs_synth_appearance.h"
#include "synth/rs_synth_sandbox.h"

void rs_synth_render_options_default(rs_synth_render_options *opt)
{
    memset(opt, 0, sizeof(*opt));
    opt->canvas_scale = 1;
    opt->write_files = true;
    rs_synth_scene_options_default(&opt->scene);
}

void rs_synth_render_result_free(rs_synth_render_result *r)
{
    if (!r) return;
    rs_image_free(&r->rgba);
    rs_image_free(&r->composite);
    free(r->ids);
    free(r->visible);
    free(r->shadow);
    memset(r, 0, sizeof(*r));
}

// ---- culling ----

bool rs_synth_vehicle_rect(int rect[4], const double fxycxy[4], int width, int height, const double rt_cam_enu[6],
                           const double corners_enu_m[8][3], double near_m)
{
    double p[8][3];
    for (int k = 0; k < 8; k++) mrcal_transform_point_rt(p[k], NULL, NULL, rt_cam_enu, corners_enu_m[k]);
    // The box clipped to z >= near is the convex hull of its corners in front and of the
    // crossings of its 12 edges with the plane z = near: their projections bound its image.
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    int Nin = 0;
    for (int a = 0; a < 8; a++) {
        for (int b = a; b < 8; b++) {
            const int diff = a ^ b;
            double q[3];
            if (a == b) {
                if (!(p[a][2] >= near_m)) continue;
                memcpy(q, p[a], sizeof(q));
            } else if (diff == 1 || diff == 2 || diff == 4) {
                const double za = p[a][2] - near_m, zb = p[b][2] - near_m;
                if (!((za < 0 && zb > 0) || (za > 0 && zb < 0))) continue;
                const double t = za / (za - zb);
                for (int k = 0; k < 3; k++) q[k] = p[a][k] + t * (p[b][k] - p[a][k]);
                q[2] = near_m;
            } else {
                continue;
            }
            const double u = fxycxy[0] * q[0] / q[2] + fxycxy[2], v = fxycxy[1] * q[1] / q[2] + fxycxy[3];
            lo[0] = fmin(lo[0], u), hi[0] = fmax(hi[0], u);
            lo[1] = fmin(lo[1], v), hi[1] = fmax(hi[1], v);
            Nin++;
        }
    }
    if (Nin == 0 || hi[0] < -0.5 || hi[1] < -0.5 || lo[0] > width - 0.5 || lo[1] > height - 0.5) return false;
    // Pixel k covers [k - 0.5, k + 0.5]; one pixel of margin on each side.
    rect[0] = (int)fmax(0, floor(lo[0] + 0.5) - 1);
    rect[1] = (int)fmax(0, floor(lo[1] + 0.5) - 1);
    rect[2] = (int)fmin(width - 1, floor(hi[0] + 0.5) + 1);
    rect[3] = (int)fmin(height - 1, floor(hi[1] + 0.5) + 1);
    return true;
}

// ---- running povray ----

// Writes OUT/.povray/3.7/povray.conf, which asks povray to restrict its file I/O to the output
// folder (povray is run with HOME = OUT so that this is the user configuration it reads).
// POV-Ray 3.7.0.10 does not enforce it (docs/povray.md): Landlock does (rs_synth_sandbox.h).
static rs_status write_povray_conf(const char *out_dir, rs_err *err)
{
    char *conf_dir = rs_io_join(out_dir, ".povray/3.7");
    char *conf = conf_dir ? rs_io_join(conf_dir, "povray.conf") : NULL;
    rs_status st = RS_OK;
    if (!conf) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    static const char text[] = "; Written by roadside render: asks povray to read and write only this "
                               "folder, and to run no shell command (POV-Ray 3.7.0.10 does not enforce "
                               "the first: roadside confines povray with Landlock, docs/povray.md).\n"
                               "[File I/O Security]\nrestricted\n"
                               "[Shellout Security]\nforbidden\n"
                               "[Permitted Paths]\nread+write = .\n";
    if (!(st = rs_io_mkdir_p(conf_dir, err))) st = rs_io_write_file(conf, text, sizeof(text) - 1, err);
done:
    free(conf_dir);
    free(conf);
    return st;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// The program execvp would run for `name`: itself when it holds a '/', else the first
// executable regular file "DIR/name" along $PATH's absolute folders (malloc'ed), or NULL.
static char *find_program(const char *name)
{
    if (strchr(name, '/')) return strdup(name);
    const char *path = getenv("PATH");
    if (!path || !*path) path = "/usr/local/bin:/usr/bin:/bin";
    for (const char *p = path; *p;) {
        const char *colon = strchr(p, ':');
        const size_t n = colon ? (size_t)(colon - p) : strlen(p);
        if (n > 0 && p[0] == '/') {
            char *dir = strndup(p, n), *file = dir ? rs_io_join(dir, name) : NULL;
            struct stat sb;
            free(dir);
            if (file && stat(file, &sb) == 0 && S_ISREG(sb.st_mode) && access(file, X_OK) == 0) return file;
            free(file);
        }
        p += n + (colon ? 1 : 0);
    }
    return NULL;
}

// Writes "roadside: TEXT STEP: errno E\n" to fd with system calls only (a child after fork).
static void child_say(int fd, const char *text, const char *step, int e)
{
    char num[16];
    int n = 0;
    do num[sizeof(num) - 1 - n++] = (char)('0' + e % 10);
    while ((e /= 10) > 0 && n < 15);
    const char *parts[] = {"roadside: ", text, step, ": errno ", num + sizeof(num) - n, "\n"};
    for (size_t i = 0; i < sizeof(parts) / sizeof(parts[0]); i++)
        if (write(fd, parts[i], i == 4 ? (size_t)n : strlen(parts[i])) < 0) return;
}

rs_status rs_synth_povray_run(const char *povray, const char *dir, const char *const *args, int Nargs, double *seconds,
                              rs_err *err)
{
    const char *argv[32];
    if (Nargs < 0 || Nargs > 30) return rs_err_set(err, RS_ERR_USAGE, "povray: %d arguments (at most 30)", Nargs);
    argv[0] = povray;
    for (int i = 0; i < Nargs; i++) argv[1 + i] = args[i];
    argv[1 + Nargs] = NULL;
    rs_synth_sandbox_info box;
    rs_synth_sandbox_probe(&box);
    char *log = rs_io_join(dir, "povray.log");
    char *exe = find_program(povray); // NULL: not found (execvp then fails: "cannot run")
    if (!log) {
        free(exe);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    const double t0 = now_s();
    const pid_t parent = getpid();
    pid_t pid = fork();
    if (pid < 0) {
        free(log);
        free(exe);
        return rs_err_set(err, RS_ERR_EXTERNAL, "fork: %s", strerror(errno));
    }
    if (pid == 0) {
        // povray dies with us (a killed roadside leaves no povray running; kept across exec)
        if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != parent) _exit(126);
        int fd = open(log, O_WRONLY | O_CREAT | O_APPEND, 0644);
        if (fd < 0 || chdir(dir) != 0) _exit(126);
        // HOME must be absolute for povray's %HOME%: the folder we are now in
        char cwd[4096];
        if (!getcwd(cwd, sizeof(cwd)) || setenv("HOME", cwd, 1) != 0) _exit(126);
        unsetenv("POVINC");
        unsetenv("POVINI");
        dup2(fd, 1);
        dup2(fd, 2);
        close(fd);
        // confined to this folder and the system's programs (rs_synth_sandbox.h)
        const char *step = NULL;
        const int e = box.abi > 0 ? rs_synth_sandbox_enter(box.abi, exe, &step) : 0;
        if (e) {
            child_say(2, "cannot confine povray (Landlock): ", step, e);
            _exit(125);
        }
        if (exe) execv(exe, (char *const *)argv);
        execvp(povray, (char *const *)argv);
        _exit(127);
    }
    free(exe);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
        ;
    if (seconds) *seconds += now_s() - t0;
    rs_status st = RS_OK;
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        char *text = NULL;
        char last[256] = "";
        if (rs_io_read_file(&text, NULL, log, NULL) == RS_OK) {
            // last non-empty line
            size_t n = strlen(text);
            while (n > 0 && (text[n - 1] == '\n' || text[n - 1] == '\r')) text[--n] = 0;
            const char *nl = strrchr(text, '\n');
            snprintf(last, sizeof(last), "%s", nl ? nl + 1 : text);
        }
        free(text);
        if (WIFEXITED(status) && WEXITSTATUS(status) == 125 && strstr(last, "cannot confine povray"))
            st = rs_err_set(err, RS_ERR_EXTERNAL,
                            "%s (see %s); set ROADSIDE_POVRAY_SANDBOX=off to run povray unconfined "
                            "(docs/povray.md)",
                            last, log);
        else if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
            st = rs_err_set(err, RS_ERR_EXTERNAL,
                            "cannot run \"%s\": is POV-Ray 3.7 installed (Debian package "
                            "povray)? Set ROADSIDE_POVRAY to its path",
                            povray);
        else
            st = rs_err_set(err, RS_ERR_EXTERNAL, "povray failed in %s (exit %d): %s (see %s)", dir,
                            WIFEXITED(status) ? WEXITSTATUS(status) : -1, last, log);
    }
    free(log);
    return st;
}

// Runs `povray INI region` in out_dir (rs_synth_povray_run).
static rs_status run_povray(const char *povray, const char *out_dir, const char *ini, const int region[4], int width,
                            int height, double *seconds, rs_err *err)
{
    char sc[32], ec[32], sr[32], er[32];
    // POV-Ray counts columns and rows from 1, inclusive; a value of exactly 1 would read as a
    // fraction (the whole width), so the region starts at fraction 0.0 in that case and ends at
    // least at column/row 2.
    snprintf(sc, sizeof(sc), region[0] == 0 ? "+SC0.0" : "+SC%d", region[0] + 1);
    snprintf(sr, sizeof(sr), region[1] == 0 ? "+SR0.0" : "+SR%d", region[1] + 1);
    snprintf(ec, sizeof(ec), "+EC%d", region[2] + 1 < 2 ? (width > 1 ? 2 : 1) : region[2] + 1);
    snprintf(er, sizeof(er), "+ER%d", region[3] + 1 < 2 ? (height > 1 ? 2 : 1) : region[3] + 1);
    const char *args[] = {ini, sc, ec, sr, er, "+WT1"};
    return rs_synth_povray_run(povray, out_dir, args, 6, seconds, err);
}

// ---- images ----

// Zeroes (transparent) everything outside the rendered rectangle: povray leaves it opaque black.
static void mask_outside(rs_image *img, const int region[4])
{
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++)
            if (x < region[0] || x > region[2] || y < region[1] || y > region[3])
                memset(&img->data[((size_t)y * img->width + x) * img->channels], 0,
                       sizeof(float) * (size_t)img->channels);
}

// Renders passes[0..Npasses-1] with ONE povray process: writes NAME.pov and NAME.ini in
// out_dir, runs povray, reads its images into imgs[0..Npasses-1]: NAME.png for a single pass
// (rs_synth_scene_write, antialias as given), else the frames NAME1.png .. NAMEn.png
// (rs_synth_scene_write_frames; no antialiasing, which would blend the IDs).
static rs_status render_passes(rs_image *imgs, const char *out_dir, const char *name, const char *povray,
                               const rs_synth_povcam *cam, const double fxy[2], const double ground_normal_enu[3],
                               double ground_offset_m, const rs_synth_prepared *vehicles,
                               const rs_synth_scene_options *passes, int Npasses, int antialias, const int region[4],
                               double *seconds, rs_err *err)
{
    char file[64];
    char *pov = NULL, *ini = NULL;
    rs_io_atomic a = {0};
    rs_status st = RS_OK;
    snprintf(file, sizeof(file), "%s.pov", name);
    pov = rs_io_join(out_dir, file);
    snprintf(file, sizeof(file), "%s.ini", name);
    ini = rs_io_join(out_dir, file);
    if (!pov || !ini) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    if ((st = rs_io_atomic_open(&a, pov, err))) goto done;
    st = Npasses == 1
             ? rs_synth_scene_write(a.f, cam, fxy, ground_normal_enu, ground_offset_m, vehicles, &passes[0], err)
             : rs_synth_scene_write_frames(a.f, cam, fxy, ground_normal_enu, ground_offset_m, vehicles, passes, Npasses,
                                           err);
    if (st) {
        rs_io_atomic_abort(&a);
        goto done;
    }
    if ((st = rs_io_atomic_commit(&a, err)) ||
        (st = Npasses == 1 ? rs_synth_scene_write_ini(ini, pov, cam, passes[0].pass, antialias, err)
                           : rs_synth_scene_write_ini_frames(ini, pov, cam, Npasses, 0, err)))
        goto done;
    snprintf(file, sizeof(file), "%s.ini", name);
    if ((st = run_povray(povray, out_dir, file, region, cam->width, cam->height, seconds, err))) goto done;
    for (int k = 0; k < Npasses && !st; k++) {
        if (Npasses == 1)
            snprintf(file, sizeof(file), "%s.png", name);
        else
            snprintf(file, sizeof(file), "%s%d.png", name, k + 1);
        char *png = rs_io_join(out_dir, file);
        if (!png) {
            st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
            break;
        }
        if ((st = rs_image_read(&imgs[k], png, err)) == RS_OK &&
            (imgs[k].width != cam->width || imgs[k].height != cam->height))
            st = rs_err_set(err, RS_ERR_EXTERNAL, "%s: povray wrote %dx%d, expected %dx%d", png, imgs[k].width,
                            imgs[k].height, cam->width, cam->height);
        else if (!st)
            mask_outside(&imgs[k], region);
        free(png);
    }
done:
    free(pov);
    free(ini);
    return st;
}

// Widens rect (x0, y0, x1, y1; empty when x1 < x0) by the canvas rectangle of vehicle v's
// shadows: its bottom corners and its top corners projected onto the ground along each light
// higher than 3 deg above the ground.
static void widen_by_shadows(int rect[4], const double fxycxy[4], int width, int height, const double rt_cam_enu[6],
                             const double corners[8][3], const double ground_normal_enu[3], double ground_offset_m,
                             const rs_synth_light *lights, int Nlights)
{
    const double *g = ground_normal_enu;
    const double gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    for (int j = 0; j < Nlights; j++) {
        const double *d = lights[j].dir_enu;
        const double nd = (g[0] * d[0] + g[1] * d[1] + g[2] * d[2]) / gn;
        if (!(nd > 0.05)) continue;
        double pts[8][3];
        for (int k = 0; k < 4; k++) {
            memcpy(pts[k], corners[k], sizeof(pts[k]));
            const double *p = corners[4 + k];
            const double t = ((g[0] * p[0] + g[1] * p[1] + g[2] * p[2]) / gn - ground_offset_m / gn) / nd;
            for (int c = 0; c < 3; c++) pts[4 + k][c] = p[c] - t * d[c];
        }
        int r[4];
        if (!rs_synth_vehicle_rect(r, fxycxy, width, height, rt_cam_enu, (const double(*)[3])pts, 0.05)) continue;
        if (rect[2] < rect[0]) {
            memcpy(rect, r, sizeof(r));
            continue;
        }
        rect[0] = r[0] < rect[0] ? r[0] : rect[0];
        rect[1] = r[1] < rect[1] ? r[1] : rect[1];
        rect[2] = r[2] > rect[2] ? r[2] : rect[2];
        rect[3] = r[3] > rect[3] ? r[3] : rect[3];
    }
}

// The shadow frame (canvas, RGBA, white ground) as the lit fraction: value / unlit, clamped to
// [0, 1]; 1 where nothing was rendered (transparent).
static rs_status shadow_fraction(rs_image *frac, const rs_image *pass, double unlit, rs_err *err)
{
    rs_status st = rs_image_alloc(frac, pass->width, pass->height, 1, err);
    if (st) return st;
    const size_t n = (size_t)pass->width * pass->height;
    for (size_t i = 0; i < n; i++) {
        const float *px = &pass->data[(size_t)pass->channels * i];
        double v = pass->channels >= 4 && px[3] <= 0 ? 1.0 : (unlit > 0 ? px[0] / unlit : 1.0);
        frac->data[i] = (float)(v < 0 ? 0 : v > 1 ? 1 : v);
    }
    return RS_OK;
}

// Removes the intermediates of a render (scene files, povray outputs, the conf).
static void remove_intermediates(const char *out_dir)
{
    static const char *const names[] = {
        "pass_colour.pov", "pass_colour.ini", "pass_colour.png",         "pass_ids.pov", "pass_ids.ini", "pass_ids.png",
        "pass_shadow.pov", "pass_shadow.ini", "pass_shadow.png",         "passes.pov",   "passes.ini",   "passes1.png",
        "passes2.png",     "passes3.png",     ".povray/3.7/povray.conf", ".povray/3.7",  ".povray",      "povray.log"};
    for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); i++) {
        char *p = rs_io_join(out_dir, names[i]);
        if (p) (void)remove(p); // a missing file, or a folder someone else used: left as it is
        free(p);
    }
}

// Resamples the canvas passes into the real lens: colour through premultiplied linear
// interpolation, IDs nearest-neighbour.
static rs_status to_lens(rs_image *rgba, rs_image *ids, const float *map, int width, int height, rs_err *err)
{
    const size_t Nc = (size_t)rgba->width * rgba->height;
    for (size_t i = 0; i < Nc; i++)
        for (int k = 0; k < 3; k++) rgba->data[4 * i + k] *= rgba->data[4 * i + 3];
    rs_image out_rgba = {0}, out_ids = {0};
    rs_status st = rs_synth_remap(&out_rgba, rgba, map, width, height, 1, err);
    if (!st) st = rs_synth_remap(&out_ids, ids, map, width, height, 0, err);
    if (st) {
        rs_image_free(&out_rgba);
        return st;
    }
    const size_t N = (size_t)width * height;
    for (size_t i = 0; i < N; i++) {
        const float a = out_rgba.data[4 * i + 3];
        for (int k = 0; k < 3; k++) out_rgba.data[4 * i + k] = a > 0 ? out_rgba.data[4 * i + k] / a : 0;
    }
    rs_image_free(rgba);
    rs_image_free(ids);
    *rgba = out_rgba;
    *ids = out_ids;
    return RS_OK;
}

// Decodes the ID pass (R + 256 G in 8-bit units) into out->ids; values above N become 0.
static void decode_ids(rs_synth_render_result *out, const rs_image *ids, int N)
{
    const size_t Npx = (size_t)out->width * out->height;
    for (size_t i = 0; i < Npx; i++) {
        const float *px = &ids->data[i * (size_t)ids->channels];
        const long v = lroundf(px[0] * 255.0f) + 256 * lroundf(px[1] * 255.0f);
        out->ids[i] = (uint16_t)(v >= 0 && v <= N ? v : 0);
    }
}

// out->composite = rgba over the background (or black), in linear light, sRGB-encoded.
static void composite(rs_synth_render_result *out, const rs_image *bg)
{
    const size_t Npx = (size_t)out->width * out->height;
    for (size_t i = 0; i < Npx; i++) {
        const float *c = &out->rgba.data[4 * i];
        for (int k = 0; k < 3; k++) {
            double b = bg ? rs_synth_srgb_decode(bg->data[i * bg->channels + (bg->channels >= 3 ? k : 0)]) : 0;
            if (out->shadow && out->ids[i] == 0) b *= out->shadow[i];
            out->composite.data[3 * i + k] = (float)rs_synth_srgb_encode(c[3] * c[k] + (1 - c[3]) * b);
        }
    }
}

static rs_status write_outputs(const char *out_dir, const rs_synth_render_result *out, rs_err *err)
{
    rs_image ids = {0};
    rs_status st = rs_image_alloc(&ids, out->width, out->height, 1, err);
    if (st) return st;
    const size_t Npx = (size_t)out->width * out->height;
    for (size_t i = 0; i < Npx; i++) ids.data[i] = out->ids[i] / 65535.0f;
    const char *names[3] = {"image.png", "rgba.png", "ids.png"};
    const rs_image *imgs[3] = {&out->composite, &out->rgba, &ids};
    const int bits[3] = {8, 16, 16};
    for (int k = 0; k < 3 && !st; k++) {
        char *p = rs_io_join(out_dir, names[k]);
        st = p ? rs_image_write(p, imgs[k], bits[k], err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(p);
    }
    if (!st && out->shadow) {
        const rs_image sh = {.width = out->width, .height = out->height, .channels = 1, .data = out->shadow};
        char *p = rs_io_join(out_dir, "shadow.png");
        st = p ? rs_image_write(p, &sh, 16, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        free(p);
    }
    rs_image_free(&ids);
    return st;
}

rs_status rs_synth_render(rs_synth_render_result *out, const char *out_dir, const rs_camera *camera,
                          const double ground_normal_enu[3], double ground_offset_m, const rs_synth_prepared *vehicles,
                          const rs_synth_render_options *opt_in, rs_err *err)
{
    memset(out, 0, sizeof(*out));
    const mrcal_lensmodel_t *lensmodel = &camera->lensmodel;
    const double *intrinsics = camera->intrinsics, *rt_cam_enu = camera->rt_cam_enu;
    const int width = camera->width, height = camera->height;
    rs_synth_render_options opt;
    if (opt_in)
        opt = *opt_in;
    else
        rs_synth_render_options_default(&opt);
    const char *povray = opt.povray ? opt.povray : getenv("ROADSIDE_POVRAY");
    if (!povray || !*povray) povray = "povray";
    const int N = vehicles->N;
    rs_synth_canvas canvas;
    rs_synth_povcam cam;
    rs_image bg = {0}, rgba = {0}, idimg = {0};
    uint8_t *include = NULL;
    float *map = NULL;
    rs_status st;
    if (opt.canvas)
        canvas = *opt.canvas;
    else if ((st = rs_synth_canvas_for_lens(&canvas, lensmodel, intrinsics, width, height,
                                            opt.canvas_scale > 1 ? opt.canvas_scale : 1, err)))
        return st;
    if ((st = rs_synth_povcam_init(&cam, canvas.fxycxy, canvas.width, canvas.height, rt_cam_enu, err))) return st;
    if (opt.background_path) {
        if ((st = rs_image_read(&bg, opt.background_path, err))) return st;
        if (bg.width != width || bg.height != height) {
            rs_image_free(&bg);
            return rs_err_set(err, RS_ERR_INVALID, "%s: the background is %dx%d, the camera %dx%d", opt.background_path,
                              bg.width, bg.height, width, height);
        }
    }
    out->width = width;
    out->height = height;
    out->Nvehicles = N;
    out->ids = calloc((size_t)width * height, sizeof(uint16_t));
    out->visible = calloc((size_t)(N > 0 ? N : 1), 1);
    include = calloc((size_t)(N > 0 ? N : 1), 1);
    if (!out->ids || !out->visible || !include) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    if ((st = rs_image_alloc(&out->composite, width, height, 3, err))) goto done;
    // 1-2. Culling and the region
    rs_synth_light lights[RS_SYNTH_SKY_LIGHTS + 1];
    const int Nlights = rs_synth_scene_lights(lights, &opt.scene);
    int region[4] = {canvas.width, canvas.height, -1, -1};
    for (int i = 0; i < N; i++) {
        double corners[8][3];
        int rect[4];
        rs_synth_vehicle_corners_enu(corners, &vehicles->v[i], ground_normal_enu, ground_offset_m);
        const bool in =
            rs_synth_vehicle_rect(rect, canvas.fxycxy, canvas.width, canvas.height, rt_cam_enu, corners, 0.05);
        include[i] = opt.full_frame || in;
        out->visible[i] = include[i];
        if (!in) continue;
        out->Nrendered++;
        if (opt.shadow)
            widen_by_shadows(rect, canvas.fxycxy, canvas.width, canvas.height, rt_cam_enu, (const double(*)[3])corners,
                             ground_normal_enu, ground_offset_m, lights, Nlights);
        region[0] = rect[0] < region[0] ? rect[0] : region[0];
        region[1] = rect[1] < region[1] ? rect[1] : region[1];
        region[2] = rect[2] > region[2] ? rect[2] : region[2];
        region[3] = rect[3] > region[3] ? rect[3] : region[3];
    }
    // Pins, and the ground when there is no background to composite onto, are part of the
    // picture too: they widen the region to the whole canvas.
    const bool ground_drawn = !opt.background_path && opt.scene.ground_visible;
    if (opt.full_frame || opt.scene.Npins > 0 || ground_drawn) {
        region[0] = region[1] = 0;
        region[2] = canvas.width - 1;
        region[3] = canvas.height - 1;
    }
    if (opt.full_frame) out->Nrendered = N;
    const bool run = out->Nrendered > 0 || opt.scene.Npins > 0 || ground_drawn;
    if (!run) {
        for (int k = 0; k < 4; k++) out->region[k] = -1;
        if ((st = rs_image_alloc(&out->rgba, width, height, 4, err))) goto done;
    } else {
        memcpy(out->region, region, sizeof(region));
        if ((st = rs_io_mkdir_p(out_dir, err)) || (st = write_povray_conf(out_dir, err))) goto done;
        // The passes: colour; ID and shadow when vehicles are rendered.
        rs_synth_scene_options passes[3];
        int Npasses = 0, i_id = -1, i_shadow = -1;
        passes[Npasses] = opt.scene;
        passes[Npasses].include = include;
        passes[Npasses].pass = RS_SYNTH_PASS_COLOUR;
        passes[Npasses].ground_visible = opt.background_path ? false : opt.scene.ground_visible;
        Npasses++;
        if (out->Nrendered > 0) {
            passes[Npasses] = passes[0];
            passes[Npasses].pass = RS_SYNTH_PASS_ID;
            passes[Npasses].Npins = 0;
            i_id = Npasses++;
            if (opt.shadow) {
                passes[Npasses] = passes[i_id];
                passes[Npasses].pass = RS_SYNTH_PASS_SHADOW;
                i_shadow = Npasses++;
            }
        }
        rs_image imgs[3] = {{0}};
        // (pins are sized in real-image pixels: the lens's fx, fy, not the canvas's)
        const bool colour_alone = opt.antialias >= 2;
        // Processes: [first, first + count) of the passes each; one for all of them unless
        // separate or antialiased (then the colour pass alone first).
        static const char *const names[3] = {"pass_colour", "pass_ids", "pass_shadow"};
        for (int first = 0; first < Npasses && !st; out->Npovray++) {
            const int count = opt.separate_processes || (first == 0 && colour_alone) ? 1 : Npasses - first;
            st = render_passes(&imgs[first], out_dir, count == 1 ? names[passes[first].pass] : "passes", povray, &cam,
                               intrinsics, ground_normal_enu, ground_offset_m, vehicles, &passes[first], count,
                               first == 0 ? opt.antialias : 0, region, &out->seconds_povray, err);
            first += count;
        }
        out->Npasses = Npasses;
        rgba = imgs[0];
        if (i_id >= 0) idimg = imgs[1];
        rs_image frac = {0};
        if (!st && i_shadow >= 0)
            st = shadow_fraction(&frac, &imgs[i_shadow],
                                 rs_synth_scene_shadow_unlit(lights, Nlights, ground_normal_enu), err);
        if (i_shadow >= 0) rs_image_free(&imgs[i_shadow]);
        if (st) {
            rs_image_free(&frac);
            goto done;
        }
        if (i_id < 0 && (st = rs_image_alloc(&idimg, canvas.width, canvas.height, 3, err))) goto done;
        // 3. Into the real lens
        if (!canvas.identity) {
            if ((!opt.canvas_map &&
                 (st = rs_synth_canvas_map(&map, &canvas, lensmodel, intrinsics, width, height, err))) ||
                (st = to_lens(&rgba, &idimg, opt.canvas_map ? opt.canvas_map : map, width, height, err))) {
                rs_image_free(&frac);
                goto done;
            }
            if (frac.data) {
                rs_image lens = {0};
                st = rs_synth_remap(&lens, &frac, opt.canvas_map ? opt.canvas_map : map, width, height, 1, err);
                rs_image_free(&frac);
                frac = lens;
                if (st) goto done;
            }
        }
        out->shadow = frac.data; // owned by out now
        out->rgba = rgba;
        rgba = (rs_image){0};
        decode_ids(out, &idimg, N);
    }
    // 4. Composite
    composite(out, opt.background_path ? &bg : NULL);
    if (opt.write_files && ((st = rs_io_mkdir_p(out_dir, err)) || (st = write_outputs(out_dir, out, err)))) goto done;
done:
    if (!opt.keep_files) remove_intermediates(out_dir);
    rs_image_free(&bg);
    rs_image_free(&rgba);
    rs_image_free(&idimg);
    free(include);
    free(map);
    if (st) rs_synth_render_result_free(out);
    return st;
}

rs_status rs_synth_render_write_labels(const char *out_dir, const rs_synth_render_result *r, const char *split,
                                       const rs_synth_label_options *lopt, const rs_camera *cam,
                                       const double ground_normal_enu[3], double ground_offset_m,
                                       const rs_synth_prepared *prepared, rs_err *err)
{
    const int N = prepared->N;
    const size_t n = (size_t)(N > 0 ? N : 1);
    double *up = malloc(n * sizeof(double));
    rs_synth_mesh *meshes = malloc(n * sizeof(rs_synth_mesh));
    const char **ids = malloc(n * sizeof(char *));
    rs_synth_label *labels = NULL;
    char *folder = NULL, *image = NULL;
    rs_status st = RS_OK;
    if (!up || !meshes || !ids) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    for (int i = 0; i < N; i++) {
        const rs_synth_vehicle *v = &prepared->v[i];
        up[i] = rs_synth_ground_up_m(ground_normal_enu, ground_offset_m, v->e_m, v->n_m);
        meshes[i] = prepared->meshes[prepared->imesh[i]]; // shallow: borrowed arrays
        ids[i] = v->id ? v->id : "";
    }
    if ((st = rs_synth_labels_compute(&labels, cam, prepared->v, up, N, meshes, r->ids, err))) goto done;
    const rs_synth_label_image img = {.file_name = "image.png",
                                      .width = r->width,
                                      .height = r->height,
                                      .labels = labels,
                                      .Nlabels = N,
                                      .vehicle_ids = ids};
    if ((st = rs_synth_labels_write_coco(out_dir, split, &img, 1, lopt, err)) ||
        (st = rs_synth_labels_write_yolo(out_dir, split, &img, 1, lopt, err)) ||
        (st = rs_synth_labels_write_kitti(out_dir, &img, 1, lopt, err)))
        goto done;
    folder = rs_io_join(out_dir, split);
    image = folder ? rs_io_join(folder, "image.png") : NULL;
    st = image ? rs_image_write(image, &r->composite, 8, err) : rs_err_set(err, RS_ERR_NOMEM, "out of memory");
done:
    free(up);
    free(meshes);
    free(ids);
    free(labels);
    free(folder);
    free(image);
    return st;
}
