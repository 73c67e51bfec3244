/* OpenBLAS's kernels on processors it does not know (thorax/core/blas_kernels.h). */
#include <dlfcn.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "thorax/core/blas_kernels.h"

const char *thx_blas_better_core(const char *loaded)
{
    if (!loaded || strcmp(loaded, "Prescott") != 0) return NULL;
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") &&
        __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") &&
        __builtin_cpu_supports("avx512vl"))
        return "SkylakeX";
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return "Haswell";
#endif
    return NULL;
}

void thx_blas_pick_kernels(char **argv)
{
    static const char guard[] = "THORAX_BLAS_REEXEC";
    if (getenv("OPENBLAS_CORETYPE") || getenv(guard)) return;
    const char *preload = getenv("LD_PRELOAD");
    if (preload && strstr(preload, "vgpreload")) return; /* valgrind */
    char *(*corename)(void) = (char *(*)(void))dlsym(RTLD_DEFAULT, "openblas_get_corename");
    if (!corename) return; /* another BLAS */
    const char *core = thx_blas_better_core(corename());
    if (!core) return;
    if (setenv("OPENBLAS_CORETYPE", core, 1) || setenv(guard, core, 1)) return;
    execv("/proc/self/exe", argv);
    unsetenv("OPENBLAS_CORETYPE"); /* the execution failed: go on as we are */
}
