/* fem's table in the solver module (src/fem/solver_module.h); built into libthorax-petsc.so with
 * src/fem/solver.c, not into the library. */
#include "fem/solver_module.h"

static const thx_fem_petsc table = {
    .abi = THX_FEM_PETSC_ABI,
    .init = thx_fem_init,
    .finalize = thx_fem_finalize,
    .options_unused = thx_fem_options_unused,
    .system_create = thx_fem_system_create,
    .system_destroy = thx_fem_system_destroy,
    .solve = thx_fem_solve,
    .system_dump = thx_fem_system_dump,
    .system_hint_rhs = thx_fem_system_hint_rhs,
    .solve_block = thx_fem_solve_block,
    .system_block = thx_fem_system_block,
    .system_set_block = thx_fem_system_set_block,
    .system_info = thx_fem_system_info,
    .system_matrix_seconds = thx_fem_system_matrix_seconds,
    .system_describe = thx_fem_system_describe,
    .system_factor_info = thx_fem_system_factor_info,
    .system_create_parts = thx_fem_system_create_parts,
    .solve_rows = thx_fem_solve_rows,
};

const thx_fem_petsc *thx_fem_petsc_get(void) { return &table; }
