// rs_synth_sandbox.h -- confining povray with Linux Landlock: what a povray process started by
// roadside may open (docs/povray.md, "Confinement").
//
// Why: POV-Ray's own file I/O restriction does not hold. Measured with Debian 12's POV-Ray
// 3.7.0.10 under exactly the configuration roadside writes (OUT/.povray/3.7/povray.conf:
// "restricted", only "." permitted; /etc/povray/3.7/povray.conf also permits /tmp, %HOME% and
// the include folders): a scene's #fopen + #read of /etc/passwd, #include "/etc/hostname",
// #write to /tmp/x, to /var/tmp/x and to OUT/../x all succeed. roadside's scenes hold no file
// operation and no input text outside sanitised comments (rs_synth_scene.h): that is the first
// line of defence; this is the second.
//
// Method: Landlock (Linux >= 5.13, kernel-enforced, needs no privilege and no namespace, kept
// across exec; Salaün, "Landlock: unprivileged access control", docs.kernel.org). The child
// that becomes povray, between fork and exec, restricts itself to
//   read, list, execute   /usr, /bin, /sbin, /lib, /lib32, /lib64 (programs, libraries,
//                         POV-Ray's include files and fonts), /etc/povray (its configuration),
//                         /etc/ld.so.cache, and the povray executable itself
//   read and write        the folder povray runs in (its scene, configuration and outputs:
//                         create, remove, rename there), /dev/null
//   nothing else          every other file or folder: open, list, create, remove, link,
//                         rename, truncate (ABI >= 3), device ioctl (ABI >= 5) refused (EACCES)
//   network (ABI >= 4)    no TCP bind or connect
//   scope (ABI >= 6)      no signal to, no abstract unix socket of, a process outside
// (/proc and /tmp included: measured, a scene cannot open /proc/self/status or /proc/cpuinfo.)
// Not confined: file descriptors open before the restriction (povray's log on stdout and
// stderr), CPU time and memory, and sockets other than TCP (POV-Ray's scene language opens
// none). Rights a kernel does not know are not enforced: Linux 6.1 (Debian 12's) has ABI 2,
// files only; the ABI in force is reported.
//
// When Landlock cannot run (a kernel older than 5.13 or built without it, Landlock left out of
// the boot's lsm= list, a seccomp filter that refuses the system calls, as some container
// profiles do) or ROADSIDE_POVRAY_SANDBOX=off is set, povray runs unconfined:
// rs_synth_sandbox_probe says so, and why; the cli prints it. When Landlock is there but the
// restriction fails in the child, povray does not run (RS_ERR_EXTERNAL, the log names the step).
#pragma once
#include <stdbool.h>
#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int abi;       // the Landlock ABI version povray runs under (>= 1); 0: it runs unconfined
    char why[256]; // abi 0: why (the system call's error, or the environment variable)
} rs_synth_sandbox_info;

// What confines povray in this process: asks the kernel once for its Landlock ABI and restricts
// a forked trial process as povray's will be (later calls return the cached answer;
// ROADSIDE_POVRAY_SANDBOX is read at the first call). Cost: one fork, about a millisecond.
// out: info
void rs_synth_sandbox_probe(rs_synth_sandbox_info *info);

// Confines the calling process as described above, for a child between fork and exec: only
// system calls, no allocation (async-signal-safe). `abi` from rs_synth_sandbox_probe (>= 1);
// `exe` the program about to be executed, relative to the current folder if not absolute (may be
// NULL: no rule for it); the current folder is the one granted read and write.
// Returns 0, or an errno value with *step (may be NULL) naming the step that failed.
int rs_synth_sandbox_enter(int abi, const char *exe, const char **step);

#ifdef __cplusplus
}
#endif
