/* bem's table in the solver module (src/bem/scalapack_module.h); built into libthorax-petsc.so with
 * src/bem/scalapack.c, not into the library. */
#include "bem/scalapack_module.h"

static const thx_bem_petsc table = {
    .abi = THX_BEM_PETSC_ABI,
    .transfer_parallel = thx_bem_transfer_parallel,
    .dipoles_parallel = thx_bem_dipoles_parallel,
};

const thx_bem_petsc *thx_bem_petsc_get(void) { return &table; }
