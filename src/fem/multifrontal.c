/*
 * thorax's numeric supernodal Cholesky factorization, multifrontal (src/fem/multifrontal.h).
 *
 * Supernode s, in a postorder of the supernodal elimination tree: its front is the nsrow x nsrow
 * matrix on its rows; the first nscol columns are L's block (assembled in place in Lx), the lower right
 * nb x nb part its update matrix U_s. A's entries of its columns and its children's update matrices
 * are added into the front (extend-add), then
 *     L11 = chol(F11),  L21 = F21 L11^-T,  U_s = F22 - L21 L21^T
 * (dpotrf, dtrsm, dsyrk). A child's update matrix is consumed by its parent alone, so in a postorder
 * the update matrices live on a stack: a supernode's children's are on its top.
 *
 * Threads: the tree is cut (Geist and Ng's rule) into independent subtrees, the heaviest split into its
 * children until the subtrees can be dealt to the threads with no thread more than 5 % above the
 * mean; each thread takes subtrees, heaviest first, with its own stack and BLAS called single-threaded.
 * A subtree root's update matrix goes to a shared arena, where the supernodes above the subtrees (the
 * top: the largest separators) find it; those are factored one after the other, each BLAS call with
 * the threads the caller gives (thx_mf_factor), or later, in a step of its own (thx_mf_begin, then
 * thx_mf_top), on one thread while the caller's other threads start the solves below the top
 * (src/fem/solver_own.c). The arithmetic of a supernode is the same whichever thread does it.
 */
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "fem/multifrontal.h"
#include "thorax/core/pages.h"

/* LAPACK and BLAS, Fortran calling convention (OpenBLAS behind liblapack.so.3 and libblas.so.3) */
void dpotrf_(const char *uplo, const int *n, double *a, const int *lda, int *info);
void dtrsm_(const char *side, const char *uplo, const char *transa, const char *diag, const int *m, const int *n,
            const double *alpha, const double *a, const int *lda, double *b, const int *ldb);
void dsyrk_(const char *uplo, const char *trans, const int *n, const int *k, const double *alpha, const double *a,
            const int *lda, const double *beta, double *c, const int *ldc);

enum { K_INNER = 0, K_ROOT = 1, K_TOP = 2 }; /* where a supernode's update matrix lives */

typedef struct {
    const thx_mf_symbolic *S;
    int64_t *parent, *cstart, *child; /* the supernodal tree; children of s: child[cstart[s] .. cstart[s + 1] - 1] */
    int64_t *post, *pos, *first;      /* a postorder; s's place in it; its subtree's first place */
    double *cost, *sub;               /* a supernode's work; its subtree's */
    unsigned char *kind;
    int64_t *uoff;                    /* where its update matrix starts (in its stack, or in the roots' arena) */
    const int64_t *rowp, *perm, *iperm;
    const int32_t *col;
    const double *val;
    double *Lx, *roots; /* Lx: zeros before the first front (its columns are assembled into it) */
} mf_tree;

static inline int64_t ncol(const thx_mf_symbolic *S, int64_t s) { return S->super[s + 1] - S->super[s]; }
static inline int64_t nrow(const thx_mf_symbolic *S, int64_t s) { return S->pi[s + 1] - S->pi[s]; }
static inline size_t usize(const thx_mf_symbolic *S, int64_t s)
{
    size_t nb = (size_t)(nrow(S, s) - ncol(S, s));
    return nb * nb;
}

static void tree_free(mf_tree *t)
{
    free(t->parent);
    free(t->cstart);
    free(t->child);
    free(t->post);
    free(t->pos);
    free(t->first);
    free(t->cost);
    free(t->sub);
    free(t->kind);
    free(t->uoff);
    memset(t, 0, sizeof *t);
}

/* The supernodal tree, a postorder, the work of each supernode and subtree. */
static thx_status tree_build(thx_ctx *ctx, const thx_mf_symbolic *S, mf_tree *t)
{
    const int64_t ns = S->nsuper, n = S->n;
    size_t m = (size_t)(ns > 0 ? ns : 1);
    t->S = S;
    t->parent = malloc(m * sizeof *t->parent);
    t->cstart = calloc(m + 1, sizeof *t->cstart);
    t->child = malloc(m * sizeof *t->child);
    t->post = malloc(m * sizeof *t->post);
    t->pos = malloc(m * sizeof *t->pos);
    t->first = malloc(m * sizeof *t->first);
    t->cost = malloc(m * sizeof *t->cost);
    t->sub = malloc(m * sizeof *t->sub);
    t->kind = calloc(m, 1);
    t->uoff = calloc(m, sizeof *t->uoff);
    int64_t *of = malloc((size_t)(n > 0 ? n : 1) * sizeof *of), *stack = malloc(m * sizeof *stack);
    thx_status st = THX_OK;
    if (!t->parent || !t->cstart || !t->child || !t->post || !t->pos || !t->first || !t->cost || !t->sub || !t->kind ||
        !t->uoff || !of || !stack) { st = THX_ENOMEM; goto done; }
    for (int64_t s = 0; s < ns; s++)
        for (int64_t j = S->super[s]; j < S->super[s + 1]; j++) of[j] = s;
    for (int64_t s = 0; s < ns; s++) {
        int64_t k = ncol(S, s), r = nrow(S, s), b = r - k;
        if (k < 1 || b < 0 || r > INT_MAX) {
            st = thx_error(ctx, THX_ESOLVER, "fem: supernode %lld of the symbolic factor has %lld columns and %lld rows "
                           "(the factorization needs 1 to %d)", (long long)s + 1, (long long)k, (long long)r, INT_MAX);
            goto done;
        }
        t->parent[s] = b > 0 ? of[S->rows[S->pi[s] + k]] : -1;
        if (t->parent[s] >= 0 && t->parent[s] <= s) {
            st = thx_error(ctx, THX_ESOLVER, "fem: the symbolic factor's supernode %lld has its parent %lld before it",
                           (long long)s + 1, (long long)t->parent[s] + 1);
            goto done;
        }
        double kk = (double)k, bb = (double)b;
        t->cost[s] = kk * kk * kk / 3 + bb * kk * kk + bb * bb * kk + (double)r * kk + bb * bb;
        if (t->parent[s] >= 0) t->cstart[t->parent[s] + 1]++;
    }
    for (int64_t s = 0; s < ns; s++) t->cstart[s + 1] += t->cstart[s];
    {
        int64_t *fill = of; /* reused: the next free place of each supernode's children */
        for (int64_t s = 0; s < ns; s++) fill[s] = t->cstart[s];
        for (int64_t s = 0; s < ns; s++)
            if (t->parent[s] >= 0) t->child[fill[t->parent[s]]++] = s; /* ascending */
    }
    /* subtree sums: a parent comes after its children */
    for (int64_t s = 0; s < ns; s++) t->sub[s] = t->cost[s];
    for (int64_t s = 0; s < ns; s++)
        if (t->parent[s] >= 0) t->sub[t->parent[s]] += t->sub[s];
    /* a postorder: depth first from each root, children in ascending order */
    int64_t np = 0;
    for (int64_t r = 0; r < ns; r++) {
        if (t->parent[r] >= 0) continue;
        int64_t sp = 0;
        stack[sp++] = r;
        of[r] = t->cstart[r]; /* the next child to visit */
        while (sp) {
            int64_t s = stack[sp - 1];
            if (of[s] < t->cstart[s + 1]) {
                int64_t c = t->child[of[s]++];
                of[c] = t->cstart[c];
                stack[sp++] = c;
            } else {
                sp--;
                t->pos[s] = np;
                t->post[np++] = s;
                t->first[s] = t->cstart[s] < t->cstart[s + 1] ? t->first[t->child[t->cstart[s]]] : t->pos[s];
            }
        }
    }
    if (np != ns) st = thx_error(ctx, THX_ESOLVER, "fem: the symbolic factor's supernodal tree is not a forest");
done:
    free(of);
    free(stack);
    return st;
}

/* L sorted by subtree work, heaviest first (ties: lower number first); L is short (the subtrees). */
static void sort_heaviest_first(int64_t *L, size_t nl, const double *sub)
{
    for (size_t i = 1; i < nl; i++) {
        int64_t x = L[i];
        size_t j = i;
        while (j > 0 && (sub[L[j - 1]] < sub[x] || (sub[L[j - 1]] == sub[x] && L[j - 1] > x))) {
            L[j] = L[j - 1];
            j--;
        }
        L[j] = x;
    }
}

/* The largest load when the subtrees (heaviest first) are dealt one by one to the least loaded of T threads. */
static double lpt(const int64_t *L, size_t nl, const double *sub, int T, double *bins)
{
    for (int i = 0; i < T; i++) bins[i] = 0;
    for (size_t i = 0; i < nl; i++) {
        int lo = 0;
        for (int k = 1; k < T; k++)
            if (bins[k] < bins[lo]) lo = k;
        bins[lo] += sub[L[i]];
    }
    double mx = 0;
    for (int i = 0; i < T; i++) mx = bins[i] > mx ? bins[i] : mx;
    return mx;
}

/* The subtrees for T threads into *out (heaviest first), the rest marked K_TOP. */
static thx_status cut_tree(mf_tree *t, int T, int64_t **out, size_t *n_out)
{
    const int64_t ns = t->S->nsuper;
    size_t cap = (size_t)(ns > 0 ? ns : 1);
    int64_t *L = malloc(cap * sizeof *L);
    double *bins = malloc((size_t)T * sizeof *bins);
    if (!L || !bins) { free(L); free(bins); return THX_ENOMEM; }
    size_t nl = 0;
    for (int64_t s = 0; s < ns; s++)
        if (t->parent[s] < 0) L[nl++] = s;
    for (;;) {
        sort_heaviest_first(L, nl, t->sub);
        if (T <= 1 || !nl) break;
        double sum = 0;
        for (size_t i = 0; i < nl; i++) sum += t->sub[L[i]];
        int64_t h = L[0];
        if (nl >= (size_t)T && lpt(L, nl, t->sub, T, bins) <= 1.05 * sum / T) break;
        if (t->cstart[h] == t->cstart[h + 1] || nl > (size_t)64 * (size_t)T) break; /* a leaf cannot be split */
        t->kind[h] = K_TOP;
        L[0] = L[--nl];
        for (int64_t e = t->cstart[h]; e < t->cstart[h + 1]; e++) L[nl++] = t->child[e];
    }
    for (size_t i = 0; i < nl; i++) t->kind[L[i]] = K_ROOT;
    free(bins);
    *out = L;
    *n_out = nl;
    return THX_OK;
}

/* The most doubles a stack holds while the supernodes post[a .. b] are done in order (K_ROOT's update
   matrix goes to the roots' arena, not to the stack); top_only: the K_TOP ones alone (the top's stack, whose
   supernodes' children are K_TOP or K_ROOT). */
static size_t stack_peak(const mf_tree *t, int64_t a, int64_t b, int top_only)
{
    size_t top = 0, peak = 0;
    for (int64_t k = a; k <= b; k++) {
        int64_t s = t->post[k];
        if (top_only && t->kind[s] != K_TOP) continue;
        size_t popped = 0;
        for (int64_t e = t->cstart[s]; e < t->cstart[s + 1]; e++)
            if (t->kind[t->child[e]] != K_ROOT) popped += usize(t->S, t->child[e]);
        size_t u = t->kind[s] == K_ROOT ? 0 : usize(t->S, s);
        if (top + u > peak) peak = top + u;
        top = top - popped + u;
    }
    return peak;
}

/* Supernode s: its front assembled, factored, its update matrix left at the stack's top (or in the
   roots' arena). map (n, all -1 between fronts) and rel (the most rows) are the thread's. Returns 0,
   dpotrf's info (> 0), or -1 when the symbolic factor does not hold the matrix (a row of A or of a child's
   update matrix missing from the front). */
static int front(mf_tree *t, int64_t s, double *stk, size_t *top, int32_t *map, int32_t *rel)
{
    const thx_mf_symbolic *S = t->S;
    const int64_t j0 = S->super[s], k = ncol(S, s), r = nrow(S, s), nb = r - k;
    const int64_t *rows = S->rows + S->pi[s];
    double *Lb = t->Lx + S->px[s];
    double *U = t->kind[s] == K_ROOT ? t->roots + t->uoff[s] : stk + *top;
    /* only U's lower triangle is ever written or read (the extend-add and dsyrk's "L"): the upper one is
       neither zeroed nor moved, and a large update matrix's pages above the diagonal are never touched */
    for (int64_t b = 0; b < nb; b++) memset(U + (size_t)b * (size_t)nb + (size_t)b, 0, (size_t)(nb - b) * sizeof *U);
    for (int64_t i = 0; i < r; i++) map[rows[i]] = (int32_t)i;
    int fault = 0;
    /* A's entries of the front's columns (the lower triangle, in the factor's order) */
    for (int64_t j = j0; j < j0 + k; j++) {
        const int64_t q = t->perm[j];
        double *cj = Lb + (size_t)(j - j0) * (size_t)r;
        for (int64_t e = t->rowp[q]; e < t->rowp[q + 1]; e++) {
            const int64_t i = t->iperm[t->col[e]];
            if (i < j) continue;
            if (map[i] < 0) fault = 1; /* a row the symbolic factor does not hold */
            else cj[map[i]] += t->val[e];
        }
    }
    /* the children's update matrices (their rows are some of the front's) */
    size_t popped = 0;
    for (int64_t e = t->cstart[s]; e < t->cstart[s + 1]; e++) {
        const int64_t c = t->child[e], kc = ncol(S, c), nbc = nrow(S, c) - kc;
        const int64_t *crow = S->rows + S->pi[c] + kc;
        const double *Uc = t->kind[c] == K_ROOT ? t->roots + t->uoff[c] : stk + t->uoff[c];
        if (t->kind[c] != K_ROOT) popped += (size_t)nbc * (size_t)nbc;
        for (int64_t a = 0; a < nbc; a++) {
            rel[a] = map[crow[a]];
            if (rel[a] < 0) fault = 1;
        }
        if (fault) break;
        for (int64_t b = 0; b < nbc; b++) {
            const double *src = Uc + (size_t)b * (size_t)nbc;
            const int32_t tc = rel[b];
            double *dst = tc < k ? Lb + (size_t)tc * (size_t)r : U + (size_t)(tc - k) * (size_t)nb - k;
            for (int64_t a = b; a < nbc; a++) dst[rel[a]] += src[a];
        }
    }
    for (int64_t i = 0; i < r; i++) map[rows[i]] = -1; /* (unset for the next front: a row it lacks is seen) */
    if (fault) return -1;
    /* the children popped: the update matrix moved down onto them */
    if (t->kind[s] != K_ROOT) {
        size_t base = *top - popped;
        if (popped) /* column by column, lower parts only: each destination lies below every later source */
            for (int64_t b = 0; b < nb; b++) {
                size_t o = (size_t)b * (size_t)nb + (size_t)b;
                memmove(stk + base + o, U + o, (size_t)(nb - b) * sizeof *U);
            }
        U = stk + base;
        t->uoff[s] = (int64_t)base;
        *top = base + (size_t)nb * (size_t)nb;
    } else *top -= popped;
    int ik = (int)k, ir = (int)r, ib = (int)nb, info = 0;
    const double one = 1, minus = -1;
    dpotrf_("L", &ik, Lb, &ir, &info);
    if (info) return info;
    if (nb) {
        dtrsm_("R", "L", "T", "N", &ib, &ik, &one, Lb, &ir, Lb + k, &ir);
        dsyrk_("L", "N", &ib, &ik, &minus, Lb + k, &ir, &one, U, &ib);
    }
    return 0;
}

struct thx_mf {
    const thx_mf_symbolic *S;
    mf_tree t;
    int T;
    int64_t *subs;
    size_t nsub;
    double **stacks, *top_stack;  /* in stack_pg (the threads'), in top_pg (the top's, after the roots') */
    thx_pages stack_pg, top_pg;    /* present before the first front (thorax/core/pages.h) */
    int32_t **maps;
    unsigned char *top_mask; /* nsuper: 1 for the top's supernodes */
    int top_left;            /* the top is still to be factored */
    thx_mf_info inf;
};

void thx_mf_free(thx_mf **mp)
{
    if (!mp || !*mp) return;
    thx_mf *m = *mp;
    if (m->maps)
        for (int i = 0; i < m->T; i++) free(m->maps[i]);
    free(m->stacks);
    free(m->maps);
    thx_pages_free(&m->stack_pg);
    thx_pages_free(&m->top_pg);
    m->t.roots = NULL;
    free(m->subs);
    free(m->top_mask);
    tree_free(&m->t);
    free(m);
    *mp = NULL;
}

/* The top's fronts checked before any is factored: every row of A's columns and of each child's update matrix
   is one of the front's rows (front() checks the same as it assembles; here it is known before the subtrees'
   results are waited for, so a top run beside other work cannot fail on it). 1 when they all are. */
static int top_structure_ok(const mf_tree *t, int32_t *map)
{
    const thx_mf_symbolic *S = t->S;
    int ok = 1;
    for (int64_t s = 0; s < S->nsuper && ok; s++) {
        if (t->kind[s] != K_TOP) continue;
        const int64_t j0 = S->super[s], k = ncol(S, s), r = nrow(S, s);
        const int64_t *rows = S->rows + S->pi[s];
        for (int64_t i = 0; i < r; i++) map[rows[i]] = 1;
        for (int64_t j = j0; j < j0 + k && ok; j++) {
            const int64_t q = t->perm[j];
            for (int64_t e = t->rowp[q]; e < t->rowp[q + 1]; e++) {
                const int64_t i = t->iperm[t->col[e]];
                if (i >= j && map[i] < 0) ok = 0;
            }
        }
        for (int64_t e = t->cstart[s]; e < t->cstart[s + 1] && ok; e++) {
            const int64_t c = t->child[e], kc = ncol(S, c), nbc = nrow(S, c) - kc;
            const int64_t *crow = S->rows + S->pi[c] + kc;
            for (int64_t a = 0; a < nbc; a++)
                if (map[crow[a]] < 0) ok = 0;
        }
        for (int64_t i = 0; i < r; i++) map[rows[i]] = -1;
    }
    return ok;
}

thx_status thx_mf_begin(thx_ctx *ctx, const thx_mf_symbolic *S, const int64_t *rowp, const int32_t *col,
                        const double *val, const int64_t *perm, const int64_t *iperm, int threads,
                        void (*set_blas_threads)(int), double *Lx, thx_mf **out, thx_mf_info *info)
{
    *out = NULL;
    thx_mf *m = calloc(1, sizeof *m);
    if (!m) return THX_ENOMEM;
    m->S = S;
    m->inf.not_posdef = -1;
    const int T = threads > 1 ? threads : 1;
    m->T = m->inf.threads = T;
    mf_tree *tp = &m->t;
    thx_status st = tree_build(ctx, S, tp);
    if (st != THX_OK) goto done;
    tp->rowp = rowp;
    tp->col = col;
    tp->val = val;
    tp->perm = perm;
    tp->iperm = iperm;
    tp->Lx = Lx;
    if ((st = cut_tree(tp, T, &m->subs, &m->nsub)) != THX_OK) goto done;
    const mf_tree t = *tp; /* (its arrays are tp's) */
    /* the arenas: the subtree roots' update matrices, a stack per thread, the top's stack */
    size_t roots_n = 0, thread_n = 0, top_n = 0, max_rows = 1;
    for (size_t i = 0; i < m->nsub; i++) {
        tp->uoff[m->subs[i]] = (int64_t)roots_n;
        roots_n += usize(S, m->subs[i]);
        size_t p = stack_peak(&t, t.first[m->subs[i]], t.pos[m->subs[i]], 0);
        thread_n = p > thread_n ? p : thread_n;
    }
    m->top_mask = calloc((size_t)(S->nsuper > 0 ? S->nsuper : 1), 1);
    if (!m->top_mask) { st = THX_ENOMEM; goto done; }
    for (int64_t s = 0; s < S->nsuper; s++) {
        max_rows = (size_t)nrow(S, s) > max_rows ? (size_t)nrow(S, s) : max_rows;
        if (t.kind[s] == K_TOP) {
            m->inf.top++;
            m->top_mask[s] = 1;
        }
    }
    top_n = stack_peak(&t, 0, S->nsuper - 1, 1); /* the top's stack: its supernodes alone, in the postorder */
    /* the arenas' pages asked for at once, by the threads together: every page of them is written (the
       stacks up to their peak, which is their size), and a page faulted in alone costs about twice as much */
    const size_t line = 8; /* each thread's stack on a 64-byte line of its own */
    roots_n = (roots_n + line - 1) / line * line;
    thread_n = (thread_n + line - 1) / line * line;
    m->stacks = calloc((size_t)T, sizeof *m->stacks);
    m->maps = calloc((size_t)T, sizeof *m->maps);
    if (!m->stacks || !m->maps || thx_pages_zeroed(&m->top_pg, (roots_n + top_n + 1) * sizeof(double), T) ||
        thx_pages_zeroed(&m->stack_pg, ((size_t)T * thread_n + 1) * sizeof(double), T)) {
        st = THX_ENOMEM;
        goto done;
    }
    tp->roots = m->top_pg.p;
    m->top_stack = tp->roots + roots_n;
    for (int i = 0; i < T; i++) {
        m->stacks[i] = (double *)m->stack_pg.p + (size_t)i * thread_n;
        m->maps[i] = malloc(((size_t)S->n + max_rows + 1) * sizeof **m->maps);
        if (!m->maps[i]) { st = THX_ENOMEM; goto done; }
        for (int64_t j = 0; j < S->n; j++) m->maps[i][j] = -1;
    }
    m->inf.subtrees = m->nsub;
    m->inf.stack_bytes = (roots_n + top_n + (size_t)T * thread_n) * sizeof(double);
    double total = 0, top_cost = 0;
    for (int64_t s = 0; s < S->nsuper; s++) {
        total += t.cost[s];
        if (t.kind[s] == K_TOP) top_cost += t.cost[s];
        double k = (double)ncol(S, s), b = (double)(nrow(S, s) - ncol(S, s));
        m->inf.flops += k * k * k / 3 + b * k * k + b * b * k;
        if (t.kind[s] == K_TOP) m->inf.top_flops += k * k * k / 3 + b * k * k + b * b * k;
    }
    m->inf.top_share = total > 0 ? top_cost / total : 0;
    if (!top_structure_ok(tp, m->maps[0])) {
        st = thx_error(ctx, THX_EINTERNAL, "fem: the symbolic factor does not hold the matrix's pattern (a row missing "
                       "from a supernode): not the analysis of this matrix");
        goto done;
    }

    /* the subtrees, heaviest first, each thread with its own stack and BLAS single-threaded */
    double t0 = thx_wtime();
    if (set_blas_threads) set_blas_threads(1);
    int64_t bad = INT64_MAX;
    int failed = 0, structure = 0;
    const int64_t *subs = m->subs;
    double **stacks = m->stacks;
    int32_t **maps = m->maps;
#pragma omp parallel num_threads(T)
    {
        int me = 0;
#ifdef _OPENMP
        me = omp_get_thread_num();
#endif
        int32_t *map = maps[me], *rel = maps[me] + S->n;
#pragma omp for schedule(dynamic, 1)
        for (size_t i = 0; i < m->nsub; i++) {
            int stop;
#pragma omp atomic read
            stop = failed;
            if (stop) continue;
            size_t top = 0;
            for (int64_t k = tp->first[subs[i]]; k <= tp->pos[subs[i]]; k++) {
                int64_t s = tp->post[k];
                int e = front(tp, s, stacks[me], &top, map, rel);
                if (e) {
#pragma omp critical(thx_mf_bad)
                    {
                        if (e < 0) structure = 1;
                        else {
                            int64_t c = S->super[s] + e - 1;
                            bad = c < bad ? c : bad;
                        }
                        failed = 1;
                    }
                    break;
                }
            }
        }
    }
    m->inf.t_subtrees = thx_wtime() - t0;
    /* the threads' stacks are not needed by the top: given back before it (it may run beside other work) */
    for (int i = 0; i < T; i++) m->stacks[i] = NULL; /* (spare now: thx_mf_take_spare) */
    if (structure)
        st = thx_error(ctx, THX_EINTERNAL, "fem: the symbolic factor does not hold the matrix's pattern (a row missing "
                       "from a supernode): not the analysis of this matrix");
    else if (failed) {
        m->inf.not_posdef = bad;
        st = THX_ESOLVER;
    }
    m->top_left = st == THX_OK;
done:
    if (info) *info = m->inf;
    if (st != THX_OK) thx_mf_free(&m);
    *out = m;
    return st;
}

thx_status thx_mf_top(thx_mf *m, int top_threads, void (*set_blas_threads)(int), thx_mf_info *info)
{
    if (!m->top_left) {
        if (info) *info = m->inf;
        return THX_OK;
    }
    const thx_mf_symbolic *S = m->S;
    mf_tree *tp = &m->t;
    double t0 = thx_wtime();
    if (set_blas_threads) set_blas_threads(top_threads > 1 ? top_threads : 1);
    size_t top = 0;
    int failed = 0;
    thx_status st = THX_OK;
    for (int64_t k = 0; k < S->nsuper && !failed; k++) {
        int64_t s = tp->post[k];
        if (tp->kind[s] != K_TOP) continue;
        int e = front(tp, s, m->top_stack, &top, m->maps[0], m->maps[0] + S->n);
        if (e) { /* (e < 0, the structure, was ruled out before the subtrees) */
            m->inf.not_posdef = e > 0 ? S->super[s] + e - 1 : S->super[s];
            failed = 1;
            st = THX_ESOLVER;
        }
    }
    m->inf.t_top = thx_wtime() - t0;
    m->top_left = 0;
    /* what the top needed, given back (the mask stays: other threads may still read it) */
    tp->roots = NULL;
    m->top_stack = NULL;
    if (info) *info = m->inf;
    return st;
}

const unsigned char *thx_mf_top_mask(const thx_mf *m) { return m->top_left ? m->top_mask : NULL; }

void thx_mf_take_spare(thx_mf *m, thx_pages *out)
{
    /* (a state the caller holds has its subtrees done: thx_mf_begin frees it on failure) */
    thx_pages *a = m->stack_pg.p ? &m->stack_pg : NULL, *b = !m->top_left && m->top_pg.p ? &m->top_pg : NULL;
    thx_pages *take = a && b ? (a->bytes >= b->bytes ? a : b) : a ? a : b;
    if (take) {
        *out = *take;
        take->p = NULL;
        take->bytes = 0;
    } else
        out->p = NULL, out->bytes = 0;
}

thx_status thx_mf_factor(thx_ctx *ctx, const thx_mf_symbolic *S, const int64_t *rowp, const int32_t *col,
                         const double *val, const int64_t *perm, const int64_t *iperm, int threads, int top_threads,
                         void (*set_blas_threads)(int), double *Lx, thx_mf_info *info)
{
    thx_mf *m = NULL;
    thx_status st = thx_mf_begin(ctx, S, rowp, col, val, perm, iperm, threads, set_blas_threads, Lx, &m, info);
    if (st == THX_OK) st = thx_mf_top(m, top_threads, set_blas_threads, info);
    thx_mf_free(&m);
    return st;
}
