/* thorax export (not yet written). */
#include <stdio.h>
#include "cli/cli.h"
int cmd_export(int argc, char **argv)
{
    (void)argc; (void)argv;
    fprintf(stderr, "thorax export: not yet implemented\n");
    return 1;
}
