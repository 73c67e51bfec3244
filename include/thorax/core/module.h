/*
 * thorax/core/module.h — the solver module, loaded when first needed.
 *
 * The code that calls PETSc and MPI (the FEM system and its solves, boundary elements over MPI
 * ranks) is built as a shared object of its own, libthorax-petsc.so, which the library loads on
 * the first call that needs it: PETSc brings about a hundred shared libraries, and loading them
 * cost every run of every command about 0.1 s of CPU, the commands that never solve included
 * (docs/design/fem.md, "The solver module"). fem and bem keep their public functions as
 * forwarders to the tables the module exports.
 */
#ifndef THORAX_CORE_MODULE_H
#define THORAX_CORE_MODULE_H

#include "thorax/core/core.h"

/* The solver module's symbol `name` (loading the module once, thread-safe), or NULL with
 * THX_ESOLVER recorded in ctx (when not NULL): the places looked in and the loader's reason for
 * each. Looked for: $THORAX_PETSC_MODULE alone when set; else thorax/libthorax-petsc.so beside
 * libthorax.so, then relative to the running program (installed: BINDIR's way to LIBDIR/thorax/;
 * the build tree's bin/ and tests/: ../thorax/), then the configured install path. */
void *thx_solver_module_symbol(thx_ctx *ctx, const char *name);

#endif
