// rs_bench_site.c -- `roadside bench site` (bench/rs_bench_site.h).
#include "bench/rs_bench_site.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "core/rs_camera.h"
#include "core/rs_io.h"
#include "core/rs_rng.h"
#include "geo/rs_geo.h"
#include "geo/rs_site.h"
#include "geo/rs_site_write.h"

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

// The site of rs_bench_site.h in dir (created).
// The camera's observations: Npicks picks of landmarks 2.. on a grid over the image, then
// Nunknown rows of ids no landmark has.
static rs_status write_picks(const char *csv, int Npicks, int Nunknown, rs_err *err)
{
    const size_t cap = 32 + (size_t)(Npicks + Nunknown) * 40;
    char *text = malloc(cap);
    if (!text) return rs_err_set(err, RS_ERR_NOMEM, "bench site: out of memory");
    size_t n = (size_t)snprintf(text, cap, "landmark,u,v\n");
    for (int k = 0; k < Npicks + Nunknown; k++)
        n += (size_t)snprintf(text + n, cap - n, "%c%07d,%.2f,%.2f\n", k < Npicks ? 'L' : 'X', k, 10 + (k % 1900) * 1.0,
                              10 + (k / 1900 % 1060) * 1.0);
    const rs_status st = rs_io_write_file(csv, text, n, err);
    free(text);
    return st;
}

static rs_status write_site(const char *dir, int N, int Npicks, int Nunknown, uint64_t seed, rs_err *err)
{
    const rs_llh origin = {48.137, 11.575, 520.0};
    rs_site_landmark *l = calloc((size_t)N, sizeof *l);
    double *p = malloc((size_t)N * 3 * sizeof *p), *llh = malloc((size_t)N * 3 * sizeof *llh);
    char *ids = malloc((size_t)N * 16);
    rs_status st = l && p && llh && ids ? RS_OK : rs_err_set(err, RS_ERR_NOMEM, "bench site: out of memory");
    rs_rng rng;
    rs_rng_seed(&rng, seed);
    for (int i = 0; st == RS_OK && i < N; i++) {
        const double r = 500 * sqrt(rs_rng_uniform(&rng)), a = 2 * M_PI * rs_rng_uniform(&rng);
        p[3 * i] = r * cos(a), p[3 * i + 1] = r * sin(a), p[3 * i + 2] = 10 * rs_rng_uniform(&rng);
    }
    memcpy(&p[3 * (N - 2)], &p[3], 3 * sizeof *p); // planted: N-2 at 1's position
    if (st == RS_OK) st = rs_geo_enu_to_llh(llh, &origin, p, N, err);
    for (int i = 0; st == RS_OK && i < N; i++) {
        snprintf(&ids[16 * i], 16, "L%07d", i == N - 1 ? 0 : i); // planted: N-1 repeats 0's id
        l[i].id = &ids[16 * i];
        l[i].llh = (rs_llh){llh[3 * i], llh[3 * i + 1], llh[3 * i + 2]};
        l[i].sigma_h_m = l[i].sigma_v_m = NAN;
    }
    char *cameras = rs_io_join(dir, RS_SITE_CAMERAS_DIR), *observations = rs_io_join(dir, RS_SITE_OBSERVATIONS_DIR);
    char *model = rs_io_join(dir, RS_SITE_CAMERAS_DIR "/cam1" RS_CAMERA_EXT_CAMERAMODEL),
         *csv = rs_io_join(dir, RS_SITE_OBSERVATIONS_DIR "/cam1" RS_SITE_OBSERVATIONS_EXT);
    if (st == RS_OK && !(cameras && observations && model && csv))
        st = rs_err_set(err, RS_ERR_NOMEM, "bench site: out of memory");
    if (st == RS_OK && (mkdir(dir, 0777) || mkdir(cameras, 0777) || mkdir(observations, 0777)))
        st = rs_err_set(err, RS_ERR_IO, "%s: cannot create the folder", dir);
    const rs_site_spec_camera cam = {.id = "cam1",
                                     .model = RS_SITE_CAMERAS_DIR "/cam1" RS_CAMERA_EXT_CAMERAMODEL,
                                     .observations = RS_SITE_OBSERVATIONS_DIR "/cam1" RS_SITE_OBSERVATIONS_EXT};
    const rs_site_spec spec = {.name = "bench",
                               .origin = origin,
                               .landmark_sigma_h_m = 0.3,
                               .landmark_sigma_v_m = 0.5,
                               .cameras = &cam,
                               .Ncameras = 1};
    if (st == RS_OK) st = rs_site_write_json(dir, &spec, RS_SITE_LAYOUT_TOOL, err);
    if (st == RS_OK) st = rs_site_write_landmarks(dir, l, N, 0, RS_SITE_LAYOUT_HAND, err);
    rs_camera c = {0};
    const mrcal_lensmodel_t pinhole = {.type = MRCAL_LENSMODEL_PINHOLE};
    const double intrinsics[4] = {1000, 1000, 959.5, 539.5};
    if (st == RS_OK) st = rs_camera_init(&c, &pinhole, intrinsics, 1920, 1080, err);
    if (st == RS_OK) st = rs_camera_write_cameramodel(&c, model, err);
    rs_camera_free(&c);
    rs_site_observation obs[4];
    for (int k = 0; k < 4; k++)
        obs[k] = (rs_site_observation){.ilandmark = 2 + k, .q_px = {400.0 + 300 * k, 300.0 + 100 * k}, .sigma_px = 1};
    if (st == RS_OK)
        st = Npicks > 0 ? write_picks(csv, Npicks, Nunknown, err) : rs_site_write_observations(csv, obs, 4, l, err);
    free(cameras), free(observations), free(model), free(csv);
    free(l), free(p), free(llh), free(ids);
    return st;
}

static void remove_site(const char *dir)
{
    static const char *const files[] = {RS_SITE_JSON,
                                        RS_SITE_LANDMARKS,
                                        RS_SITE_CAMERAS_DIR "/cam1" RS_CAMERA_EXT_CAMERAMODEL,
                                        RS_SITE_OBSERVATIONS_DIR "/cam1" RS_SITE_OBSERVATIONS_EXT,
                                        RS_SITE_CAMERAS_DIR,
                                        RS_SITE_OBSERVATIONS_DIR,
                                        NULL};
    for (int k = 0; files[k]; k++) {
        char *f = rs_io_join(dir, files[k]);
        if (f) remove(f);
        free(f);
    }
    remove(dir);
}

// What the child sends back.
typedef struct {
    double check_s, cpu_s, peak_mib;
    int Nerrors, Nwarnings;
    bool found;
    rs_status st;
} child_result;

static child_result check_in_child(const char *dir, int N, int Nunknown)
{
    child_result r = {.st = RS_OK};
    const double t0 = now_s();
    rs_site_report *rep = NULL;
    rs_err e = {0};
    r.st = rs_site_check(&rep, dir, &e);
    r.check_s = now_s() - t0;
    struct rusage u;
    getrusage(RUSAGE_SELF, &u);
    r.cpu_s = (double)u.ru_utime.tv_sec + 1e-6 * (double)u.ru_utime.tv_usec + (double)u.ru_stime.tv_sec +
              1e-6 * (double)u.ru_stime.tv_usec;
    r.peak_mib = (double)u.ru_maxrss / 1024.0; // kB on Linux
    if (rep) {
        char dup_id[16], coincident_id[16];
        snprintf(dup_id, sizeof dup_id, "L%07d", 0);
        snprintf(coincident_id, sizeof coincident_id, "L%07d", N - 2);
        bool dup = false, coincident = false;
        int unknown = 0;
        for (int i = 0; i < rep->N; i++) {
            const rs_site_diag *d = &rep->diags[i];
            const bool is_id = d->feature_id && d->feature == N - 1 && !strcmp(d->feature_id, dup_id);
            const bool is_pos = d->feature_id && d->feature == N - 2 && !strcmp(d->feature_id, coincident_id);
            unknown += d->severity == RS_SITE_ERROR && d->field && !strcmp(d->field, "landmark") &&
                       strstr(d->message, "is not a landmark");
            dup = dup || (d->severity == RS_SITE_ERROR && is_id && strstr(d->message, "duplicate id"));
            coincident =
                coincident || (d->severity == RS_SITE_WARNING && is_pos && strstr(d->message, "same position"));
        }
        r.Nerrors = rep->Nerrors, r.Nwarnings = rep->Nwarnings;
        r.found = dup && coincident && unknown == Nunknown && rep->Nerrors == 1 + Nunknown && rep->Nwarnings == 1;
        rs_site_report_free(rep);
    }
    return r;
}

rs_status rs_bench_site_run(rs_bench_site_row *row, int N, int Npicks, int Nunknown, uint64_t seed,
                            const char *work_dir, rs_err *err)
{
    memset(row, 0, sizeof *row);
    row->Nlandmarks = N;
    row->Npicks = Npicks > 0 ? Npicks : 4, row->Nunknown = Npicks > 0 ? Nunknown : 0;
    if (N < 4) return rs_err_set(err, RS_ERR_USAGE, "bench site: at least 4 landmarks");
    if (Npicks > N - 1 || Npicks < 0 || Nunknown < 0)
        return rs_err_set(err, RS_ERR_USAGE, "bench site: %d picks of %d landmarks: at most N - 1", Npicks, N);
    char name[64];
    snprintf(name, sizeof name, "site-%d", N);
    char *dir = rs_io_join(work_dir, name), *geojson = dir ? rs_io_join(dir, RS_SITE_LANDMARKS) : NULL;
    if (!dir || !geojson) {
        free(dir);
        return rs_err_set(err, RS_ERR_NOMEM, "bench site: out of memory");
    }
    // the site is written in a child too: the writer's cJSON tree (1.5 GB for 10^6 landmarks),
    // freed but kept by malloc, would otherwise be inherited by the checking child
    double t0 = now_s();
    rs_status st = RS_OK;
    pid_t writer = fork();
    if (writer < 0) st = rs_err_set(err, RS_ERR_IO, "bench site: cannot fork");
    if (writer == 0) {
        rs_err e = {0};
        _exit(write_site(dir, N, Npicks, row->Nunknown, seed, &e) == RS_OK
                  ? 0
                  : (fprintf(stderr, "bench site: %s\n", e.msg), 1));
    }
    int wstatus = 0;
    if (writer > 0 && (waitpid(writer, &wstatus, 0) != writer || !WIFEXITED(wstatus) || WEXITSTATUS(wstatus)))
        st = rs_err_set(err, RS_ERR_IO, "bench site: writing the site of %d landmarks in %s failed", N, dir);
    row->write_s = now_s() - t0;
    struct stat sb;
    if (st == RS_OK && stat(geojson, &sb) == 0) row->file_mib = (double)sb.st_size / (1024.0 * 1024.0);
    int fd[2] = {-1, -1};
    if (st == RS_OK && pipe(fd)) st = rs_err_set(err, RS_ERR_IO, "bench site: cannot create a pipe");
    pid_t pid = st == RS_OK ? fork() : -1;
    if (st == RS_OK && pid < 0) st = rs_err_set(err, RS_ERR_IO, "bench site: cannot fork");
    if (pid == 0) { // the child: check, send the figures, leave without running atexit handlers
        close(fd[0]);
        child_result r = check_in_child(dir, N, row->Nunknown);
        const ssize_t n = write(fd[1], &r, sizeof r);
        _exit(n == (ssize_t)sizeof r ? 0 : 1);
    }
    if (pid > 0) {
        close(fd[1]);
        fd[1] = -1;
        child_result r;
        const ssize_t n = read(fd[0], &r, sizeof r);
        int status = 0;
        waitpid(pid, &status, 0);
        if (n != (ssize_t)sizeof r || !WIFEXITED(status) || WEXITSTATUS(status))
            st = rs_err_set(err, RS_ERR_IO, "bench site: the check of %d landmarks did not finish (killed?)", N);
        else if (r.st != RS_OK)
            st = rs_err_set(err, r.st, "bench site: the check of %d landmarks failed: %s", N, rs_strerror(r.st));
        else {
            row->check_s = r.check_s, row->check_cpu_s = r.cpu_s, row->peak_mib = r.peak_mib;
            row->Nerrors = r.Nerrors, row->Nwarnings = r.Nwarnings, row->found = r.found;
        }
    }
    for (int k = 0; k < 2; k++)
        if (fd[k] >= 0) close(fd[k]);
    remove_site(dir);
    free(geojson);
    free(dir);
    return st;
}
