/* thorax check (not yet written). */
#include <stdio.h>
#include "cli/cli.h"
int cmd_check(int argc, char **argv)
{
    (void)argc; (void)argv;
    fprintf(stderr, "thorax check: not yet implemented\n");
    return 1;
}
