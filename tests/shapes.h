/*
 * Shapes the unit tests draw and mesh, written once: a UV sphere, a square plate of 5 x 5 nodes, and a
 * block of cubes cut into tetrahedra. Header-only (static inline), for the tests that include it.
 */
#ifndef THORAX_TESTS_SHAPES_H
#define THORAX_TESTS_SHAPES_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/predicates.h"
#include "thorax/model/surface.h"

/* A UV sphere of radius r at c, outward, nlon x nlat (two poles, nlat - 1 rings of nlon nodes), named
 * name; NULL if it cannot be made. */
static inline thx_surface *shape_sphere(thx_ctx *ctx, const char *name, const double c[3], double r, int nlon, int nlat)
{
    thx_surface *s = NULL;
    if (thx_surface_create(ctx, name, THX_ROLE_OTHER, &s) != THX_OK) return NULL;
    size_t nn = 2 + (size_t)nlon * (size_t)(nlat - 1), nt = 2 * (size_t)nlon * (size_t)(nlat - 1);
    s->xyz = malloc(3 * nn * sizeof *s->xyz);
    s->tri = malloc(3 * nt * sizeof *s->tri);
    if (!s->xyz || !s->tri) {
        thx_surface_destroy(&s);
        return NULL;
    }
    s->n_nodes = nn;
    s->n_tris = nt;
    double *x = s->xyz;
    int32_t *t = s->tri;
    size_t k = 0, m = 0;
    x[k++] = c[0], x[k++] = c[1], x[k++] = c[2] + r;
    for (int j = 1; j < nlat; j++)
        for (int i = 0; i < nlon; i++) {
            double th = M_PI * j / nlat, ph = 2 * M_PI * i / nlon;
            x[k++] = c[0] + r * sin(th) * cos(ph);
            x[k++] = c[1] + r * sin(th) * sin(ph);
            x[k++] = c[2] + r * cos(th);
        }
    x[k++] = c[0], x[k++] = c[1], x[k++] = c[2] - r;
    int32_t south = (int32_t)nn - 1;
    for (int i = 0; i < nlon; i++) t[m++] = 0, t[m++] = 1 + i, t[m++] = 1 + (i + 1) % nlon;
    for (int j = 1; j < nlat - 1; j++)
        for (int i = 0; i < nlon; i++) {
            int32_t a = 1 + (j - 1) * nlon + i, b = 1 + (j - 1) * nlon + (i + 1) % nlon, cc = a + nlon, d = b + nlon;
            t[m++] = a, t[m++] = cc, t[m++] = d;
            t[m++] = a, t[m++] = d, t[m++] = b;
        }
    for (int i = 0; i < nlon; i++) {
        int32_t a = 1 + (nlat - 2) * nlon + i, b = 1 + (nlat - 2) * nlon + (i + 1) % nlon;
        t[m++] = a, t[m++] = south, t[m++] = b;
    }
    return s;
}

/* A plate of 5 x 5 nodes in the plane y = 0 (facing the anterior view), x in x0..x0+50, z in
 * -25..25, 32 triangles; NULL if it cannot be made. */
static inline thx_surface *shape_plate(thx_ctx *ctx, const char *name, double x0)
{
    thx_surface *s = NULL;
    if (thx_surface_create(ctx, name, THX_ROLE_OTHER, &s) != THX_OK) return NULL;
    s->n_nodes = 25;
    s->xyz = calloc(3 * 25, sizeof *s->xyz);
    s->n_tris = 32;
    s->tri = calloc(3 * 32, sizeof *s->tri);
    if (!s->xyz || !s->tri) {
        thx_surface_destroy(&s);
        return NULL;
    }
    for (int j = 0; j < 5; j++)
        for (int i = 0; i < 5; i++) {
            double *p = s->xyz + 3 * (5 * j + i);
            p[0] = x0 + 12.5 * i;
            p[1] = 0;
            p[2] = -25 + 12.5 * j;
        }
    int t = 0;
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++) {
            int a = 5 * j + i, b = a + 1, c = a + 5, d = c + 1;
            int32_t q[6] = {a, b, d, a, d, c};
            memcpy(s->tri + 6 * t++, q, sizeof q);
        }
    return s;
}

/* n^3 cubes of side h from the origin, each cut into 6 positively oriented tetrahedra around its
 * main diagonal: (n + 1)^3 nodes into xyz (node i + m (j + m k), m = n + 1), 6 n^3 tetrahedra into
 * tet, cube (i, j, k)'s six at 6 (i + n (j + n k)). A map moving each coordinate by an increasing
 * function of that coordinate alone keeps every tetrahedron positive (each is the simplex of a
 * permutation of the axes in a box). */
static inline void shape_cube_grid(int n, double h, double *xyz, int32_t *tet)
{
    int m = n + 1;
    for (int k = 0; k < m; k++)
        for (int j = 0; j < m; j++)
            for (int i = 0; i < m; i++) {
                double *p = xyz + 3 * (i + m * (j + m * k));
                p[0] = i * h, p[1] = j * h, p[2] = k * h;
            }
    static const int path[6][2] = {{1, 2}, {1, 4}, {2, 1}, {2, 4}, {4, 1}, {4, 2}};
    size_t nt = 0;
    for (int k = 0; k < n; k++)
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++)
                for (int t = 0; t < 6; t++) {
                    int a = path[t][0], b = a | path[t][1], c[4] = {0, a, b, 7};
                    int32_t q[4];
                    for (int r = 0; r < 4; r++) q[r] = (i + (c[r] & 1)) + m * ((j + (c[r] >> 1 & 1)) + m * (k + (c[r] >> 2 & 1)));
                    /* orient positively: det[p1 - p0; p2 - p0; p3 - p0] > 0 */
                    if (thx_orient3d(xyz + 3 * q[1], xyz + 3 * q[2], xyz + 3 * q[3], xyz + 3 * q[0]) < 0) {
                        int32_t x = q[1];
                        q[1] = q[2];
                        q[2] = x;
                    }
                    memcpy(tet + 4 * nt++, q, sizeof q);
                }
}

#endif
