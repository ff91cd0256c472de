// PLACEHOLDER, replaced by the module's real command.
#include "rs_cli.h"

int rs_cli_calib(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "roadside calib: under construction\n");
    return RS_EXIT_FAIL;
}

int rs_cli_locate(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "roadside locate: under construction\n");
    return RS_EXIT_FAIL;
}
