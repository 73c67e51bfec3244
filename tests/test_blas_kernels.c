/* thx_blas_better_core (thorax/core/blas_kernels.h) against the processor's flags as Linux lists
 * them in /proc/cpuinfo, read here on their own: "Prescott" (OpenBLAS's fallback) gets SkylakeX's
 * kernels exactly when avx512f, avx512cd, avx512bw, avx512dq and avx512vl are all listed,
 * Haswell's when avx2 and fma are (and not all of those), nothing otherwise; a core OpenBLAS
 * recognised (any other name) and no name are left alone. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/core/blas_kernels.h"

static char flags[8192];

static int has(const char *flag)
{
    size_t n = strlen(flag);
    for (const char *p = flags; (p = strstr(p, flag)); p += n)
        if ((p == flags || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\n' || p[n] == '\0')) return 1;
    return 0;
}

int main(void)
{
    FILE *f = fopen("/proc/cpuinfo", "r");
    CHECK(f != NULL);
    if (f) {
        char line[sizeof flags];
        while (fgets(line, sizeof line, f))
            if (strncmp(line, "flags", 5) == 0) {
                const char *colon = strchr(line, ':');
                snprintf(flags, sizeof flags, "%s", colon ? colon + 1 : "");
                break;
            }
        fclose(f);
    }
    CHECK(flags[0] != '\0');
    const char *expect = NULL;
    if (has("avx512f") && has("avx512cd") && has("avx512bw") && has("avx512dq") && has("avx512vl"))
        expect = "SkylakeX";
    else if (has("avx2") && has("fma"))
        expect = "Haswell";
    const char *got = thx_blas_better_core("Prescott");
    printf("processor: avx2 %d fma %d avx512f %d; for Prescott: %s (expected %s)\n", has("avx2"),
           has("fma"), has("avx512f"), got ? got : "nothing", expect ? expect : "nothing");
    CHECK((got == NULL) == (expect == NULL));
    if (got && expect) CHECK(strcmp(got, expect) == 0);
    CHECK(thx_blas_better_core(NULL) == NULL);
    CHECK(thx_blas_better_core("Haswell") == NULL);
    CHECK(thx_blas_better_core("SkylakeX") == NULL);
    CHECK(thx_blas_better_core("Zen") == NULL);
    CHECK(thx_blas_better_core("prescott") == NULL); /* OpenBLAS's own spelling only */
    return tl_finish();
}
