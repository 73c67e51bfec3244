/*
 * The library's side of boundary elements over MPI ranks (thorax/bem/bem.h): forwarders to the
 * solver module's table (src/bem/scalapack_module.h), loaded on the first call.
 */
#include <stddef.h>

#include "bem/scalapack_module.h"
#include "thorax/core/module.h"

static const thx_bem_petsc *volatile g_api;

/* The table, or NULL with the reason in ctx (when not NULL). */
static const thx_bem_petsc *api(thx_ctx *ctx)
{
    return (const thx_bem_petsc *)thx_solver_module_table(ctx, "thx_bem_petsc_get", THX_BEM_PETSC_ABI, (const void *volatile *)&g_api);
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
