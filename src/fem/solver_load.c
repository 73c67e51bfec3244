/*
 * The library's side of fem's solver functions (thorax/fem/fem.h): forwarders to the solver
 * module's table (src/fem/solver_module.h), loaded on the first call that needs PETSc. A run that
 * never solves never loads PETSc. A system exists only once the module is loaded.
 */
#include <stddef.h>

#include "fem/solver_module.h"
#include "thorax/core/module.h"

static const thx_fem_petsc *volatile g_api;

/* The table, or NULL with the reason in ctx (when not NULL). */
static const thx_fem_petsc *api(thx_ctx *ctx)
{
    return (const thx_fem_petsc *)thx_solver_module_table(ctx, "thx_fem_petsc_get", THX_FEM_PETSC_ABI, (const void *volatile *)&g_api);
}

thx_status thx_fem_available(thx_ctx *ctx) { return api(ctx) ? THX_OK : THX_ESOLVER; }

thx_status thx_fem_init(int argc, char **argv, int *rank, int *size)
{
    return api(NULL) ? g_api->init(argc, argv, rank, size) : THX_ESOLVER;
}

void thx_fem_finalize(void)
{
    if (g_api) g_api->finalize();
}

int thx_fem_options_unused(int list) { return g_api ? g_api->options_unused(list) : 0; }

thx_status thx_fem_system_create(thx_ctx *ctx, const thx_csr *K, const unsigned char *kind, int pin_one,
                                 thx_fem_system **out)
{
    return api(ctx) ? g_api->system_create(ctx, K, kind, pin_one, out) : THX_ESOLVER;
}

thx_status thx_fem_system_create_parts(thx_ctx *ctx, const thx_csr *K, const unsigned char *kind, int pin_one,
                                       const int32_t *part, thx_fem_system **out)
{
    return api(ctx) ? g_api->system_create_parts(ctx, K, kind, pin_one, part, out) : THX_ESOLVER;
}

void thx_fem_system_destroy(thx_fem_system **s)
{
    if (g_api && s && *s) g_api->system_destroy(s);
}

thx_status thx_fem_solve(thx_ctx *ctx, thx_fem_system *s, double *phi, const double *load, int warm,
                         thx_fem_solve_stats *st)
{
    return g_api->solve(ctx, s, phi, load, warm, st);
}

thx_status thx_fem_system_dump(thx_ctx *ctx, thx_fem_system *s, const double *phi, const double *load, const char *path)
{
    return g_api->system_dump(ctx, s, phi, load, path);
}

void thx_fem_system_hint_rhs(thx_fem_system *s, size_t n_rhs) { g_api->system_hint_rhs(s, n_rhs); }

thx_status thx_fem_solve_block(thx_ctx *ctx, thx_fem_system *s, double *phi, const double *load, size_t k, int warm,
                               thx_fem_solve_stats *st)
{
    return g_api->solve_block(ctx, s, phi, load, k, warm, st);
}

thx_status thx_fem_solve_rows(thx_ctx *ctx, thx_fem_system *s, const int32_t *pnode, size_t np, const double *pres,
                              size_t k, int warm, const int32_t *rows, size_t m, double *out, thx_fem_solve_stats *st)
{
    return g_api->solve_rows(ctx, s, pnode, np, pres, k, warm, rows, m, out, st);
}

size_t thx_fem_system_block(const thx_fem_system *s) { return g_api->system_block(s); }

void thx_fem_system_set_block(thx_fem_system *s, size_t k) { g_api->system_set_block(s, k); }

void thx_fem_system_info(const thx_fem_system *s, size_t *n_free, size_t *n_prescribed, double *setup_seconds)
{
    g_api->system_info(s, n_free, n_prescribed, setup_seconds);
}

double thx_fem_system_matrix_seconds(const thx_fem_system *s) { return g_api->system_matrix_seconds(s); }

void thx_fem_system_describe(const thx_fem_system *s, char ksp[32], char pc[32], int *ranks)
{
    g_api->system_describe(s, ksp, pc, ranks);
}

void thx_fem_system_factor_info(const thx_fem_system *s, thx_fem_factor_info *out) { g_api->system_factor_info(s, out); }
