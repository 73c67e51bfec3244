#include "testlib.h"

int tl_pass, tl_fail;

void tl_report_fail(const char *file, int line, const char *what)
{
    fprintf(stderr, "%s:%d: check failed: %s\n", file, line, what);
}

int tl_finish(void)
{
    printf("%d passed, %d failed\n", tl_pass, tl_fail);
    return tl_fail ? 1 : (tl_pass ? 0 : 1); /* a test that checked nothing fails */
}
