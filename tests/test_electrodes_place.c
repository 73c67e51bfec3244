/*
 * Tests of electrodes anywhere on a surface, channel maps and lead links
 * (src/model/surface_nearest.c, electrodes_place.c, channels.c; src/io/map3d/channels.c,
 * electrodes_any.c; src/leads/leads.c), on the phantom's torso:
 *  - a field linear in space, given at the nodes, is reproduced exactly at
 *    electrodes between nodes (on a triangle, or off the surface and projected);
 *    the projection is the nearest surface point (checked against a dense sampling
 *    of every triangle) and never farther than the offset given;
 *  - a position within 1e-3 mm of a node becomes that node; one beyond
 *    --max-offset is refused, naming the electrode and the distance;
 *  - thx_electrodes_sample and thx_ecg12 weigh the triangle's rows; the file
 *    round trip keeps an off-node electrode ('-');
 *  - .channels: mapping, NaN for a node with no channel (none listed, 0 or
 *    negative), every malformed file refused with file:line;
 *  - .leadlinks: labels and nodes, 0-based files detected, errors with file:line;
 *  - thx_electrodes_load tells a thorax file, a .leadlinks, a node list and
 *    positions apart and refuses anything else.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/io/channels_file.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/leads/leads.h"
#include "thorax/model/channels.h"
#include "thorax/model/electrodes.h"
#include "thorax/model/model.h"

static thx_ctx *ctx;

static const thx_surface *outer_of(const thx_model *m)
{
    for (size_t s = 0; s < m->n_surfaces; s++)
        if (m->surf[s]->role == THX_ROLE_OUTER) return m->surf[s];
    return NULL;
}

static double lin(const double *x) { return 2.0 * x[0] - 3.0 * x[1] + 0.5 * x[2] + 7.0; }

/* A set of n off-node electrodes at the given positions on the outer surface. */
static thx_electrodes *off_nodes(const double *xyz, size_t n)
{
    thx_electrodes *e = NULL;
    if (thx_electrodes_create(ctx, n, &e) != THX_OK) return NULL;
    snprintf(e->surface, sizeof e->surface, "torso");
    for (size_t i = 0; i < n; i++) {
        snprintf(e->name[i], sizeof e->name[i], "P%zu", i + 1);
        e->node[i] = THX_ELECTRODE_OFF_NODE;
    }
    memcpy(e->xyz, xyz, 3 * n * sizeof *xyz);
    return e;
}

static void test_linear_field(const thx_model *m)
{
    const thx_surface *s = outer_of(m);
    enum { N = 60 };
    double p[3 * N], on[3 * N];
    double *u = malloc(s->n_nodes * sizeof *u);
    for (size_t k = 0; k < s->n_nodes; k++) u[k] = lin(s->xyz + 3 * k);
    /* points inside triangles spread over the surface; half of them 4 mm off along the normal */
    for (int i = 0; i < N; i++) {
        const int32_t *t = s->tri + 3 * ((size_t)i * s->n_tris / N + 1);
        const double *a = s->xyz + 3 * (size_t)t[0], *b = s->xyz + 3 * (size_t)t[1], *c = s->xyz + 3 * (size_t)t[2];
        double w0 = 0.15 + 0.5 * (i % 5) / 5.0, w1 = 0.2 + 0.3 * (i % 3) / 3.0, w2 = 1 - w0 - w1;
        double nrm[3] = {(b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]),
                         (b[2] - a[2]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[2] - a[2]),
                         (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])};
        double ln = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        for (int k = 0; k < 3; k++) {
            on[3 * i + k] = w0 * a[k] + w1 * b[k] + w2 * c[k];
            p[3 * i + k] = on[3 * i + k] + (i % 2 ? 4.0 * nrm[k] / ln : 0.0);
        }
    }
    thx_electrodes *e = off_nodes(p, N);
    double moved = -1;
    CHECK_OK(ctx, thx_electrodes_place(ctx, e, m, 5.0, &moved));
    CHECK(e->placed == 1);
    CHECK(moved > 3.0 && moved <= 4.0 + 1e-9);
    double err = 0, derr = 0, werr = 0, far = 0;
    int between = 0;
    for (int i = 0; i < N; i++) {
        /* the linear field at the projected point, exactly */
        err = fmax(err, fabs(thx_electrode_value(e, (size_t)i, u) - lin(e->xyz + 3 * i)));
        between += e->node[i] == THX_ELECTRODE_OFF_NODE;
        const double *w = e->weight + 3 * i;
        werr = fmax(werr, fabs(w[0] + w[1] + w[2] - 1));
        CHECK(w[0] >= 0 && w[1] >= 0 && w[2] >= 0);
        double d = sqrt(pow(e->xyz[3 * i] - p[3 * i], 2) + pow(e->xyz[3 * i + 1] - p[3 * i + 1], 2) +
                        pow(e->xyz[3 * i + 2] - p[3 * i + 2], 2));
        far = fmax(far, d);
        if (i % 2 == 0) derr = fmax(derr, d); /* on the surface: stays where it is */
        /* nearest: no point of a dense sampling of every triangle is nearer (by more than rounding) */
        if (i < 8) {
            double best = INFINITY;
            for (size_t t = 0; t < s->n_tris; t++) {
                const int32_t *T = s->tri + 3 * t;
                for (int a = 0; a <= 10; a++)
                    for (int b = 0; a + b <= 10; b++) {
                        double q[3];
                        for (int k = 0; k < 3; k++)
                            q[k] = (a * s->xyz[3 * (size_t)T[0] + k] + b * s->xyz[3 * (size_t)T[1] + k] +
                                    (10 - a - b) * s->xyz[3 * (size_t)T[2] + k]) / 10.0;
                        best = fmin(best, sqrt(pow(q[0] - p[3 * i], 2) + pow(q[1] - p[3 * i + 1], 2) + pow(q[2] - p[3 * i + 2], 2)));
                    }
            }
            CHECK(d <= best + 1e-9);
        }
    }
    printf("placed %d electrodes (%d between nodes): linear field error %.2e, weights sum error %.2e, moved <= %.3f mm\n", N,
           between, err, werr, far);
    CHECK(between > N / 2);
    CHECK(err < 1e-9);
    CHECK(werr < 1e-15);
    CHECK(derr < 1e-9);

    /* sampling a series: two frames, the second twice the first */
    thx_series *sr = NULL, *at = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, s->n_nodes, 2, &sr));
    for (size_t k = 0; k < s->n_nodes; k++) sr->v[k] = u[k], sr->v[s->n_nodes + k] = 2 * u[k];
    CHECK_OK(ctx, thx_electrodes_sample(ctx, e, sr, &at));
    if (at) {
        double se = 0;
        for (int i = 0; i < N; i++) {
            se = fmax(se, fabs(at->v[i] - lin(e->xyz + 3 * i)));
            se = fmax(se, fabs(at->v[N + i] - 2 * lin(e->xyz + 3 * i)));
        }
        CHECK(se < 1e-9);
    }
    thx_series_destroy(&at);
    /* an off-node set that was not placed is refused by the sampler */
    thx_electrodes *raw = off_nodes(p, 2);
    CHECK(thx_electrodes_sample(ctx, raw, sr, &at) == THX_EINPUT && strstr(thx_ctx_message(ctx), "not placed"));
    thx_electrodes_destroy(&raw);

    /* the file keeps an off-node electrode as '-' and reads back to the same placement */
    CHECK_OK(ctx, thx_electrodes_write(ctx, e, tl_path("off.txt")));
    char *text = tl_slurp(ctx, tl_path("off.txt"), NULL);
    CHECK(text && strstr(text, "\nP2 - ") != NULL);
    free(text);
    thx_electrodes *r = NULL;
    CHECK_OK(ctx, thx_electrodes_read(ctx, tl_path("off.txt"), &r));
    if (r) {
        CHECK(r->node[1] == THX_ELECTRODE_OFF_NODE);
        CHECK_OK(ctx, thx_electrodes_check(ctx, r, m));
        CHECK_OK(ctx, thx_electrodes_place(ctx, r, m, 0.001, NULL));
        double d = 0;
        for (size_t k = 0; k < 3 * (size_t)N; k++) d = fmax(d, fabs(r->weight[k] - e->weight[k]));
        CHECK(d < 1e-5); /* positions printed to 1e-6 mm */
    }
    thx_electrodes_destroy(&r);
    thx_series_destroy(&sr);
    thx_electrodes_destroy(&e);

    /* a position 1e-4 mm from a node is that node; one 12 mm off is refused */
    double q[6];
    memcpy(q, s->xyz + 3 * 17, 3 * sizeof *q);
    q[0] += 1e-4;
    const int32_t *t0 = s->tri;
    for (int k = 0; k < 3; k++) q[3 + k] = (s->xyz[3 * (size_t)t0[0] + k] + s->xyz[3 * (size_t)t0[1] + k]) / 2;
    e = off_nodes(q, 2);
    CHECK_OK(ctx, thx_electrodes_place(ctx, e, m, THX_ELECTRODE_MAX_OFFSET_MM, NULL));
    CHECK(e->node[0] == 17 && e->weight[0] == 1 && e->corner[0] == 17);
    CHECK(e->node[1] == THX_ELECTRODE_OFF_NODE); /* the middle of an edge */
    CHECK_NEAR(e->weight[3] + e->weight[4] + e->weight[5], 1, 1e-15);
    thx_electrodes_destroy(&e);
    /* far outside: the point 12 mm out along the x axis beyond the largest x */
    size_t ix = 0;
    for (size_t k = 1; k < s->n_nodes; k++)
        if (s->xyz[3 * k] > s->xyz[3 * ix]) ix = k;
    memcpy(q, s->xyz + 3 * ix, 3 * sizeof *q);
    q[0] += 12;
    e = off_nodes(q, 1);
    CHECK(thx_electrodes_place(ctx, e, m, 10, NULL) == THX_EINPUT);
    CHECK(strstr(thx_ctx_message(ctx), "electrode 1 (\"P1\")") && strstr(thx_ctx_message(ctx), "12 mm from surface"));
    CHECK(thx_electrodes_check(ctx, e, m) == THX_EINPUT);
    thx_electrodes_destroy(&e);
    free(u);
}

static void expect_fail_channels(const char *name, const char *text, const char *part)
{
    tl_write_text(tl_path(name), text);
    thx_channels *c = NULL;
    thx_status st = thx_channels_read(ctx, tl_path(name), &c);
    CHECK(st == THX_EINPUT && c == NULL);
    if (!strstr(thx_ctx_message(ctx), part)) {
        fprintf(stderr, "%s: message '%s' lacks '%s'\n", name, thx_ctx_message(ctx), part);
        CHECK(0);
    }
}

static void test_channels(void)
{
    tl_write_text(tl_path("a.channels"), "5 leads\n 1 3\n 3 10\n\n 2 1\n 5 0\n 4 -1\n");
    thx_channels *c = NULL;
    CHECK_OK(ctx, thx_channels_read(ctx, tl_path("a.channels"), &c));
    if (!c) return;
    CHECK(c->n == 5 && c->channel[0] == 2 && c->channel[1] == 0 && c->channel[2] == 9 && c->channel[3] == -1 &&
          c->channel[4] == -1);
    CHECK(thx_channels_unmapped(c) == 2);
    thx_series *rec = NULL, *out = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, 10, 3, &rec));
    for (size_t f = 0; f < 3; f++)
        for (size_t r = 0; r < 10; r++) rec->v[f * 10 + r] = 100.0 * (double)f + (double)r + 1;
    snprintf(rec->unit, sizeof rec->unit, "uV");
    CHECK_OK(ctx, thx_channels_apply(ctx, c, rec, &out));
    if (out) {
        CHECK(out->n_rows == 5 && out->n_frames == 3 && !strcmp(out->unit, "uV"));
        CHECK(out->v[5 + 0] == 103 && out->v[5 + 1] == 101 && out->v[5 + 2] == 110 && isnan(out->v[5 + 3]) &&
              isnan(out->v[5 + 4]));
    }
    thx_series_destroy(&out);
    /* a channel beyond the recording: the file's line named */
    thx_series *small = NULL;
    CHECK_OK(ctx, thx_series_create(ctx, 9, 1, &small));
    CHECK(thx_channels_apply(ctx, c, small, &out) == THX_EINPUT && out == NULL);
    CHECK(strstr(thx_ctx_message(ctx), "a.channels:3: channel 10 is not in 1..9 (the recording's rows; node 3)") != NULL);
    thx_series_destroy(&small);
    thx_series_destroy(&rec);
    thx_channels_destroy(&c);

    expect_fail_channels("e1.channels", "", "e1.channels:1: empty file");
    expect_fail_channels("e2.channels", "leads 5\n", "e2.channels:1: expected 'N leads'");
    expect_fail_channels("e3.channels", "2 leads\n1 5\n", "e3.channels:2: truncated: 1 of the 2");
    expect_fail_channels("e4.channels", "2 leads\n1 5\n1 6\n", "e4.channels:3: node 1 given twice (first on line 2)");
    expect_fail_channels("e5.channels", "2 leads\n1 5\n3 6\n", "e5.channels:3: node 3 is not in 1..2");
    expect_fail_channels("e6.channels", "1 leads\n1 5\n2 6\n", "e6.channels:3: more than the 1 lines");
    expect_fail_channels("e7.channels", "1 leads\n1 x\n", "e7.channels:2: line 1 of 1: expected 'NODE CHANNEL'");
    expect_fail_channels("e8.channels", "1 leads\n1 5 7\n", "e8.channels:2: line 1 of 1");
    tl_write_bytes(tl_path("e9.channels"), "1 leads\n1\0 5\n", 13);
    thx_channels *z = NULL;
    CHECK(thx_channels_read(ctx, tl_path("e9.channels"), &z) == THX_EINPUT && strstr(thx_ctx_message(ctx), ":2: NUL byte"));
}

static void test_leadlinks(const thx_model *m)
{
    const thx_surface *s = outer_of(m);
    char text[256];
    snprintf(text, sizeof text, "3 leads\n  1  5\n  V1 %zu\n  x.2 1\n", s->n_nodes);
    tl_write_text(tl_path("a.leadlinks"), text);
    thx_electrodes *e = NULL;
    CHECK_OK(ctx, thx_leadlinks_read(ctx, tl_path("a.leadlinks"), s, &e));
    if (e) {
        CHECK(e->n == 3 && !strcmp(e->name[0], "1") && !strcmp(e->name[1], "V1") && !strcmp(e->name[2], "x.2"));
        CHECK(e->node[0] == 4 && e->node[1] == (int32_t)s->n_nodes - 1 && e->node[2] == 0);
        CHECK(!memcmp(e->xyz + 3, s->xyz + 3 * (s->n_nodes - 1), 3 * sizeof(double)));
        CHECK_OK(ctx, thx_electrodes_check(ctx, e, m));
    }
    thx_electrodes_destroy(&e);
    /* a node 0: the file is 0-based (map3d's rule) */
    tl_write_text(tl_path("z.leadlinks"), "2 leads\n1 0\n2 5\n");
    CHECK_OK(ctx, thx_leadlinks_read(ctx, tl_path("z.leadlinks"), s, &e));
    CHECK(e && e->node[0] == 0 && e->node[1] == 5);
    thx_electrodes_destroy(&e);
    snprintf(text, sizeof text, "2 leads\n1 4\n2 %zu\n", s->n_nodes + 1);
    tl_write_text(tl_path("b.leadlinks"), text);
    CHECK(thx_leadlinks_read(ctx, tl_path("b.leadlinks"), s, &e) == THX_EINPUT && !e);
    snprintf(text, sizeof text, "b.leadlinks:3: lead 2 (\"2\"): node %zu is not on surface \"torso\"", s->n_nodes + 1);
    CHECK(strstr(thx_ctx_message(ctx), text) != NULL);
    tl_write_text(tl_path("c.leadlinks"), "2 leads\n1 4\n1 5\n");
    CHECK(thx_leadlinks_read(ctx, tl_path("c.leadlinks"), s, &e) == THX_EINPUT &&
          strstr(thx_ctx_message(ctx), "c.leadlinks:3: lead 2: label \"1\" already used on line 2"));
    tl_write_text(tl_path("d.leadlinks"), "1 leads\nend 4\n");
    CHECK(thx_leadlinks_read(ctx, tl_path("d.leadlinks"), s, &e) == THX_EINPUT &&
          strstr(thx_ctx_message(ctx), "d.leadlinks:2: lead 1: label \"end\" is a keyword"));
    tl_write_text(tl_path("n.leadlinks"), "1 leads\nA -1\n");
    CHECK(thx_leadlinks_read(ctx, tl_path("n.leadlinks"), s, &e) == THX_EINPUT &&
          strstr(thx_ctx_message(ctx), "n.leadlinks:2: lead 1 (\"A\"): node -1 is negative"));
}

static void test_load(const thx_model *m)
{
    const thx_surface *s = outer_of(m);
    thx_electrodes *e = NULL;
    thx_electrodes_kind k = THX_ELECTRODES_FILE;
    tl_write_text(tl_path("nodes.txt"), "# three nodes\n3\n\n9\n4 # a comment\n");
    CHECK_OK(ctx, thx_electrodes_load(ctx, tl_path("nodes.txt"), m, NULL, 10, &e, &k, NULL));
    CHECK(e && k == THX_ELECTRODES_NODES && e->n == 3 && e->node[1] == 8 && !strcmp(e->name[2], "N4"));
    thx_electrodes_destroy(&e);
    CHECK_OK(ctx, thx_electrodes_load(ctx, tl_path("a.leadlinks"), m, NULL, 10, &e, &k, NULL));
    CHECK(e && k == THX_ELECTRODES_LEADLINKS && e->n == 3);
    thx_electrodes_destroy(&e);
    /* positions: two nodes exactly and a triangle's centroid */
    char text[512];
    const int32_t *t = s->tri + 3 * 7;
    double cen[3];
    for (int q = 0; q < 3; q++)
        cen[q] = (s->xyz[3 * (size_t)t[0] + q] + s->xyz[3 * (size_t)t[1] + q] + s->xyz[3 * (size_t)t[2] + q]) / 3;
    snprintf(text, sizeof text, "%.17g %.17g %.17g\n%.17g %.17g %.17g\n%.17g %.17g %.17g\n", s->xyz[30], s->xyz[31],
             s->xyz[32], cen[0], cen[1], cen[2], s->xyz[3], s->xyz[4], s->xyz[5]);
    tl_write_text(tl_path("p.pts"), text);
    double moved = -1;
    CHECK_OK(ctx, thx_electrodes_load(ctx, tl_path("p.pts"), m, NULL, 10, &e, &k, &moved));
    CHECK(e && k == THX_ELECTRODES_POINTS && e->n == 3 && e->node[0] == 10 && e->node[2] == 1 &&
          e->node[1] == THX_ELECTRODE_OFF_NODE && !strcmp(e->name[1], "P2"));
    if (e) {
        int corners = 0;
        for (int q = 0; q < 3; q++)
            for (int r = 0; r < 3; r++) corners += e->corner[3 + q] == t[r];
        CHECK(corners == 3);
        for (int q = 0; q < 3; q++) CHECK_NEAR(e->weight[3 + q], 1.0 / 3, 1e-12);
        CHECK(moved < 1e-9);
    }
    thx_electrodes_destroy(&e);
    CHECK(thx_electrodes_load(ctx, tl_path("p.pts"), m, "nosuch", 10, &e, &k, NULL) == THX_EINPUT &&
          strstr(thx_ctx_message(ctx), "no surface \"nosuch\""));
    tl_write_text(tl_path("bad.txt"), "1 2\n");
    CHECK(thx_electrodes_load(ctx, tl_path("bad.txt"), m, NULL, 10, &e, &k, NULL) == THX_EINPUT && !e &&
          strstr(thx_ctx_message(ctx), "bad.txt:1: not an electrode file"));
    tl_write_text(tl_path("mixed.txt"), "3\n4 5 6\n");
    CHECK(thx_electrodes_load(ctx, tl_path("mixed.txt"), m, NULL, 10, &e, &k, NULL) == THX_EINPUT &&
          strstr(thx_ctx_message(ctx), "mixed.txt:2: a node list holds one node number"));
}

int main(void)
{
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    if (tl_scratch_make("test_electrodes_place")) return 1;
    thx_model *m = tl_phantom_surfaces(ctx);
    if (!m) return 1;
    test_linear_field(m);
    test_channels();
    test_leadlinks(m);
    test_load(m);
    thx_model_destroy(&m);
    int rc = tl_scratch_finish("test_electrodes_place");
    thx_ctx_destroy(&ctx);
    return rc;
}
