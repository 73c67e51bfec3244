/* The environment a heavy command starts in (thorax/core/startup.h). */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "thorax/core/blas_kernels.h"
#include "thorax/core/startup.h"

/* 1 when the kernel gives transparent huge pages to a process that asks (madvise) or always. */
static int thp_available(void)
{
    FILE *f = fopen("/sys/kernel/mm/transparent_hugepage/enabled", "r");
    if (!f) return 0;
    char line[128] = "";
    int ok = fgets(line, sizeof line, f) && (strstr(line, "[always]") || strstr(line, "[madvise]"));
    fclose(f);
    return ok;
}

void thx_startup_heavy(char **argv)
{
    static const char guard[] = "THORAX_BLAS_REEXEC";
    if (getenv(guard)) return;
    const char *preload = getenv("LD_PRELOAD");
    if (preload && strstr(preload, "vgpreload")) return; /* valgrind */
    const char *core = NULL;
    if (!getenv("OPENBLAS_CORETYPE")) {
        char *(*corename)(void) = (char *(*)(void))dlsym(RTLD_DEFAULT, "openblas_get_corename");
        if (corename) core = thx_blas_better_core(corename());
    }
    const char *tun = getenv("GLIBC_TUNABLES");
    int thp = !(tun && strstr(tun, "glibc.malloc.hugetlb")) && thp_available();
    if (!core && !thp) return;
    char *old_tun = tun ? strdup(tun) : NULL;
    if (tun && !old_tun) return;
    char tunables[4096];
    if (thp && snprintf(tunables, sizeof tunables, "%s%sglibc.malloc.hugetlb=1", tun ? tun : "", tun && *tun ? ":" : "") >=
                   (int)sizeof tunables)
        thp = 0;
    if (!core && !thp) {
        free(old_tun);
        return;
    }
    if ((core && setenv("OPENBLAS_CORETYPE", core, 1)) || (thp && setenv("GLIBC_TUNABLES", tunables, 1)) ||
        setenv(guard, core ? core : "thp", 1)) {
        free(old_tun);
        return;
    }
    execv("/proc/self/exe", argv);
    /* the execution failed: go on as we are */
    if (core) unsetenv("OPENBLAS_CORETYPE");
    if (thp) {
        if (old_tun) setenv("GLIBC_TUNABLES", old_tun, 1);
        else unsetenv("GLIBC_TUNABLES");
    }
    unsetenv(guard);
    free(old_tun);
}
