// Runs POV-Ray exactly as roadside does (rs_synth_povray_run: its folder, HOME, environment and
// Landlock confinement) on a given scene, for tests/synth/povray/test_povray_sandbox.py.
//   test_povray_sandbox_run probe             "landlock ABI N" or "unconfined: WHY"
//   test_povray_sandbox_run run DIR SCENE     renders DIR/SCENE at 8x8 into DIR/probe.png;
//                                             prints "ok" (exit 0) or the error (exit 1)
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "synth/povray/rs_synth_render.h"
#include "synth/povray/rs_synth_sandbox.h"

int main(int argc, char **argv)
{
    if (argc == 2 && !strcmp(argv[1], "probe")) {
        rs_synth_sandbox_info box;
        rs_synth_sandbox_probe(&box);
        if (box.abi > 0)
            printf("landlock ABI %d\n", box.abi);
        else
            printf("unconfined: %s\n", box.why);
        return 0;
    }
    if (argc != 4 || strcmp(argv[1], "run") != 0) {
        fprintf(stderr, "usage: test_povray_sandbox_run probe | run DIR SCENE\n");
        return 2;
    }
    const char *povray = rs_synth_povray_exe(NULL);
    char input[1100];
    snprintf(input, sizeof(input), "+I%s", argv[3]);
    const char *args[] = {input, "+Oprobe.png", "+W8", "+H8", "-D", "+WT1"};
    rs_err err = {RS_OK, ""};
    const rs_status st = rs_synth_povray_run(povray, argv[2], args, 6, NULL, &err);
    if (st) {
        printf("%s\n", err.msg);
        return 1;
    }
    printf("ok\n");
    return 0;
}
