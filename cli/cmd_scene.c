// PLACEHOLDER, replaced by the module's real command.
#include "rs_cli.h"

int rs_cli_scene(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "roadside scene: under construction\n");
    return RS_EXIT_FAIL;
}
