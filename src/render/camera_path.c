/*
 * The C2 camera path through key frames (thorax/render/camera_path.h).
 *
 * Knots. Keys at movie frames t_0 < ... < t_m (n = m + 1 keys) give the clamped cubic knot vector
 * U = (t_0, t_0, t_0, t_0, t_1, ..., t_{m-1}, t_m, t_m, t_m, t_m), nc = n + 2 B-spline basis
 * functions N_0..N_{nc-1} and nc control points; piece j (t_j <= t < t_{j+1}) is span s = j + 3,
 * where N_{s-3}..N_s are the ones not zero.
 *
 * Positions: P(t) = sum_i c_i N_i(t). The nc equations: P(t_j) = X_j at the n keys and one end
 * condition at each end (natural: P'' = 0; rest: P' = 0), ordered interp t_0, end t_0, interp
 * t_1..t_{m-1}, end t_m, interp t_m, so that the matrix is banded (two below and two above the
 * diagonal) and solved by Gaussian elimination with partial pivoting within the band. Closed ends
 * (P' and P'' the same at t_0 and t_m) couple the first and last controls: the band is then the
 * whole matrix (at most 100 keys).
 *
 * Orientation: Kim, Kim and Shin's cumulative form q(t) = q_0 prod_{i>=1} exp(w_i Bc_i(t)) with
 * w_i = log(q_{i-1}^-1 q_i) and Bc_i = sum_{k>=i} N_k, which on span s is
 * q_{s-3} exp(w_{s-2} Bc_{s-2}) exp(w_{s-1} Bc_{s-1}) exp(w_s Bc_s): unit, C2 because the basis is,
 * and with derivatives from the product rule (d/dt exp(w B) = exp(w B) w B'). The control
 * quaternions solve the nonlinear counterpart of the position system (the key orientations at the
 * keys, zero angular acceleration or velocity at the ends, or the same at both) by Newton's method,
 * its banded Jacobian by central differences in each control's tangent space, started from the
 * spline of the keys' rotation vectors (exact when all the turns share one axis). The turns w_i are
 * kept continuous past half a turn (qlog_near): uneven keys need controls more than 180 degrees
 * apart, where the principal logarithm would jump.
 */
#include "thorax/render/camera_path.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NV 8 /* position values per control: eye 3, target 3, fov, height */

struct thx_camera_path {
    int n, nc;              /* keys, controls */
    double *t;              /* n key frames */
    double *U;              /* nc + 4 knots */
    double (*c)[NV];        /* position controls */
    double (*q)[4];         /* orientation controls */
    double (*w)[3];         /* the turns between them: w[i] from q[i-1] to q[i] (w[0] unused) */
    int *data_t, *data_v;   /* the keys that give a data frame: movie frame, data frame */
    int n_data;
    thx_camera_look look;
    int ortho;
};

/* ---- quaternions (w, x, y, z); rotation vectors of full angle: exp(v) = (cos |v|/2, sin |v|/2 v/|v|) ---- */

static void qmul(const double a[4], const double b[4], double o[4])
{
    double r[4] = {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
                   a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
                   a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
                   a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
    memcpy(o, r, sizeof r);
}

static void qconj(const double a[4], double o[4]) { o[0] = a[0], o[1] = -a[1], o[2] = -a[2], o[3] = -a[3]; }

static void qexp(const double v[3], double o[4])
{
    double th = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]), h = 0.5 * th;
    double s = th > 1e-8 ? sin(h) / th : 0.5 - th * th / 48; /* sin(th/2)/th */
    o[0] = cos(h), o[1] = s * v[0], o[2] = s * v[1], o[3] = s * v[2];
}

/* The rotation vector of a unit quaternion, the shorter way round (angle <= pi). */
static void qlog(const double q[4], double v[3])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    if (w < 0) w = -w, x = -x, y = -y, z = -z;
    double sn = sqrt(x * x + y * y + z * z), th = 2 * atan2(sn, w);
    double f = sn > 1e-12 ? th / sn : 2 / (w > 0 ? w : 1);
    v[0] = f * x, v[1] = f * y, v[2] = f * z;
}

static void qnormalize(double q[4])
{
    double l = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int k = 0; k < 4; k++) q[k] /= l;
}

/* The columns of q's rotation: e = 0 right, 1 up, 2 back. */
static void qaxis(const double q[4], int e, double o[3])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    if (e == 0) o[0] = 1 - 2 * (y * y + z * z), o[1] = 2 * (x * y + w * z), o[2] = 2 * (x * z - w * y);
    else if (e == 1) o[0] = 2 * (x * y - w * z), o[1] = 1 - 2 * (x * x + z * z), o[2] = 2 * (y * z + w * x);
    else o[0] = 2 * (x * z + w * y), o[1] = 2 * (y * z - w * x), o[2] = 1 - 2 * (x * x + y * y);
}

int thx_camera_quaternion(const thx_camera *cam, double q[4])
{
    double b[3], r[3], u[3], lb = 0, lr = 0, lu = 0;
    for (int k = 0; k < 3; k++) b[k] = cam->eye[k] - cam->center[k], lb += b[k] * b[k], lu += cam->up[k] * cam->up[k];
    lb = sqrt(lb), lu = sqrt(lu);
    if (!(lb > 0) || !isfinite(lb) || !(lu > 0) || !isfinite(lu)) return -1;
    for (int k = 0; k < 3; k++) b[k] /= lb;
    const double *up = cam->up;
    r[0] = up[1] * b[2] - up[2] * b[1], r[1] = up[2] * b[0] - up[0] * b[2], r[2] = up[0] * b[1] - up[1] * b[0];
    lr = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    if (!(lr > 1e-9 * lu)) return -1;
    for (int k = 0; k < 3; k++) r[k] /= lr;
    u[0] = b[1] * r[2] - b[2] * r[1], u[1] = b[2] * r[0] - b[0] * r[2], u[2] = b[0] * r[1] - b[1] * r[0];
    /* M = [r u b] (columns) to a quaternion, Shepperd's way (the largest of w, x, y, z first) */
    double m00 = r[0], m11 = u[1], m22 = b[2], tr = m00 + m11 + m22;
    if (tr >= m00 && tr >= m11 && tr >= m22) {
        double s = 2 * sqrt(1 + tr);
        q[0] = s / 4, q[1] = (u[2] - b[1]) / s, q[2] = (b[0] - r[2]) / s, q[3] = (r[1] - u[0]) / s;
    } else if (m00 >= m11 && m00 >= m22) {
        double s = 2 * sqrt(1 + m00 - m11 - m22);
        q[0] = (u[2] - b[1]) / s, q[1] = s / 4, q[2] = (u[0] + r[1]) / s, q[3] = (b[0] + r[2]) / s;
    } else if (m11 >= m22) {
        double s = 2 * sqrt(1 + m11 - m00 - m22);
        q[0] = (b[0] - r[2]) / s, q[1] = (u[0] + r[1]) / s, q[2] = s / 4, q[3] = (b[1] + u[2]) / s;
    } else {
        double s = 2 * sqrt(1 + m22 - m00 - m11);
        q[0] = (r[1] - u[0]) / s, q[1] = (b[0] + r[2]) / s, q[2] = (b[1] + u[2]) / s, q[3] = s / 4;
    }
    if (q[0] < 0) for (int k = 0; k < 4; k++) q[k] = -q[k];
    qnormalize(q);
    return 0;
}

/* ---- banded linear systems: kl below and ku above the diagonal, partial pivoting ---- */

typedef struct {
    int n, kl, ku, w;
    double *a; /* row i holds columns i - kl .. i + kl + ku (room for the pivoting's fill) */
} band;

static double *bat(band *b, int i, int j) { return &b->a[(size_t)i * b->w + (j - i + b->kl)]; }

static int band_init(band *b, int n, int kl, int ku)
{
    b->n = n, b->kl = kl, b->ku = ku, b->w = 2 * kl + ku + 1;
    b->a = calloc((size_t)n * b->w, sizeof *b->a);
    return b->a ? 0 : -1;
}

/* Solves A X = B in place for nrhs right-hand sides (B row-major, n x nrhs); -1 if singular. */
static int band_solve(band *b, double *B, int nrhs)
{
    int n = b->n, kl = b->kl, ku = b->ku;
    double amax = 0;
    for (size_t k = 0; k < (size_t)n * b->w; k++) amax = fmax(amax, fabs(b->a[k]));
    for (int k = 0; k < n; k++) {
        int last = k + kl < n - 1 ? k + kl : n - 1, lastc = k + kl + ku < n - 1 ? k + kl + ku : n - 1, p = k;
        for (int r = k + 1; r <= last; r++)
            if (fabs(*bat(b, r, k)) > fabs(*bat(b, p, k))) p = r;
        if (!(fabs(*bat(b, p, k)) > 1e-14 * amax)) return -1;
        if (p != k) {
            for (int c = k; c <= lastc; c++) {
                double t = *bat(b, k, c);
                *bat(b, k, c) = *bat(b, p, c), *bat(b, p, c) = t;
            }
            for (int r = 0; r < nrhs; r++) {
                double t = B[(size_t)k * nrhs + r];
                B[(size_t)k * nrhs + r] = B[(size_t)p * nrhs + r], B[(size_t)p * nrhs + r] = t;
            }
        }
        double piv = *bat(b, k, k);
        for (int r = k + 1; r <= last; r++) {
            double f = *bat(b, r, k) / piv;
            if (f == 0) continue;
            for (int c = k; c <= lastc; c++) *bat(b, r, c) -= f * *bat(b, k, c);
            for (int q = 0; q < nrhs; q++) B[(size_t)r * nrhs + q] -= f * B[(size_t)k * nrhs + q];
        }
    }
    for (int k = n - 1; k >= 0; k--) {
        int lastc = k + kl + ku < n - 1 ? k + kl + ku : n - 1;
        for (int q = 0; q < nrhs; q++) {
            double s = B[(size_t)k * nrhs + q];
            for (int c = k + 1; c <= lastc; c++) s -= *bat(b, k, c) * B[(size_t)c * nrhs + q];
            B[(size_t)k * nrhs + q] = s / *bat(b, k, k);
        }
    }
    return 0;
}

/* ---- the cubic B-spline basis ---- */

/* The span of t: piece j of the keys, s = j + 3; side < 0 takes the piece ending at a key's frame. */
static int span_of(const thx_camera_path *p, double t, int side)
{
    int m = p->n - 1, lo = 0, hi = m - 1;
    while (lo < hi) { /* the last piece j with t_j <= t (side >= 0) or t_j < t (side < 0) */
        int mid = (lo + hi + 1) / 2;
        if (side < 0 ? p->t[mid] < t : p->t[mid] <= t) lo = mid;
        else hi = mid - 1;
    }
    return lo + 3;
}

/* d[r][a]: the r-th derivative (r = 0..3) of N_{s-3+a} (a = 0..3) at t, on span s's polynomial. */
static void basis(const double *U, int s, double t, double d[4][4])
{
    double D[4][4][5]; /* [derivative][degree][a], a = 4 the zero N_{s+1} */
    memset(D, 0, sizeof D);
    D[0][0][3] = 1;
    for (int k = 1; k <= 3; k++)
        for (int a = 0; a < 4; a++) {
            int i = s - 3 + a;
            double d1 = U[i + k] - U[i], d2 = U[i + k + 1] - U[i + 1];
            double v = 0;
            if (d1 > 0) v += (t - U[i]) / d1 * D[0][k - 1][a];
            if (d2 > 0) v += (U[i + k + 1] - t) / d2 * D[0][k - 1][a + 1];
            D[0][k][a] = v;
            for (int r = 1; r <= k; r++) {
                double g = 0;
                if (d1 > 0) g += D[r - 1][k - 1][a] / d1;
                if (d2 > 0) g -= D[r - 1][k - 1][a + 1] / d2;
                D[r][k][a] = k * g;
            }
        }
    for (int r = 0; r < 4; r++)
        for (int a = 0; a < 4; a++) d[r][a] = D[r][3][a];
}

/* ---- the orientation curve ---- */

/* The rotation vector of q nearest ref among those of the same rotation (v + 2 pi k v/|v|): the
 * turn between successive controls followed continuously past half a turn. */
static void qlog_near(const double q[4], const double ref[3], double v[3])
{
    qlog(q, v);
    double th = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]), a[3];
    double lr = sqrt(ref[0] * ref[0] + ref[1] * ref[1] + ref[2] * ref[2]);
    if (th > 1e-9) for (int e = 0; e < 3; e++) a[e] = v[e] / th;
    else if (lr > 1e-9) for (int e = 0; e < 3; e++) a[e] = ref[e] / lr;
    else return;
    double best = INFINITY, out[3] = {v[0], v[1], v[2]};
    for (int kk = -2; kk <= 2; kk++) {
        double c[3], d = 0;
        for (int e = 0; e < 3; e++) c[e] = v[e] + 2 * M_PI * kk * a[e], d += (c[e] - ref[e]) * (c[e] - ref[e]);
        if (d < best) best = d, memcpy(out, c, sizeof out);
    }
    memcpy(v, out, sizeof out);
}

/* q(t) and its first two derivatives on span s, from the controls Q and the turns W between them
 * (W[i] the rotation vector from Q[i-1] to Q[i]). */
static void qcurve(const thx_camera_path *p, const double (*Q)[4], const double (*W)[3], int s, double t,
                   double out[3][4])
{
    double d[4][4], E[3][3][4]; /* E[k][order]: exp(w_k B_k) and its derivatives */
    basis(p->U, s, t, d);
    for (int k = 0; k < 3; k++) {
        int i = s - 2 + k; /* controls s-2, s-1, s */
        double Bc[3] = {0, 0, 0};
        for (int r = 0; r < 3; r++)
            for (int a = k + 1; a < 4; a++) Bc[r] += d[r][a];
        const double *w = W[i];
        double h[4], e[4], wv[3];
        for (int c = 0; c < 3; c++) wv[c] = w[c] * Bc[0];
        qexp(wv, e);
        h[0] = 0, h[1] = 0.5 * w[0], h[2] = 0.5 * w[1], h[3] = 0.5 * w[2]; /* d/dt exp(w B) = exp(w B) (w/2) B' */
        double hh = -(h[1] * h[1] + h[2] * h[2] + h[3] * h[3]);           /* (w/2)^2, a real number */
        double d1[4] = {0, h[1] * Bc[1], h[2] * Bc[1], h[3] * Bc[1]};
        double d2[4] = {hh * Bc[1] * Bc[1], h[1] * Bc[2], h[2] * Bc[2], h[3] * Bc[2]};
        memcpy(E[k][0], e, sizeof e);
        qmul(e, d1, E[k][1]);
        qmul(e, d2, E[k][2]);
    }
    /* q = Q_{s-3} E0 E1 E2; the product rule for the first and second derivatives */
    memset(out, 0, 3 * sizeof out[0]);
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
            for (int c = 0; c < 3; c++) {
                int order = a + b + c;
                if (order > 2) continue;
                double coef = order == 2 && a != 2 && b != 2 && c != 2 ? 2 : 1; /* 2!/(a! b! c!) */
                double m[4];
                qmul(E[0][a], E[1][b], m);
                qmul(m, E[2][c], m);
                qmul(Q[s - 3], m, m);
                for (int k = 0; k < 4; k++) out[order][k] += coef * m[k];
            }
}

/* ---- residuals of the orientation system ---- */

/* Block b's residual (3 values): 0 the first key, 1 the first end's condition, 2..nc-3 keys
 * 1..n-2, nc-2 the last end's condition, nc-1 the last key. Kq: the keys' quaternions. */
static void residual(const thx_camera_path *p, const double (*Q)[4], const double (*W)[3], const double (*Kq)[4],
                     thx_camera_ends ends, int b, double r[3])
{
    int nc = p->nc, m = p->n - 1;
    if (b == 1 || b == nc - 2) {
        /* body angular velocity (w1) and acceleration (w2 - w1^2), halves, at each end */
        double om[2][2][3], dt0 = p->t[1] - p->t[0], dt1 = p->t[m] - p->t[m - 1];
        for (int end = 0; end < 2; end++) {
            if (ends != THX_CAMERA_ENDS_CLOSED && end != (b == 1 ? 0 : 1)) continue;
            double qd[3][4], qi[4], w1[4], w2[4], ww[4];
            qcurve(p, Q, W, end == 0 ? 3 : nc - 1, end == 0 ? p->t[0] : p->t[m], qd);
            qconj(qd[0], qi);
            qmul(qi, qd[1], w1);
            qmul(qi, qd[2], w2);
            qmul(w1, w1, ww);
            for (int k = 0; k < 3; k++) om[end][0][k] = 2 * w1[k + 1], om[end][1][k] = 2 * (w2[k + 1] - ww[k + 1]);
        }
        double dt = b == 1 ? dt0 : dt1;
        for (int k = 0; k < 3; k++) {
            if (ends == THX_CAMERA_ENDS_CLOSED) /* the same turning at both ends: velocity, then acceleration */
                r[k] = b == 1 ? (om[0][0][k] - om[1][0][k]) * 0.5 * (dt0 + dt1)
                              : (om[0][1][k] - om[1][1][k]) * 0.25 * (dt0 + dt1) * (dt0 + dt1);
            else if (ends == THX_CAMERA_ENDS_REST) r[k] = om[b == 1 ? 0 : 1][0][k] * dt;
            else r[k] = om[b == 1 ? 0 : 1][1][k] * dt * dt;
        }
        return;
    }
    int j = b == 0 ? 0 : b == nc - 1 ? m : b - 1;
    double qd[3][4], qi[4];
    qcurve(p, Q, W, j < m ? j + 3 : nc - 1, p->t[j], qd);
    qconj(Kq[j], qi);
    qmul(qi, qd[0], qi);
    qlog(qi, r);
}

static double residual_all(const thx_camera_path *p, const double (*Q)[4], const double (*W)[3], const double (*Kq)[4],
                           thx_camera_ends ends, double *R)
{
    double ss = 0; /* the 2-norm, which a Newton step decreases */
    for (int b = 0; b < p->nc; b++) {
        residual(p, Q, W, Kq, ends, b, R + 3 * b);
        for (int k = 0; k < 3; k++) ss += R[3 * b + k] * R[3 * b + k];
    }
    return isfinite(ss) ? sqrt(ss) : INFINITY;
}

static void qstep(const double q[4], const double v[3], double o[4])
{
    double e[4];
    qexp(v, e);
    qmul(q, e, o);
    qnormalize(o);
}

/* W[i] (i = lo..hi, 1 <= i < nc) from the controls, each on the branch nearest its old value. */
static void turns(int nc, const double (*Q)[4], double (*W)[3], int lo, int hi)
{
    for (int i = lo < 1 ? 1 : lo; i <= hi && i < nc; i++) {
        double qi[4], old[3];
        memcpy(old, W[i], sizeof old);
        qconj(Q[i - 1], qi);
        qmul(qi, Q[i], qi);
        qlog_near(qi, old, W[i]);
    }
}

/* Newton's method for the orientation controls (p->q, p->w); 0, or -1 when it does not converge. */
static int solve_orientation(thx_camera_path *p, const double (*Kq)[4], thx_camera_ends ends, double *resid)
{
    int nc = p->nc, N = 3 * nc, rc = -1;
    double *R = malloc(sizeof(double) * N), Rp[3], Rm[3];
    double *dx = malloc(sizeof(double) * N), (*Qt)[4] = malloc(sizeof(double[4]) * nc);
    double (*Wt)[3] = malloc(sizeof(double[3]) * nc);
    band J = {0};
    int closed = ends == THX_CAMERA_ENDS_CLOSED, bw = closed ? N - 1 : 8;
    if (!R || !dx || !Qt || !Wt || band_init(&J, N, bw, bw)) goto done;
    double norm = residual_all(p, (const double(*)[4])p->q, (const double(*)[3])p->w, Kq, ends, R);
    for (int it = 0; it < 100 && norm > 1e-14; it++) {
        memset(J.a, 0, sizeof(double) * (size_t)N * J.w);
        const double h = 1e-6;
        for (int c = 0; c < nc; c++)
            for (int e = 0; e < 3; e++) {
                double save[4], ws[2][3], v[3] = {0, 0, 0};
                memcpy(save, p->q[c], sizeof save);
                memcpy(ws[0], p->w[c], sizeof ws[0]);
                if (c + 1 < nc) memcpy(ws[1], p->w[c + 1], sizeof ws[1]);
                for (int sgn = -1; sgn <= 1; sgn += 2) {
                    v[e] = sgn * h;
                    qstep(save, v, p->q[c]);
                    turns(nc, (const double(*)[4])p->q, p->w, c, c + 1);
                    for (int b = closed ? 0 : c - 2; b <= (closed ? nc - 1 : c + 2); b++)
                        if (b >= 0 && b < nc && (!closed || (b >= c - 2 && b <= c + 2) || b == 1 || b == nc - 2)) {
                            residual(p, (const double(*)[4])p->q, (const double(*)[3])p->w, Kq, ends, b, sgn < 0 ? Rm : Rp);
                            if (sgn > 0)
                                for (int k = 0; k < 3; k++) *bat(&J, 3 * b + k, 3 * c + e) += Rp[k] / (2 * h);
                            else
                                for (int k = 0; k < 3; k++) *bat(&J, 3 * b + k, 3 * c + e) -= Rm[k] / (2 * h);
                        }
                    memcpy(p->w[c], ws[0], sizeof ws[0]);
                    if (c + 1 < nc) memcpy(p->w[c + 1], ws[1], sizeof ws[1]);
                }
                memcpy(p->q[c], save, sizeof save);
            }
        for (int k = 0; k < N; k++) dx[k] = -R[k];
        if (band_solve(&J, dx, 1)) goto done;
        /* a damped step: halved until the residual falls */
        double lam = 1, nn = INFINITY;
        for (int ls = 0; ls < 40; ls++, lam *= 0.5) {
            for (int c = 0; c < nc; c++) {
                double v[3] = {lam * dx[3 * c], lam * dx[3 * c + 1], lam * dx[3 * c + 2]};
                qstep(p->q[c], v, Qt[c]);
            }
            memcpy(Wt, p->w, sizeof(double[3]) * nc);
            turns(nc, (const double(*)[4])Qt, Wt, 1, nc - 1);
            nn = residual_all(p, (const double(*)[4])Qt, (const double(*)[3])Wt, Kq, ends, R);
            if (nn < norm) break;
        }
        if (!(nn < norm)) break;
        memcpy(p->q, Qt, sizeof(double[4]) * nc);
        memcpy(p->w, Wt, sizeof(double[3]) * nc);
        norm = nn;
    }
    /* the controls' signs made to follow the turns, so the pieces join as quaternions, not only as rotations */
    for (int i = 1; i < nc; i++) qstep(p->q[i - 1], p->w[i], p->q[i]);
    residual_all(p, (const double(*)[4])p->q, (const double(*)[3])p->w, Kq, ends, R);
    /* converged when every key (and end condition) is met to 1e-12 rad: the largest block's
       residual, not the 2-norm over all of them, which grows as the square root of the number of
       keys (a smooth 10,000-key flight stopped at 2e-12 rad and was refused) */
    double worst = 0;
    for (int b = 0; b < nc; b++)
        worst = fmax(worst, sqrt(R[3 * b] * R[3 * b] + R[3 * b + 1] * R[3 * b + 1] + R[3 * b + 2] * R[3 * b + 2]));
    *resid = isfinite(worst) ? worst : INFINITY;
    rc = worst < 1e-12 ? 0 : -1;
done:
    free(R), free(dx), free(Qt), free(Wt), free(J.a);
    return rc;
}

/* ---- the path ---- */

/* The equations of the position system (row order as the orientation's blocks) into b. */
static void position_matrix(const thx_camera_path *p, thx_camera_ends ends, band *B)
{
    int nc = p->nc, m = p->n - 1;
    double d[4][4];
    for (int row = 0; row < nc; row++) {
        if (row == 1 || row == nc - 2) {
            int first = row == 1, s = first ? 3 : nc - 1;
            if (ends == THX_CAMERA_ENDS_CLOSED) { /* P' (row 1) and P'' (row nc-2) the same at both ends */
                basis(p->U, 3, p->t[0], d);
                for (int a = 0; a < 4; a++) *bat(B, row, a) += d[first ? 1 : 2][a];
                basis(p->U, nc - 1, p->t[m], d);
                for (int a = 0; a < 4; a++) *bat(B, row, nc - 4 + a) -= d[first ? 1 : 2][a];
                continue;
            }
            basis(p->U, s, first ? p->t[0] : p->t[m], d);
            for (int a = 0; a < 4; a++) *bat(B, row, s - 3 + a) += d[ends == THX_CAMERA_ENDS_REST ? 1 : 2][a];
            continue;
        }
        int j = row == 0 ? 0 : row == nc - 1 ? m : row - 1, s = j < m ? j + 3 : nc - 1;
        basis(p->U, s, p->t[j], d);
        for (int a = 0; a < 4; a++)
            if (d[0][a] != 0) *bat(B, row, s - 3 + a) += d[0][a];
    }
}

thx_status thx_camera_path_create(thx_ctx *ctx, const thx_camera_keys *k, thx_camera_path **out)
{
    *out = NULL;
    const char *path = k->path ? k->path : "camera keys";
    if (k->n < 2) return thx_error(ctx, THX_EINPUT, "%s: %zu key%s: a camera path needs at least 2", path, k->n, k->n == 1 ? "" : "s");
    if (k->n > 100000) return thx_error(ctx, THX_EINPUT, "%s: %zu keys: at most 100000", path, k->n);
    if (k->ends == THX_CAMERA_ENDS_CLOSED && k->n > 100)
        return thx_error(ctx, THX_EINPUT, "%s: ends closed: %zu keys, at most 100 for a closed flight", path, k->n);
    if (k->ends == THX_CAMERA_ENDS_CLOSED && k->n < 3)
        return thx_error(ctx, THX_EINPUT, "%s: ends closed: a closed flight needs at least 3 keys (the last repeating the first)", path);
    thx_camera_path *p = calloc(1, sizeof *p);
    if (!p) return thx_error(ctx, THX_ENOMEM, "camera path: out of memory");
    int n = (int)k->n, nc = n + 2, m = n - 1;
    p->n = n, p->nc = nc, p->look = k->look, p->ortho = !(k->keys[0].cam.fov_deg > 0);
    p->t = malloc(sizeof(double) * n);
    p->U = malloc(sizeof(double) * (nc + 4));
    p->c = malloc(sizeof(double[NV]) * nc);
    p->q = malloc(sizeof(double[4]) * nc);
    p->w = calloc(nc, sizeof(double[3]));
    p->data_t = malloc(sizeof(int) * n);
    p->data_v = malloc(sizeof(int) * n);
    double (*Kq)[4] = malloc(sizeof(double[4]) * n), *rv = malloc(sizeof(double) * 3 * (nc + n));
    band B = {0};
    thx_status st = THX_OK;
    if (!p->t || !p->U || !p->c || !p->q || !p->w || !p->data_t || !p->data_v || !Kq || !rv || band_init(&B, nc, k->ends == THX_CAMERA_ENDS_CLOSED ? nc - 1 : 2, k->ends == THX_CAMERA_ENDS_CLOSED ? nc - 1 : 2)) {
        st = thx_error(ctx, THX_ENOMEM, "camera path: out of memory");
        goto done;
    }
    for (int j = 0; j < n; j++) {
        const thx_camera_key *ky = &k->keys[j];
        p->t[j] = ky->frame;
        if (j && !(ky->frame > k->keys[j - 1].frame)) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: frame %d: not after the previous key's frame %d (line %d)", path, ky->line,
                           ky->frame, k->keys[j - 1].frame, k->keys[j - 1].line);
            goto done;
        }
        if (thx_camera_quaternion(&ky->cam, Kq[j])) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: the camera is degenerate (eye on the target, or up along the view direction)",
                           path, ky->line);
            goto done;
        }
        if (j) {
            double qi[4], v[3];
            qconj(Kq[j - 1], qi);
            qmul(qi, Kq[j], qi);
            qlog(qi, v);
            double ang = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) * 180 / M_PI;
            if (ang > 160) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: the camera turns %.1f degrees from the key at line %d: at most 160 "
                               "between successive keys (the way round is undecided near 180): add a key between",
                               path, ky->line, ang, k->keys[j - 1].line);
                goto done;
            }
        }
    }
    if (k->ends == THX_CAMERA_ENDS_CLOSED) { /* the last key repeats the first */
        const thx_camera *a = &k->keys[0].cam, *b = &k->keys[m].cam;
        double scale = 1, off = fabs(a->fov_deg - b->fov_deg) + fabs(a->height - b->height);
        for (int e = 0; e < 3; e++) {
            scale = fmax(scale, fmax(fabs(a->eye[e]), fabs(a->center[e])));
            off = fmax(off, fmax(fabs(a->eye[e] - b->eye[e]), fabs(a->center[e] - b->center[e])));
        }
        if (off > 1e-9 * scale || fabs(fabs(Kq[0][0] * Kq[m][0] + Kq[0][1] * Kq[m][1] + Kq[0][2] * Kq[m][2] + Kq[0][3] * Kq[m][3]) - 1) > 1e-12) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: ends closed: the last key must repeat the first key's camera (line %d): "
                           "eye, target, up, fov and height", path, k->keys[m].line, k->keys[0].line);
            goto done;
        }
    }
    p->U[0] = p->U[1] = p->U[2] = p->t[0];
    for (int j = 0; j <= m; j++) p->U[3 + j] = p->t[j];
    p->U[nc + 1] = p->U[nc + 2] = p->U[nc + 3] = p->t[m];
    for (int j = 0; j < n; j++)
        if (k->keys[j].data_frame > 0) {
            p->data_t[p->n_data] = k->keys[j].frame;
            p->data_v[p->n_data++] = k->keys[j].data_frame;
        }
    /* positions: one banded solve for the eye, the target, the fov and the height */
    position_matrix(p, k->ends, &B);
    memset(p->c, 0, sizeof(double[NV]) * nc);
    /* the unwrapped rotation vectors of the keys (body-frame turns summed), for the first guess */
    double (*r)[3] = (double(*)[3])rv, (*kr)[3] = (double(*)[3])(rv + 3 * nc);
    memset(rv, 0, sizeof(double) * 3 * nc);
    for (int j = 0; j < n; j++) {
        const thx_camera *c = &k->keys[j].cam;
        int row = j == 0 ? 0 : j == m ? nc - 1 : j + 1;
        for (int e = 0; e < 3; e++) p->c[row][e] = c->eye[e], p->c[row][3 + e] = c->center[e];
        p->c[row][6] = c->fov_deg;
        p->c[row][7] = c->height;
        memset(kr[j], 0, sizeof kr[j]);
        if (j) {
            double qi[4], v[3];
            qconj(Kq[j - 1], qi);
            qmul(qi, Kq[j], qi);
            qlog(qi, v);
            for (int e = 0; e < 3; e++) kr[j][e] = kr[j - 1][e] + v[e];
        }
        memcpy(r[row], kr[j], sizeof kr[j]);
    }
    band B2 = {0};
    if (band_init(&B2, nc, B.kl, B.ku)) {
        st = thx_error(ctx, THX_ENOMEM, "camera path: out of memory");
        goto done;
    }
    memcpy(B2.a, B.a, sizeof(double) * (size_t)nc * B.w);
    int bad = band_solve(&B, &p->c[0][0], NV) || band_solve(&B2, rv, 3);
    free(B2.a);
    if (bad) {
        st = thx_error(ctx, THX_EINTERNAL, "%s: the spline's system is singular", path);
        goto done;
    }
    /* the first guess of the control quaternions: the key nearest each control's Greville abscissa,
       turned by the difference of the rotation vectors' spline control and that key's vector */
    for (int i = 0; i < nc; i++) {
        double g = (p->U[i + 1] + p->U[i + 2] + p->U[i + 3]) / 3;
        int best = 0;
        for (int j = 1; j < n; j++)
            if (fabs(p->t[j] - g) < fabs(p->t[best] - g)) best = j;
        double v[3] = {r[i][0] - kr[best][0], r[i][1] - kr[best][1], r[i][2] - kr[best][2]};
        qstep(Kq[best], v, p->q[i]);
    }
    for (int i = 1; i < nc; i++) /* the turns on the branches of the rotation vectors' spline */
        for (int e = 0; e < 3; e++) p->w[i][e] = r[i][e] - r[i - 1][e];
    turns(nc, (const double(*)[4])p->q, p->w, 1, nc - 1);
    double resid = 0;
    if (solve_orientation(p, (const double(*)[4])Kq, k->ends, &resid)) {
        st = thx_error(ctx, THX_ESOLVER, "%s: the orientation curve through the %d keys did not converge (residual %.3g rad): "
                       "add keys where the camera turns most", path, n, resid);
        goto done;
    }
    /* the interpolated camera must stay a camera: checked at every frame and at quarter frames */
    for (int j = 0; j < m && st == THX_OK; j++)
        for (double t = p->t[j]; t < p->t[j + 1] && st == THX_OK; t += 0.25) {
            thx_camera cam;
            double qq[4];
            thx_camera_path_camera(p, t, &cam);
            const char *what = NULL;
            if (!p->ortho && !(cam.fov_deg > 0 && cam.fov_deg < 180)) what = "the field of view leaves 0..180 degrees";
            else if (p->ortho && !(cam.height > 0)) what = "the orthographic height is not positive";
            else if (thx_camera_quaternion(&cam, qq)) what = "the eye meets the target or the up turns along the view";
            if (what)
                st = thx_error(ctx, THX_EINPUT, "%s: between the keys at lines %d and %d, at frame %g %s (fov %g, height %g): "
                               "add a key between", path, k->keys[j].line, k->keys[j + 1].line, t, what, cam.fov_deg, cam.height);
        }
done:
    free(Kq), free(rv), free(B.a);
    if (st != THX_OK) thx_camera_path_destroy(&p);
    *out = p;
    return st;
}

void thx_camera_path_destroy(thx_camera_path **pp)
{
    if (!pp || !*pp) return;
    thx_camera_path *p = *pp;
    free(p->t), free(p->U), free(p->c), free(p->q), free(p->w), free(p->data_t), free(p->data_v);
    free(p);
    *pp = NULL;
}

int thx_camera_path_first(const thx_camera_path *p) { return (int)p->t[0]; }
int thx_camera_path_last(const thx_camera_path *p) { return (int)p->t[p->n - 1]; }

void thx_camera_path_state_at(const thx_camera_path *p, double t, int side, thx_camera_path_state *st)
{
    memset(st, 0, sizeof *st);
    double lo = p->t[0], hi = p->t[p->n - 1];
    int clamped = t < lo || t > hi;
    if (t < lo) t = lo;
    if (t > hi) t = hi;
    int s = span_of(p, t, side);
    double d[4][4], qd[3][4];
    basis(p->U, s, t, d);
    for (int r = 0; r < 3; r++)
        for (int a = 0; a < 4; a++) {
            const double *c = p->c[s - 3 + a];
            for (int e = 0; e < 3; e++) st->eye[r][e] += d[r][a] * c[e], st->target[r][e] += d[r][a] * c[3 + e];
            st->fov[r] += d[r][a] * c[6];
            st->height[r] += d[r][a] * c[7];
        }
    qcurve(p, (const double(*)[4])p->q, (const double(*)[3])p->w, s, t, qd);
    memcpy(st->q, qd, sizeof qd);
    if (clamped) /* held still before the first key and after the last */
        for (int r = 1; r < 3; r++) {
            memset(st->eye[r], 0, sizeof st->eye[r]);
            memset(st->target[r], 0, sizeof st->target[r]);
            memset(st->q[r], 0, sizeof st->q[r]);
            st->fov[r] = st->height[r] = 0;
        }
}

void thx_camera_path_camera(const thx_camera_path *p, double frame, thx_camera *cam)
{
    thx_camera_path_state s;
    thx_camera_path_state_at(p, frame, 1, &s);
    double q[4], back[3], dist = 0;
    memcpy(q, s.q[0], sizeof q);
    qnormalize(q);
    memset(cam, 0, sizeof *cam);
    memcpy(cam->eye, s.eye[0], sizeof cam->eye);
    qaxis(q, 1, cam->up);
    qaxis(q, 2, back);
    for (int e = 0; e < 3; e++) dist += (s.target[0][e] - s.eye[0][e]) * (s.target[0][e] - s.eye[0][e]);
    dist = sqrt(dist);
    for (int e = 0; e < 3; e++)
        cam->center[e] = p->look == THX_CAMERA_LOOK_TARGET ? s.target[0][e] : s.eye[0][e] - dist * back[e];
    cam->fov_deg = p->ortho ? 0 : s.fov[0];
    cam->height = s.height[0];
}

int thx_camera_path_data_frame(const thx_camera_path *p, int frame)
{
    if (!p->n_data) return 0;
    if (frame <= p->data_t[0]) return p->data_v[0];
    if (frame >= p->data_t[p->n_data - 1]) return p->data_v[p->n_data - 1];
    int j = 0;
    while (j + 1 < p->n_data && p->data_t[j + 1] <= frame) j++;
    double f = (double)(frame - p->data_t[j]) / (p->data_t[j + 1] - p->data_t[j]);
    return (int)floor(p->data_v[j] + f * (p->data_v[j + 1] - p->data_v[j]) + 0.5);
}
