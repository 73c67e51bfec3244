/*
 * Forward problems on a meshed model (thorax/fem/fem.h): the epicardial problem
 * for a series of frames, and its transfer matrix; both solve their right-hand
 * sides in blocks (thx_fem_solve_block: one dense multi-right-hand-side solve
 * per block with a factorization, one KSPSolve per column otherwise).
 */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/fem/fem.h"
void thx_forward_opts_default(thx_forward_opts *o)
{
    memset(o, 0, sizeof *o);
    o->warm = 1;
}

void thx_forward_result_free(thx_forward_result *r)
{
    if (!r) return;
    thx_series_destroy(&r->torso);
    thx_series_destroy(&r->volume);
}

/* The one surface of a role, or an error naming how many there are. */
static thx_status one_surface(thx_ctx *ctx, const thx_model *m, thx_role role, const char *what, size_t *idx)
{
    size_t n = 0;
    for (size_t s = 0; s < m->n_surfaces; s++)
        if (m->surf[s]->role == role) { *idx = s; n++; }
    if (n != 1)
        return thx_error(ctx, THX_EINPUT, "forward: the model has %zu surfaces of role %s; exactly one is needed", n, what);
    return THX_OK;
}

/* The epicardial problem's set-up shared by the frame loop and the transfer matrix.
 * Prescribed (Dirichlet) nodes: the heart surface's nodes, and the Steiner
 * nodes the mesher put on its triangles (thorax/model/volume.h), whose values are
 * interpolated from the triangle's corners with the barycentric weights —
 * left free, they would be unknowns inside the boundary and the potential
 * would sag between the corners. */
typedef struct {
    size_t heart, outer;
    unsigned char *use_region, *kind;
    thx_csr K;
    int32_t *part;             /* under mpirun: node -> rank (thx_fem_partition), else NULL */
    thx_fem_system *sys;
    double t_assemble;
    thx_fem_assembly_info assembly;
    size_t n_st;            /* Steiner nodes on the heart surface (active ones) */
    int32_t *st_node;       /* their volume nodes */
    int32_t *st_corner;     /* 3 per node: heart-surface node numbers of the triangle's corners */
    double *st_w;           /* 3 per node: barycentric weights */
} epi_problem;

static void epi_free(epi_problem *p)
{
    free(p->use_region);
    free(p->kind);
    free(p->st_node);
    free(p->st_corner);
    free(p->st_w);
    thx_csr_free(&p->K);
    free(p->part);
    thx_fem_system_destroy(&p->sys);
}

static thx_status epi_setup(thx_ctx *ctx, const thx_model *m, epi_problem *p)
{
    memset(p, 0, sizeof *p);
    const thx_volume *v = m->volume;
    if (!v || !v->n_tets) return thx_error(ctx, THX_EINPUT, "forward: the model has no volume mesh (run thorax mesh)");
    THX_CHECK(one_surface(ctx, m, THX_ROLE_HEART, "heart", &p->heart));
    THX_CHECK(one_surface(ctx, m, THX_ROLE_OUTER, "outer", &p->outer));
    if (v->n_surfaces != m->n_surfaces)
        return thx_error(ctx, THX_EINPUT, "forward: the volume's node tables list %zu surfaces, the model %zu", v->n_surfaces,
                         m->n_surfaces);
    thx_status st = THX_OK;
    p->use_region = thx_malloc(ctx, v->n_regions ? v->n_regions : 1);
    if (!p->use_region) return THX_ENOMEM;
    for (size_t r = 0; r < v->n_regions; r++) p->use_region[r] = strcmp(v->regions[r].name, "heart") != 0;
    THX_TRY(thx_fem_active_nodes(ctx, v, p->use_region, &p->kind));
    size_t on = 0;
    for (size_t i = 0; i < m->surf[p->heart]->n_nodes; i++) {
        int32_t k = v->surf_node[p->heart][i];
        if (p->kind[k]) { p->kind[k] = 2; on++; }
    }
    if (!on) { st = thx_error(ctx, THX_EINPUT, "forward: no node of the heart surface '%s' is in the mesh", m->surf[p->heart]->name); goto done; }
    {
        const thx_surface *hs = m->surf[p->heart];
        size_t n = 0;
        for (size_t k = 0; k < v->n_steiner; k++) n += v->steiner[k].surf == (int32_t)p->heart;
        p->st_node = thx_malloc(ctx, (n ? n : 1) * sizeof *p->st_node);
        p->st_corner = thx_malloc(ctx, 3 * (n ? n : 1) * sizeof *p->st_corner);
        p->st_w = thx_malloc(ctx, 3 * (n ? n : 1) * sizeof *p->st_w);
        if (!p->st_node || !p->st_corner || !p->st_w) { st = THX_ENOMEM; goto done; }
        for (size_t k = 0; k < v->n_steiner; k++) {
            const thx_steiner *r = &v->steiner[k];
            if (r->surf != (int32_t)p->heart) continue;
            if (r->node < 0 || (size_t)r->node >= v->n_nodes || r->tri < 0 || (size_t)r->tri >= hs->n_tris) {
                st = thx_error(ctx, THX_EINPUT, "forward: Steiner record %zu: node or triangle of '%s' out of range", k + 1,
                               hs->name);
                goto done;
            }
            if (!p->kind[r->node]) continue;
            p->kind[r->node] = 2;
            for (int c = 0; c < 3; c++) {
                p->st_corner[3 * p->n_st + (size_t)c] = hs->tri[3 * (size_t)r->tri + (size_t)c];
                p->st_w[3 * p->n_st + (size_t)c] = r->bary[c];
            }
            p->st_node[p->n_st++] = r->node;
        }
    }
    {
        /* under mpirun: the nodes partitioned among the ranks, each assembling the rows it owns (and
           the prescribed nodes' rows, which the transfer matrix's adjoint method reads) */
        int rank = 0, size = 1;
        THX_TRY(thx_fem_init(0, NULL, &rank, &size));
        unsigned char *rows = NULL;
        if (size > 1) {
            size_t nn = v->n_nodes;
            p->part = thx_malloc(ctx, (nn ? nn : 1) * sizeof *p->part);
            rows = thx_malloc(ctx, nn ? nn : 1);
            if (!p->part || !rows) { free(rows); st = THX_ENOMEM; goto done; }
            st = thx_fem_partition(ctx, v, p->kind, size, p->part);
            for (size_t i = 0; st == THX_OK && i < nn; i++) rows[i] = p->part[i] == rank || p->kind[i] == 2;
        }
        double t0 = thx_wtime();
        /* one rank: the matrix kept from an earlier run on the same mesh and conductivities, if any */
        if (st == THX_OK)
            st = size > 1 ? thx_fem_assemble_rows(ctx, v, p->use_region, rows, &p->K)
                          : thx_fem_assemble_kept(ctx, v, p->use_region, &p->K, &p->assembly);
        p->t_assemble = thx_wtime() - t0;
        free(rows);
        if (st != THX_OK) goto done;
    }
    THX_TRY(thx_fem_system_create_parts(ctx, &p->K, p->kind, 0, p->part, &p->sys));
    return THX_OK;
done:
    epi_free(p);
    return st;
}

/* (K_fd^T y)_d = sum over free k of K(k, d) y_k (K symmetric: row d of K holds K(k, d)). */
static double kfd_dot(const epi_problem *P, int32_t d, const double *y)
{
    double s = 0;
    for (int64_t k = P->K.row[d]; k < P->K.row[d + 1]; k++)
        if (P->kind[P->K.col[k]] == 1) s += P->K.val[k] * y[P->K.col[k]];
    return s;
}

/* The epicardial frames through thx_fem_solve_rows: the heart's nodes and its Steiner points (their values
   interpolated in the heart's triangles) in, the outer surface's nodes out, into r->torso. */
static thx_status epi_solve_rows(thx_ctx *ctx, const thx_model *m, const thx_series *epi, const epi_problem *P,
                                 const thx_forward_opts *o, thx_forward_result *r)
{
    const thx_volume *v = m->volume;
    const thx_surface *hs = m->surf[P->heart], *os = m->surf[P->outer];
    const size_t nf = epi->n_frames, nh = hs->n_nodes;
    thx_status st = THX_OK;
    int32_t *pnode = thx_malloc(ctx, (nh + P->n_st + 1) * sizeof *pnode);
    int32_t *src = thx_malloc(ctx, (nh + 1) * sizeof *src); /* the heart node of each value, or -1: a Steiner point */
    double *pres = NULL;
    size_t np = 0;
    if (!pnode || !src) { st = THX_ENOMEM; goto done; }
    for (size_t i = 0; i < nh; i++) {
        int32_t k = v->surf_node[P->heart][i];
        if (P->kind[k] == 2) { src[np] = (int32_t)i; pnode[np++] = k; }
    }
    size_t nheart = np;
    for (size_t q = 0; q < P->n_st; q++) pnode[np++] = P->st_node[q];
    pres = thx_malloc(ctx, (np * nf > 0 ? np * nf : 1) * sizeof *pres);
    if (!pres) { st = THX_ENOMEM; goto done; }
    /* (the frames shared by the threads: 22 MB of new pages on the high phantom's 300 frames) */
#pragma omp parallel for schedule(static)
    for (size_t f = 0; f < nf; f++) {
        const double *e = epi->v + f * epi->n_rows;
        double *pf = pres + f * np;
        for (size_t c = 0; c < nheart; c++) pf[c] = e[src[c]];
        for (size_t q = 0; q < P->n_st; q++) {
            const int32_t *c = P->st_corner + 3 * q;
            const double *w = P->st_w + 3 * q;
            pf[nheart + q] = w[0] * e[c[0]] + w[1] * e[c[1]] + w[2] * e[c[2]];
        }
    }
    thx_fem_solve_stats ss;
    THX_TRY(thx_fem_solve_rows(ctx, P->sys, pnode, np, pres, nf, o->warm, v->surf_node[P->outer], os->n_nodes, r->torso->v,
                               &ss));
    r->it_min = ss.iterations_min;
    r->it_max = ss.iterations;
    r->it_total = ss.iterations_total;
    r->max_residual = ss.residual;
    r->backward_share = ss.backward_share;
    r->check = ss.check;
    r->t_solve = ss.seconds;
    if (ss.block) r->block = ss.block;
    if (o->progress) o->progress(o->user, nf, nf);
done:
    free(pnode);
    free(src);
    free(pres);
    return st;
}

thx_status thx_forward_epicardial(thx_ctx *ctx, const thx_model *m, const thx_series *epi, const thx_forward_opts *o,
                                  thx_forward_result *r)
{
    memset(r, 0, sizeof *r);
    thx_forward_opts def;
    if (!o) { thx_forward_opts_default(&def); o = &def; }
    epi_problem P;
    thx_status st = THX_OK;
    double *phi = NULL;
    /* the series before anything expensive */
    {
        size_t heart = 0;
        THX_CHECK(one_surface(ctx, m, THX_ROLE_HEART, "heart", &heart));
        if (epi->n_rows != m->surf[heart]->n_nodes)
            return thx_error(ctx, THX_EINPUT, "forward: the epicardial series has %zu rows, the heart surface '%s' %zu nodes",
                             epi->n_rows, m->surf[heart]->name, m->surf[heart]->n_nodes);
        size_t row, frame;
        size_t bad = thx_series_find_nonfinite(epi, &row, &frame);
        if (bad)
            return thx_error(ctx, THX_EINPUT, "forward: the epicardial series has %zu value%s that %s not finite "
                             "(first: row %zu, frame %zu)", bad, bad > 1 ? "s" : "", bad > 1 ? "are" : "is", row + 1, frame + 1);
    }
    THX_CHECK(epi_setup(ctx, m, &P));
    const thx_volume *v = m->volume;
    const thx_surface *hs = m->surf[P.heart], *os = m->surf[P.outer];
    size_t nf = epi->n_frames, nn = v->n_nodes;
    THX_TRY(thx_series_create(ctx, os->n_nodes, nf, &r->torso));
    if (o->keep_volume) THX_TRY(thx_series_create(ctx, nn, nf, &r->volume));
    thx_series *outs[2] = {r->torso, r->volume};
    for (int k = 0; k < 2; k++) {
        if (!outs[k]) continue;
        memcpy(outs[k]->time, epi->time, nf * sizeof *epi->time);
        snprintf(outs[k]->unit, sizeof outs[k]->unit, "%s", epi->unit);
        snprintf(outs[k]->time_unit, sizeof outs[k]->time_unit, "%s", epi->time_unit);
    }
    snprintf(r->torso->label, sizeof r->torso->label, "potentials on '%s' (epicardial forward problem)", os->name);
    if (r->volume) snprintf(r->volume->label, sizeof r->volume->label, "potentials at the volume nodes (epicardial forward problem)");
    r->it_min = 1 << 30;
    thx_fem_system_hint_rhs(P.sys, nf);
    if (o->block) thx_fem_system_set_block(P.sys, o->block);
    /* frames in blocks: one dense multi-right-hand-side solve per block with a factorization, else
       (block 1) frame by frame, each frame starting from the previous one's solution */
    size_t nb = thx_fem_system_block(P.sys);
    nb = nb < nf ? nb : nf ? nf : 1;
    r->block = nb;
    if (nb > 1 && !r->volume && !o->dump_system) {
        /* a factorization and the outer surface alone: the prescribed values per prescribed node in, the outer
           surface's values out (thx_fem_solve_rows: no column of every node is made) */
        THX_TRY(epi_solve_rows(ctx, m, epi, &P, o, r));
        goto solved;
    }
    phi = thx_calloc(ctx, nn * nb > 0 ? nn * nb : 1, sizeof *phi);
    if (!phi) { st = THX_ENOMEM; goto done; }
    for (size_t f0 = 0; f0 < nf; f0 += nb) {
        size_t k = nf - f0 < nb ? nf - f0 : nb;
        if (f0 > 0 && nb > 1) memcpy(phi, phi + (nb - 1) * nn, nn * sizeof *phi); /* the warm start */
        for (size_t j = 0; j < k; j++) {
            const double *e = epi->v + (f0 + j) * epi->n_rows;
            double *pj = phi + j * nn;
            for (size_t i = 0; i < hs->n_nodes; i++) pj[v->surf_node[P.heart][i]] = e[i];
            for (size_t q = 0; q < P.n_st; q++) {
                const int32_t *c = P.st_corner + 3 * q;
                const double *w = P.st_w + 3 * q;
                pj[P.st_node[q]] = w[0] * e[c[0]] + w[1] * e[c[1]] + w[2] * e[c[2]];
            }
        }
        if (f0 == 0 && o->dump_system) THX_TRY(thx_fem_system_dump(ctx, P.sys, phi, NULL, o->dump_system));
        thx_fem_solve_stats ss;
        THX_TRY(thx_fem_solve_block(ctx, P.sys, phi, NULL, k, o->warm, &ss)); /* frame 1 starts from 0 */
        r->it_min = ss.iterations_min < r->it_min ? ss.iterations_min : r->it_min;
        r->it_max = ss.iterations > r->it_max ? ss.iterations : r->it_max;
        r->it_total += ss.iterations_total;
        r->max_residual = fmax(r->max_residual, ss.residual);
        r->t_solve += ss.seconds;
        for (size_t j = 0; j < k; j++) {
            const double *pj = phi + j * nn;
            double *t = r->torso->v + (f0 + j) * os->n_nodes;
            for (size_t i = 0; i < os->n_nodes; i++) t[i] = pj[v->surf_node[P.outer][i]];
            if (r->volume) memcpy(r->volume->v + (f0 + j) * nn, pj, nn * sizeof *pj);
        }
        if (o->progress) o->progress(o->user, f0 + k, nf);
    }
solved:
    if (!nf) r->it_min = 0;
    thx_fem_system_info(P.sys, &r->n_free, &r->n_prescribed, &r->t_setup);
    r->t_matrix = thx_fem_system_matrix_seconds(P.sys);
    thx_fem_system_describe(P.sys, r->ksp, r->pc, &r->ranks);
    thx_fem_system_factor_info(P.sys, &r->factor);
    r->t_assemble = P.t_assemble;
    r->assembly = P.assembly;
done:
    if (st != THX_OK) thx_forward_result_free(r);
    free(phi);
    epi_free(&P);
    return st;
}

/* rows == NULL: every outer node; corner == NULL: rows[i] alone; else row i weighs corner[3i..3i+2]. */
static thx_status transfer(thx_ctx *ctx, const thx_model *m, const int32_t *rows, const int32_t *corner,
                           const double *weight, size_t n_rows, int method, const thx_forward_opts *o, thx_series **T,
                           thx_forward_result *info)
{
    *T = NULL;
    thx_forward_opts def;
    if (!o) { thx_forward_opts_default(&def); o = &def; }
    if (info) memset(info, 0, sizeof *info);
    epi_problem P;
    THX_CHECK(epi_setup(ctx, m, &P));
    thx_status st = THX_OK;
    const thx_volume *v = m->volume;
    const thx_surface *hs = m->surf[P.heart], *os = m->surf[P.outer];
    size_t nh = hs->n_nodes, nn = v->n_nodes;
    int32_t *rv = NULL; /* volume nodes of each row: 3 a row */
    double *rw = NULL;  /* ... and their weights */
    double *phi = NULL, *load = NULL;
    thx_series *A = NULL;
    size_t nr = rows || corner ? n_rows : os->n_nodes;
    rv = thx_malloc(ctx, 3 * (nr ? nr : 1) * sizeof *rv);
    rw = thx_malloc(ctx, 3 * (nr ? nr : 1) * sizeof *rw);
    if (!rv || !rw) { st = THX_ENOMEM; goto done; }
    for (size_t i = 0; i < nr; i++)
        for (int k = 0; k < 3; k++) {
            int32_t s = corner ? corner[3 * i + (size_t)k] : rows ? rows[i] : (int32_t)i;
            double w = corner ? weight[3 * i + (size_t)k] : k == 0;
            if (s < 0 || (size_t)s >= os->n_nodes) { st = thx_error(ctx, THX_EINPUT, "forward: row %zu: node %d is not on '%s'", i + 1, s + 1, os->name); goto done; }
            if (!isfinite(w)) { st = thx_error(ctx, THX_EINPUT, "forward: row %zu: weight %d is not finite", i + 1, k + 1); goto done; }
            rv[3 * i + (size_t)k] = v->surf_node[P.outer][s];
            rw[3 * i + (size_t)k] = w;
        }
    THX_TRY(thx_series_create(ctx, nr, nh, &A));
    for (size_t j = 0; j < nh; j++) A->time[j] = (double)(j + 1);
    snprintf(A->time_unit, sizeof A->time_unit, "node");
    snprintf(A->unit, sizeof A->unit, "1");
    if (method < 0) method = nr < nh ? 1 : 0;
    thx_fem_system_hint_rhs(P.sys, o->direct ? (size_t)-1 : method ? nr : nh);
    if (corner)
        snprintf(A->label, sizeof A->label, "transfer matrix electrodes on %.40s <- %.40s (%s)", os->name, hs->name,
                 method ? "adjoint" : "forward");
    else
        snprintf(A->label, sizeof A->label, "transfer matrix %.40s <- %.40s (%s)", os->name, hs->name, method ? "adjoint" : "forward");
    int it_min = 1 << 30, it_max = 0;
    long it_total = 0;
    double tsolve = 0, maxres = 0;
    /* the solves in blocks of nb right-hand sides (one dense multi-right-hand-side solve each with a
       factorization), nb columns of phi (and of load) at a time */
    size_t n_solves = method ? nr : nh;
    if (o->block) thx_fem_system_set_block(P.sys, o->block);
    size_t nb = thx_fem_system_block(P.sys);
    nb = nb < n_solves ? nb : n_solves ? n_solves : 1;
    if (info) info->block = nb;
    phi = thx_calloc(ctx, nn * nb > 0 ? nn * nb : 1, sizeof *phi);
    load = method ? thx_calloc(ctx, nn * nb > 0 ? nn * nb : 1, sizeof *load) : NULL;
    if (!phi || (method && !load)) { st = THX_ENOMEM; goto done; }
    for (size_t c0 = 0; c0 < n_solves; c0 += nb) {
        size_t k = n_solves - c0 < nb ? n_solves - c0 : nb;
        memset(phi, 0, nn * k * sizeof *phi);
        if (method == 0) {
            /* column j: the heart at e_j; a Steiner node carries its weight of corner j */
            for (size_t q = 0; q < k; q++) phi[q * nn + (size_t)v->surf_node[P.heart][c0 + q]] = 1;
            for (size_t t = 0; t < P.n_st; t++)
                for (int c = 0; c < 3; c++) {
                    size_t j = (size_t)P.st_corner[3 * t + (size_t)c];
                    if (j >= c0 && j < c0 + k) phi[(j - c0) * nn + (size_t)P.st_node[t]] += P.st_w[3 * t + (size_t)c];
                }
        } else {
            /* row i: y = K_ff^-1 e_i (the heart at 0), loaded at the row's nodes by its weights */
            memset(load, 0, nn * k * sizeof *load);
            for (size_t q = 0; q < k; q++)
                for (int c = 0; c < 3; c++) load[q * nn + (size_t)rv[3 * (c0 + q) + (size_t)c]] += rw[3 * (c0 + q) + (size_t)c];
        }
        thx_fem_solve_stats ss;
        THX_TRY(thx_fem_solve_block(ctx, P.sys, phi, load, k, 0, &ss));
        for (size_t q = 0; q < k; q++) {
            const double *y = phi + q * nn;
            if (method == 0) {
                size_t j = c0 + q;
                for (size_t i = 0; i < nr; i++)
                    A->v[j * nr + i] = rw[3 * i] * y[rv[3 * i]] + rw[3 * i + 1] * y[rv[3 * i + 1]] + rw[3 * i + 2] * y[rv[3 * i + 2]];
            } else {
                /* T_ij = -(K_fd^T y)_j = -sum_k K(k, heart_j) y_k; a Steiner node's column of K_fd counts for its
                   corners by their weights */
                size_t i = c0 + q;
                for (size_t j = 0; j < nh; j++) A->v[j * nr + i] = -kfd_dot(&P, v->surf_node[P.heart][j], y);
                for (size_t t = 0; t < P.n_st; t++) {
                    double g = kfd_dot(&P, P.st_node[t], y);
                    for (int c = 0; c < 3; c++) A->v[(size_t)P.st_corner[3 * t + (size_t)c] * nr + i] -= P.st_w[3 * t + (size_t)c] * g;
                }
            }
        }
        it_min = ss.iterations_min < it_min ? ss.iterations_min : it_min;
        it_max = ss.iterations > it_max ? ss.iterations : it_max;
        it_total += ss.iterations_total;
        tsolve += ss.seconds;
        maxres = fmax(maxres, ss.residual);
        if (o->progress) o->progress(o->user, c0 + k, n_solves);
    }
    if (!n_solves) it_min = 0;
    if (info) {
        thx_fem_system_info(P.sys, &info->n_free, &info->n_prescribed, &info->t_setup);
        info->t_matrix = thx_fem_system_matrix_seconds(P.sys);
        thx_fem_system_describe(P.sys, info->ksp, info->pc, &info->ranks);
        thx_fem_system_factor_info(P.sys, &info->factor);
        info->t_assemble = P.t_assemble;
        info->assembly = P.assembly;
        info->t_solve = tsolve;
        info->it_min = it_min;
        info->it_max = it_max;
        info->it_total = it_total;
        info->max_residual = maxres;
    }
    *T = A;
    A = NULL;
done:
    thx_series_destroy(&A);
    free(rv);
    free(rw);
    free(phi);
    free(load);
    epi_free(&P);
    return st;
}

thx_status thx_forward_transfer(thx_ctx *ctx, const thx_model *m, const int32_t *rows, size_t n_rows, int method,
                                const thx_forward_opts *o, thx_series **T, thx_forward_result *info)
{
    return transfer(ctx, m, rows, NULL, NULL, n_rows, method, o, T, info);
}

thx_status thx_forward_transfer_weighted(thx_ctx *ctx, const thx_model *m, const int32_t *corner, const double *weight,
                                         size_t n_rows, int method, const thx_forward_opts *o, thx_series **T,
                                         thx_forward_result *info)
{
    *T = NULL;
    if (!corner || !weight) return thx_error(ctx, THX_EINPUT, "forward: weighted rows without corners or weights");
    return transfer(ctx, m, NULL, corner, weight, n_rows, method, o, T, info);
}

/* BLAS through its Fortran symbol (libblas3, OpenBLAS's at run time), as bem and inverse declare it
 * for themselves (a module's private prototypes: tests/layers.py). */
void dgemm_(const char *ta, const char *tb, const int *m, const int *n, const int *k, const double *alpha,
            const double *a, const int *lda, const double *b, const int *ldb, const double *beta, double *c,
            const int *ldc);

thx_status thx_transfer_apply(thx_ctx *ctx, const thx_series *T, const thx_series *epi, thx_series **out)
{
    *out = NULL;
    if (T->n_frames != epi->n_rows)
        return thx_error(ctx, THX_EINPUT, "transfer: the matrix has %zu columns (heart nodes), the series %zu rows",
                         T->n_frames, epi->n_rows);
    size_t row, frame;
    if (thx_series_find_nonfinite(epi, &row, &frame))
        return thx_error(ctx, THX_EINPUT, "transfer: the series has a value that is not finite (row %zu, frame %zu)", row + 1,
                         frame + 1);
    thx_series *r = NULL;
    THX_CHECK(thx_series_create(ctx, T->n_rows, epi->n_frames, &r));
    memcpy(r->time, epi->time, epi->n_frames * sizeof *r->time);
    snprintf(r->unit, sizeof r->unit, "%s", epi->unit);
    snprintf(r->time_unit, sizeof r->time_unit, "%s", epi->time_unit);
    snprintf(r->label, sizeof r->label, "transfer matrix applied");
    size_t nr = T->n_rows, nh = T->n_frames, nf = epi->n_frames;
    if (nr <= INT_MAX && nh <= INT_MAX && nf <= INT_MAX && nr && nh && nf) {
        /* the frames at once: (torso rows x heart nodes) (heart nodes x frames), one dgemm (both
           column-major, a frame a column); frame by frame it was 17 times slower for 300 frames */
        int M = (int)nr, N = (int)nf, K = (int)nh;
        double one = 1, zero = 0;
        dgemm_("N", "N", &M, &N, &K, &one, T->v, &M, epi->v, &K, &zero, r->v, &M);
    } else {
#pragma omp parallel for schedule(static)
        for (long f = 0; f < (long)nf; f++) {
            const double *e = epi->v + (size_t)f * nh;
            double *o = r->v + (size_t)f * nr;
            for (size_t j = 0; j < nh; j++) {
                const double *c = T->v + j * nr;
                double ej = e[j];
                for (size_t i = 0; i < nr; i++) o[i] += c[i] * ej;
            }
        }
    }
    *out = r;
    return THX_OK;
}
