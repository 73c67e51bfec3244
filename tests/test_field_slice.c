/* Slices (thorax/field/field.h): planes cut exactly through the tetrahedra of a box; a known
 * linear field interpolated onto the slice matches it; the slice's area is the box's
 * cross-section; planes exactly through node layers; several planes; contour lines on the slice
 * (exact for a linear field, their length the analytic one, greater values on their left); the
 * plane texts; the writers (VTP header and OBJ counts; VTK reads them back in e2e_field); a part of
 * the volume (a corner's tetrahedra and their neighbours, as thorax/fem/parts.h holds them) sliced
 * with the whole's tolerance scale holds the whole's triangles of its own tetrahedra, bit for bit
 * (what thorax field under mpirun puts together). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "field_box.h"
#include "testlib.h"


static const double G[3] = {1.0, 2.0, 3.0}, C0 = -0.5;
static double field(const double *x) { return G[0] * x[0] + G[1] * x[1] + G[2] * x[2] + C0; }

static void check_slice(thx_ctx *ctx, const thx_volume *v, const double *phi, const char *spec, const char *what)
{
    thx_field_plane pl;
    CHECK_OK(ctx, thx_field_plane_parse(ctx, spec, &pl));
    thx_field_mesh *m = NULL;
    CHECK_OK(ctx, thx_field_mesh_create(ctx, &m));
    CHECK_OK(ctx, thx_field_slice(ctx, v, phi, &pl, 1, NULL, m));
    double off = 0, err = 0, wrong = 0;
    for (size_t i = 0; i < m->n_points; i++) {
        const double *x = m->xyz + 3 * i;
        double r = fabs(pl.n[0] * x[0] + pl.n[1] * x[1] + pl.n[2] * x[2] - pl.d);
        if (r > off) off = r;
        double e = fabs(m->value[i] - field(x));
        if (e > err) err = e;
    }
    for (size_t t = 0; t < m->n_tris; t++) {
        const int32_t *c = m->tri + 3 * t;
        const double *p = m->xyz + 3 * (size_t)c[0], *q = m->xyz + 3 * (size_t)c[1], *r = m->xyz + 3 * (size_t)c[2];
        double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, w[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
        double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
        double ln = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if ((n[0] * pl.n[0] + n[1] * pl.n[1] + n[2] * pl.n[2]) / ln < 1 - 1e-9) wrong++;
        /* the tetrahedron it came from spans the plane */
        const int32_t *q4 = v->tet + 4 * (size_t)m->cell[t];
        double lo = INFINITY, hi = -INFINITY;
        for (int k = 0; k < 4; k++) {
            const double *x = v->xyz + 3 * (size_t)q4[k];
            double s = pl.n[0] * x[0] + pl.n[1] * x[1] + pl.n[2] * x[2];
            lo = fmin(lo, s);
            hi = fmax(hi, s);
        }
        if (!(lo <= pl.d + 1e-12 && hi >= pl.d - 1e-12)) wrong++;
    }
    double exact = box_section_area(pl.n, pl.d, G_L), area = thx_field_mesh_area(m, 0);
    mesh_facts f = mesh_check(m, 0, on_box);
    printf("%-30s %5zu tris area %.12g (exact %.12g) off-plane %.2g potential error %.2g open %zu bad %zu degen %zu "
           "dup %zu\n", what, m->n_tris, area, exact, off, err, f.open_edges, f.bad_edges, f.degenerate, f.duplicate);
    CHECK(m->n_tris > 0);
    CHECK(off < 1e-12 * G_L[0]);
    CHECK(err < 1e-12 * 6 * G_L[0]);
    CHECK_NEAR(area, exact, 1e-11 * exact);
    CHECK(f.open_edges == 0 && f.bad_edges == 0 && f.degenerate == 0 && f.duplicate == 0);
    CHECK(wrong == 0);

    /* contours at three values: on the slice, exact, their length the line's inside the polygon
       (for an axis plane z = c: x + 2y = value - 3c - C0 inside the square, by sampling) */
    double cv[3] = {field((double[]){G_L[0] / 2, G_L[1] / 2, pl.origin[2]}), 0, 0};
    cv[1] = cv[0] - 6;
    cv[2] = cv[0] + 5;
    CHECK_OK(ctx, thx_field_contours(ctx, m, cv, 3));
    CHECK(m->n_segs > 0);
    double cerr = 0;
    size_t leftbad = 0;
    double len[3] = {0, 0, 0};
    for (size_t s = 0; s < m->n_segs; s++) {
        const double *a = m->cxyz + 3 * (size_t)m->seg[2 * s], *b = m->cxyz + 3 * (size_t)m->seg[2 * s + 1];
        int k = m->seg_tag[s];
        cerr = fmax(cerr, fmax(fabs(field(a) - cv[k]), fabs(field(b) - cv[k])));
        CHECK(m->cvalue[m->seg[2 * s]] == cv[k]);
        double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        len[k] += sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        /* left = n x d points up the gradient's in-plane part */
        double l[3] = {pl.n[1] * d[2] - pl.n[2] * d[1], pl.n[2] * d[0] - pl.n[0] * d[2], pl.n[0] * d[1] - pl.n[1] * d[0]};
        if (l[0] * G[0] + l[1] * G[1] + l[2] * G[2] <= 0) leftbad++;
    }
    CHECK(cerr < 1e-12 * 6 * G_L[0]);
    CHECK(leftbad == 0);
    if (pl.n[2] == 1) {
        for (int k = 0; k < 3; k++) {
            /* x + 2y = r in [0,Lx] x [0,Ly]: y = (r - x)/2, the part with 0 <= y <= Ly */
            double r = cv[k] - G[2] * pl.d - C0, x0 = fmax(0, r - 2 * G_L[1]), x1 = fmin(G_L[0], r);
            double exact_len = x1 > x0 ? (x1 - x0) * sqrt(1.25) : 0;
            CHECK_NEAR(len[k], exact_len, 1e-10 * G_L[0]);
        }
        printf("  contours: lengths %.10g %.10g %.10g, error %.2g, %zu segments\n", len[0], len[1], len[2], cerr, m->n_segs);
    }
    thx_field_mesh_destroy(&m);
}

static void check_specs(thx_ctx *ctx)
{
    thx_field_plane p;
    CHECK_OK(ctx, thx_field_plane_parse(ctx, "y=-12.5", &p));
    CHECK(p.n[0] == 0 && p.n[1] == 1 && p.n[2] == 0 && p.d == -12.5);
    CHECK_OK(ctx, thx_field_plane_parse(ctx, "1,2,3:0,0,-2", &p));
    CHECK(p.n[2] == -1 && p.d == -3 && p.origin[0] == 1);
    CHECK(thx_field_plane_parse(ctx, "w=3", &p) == THX_EINPUT && tl_msg_has(ctx, "expected"));
    CHECK(thx_field_plane_parse(ctx, "x=", &p) == THX_EINPUT);
    CHECK(thx_field_plane_parse(ctx, "0,0,0:0,0,0", &p) == THX_EINPUT && tl_msg_has(ctx, "normal is zero"));
    CHECK(thx_field_plane_parse(ctx, "0,0:1,0,0", &p) == THX_EINPUT);
    CHECK(thx_field_plane_parse(ctx, "z=inf", &p) == THX_EINPUT);
}

static void check_writers(thx_ctx *ctx, const thx_volume *v, const double *phi)
{
    thx_field_plane pl[2];
    CHECK_OK(ctx, thx_field_plane_parse(ctx, "z=2.2", &pl[0]));
    CHECK_OK(ctx, thx_field_plane_parse(ctx, "1,1,1:1,1,0", &pl[1]));
    thx_field_mesh *m = NULL;
    CHECK_OK(ctx, thx_field_mesh_create(ctx, &m));
    CHECK_OK(ctx, thx_field_slice(ctx, v, phi, pl, 2, NULL, m));
    size_t n0 = 0, n1 = 0;
    for (size_t t = 0; t < m->n_tris; t++) n0 += m->tag[t] == 0, n1 += m->tag[t] == 1;
    CHECK(n0 > 0 && n1 > 0 && n0 + n1 == m->n_tris);
    double c = 10;
    CHECK_OK(ctx, thx_field_contours(ctx, m, &c, 1));
    double tagv[2] = {1, 2}, *jm = malloc(v->n_tets * sizeof *jm);
    for (size_t t = 0; t < v->n_tets; t++) jm[t] = (double)t;
    thx_field_write_opts o = {.tag_name = {"plane", NULL}, .tag_value = {tagv, NULL}, .cell_scalar = jm,
                              .cell_scalar_name = "current_magnitude", .seg_value = &c, .has_time = 1, .time = 2.5};
    if (tl_scratch_make("field_slice") == 0) {
        CHECK_OK(ctx, thx_field_mesh_write_vtp(ctx, m, &o, tl_path("s.vtp")));
        CHECK_OK(ctx, thx_field_mesh_write_obj(ctx, m, (const char *const[]){"plane_1", "plane_2"}, 2, tl_path("s.obj")));
        size_t len = 0;
        char *t = tl_slurp(ctx, tl_path("s.vtp"), &len);
        CHECK(t && strstr(t, "<!-- thorax field") && strstr(t, "Name=\"current_magnitude\"") &&
              strstr(t, "Name=\"plane\"") && strstr(t, "TimeValue"));
        free(t);
        t = tl_slurp(ctx, tl_path("s.obj"), &len);
        size_t nv = 0, nf = 0, nl = 0;
        for (char *p = t; p && *p; p = strchr(p, '\n') ? strchr(p, '\n') + 1 : p + strlen(p)) {
            nv += p[0] == 'v' && p[1] == ' ';
            nf += p[0] == 'f' && p[1] == ' ';
            nl += p[0] == 'l' && p[1] == ' ';
        }
        CHECK(nv == m->n_points + m->n_cpoints && nf == m->n_tris && nl == m->n_segs);
        free(t);
        /* a user's file that is not thorax's is never replaced */
        tl_write_text(tl_path("mine.vtp"), "my notes\n");
        CHECK(thx_field_mesh_write_vtp(ctx, m, &o, tl_path("mine.vtp")) != THX_OK);
        t = tl_slurp(ctx, tl_path("mine.vtp"), &len);
        CHECK(t && !strcmp(t, "my notes\n"));
        free(t);
        /* thorax's own is */
        CHECK_OK(ctx, thx_field_mesh_write_vtp(ctx, m, NULL, tl_path("s.vtp")));
        CHECK(!tl_leftover_tmp(""));
        tl_scratch_finish("field_slice");
    }
    free(jm);
    thx_field_mesh_destroy(&m);
}

/* The part of v whose tetrahedra's centroids lie below `corner` on every axis (own), with the
 * tetrahedra sharing a node with them (ghosts), in v's order; its slice with v's scale against v's. */
static void check_part(thx_ctx *ctx, const thx_volume *v, const double *phi, const char *spec, double corner)
{
    size_t nt = 0, nn = 0;
    unsigned char *own = calloc(v->n_tets, 1), *near = calloc(v->n_nodes, 1), *keep = calloc(v->n_tets, 1);
    int32_t *node_map = malloc(v->n_nodes * sizeof *node_map), *tet_of = malloc(v->n_tets * sizeof *tet_of);
    for (size_t t = 0; t < v->n_tets; t++) {
        double c[3] = {0, 0, 0};
        for (int k = 0; k < 4; k++)
            for (int a = 0; a < 3; a++) c[a] += v->xyz[3 * (size_t)v->tet[4 * t + k] + a] / 4;
        own[t] = c[0] < corner && c[1] < corner && c[2] < corner;
        for (int k = 0; own[t] && k < 4; k++) near[v->tet[4 * t + k]] = 1;
    }
    for (size_t t = 0; t < v->n_tets; t++)
        for (int k = 0; k < 4; k++) keep[t] |= near[v->tet[4 * t + k]];
    for (size_t i = 0; i < v->n_nodes; i++) node_map[i] = -1;
    thx_volume p = {.n_regions = v->n_regions, .regions = v->regions};
    p.tet = malloc(4 * v->n_tets * sizeof *p.tet);
    p.region = malloc(v->n_tets * sizeof *p.region);
    p.xyz = malloc(3 * v->n_nodes * sizeof *p.xyz);
    double *pphi = malloc(v->n_nodes * sizeof *pphi);
    for (size_t i = 0; i < v->n_nodes; i++) /* (the part's nodes in the whole's order) */
        for (size_t t = 0; t < v->n_tets && node_map[i] < 0; t++)
            for (int k = 0; keep[t] && k < 4; k++)
                if ((size_t)v->tet[4 * t + k] == i && node_map[i] < 0) {
                    memcpy(p.xyz + 3 * nn, v->xyz + 3 * i, 3 * sizeof *p.xyz);
                    pphi[nn] = phi[i];
                    node_map[i] = (int32_t)nn++;
                }
    for (size_t t = 0; t < v->n_tets; t++) {
        if (!keep[t]) continue;
        for (int k = 0; k < 4; k++) p.tet[4 * nt + k] = node_map[v->tet[4 * t + k]];
        p.region[nt] = v->region[t];
        tet_of[nt++] = (int32_t)t;
    }
    p.n_nodes = nn;
    p.n_tets = nt;
    thx_field_plane pl;
    thx_field_mesh *w = NULL, *m = NULL;
    CHECK_OK(ctx, thx_field_plane_parse(ctx, spec, &pl));
    CHECK_OK(ctx, thx_field_mesh_create(ctx, &w));
    CHECK_OK(ctx, thx_field_mesh_create(ctx, &m));
    CHECK_OK(ctx, thx_field_slice(ctx, v, phi, &pl, 1, NULL, w));
    CHECK_OK(ctx, thx_field_slice_scaled(ctx, &p, pphi, &pl, 1, NULL, thx_field_slice_scale(v), m));
    size_t a = 0, b = 0, same = 0, owned = 0;
    while (1) { /* the own triangles of both, in order: the same tetrahedra, corners and values, bit for bit */
        while (a < w->n_tris && !own[w->cell[a]]) a++;
        while (b < m->n_tris && !own[tet_of[m->cell[b]]]) b++;
        if (a == w->n_tris || b == m->n_tris) break;
        int eq = w->cell[a] == tet_of[m->cell[b]];
        for (int c = 0; c < 3 && eq; c++) {
            int32_t i = w->tri[3 * a + c], j = m->tri[3 * b + c];
            eq = !memcmp(w->xyz + 3 * (size_t)i, m->xyz + 3 * (size_t)j, 3 * sizeof *w->xyz) &&
                 !memcmp(&w->value[i], &m->value[j], sizeof *w->value);
        }
        same += eq;
        owned++;
        a++;
        b++;
    }
    while (a < w->n_tris && !own[w->cell[a]]) a++;
    while (b < m->n_tris && !own[tet_of[m->cell[b]]]) b++;
    printf("%-30s part of %zu of %zu tetrahedra: %zu own triangles, %zu the whole's bit for bit\n", spec, nt, v->n_tets,
           owned, same);
    CHECK(owned > 10 && same == owned && a == w->n_tris && b == m->n_tris);
    thx_field_mesh_destroy(&w);
    thx_field_mesh_destroy(&m);
    free(p.tet);
    free(p.region);
    free(p.xyz);
    free(pphi);
    free(own);
    free(near);
    free(keep);
    free(node_map);
    free(tet_of);
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    const int N = 8;
    const double h = 0.75;
    G_L[0] = G_L[1] = G_L[2] = N * h;
    thx_volume *box = box_mesh(ctx, N, N, N, h, 0, 3.0), *jit = box_mesh(ctx, N, N, N, h, 0.3, 3.0);
    double *pb = malloc(box->n_nodes * sizeof *pb), *pj = malloc(jit->n_nodes * sizeof *pj);
    for (size_t i = 0; i < box->n_nodes; i++) pb[i] = field(box->xyz + 3 * i);
    for (size_t i = 0; i < jit->n_nodes; i++) pj[i] = field(jit->xyz + 3 * i);
    check_slice(ctx, box, pb, "z=2.2", "z = 2.2, box");
    check_slice(ctx, jit, pj, "z=2.2", "z = 2.2, jittered");
    check_slice(ctx, box, pb, "z=3", "z = 3 (a node layer)");
    check_slice(ctx, box, pb, "z=6", "z = 6 (the top face)");
    {
        /* the bottom face z = 0: every node is at or above it, none below (a node at the value counts
           as above): nothing, as for a plane just below the box */
        thx_field_plane pl;
        thx_field_mesh *m = NULL;
        CHECK_OK(ctx, thx_field_plane_parse(ctx, "z=0", &pl));
        CHECK_OK(ctx, thx_field_mesh_create(ctx, &m));
        CHECK_OK(ctx, thx_field_slice(ctx, box, pb, &pl, 1, NULL, m));
        CHECK(m->n_tris == 0 && m->n_points == 0);
        thx_field_mesh_destroy(&m);
    }
    check_slice(ctx, jit, pj, "1,2,3:0.2,-0.5,1", "oblique, jittered");
    check_slice(ctx, box, pb, "3,3,3:1,1,1", "diagonal through nodes");
    check_specs(ctx);
    check_writers(ctx, jit, pj);
    check_part(ctx, jit, pj, "1,2,3:0.2,-0.5,1", 3.2);
    check_part(ctx, box, pb, "3,3,3:1,1,1", 4.6);
    check_part(ctx, box, pb, "z=3", 3.2);
    free(pb);
    free(pj);
    thx_volume_destroy(&box);
    thx_volume_destroy(&jit);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
