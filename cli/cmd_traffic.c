// PLACEHOLDER, replaced by the module's real command.
#include "rs_cli.h"

int rs_cli_traffic(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "roadside traffic: under construction\n");
    return RS_EXIT_FAIL;
}
