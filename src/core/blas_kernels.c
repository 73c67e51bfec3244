/* OpenBLAS's kernels on processors it does not know (thorax/core/blas_kernels.h). */
#include <stdlib.h>
#include <string.h>

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
