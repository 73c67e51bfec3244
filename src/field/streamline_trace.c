/* Tracing current streamlines (thorax/field/streamline.h): RK2, RK4 and RK45 in arc length through the
 * linearly interpolated field, each point located by walking from the tetrahedron of the point before,
 * with the stop rules of the header. One seed's lines are traced by one thread into their own buffer;
 * the buffers are joined in the seeds' order. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "field/streamline_impl.h"

typedef thx_stream_piece line_buf;

typedef struct {
    line_buf line[2];
    int n_lines;
    size_t steps, evals;
    int nomem;
} seed_out;

static int push(line_buf *b, const double x[3], double cur, double phi, double arc, long tet)
{
    if (b->n == b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 64;
        double *xyz = realloc(b->xyz, 3 * cap * sizeof *xyz);
        if (xyz) b->xyz = xyz;
        double *c = realloc(b->cur, cap * sizeof *c);
        if (c) b->cur = c;
        double *p = realloc(b->phi, cap * sizeof *p);
        if (p) b->phi = p;
        double *a = realloc(b->arc, cap * sizeof *a);
        if (a) b->arc = a;
        int32_t *t = realloc(b->tet, cap * sizeof *t);
        if (t) b->tet = t;
        if (!xyz || !c || !p || !a || !t) return 0;
        b->cap = cap;
    }
    memcpy(b->xyz + 3 * b->n, x, 3 * sizeof *x);
    b->cur[b->n] = cur;
    b->phi[b->n] = phi;
    b->arc[b->n] = arc;
    b->tet[b->n] = (int32_t)tet;
    b->n++;
    return 1;
}

void thx_stream_piece_free(line_buf *b)
{
    free(b->xyz), free(b->cur), free(b->phi), free(b->arc), free(b->tet);
    memset(b, 0, sizeof *b);
}

/* The unit direction sign J/|J| at p (walking from hint): 0 and *tet, 1 outside the domain, 2 |J| = 0,
 * 3 beyond a part's edge (perhaps inside the domain: the part cannot tell). */
static int direction(const thx_stream_field *f, const double p[3], long hint, double sign, double k[3], long *tet,
                     size_t *evals)
{
    double J[3];
    (*evals)++;
    long t = thx_stream_field_eval(f, p, hint, J, NULL);
    if (t < 0) return t == -2 ? 3 : 1;
    double m = sqrt(J[0] * J[0] + J[1] * J[1] + J[2] * J[2]);
    if (!(m > 0)) return 2;
    for (int c = 0; c < 3; c++) k[c] = sign * J[c] / m;
    *tet = t;
    return 0;
}

static double dist_point_segment(const double p[3], const double a[3], const double b[3])
{
    double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, ap[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    double l2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
    double u = l2 > 0 ? (ab[0] * ap[0] + ab[1] * ap[1] + ab[2] * ap[2]) / l2 : 0;
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    double d[3] = {ap[0] - u * ab[0], ap[1] - u * ab[1], ap[2] - u * ab[2]};
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* Dormand-Prince 5(4): the stages' nodes' coefficients, the 5th-order weights (= row 7, FSAL) and the
 * difference between the 5th- and 4th-order weights (the error estimate). */
static const double DP_A[7][6] = {
    {0, 0, 0, 0, 0, 0},
    {1.0 / 5, 0, 0, 0, 0, 0},
    {3.0 / 40, 9.0 / 40, 0, 0, 0, 0},
    {44.0 / 45, -56.0 / 15, 32.0 / 9, 0, 0, 0},
    {19372.0 / 6561, -25360.0 / 2187, 64448.0 / 6561, -212.0 / 729, 0, 0},
    {9017.0 / 3168, -355.0 / 33, 46732.0 / 5247, 49.0 / 176, -5103.0 / 18656, 0},
    {35.0 / 384, 0, 500.0 / 1113, 125.0 / 192, -2187.0 / 6784, 11.0 / 84}};
static const double DP_E[7] = {71.0 / 57600, 0, -71.0 / 16695, 71.0 / 1920, -17253.0 / 339200, 22.0 / 525, -1.0 / 40};

int thx_stream_start(const thx_stream_field *f, const thx_stream_opts *o, const double x0[3], long t0, double sign,
                     thx_stream_state *s, line_buf *b, int *nomem)
{
    double J[3], phi;
    memset(s, 0, sizeof *s);
    memcpy(s->x0, x0, sizeof s->x0);
    memcpy(s->x, x0, sizeof s->x);
    s->t = s->t0 = t0;
    s->sign = sign > 0 ? 1 : -1;
    thx_stream_interp(f, (size_t)t0, x0, J, &phi);
    double jm = sqrt(J[0] * J[0] + J[1] * J[1] + J[2] * J[2]), jmin = o->min_current * f->jmax;
    s->j0 = jm;
    s->phi0 = phi;
    b->dir = s->sign;
    b->length = 0;
    if (!push(b, x0, jm, phi, 0, t0)) {
        *nomem = 1;
        return b->stop = THX_STOP_LOW_CURRENT; /* (the line is given up: out of memory) */
    }
    if (!(jm > 0) || jm < jmin) return b->stop = THX_STOP_LOW_CURRENT;
    for (int c = 0; c < 3; c++) s->k1[c] = sign * J[c] / jm;
    memcpy(s->k_start, s->k1, sizeof s->k1);
    s->loop_tol = o->loop_tol * thx_stream_cell_size(f->v, (size_t)t0);
    s->h = o->step_mm > 0 ? o->step_mm : o->step * thx_stream_cell_size(f->v, (size_t)t0);
    return THX_STREAM_GOING;
}

/*
 * A line's steps from the state s; the stop rules of the header. On a part, the line is handed over
 * after a step whose point is in a tetrahedron owned elsewhere, with the state that step left.
 */
int thx_stream_run(const thx_stream_field *f, const thx_stream_opts *o, thx_stream_state *ls, line_buf *b,
                   size_t *n_steps, size_t *n_evals, int *nomem)
{
    double *x = ls->x, *k1 = ls->k1, J[3], phi, jm;
    const double *x0 = ls->x0, *k_start = ls->k_start, sign = ls->sign;
    double jmin = o->min_current * f->jmax, maxlen = o->max_length > 0 ? o->max_length : 4 * f->diag;
    double loop_tol = ls->loop_tol, len = ls->len, h = ls->h;
    long t = (long)ls->t, t0 = (long)ls->t0;
    int away = ls->away, fixed = o->integrator != THX_STREAM_RK45;
    b->dir = ls->sign;
    for (size_t step = (size_t)ls->step;; step++) {
        if (step >= o->max_steps) {
            b->stop = THX_STOP_MAX_STEPS;
            break;
        }
        double hc = thx_stream_cell_size(f->v, (size_t)t);
        if (fixed) h = o->step_mm > 0 ? o->step_mm : o->step * hc;
        else h = fmin(fmax(h, o->min_step * hc), o->max_step * hc);
        double xn[3], kn[3], h_next = h;
        long tn = -1;
        int last = 0, ok = 0, zero = 0, to_exit = 0;
        for (int attempt = 0; attempt < 64 && !ok; attempt++) {
            last = 0;
            if (len + h >= maxlen) h = maxlen - len, last = 1;
            double K[7][3], p[3];
            long ts = t;
            int r = 0;
            memcpy(K[0], k1, sizeof K[0]);
            if (o->integrator == THX_STREAM_RK2) {
                for (int c = 0; c < 3; c++) p[c] = x[c] + 0.5 * h * K[0][c];
                r = direction(f, p, ts, sign, K[1], &ts, n_evals);
                if (!r)
                    for (int c = 0; c < 3; c++) xn[c] = x[c] + h * K[1][c];
            } else if (o->integrator == THX_STREAM_RK4) {
                static const double cs[3] = {0.5, 0.5, 1.0};
                for (int s = 1; s <= 3 && !r; s++) {
                    for (int c = 0; c < 3; c++) p[c] = x[c] + cs[s - 1] * h * K[s - 1][c];
                    r = direction(f, p, ts, sign, K[s], &ts, n_evals);
                }
                if (!r)
                    for (int c = 0; c < 3; c++) xn[c] = x[c] + h / 6 * (K[0][c] + 2 * K[1][c] + 2 * K[2][c] + K[3][c]);
            } else {
                for (int s = 1; s <= 6 && !r; s++) {
                    for (int c = 0; c < 3; c++) {
                        double a = 0;
                        for (int m = 0; m < s; m++) a += DP_A[s][m] * K[m][c];
                        p[c] = x[c] + h * a;
                    }
                    if (s == 6) memcpy(xn, p, sizeof p);
                    r = direction(f, p, ts, sign, K[s], &ts, n_evals);
                }
                if (!r) {
                    double e[3] = {0, 0, 0};
                    for (int s = 0; s < 7; s++)
                        for (int c = 0; c < 3; c++) e[c] += h * DP_E[s] * K[s][c];
                    double err = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]), tol = o->tolerance * hc;
                    double fac = err > 0 ? 0.9 * pow(tol / err, 0.2) : 5.0;
                    if (err > tol && h > o->min_step * hc * 1.0000001) {
                        h = fmax(h * fmax(0.2, fac), o->min_step * hc);
                        continue; /* rejected: again with the smaller step */
                    }
                    h_next = h * fmin(5.0, fmax(0.2, fac));
                }
            }
            int unsure = r == 3; /* a stage the part cannot place: the exit walk below may tell */
            if (r == 3) r = 1;
            if (r == 2) {
                zero = 1;
                break;
            }
            if (!r && o->integrator != THX_STREAM_RK45) {
                r = direction(f, xn, ts, sign, kn, &tn, n_evals);
                if (r == 3) unsure = 1, r = 1;
                if (r == 2) {
                    zero = 1;
                    break;
                }
            } else if (!r) {
                memcpy(kn, K[6], sizeof kn);
                tn = ts;
            }
            if (!r) {
                ok = 1;
                break;
            }
            /* A stage or the end outside the domain: is the boundary within this step, straight ahead? Then
             * the step again with exactly that length (the curve may still bend out first: halved then); a
             * point within a thousandth of the cell of the boundary goes straight to it and the line ends. */
            long te = t;
            int unknown = 0;
            double se = thx_stream_exit(f, (size_t)t, x, k1, h, &te, &unknown);
            /* on a part: the straight path reaching the part's edge, or a stage the part could not place with
               no edge of the domain ahead, is the whole's to tell (the one process's step may go on there) */
            if (unknown || (unsure && !(se < h))) return THX_STREAM_UNSURE;
            if (se < h && se > 1e-3 * hc && !to_exit) {
                h = se;
                h_next = h;
                to_exit = 1;
                continue;
            }
            if (se < h) {
                for (int c = 0; c < 3; c++) xn[c] = x[c] + se * k1[c];
                thx_stream_interp(f, (size_t)te, xn, J, &phi);
                len += se;
                if (!push(b, xn, sqrt(J[0] * J[0] + J[1] * J[1] + J[2] * J[2]), phi, len, te)) *nomem = 1;
                (*n_steps)++;
                b->stop = THX_STOP_BOUNDARY;
                b->length = len;
                return b->stop;
            }
            h *= 0.5; /* the curve bends out before the straight path does: a shorter step */
            h_next = h;
        }
        if (zero) {
            b->stop = THX_STOP_LOW_CURRENT;
            break;
        }
        if (!ok) {
            b->stop = THX_STOP_BOUNDARY; /* no step stays inside: on the boundary already */
            break;
        }
        (*n_steps)++;
        thx_stream_interp(f, (size_t)tn, xn, J, &phi);
        jm = sqrt(J[0] * J[0] + J[1] * J[1] + J[2] * J[2]);
        len += h;
        /* a closed loop: back within loop_tol of the seed, going the same way, after going away */
        if (o->loops && !away) {
            double d[3] = {xn[0] - x0[0], xn[1] - x0[1], xn[2] - x0[2]};
            away = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) > 2 * loop_tol;
        } else if (o->loops && dist_point_segment(x0, x, xn) < loop_tol &&
                   (xn[0] - x[0]) * k_start[0] + (xn[1] - x[1]) * k_start[1] + (xn[2] - x[2]) * k_start[2] > 0) {
            double dx[3] = {x0[0] - x[0], x0[1] - x[1], x0[2] - x[2]};
            len += sqrt(dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2]) - h;
            if (!push(b, x0, ls->j0, ls->phi0, len, t0)) *nomem = 1;
            b->stop = THX_STOP_LOOP;
            break;
        }
        if (!push(b, xn, jm, phi, len, tn)) {
            *nomem = 1;
            break;
        }
        if (jm < jmin) {
            b->stop = THX_STOP_LOW_CURRENT;
            break;
        }
        if (last) {
            b->stop = THX_STOP_MAX_LENGTH;
            break;
        }
        memcpy(x, xn, 3 * sizeof *x);
        memcpy(k1, kn, sizeof kn);
        t = tn;
        h = h_next;
        if (f->own && !f->own[t]) { /* into another part's tetrahedron: its owner goes on */
            ls->t = t, ls->h = h, ls->len = len, ls->away = away, ls->step = (int64_t)step + 1;
            return THX_STREAM_HANDOVER;
        }
    }
    b->length = len;
    return b->stop;
}

/* One line from x0 (in tetrahedron t0) in direction sign; the first point is the seed. */
static void trace_one(const thx_stream_field *f, const thx_stream_opts *o, const double x0[3], long t0, double sign,
                      line_buf *b, size_t *n_steps, size_t *n_evals, int *nomem)
{
    thx_stream_state s;
    if (thx_stream_start(f, o, x0, t0, sign, &s, b, nomem) == THX_STREAM_GOING)
        thx_stream_run(f, o, &s, b, n_steps, n_evals, nomem);
}

void thx_streamlines_destroy(thx_streamlines **s)
{
    if (!s || !*s) return;
    thx_streamlines *l = *s;
    free(l->first), free(l->xyz), free(l->current), free(l->potential), free(l->arc), free(l->tet);
    free(l->seed), free(l->direction), free(l->stop), free(l->length);
    free(l);
    *s = NULL;
}

thx_status thx_streamlines_trace(thx_ctx *ctx, const thx_stream_field *f, const double *xyz, const long *tet,
                                 size_t n_seeds, const thx_stream_opts *o, thx_streamlines **out)
{
    *out = NULL;
    if (o->integrator < THX_STREAM_RK2 || o->integrator > THX_STREAM_RK45)
        return thx_error(ctx, THX_EINPUT, "streamlines: unknown integrator %d", o->integrator);
    if (!(o->direction >= 1 && o->direction <= 3))
        return thx_error(ctx, THX_EINPUT, "streamlines: unknown direction %d", o->direction);
    if (!(o->step > 0) || !(o->step_mm >= 0) || !(o->min_step > 0) || !(o->max_step >= o->min_step) || !(o->tolerance > 0) ||
        !(o->min_current >= 0) || !(o->max_length >= 0) || !(o->loop_tol > 0))
        return thx_error(ctx, THX_EINPUT, "streamlines: a step, tolerance or limit out of range");
    long *t0 = thx_malloc(ctx, (n_seeds + 1) * sizeof *t0);
    seed_out *so = thx_calloc(ctx, n_seeds + 1, sizeof *so);
    if (!t0 || !so) {
        free(t0), free(so);
        return THX_ENOMEM;
    }
    for (size_t i = 0; i < n_seeds; i++) {
        const double *p = xyz + 3 * i;
        t0[i] = tet ? tet[i] : thx_stream_field_eval(f, p, -1, NULL, NULL);
        if (t0[i] < 0 || (size_t)t0[i] >= f->v->n_tets || !f->active[t0[i]]) {
            free(t0), free(so);
            return thx_error(ctx, THX_EINPUT, "streamlines: seed %zu (%g, %g, %g) is outside the domain", i, p[0], p[1],
                             p[2]);
        }
    }
#pragma omp parallel for schedule(dynamic, 1)
    for (long i = 0; i < (long)n_seeds; i++) {
        seed_out *s = so + i;
        const double *p = xyz + 3 * i;
        if (o->direction & THX_STREAM_FORWARD)
            trace_one(f, o, p, t0[i], 1.0, &s->line[s->n_lines++], &s->steps, &s->evals, &s->nomem);
        if ((o->direction & THX_STREAM_BACKWARD) && !(s->n_lines && s->line[0].stop == THX_STOP_LOOP))
            trace_one(f, o, p, t0[i], -1.0, &s->line[s->n_lines++], &s->steps, &s->evals, &s->nomem);
    }
    free(t0);
    thx_status st = THX_OK;
    size_t nl = 0, np = 0;
    for (size_t i = 0; i < n_seeds; i++) {
        if (so[i].nomem) st = thx_error(ctx, THX_ENOMEM, "streamlines: out of memory tracing seed %zu", i);
        nl += (size_t)so[i].n_lines;
        for (int k = 0; k < so[i].n_lines; k++) np += so[i].line[k].n;
    }
    thx_streamlines *s = NULL;
    if (!st) {
        s = thx_calloc(ctx, 1, sizeof *s);
        if (!s) st = THX_ENOMEM;
    }
    if (!st) {
        s->first = thx_malloc(ctx, (nl + 1) * sizeof *s->first);
        s->xyz = thx_malloc(ctx, (3 * np + 1) * sizeof *s->xyz);
        s->current = thx_malloc(ctx, (np + 1) * sizeof *s->current);
        s->potential = thx_malloc(ctx, (np + 1) * sizeof *s->potential);
        s->arc = thx_malloc(ctx, (np + 1) * sizeof *s->arc);
        s->tet = thx_malloc(ctx, (np + 1) * sizeof *s->tet);
        s->seed = thx_malloc(ctx, (nl + 1) * sizeof *s->seed);
        s->direction = thx_malloc(ctx, nl + 1);
        s->stop = thx_malloc(ctx, nl + 1);
        s->length = thx_malloc(ctx, (nl + 1) * sizeof *s->length);
        if (!s->first || !s->xyz || !s->current || !s->potential || !s->arc || !s->tet || !s->seed || !s->direction ||
            !s->stop || !s->length)
            st = THX_ENOMEM;
    }
    if (!st) {
        size_t l = 0, q = 0;
        for (size_t i = 0; i < n_seeds; i++) {
            s->n_steps += so[i].steps;
            s->n_evals += so[i].evals;
            for (int k = 0; k < so[i].n_lines; k++, l++) {
                const line_buf *b = &so[i].line[k];
                s->first[l] = q;
                s->seed[l] = (int32_t)i;
                s->direction[l] = (int8_t)b->dir;
                s->stop[l] = (int8_t)b->stop;
                s->length[l] = b->length;
                memcpy(s->xyz + 3 * q, b->xyz, 3 * b->n * sizeof *s->xyz);
                memcpy(s->current + q, b->cur, b->n * sizeof *s->current);
                memcpy(s->potential + q, b->phi, b->n * sizeof *s->potential);
                memcpy(s->arc + q, b->arc, b->n * sizeof *s->arc);
                memcpy(s->tet + q, b->tet, b->n * sizeof *s->tet);
                q += b->n;
            }
        }
        s->first[nl] = q;
        s->n_lines = nl;
        s->n_points = np;
    }
    for (size_t i = 0; i < n_seeds; i++)
        for (int k = 0; k < so[i].n_lines; k++) thx_stream_piece_free(&so[i].line[k]);
    free(so);
    if (st) {
        thx_streamlines_destroy(&s);
        return st;
    }
    *out = s;
    return THX_OK;
}
