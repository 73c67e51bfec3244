/*
 * thorax/core/module.h — files shipped beside the library: where they are looked for, and the
 * solver module, loaded when first needed.
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

/* Where to look for a file shipped with thorax (a helper program, the solver module), in order:
 * dirname(libthorax.so)/from_lib when the library's code is in a shared object (not the running
 * program itself), dirname(the running program)/from_bin[i] for each of the n_bin, then installed:
 * relative paths, so that a moved prefix keeps working. Writes up to max paths of size bytes each
 * into out (out + k * size); returns how many. */
int thx_shipped_paths(const char *from_lib, const char *const *from_bin, int n_bin, const char *installed, char *out,
                      size_t size, int max);

/* The solver module's symbol `name` (loading the module once, thread-safe), or NULL with
 * THX_ESOLVER recorded in ctx (when not NULL): the places looked in and the loader's reason for
 * each. Looked for: $THORAX_PETSC_MODULE alone when set; else thorax/libthorax-petsc.so beside
 * libthorax.so, then relative to the running program (installed: BINDIR's way to LIBDIR/thorax/;
 * the build tree's bin/ and tests/: ../thorax/), then the configured install path. */
void *thx_solver_module_symbol(thx_ctx *ctx, const char *name);

/* The table the module's function `getter` returns (looked up and called once per cache, under a
 * lock), or NULL with THX_ESOLVER in ctx (when not NULL). Every table begins with `int abi`; a table
 * whose abi is not `abi` is refused as built for another version of thorax. *cache holds the table
 * once found, so the caller's later calls cost one load. */
const void *thx_solver_module_table(thx_ctx *ctx, const char *getter, int abi, const void *volatile *cache);

#endif
