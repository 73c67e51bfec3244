/*
 * Tests of the voxelizer and the phantom as an image (src/phantom/voxelize.c, the point test of
 * src/phantom/phantom.c):
 *  - a box whose faces, edges and vertices lie exactly on the rays (the symbolic perturbation must
 *    count every ray once): its volume exactly, for either orientation of the triangles;
 *  - nested icospheres (either order, one turned inside out): each region's volume against the
 *    polyhedra's volumes computed here (tetrahedra from a node), by label and by fraction; the same
 *    on an oblique grid (a rotated direction matrix);
 *  - a surface with a triangle missing: refused, named;
 *  - the phantom's smooth outlines (thx_phantom_section) against its point test, 0.1 mm either side;
 *  - the phantom at 2 mm: every region's label volume within 0.2% of the phantom's section-integral
 *    volumes, the torso by fractions within 0.1%; the heart's slab of its ellipsoid against the
 *    closed form computed here from the ellipsoid's constants.
 */
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/phantom/phantom.h"
#include "thorax/phantom/voxelize.h"
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static thx_ctx *ctx;

/* ---- surfaces made here -------------------------------------------------- */

static thx_surface *make_surface(const char *name, const double *xyz, size_t nn, const int *tri, size_t nt)
{
    thx_surface *s = NULL;
    if (thx_surface_create(ctx, name, THX_ROLE_OTHER, &s) != THX_OK) exit(1);
    s->xyz = malloc(nn * 3 * sizeof *s->xyz);
    s->tri = malloc(nt * 3 * sizeof *s->tri);
    if (!s->xyz || !s->tri) exit(1);
    memcpy(s->xyz, xyz, nn * 3 * sizeof *s->xyz);
    for (size_t i = 0; i < 3 * nt; i++) s->tri[i] = tri[i];
    s->n_nodes = nn;
    s->n_tris = nt;
    return s;
}

/* Box lo..hi, triangles outward (flip: inward). */
static thx_surface *box(const double lo[3], const double hi[3], int flip)
{
    double x[24];
    for (int v = 0; v < 8; v++)
        for (int c = 0; c < 3; c++) x[3 * v + c] = (v >> c) & 1 ? hi[c] : lo[c];
    static const int T[36] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                              2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
    int t[36];
    for (int i = 0; i < 12; i++) {
        t[3 * i] = T[3 * i];
        t[3 * i + 1] = T[3 * i + (flip ? 2 : 1)];
        t[3 * i + 2] = T[3 * i + (flip ? 1 : 2)];
    }
    return make_surface("box", x, 8, t, 12);
}

/* Icosphere: an icosahedron subdivided `level` times, nodes on the sphere (centre c, radius r). */
static thx_surface *icosphere(const char *name, const double c[3], double r, int level, int flip)
{
    const double p = (1 + sqrt(5.0)) / 2;
    double v0[12][3] = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p},
                        {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
    int f0[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                     {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                     {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    size_t nv = 12, nt = 20, capv = 12 * (size_t)pow(4, level) + 12, capt = 20 * (size_t)pow(4, level);
    double *x = malloc(capv * 3 * sizeof *x);
    int *t = malloc(capt * 3 * sizeof *t);
    for (int i = 0; i < 12; i++) {
        double nrm = sqrt(v0[i][0] * v0[i][0] + v0[i][1] * v0[i][1] + v0[i][2] * v0[i][2]);
        for (int k = 0; k < 3; k++) x[3 * i + k] = v0[i][k] / nrm;
    }
    for (int i = 0; i < 20; i++)
        for (int k = 0; k < 3; k++) t[3 * i + k] = f0[i][k];
    for (int l = 0; l < level; l++) {
        /* midpoints, found by a search over the new vertices (small meshes) */
        int *nt2 = malloc(4 * nt * 3 * sizeof *nt2);
        size_t first_new = nv;
        for (size_t f = 0; f < nt; f++) {
            int m[3];
            for (int e = 0; e < 3; e++) {
                int a = t[3 * f + e], b = t[3 * f + (e + 1) % 3];
                double q[3];
                for (int k = 0; k < 3; k++) q[k] = 0.5 * (x[3 * a + k] + x[3 * b + k]);
                double nq = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
                for (int k = 0; k < 3; k++) q[k] /= nq;
                size_t found = nv;
                for (size_t w = first_new; w < nv; w++)
                    if (fabs(x[3 * w] - q[0]) + fabs(x[3 * w + 1] - q[1]) + fabs(x[3 * w + 2] - q[2]) < 1e-12) found = w;
                if (found == nv) {
                    for (int k = 0; k < 3; k++) x[3 * nv + k] = q[k];
                    nv++;
                }
                m[e] = (int)found;
            }
            int a = t[3 * f], b = t[3 * f + 1], cc = t[3 * f + 2];
            int nf[4][3] = {{a, m[0], m[2]}, {b, m[1], m[0]}, {cc, m[2], m[1]}, {m[0], m[1], m[2]}};
            for (int q = 0; q < 4; q++)
                for (int k = 0; k < 3; k++) nt2[3 * (4 * f + q) + k] = nf[q][k];
        }
        free(t);
        t = nt2;
        nt *= 4;
    }
    for (size_t i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) x[3 * i + k] = c[k] + r * x[3 * i + k];
    if (flip)
        for (size_t f = 0; f < nt; f++) {
            int a = t[3 * f + 1];
            t[3 * f + 1] = t[3 * f + 2];
            t[3 * f + 2] = a;
        }
    thx_surface *s = make_surface(name, x, nv, t, nt);
    free(x);
    free(t);
    return s;
}

/* Enclosed volume, tetrahedra from the first node (independent of thx_surface_volume). */
static double poly_volume(const thx_surface *s)
{
    const double *o = s->xyz;
    double v = 0;
    for (size_t f = 0; f < s->n_tris; f++) {
        const double *a = s->xyz + 3 * s->tri[3 * f], *b = s->xyz + 3 * s->tri[3 * f + 1], *c = s->xyz + 3 * s->tri[3 * f + 2];
        double u[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]}, w[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]},
               z[3] = {c[0] - o[0], c[1] - o[1], c[2] - o[2]};
        v += u[0] * (w[1] * z[2] - w[2] * z[1]) - u[1] * (w[0] * z[2] - w[2] * z[0]) + u[2] * (w[0] * z[1] - w[1] * z[0]);
    }
    return fabs(v) / 6.0;
}

static double label_volume(const thx_image *img, int r)
{
    size_t n = 0, nv = thx_image_count(img);
    for (size_t q = 0; q < nv; q++) n += img->v[q] == (float)r;
    return (double)n * img->spacing[0] * img->spacing[1] * img->spacing[2];
}

static double sum_volume(const thx_image *img)
{
    double s = 0;
    size_t nv = thx_image_count(img);
    for (size_t q = 0; q < nv; q++) s += img->v[q];
    return s * img->spacing[0] * img->spacing[1] * img->spacing[2];
}

/* ---- tests --------------------------------------------------------------- */

static void test_box_on_rays(void)
{
    /* grid of 1 mm voxels, 4 x 4 rays each: rays at x = i - 0.375, -0.125, 0.125, 0.375 (+ origin).
     * The box's corners are placed exactly on rays, so rays run along its edges and through its
     * vertices and diagonals: each must count once. Box 3.25 x 2.5 x 4.3 mm. */
    double lo[3] = {-10, -10, -10}, hi[3] = {10, 10, 10};
    for (int flip = 0; flip < 2; flip++) {
        thx_image lab;
        CHECK_OK(ctx, thx_voxel_grid(ctx, lo, hi, 1.0, 0, &lab));
        double b0[3] = {lab.origin[0] + 3 - 0.375, lab.origin[1] + 5 + 0.125, lab.origin[2] + 4.1};
        double b1[3] = {b0[0] + 3.25, b0[1] + 2.5, b0[2] + 4.3};
        thx_surface *s = box(b0, b1, flip);
        thx_image mix;
        CHECK_OK(ctx, thx_image_alloc(ctx, lab.n, &mix));
        double values[2] = {0, 1};
        thx_voxelize_opts o;
        thx_voxelize_opts_default(&o);
        o.values = values;
        const thx_surface *ss[1] = {s};
        CHECK_OK(ctx, thx_voxelize(ctx, ss, 1, &o, &lab, &mix));
        /* the rays counted inside: U in [U0, U1) with U0 on a ray -> 13 rays in x (3.25 * 4), 10 in y */
        CHECK_NEAR(sum_volume(&mix), 3.25 * 2.5 * 4.3, 1e-5); /* float voxels */
        thx_image_free(&mix);
        thx_image_free(&lab);
        thx_surface_destroy(&s);
    }
}

static void test_nested_spheres(void)
{
    double c[3] = {0.3, -0.7, 0.11}, c2[3] = {2.1, -0.2, 1.3};
    thx_surface *out = icosphere("outer", c, 10.0, 4, 0), *in = icosphere("inner", c2, 5.0, 3, 1);
    double vo = poly_volume(out), vi = poly_volume(in);
    CHECK(fabs(vo - 4.0 / 3 * M_PI * 1000) < 0.01 * 4.0 / 3 * M_PI * 1000); /* the polyhedron is nearly the ball */
    double lo[3] = {-11, -11, -11}, hi[3] = {11, 11, 11};
    for (int order = 0; order < 2; order++) {
        thx_image lab, mix;
        CHECK_OK(ctx, thx_voxel_grid(ctx, lo, hi, 1.0, 1, &lab));
        CHECK_OK(ctx, thx_image_alloc(ctx, lab.n, &mix));
        const thx_surface *ss[2] = {order ? in : out, order ? out : in};
        int r_out = order ? 2 : 1, r_in = order ? 1 : 2;
        double values[3] = {0, 0, 0};
        values[r_out] = 1; /* the mix: the shell's volume by fractions */
        thx_voxelize_opts o;
        thx_voxelize_opts_default(&o);
        o.values = values;
        CHECK_OK(ctx, thx_voxelize(ctx, ss, 2, &o, &lab, &mix));
        double shell = vo - vi;
        CHECK(fabs(sum_volume(&mix) - shell) < 0.001 * shell);
        CHECK(fabs(label_volume(&lab, r_out) - shell) < 0.01 * shell);
        CHECK(fabs(label_volume(&lab, r_in) - vi) < 0.02 * vi);
        fprintf(stderr, "spheres (order %d): shell %.2f by fractions, %.2f by labels, polyhedra %.2f; core %.2f vs %.2f\n",
                order, sum_volume(&mix), label_volume(&lab, r_out), shell, label_volume(&lab, r_in), vi);
        thx_image_free(&mix);
        thx_image_free(&lab);
    }
    /* an oblique grid (dir a rotation by 40 degrees about (1, 2, 2)/3, origin off the centre): the
     * rays run along its third axis, the volumes stay */
    {
        thx_image lab, mix;
        CHECK_OK(ctx, thx_voxel_grid(ctx, lo, hi, 1.0, 3, &lab));
        double ax[3] = {1.0 / 3, 2.0 / 3, 2.0 / 3}, t = 40 * M_PI / 180, cs = cos(t), sn = sin(t);
        for (int r = 0; r < 3; r++)
            for (int q = 0; q < 3; q++) {
                double k = r == q ? cs : 0, x = 0;
                if (r != q) {
                    int e = 3 - r - q; /* the cross-product matrix entry */
                    x = ((r + 1) % 3 == q ? -1 : 1) * ax[e] * sn;
                }
                lab.dir[3 * r + q] = k + (1 - cs) * ax[r] * ax[q] + x;
            }
        /* keep the sphere inside: the grid turns about its own centre */
        double ctr[3] = {0.5 * (double)(lab.n[0] - 1), 0.5 * (double)(lab.n[1] - 1), 0.5 * (double)(lab.n[2] - 1)}, rc[3];
        lab.origin[0] = lab.origin[1] = lab.origin[2] = 0;
        thx_image_index_to_ras(&lab, ctr, rc);
        for (int q = 0; q < 3; q++) lab.origin[q] = 0.2 - rc[q];
        CHECK_OK(ctx, thx_image_validate(ctx, &lab, "oblique grid"));
        CHECK_OK(ctx, thx_image_alloc(ctx, lab.n, &mix));
        const thx_surface *ss[2] = {out, in};
        double values[3] = {0, 1, 0};
        thx_voxelize_opts o;
        thx_voxelize_opts_default(&o);
        o.values = values;
        CHECK_OK(ctx, thx_voxelize(ctx, ss, 2, &o, &lab, &mix));
        double shell = vo - vi;
        fprintf(stderr, "spheres, oblique grid: shell %.2f by fractions, polyhedra %.2f\n", sum_volume(&mix), shell);
        CHECK(fabs(sum_volume(&mix) - shell) < 0.001 * shell);
        thx_image_free(&mix);
        thx_image_free(&lab);
    }
    /* a triangle missing (a box's bottom half-face, larger than the rays' spacing): not closed */
    double b0[3] = {-3.1, -2.2, -4.3}, b1[3] = {3.3, 2.9, 3.7};
    thx_surface *bx = box(b0, b1, 0);
    snprintf(bx->name, sizeof bx->name, "open");
    memmove(bx->tri, bx->tri + 3, 33 * sizeof *bx->tri);
    bx->n_tris = 11;
    thx_image lab;
    CHECK_OK(ctx, thx_voxel_grid(ctx, lo, hi, 1.0, 1, &lab));
    const thx_surface *ss[1] = {bx};
    CHECK(thx_voxelize(ctx, ss, 1, NULL, &lab, NULL) == THX_EINPUT && tl_msg_has(ctx, "\"open\" is not closed"));
    thx_image_free(&lab);
    thx_surface_destroy(&bx);
    thx_surface_destroy(&out);
    thx_surface_destroy(&in);
}

/* The heart: ellipsoid centre C, long axis along U (semi-axis A), B across it horizontally, CC the
 * third (src/phantom/phantom.c's constants); its section area at height z is A0 (1 - (z - Cz)^2 / H^2)
 * with H the ellipsoid's half-height sqrt((M^-1)_zz) and A0 = pi A B CC / H. */
static double heart_slab_volume(double z0, double z1)
{
    const double C2 = 110.0, A = 62.0, B = 60.0, CC = 50.0;
    double u[3] = {-0.70, 0.50, -0.50}, nu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int i = 0; i < 3; i++) u[i] /= nu;
    double w[3] = {u[1], -u[0], 0}, nw = hypot(w[0], w[1]);
    w[0] /= nw;
    w[1] /= nw;
    double v[3] = {w[1] * u[2] - w[2] * u[1], w[2] * u[0] - w[0] * u[2], w[0] * u[1] - w[1] * u[0]};
    /* (M^-1)_zz = sum s_i^2 e_i[z]^2 */
    double H = sqrt(A * A * u[2] * u[2] + B * B * w[2] * w[2] + CC * CC * v[2] * v[2]);
    double A0 = M_PI * A * B * CC / H;
    double a = z0 - C2, b = z1 - C2;
    return A0 * ((b - a) - (b * b * b - a * a * a) / (3 * H * H));
}

/* The smooth outlines (thx_phantom_section) and the point test agree: 0.1 mm inside each outline the
 * surface's own region, 0.1 mm outside its container's; no surface is within 6.5 mm of another. */
static void test_sections_vs_point_test(void)
{
    thx_phantom_field *f = NULL;
    CHECK_OK(ctx, thx_phantom_field_create(ctx, &f));
    if (!f) return;
    static const int parent[THX_PHANTOM_N_SURFACES] = {0, 1, 2, 3, 3, 3};
    double zs[] = {0, 47.5, 60, 112.3, 160, 201, 240, 270};
    size_t tested = 0, wrong = 0, corners = 0;
    for (size_t q = 0; q < sizeof zs / sizeof zs[0]; q++) {
        thx_phantom_plane *P = NULL;
        CHECK_OK(ctx, thx_phantom_plane_create(ctx, f, zs[q], &P));
        for (int s = 0; s < THX_PHANTOM_N_SURFACES && P; s++) {
            thx_vec2 *p = NULL;
            size_t n = 0;
            CHECK_OK(ctx, thx_phantom_section(ctx, f, s, zs[q], &p, &n));
            double z0, z1;
            thx_phantom_slab(f, s, &z0, &z1);
            CHECK((n > 0) == (zs[q] >= z0 && zs[q] <= z1) || s == 5);
            for (size_t i = 0; i < n; i += 3) {
                thx_vec2 a = p[(i + n - 2) % n], b = p[(i + 2) % n];
                /* a corner of the traced outline (the tip of a lower lung's crescent, which the 1.25 mm
                 * trace cuts across) has no normal: skipped, counted */
                double t1x = p[i].x - a.x, t1y = p[i].y - a.y, t2x = b.x - p[i].x, t2y = b.y - p[i].y;
                if (t1x * t2x + t1y * t2y < cos(45 * M_PI / 180) * hypot(t1x, t1y) * hypot(t2x, t2y)) {
                    corners++;
                    continue;
                }
                double tx = b.x - a.x, ty = b.y - a.y, tl = hypot(tx, ty);
                double nx = ty / tl, ny = -tx / tl; /* outward: the outline is counterclockwise */
                int in = thx_phantom_region(P, p[i].x - 0.1 * nx, p[i].y - 0.1 * ny);
                int out = thx_phantom_region(P, p[i].x + 0.1 * nx, p[i].y + 0.1 * ny);
                tested++;
                if (in != s + 1 || out != parent[s]) {
                    if (wrong++ < 5)
                        fprintf(stderr, "z %g surface %d point (%g, %g): inside %d, outside %d\n", zs[q], s, p[i].x,
                                p[i].y, in, out);
                }
            }
            free(p);
        }
        thx_phantom_plane_destroy(&P);
    }
    fprintf(stderr, "sections: %zu outline points, %zu where the point test disagrees at 0.1 mm, %zu corners skipped\n",
            tested, wrong, corners);
    CHECK(tested > 5000 && wrong == 0 && corners < 10);
    thx_phantom_field_destroy(&f);
}

static void test_phantom(void)
{
    thx_phantom_field *f = NULL;
    CHECK_OK(ctx, thx_phantom_field_create(ctx, &f));
    if (!f) return;
    double vol[THX_PHANTOM_N_SURFACES], z0, z1;
    CHECK_OK(ctx, thx_phantom_volumes(ctx, f, 1.0, vol));
    thx_phantom_slab(f, 5, &z0, &z1);
    CHECK(fabs(vol[5] - heart_slab_volume(z0, z1)) < 1e-6 * vol[5]);
    double lo[3], hi[3];
    thx_phantom_bounds(f, lo, hi);
    thx_image lab, mix;
    CHECK_OK(ctx, thx_voxel_grid(ctx, lo, hi, 2.0, 2, &lab));
    CHECK_OK(ctx, thx_image_alloc(ctx, lab.n, &mix));
    memcpy(mix.origin, lab.origin, sizeof lab.origin);
    memcpy(mix.spacing, lab.spacing, sizeof lab.spacing);
    double values[7] = {0, 1, 1, 1, 1, 1, 1};
    thx_voxelize_opts o;
    thx_voxelize_opts_default(&o);
    o.values = values;
    /* THORAX_QUICK (the sanitized build): 2 x 2 x 2 sub-samples per boundary voxel instead of 4 x 4 x 4 */
    if (getenv("THORAX_QUICK")) o.sub = 2;
    size_t mixed = 0;
    CHECK_OK(ctx, thx_phantom_voxelize(ctx, &o, &lab, &mix, &mixed));
    /* regions: inside surface s and not inside the next ones */
    double reg[7];
    reg[1] = vol[0] - vol[1];
    reg[2] = vol[1] - vol[2];
    reg[3] = vol[2] - vol[3] - vol[4] - vol[5];
    reg[4] = vol[3];
    reg[5] = vol[4];
    reg[6] = vol[5];
    for (int r = 1; r <= 6; r++) {
        double lv = label_volume(&lab, r);
        fprintf(stderr, "phantom 2 mm: region %d: %.0f mm^3 by labels, %.0f by sections (%+.3f%%)\n", r, lv, reg[r],
                100 * (lv - reg[r]) / reg[r]);
        CHECK(fabs(lv - reg[r]) < 0.002 * reg[r]);
    }
    double torso = sum_volume(&mix);
    fprintf(stderr, "phantom 2 mm: torso %.0f mm^3 by fractions, %.0f by sections (%+.4f%%); %zu voxels sub-sampled\n",
            torso, vol[0], 100 * (torso - vol[0]) / vol[0], mixed);
    CHECK(fabs(torso - vol[0]) < 0.001 * vol[0]);
    thx_image_free(&mix);
    thx_image_free(&lab);
    thx_phantom_field_destroy(&f);
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    test_box_on_rays();
    test_nested_spheres();
    test_sections_vs_point_test();
    test_phantom();
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
