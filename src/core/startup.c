/* The environment a heavy command starts in (thorax/core/startup.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "thorax/core/blas_kernels.h"
#include "thorax/core/startup.h"

void thx_startup_heavy(char **argv)
{
    static const char guard[] = "THORAX_BLAS_REEXEC";
    if (getenv("THORAX_BLAS_PROBE")) exit(thx_blas_probe_run()); /* a probe of thx_blas_chosen_core's */
    if (getenv(guard)) return;
    const char *preload = getenv("LD_PRELOAD");
    if (preload && strstr(preload, "vgpreload")) return; /* valgrind */
    const char *core = NULL;
    if (!getenv("OPENBLAS_CORETYPE")) core = thx_blas_chosen_core(thx_blas_loaded_core(), argv);
    /* OpenMP's threads waiting at a barrier: a short spin, then sleep, unless the user chose */
    int spin = !getenv("GOMP_SPINCOUNT") && !getenv("OMP_WAIT_POLICY");
    if (!core && !spin) return;
    if ((core && setenv("OPENBLAS_CORETYPE", core, 1)) || (spin && setenv("GOMP_SPINCOUNT", THX_STARTUP_SPINCOUNT, 1)) ||
        setenv(guard, core ? core : "1", 1))
        return;
    execv("/proc/self/exe", argv);
    /* the execution failed: go on as we are */
    if (core) unsetenv("OPENBLAS_CORETYPE");
    if (spin) unsetenv("GOMP_SPINCOUNT");
    unsetenv(guard);
}
