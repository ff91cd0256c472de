// rs_synth_povray.c -- running the real POV-Ray: its configuration, starting a confined povray
// process and waiting for it (synth/povray/internal/rs_synth_povray.h; rs_synth_povray_run in
// rs_synth_render.h; docs/povray.md, "Confinement").
#include "synth/povray/internal/rs_synth_povray.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "core/rs_io.h"
#include "synth/backdrop/rs_synth_light.h"
#include "synth/povray/rs_synth_render.h"
#include "synth/povray/rs_synth_sandbox.h"

// Writes OUT/.povray/3.7/povray.conf, which asks povray to restrict its file I/O to the output
// folder (povray is run with HOME = OUT so that this is the user configuration it reads).
// POV-Ray 3.7.0.10 does not enforce it (docs/povray.md): Landlock does (rs_synth_sandbox.h).
rs_status rs_synth_povray_write_conf(const char *out_dir, rs_err *err)
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

double rs_synth_povray_now_s(void)
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

// Starts `povray ARGS` in `dir` (rs_synth_povray_run), its output appended to dir/LOG_NAME;
// *pid the child's process id.
// What the child of spawn_child needs, all made before it starts: it shares our memory until it
// runs povray, so it only makes system calls (no allocation, no change to our environment).
typedef struct {
    const char *log, *dir, *exe, *const *argv;
    char *const *envp;
    int abi; // Landlock ABI, 0: unconfined
    pid_t parent;
} spawn_args;

// vfork + exec: unlike fork, no copy of our page tables and no copy-on-write faults in the
// worker afterwards (issue 18's cost: a fork of a 100 MB worker cost 45 ms of CPU, measured with
// a worker rewriting its heap; vfork 0.01 ms). The child runs on our stack until it calls
// execve or _exit, as vfork(2) requires.
static pid_t spawn_child(const spawn_args *a)
{
    const pid_t pid = vfork();
    if (pid != 0) return pid;
    // povray dies with us (a killed roadside leaves no povray running; kept across exec)
    if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != a->parent) _exit(126);
    const int fd = open(a->log, O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd < 0 || chdir(a->dir) != 0) _exit(126);
    dup2(fd, 1);
    dup2(fd, 2);
    close(fd);
    // confined to this folder and the system's programs (rs_synth_sandbox.h)
    const char *step = NULL;
    const int e = a->abi > 0 ? rs_synth_sandbox_enter(a->abi, a->exe, &step) : 0;
    if (e) {
        child_say(2, "cannot confine povray (Landlock): ", step, e);
        _exit(125);
    }
    if (a->exe) execve(a->exe, (char *const *)a->argv, a->envp);
    _exit(127);
}

rs_status rs_synth_povray_spawn(pid_t *pid_out, const char *povray, const char *dir, const char *log_name,
                                const char *const *args, int Nargs, rs_err *err)
{
    const char *argv[32];
    if (Nargs < 0 || Nargs > 30) return rs_err_set(err, RS_ERR_USAGE, "povray: %d arguments (at most 30)", Nargs);
    argv[0] = povray;
    for (int i = 0; i < Nargs; i++) argv[1 + i] = args[i];
    argv[1 + Nargs] = NULL;
    rs_synth_sandbox_info box;
    rs_synth_sandbox_probe(&box);
    // the environment: ours without POVINC, POVINI and HOME, then HOME = the folder, absolute for
    // povray's %HOME%
    char *abs = realpath(dir, NULL);
    if (!abs) return rs_err_set(err, RS_ERR_IO, "%s: %s", dir, strerror(errno));
    extern char **environ;
    size_t Nenv = 0;
    while (environ && environ[Nenv]) Nenv++;
    char **envp = malloc((Nenv + 2) * sizeof(char *)), *home = malloc(strlen(abs) + 6);
    char *log = rs_io_join(dir, log_name);
    char *exe = find_program(povray); // NULL: not found ("cannot run", exit 127)
    rs_status st = RS_OK;
    if (!envp || !home || !log) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    size_t n = 0;
    for (size_t i = 0; i < Nenv; i++)
        if (strncmp(environ[i], "POVINC=", 7) && strncmp(environ[i], "POVINI=", 7) && strncmp(environ[i], "HOME=", 5))
            envp[n++] = environ[i];
    snprintf(home, strlen(abs) + 6, "HOME=%s", abs);
    envp[n++] = home;
    envp[n] = NULL;
    const spawn_args a = {log, dir, exe, argv, envp, box.abi, getpid()};
    const pid_t pid = spawn_child(&a);
    if (pid < 0)
        st = rs_err_set(err, RS_ERR_EXTERNAL, "vfork: %s", strerror(errno));
    else
        *pid_out = pid;
done:
    free(envp);
    free(abs);
    free(home);
    free(log);
    free(exe);
    return st;
}

// Waits for the povray process `pid` started by rs_synth_povray_spawn; its exit status as an error
// quoting the last line of dir/LOG_NAME.
rs_status rs_synth_povray_reap(pid_t pid, const char *povray, const char *dir, const char *log_name, rs_err *err)
{
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
        ;
    if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return RS_OK;
    char *log = rs_io_join(dir, log_name), *text = NULL;
    char last[256] = "";
    if (log && rs_io_read_file(&text, NULL, log, NULL) == RS_OK) {
        // last non-empty line
        size_t n = strlen(text);
        while (n > 0 && (text[n - 1] == '\n' || text[n - 1] == '\r')) text[--n] = 0;
        const char *nl = strrchr(text, '\n');
        snprintf(last, sizeof(last), "%s", nl ? nl + 1 : text);
    }
    free(text);
    rs_status st;
    if (WIFEXITED(status) && WEXITSTATUS(status) == 125 && strstr(last, "cannot confine povray"))
        st = rs_err_set(err, RS_ERR_EXTERNAL,
                        "%s (see %s); set ROADSIDE_POVRAY_SANDBOX=off to run povray unconfined "
                        "(docs/povray.md)",
                        last, log ? log : log_name);
    else if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
        st = rs_err_set(err, RS_ERR_EXTERNAL,
                        "cannot run \"%s\": is POV-Ray 3.7 installed (Debian package "
                        "povray)? Set ROADSIDE_POVRAY to its path",
                        povray);
    else if (rs_io_disk_full(dir)) // povray says "Fatal error in renderer", not why
        st = rs_err_set(err, RS_ERR_IO, "disk full writing %s: povray failed (exit %d)", dir,
                        WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    else
        st = rs_err_set(err, RS_ERR_EXTERNAL, "povray failed in %s (exit %d): %s (see %s)", dir,
                        WIFEXITED(status) ? WEXITSTATUS(status) : -1, last, log ? log : log_name);
    free(log);
    return st;
}

const char *rs_synth_povray_exe(const char *given)
{
    if (given) return *given ? given : "povray";
    const char *env = getenv("ROADSIDE_POVRAY");
    return env && *env ? env : "povray";
}

rs_status rs_synth_povray_run(const char *povray, const char *dir, const char *const *args, int Nargs, double *seconds,
                              rs_err *err)
{
    const double t0 = rs_synth_povray_now_s();
    pid_t pid;
    rs_status st = rs_synth_povray_spawn(&pid, povray, dir, "povray.log", args, Nargs, err);
    if (!st) st = rs_synth_povray_reap(pid, povray, dir, "povray.log", err);
    if (seconds) *seconds += rs_synth_povray_now_s() - t0;
    return st;
}

void rs_synth_povray_remove_work(const char *out_dir)
{
    static const char *const names[] = {
        "pass_colour.pov",   "pass_colour.ini",   "pass_colour.png",   "pass_colour.ppm",     "pass_ids.pov",
        "pass_ids.ini",      "pass_ids.png",      "pass_ids.log",      "pass_shadow.pov",     "pass_shadow.ini",
        "pass_shadow.png",   "pass_shadow.log",   "pass_mirror.pov",   "pass_mirror.ini",     "pass_mirror.png",
        "pass_mirror.log",   "pass_colour_2.pov", "pass_colour_2.ini", "pass_colour_2.ppm",   "pass_colour_2.log",
        "pass_colour_3.pov", "pass_colour_3.ini", "pass_colour_3.ppm", "pass_colour_3.log",   "pass_colour_4.pov",
        "pass_colour_4.ini", "pass_colour_4.ppm", "pass_colour_4.log", RS_SYNTH_ENV_MAP_FILE, ".povray/3.7/povray.conf",
        ".povray/3.7",       ".povray",           "povray.log"};
    for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); i++) {
        char *p = rs_io_join(out_dir, names[i]);
        if (p) (void)remove(p); // a missing file, or a folder someone else used: left as it is
        free(p);
    }
}
