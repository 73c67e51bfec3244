/*
 * fem's table in the solver module (thorax/core/module.h): src/fem/solver.c's functions, which
 * call PETSc, reached from the library's forwarders (src/fem/solver_load.c) through the table
 * that src/fem/solver_table.c builds into libthorax-petsc.so.
 */
#ifndef THORAX_FEM_SOLVER_MODULE_H
#define THORAX_FEM_SOLVER_MODULE_H

#include "thorax/fem/fem.h"

/* Raised whenever the table changes: a module from another build is refused, not misused. */
#define THX_FEM_PETSC_ABI 5

typedef struct {
    int abi; /* THX_FEM_PETSC_ABI */
    thx_status (*init)(int argc, char **argv, int *rank, int *size);
    void (*finalize)(void);
    int (*options_unused)(int list);
    thx_status (*system_create)(thx_ctx *ctx, const thx_csr *K, const unsigned char *kind, int pin_one,
                                thx_fem_system **out);
    void (*system_destroy)(thx_fem_system **s);
    thx_status (*solve)(thx_ctx *ctx, thx_fem_system *s, double *phi, const double *load, int warm,
                        thx_fem_solve_stats *st);
    thx_status (*system_dump)(thx_ctx *ctx, thx_fem_system *s, const double *phi, const double *load,
                              const char *path);
    void (*system_hint_rhs)(thx_fem_system *s, size_t n_rhs);
    thx_status (*solve_block)(thx_ctx *ctx, thx_fem_system *s, double *phi, const double *load, size_t k,
                              int warm, thx_fem_solve_stats *st);
    size_t (*system_block)(const thx_fem_system *s);
    void (*system_set_block)(thx_fem_system *s, size_t k);
    void (*system_info)(const thx_fem_system *s, size_t *n_free, size_t *n_prescribed, double *setup_seconds);
    double (*system_matrix_seconds)(const thx_fem_system *s);
    void (*system_describe)(const thx_fem_system *s, char ksp[32], char pc[32], int *ranks);
    void (*system_factor_info)(const thx_fem_system *s, thx_fem_factor_info *out);
    thx_status (*system_create_parts)(thx_ctx *ctx, const thx_csr *K, const unsigned char *kind, int pin_one,
                                      const int32_t *part, thx_fem_system **out);
    thx_status (*solve_rows)(thx_ctx *ctx, thx_fem_system *s, const int32_t *pnode, size_t np, const double *pres,
                             size_t k, int warm, const int32_t *rows, size_t m, double *out, thx_fem_solve_stats *st);
} thx_fem_petsc;

/* Exported by the module. */
const thx_fem_petsc *thx_fem_petsc_get(void);

#endif
