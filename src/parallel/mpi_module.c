/* MPI's table in the solver module (src/parallel/mpi_module.h); built into libthorax-petsc.so, not
 * into the library. */
#include <limits.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "parallel/mpi_module.h"

/* src/parallel/icet_module.c */
int thx_par_icet_composite(int mode, int w, int h, void *color, float *depth, const int *order, char *why, size_t why_size);
void thx_par_icet_end(void);

static int init(int *rank, int *size, int *started)
{
    int inited = 0, rc = MPI_Initialized(&inited);
    *started = 0;
    if (rc == MPI_SUCCESS && !inited) {
        int provided = 0;
        rc = MPI_Init_thread(NULL, NULL, MPI_THREAD_FUNNELED, &provided);
        *started = rc == MPI_SUCCESS;
    }
    if (rc == MPI_SUCCESS) rc = MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
    if (rc == MPI_SUCCESS) rc = MPI_Comm_rank(MPI_COMM_WORLD, rank);
    if (rc == MPI_SUCCESS) rc = MPI_Comm_size(MPI_COMM_WORLD, size);
    return rc;
}

static void finalize(void)
{
    int done = 0;
    MPI_Finalized(&done);
    if (!done) thx_par_icet_end();
    if (!done) MPI_Finalize();
}

static int barrier(void) { return MPI_Barrier(MPI_COMM_WORLD); }

/* (in pieces of at most INT_MAX bytes: MPI counts are int) */
static int bcast(void *buf, size_t n, int root)
{
    for (size_t off = 0; off < n;) {
        int part = n - off > INT_MAX ? INT_MAX : (int)(n - off);
        int rc = MPI_Bcast((char *)buf + off, part, MPI_BYTE, root, MPI_COMM_WORLD);
        if (rc != MPI_SUCCESS) return rc;
        off += (size_t)part;
    }
    return MPI_SUCCESS;
}

static int max_int(int *v, int n) { return MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_INT, MPI_MAX, MPI_COMM_WORLD); }
static int min_int(int *v, int n) { return MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_INT, MPI_MIN, MPI_COMM_WORLD); }
static int max_dbl(double *v, int n) { return MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD); }
static int sum_ll(long long *v, int n) { return MPI_Allreduce(MPI_IN_PLACE, v, n, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD); }

static int gather_size(size_t n, size_t *counts, int root)
{
    unsigned long long mine = n;
    return MPI_Gather(&mine, 1, MPI_UNSIGNED_LONG_LONG, counts, 1, MPI_UNSIGNED_LONG_LONG, root, MPI_COMM_WORLD);
}

/* Point to point from each rank to root, in pieces of at most INT_MAX bytes (a gather's counts and
 * displacements are int: 2 GB in all). */
static int gatherv(const void *send, size_t n, void *recv, const size_t *counts, int root)
{
    int rank, size, rc = MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (rc == MPI_SUCCESS) rc = MPI_Comm_size(MPI_COMM_WORLD, &size);
    if (rc != MPI_SUCCESS) return rc;
    if (rank != root) {
        for (size_t off = 0; off < n && rc == MPI_SUCCESS;) {
            int part = n - off > INT_MAX ? INT_MAX : (int)(n - off);
            rc = MPI_Send((const char *)send + off, part, MPI_BYTE, root, 7301, MPI_COMM_WORLD);
            off += (size_t)part;
        }
        return rc;
    }
    size_t at = 0;
    for (int r = 0; r < size && rc == MPI_SUCCESS; r++) {
        char *dst = (char *)recv + at;
        if (r == root) {
            memcpy(dst, send, counts[r]);
        } else {
            for (size_t off = 0; off < counts[r] && rc == MPI_SUCCESS;) {
                int part = counts[r] - off > INT_MAX ? INT_MAX : (int)(counts[r] - off);
                rc = MPI_Recv(dst + off, part, MPI_BYTE, r, 7301, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
                off += (size_t)part;
            }
        }
        at += counts[r];
    }
    return rc;
}

static void error_string(int code, char *buf, size_t size)
{
    char s[MPI_MAX_ERROR_STRING];
    int len = 0;
    if (MPI_Error_string(code, s, &len) != MPI_SUCCESS) len = snprintf(s, sizeof s, "MPI error %d", code);
    snprintf(buf, size, "%.*s", len, s);
}

static const thx_par_mpi table = {
    .abi = THX_PAR_MPI_ABI,
    .init = init,
    .finalize = finalize,
    .barrier = barrier,
    .bcast = bcast,
    .max_int = max_int,
    .min_int = min_int,
    .sum_ll = sum_ll,
    .max_dbl = max_dbl,
    .gather_size = gather_size,
    .gatherv = gatherv,
    .error_string = error_string,
    .composite = thx_par_icet_composite,
};

const thx_par_mpi *thx_par_mpi_get(void) { return &table; }
