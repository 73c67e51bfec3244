/* thorax surfaces (not yet written). */
#include <stdio.h>
#include "cli/cli.h"
int cmd_surfaces(int argc, char **argv)
{
    (void)argc; (void)argv;
    fprintf(stderr, "thorax surfaces: not yet implemented\n");
    return 1;
}
