/* Equipotential surfaces (thorax/field/field.h): a linear field's isosurface is the exact plane
 * (every vertex on it, the area of the box's cross-section, normal along grad phi), closed
 * wherever it does not reach the box's faces, with no degenerate or duplicate triangle even when
 * the value passes exactly through nodes; a quadratic field's vertices are exactly the linear
 * interpolation along the cut edges; several values, region restriction, thread-count
 * independence, and the value lists. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "field_box.h"
#include "testlib.h"


/* phi = g.x + c0 at every node */
static double *linear(const thx_volume *v, const double *g, double c0)
{
    double *phi = malloc(v->n_nodes * sizeof *phi);
    for (size_t i = 0; i < v->n_nodes; i++) {
        const double *x = v->xyz + 3 * i;
        phi[i] = g[0] * x[0] + g[1] * x[1] + g[2] * x[2] + c0;
    }
    return phi;
}

/* The isosurface of a linear field at one value: exact plane, area, closed, oriented, clean. */
static void check_plane(thx_ctx *ctx, const thx_volume *v, const double *g, double c0, double value, const char *what)
{
    double *phi = linear(v, g, c0);
    thx_field_mesh *m = NULL;
    CHECK_OK(ctx, thx_field_mesh_create(ctx, &m));
    CHECK_OK(ctx, thx_field_isosurface(ctx, v, phi, &value, 1, NULL, m));
    double gl = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    double worst = 0;
    for (size_t i = 0; i < m->n_points; i++) {
        const double *x = m->xyz + 3 * i;
        double r = fabs(g[0] * x[0] + g[1] * x[1] + g[2] * x[2] + c0 - value) / gl;
        if (r > worst) worst = r;
        if (m->value[i] != value) worst = INFINITY;
    }
    double exact = box_section_area(g, value - c0, G_L);
    double area = thx_field_mesh_area(m, 0);
    mesh_facts f = mesh_check(m, 0, on_box);
    size_t wrong_way = 0;
    for (size_t t = 0; t < m->n_tris; t++) {
        const int32_t *c = m->tri + 3 * t;
        const double *p = m->xyz + 3 * (size_t)c[0], *q = m->xyz + 3 * (size_t)c[1], *r = m->xyz + 3 * (size_t)c[2];
        double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, w[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
        double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        double ln = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if ((n[0] * g[0] + n[1] * g[1] + n[2] * g[2]) / (ln * gl) < 1 - 1e-9) wrong_way++;
        if (m->tag[t] != 0 || m->cell[t] < 0 || (size_t)m->cell[t] >= v->n_tets) wrong_way++;
    }
    printf("%-34s %6zu tris %6zu pts  area %.12g (exact %.12g)  off-plane %.2g mm  open %zu bad %zu degen %zu dup %zu\n",
           what, m->n_tris, m->n_points, area, exact, worst, f.open_edges, f.bad_edges, f.degenerate, f.duplicate);
    CHECK(m->n_tris > 0);
    CHECK(worst < 1e-12 * (G_L[0] + G_L[1] + G_L[2]));
    CHECK_NEAR(area, exact, 1e-11 * exact);
    CHECK(f.open_edges == 0);
    CHECK(f.bad_edges == 0);
    CHECK(f.degenerate == 0);
    CHECK(f.duplicate == 0);
    CHECK(wrong_way == 0);
    thx_field_mesh_destroy(&m);
    CHECK(m == NULL);
    free(phi);
}

/* A closed surface inside: phi = |x - c|^2 at a value below the box's reach: no boundary edge at
 * all, and every vertex exactly where the edge's linear interpolation puts it (1e-14 relative). */
static void check_quadratic(thx_ctx *ctx, const thx_volume *v)
{
    double c[3] = {G_L[0] / 2 + 0.013, G_L[1] / 2 - 0.021, G_L[2] / 2 + 0.007};
    double *phi = malloc(v->n_nodes * sizeof *phi);
    for (size_t i = 0; i < v->n_nodes; i++) {
        const double *x = v->xyz + 3 * i;
        phi[i] = (x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) + (x[2] - c[2]) * (x[2] - c[2]);
    }
    double value = 4.0; /* a sphere of radius 2 */
    thx_field_mesh *m = NULL;
    CHECK_OK(ctx, thx_field_mesh_create(ctx, &m));
    CHECK_OK(ctx, thx_field_isosurface(ctx, v, phi, &value, 1, NULL, m));
    mesh_facts f = mesh_check(m, -1, NULL);
    /* each vertex: on a cut edge of its triangle's tetrahedron, at t = (v - phi_a) / (phi_b - phi_a) */
    size_t off = 0;
    for (size_t t = 0; t < m->n_tris; t++)
        for (int k = 0; k < 3; k++) {
            const double *x = m->xyz + 3 * (size_t)m->tri[3 * t + k];
            const int32_t *q = v->tet + 4 * (size_t)m->cell[t];
            double best = INFINITY;
            for (int i = 0; i < 4; i++)
                for (int j = 0; j < 4; j++) {
                    int32_t a = q[i], b = q[j];
                    if (!(phi[a] < value && phi[b] >= value)) continue;
                    double s = (value - phi[a]) / (phi[b] - phi[a]), d = 0;
                    for (int r = 0; r < 3; r++) {
                        double e = v->xyz[3 * (size_t)a + r] + s * (v->xyz[3 * (size_t)b + r] - v->xyz[3 * (size_t)a + r]) - x[r];
                        d += e * e;
                    }
                    if (d < best) best = d;
                }
            if (!(sqrt(best) <= 1e-14 * G_L[0])) off++;
        }
    /* volume enclosed (divergence theorem, normals outward = along grad phi): near 4/3 pi 8 */
    double vol = 0;
    for (size_t t = 0; t < m->n_tris; t++) {
        const double *p = m->xyz + 3 * (size_t)m->tri[3 * t], *q = m->xyz + 3 * (size_t)m->tri[3 * t + 1],
                     *r = m->xyz + 3 * (size_t)m->tri[3 * t + 2];
        vol += (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) + p[2] * (q[0] * r[1] - q[1] * r[0])) / 6;
    }
    printf("quadratic (sphere r=2): %zu tris, open %zu bad %zu degen %zu dup %zu, off-edge vertices %zu, volume %.4f "
           "(sphere %.4f)\n", m->n_tris, f.open_edges, f.bad_edges, f.degenerate, f.duplicate, off, vol,
           4.0 / 3.0 * M_PI * 8);
    CHECK(m->n_tris > 100);
    CHECK(f.open_edges == 0 && f.bad_edges == 0 && f.degenerate == 0 && f.duplicate == 0);
    CHECK(off == 0);
    CHECK(vol > 0); /* outward normals: the enclosed volume is positive */
    /* phi convex: its linear interpolant lies above it, so the interpolant's level set lies inside
       the sphere: every vertex within radius 2, the volume below the sphere's (and near it) */
    double rmax = 0;
    for (size_t i = 0; i < m->n_points; i++) {
        const double *x = m->xyz + 3 * i;
        double r = sqrt((x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) + (x[2] - c[2]) * (x[2] - c[2]));
        if (r > rmax) rmax = r;
    }
    CHECK(rmax <= 2 + 1e-12);
    CHECK(vol < 4.0 / 3.0 * M_PI * 8 && vol > 0.8 * 4.0 / 3.0 * M_PI * 8);
    thx_field_mesh_destroy(&m);
    free(phi);
}

/* Several values at once: tags, each the same as alone; thread-count independence; regions. */
static void check_several(thx_ctx *ctx, const thx_volume *v)
{
    double g[3] = {0.3, -0.7, 1.1};
    double *phi = linear(v, g, 0.25);
    double vals[3] = {2.0, -1.5, 0.5};
    thx_field_mesh *all = NULL, *one = NULL;
    CHECK_OK(ctx, thx_field_mesh_create(ctx, &all));
    CHECK_OK(ctx, thx_field_mesh_create(ctx, &one));
    CHECK_OK(ctx, thx_field_isosurface(ctx, v, phi, vals, 3, NULL, all));
    for (int k = 0; k < 3; k++) {
        thx_field_mesh_clear(one);
        CHECK_OK(ctx, thx_field_isosurface(ctx, v, phi, &vals[k], 1, NULL, one));
        size_t nk = 0;
        for (size_t t = 0; t < all->n_tris; t++) nk += all->tag[t] == k;
        CHECK(nk == one->n_tris && nk > 0);
        CHECK_NEAR(thx_field_mesh_area(all, k), thx_field_mesh_area(one, 0), 1e-12 * thx_field_mesh_area(one, 0));
        CHECK_NEAR(thx_field_mesh_area(one, 0), box_section_area(g, vals[k] - 0.25, G_L), 1e-10);
    }
    /* the same bytes for any thread count */
#ifdef _OPENMP
    int threads = omp_get_max_threads();
    for (int T = 1; T <= 3; T++) {
        omp_set_num_threads(T);
        thx_field_mesh_clear(one);
        CHECK_OK(ctx, thx_field_isosurface(ctx, v, phi, vals, 3, NULL, one));
        CHECK(one->n_points == all->n_points && one->n_tris == all->n_tris);
        CHECK(one->n_tris == all->n_tris && !memcmp(one->tri, all->tri, 3 * all->n_tris * sizeof *all->tri) &&
              !memcmp(one->xyz, all->xyz, 3 * all->n_points * sizeof *all->xyz) &&
              !memcmp(one->cell, all->cell, all->n_tris * sizeof *all->cell));
    }
    omp_set_num_threads(threads);
#endif
    /* the lower region only (z < L/2): the surface ends on the region interface */
    unsigned char use[2] = {1, 0};
    double z = 0;
    thx_field_mesh_clear(one);
    double gz[3] = {0, 0, 1}, *pz = linear(v, gz, 0);
    double vz = 0.37 * G_L[2], vhi = 0.8 * G_L[2];
    CHECK_OK(ctx, thx_field_isosurface(ctx, v, pz, &vz, 1, use, one));
    CHECK(one->n_tris > 0);
    for (size_t t = 0; t < one->n_tris; t++) CHECK(v->region[one->cell[t]] == 0);
    thx_field_mesh_clear(one);
    CHECK_OK(ctx, thx_field_isosurface(ctx, v, pz, &vhi, 1, use, one));
    CHECK(one->n_tris == 0);
    (void)z;
    /* a non-finite potential in the cut region is refused, naming the node */
    pz[v->tet[0]] = NAN;
    thx_field_mesh_clear(one);
    CHECK(thx_field_isosurface(ctx, v, pz, &vz, 1, NULL, one) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "non-finite potential"));
    double dup[2] = {1, 1};
    CHECK(thx_field_isosurface(ctx, v, phi, dup, 2, NULL, one) == THX_EINPUT);
    CHECK(tl_msg_has(ctx, "twice"));
    thx_field_mesh_destroy(&all);
    thx_field_mesh_destroy(&one);
    free(phi);
    free(pz);
}

static void check_values(thx_ctx *ctx)
{
    double *v = NULL;
    size_t n = 0;
    CHECK_OK(ctx, thx_field_values_parse(ctx, "-5,0,5", -10, 10, &v, &n));
    CHECK(n == 3 && v[0] == -5 && v[1] == 0 && v[2] == 5);
    free(v);
    CHECK_OK(ctx, thx_field_values_parse(ctx, "count:3", -10, 10, &v, &n));
    CHECK(n == 3 && v[0] == -5 && v[1] == 0 && v[2] == 5); /* evenly inside, ends excluded */
    free(v);
    /* a number is always a value (issue 24: "0", the zero equipotential, was refused as a count of
       none, and "3" gave three values) */
    CHECK_OK(ctx, thx_field_values_parse(ctx, "0", -1, 1, &v, &n));
    CHECK(n == 1 && v[0] == 0);
    free(v);
    CHECK_OK(ctx, thx_field_values_parse(ctx, "3", -10, 10, &v, &n));
    CHECK(n == 1 && v[0] == 3);
    free(v);
    CHECK_OK(ctx, thx_field_values_parse(ctx, "25%,50%,100%", 0, 8, &v, &n));
    CHECK(n == 3 && v[0] == 2 && v[1] == 4 && v[2] == 8);
    free(v);
    CHECK_OK(ctx, thx_field_values_parse(ctx, "10,", -1, 1, &v, &n));
    CHECK(n == 1 && v[0] == 10);
    free(v);
    CHECK(thx_field_values_parse(ctx, "count:0", -1, 1, &v, &n) == THX_EINPUT && !v && tl_msg_has(ctx, "count:N"));
    CHECK(thx_field_values_parse(ctx, "count:1001", -1, 1, &v, &n) == THX_EINPUT && !v);
    CHECK(thx_field_values_parse(ctx, "count:3,4", -1, 1, &v, &n) == THX_EINPUT && !v);
    CHECK(thx_field_values_parse(ctx, "120%", -1, 1, &v, &n) == THX_EINPUT && tl_msg_has(ctx, "outside"));
    CHECK(thx_field_values_parse(ctx, "1,1.0", -1, 1, &v, &n) == THX_EINPUT && tl_msg_has(ctx, "twice"));
    CHECK(thx_field_values_parse(ctx, "1,abc", -1, 1, &v, &n) == THX_EINPUT && tl_msg_has(ctx, "item 2"));
    CHECK(thx_field_values_parse(ctx, "", -1, 1, &v, &n) == THX_EINPUT);
    CHECK(thx_field_values_parse(ctx, "nan", -1, 1, &v, &n) == THX_EINPUT);
    CHECK(thx_field_values_parse(ctx, "count:4", 2, 2, &v, &n) == THX_EINPUT);
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    const int N = 8;
    const double h = 0.75;
    G_L[0] = G_L[1] = G_L[2] = N * h;
    thx_volume *box = box_mesh(ctx, N, N, N, h, 0, 3.0);
    thx_volume *jit = box_mesh(ctx, N, N, N, h, 0.3, 3.0);
    CHECK(box && jit);
    size_t inverted = 0;
    for (size_t t = 0; t < jit->n_tets; t++) inverted += !(thx_volume_tet_volume(jit, t) > 0);
    CHECK(inverted == 0);
    /* generic planes, on the regular and the jittered mesh */
    double g1[3] = {0.3, -0.7, 1.1}, g2[3] = {1, 1, 1}, gz[3] = {0, 0, 1}, gx[3] = {2, 0, 0};
    check_plane(ctx, box, g1, 0.25, 0.9, "oblique, box");
    check_plane(ctx, jit, g1, 0.25, 0.9, "oblique, jittered");
    check_plane(ctx, jit, g2, 0, 7.3, "diagonal, jittered");
    /* exactly through nodes: a layer (z = 3h), x = 2h (phi = 4h), and x+y+z = 6h through nodes
       in every configuration (tetrahedra with 1, 2, 3 nodes on the value) */
    check_plane(ctx, box, gz, 0, 3 * h, "z = node layer (exact)");
    check_plane(ctx, box, gx, 0, 4 * h, "x = node layer (exact)");
    check_plane(ctx, box, g2, 0, 6 * h, "x+y+z through nodes (exact)");
    check_plane(ctx, box, g2, 0, 9 * h, "x+y+z through nodes, middle");
    check_plane(ctx, jit, gz, 0, 3 * h, "z = boundary node layer, jittered");
    /* a value at the field's extremes: only the corner node (0 triangles at the minimum) */
    {
        double *phi = linear(box, g2, 0), lo = 0, hi = 3 * N * h;
        thx_field_mesh *m = NULL;
        CHECK_OK(ctx, thx_field_mesh_create(ctx, &m));
        CHECK_OK(ctx, thx_field_isosurface(ctx, box, phi, &lo, 1, NULL, m));
        CHECK(m->n_tris == 0); /* every node is >= the minimum: nothing below */
        CHECK_OK(ctx, thx_field_isosurface(ctx, box, phi, &hi, 1, NULL, m));
        mesh_facts f = mesh_check(m, -1, on_box);
        CHECK(f.degenerate == 0 && f.duplicate == 0); /* the top corner: a point, no triangle */
        CHECK(thx_field_mesh_area(m, -1) < 1e-20);
        thx_field_mesh_destroy(&m);
        free(phi);
    }
    /* films: the value exactly on a layer of nodes where the potential peaks (phi = -|z - 3h|):
       the nodes of the layer count as above, everything else below, so the perturbed surface is a
       film of no thickness round the layer: every triangle collapses or meets its twin, and
       nothing is left (no duplicate faces). With the potential flat (0) below the layer and
       falling above it, the layer is reached from above only: the plane, facing -z (grad phi). */
    {
        double *tent = malloc(box->n_nodes * sizeof *tent), *half = malloc(box->n_nodes * sizeof *half), zero = 0;
        for (size_t i = 0; i < box->n_nodes; i++) {
            double z = box->xyz[3 * i + 2];
            tent[i] = -fabs(z - 3 * h);
            half[i] = z > 3 * h ? 3 * h - z : 0;
        }
        thx_field_mesh *m = NULL;
        CHECK_OK(ctx, thx_field_mesh_create(ctx, &m));
        CHECK_OK(ctx, thx_field_isosurface(ctx, box, tent, &zero, 1, NULL, m));
        CHECK(m->n_tris == 0 && m->n_points == 0);
        CHECK_OK(ctx, thx_field_isosurface(ctx, box, half, &zero, 1, NULL, m));
        mesh_facts f = mesh_check(m, -1, on_box);
        CHECK(f.open_edges == 0 && f.bad_edges == 0 && f.degenerate == 0 && f.duplicate == 0);
        CHECK_NEAR(thx_field_mesh_area(m, -1), G_L[0] * G_L[1], 1e-12 * G_L[0] * G_L[1]);
        size_t up = 0;
        for (size_t t = 0; t < m->n_tris; t++) {
            const int32_t *c = m->tri + 3 * t;
            const double *p = m->xyz + 3 * (size_t)c[0], *q = m->xyz + 3 * (size_t)c[1], *r = m->xyz + 3 * (size_t)c[2];
            double nz = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
            up += !(nz < 0) || p[2] != 3 * h || q[2] != 3 * h || r[2] != 3 * h;
        }
        CHECK(m->n_tris == 2 * (size_t)N * (size_t)N && up == 0);
        printf("films: tent 0 triangles; half-tent %zu triangles on the layer, all facing -z\n", m->n_tris);
        thx_field_mesh_destroy(&m);
        free(tent);
        free(half);
    }
    check_quadratic(ctx, jit);
    check_several(ctx, jit);
    check_values(ctx);
    thx_volume_destroy(&box);
    thx_volume_destroy(&jit);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
