// rs_synth_sandbox.c -- confining povray with Linux Landlock (rs_synth_sandbox.h). Called by
// rs_synth_render.c's povray runner; calls the kernel only (Landlock's three system calls,
// prctl, and one fork for the probe's trial). The constants of Landlock ABIs newer than the build's <linux/landlock.h> (Debian 12's
// has ABI 2) are the kernel's stable values (include/uapi/linux/landlock.h).
#define _GNU_SOURCE
#include "synth/povray/rs_synth_sandbox.h"

#include <errno.h>
#include <fcntl.h>
#include <linux/landlock.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#ifndef LANDLOCK_ACCESS_FS_REFER
#define LANDLOCK_ACCESS_FS_REFER (1ULL << 13) // ABI 2
#endif
#ifndef LANDLOCK_ACCESS_FS_TRUNCATE
#define LANDLOCK_ACCESS_FS_TRUNCATE (1ULL << 14) // ABI 3
#endif
#ifndef LANDLOCK_ACCESS_FS_IOCTL_DEV
#define LANDLOCK_ACCESS_FS_IOCTL_DEV (1ULL << 15) // ABI 5
#endif
#define RS_LANDLOCK_NET_BIND_TCP    (1ULL << 0) // ABI 4
#define RS_LANDLOCK_NET_CONNECT_TCP (1ULL << 1)
#define RS_LANDLOCK_SCOPE_ABSTRACT  (1ULL << 0) // ABI 6
#define RS_LANDLOCK_SCOPE_SIGNAL    (1ULL << 1)

// struct landlock_ruleset_attr as of ABI 6; the kernel is given the prefix its ABI knows.
typedef struct {
    uint64_t handled_access_fs;
    uint64_t handled_access_net; // ABI >= 4
    uint64_t scoped;             // ABI >= 6
} ruleset_attr;

// The file-system rights Landlock ABI `abi` handles (every one: deny by default).
static uint64_t fs_rights(int abi)
{
    uint64_t r = (LANDLOCK_ACCESS_FS_MAKE_SYM << 1) - 1; // ABI 1: EXECUTE .. MAKE_SYM
    if (abi >= 2) r |= LANDLOCK_ACCESS_FS_REFER;
    if (abi >= 3) r |= LANDLOCK_ACCESS_FS_TRUNCATE;
    if (abi >= 5) r |= LANDLOCK_ACCESS_FS_IOCTL_DEV;
    return r;
}

// Restricts a forked child the way povray's will be (without an executable rule): a filter that
// lets the version query through but not the rest is found here, not in every povray run.
static void trial(rs_synth_sandbox_info *info, int abi)
{
    const pid_t pid = fork();
    if (pid == 0) _exit(chdir("/") != 0 ? EACCES : rs_synth_sandbox_enter(abi, NULL, NULL) & 0xff);
    int status = 0;
    while (pid > 0 && waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
    if (pid > 0 && WIFEXITED(status) && WEXITSTATUS(status) == 0) {
        info->abi = abi;
        return;
    }
    snprintf(info->why, sizeof(info->why), "Linux Landlock (ABI %d) is there, but restricting a process fails: %s", abi,
             pid < 0             ? strerror(errno)
             : WIFEXITED(status) ? strerror(WEXITSTATUS(status))
                                 : "the trial process was killed");
}

void rs_synth_sandbox_probe(rs_synth_sandbox_info *info)
{
    static bool done = false;
    static rs_synth_sandbox_info cached;
    if (!done) {
        memset(&cached, 0, sizeof(cached));
        const char *env = getenv("ROADSIDE_POVRAY_SANDBOX");
        if (env && !strcmp(env, "off")) {
            snprintf(cached.why, sizeof(cached.why), "ROADSIDE_POVRAY_SANDBOX=off");
        } else {
            const long abi = syscall(SYS_landlock_create_ruleset, NULL, 0, LANDLOCK_CREATE_RULESET_VERSION);
            if (abi >= 1)
                trial(&cached, (int)abi);
            else
                snprintf(cached.why, sizeof(cached.why), "Linux Landlock is not available: %s",
                         errno == ENOSYS       ? "this kernel has no Landlock (Linux >= 5.13 has)"
                         : errno == EOPNOTSUPP ? "it is disabled (not in the boot's lsm= list)"
                         : errno == EPERM      ? "a seccomp filter refuses it (a container's profile?)"
                                               : strerror(errno));
        }
        done = true;
    }
    *info = cached;
}

// Allows `rights` beneath `path` (a folder, or a single file). A path that does not exist is
// skipped when `optional`. Returns 0 or an errno value.
static int allow(int ruleset, const char *path, uint64_t rights, bool optional)
{
    const int fd = open(path, O_PATH | O_CLOEXEC);
    if (fd < 0) return optional && (errno == ENOENT || errno == ENOTDIR) ? 0 : errno;
    struct landlock_path_beneath_attr rule = {.allowed_access = rights, .parent_fd = fd};
    const int r = (int)syscall(SYS_landlock_add_rule, ruleset, LANDLOCK_RULE_PATH_BENEATH, &rule, 0);
    const int e = errno;
    close(fd);
    return r == 0 ? 0 : e;
}

int rs_synth_sandbox_enter(int abi, const char *exe, const char **step)
{
    const uint64_t all = fs_rights(abi);
    const uint64_t read_dir = LANDLOCK_ACCESS_FS_EXECUTE | LANDLOCK_ACCESS_FS_READ_FILE | LANDLOCK_ACCESS_FS_READ_DIR;
    const uint64_t read_file = LANDLOCK_ACCESS_FS_EXECUTE | LANDLOCK_ACCESS_FS_READ_FILE;
    const uint64_t rw_file = LANDLOCK_ACCESS_FS_READ_FILE | LANDLOCK_ACCESS_FS_WRITE_FILE;
    ruleset_attr attr = {.handled_access_fs = all};
    size_t size = sizeof(uint64_t);
    if (abi >= 4) {
        attr.handled_access_net = RS_LANDLOCK_NET_BIND_TCP | RS_LANDLOCK_NET_CONNECT_TCP;
        size = 2 * sizeof(uint64_t);
    }
    if (abi >= 6) {
        attr.scoped = RS_LANDLOCK_SCOPE_ABSTRACT | RS_LANDLOCK_SCOPE_SIGNAL;
        size = 3 * sizeof(uint64_t);
    }
    const char *at = "landlock_create_ruleset";
    int e = 0;
    const int ruleset = (int)syscall(SYS_landlock_create_ruleset, &attr, size, 0);
    if (ruleset < 0) {
        e = errno;
        goto done;
    }
    static const char *const system_dirs[] = {"/usr", "/bin", "/sbin", "/lib", "/lib32", "/lib64", "/etc/povray"};
    for (size_t i = 0; i < sizeof(system_dirs) / sizeof(system_dirs[0]) && !e; i++) {
        at = system_dirs[i];
        e = allow(ruleset, system_dirs[i], read_dir, true);
    }
    if (!e) e = allow(ruleset, at = "/etc/ld.so.cache", read_file, true);
    if (!e) e = allow(ruleset, at = "/dev/null", rw_file, true);
    if (!e && exe) e = allow(ruleset, at = exe, read_file, true);
    if (!e) e = allow(ruleset, at = ".", all, false);
    if (!e && prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0) {
        at = "prctl(PR_SET_NO_NEW_PRIVS)";
        e = errno;
    }
    if (!e && syscall(SYS_landlock_restrict_self, ruleset, 0) != 0) {
        at = "landlock_restrict_self";
        e = errno;
    }
    close(ruleset);
done:
    if (step) *step = at;
    return e;
}
