// PLACEHOLDER, replaced by the solver benchmark.
#include "rs_cli.h"

int rs_cli_bench_calib(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    fprintf(stderr, "roadside bench calib: under construction\n");
    return RS_EXIT_FAIL;
}
