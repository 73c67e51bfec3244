/*
 * A small corner on a sharp fold (issue 24, item 2; src/mesh/conform.c, protect_folds): a wedge of
 * 16 deg (a "fin", like ECGSim's right-ventricular rim at heart node 195) inside a box, whose ridge
 * V-R holds the needle triangle (V, R, Q) with a 2 deg corner at V on one sheet, the other sheet
 * folding back at 16 deg, meshed at grids (and planes) of 4, 6 and 8 mm. Before the fold protection
 * the conformity's concentric shells left flat tetrahedra there (two points on the needle's edges at
 * the same distance from V, two on the other sheet) that no repair could remove: 0.955, 0.769 and
 * 1.142 deg (after: 2.02, 1.13, 1.51 deg). The volume must now have no
 * dihedral angle below thorax check's 1 deg (computed here from the coordinates), fill the box, and
 * every Steiner record must give its node's position from its triangle's corners.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/mesh/mesh.h"
#include "thorax/model/model.h"
#include "thorax/model/volume.h"

static thx_surface *surface(thx_ctx *ctx, const char *name, thx_role role, const double (*p)[3], size_t np,
                            const int (*t)[3], size_t nt)
{
    thx_surface *s = NULL;
    if (thx_surface_create(ctx, name, role, &s) != THX_OK) return NULL;
    s->n_nodes = np;
    s->xyz = malloc(3 * np * sizeof *s->xyz);
    s->n_tris = nt;
    s->tri = malloc(3 * nt * sizeof *s->tri);
    for (size_t i = 0; i < np; i++)
        for (int d = 0; d < 3; d++) s->xyz[3 * i + d] = p[i][d];
    for (size_t i = 0; i < nt; i++)
        for (int d = 0; d < 3; d++) s->tri[3 * i + d] = t[i][d] - 1;
    return s;
}

/* Smallest dihedral angle of a tetrahedron, degrees (the angle between the outward normals of two
 * faces is 180 deg minus the dihedral angle at their common edge). */
static double min_dihedral(const double *p[4])
{
    static const int fv[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    double n[4][3];
    for (int f = 0; f < 4; f++) {
        const double *a = p[fv[f][0]], *b = p[fv[f][1]], *c = p[fv[f][2]];
        double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double x[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        double l = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]), s = 0;
        for (int k = 0; k < 3; k++) s += x[k] * (p[f][k] - a[k]);
        for (int k = 0; k < 3; k++) n[f][k] = (s > 0 ? -x[k] : x[k]) / l;
    }
    double best = 180;
    for (int f = 0; f < 4; f++)
        for (int g = f + 1; g < 4; g++) {
            double d = n[f][0] * n[g][0] + n[f][1] * n[g][1] + n[f][2] * n[g][2];
            double ang = 180 - acos(d < -1 ? -1 : d > 1 ? 1 : d) * 180 / M_PI;
            if (ang < best) best = ang;
        }
    return best;
}

int main(void)
{
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    /* the fin: ridge V-R along x; sheet A in z = 0 (y < 0) holds the needle (V, R, Q), 2 deg at V;
       sheet B at 16 deg from A around the ridge; closed by a back face and two ends */
    const double W = 16 * M_PI / 180, al = 2 * M_PI / 180, L = 16, h = 8, o[3] = {10.3, 20.7, 30.1};
    double fin[7][3] = {{0, 0, 0},                          /* 1 V */
                        {L, 0, 0},                          /* 2 R */
                        {0, -h, 0},                         /* 3 VA */
                        {L + h, -h, 0},                     /* 4 RA */
                        {0, -h * cos(W), h * sin(W)},       /* 5 VB */
                        {L, -h * cos(W), h * sin(W)},       /* 6 RB */
                        {L * cos(al), -L * sin(al), 0}};    /* 7 Q */
    for (int i = 0; i < 7; i++)
        for (int d = 0; d < 3; d++) fin[i][d] += o[d];
    static const int fin_t[10][3] = {{1, 2, 7}, {1, 7, 3}, {7, 4, 3}, {2, 4, 7}, {1, 5, 2},
                                     {2, 5, 6}, {3, 4, 6}, {3, 6, 5}, {1, 3, 5}, {2, 6, 4}};
    double box[8][3];
    const double lo[3] = {-14.7, -14.3, 5.1}, hi[3] = {59.3, 45.7, 60.1};
    for (int i = 0; i < 8; i++) {
        box[i][0] = i & 4 ? hi[0] : lo[0];
        box[i][1] = i & 2 ? hi[1] : lo[1];
        box[i][2] = i & 1 ? hi[2] : lo[2];
    }
    static const int box_t[12][3] = {{1, 2, 4}, {1, 4, 3}, {5, 7, 8}, {5, 8, 6}, {1, 5, 6}, {1, 6, 2},
                                     {3, 4, 8}, {3, 8, 7}, {1, 3, 7}, {1, 7, 5}, {2, 6, 8}, {2, 8, 4}};
    thx_model *m = NULL;
    CHECK_OK(ctx, thx_model_create(ctx, &m));
    thx_surface *sb = surface(ctx, "box", THX_ROLE_OUTER, (const double(*)[3])box, 8, box_t, 12);
    thx_surface *sf = surface(ctx, "heart", THX_ROLE_HEART, (const double(*)[3])fin, 7, fin_t, 10);
    CHECK(sb && sf);
    if (!sb || !sf) return tl_finish();
    CHECK_OK(ctx, thx_model_add_surface(ctx, m, &sb));
    CHECK_OK(ctx, thx_model_add_surface(ctx, m, &sf));
    const double grids[] = {4, 6, 8};
    for (size_t gi = 0; gi < sizeof grids / sizeof *grids; gi++) {
        thx_mesh_opts opt;
        thx_mesh_opts_default(&opt);
        opt.grid = opt.layer_spacing = grids[gi];
        thx_mesh_stats st;
        CHECK_OK(ctx, thx_mesh_build(ctx, m, &opt, &st));
        const thx_volume *v = m->volume;
        CHECK(v != NULL);
        if (!v) break;
        double worst = 180, total = 0;
        size_t at = 0;
        for (size_t t = 0; t < v->n_tets; t++) {
            const double *p[4];
            for (int k = 0; k < 4; k++) p[k] = v->xyz + 3 * (size_t)v->tet[4 * t + k];
            double d = min_dihedral(p);
            if (d < worst) { worst = d; at = t; }
            total += thx_volume_tet_volume(v, t);
        }
        printf("grid %g mm: %zu tetrahedra, %zu Steiner nodes, smallest dihedral %.3f deg (tetrahedron %zu)\n", grids[gi],
               v->n_tets, v->n_steiner, worst, at + 1);
        CHECK(worst >= 1.0);
        /* the box's volume, the fin's included (the heart is meshed) */
        double box_vol = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
        CHECK_NEAR(total, box_vol, 1e-9 * box_vol);
        /* every Steiner node where its record says: on its triangle */
        double err = 0;
        for (size_t i = 0; i < v->n_steiner; i++) {
            const thx_steiner *r = &v->steiner[i];
            const thx_surface *s = m->surf[r->surf];
            double q[3] = {0, 0, 0};
            for (int k = 0; k < 3; k++)
                for (int d = 0; d < 3; d++) q[d] += r->bary[k] * s->xyz[3 * (size_t)s->tri[3 * (size_t)r->tri + k] + d];
            for (int d = 0; d < 3; d++) err = fmax(err, fabs(q[d] - v->xyz[3 * (size_t)r->node + d]));
        }
        CHECK(err < 1e-6);
    }
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return tl_finish();
}
