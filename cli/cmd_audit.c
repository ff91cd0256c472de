// PLACEHOLDER, replaced by the module's real command.
#include "rs_cli.h"

int rs_cli_audit(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "roadside audit: under construction\n");
    return RS_EXIT_FAIL;
}
