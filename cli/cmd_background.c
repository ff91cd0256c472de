// PLACEHOLDER, replaced by the module's real command.
#include "rs_cli.h"

int rs_cli_background(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "roadside background: under construction\n");
    return RS_EXIT_FAIL;
}

int rs_cli_site_render_backgrounds(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "roadside site render-backgrounds: under construction\n");
    return RS_EXIT_FAIL;
}
