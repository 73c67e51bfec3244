/*
 * thorax/fem/fem.h — finite-element volume-conductor solutions (paper 4.1).
 *
 * Linear tetrahedral elements on a thx_volume: the stiffness matrix
 *   K_ij = sum over tetrahedra T of |T| grad(l_i) . sigma_T grad(l_j)
 * (l_i the barycentric functions, sigma_T the tensor of T's region). With
 * lengths in mm and conductivities in S/m, K is in S/m x mm = mS: (K phi)_i
 * is the current (mA) leaving node i's share of the domain when phi is in
 * volts, so nodal current loads are given in mA (or uA with phi in mV).
 *
 * Assembly is plain C with OpenMP (thx_fem_assemble); the solves go through
 * PETSc (KSP, default conjugate gradients with algebraic multigrid, every
 * PETSc runtime option honoured) on PETSC_COMM_WORLD, so the same code runs
 * under mpirun with the rows split over the ranks. Every rank holds the whole
 * mesh (500,000 tetrahedra are 10 MB) and assembles only its own rows.
 */
#ifndef THORAX_FEM_H
#define THORAX_FEM_H

#include <stdint.h>

#include "thorax/model/volume.h"
#ifdef __cplusplus
extern "C" {
#endif

/* A sparse matrix in compressed rows (0-based, columns sorted in each row). */
typedef struct {
    int32_t n_rows, n_cols;
    int64_t *row;   /* n_rows + 1 */
    int32_t *col;   /* row[n_rows] */
    double *val;
} thx_csr;

void thx_csr_free(thx_csr *a);
/* y = A x */
void thx_csr_mul(const thx_csr *a, const double *x, double *y);

/*
 * The stiffness matrix of the volume's tetrahedra whose region is enabled
 * (use_region[r] != 0; NULL = all), n_nodes x n_nodes. Errors: a region
 * whose tensor is not symmetric positive definite (named), a tetrahedron
 * with non-positive volume (numbered).
 */
thx_status thx_fem_assemble(thx_ctx *ctx, const thx_volume *v, const unsigned char *use_region, thx_csr *K);
/* The same matrix's rows where rows[node] != 0 (NULL: all), the other rows empty: the rows one MPI
 * rank owns, from the tetrahedra around them alone (a partitioned system's share of the work and
 * memory). Each row kept is the whole matrix's row, to the bit. */
thx_status thx_fem_assemble_rows(thx_ctx *ctx, const thx_volume *v, const unsigned char *use_region,
                                 const unsigned char *rows, thx_csr *K);

/* What thx_fem_assemble_kept did. */
typedef struct {
    int kept;       /* 1: the matrix was read from the cache, not assembled */
    double seconds; /* the whole call: the key, the read and its checks, or the assembly and the write */
    char note[256]; /* why the matrix could not be kept (empty: nothing to say) */
} thx_fem_assembly_info;

/* thx_fem_assemble's matrix, kept between runs in the user's cache directory (thorax/core/cache.h) as
 * stiffness-KEY.bin, KEY the SHA-256 of the nodes, the tetrahedra, their regions, the conductivities and
 * use_region. A kept file is used only when it reads back whole and is a stiffness matrix (rows and
 * columns in order, rows summing to zero, a positive diagonal, symmetric); otherwise the matrix is
 * assembled and the file written anew. The same matrix to the bit either way. A file that cannot be
 * written is a note, not an error. */
thx_status thx_fem_assemble_kept(thx_ctx *ctx, const thx_volume *v, const unsigned char *use_region, thx_csr *K,
                                 thx_fem_assembly_info *info);

/* Nodes used by the enabled tetrahedra (1) or not (0), n_nodes bytes. */
thx_status thx_fem_active_nodes(thx_ctx *ctx, const thx_volume *v, const unsigned char *use_region, unsigned char **active);

/* ---- solving (PETSc) ---- */

/* PetscInitialize with the PETSc options found in argv (arguments from the first one starting with a
 * single '-' that is not one of ours are left to PETSc); idempotent. rank/size of PETSC_COMM_WORLD. */
thx_status thx_fem_init(int argc, char **argv, int *rank, int *size);
void thx_fem_finalize(void);
/* PETSc options given to thx_fem_init that no solver used (0 before it); with list, rank 0 has PETSc
 * list them (PetscOptionsLeft). */
int thx_fem_options_unused(int list);
/* Whether the solver module (PETSc and MPI, loaded on the first solve: docs/design/fem.md, "The solver
 * module") can be loaded; when not, THX_ESOLVER with the loader's reason and where it looked. */
thx_status thx_fem_available(thx_ctx *ctx);

typedef struct thx_fem_system thx_fem_system;

/*
 * The system for the free nodes: K_ff phi_f = f_f - K_fd phi_d, where
 * kind[i] is 0 for an inactive node (not in the system), 1 free, 2 prescribed
 * (Dirichlet). A free block without any prescribed node (pure Neumann) is
 * accepted only with pin_one: the first free node is then prescribed 0.
 * The KSP is created with KSPSetFromOptions (default -ksp_type cg -pc_type
 * gamg, rtol 1e-10) and keeps its preconditioner across solves.
 */
thx_status thx_fem_system_create(thx_ctx *ctx, const thx_csr *K, const unsigned char *kind, int pin_one,
                                 thx_fem_system **out);
/* The same system partitioned over the MPI ranks: rank r owns the free nodes with part[node] == r
 * (thx_fem_partition), numbered rank after rank, and needs K's rows of those nodes alone
 * (thx_fem_assemble_rows); part NULL: the free nodes in order, split in equal ranges (as
 * thx_fem_system_create). An owned row that K lacks is refused (THX_EINTERNAL). */
thx_status thx_fem_system_create_parts(thx_ctx *ctx, const thx_csr *K, const unsigned char *kind, int pin_one,
                                       const int32_t *part, thx_fem_system **out);
/* A partition of the active nodes (kind[i] != 0) into n_parts parts for as many ranks: recursive
 * coordinate bisection, each cut across the longest side of its nodes' box at the median of the
 * free nodes (kind 1) it holds, so that every part holds as many free nodes (rows) as the others
 * within one, and every part is a box (convex: the parts can be ordered along any ray). Ties broken
 * by node number: the same partition on every rank. part[i] = -1 for an inactive node. */
thx_status thx_fem_partition(thx_ctx *ctx, const thx_volume *v, const unsigned char *kind, int n_parts, int32_t *part);
/* A cut of the bisection: parts [lo, hi) split into [lo, mid), where the coordinate on axis is below
 * at, and [mid, hi), at or above it. */
typedef struct {
    int lo, mid, hi, axis;
    double at;
} thx_fem_cut;
/* The same partition, and its n_parts - 1 cuts into cuts (a cut before the cuts inside its sides):
 * the boxes as planes, so that any point (a tetrahedron's centroid) falls in exactly one part's box. */
thx_status thx_fem_partition_cuts(thx_ctx *ctx, const thx_volume *v, const unsigned char *kind, int n_parts, int32_t *part,
                                  thx_fem_cut *cuts);
/* The part whose box holds p (-1 for cuts that are not a bisection's). */
int thx_fem_cut_part(const thx_fem_cut *cuts, int n_parts, const double p[3]);
/* The parts back to front for an eye at eye (sort-last's blending order; an orthographic camera: a
 * point far back along its view): a part is listed after every part it hides, since for each cut the
 * side away from the eye comes first. order: n_parts ints. */
void thx_fem_cut_order(const thx_fem_cut *cuts, int n_parts, const double eye[3], int *order);
/* Part's box: box[0] its low corner, box[1] its high one (infinite where no cut bounds it); the box
 * holds the points p with box[0] <= p < box[1] (thx_fem_cut_part's rule: a point on a cut is above it). */
void thx_fem_cut_box(const thx_fem_cut *cuts, int n_parts, int part, double box[2][3]);
void thx_fem_system_destroy(thx_fem_system **s);

typedef struct {
    int iterations;    /* of a block (thx_fem_solve_block): the most over its columns */
    int iterations_min;   /* the fewest over a block's columns (one solve: = iterations) */
    long iterations_total; /* summed over a block's columns */
    double residual;   /* final relative residual (as KSP reports it; the true one for a direct solve);
                          of a block the largest */
    double seconds;
    int converged;     /* KSPConvergedReason > 0 */
    size_t block;      /* thx_fem_solve_rows: the most columns solved at once (0: not said) */
    /* thx_fem_solve_rows on thorax's own factor: the backward sweep kept to the supernodes the rows need
       (their share of its flops; 0: every supernode, every column's residual), and each block checked by
       two combinations of its columns solved in full: residual is theirs, check the largest difference at
       the rows between them and the columns' answers combined, relative to the combination's scale */
    double backward_share, check;
} thx_fem_solve_stats;

/*
 * One solve. phi (n_nodes, on every rank): on entry the prescribed values at
 * kind == 2 nodes and, with warm = 1, the initial guess at free nodes; on
 * return the solution at every active node (inactive: 0). load (n_nodes, or
 * NULL): nodal currents (mA per V of phi units) at free nodes. A solve that
 * does not converge is THX_ESOLVER with KSP's reason in the message.
 */
thx_status thx_fem_solve(thx_ctx *ctx, thx_fem_system *s, double *phi, const double *load, int warm,
                         thx_fem_solve_stats *st);

/* Writes K_ff and the right-hand side for phi's prescribed values (and load, or NULL) in PETSc's
 * binary format (MatLoad / VecLoad order: matrix, then vector) — for running PETSc alone on the very
 * same system (bench/forward.sh). */
thx_status thx_fem_system_dump(thx_ctx *ctx, thx_fem_system *s, const double *phi, const double *load, const char *path);

/*
 * Tells the system how many right-hand sides will follow. Unless the
 * command line chose a solver (-ksp_type or -pc_type), n_rhs >= 12 switches
 * to a sparse Cholesky factorization (-ksp_type preonly -pc_type cholesky,
 * CHOLMOD on one rank, MUMPS on several): on the high-resolution phantom the
 * factorization costs about 11 solves of CG + GAMG and each solve after it
 * a seventh of one (docs/decisions.md). Call before the first solve.
 */
void thx_fem_system_hint_rhs(thx_fem_system *s, size_t n_rhs);

/*
 * Many right-hand sides at once (issue 15, item 6). phi and load (or NULL)
 * hold k columns of n_nodes values each, column j at phi + j * n_nodes, each
 * as in thx_fem_solve. With a factorization (-ksp_type preonly, -pc_type
 * cholesky or lu: thx_fem_system_hint_rhs's choice for many right-hand sides)
 * the columns go to the factorization's package as dense blocks of
 * thx_fem_system_block(s) columns (MatMatSolve: CHOLMOD and MUMPS traverse the
 * factor once per block, not once per column, with level-3 BLAS; on one rank
 * with no solver named, thorax's own path: CHOLMOD's analysis with the ordering
 * kept in the cache, thorax's multifrontal factorization and row-major blocked
 * solves over the threads,
 * thx_fem_system_factor_info, docs/design/parallel.md); the answers
 * agree with column-by-column solves to rounding (1e-14 relative measured),
 * the residuals are the true ones (||b - A x|| / ||b|| per column), and a
 * failed factorization or a non-finite answer is THX_ESOLVER as in
 * thx_fem_solve. Otherwise (an iterative KSP: PETSc 3.18 as Debian builds it
 * has no block Krylov method, KSPHPDDM) and for k = 1 it is thx_fem_solve
 * column by column, column j > 0 warm-started from column j - 1's solution
 * when warm. st: iterations (most, fewest, total) and the largest residual
 * over the columns, seconds of solving (the factorization is setup time).
 */
thx_status thx_fem_solve_block(thx_ctx *ctx, thx_fem_system *s, double *phi, const double *load, size_t k, int warm,
                               thx_fem_solve_stats *st);

/*
 * Many right-hand sides whose answers are wanted at a few nodes (the forward problem's outer surface
 * without the volume): thx_fem_solve_block's solves, with the prescribed values given per prescribed
 * node and the answers returned at rows alone, so that no column of every node is made. pnode[0 .. np-1]
 * are the system's prescribed nodes (kind 2), each once and every one of them (a pure Neumann problem's
 * pinned node is not among them: it is 0); pres holds k columns of np values (column j at pres + j * np,
 * value c for node pnode[c]). out receives k columns of m values (column j at out + j * m, value i at node
 * rows[i]: its answer, its prescribed value, or 0 for an inactive node). On thorax's own path the blocks
 * hold as many columns as keep one free-node column per right-hand side within 768 MB (at most 512);
 * otherwise it is thx_fem_solve_block on blocks of every node, warm as there. st as thx_fem_solve_block's.
 * A node list that does not match the system is THX_EINTERNAL.
 */
thx_status thx_fem_solve_rows(thx_ctx *ctx, thx_fem_system *s, const int32_t *pnode, size_t np, const double *pres,
                              size_t k, int warm, const int32_t *rows, size_t m, double *out, thx_fem_solve_stats *st);

/*
 * Columns per blocked solve: 1 without a factorization (nothing to gain);
 * else the thx_fem_system_set_block value, or the PETSc option
 * -thorax_block_size N, or as many as keep five n_nodes-long columns per
 * right-hand side (the caller's block, PETSc's B and X, CHOLMOD's workspace,
 * the residuals) within 512 MB, at most 64 (docs/decisions.md: the measured
 * gain flattens there); on thorax's own path as many as keep the caller's
 * column and one free-node column per right-hand side within 768 MB, at most
 * 256 (split among the threads). Call after thx_fem_system_hint_rhs. A block size of 1
 * is the frame-by-frame solve exactly (KSPSolve per column).
 */
size_t thx_fem_system_block(const thx_fem_system *s);
void thx_fem_system_set_block(thx_fem_system *s, size_t k); /* 0: automatic */

/* Free and prescribed node counts, and the setup time (matrix + preconditioner) so far, seconds. */
void thx_fem_system_info(const thx_fem_system *s, size_t *n_free, size_t *n_prescribed, double *setup_seconds);
/* Of the setup time: building PETSc's matrix from ours (the rest is the preconditioner's setup). */
double thx_fem_system_matrix_seconds(const thx_fem_system *s);
/* The KSP and PC types in use ("cg", "gamg", ...) and the number of MPI ranks. */
void thx_fem_system_describe(const thx_fem_system *s, char ksp[32], char pc[32], int *ranks);

/* Current density J = -sigma grad(phi) per tetrahedron (3 per tet; A/m^2 for phi in V and mm,
 * i.e. the gradient is converted to V/m) and per node (volume-weighted average of the tetrahedra
 * around it, enabled regions only; 0 at inactive nodes). Either output may be NULL. */
void thx_fem_currents(const thx_volume *v, const unsigned char *use_region, const double *phi, double *j_tet,
                      double *j_node);

/* thorax's own direct path (one rank, many right-hand sides, no solver named on the command line:
 * CHOLMOD's supernodal analysis, thorax's multifrontal numeric factorization, docs/design/parallel.md):
 * what it did. All zero when the system was solved another way. */
typedef struct {
    int used;               /* 1: the factor was made by the own path */
    int ordering_cached;    /* 1: the fill-reducing ordering came from the cache (else METIS ran) */
    int symbolic_cached;    /* 1: the symbolic factor came from the cache (else CHOLMOD's analysis ran) */
    double t_ordering, t_analysis, t_factor; /* seconds */
    double flops;           /* the factorization's (CHOLMOD's count) */
    double nonzeros;        /* in the factor L */
    double solve_flops;     /* the solves' so far (the supernodes they touched: both sweeps, less the forward
                               sweep's supernodes with no right-hand side below them) */
    size_t factor_bytes;
    char cache_note[160];   /* why the ordering was not cached (empty when it was, or was read) */
    int blas_threads;       /* OpenBLAS's threads in the factorization (the cores free then; 0: not OpenBLAS) */
    char numeric[48];       /* who computed the factor's values (thorax's multifrontal code, or CHOLMOD) */
    int threads;            /* ours: threads sharing the subtrees (0: CHOLMOD's) */
    size_t subtrees, top;   /* ours: independent subtrees; supernodes above them */
    double top_share;       /* ours: the top's share of the work */
    double t_subtrees, t_top; /* ours: seconds in the subtrees, then in the top */
    int top_beside;         /* ours: 1 when the top was factored on one thread beside the first solves' start */
} thx_fem_factor_info;

void thx_fem_system_factor_info(const thx_fem_system *s, thx_fem_factor_info *out);

/* ---- forward problems (paper 4.1) ---- */

#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
#include "thorax/model/series.h"
#include "thorax/io/series_file.h"
typedef struct {
    int keep_volume;        /* also return the potentials at every volume node */
    int warm;               /* start each frame from the previous frame's solution (default 1) */
    void (*progress)(void *user, size_t done, size_t total); /* after each frame (may be NULL) */
    void *user;
    const char *dump_system; /* if set: the first frame's system written there (thx_fem_system_dump) */
    size_t block;           /* right-hand sides per blocked solve (thx_fem_solve_block); 0 = automatic
                               (thx_fem_system_block), 1 = frame by frame */
    int dipole_method;      /* thx_forward_dipoles: THX_DIPOLE_VENANT (default) or THX_DIPOLE_PARTIAL */
    int direct;             /* transfer matrices: factor the system even for a few solves (as for many:
                               thx_fem_system_hint_rhs), so that the matrix is as exact as the factorization
                               and not as the iterative solver's tolerance (default 0) */
} thx_forward_opts;

/* How thx_forward_dipoles puts a dipole on the mesh (docs/decisions.md, "Dipole sources"). */
enum { THX_DIPOLE_VENANT = 0, THX_DIPOLE_PARTIAL = 1 };

typedef struct {
    thx_series *torso;      /* the outer surface's nodes x frames */
    thx_series *volume;     /* every volume node x frames (keep_volume), else NULL */
    size_t n_free, n_prescribed;
    int it_min, it_max;     /* iterations per frame */
    long it_total;
    double max_residual;
    double backward_share, check; /* the outer surface alone on thorax's own factor: thx_fem_solve_stats's */
    double t_assemble, t_setup, t_solve; /* seconds: stiffness, matrix + preconditioner, all solves */
    thx_fem_assembly_info assembly; /* the stiffness matrix kept from an earlier run (one rank) or assembled */
    double t_matrix;        /* of t_setup: handing the matrix to PETSc */
    char ksp[32], pc[32];   /* solver in use */
    int ranks;
    size_t block;           /* right-hand sides per blocked solve used (1: frame by frame) */
    size_t n_located_by_scan; /* thx_forward_dipoles: dipoles the walk did not place (thx_fem_locate_walk) */
    size_t n_fallback;      /* thx_forward_dipoles, Saint-Venant: dipoles put on by partial integration instead
                               (every corner of their tetrahedron on an interface between regions) */
    thx_fem_factor_info factor; /* the own direct path's figures (factor.used 0 when not taken) */
} thx_forward_result;

void thx_forward_opts_default(thx_forward_opts *o);
void thx_forward_result_free(thx_forward_result *r);

/*
 * The epicardial forward problem: the potentials of epi (rows: the nodes of
 * the model's heart surface, in order; any unit) prescribed on the heart
 * surface, no current through the outer surface, the heart's interior (the
 * region named "heart", if meshed) left out. The Steiner nodes on the heart
 * surface (v->steiner) are prescribed too, each the barycentric mix of its
 * triangle's corner values (so the prescribed potential is the piecewise
 * linear one on the heart's triangles). The volume is not checked here
 * (thorax forward runs thx_volume_check first). Errors: no volume mesh, no or
 * several heart/outer surfaces, a row count that does not match, NaN/Inf
 * values (row and frame named), a region tensor not positive definite, a
 * solve that does not converge.
 */
thx_status thx_forward_epicardial(thx_ctx *ctx, const thx_model *m, const thx_series *epi, const thx_forward_opts *o,
                                  thx_forward_result *r);

/*
 * The transfer matrix of the epicardial problem: T (rows x heart nodes) with
 * phi_rows = T phi_heart, rows the outer surface's nodes (rows == NULL) or
 * the given outer-surface nodes (an electrode set, n_rows of them). Heart
 * node j's column prescribes 1 at the node and, at each Steiner node of the
 * heart, its weight of corner j (as thx_forward_epicardial interpolates). Computed
 * column by column (one solve per heart node, `forward`) or row by row (one
 * solve per row with K symmetric: row i = -(K_ff^-1 e_i)^T K_fd, `adjoint`);
 * method < 0 picks the one with fewer solves. Returned as a series whose
 * "frames" are the heart nodes (time axis = heart node numbers, 1-based).
 */
thx_status thx_forward_transfer(thx_ctx *ctx, const thx_model *m, const int32_t *rows, size_t n_rows, int method,
                                const thx_forward_opts *o, thx_series **T, thx_forward_result *info);

/*
 * The same with rows that are weighted sums of outer-surface nodes: row i is
 * sum_k weight[3i+k] phi(corner[3i+k]), k = 0..2 (an electrode between nodes,
 * thx_electrodes_place; one on a node has weights 1, 0, 0). Row i of T is
 * exactly that combination of the node rows thx_forward_transfer gives (the
 * solve is linear in the row's load). The label says "electrodes".
 */
thx_status thx_forward_transfer_weighted(thx_ctx *ctx, const thx_model *m, const int32_t *corner, const double *weight,
                                         size_t n_rows, int method, const thx_forward_opts *o, thx_series **T,
                                         thx_forward_result *info);

/* phi = T epi: a series with T's rows and epi's frames. */
thx_status thx_transfer_apply(thx_ctx *ctx, const thx_series *T, const thx_series *epi, thx_series **out);

/* ---- current dipole sources (src/fem/dipole.c; docs/decisions.md, "Dipole sources") ---- */

#include "thorax/io/dipoles_file.h"
#include "thorax/mesh/tet_locate.h"

/* The tetrahedron holding point p (mm): the one p lies deepest in (largest smallest barycentric
 * coordinate, at least -1e-9; ties: the lowest number), or -1 if p is outside every tetrahedron;
 * l (may be NULL) its barycentric coordinates there. */
void thx_fem_locate(const thx_volume *v, const double p[3], long *tet, double l[4]);

/* thx_fem_locate's answer through the walk (thorax/mesh/tet_locate.h) from start (< 0: the
 * locator's seed): the walk's tetrahedron when p lies inside it by more than 1e-9 in every
 * barycentric coordinate (then no other tetrahedron holds p, and the scan would choose it too);
 * else — the walk failed (p outside the mesh, or the mesh not convex between the start and p) or
 * p lies on a face, an edge or a node — thx_fem_locate's scan, whose rule (the tetrahedron p is
 * deepest in, then the lowest number) decides. Returns 1 if the walk decided, 0 if the scan did.
 * loc must be built on v. */
int thx_fem_locate_walk(const thx_tet_locator *loc, const thx_volume *v, const double p[3], long start, long *tet,
                        double l[4]);

/* Adds the partial-integration load of a dipole of moment q (mA·m) in tetrahedron tet to load
 * (n_nodes; µA, so that the potential comes out in mV): q . grad l_k, times 10^6 for the units, on
 * the tetrahedron's four corners (they sum to zero). */
void thx_dipole_load(const thx_volume *v, long tet, const double q[3], double *load);

/*
 * The potentials of current dipoles (positions mm, moments mA·m; thorax/io/dipoles_file.h) in the
 * whole volume: every region whose conductivity is not zero is in the domain (none is left out
 * as the epicardial problem leaves out the heart; a region of conductivity 0 is an insulator),
 * no current through the outer boundary. Each dipole goes on the mesh by o->dipole_method:
 * Saint-Venant (default: monopoles on its nearest node and that node's neighbours in its region,
 * their moments of order 0 and 1 those of the dipole, order 2 minimized; partial integration
 * for a dipole whose nearest node lies on an interface between regions, counted in
 * r->n_fallback), or partial integration (thx_dipole_load). The reference: the integral of the potential over the outer surface is zero
 * (the reference of the analytic solutions of concentric spheres). r->torso: the outer surface's
 * nodes x the dipole set's frames, mV (a .dip-layout set: one frame per dipole); r->volume with
 * keep_volume. A frame is one solve, or when there are more frames than 3 n, 3 n solves (a unit
 * moment per dipole and axis) are combined; a frame whose moments are all zero is 0 without a
 * solve. The right-hand sides are assembled as dense blocks and solved by thx_fem_solve_block
 * (o->block columns, 0: thx_fem_system_block's choice; r->block says which): with a
 * factorization, one multi-right-hand-side solve per block, the same answers as one by one to
 * rounding (o->block = 1). Errors name the dipole file and line: a dipole
 * outside the volume, in a region of conductivity 0, a position or moment that is not finite.
 */
thx_status thx_forward_dipoles(thx_ctx *ctx, const thx_model *m, const thx_dipoles *d, const thx_forward_opts *o,
                               thx_forward_result *r);

/* ---- verification (thorax verify, docs/validation.md) ---- */

typedef struct {
    int n;                   /* cells per cube edge of the cubed-sphere mesh; the spheres: nodes per icosphere */
    size_t nodes, tets;
    double h;                /* mean edge length, mm (the spheres: of the tetrahedra between r = a and r = c) */
    double rdm, mag;         /* at the outer surface's nodes against the analytic solution */
    double max_err;          /* largest nodal error on the outer surface / largest |analytic| there */
    double net_current;      /* current out of the inner sphere / the sum of its magnitudes */
    int iterations;
    double seconds;          /* the solve */
    /* the spheres only (thx_verify_spheres) */
    size_t steiner;          /* Steiner nodes thorax mesh put on the three surfaces */
    double lin_err;          /* largest |phi - z/a| at the brain's interior nodes (exactly linear there: 0 to
                                the solver's tolerance) */
    double t_mesh;           /* seconds in thx_mesh_build */
} thx_verify_row;

/*
 * Concentric shells a = 40, b = 70, c = 100 mm (thorax/geom/verify.h): P_l(cos
 * theta) prescribed on r = a, no current through r = c, conductivity s1 in
 * the inner shell and s2 in the outer one; the finite-element solution on
 * the cubed-sphere mesh with n cells per cube edge (n/2 layers per shell)
 * compared with the analytic one at the outer surface.
 */
thx_status thx_verify_shells(thx_ctx *ctx, int l, double s1, double s2, int n, thx_verify_row *row);

/*
 * OpenMEEG's three spheres (its test model data/HeadN: radii 0.87, 0.92, 1
 * and HeadN.cond, here in mm): brain r < 87 mm (1 S/m), skull 87 < r < 92 (0.0125), scalp 92 < r < 100
 * (1), each surface an icosphere of 10 4^level + 2 nodes (thx_icosphere),
 * the whole meshed by the library's mesher (thx_mesh_build, default options
 * but the grid, 60 / 2^level mm, so that surfaces and volume refine
 * together: level 5 is 10,242 nodes per sphere and a 1.875 mm grid) with
 * brain, skull and scalp as regions, and the mesh checked as thorax mesh
 * checks it (thx_volume_check; a failure is THX_ECHECK with the reasons).
 * Then the epicardial forward problem of thorax forward
 * (thx_forward_epicardial, the brain's surface in the heart's role): P_1 =
 * cos(theta) at the brain surface's nodes, its Steiner nodes interpolated,
 * no current through the scalp. Compared with the analytic solution of the
 * concentric spheres (thx_shells_potential with a = 87, b = 92, c = 100)
 * at the scalp's nodes; the brain's interior must be the linear z / a.
 * level 2 to 6 (level 5: 3.9 M tetrahedra, 0.9 GB; level 6: 31 M, 7 GB).
 */
thx_status thx_verify_spheres(thx_ctx *ctx, int level, thx_verify_row *row);

/* The anisotropic slab: the largest nodal error against the closed form (linear: exact for P1
 * elements up to the solver's tolerance), relative to the largest potential. */
thx_status thx_verify_slab(thx_ctx *ctx, double *rel_err, size_t *nodes);

/* ---- defibrillation (paper 4.1) ---- */

/* An electrode patch: volume nodes on a surface, each with its share of the patch's area: the
 * surface's nodes chosen, then the Steiner nodes (thorax/model/volume.h) on the part of the surface they
 * span (a Steiner node whose non-zero barycentric weights all fall on chosen nodes). */
typedef struct {
    char name[32];
    int is_voltage;     /* 1: the patch is held at `value` volts; 0: it injects `value` amperes */
    double value;
    size_t n;
    int32_t *node;      /* volume nodes */
    double *weight;     /* share of the area (sums to 1) */
    double area;        /* mm^2 */
} thx_patch;

/* The nodes of model surface s within radius (mm) of center, and the Steiner nodes among them (above);
 * weights from the areas of the mesh faces on the surface around each node (a third of each face's
 * area per patch node on it; without Steiner nodes these are the surface's triangles). Error if no
 * node is inside. */
thx_status thx_patch_disc(thx_ctx *ctx, const thx_model *m, size_t s, const double center[3], double radius,
                          thx_patch *p);
/* The given nodes of surface s (0-based surface node numbers). */
thx_status thx_patch_nodes(thx_ctx *ctx, const thx_model *m, size_t s, const int32_t *nodes, size_t n, thx_patch *p);
void thx_patch_free(thx_patch *p);

typedef struct {
    double threshold;        /* V/cm */
    double heart_volume;     /* mm^3 of the heart region */
    double frac_above;       /* fraction of the heart's volume where |E| > threshold */
    double e_min, e_mean, e_max;  /* |E| in the heart, V/cm (mean volume-weighted) */
    double phi_min, phi_max;      /* potential in the heart, V */
    double j_min, j_mean, j_max;  /* current density |J| in the heart, A/m^2 (mean volume-weighted) */
    double current[16];      /* current leaving each patch into the body, A (given for current patches) */
    double voltage[16];      /* mean potential of each patch, V */
    int iterations;
    double residual, t_assemble, t_setup, t_solve;
    thx_fem_assembly_info assembly; /* the stiffness matrix kept from an earlier run or assembled */
    char ksp[32], pc[32];
    int ranks;
} thx_defib_report;

/*
 * The defibrillation problem: the whole domain (heart included), patches
 * held at voltages (Dirichlet) or injecting currents (Neumann loads,
 * distributed by area); at least one voltage patch, or currents summing to
 * zero (the potential is then given relative to its mean over the volume).
 * phi (n_nodes, malloc'ed, V) and field (|E| per tetrahedron, V/cm,
 * malloc'ed) on return; either pointer may be NULL. Requires a region named
 * "heart" for the report (else the figures are over nothing and say so).
 */
thx_status thx_defib_solve(thx_ctx *ctx, const thx_model *m, const thx_patch *patches, size_t n_patches, double threshold,
                           double **phi, double **field, thx_defib_report *rep);

/* The gradients of the four hat functions of tetrahedron q (4 node numbers into xyz) as g[k]
 * (1/length), and the signed volume (positive for a positively oriented tetrahedron). */
double thx_fem_tet_gradients(const double *xyz, const int32_t *q, double g[4][3]);

#ifdef __cplusplus
}
#endif
#endif
