/*
 * The library's side of boundary elements over MPI ranks (thorax/bem/bem.h): forwarders to the
 * solver module's table (src/bem/scalapack_module.h), loaded on the first call.
 */
#include <pthread.h>
#include <stddef.h>

#include "bem/scalapack_module.h"
#include "thorax/core/module.h"

static const thx_bem_petsc *g_api;
static pthread_mutex_t g_lock = PTHREAD_MUTEX_INITIALIZER;

/* The table, or NULL with the reason in ctx. */
static const thx_bem_petsc *api(thx_ctx *ctx)
{
    pthread_mutex_lock(&g_lock);
    if (!g_api) {
        const thx_bem_petsc *(*get)(void) = (const thx_bem_petsc *(*)(void))thx_solver_module_symbol(ctx, "thx_bem_petsc_get");
        const thx_bem_petsc *t = get ? get() : NULL;
        if (t && t->abi == THX_BEM_PETSC_ABI)
            g_api = t;
        else if (t && ctx)
            thx_error(ctx, THX_ESOLVER, "the solver module libthorax-petsc.so was built for another version of thorax");
    }
    pthread_mutex_unlock(&g_lock);
    return g_api;
}

thx_status thx_bem_transfer_parallel(thx_ctx *ctx, const thx_bem *b, size_t heart, double *T, thx_bem_info *info)
{
    return api(ctx) ? g_api->transfer_parallel(ctx, b, heart, T, info) : THX_ESOLVER;
}

thx_status thx_bem_dipoles_parallel(thx_ctx *ctx, const thx_bem *b, const double *pos, const double *mom, size_t n,
                                    double *phi, thx_bem_info *info)
{
    return api(ctx) ? g_api->dipoles_parallel(ctx, b, pos, mom, n, phi, info) : THX_ESOLVER;
}
