/*
 * bem's table in the solver module (thorax/core/module.h): src/bem/scalapack.c's functions, which
 * call PETSc and MPI, reached from the library's forwarders (src/bem/scalapack_load.c) through the
 * table that src/bem/scalapack_table.c builds into libthorax-petsc.so.
 */
#ifndef THORAX_BEM_SCALAPACK_MODULE_H
#define THORAX_BEM_SCALAPACK_MODULE_H

#include "thorax/bem/bem.h"

/* Raised whenever the table changes: a module from another build is refused, not misused. */
#define THX_BEM_PETSC_ABI 1

typedef struct {
    int abi; /* THX_BEM_PETSC_ABI */
    thx_status (*transfer_parallel)(thx_ctx *ctx, const thx_bem *b, size_t heart, double *T, thx_bem_info *info);
    thx_status (*dipoles_parallel)(thx_ctx *ctx, const thx_bem *b, const double *pos, const double *mom, size_t n,
                                   double *phi, thx_bem_info *info);
} thx_bem_petsc;

/* Exported by the module. */
const thx_bem_petsc *thx_bem_petsc_get(void);

#endif
