/* thorax phantom (not yet written). */
#include <stdio.h>
#include "cli/cli.h"
int cmd_phantom(int argc, char **argv)
{
    (void)argc; (void)argv;
    fprintf(stderr, "thorax phantom: not yet implemented\n");
    return 1;
}
