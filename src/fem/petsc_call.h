/*
 * A PETSc call inside a thx function of the solver module (src/fem: the finite elements' systems;
 * src/bem/scalapack.c: the boundary elements' dense systems): on failure the call and PETSc's message
 * are recorded in ctx's error, st is set to THX_ESOLVER, and control jumps to the function's `done`
 * label. Built into the solver module alone (it needs PETSc's headers).
 */
#ifndef THORAX_FEM_PETSC_CALL_H
#define THORAX_FEM_PETSC_CALL_H

#include <petscsys.h>

#include "thorax/core/core.h"

#define PCALL(ctx, call)                                                                      \
    do {                                                                                      \
        PetscErrorCode e_ = (call);                                                           \
        if (e_) {                                                                             \
            const char *txt_ = NULL;                                                          \
            PetscErrorMessage(e_, &txt_, NULL);                                               \
            st = thx_error(ctx, THX_ESOLVER, "PETSc: %s: %s", #call, txt_ ? txt_ : "error"); \
            goto done;                                                                        \
        }                                                                                     \
    } while (0)

#endif
