// PLACEHOLDER, replaced by the module's real command.
#include "rs_cli.h"

int rs_cli_synth(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "roadside synth: under construction\n");
    return RS_EXIT_FAIL;
}
