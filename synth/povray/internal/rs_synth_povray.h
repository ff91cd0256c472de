// rs_synth_povray.h -- running the real POV-Ray (synth/povray/rs_synth_povray.c): what the renderer
// (synth/povray/rs_synth_render.c) uses to run several povray processes at once. Internal to synth;
// the API is rs_synth_povray_run (synth/povray/rs_synth_render.h), which is spawn then reap.
#pragma once
#include <sys/types.h>

#include "core/rs_status.h"

// Writes OUT/.povray/3.7/povray.conf, which asks povray to restrict its file I/O to the output
// folder (povray is run with HOME = OUT so that this is the user configuration it reads).
// POV-Ray 3.7.0.10 does not enforce it (docs/povray.md): Landlock does (rs_synth_sandbox.h).
rs_status rs_synth_povray_write_conf(const char *out_dir, rs_err *err);

// Starts `povray ARGS` (Nargs <= 30) in folder `dir` as rs_synth_povray_run does (HOME = dir,
// POVINC/POVINI unset, confined by Landlock, killed if we die), its output appended to
// dir/LOG_NAME, without waiting. out: *pid. Errors: RS_ERR_USAGE (too many arguments),
// RS_ERR_NOMEM, RS_ERR_EXTERNAL (fork).
rs_status rs_synth_povray_spawn( // out
    pid_t *pid,
    // in
    const char *povray, const char *dir, const char *log_name, const char *const *args, int Nargs, rs_err *err);

// Waits for the povray process `pid` of rs_synth_povray_spawn; a non-zero exit as
// rs_synth_povray_run's errors, quoting the last line of dir/LOG_NAME.
rs_status rs_synth_povray_reap(pid_t pid, const char *povray, const char *dir, const char *log_name, rs_err *err);

// A monotonic clock, seconds.
double rs_synth_povray_now_s(void);

// Removes the work files of a render from out_dir: the passes' scenes, .ini files, outputs and
// logs, the environment map, the configuration and povray.log (a missing file, or a folder
// someone else put there, is left as it is). Users' textures: rs_synth_scene_remove_textures.
void rs_synth_povray_remove_work(const char *out_dir);
