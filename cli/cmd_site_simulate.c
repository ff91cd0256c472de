// PLACEHOLDER, replaced by the simulator's command.
#include "rs_cli.h"

int rs_cli_site_simulate(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "roadside site simulate: under construction\n");
    return RS_EXIT_FAIL;
}
