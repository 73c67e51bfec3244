/* Label maps -> contours (thorax/image/trace.h): label maps made here from analytic solids (the
 * partial-volume label: a voxel is labelled when more than half of its 4x4x4 sub-samples are
 * inside), traced, and the loops compared with the solid: a sphere at 1, 2 and 5 mm voxels (every
 * node within half a voxel in the plane of the analytic circle at its z, the volume from the loops
 * within 1%), resampled planes, a torus (holes filled, or kept clockwise), two islands, a blob that
 * splits between planes (built into a surface that passes the check), a tissue that starts and
 * stops (its caps), one-voxel noise removed and reported, nested tissues (the torso the union), an
 * oblique and a flipped direction matrix, and the refusals (not a label map, no voxel, a gap). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/check/check.h"
#include "thorax/geom/contours_valid.h"
#include "thorax/geom/repair.h"
#include "thorax/geom/surfaces.h"
#include "thorax/image/image.h"
#include "thorax/image/trace.h"
#include "thorax/io/contours_file.h"
#include "thorax/model/model.h"

static thx_ctx *ctx;

/* a solid: label value inside, by RAS point */
typedef int (*solid_fn)(const double p[3], void *user);

/* A label map of n^3 voxels of size h, centred on the origin, direction dir (NULL: identity):
 * label = the solid's value where more than half of 4x4x4 sub-samples agree, else 0 (sub-samples
 * vote per value). */
static void make_map(thx_image *img, size_t n0, size_t n1, size_t n2, double h, const double *dir, solid_fn f, void *user)
{
    size_t n[3] = {n0, n1, n2};
    if (thx_image_alloc(ctx, n, img) != THX_OK) exit(1);
    for (int c = 0; c < 3; c++) img->spacing[c] = h;
    if (dir) memcpy(img->dir, dir, sizeof img->dir);
    /* origin so that the grid's centre is at RAS 0 */
    double mid[3] = {0.5 * (double)(n0 - 1), 0.5 * (double)(n1 - 1), 0.5 * (double)(n2 - 1)}, r[3];
    memset(img->origin, 0, sizeof img->origin);
    thx_image_index_to_ras(img, mid, r);
    for (int c = 0; c < 3; c++) img->origin[c] = -r[c];
    img->integral = 1;
    snprintf(img->stored_type, sizeof img->stored_type, "uint8");
    for (size_t k = 0; k < n2; k++)
        for (size_t j = 0; j < n1; j++)
            for (size_t i = 0; i < n0; i++) {
                int votes[8] = {0}, first = -1, same = 1;
                /* the centre and the 8 corners agree: the voxel is whole (the solids here have no
                   feature smaller than a voxel) */
                for (int s = 0; s < 9 && same; s++) {
                    double ijk[3] = {(double)i, (double)j, (double)k}, p[3];
                    if (s < 8)
                        for (int c = 0; c < 3; c++) ijk[c] += (s >> c & 1) ? 0.5 : -0.5;
                    thx_image_index_to_ras(img, ijk, p);
                    int v = f(p, user);
                    if (first < 0) first = v;
                    same = v == first;
                }
                if (same) {
                    img->v[thx_image_at(img, i, j, k)] = (float)first;
                    continue;
                }
                for (int s = 0; s < 64; s++) {
                    double ijk[3] = {(double)i + ((s & 3) + 0.5) / 4 - 0.5, (double)j + (((s >> 2) & 3) + 0.5) / 4 - 0.5,
                                     (double)k + (((s >> 4) & 3) + 0.5) / 4 - 0.5},
                           p[3];
                    thx_image_index_to_ras(img, ijk, p);
                    int v = f(p, user);
                    if (v > 0 && v < 8) votes[v]++;
                }
                int best = 0;
                for (int v = 1; v < 8; v++)
                    if (votes[v] > 32) best = v;
                img->v[thx_image_at(img, i, j, k)] = (float)best;
            }
}

typedef struct {
    double c[3], r;
} ball;

static int in_sphere(const double p[3], void *user)
{
    const ball *b = user;
    double d2 = 0;
    for (int k = 0; k < 3; k++) d2 += (p[k] - b->c[k]) * (p[k] - b->c[k]);
    return d2 <= b->r * b->r;
}

static thx_trace_tissue tissue(const long *vals, size_t n, const char *name, thx_role role)
{
    thx_trace_tissue t = {vals, n, 0, name, role};
    return t;
}

static thx_status trace(const thx_image *img, const thx_trace_tissue *t, size_t nt, double spacing, int holes,
                        thx_contours **c, thx_trace_report *rep)
{
    thx_trace_opts o;
    thx_trace_opts_default(&o);
    o.tissues = t;
    o.n_tissues = nt;
    o.spacing = spacing;
    o.holes = holes;
    return thx_image_trace(ctx, img, &o, c, rep);
}

static double loop_area(const thx_loop *lp)
{
    double a = 0;
    for (size_t i = 0, j = lp->n - 1; i < lp->n; j = i++) a += lp->p[j].x * lp->p[i].y - lp->p[i].x * lp->p[j].y;
    return 0.5 * a;
}

/* Builds the surfaces of c as thorax surfaces does (repair, build) and runs thorax check's checks. */
static int builds_and_checks(thx_contours *c, double *vol)
{
    thx_repair_opts ro;
    thx_repair_opts_default(&ro, c->spacing);
    thx_repair_log log = {0};
    log.quiet = 1;
    thx_status st = thx_contours_repair(ctx, c, &ro, &log);
    thx_repair_log_free(&log);
    if (st != THX_OK) {
        fprintf(stderr, "repair: %s\n", thx_ctx_message(ctx));
        return 0;
    }
    thx_surfaces_opts o;
    thx_surfaces_opts_default(&o);
    o.spacing = c->spacing;
    thx_model *m = NULL;
    thx_surfaces_stats *per = calloc(c->n_surfaces, sizeof *per), tot;
    st = thx_surfaces_build(ctx, c, &o, &m, per, &tot);
    free(per);
    if (st != THX_OK) {
        fprintf(stderr, "build: %s\n", thx_ctx_message(ctx));
        return 0;
    }
    thx_check_opts co;
    thx_check_opts_default(&co);
    thx_model_report *rep = NULL;
    st = thx_model_check(ctx, m, &co, &rep);
    int ok = st == THX_OK && rep && rep->ok;
    if (!ok) fprintf(stderr, "check failed: %s\n", thx_ctx_message(ctx));
    if (vol) *vol = thx_surface_volume(m->surf[0]);
    thx_model_report_destroy(&rep);
    thx_model_destroy(&m);
    return ok;
}

/* The sphere at voxel size h (planes every voxel, or `spacing` apart): every node's in-plane
 * distance from the circle at its z, and the volume from the loops. */
static void test_sphere(double h, double spacing)
{
    ball b = {{0.3 * h, -0.2 * h, 0.1 * h}, 60.0}; /* off the grid's symmetry */
    size_t n = (size_t)ceil(2 * (b.r + 3 * h) / h);
    thx_image img;
    make_map(&img, n, n, n, h, NULL, in_sphere, &b);
    long one = 1;
    thx_trace_tissue t = tissue(&one, 1, "ball", THX_ROLE_OTHER);
    thx_contours *c = NULL;
    thx_trace_report rep;
    CHECK_OK(ctx, trace(&img, &t, 1, spacing, THX_TRACE_HOLES_FILL, &c, &rep));
    if (!c) exit(1);
    CHECK_OK(ctx, thx_contours_validate(ctx, c));
    CHECK(c->frame.set && c->frame.up.axis == 2 && c->frame.up.sign == 1 && c->frame.front.axis == 1);
    double dmax = 0, d3max = 0, vol = 0, dz = rep.plane_spacing;
    const thx_contour_surface *s = &c->surf[0];
    size_t nodes = 0;
    for (size_t l = 0; l < s->n_layers; l++) {
        const thx_contour_layer *L = &s->layers[l];
        CHECK(L->n_loops == 1);
        double zz = L->z - b.c[2], rc = sqrt(fmax(0, b.r * b.r - zz * zz));
        for (size_t k = 0; k < L->n_loops; k++) {
            const thx_loop *lp = &L->loops[k];
            CHECK(loop_area(lp) > 0); /* counterclockwise seen cranio-caudally */
            vol += loop_area(lp) * dz;
            for (size_t i = 0; i < lp->n; i++) {
                double dx = lp->p[i].x - b.c[0], dy = lp->p[i].y - b.c[1], rr = hypot(dx, dy);
                dmax = fmax(dmax, fabs(rr - rc));
                d3max = fmax(d3max, fabs(sqrt(rr * rr + zz * zz) - b.r));
                nodes++;
            }
        }
    }
    double vtrue = 4.0 / 3.0 * M_PI * b.r * b.r * b.r;
    printf("sphere R %g at %g mm voxels, planes %g mm apart: %zu layers, %zu nodes; in-plane distance max %.3f mm "
           "(%.3f voxel), 3D max %.3f mm; volume from the loops %.1f vs %.1f mm^3 (%+.3f%%)\n",
           b.r, h, dz, s->n_layers, nodes, dmax, dmax / h, d3max, vol, vtrue, 100 * (vol / vtrue - 1));
    /* the label map itself is no closer: its voxel faces between labelled and unlabelled voxels lie up
       to 0.602, 0.583 and 0.557 voxel from the sphere at 1, 2 and 5 mm (numpy, the same majority
       labels); in the plane the distance grows as the surface turns flat (near the poles) */
    CHECK(d3max <= 0.61 * h);
    CHECK(fabs(vol / vtrue - 1) < 0.01);
    if (h == 2 && spacing == 0) {
        double mv = 0;
        CHECK(builds_and_checks(c, &mv));
        printf("  surfaces: volume %.1f mm^3 (%+.3f%%)\n", mv, 100 * (mv / vtrue - 1));
        CHECK(fabs(mv / vtrue - 1) < 0.01);
    }
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    thx_image_free(&img);
}

/* A flat torus (axis z, R 30, r 10) at 2 mm: holes filled (one loop per layer, holes counted) or
 * kept (a clockwise loop inside; the signed areas give the torus's volume). */
typedef struct {
    double R, r;
} torus;
static int in_torus(const double p[3], void *user)
{
    const torus *t = user;
    double q = hypot(p[0], p[1]) - t->R;
    return q * q + p[2] * p[2] <= t->r * t->r;
}

static int in_shell(const double p[3], void *user)
{
    const double *r = user;
    double d = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return d >= r[0] && d <= r[1];
}

static void test_torus(void)
{
    torus tor = {30, 10};
    thx_image img;
    make_map(&img, 40, 40, 14, 2.0, NULL, in_torus, &tor);
    long one = 1;
    thx_trace_tissue t = tissue(&one, 1, "ring", THX_ROLE_OTHER);
    thx_contours *c = NULL;
    thx_trace_report rep;
    CHECK_OK(ctx, trace(&img, &t, 1, 0, THX_TRACE_HOLES_FILL, &c, &rep));
    if (!c) exit(1);
    CHECK_OK(ctx, thx_contours_validate(ctx, c));
    CHECK(rep.tissue[0].n_holes == c->surf[0].n_layers); /* every plane of the torus is a ring */
    for (size_t l = 0; l < c->surf[0].n_layers; l++) CHECK(c->surf[0].layers[l].n_loops == 1);
    /* the filled holes that open onto the outside on a neighbouring plane: the two end planes' (the
       torus's hole runs through), none between (the plane beyond is filled there too) */
    CHECK(rep.tissue[0].n_holes_open == 2);
    CHECK(rep.tissue[0].z_hole_open == c->surf[0].layers[0].z);
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);

    CHECK_OK(ctx, trace(&img, &t, 1, 0, THX_TRACE_HOLES_KEEP, &c, &rep));
    if (!c) exit(1);
    CHECK_OK(ctx, thx_contours_validate(ctx, c));
    double vol = 0, dmax = 0;
    for (size_t l = 0; l < c->surf[0].n_layers; l++) {
        const thx_contour_layer *L = &c->surf[0].layers[l];
        CHECK(L->n_loops == 2);
        int pos = 0, neg = 0;
        double w = sqrt(fmax(0, tor.r * tor.r - L->z * L->z));
        for (size_t k = 0; k < L->n_loops; k++) {
            double a = loop_area(&L->loops[k]);
            pos += a > 0;
            neg += a < 0;
            vol += a * rep.plane_spacing;
            /* the outer loop on the circle R + w, the hole on R - w */
            double rc = a > 0 ? tor.R + w : tor.R - w;
            for (size_t i = 0; i < L->loops[k].n; i++)
                dmax = fmax(dmax, fabs(hypot(L->loops[k].p[i].x, L->loops[k].p[i].y) - rc));
        }
        CHECK(pos == 1 && neg == 1);
    }
    double vtrue = 2 * M_PI * M_PI * tor.R * tor.r * tor.r;
    printf("torus R 30 r 10 at 2 mm, holes kept: volume from the loops %.1f vs %.1f (%+.2f%%), node distance max %.3f mm\n",
           vol, vtrue, 100 * (vol / vtrue - 1), dmax);
    CHECK(fabs(vol / vtrue - 1) < 0.02);
    CHECK(dmax <= 1.0);
    CHECK(rep.tissue[0].n_holes_open == 0); /* (kept, none filled) */
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    thx_image_free(&img);

    /* a hollow ball (radii 6 and 14 mm): its cavity's holes are filled, and none opens (the planes
       beyond the cavity's ends are full discs) */
    double shell[2] = {6, 14};
    make_map(&img, 16, 16, 16, 2.0, NULL, in_shell, shell);
    CHECK_OK(ctx, trace(&img, &t, 1, 0, THX_TRACE_HOLES_FILL, &c, &rep));
    if (c) CHECK(rep.tissue[0].n_holes > 0 && rep.tissue[0].n_holes_open == 0);
    printf("hollow ball: %zu holes filled, %zu open; torus: 2 open (its end planes)\n", c ? rep.tissue[0].n_holes : 0,
           c ? rep.tissue[0].n_holes_open : 0);
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    thx_image_free(&img);
}

/* Two balls side by side (islands in every plane), a ball with one-voxel noise and a one-voxel
 * cavity (removed, filled, reported), and a ball of label 2 inside a shell of label 1 (the torso
 * the union: solid loops, no hole). */
typedef struct {
    ball b[3];
    int nb;
    int val[3];
} balls;
static int in_balls(const double p[3], void *user)
{
    const balls *B = user;
    int v = 0;
    for (int k = 0; k < B->nb; k++)
        if (in_sphere(p, (void *)&B->b[k])) v = B->val[k];
    return v;
}

static void test_islands_noise_nesting(void)
{
    balls B = {{{{-15, 0, 0}, 10}, {{15, 0, 0}, 10}}, 2, {1, 1}};
    thx_image img;
    make_map(&img, 32, 16, 16, 2.0, NULL, in_balls, &B);
    long one = 1;
    thx_trace_tissue t = tissue(&one, 1, "pair", THX_ROLE_LUNG);
    thx_contours *c = NULL;
    thx_trace_report rep;
    CHECK_OK(ctx, trace(&img, &t, 1, 0, THX_TRACE_HOLES_FILL, &c, &rep));
    if (!c) exit(1);
    CHECK_OK(ctx, thx_contours_validate(ctx, c));
    /* two 3D components of one organ label: a surface each, named by side (+x the subject's right) */
    CHECK(c->n_surfaces == 2 && rep.n_tissues == 2);
    CHECK(strcmp(c->surf[0].name, "pair_right") == 0 && strcmp(c->surf[1].name, "pair_left") == 0);
    CHECK(rep.tissue[0].centroid_ras[0] > 14 && rep.tissue[0].centroid_ras[0] < 16);
    CHECK(rep.tissue[1].centroid_ras[0] < -14 && rep.tissue[1].centroid_ras[0] > -16);
    CHECK(rep.tissue[0].n_components == 2 && rep.tissue[1].component == 1 && strcmp(rep.tissue[1].tissue, "pair") == 0);
    for (int s = 0; s < 2; s++) {
        for (size_t l = 0; l < c->surf[s].n_layers; l++) {
            CHECK(c->surf[s].layers[l].n_loops == 1);
            /* every node on its own side */
            for (size_t i = 0; i < c->surf[s].layers[l].loops[0].n; i++)
                CHECK(s == 0 ? c->surf[s].layers[l].loops[0].p[i].x > 0 : c->surf[s].layers[l].loops[0].p[i].x < 0);
        }
        CHECK(rep.tissue[s].voxels == rep.tissue[1 - s].voxels); /* mirror images */
    }
    CHECK(builds_and_checks(c, NULL));
    size_t loops = rep.tissue[0].n_loops + rep.tissue[1].n_loops;
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    /* noise: three single voxels away from the balls, a one-voxel cavity in one */
    img.v[thx_image_at(&img, 1, 1, 1)] = 1;
    img.v[thx_image_at(&img, 30, 14, 2)] = 1;
    img.v[thx_image_at(&img, 16, 1, 14)] = 1;
    size_t ci = 0, cj = 0, ck = 0;
    double cijk[3], cras[3] = {-15, 0, 0};
    thx_image_ras_to_index(&img, cras, cijk);
    ci = (size_t)lround(cijk[0]);
    cj = (size_t)lround(cijk[1]);
    ck = (size_t)lround(cijk[2]);
    img.v[thx_image_at(&img, ci, cj, ck)] = 0;
    CHECK_OK(ctx, trace(&img, &t, 1, 0, THX_TRACE_HOLES_KEEP, &c, &rep));
    if (!c) exit(1);
    CHECK(rep.tissue[0].n_removed == 3 && rep.tissue[0].removed_voxels == 3);
    CHECK(rep.tissue[0].removed_size[0] == 1 && rep.tissue[0].removed_size[2] == 1);
    CHECK(rep.tissue[0].n_cavities == 1 && rep.tissue[0].cavity_voxels == 1);
    CHECK(rep.n_tissues == 2 && rep.tissue[0].n_loops + rep.tissue[1].n_loops == loops); /* the noise left nothing */
    CHECK(rep.tissue[0].n_holes == 0 && rep.tissue[1].n_holes == 0);
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    /* without cleaning the noise is traced (and its one-plane loops dropped as flat) */
    thx_trace_opts o;
    thx_trace_opts_default(&o);
    o.tissues = &t;
    o.n_tissues = 1;
    o.min_size = 0;
    o.holes = THX_TRACE_HOLES_KEEP;
    CHECK_OK(ctx, thx_image_trace(ctx, &img, &o, &c, &rep));
    /* the three noise voxels are components of their own, one plane thick: dropped, as a group of their
       own or as a flat loop of the ball's group (the voxel beside a ball's box) */
    CHECK(rep.n_tissues == 2 && rep.tissue[0].n_removed == 0);
    printf("noise: %zu groups dropped, flat loops %zu + %zu\n", rep.tissue[0].components_dropped,
           rep.tissue[0].n_flat_dropped, rep.tissue[1].n_flat_dropped);
    CHECK(rep.tissue[0].components_dropped + rep.tissue[0].n_flat_dropped + rep.tissue[1].n_flat_dropped == 3);
    CHECK(rep.tissue[0].n_holes + rep.tissue[1].n_holes == 1);
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    thx_image_free(&img);

    /* nesting: label 1 a shell (r 10..20), label 2 the ball inside (r 10) */
    balls N = {{{{0, 0, 0}, 20}, {{0, 0, 0}, 10}}, 2, {1, 2}};
    make_map(&img, 24, 24, 24, 2.0, NULL, in_balls, &N);
    long l1 = 1, l2 = 2;
    thx_trace_tissue tt[2] = {tissue(&l1, 1, "torso", THX_ROLE_OUTER), tissue(&l2, 1, "heart", THX_ROLE_HEART)};
    CHECK_OK(ctx, trace(&img, tt, 2, 0, THX_TRACE_HOLES_KEEP, &c, &rep));
    if (!c) exit(1);
    CHECK_OK(ctx, thx_contours_validate(ctx, c));
    CHECK(rep.tissue[0].n_holes == 0); /* the union: no hole where the heart is */
    CHECK(rep.tissue[1].n_holes == 0);
    double v0 = rep.tissue[0].area_sum * rep.plane_spacing, v1 = rep.tissue[1].area_sum * rep.plane_spacing;
    CHECK(fabs(v0 / (4.0 / 3.0 * M_PI * 8000) - 1) < 0.03);
    printf("nested: torso (the union) volume %+.2f%%, heart %+.2f%%\n", 100 * (v0 / (4.0 / 3.0 * M_PI * 8000) - 1),
           100 * (v1 / (4.0 / 3.0 * M_PI * 1000) - 1));
    /* a ball of 5 voxels' radius: its 504 voxels hold 4032 mm^3, 3.7% under the ball's (quantization) */
    CHECK(fabs(v1 / ((double)rep.tissue[1].voxels * 8.0) - 1) < 0.03);
    CHECK(builds_and_checks(c, NULL));
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    /* the shell alone, as an inner tissue: its holes are filled, the same solid as the union */
    thx_trace_tissue shell = tissue(&l1, 1, "shell", THX_ROLE_FAT);
    CHECK_OK(ctx, trace(&img, &shell, 1, 0, THX_TRACE_HOLES_FILL, &c, &rep));
    CHECK(rep.tissue[0].n_holes > 0 && fabs(rep.tissue[0].area_sum * rep.plane_spacing / v0 - 1) < 1e-9);
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    thx_image_free(&img);
}

/* A trunk (a cylinder, z < 4) that splits into two branches above it (two cylinders), capped at both
 * ends inside the image: one loop below, two above, the caps at the first and last labelled plane,
 * and the surface built through the branching passes the check. */
static int in_fork(const double p[3], void *user)
{
    (void)user;
    if (p[2] < -20 || p[2] > 20) return 0;
    if (p[2] < 4) return hypot(p[0], p[1]) <= 16;
    return hypot(p[0] - 10, p[1]) <= 7 || hypot(p[0] + 10, p[1]) <= 7;
}

static void test_split_caps(void)
{
    thx_image img;
    make_map(&img, 24, 24, 30, 2.0, NULL, in_fork, NULL);
    long one = 1;
    thx_trace_tissue t = tissue(&one, 1, "fork", THX_ROLE_OTHER);
    thx_contours *c = NULL;
    thx_trace_report rep;
    CHECK_OK(ctx, trace(&img, &t, 1, 0, THX_TRACE_HOLES_FILL, &c, &rep));
    if (!c) exit(1);
    CHECK_OK(ctx, thx_contours_validate(ctx, c));
    const thx_contour_surface *s = &c->surf[0];
    /* the labelled planes: voxel centres at z = -29 + 2k; the solid spans [-20, 20] */
    CHECK_NEAR(s->layers[0].z, -19.0, 1e-9);
    CHECK_NEAR(s->layers[s->n_layers - 1].z, 19.0, 1e-9);
    CHECK(s->n_layers == 20);
    for (size_t l = 0; l < s->n_layers; l++) CHECK(s->layers[l].n_loops == (s->layers[l].z < 4 ? 1u : 2u));
    CHECK(builds_and_checks(c, NULL));
    CHECK(c->n_surfaces == 1 && rep.n_tissues == 1 && rep.tissue[0].n_components == 1); /* one component: one surface */
    CHECK(strcmp(c->surf[0].name, "fork") == 0);
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    thx_image_free(&img);
}

/* An oblique grid (rotated 20 degrees about x) and a flipped one (i along -y, j along -x, k running
 * down: the in-plane index order mirrored): model coordinates are RAS for the flipped one, the image's axes for the oblique one
 * (RAS = Q model), loops counterclockwise, nodes within half a voxel of the sphere. */
static void test_oblique_flipped(void)
{
    double a = 20 * M_PI / 180;
    double rot[9] = {1, 0, 0, 0, cos(a), -sin(a), 0, sin(a), cos(a)};
    double flip[9] = {0, -1, 0, -1, 0, 0, 0, 0, -1}; /* i -> -y, j -> -x, k -> -z: the in-plane order mirrored */
    const double *dirs[2] = {rot, flip};
    for (int d = 0; d < 2; d++) {
        ball b = {{3, -2, 5}, 20};
        thx_image img;
        make_map(&img, 28, 28, 28, 2.0, dirs[d], in_sphere, &b);
        long one = 1;
        thx_trace_tissue t = tissue(&one, 1, "ball", THX_ROLE_OTHER);
        thx_contours *c = NULL;
        thx_trace_report rep;
        CHECK_OK(ctx, trace(&img, &t, 1, 0, THX_TRACE_HOLES_FILL, &c, &rep));
        if (!c) exit(1);
        CHECK_OK(ctx, thx_contours_validate(ctx, c));
        if (d == 0) CHECK_NEAR(rep.oblique_deg, 20, 1e-6);
        else {
            CHECK(rep.oblique_deg == 0);
            for (int k = 0; k < 9; k++) CHECK(rep.to_ras[k] == (k % 4 == 0 ? 1 : 0));
        }
        double dmax = 0, d3 = 0, vol = 0;
        const thx_contour_surface *s = &c->surf[0];
        for (size_t l = 0; l < s->n_layers; l++)
            for (size_t k = 0; k < s->layers[l].n_loops; k++) {
                const thx_loop *lp = &s->layers[l].loops[k];
                CHECK(loop_area(lp) > 0);
                vol += loop_area(lp) * rep.plane_spacing;
                for (size_t i = 0; i < lp->n; i++) {
                    double m[3] = {lp->p[i].x, lp->p[i].y, s->layers[l].z}, q[3] = {0, 0, 0};
                    for (int r = 0; r < 3; r++)
                        for (int cc = 0; cc < 3; cc++) q[r] += rep.to_ras[r * 3 + cc] * m[cc];
                    /* in the plane: the circle where the plane (normal Q's z column) cuts the ball */
                    double nz[3] = {rep.to_ras[2], rep.to_ras[5], rep.to_ras[8]}, dc[3], h = 0;
                    for (int r = 0; r < 3; r++) dc[r] = q[r] - b.c[r];
                    for (int r = 0; r < 3; r++) h += dc[r] * nz[r];
                    double rr = sqrt(fmax(0, dc[0] * dc[0] + dc[1] * dc[1] + dc[2] * dc[2] - h * h));
                    dmax = fmax(dmax, fabs(rr - sqrt(fmax(0, b.r * b.r - h * h))));
                    d3 = fmax(d3, fabs(sqrt(dc[0] * dc[0] + dc[1] * dc[1] + dc[2] * dc[2]) - b.r));
                }
            }
        double vtrue = 4.0 / 3.0 * M_PI * 8000;
        printf("%s grid: in-plane distance max %.3f mm, 3D %.3f mm, volume %+.2f%%\n", d ? "flipped" : "oblique (20 deg)",
               dmax, d3, 100 * (vol / vtrue - 1));
        CHECK(d3 <= 0.61 * 2.0);
        CHECK(fabs(vol / vtrue - 1) < 0.02);
        thx_trace_report_free(&rep);
        thx_contours_destroy(&c);
        thx_image_free(&img);
    }
}

/* Refusals: a non-integral image, a tissue without voxels, one that vanishes and reappears. */
static void test_refusals(void)
{
    balls B = {{{{0, 0, -14}, 6}, {{0, 0, 14}, 6}}, 2, {1, 1}};
    thx_image img;
    make_map(&img, 10, 10, 24, 2.0, NULL, in_balls, &B);
    long one = 1, nine = 9;
    thx_trace_tissue t = tissue(&one, 1, "two", THX_ROLE_MUSCLE);
    thx_contours *c = NULL;
    thx_trace_report rep;
    CHECK(trace(&img, &t, 1, 0, THX_TRACE_HOLES_FILL, &c, &rep) == THX_EINPUT && !c);
    CHECK(strstr(thx_ctx_message(ctx), "\"two\" vanishes and reappears") != NULL);
    thx_ctx_clear(ctx);
    /* an organ: a surface per component; one above the other (x ranges overlap): numbered, ties in
       memory order (the lower first) */
    t.role = THX_ROLE_OTHER;
    CHECK_OK(ctx, trace(&img, &t, 1, 0, THX_TRACE_HOLES_FILL, &c, &rep));
    CHECK(c && c->n_surfaces == 2 && strcmp(c->surf[0].name, "two_1") == 0 && strcmp(c->surf[1].name, "two_2") == 0);
    CHECK(c && c->surf[0].layers[0].z < 0 && c->surf[1].layers[0].z > 0);
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    thx_trace_tissue none = tissue(&nine, 1, "none", THX_ROLE_OTHER);
    CHECK(trace(&img, &none, 1, 0, THX_TRACE_HOLES_FILL, &c, &rep) == THX_EINPUT && !c);
    CHECK(strstr(thx_ctx_message(ctx), "\"none\": none of its label values is in the image") != NULL);
    thx_ctx_clear(ctx);
    img.integral = 0;
    CHECK(trace(&img, &t, 1, 0, THX_TRACE_HOLES_FILL, &c, &rep) == THX_EINPUT && !c);
    CHECK(strstr(thx_ctx_message(ctx), "not a label map") != NULL);
    thx_ctx_clear(ctx);
    thx_image_free(&img);
}

/* The contour file's image line (docs/formats.md): written and read back (a path with '#', '%',
 * a space and a tab escaped), and refused when malformed, given twice or after a layer. */
static void test_image_line(void)
{
    thx_contours *c = NULL, *r = NULL;
    CHECK_OK(ctx, thx_contours_create(ctx, &c));
    size_t s;
    CHECK_OK(ctx, thx_contours_add_surface(ctx, c, "a", THX_ROLE_OTHER, THX_CAP_GRID, 0, &s));
    thx_vec2 sq[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    CHECK_OK(ctx, thx_contours_add_loop(ctx, c, s, 0, sq, 4));
    CHECK_OK(ctx, thx_contours_add_loop(ctx, c, s, 1, sq, 4));
    const char *path = " we#ird %41\tname.nii ";
    snprintf(c->image, sizeof c->image, "%s", path);
    snprintf(c->image_sha256, sizeof c->image_sha256, "%s",
             "6a8901c1e6f5dcd0fc82de7818db38b78e8801adaab86df431d972058fba303a");
    CHECK_OK(ctx, thx_contours_write(ctx, c, tl_path("c.txt"), NULL));
    char *text = tl_slurp(ctx, tl_path("c.txt"), NULL);
    CHECK(text && strstr(text, "\nimage sha256:6a8901c1e6f5dcd0fc82de7818db38b78e8801adaab86df431d972058fba303a "
                               "%20we%23ird %2541%09name.nii%20\n"));
    free(text);
    CHECK_OK(ctx, thx_contours_read_raw(ctx, tl_path("c.txt"), &r));
    CHECK(r && strcmp(r->image, path) == 0 && strcmp(r->image_sha256, c->image_sha256) == 0);
    thx_contours_destroy(&r);
    thx_contours_destroy(&c);
    static const struct {
        const char *text, *msg;
    } bad[] = {
        {"thorax-contours 1\nimage sha256:abc x.nii\nsurface a other\nlayer 0\nloop a\n0 0\n1 0\n0 1\nend\n",
         "c.txt:2: expected 'image sha256:HEX PATH'"},
        {"thorax-contours 1\nimage sha256:6a8901c1e6f5dcd0fc82de7818db38b78e8801adaab86df431d972058fba303a\nend\n",
         "c.txt:2: expected 'image sha256:HEX PATH'"},
        {"thorax-contours 1\nimage sha256:6A8901c1e6f5dcd0fc82de7818db38b78e8801adaab86df431d972058fba303a x\nend\n",
         "c.txt:2: expected 'image sha256:HEX PATH'"},
        {"thorax-contours 1\nimage sha256:6a8901c1e6f5dcd0fc82de7818db38b78e8801adaab86df431d972058fba303a x\n"
         "image sha256:6a8901c1e6f5dcd0fc82de7818db38b78e8801adaab86df431d972058fba303a y\nend\n",
         "c.txt:3: 'image' given twice"},
        {"thorax-contours 1\nsurface a other\nlayer 0\nloop a\n0 0\n1 0\n0 1\n"
         "image sha256:6a8901c1e6f5dcd0fc82de7818db38b78e8801adaab86df431d972058fba303a x\nend\n",
         "c.txt:8: 'image' must come before the first layer"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        thx_contours *b = NULL;
        CHECK(thx_contours_parse_raw(ctx, "c.txt", bad[k].text, strlen(bad[k].text), &b) == THX_EINPUT && !b);
        CHECK(tl_msg_has(ctx, bad[k].msg));
        thx_ctx_clear(ctx);
    }
}

/* A scan that cuts a neck: an outer cylinder and an inner one both run through every plane of the
 * image. The inner surface must close inside the outer's end planes (else both caps lie in one plane
 * and the mesher meets coincident nodes): its first and last planes are trimmed, counted, and the two
 * surfaces build and check; the nesting follows the roles, whatever the order the tissues are given in. */
static int in_cylinders(const double p[3], void *user)
{
    (void)user;
    double r = hypot(p[0], p[1]);
    return r < 8 ? 2 : r < 14 ? 1 : 0;
}

static void test_cut_ends(void)
{
    thx_image img;
    make_map(&img, 20, 20, 10, 2.0, NULL, in_cylinders, NULL);
    long v_in[] = {2}, v_out[] = {1, 2};
    thx_trace_tissue t[2] = {tissue(v_in, 1, "inner", THX_ROLE_OTHER), tissue(v_out, 2, "outer", THX_ROLE_OUTER)};
    thx_contours *c = NULL;
    thx_trace_report rep;
    CHECK_OK(ctx, trace(&img, t, 2, 0, THX_TRACE_HOLES_FILL, &c, &rep));
    if (!c) exit(1);
    CHECK(strcmp(c->surf[0].name, "inner") == 0 && strcmp(c->surf[1].name, "outer") == 0); /* the order given */
    CHECK(c->surf[1].n_layers == 10 && rep.tissue[1].n_trimmed_layers == 0);
    CHECK(c->surf[0].n_layers == 8 && rep.tissue[0].n_trimmed_layers == 2);
    CHECK(c->surf[0].layers[0].z > c->surf[1].layers[0].z);
    CHECK(c->surf[0].layers[c->surf[0].n_layers - 1].z < c->surf[1].layers[c->surf[1].n_layers - 1].z);
    double vol = 0;
    CHECK(builds_and_checks(c, &vol));
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    thx_image_free(&img);
}

/* Do c1 and c2 hold the same first surface: as many layers, each layer's first loop the same bytes? */
static int same_first_surface(const thx_contours *c1, const thx_contours *c2)
{
    int same = c1 && c2 && c1->surf[0].n_layers == c2->surf[0].n_layers;
    for (size_t l = 0; same && l < c1->surf[0].n_layers; l++) {
        const thx_loop *p = &c1->surf[0].layers[l].loops[0], *q = &c2->surf[0].layers[l].loops[0];
        same = p->n == q->n && memcmp(p->p, q->p, p->n * sizeof *p->p) == 0;
    }
    return same;
}

/* Siblings that touch: a lung ball and a heart ball whose voxels meet face to face over many planes
 * (no voxel between them, as in a segmentation's map). Their loops keep a gap in every plane (the
 * competition field: each boundary at 0.75 of its own smoothed indicator where they face), the
 * surfaces build and pass the check (which fails surfaces that meet); a sibling farther than the
 * smoothing's reach leaves the contours byte-identical, and a nested tissue (blood inside the heart:
 * labels a subset) is no sibling. */
static void test_siblings(void)
{
    balls B = {{{{-9, 0, 0}, 14}, {{9, 0, 0}, 12}}, 2, {2, 3}};
    thx_image img;
    make_map(&img, 30, 24, 24, 2.0, NULL, in_balls, &B);
    size_t faces = 0;
    for (size_t k = 0; k < 24; k++)
        for (size_t j = 0; j < 24; j++)
            for (size_t i = 0; i + 1 < 30; i++) {
                float a = img.v[thx_image_at(&img, i, j, k)], b = img.v[thx_image_at(&img, i + 1, j, k)];
                faces += (a == 2 && b == 3) || (a == 3 && b == 2);
            }
    CHECK(faces > 40);
    long l2 = 2, l3 = 3;
    thx_trace_tissue tt[2] = {tissue(&l2, 1, "lung", THX_ROLE_LUNG), tissue(&l3, 1, "heart", THX_ROLE_HEART)};
    thx_contours *c = NULL;
    thx_trace_report rep;
    CHECK_OK(ctx, trace(&img, tt, 2, 0, THX_TRACE_HOLES_FILL, &c, &rep));
    if (!c) exit(1);
    CHECK(rep.tissue[0].contact_voxels > 40 && rep.tissue[1].contact_voxels > 40);
    /* the gap per plane: the least distance from a node of one loop to the edges of the other */
    double gmin = INFINITY;
    size_t planes = 0;
    for (size_t a = 0; a < c->surf[0].n_layers; a++)
        for (size_t b = 0; b < c->surf[1].n_layers; b++) {
            if (c->surf[0].layers[a].z != c->surf[1].layers[b].z) continue;
            planes++;
            for (int w = 0; w < 2; w++) {
                const thx_loop *P = &c->surf[w].layers[w ? b : a].loops[0], *Q = &c->surf[1 - w].layers[w ? a : b].loops[0];
                for (size_t i = 0; i < P->n; i++)
                    for (size_t j = 0; j < Q->n; j++) {
                        thx_vec2 q0 = Q->p[j], q1 = Q->p[(j + 1) % Q->n], p = P->p[i];
                        double dx = q1.x - q0.x, dy = q1.y - q0.y, L2 = dx * dx + dy * dy;
                        double t = L2 > 0 ? ((p.x - q0.x) * dx + (p.y - q0.y) * dy) / L2 : 0;
                        t = t < 0 ? 0 : t > 1 ? 1 : t;
                        gmin = fmin(gmin, hypot(q0.x + t * dx - p.x, q0.y + t * dy - p.y));
                    }
            }
        }
    printf("siblings touching over %zu voxel faces: %zu planes with both loops, least gap %.3f mm (%.3f voxel)\n", faces,
           planes, gmin, gmin / 2.0);
    CHECK(planes >= 8);
    CHECK(gmin > 0.4 * 2.0); /* 0.636 voxel where the faces meet square on; less on the staircase */
    CHECK(builds_and_checks(c, NULL));
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    thx_image_free(&img);

    /* a heart 6 voxels away: the lung's contours the bytes they are without it */
    balls F = {{{{-9, 0, 0}, 14}, {{20, 0, 0}, 4}}, 2, {2, 3}};
    make_map(&img, 30, 24, 24, 2.0, NULL, in_balls, &F);
    thx_contours *c1 = NULL, *c2 = NULL;
    CHECK_OK(ctx, trace(&img, tt, 2, 0, THX_TRACE_HOLES_FILL, &c1, &rep));
    CHECK(rep.tissue[0].contact_voxels == 0);
    thx_trace_report_free(&rep);
    CHECK_OK(ctx, trace(&img, tt, 1, 0, THX_TRACE_HOLES_FILL, &c2, &rep));
    thx_trace_report_free(&rep);
    CHECK(same_first_surface(c1, c2));
    thx_contours_destroy(&c1);
    thx_contours_destroy(&c2);
    thx_image_free(&img);

    /* nested: blood (3) inside the heart (2, 3): the heart's contours the same with the blood listed */
    balls N = {{{{0, 0, 0}, 14}, {{0, 0, 0}, 6}}, 2, {2, 3}};
    make_map(&img, 24, 24, 24, 2.0, NULL, in_balls, &N);
    long hv[2] = {2, 3};
    thx_trace_tissue hb[2] = {tissue(hv, 2, "heart", THX_ROLE_HEART), tissue(&l3, 1, "blood", THX_ROLE_OTHER)};
    CHECK_OK(ctx, trace(&img, hb, 2, 0, THX_TRACE_HOLES_FILL, &c1, &rep));
    CHECK(rep.tissue[0].contact_voxels == 0 && rep.tissue[1].contact_voxels == 0);
    thx_trace_report_free(&rep);
    CHECK_OK(ctx, trace(&img, hb, 1, 0, THX_TRACE_HOLES_FILL, &c2, &rep));
    thx_trace_report_free(&rep);
    CHECK(same_first_surface(c1, c2));
    thx_contours_destroy(&c1);
    thx_contours_destroy(&c2);
    thx_image_free(&img);
}

/* A bead: one voxel set just outside a ball, face-joined to it across planes only (its own plane holds
 * nothing else there), as a gently sloping boundary's staircase leaves them. Its loop encloses less
 * than a voxel's area: dropped when cleaning (counted), kept with min_size 0. */
static void test_tiny_loops(void)
{
    balls B = {{{{0, 0, 0}, 10}}, 1, {1}};
    thx_image img;
    make_map(&img, 16, 16, 16, 2.0, NULL, in_balls, &B);
    /* the ball's top voxel column at the centre; the voxel beside it one plane up */
    size_t ktop = 0;
    for (size_t k = 0; k < 16; k++)
        if (img.v[thx_image_at(&img, 8, 8, k)] == 1) ktop = k;
    CHECK(ktop + 1 < 16 && img.v[thx_image_at(&img, 8, 8, ktop + 1)] == 0);
    img.v[thx_image_at(&img, 8, 8, ktop + 1)] = 1;
    long one = 1;
    thx_trace_tissue t = tissue(&one, 1, "ball", THX_ROLE_OTHER);
    thx_contours *c = NULL;
    thx_trace_report rep;
    CHECK_OK(ctx, trace(&img, &t, 1, 0, THX_TRACE_HOLES_FILL, &c, &rep));
    CHECK(rep.tissue[0].n_tiny >= 1);
    double amin = INFINITY;
    for (size_t l = 0; c && l < c->surf[0].n_layers; l++)
        for (size_t i = 0; i < c->surf[0].layers[l].n_loops; i++) amin = fmin(amin, loop_area(&c->surf[0].layers[l].loops[i]));
    printf("bead: %zu loop(s) under a voxel's area dropped; the smallest loop kept %.2f mm^2 (voxel 4 mm^2)\n",
           rep.tissue[0].n_tiny, amin);
    CHECK(amin >= 4.0);
    CHECK(c && builds_and_checks(c, NULL));
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    thx_trace_opts o;
    thx_trace_opts_default(&o);
    o.tissues = &t;
    o.n_tissues = 1;
    o.min_size = 0;
    CHECK_OK(ctx, thx_image_trace(ctx, &img, &o, &c, &rep));
    CHECK(rep.tissue[0].n_tiny == 0);
    amin = INFINITY;
    for (size_t l = 0; c && l < c->surf[0].n_layers; l++)
        for (size_t i = 0; i < c->surf[0].layers[l].n_loops; i++) amin = fmin(amin, loop_area(&c->surf[0].layers[l].loops[i]));
    CHECK(amin < 4.0); /* the bead's loop, kept */
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    thx_image_free(&img);
}

static int nothing(const double p[3], void *user)
{
    (void)p, (void)user;
    return 0;
}

/* The most loops a layer of the traced surface has, and that layer's z. */
static size_t most_loops(const thx_contours *c, double *z)
{
    size_t m = 0;
    for (size_t l = 0; c && l < c->surf[0].n_layers; l++)
        if (c->surf[0].layers[l].n_loops > m) m = c->surf[0].layers[l].n_loops, *z = c->surf[0].layers[l].z;
    return m;
}

/* Pinched beads: in one plane a U (a block with a slot 4 voxels wide cut down from one edge), a piece
 * of 2 x 2 voxels in the slot's mouth one voxel from either arm (a saddle of the smoothed field: where
 * a lung's dome meets its outer wall the tracer leaves such a piece between the two loops' tips), a
 * like piece one voxel beside the U's straight bottom side (a dome's sliver along a lung) and one two
 * voxels off its left side; the plane above joins them all. The piece in the mouth (near the loop at
 * two places far apart along it) is dropped and counted with the beads; the other two are kept; with
 * min_size 0 all are kept. */
static void test_pinch_beads(void)
{
    thx_image img;
    make_map(&img, 20, 20, 6, 2.0, NULL, nothing, NULL);
    for (size_t k = 1; k <= 4; k++)
        for (size_t j = 4; j < 16; j++)
            for (size_t i = 4; i < 16; i++) img.v[thx_image_at(&img, i, j, k)] = 1;
    /* plane 2: the slot i = 8..11, j = 8..15; the pieces: in the mouth i = 9..10, j = 14..15; beside the
       bottom i = 6..7, j = 1..2; off the left side i = 0..1, j = 8..9 */
    for (size_t j = 8; j < 16; j++)
        for (size_t i = 8; i < 12; i++) img.v[thx_image_at(&img, i, j, 2)] = 0;
    size_t at[3][2] = {{9, 14}, {6, 1}, {0, 8}};
    for (int q = 0; q < 3; q++)
        for (size_t dj = 0; dj < 2; dj++)
            for (size_t di = 0; di < 2; di++) img.v[thx_image_at(&img, at[q][0] + di, at[q][1] + dj, 2)] = 1;
    /* plane 3 joins them */
    for (size_t j = 1; j < 16; j++)
        for (size_t i = 0; i < 16; i++) img.v[thx_image_at(&img, i, j, 3)] = 1;
    double z2 = 0, z0 = 0;
    long one = 1;
    thx_trace_tissue t = tissue(&one, 1, "lung", THX_ROLE_LUNG);
    thx_contours *c = NULL;
    thx_trace_report rep;
    CHECK_OK(ctx, trace(&img, &t, 1, 0, THX_TRACE_HOLES_FILL, &c, &rep));
    size_t kept = most_loops(c, &z0), tiny = rep.tissue[0].n_tiny;
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    thx_trace_opts o;
    thx_trace_opts_default(&o);
    o.tissues = &t;
    o.n_tissues = 1;
    o.min_size = 0;
    CHECK_OK(ctx, thx_image_trace(ctx, &img, &o, &c, &rep));
    size_t all = most_loops(c, &z2);
    printf("pinched bead: plane z=%g keeps %zu loops of %zu (%zu beads dropped in all)\n", z2, kept, all, tiny);
    CHECK(all == 4);
    CHECK(kept == 3 && z0 == z2);
    CHECK(tiny >= 1);
    CHECK(rep.tissue[0].n_tiny == 0);
    thx_trace_report_free(&rep);
    thx_contours_destroy(&c);
    thx_image_free(&img);
}

int main(void)
{
    thx_ctx_create(&ctx);
    if (tl_scratch_make("test_image_trace") != 0) return 1;
    test_image_line();
    test_sphere(1.0, 0);
    test_sphere(2.0, 0);
    test_sphere(5.0, 0);
    test_sphere(2.0, 5.0); /* planes resampled 5 mm apart */
    test_torus();
    test_islands_noise_nesting();
    test_split_caps();
    test_oblique_flipped();
    test_refusals();
    test_cut_ends();
    test_siblings();
    test_tiny_loops();
    test_pinch_beads();
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("test_image_trace");
}
