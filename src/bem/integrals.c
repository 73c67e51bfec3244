/* The analytic double- and single-layer integrals of the linear hat functions over a flat
 * triangle (de Munck 1992, "A linear discretization of the volume conductor boundary integral
 * equation using analytically integrated elements"), and the triangle's solid angle (van
 * Oosterom & Strackee 1983). Derivation (docs/decisions.md, "Boundary elements"): with y = r' - x,
 * d = n.y (constant on the plane), h_i = a_i + b_i.y (b_i in the plane),
 *   int h_i d/|y|^3 = a_i Omega + d b_i.int y/|y|^3 = a_i Omega - d b_i.sum_e m_e gamma_e
 *   int 1/|y|       = sum_e (m_e.y_e) gamma_e - d Omega
 *   int y_par/|y|   = sum_e m_e int_e |y| dl
 * by the divergence theorem in the plane (m_e the outward normal of edge e in the plane,
 * gamma_e = int_e dl/|y|). */
#include <math.h>

#include "thorax/bem/bem.h"

static inline void sub(double *r, const double *a, const double *b) { r[0] = a[0] - b[0]; r[1] = a[1] - b[1]; r[2] = a[2] - b[2]; }
static inline double dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static inline void cross(double *r, const double *a, const double *b)
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}

double thx_bem_triangle(const double x[3], const double a[3], const double b[3], const double c[3], double dl[3],
                        double sl[3])
{
    const double *z[3] = {a, b, c};
    double y[3][3], r[3], nn[3], e1[3], e2[3];
    for (int i = 0; i < 3; i++) {
        sub(y[i], z[i], x);
        r[i] = sqrt(dot(y[i], y[i]));
    }
    sub(e1, b, a);
    sub(e2, c, a);
    cross(nn, e1, e2);
    double twoA = sqrt(dot(nn, nn));
    if (!(twoA > 0)) { /* degenerate triangle: nothing */
        for (int i = 0; i < 3; i++) { dl[i] = 0; if (sl) sl[i] = 0; }
        return 0;
    }
    double n[3] = {nn[0] / twoA, nn[1] / twoA, nn[2] / twoA};
    double d = dot(n, y[0]);
    double h = sqrt(twoA); /* the triangle's size */
    /* solid angle; 0 for x in the triangle's plane (a corner, an edge or the plane outside) */
    double omega = 0;
    if (fabs(d) > 1e-13 * h) {
        double t[3];
        cross(t, y[1], y[2]);
        double num = dot(y[0], t);
        double den = r[0] * r[1] * r[2] + dot(y[0], y[1]) * r[2] + dot(y[0], y[2]) * r[1] + dot(y[1], y[2]) * r[0];
        omega = 2 * atan2(num, den);
    } else {
        d = 0;
    }
    /* edges: gamma, the edge normals, the line integrals of |y| */
    double G[3] = {0, 0, 0}, J[3] = {0, 0, 0}, I0 = 0;
    for (int e = 0; e < 3; e++) {
        int p = e, q = (e + 1) % 3;
        double u[3], m[3];
        sub(u, z[q], z[p]);
        double L = sqrt(dot(u, u));
        if (!(L > 0)) continue;
        for (int k = 0; k < 3; k++) u[k] /= L;
        cross(m, u, n);
        double tp = dot(y[p], u), tq = dot(y[q], u);
        double w[3] = {y[p][0] - tp * u[0], y[p][1] - tp * u[1], y[p][2] - tp * u[2]};
        double p2 = dot(w, w); /* squared distance of x from the edge's line */
        double gamma = 0, jl;
        if (p2 > 1e-24 * L * L) {
            if (tp + tq >= 0) gamma = log((r[q] + tq) / (r[p] + tp));
            else gamma = log((r[p] - tp) / (r[q] - tq));
            jl = 0.5 * (tq * r[q] - tp * r[p] + p2 * gamma);
        } else { /* x on the line: (m.y) gamma -> 0, d = 0; int |y| dl = int |t| dt */
            jl = 0.5 * (tq * fabs(tq) - tp * fabs(tp));
        }
        for (int k = 0; k < 3; k++) {
            G[k] += m[k] * gamma;
            J[k] += m[k] * jl;
        }
        I0 += dot(m, y[p]) * gamma;
    }
    I0 -= d * omega;
    for (int i = 0; i < 3; i++) {
        const double *z1 = z[(i + 1) % 3], *z2 = z[(i + 2) % 3];
        double s[3], v[3], bi[3], t[3];
        sub(s, z2, z1);
        sub(v, x, z1);
        cross(t, s, v);
        double ai = dot(t, n) / twoA;
        cross(bi, n, s);
        for (int k = 0; k < 3; k++) bi[k] /= twoA;
        dl[i] = ai * omega - d * dot(bi, G);
        if (sl) sl[i] = ai * I0 + dot(bi, J);
    }
    return omega;
}
