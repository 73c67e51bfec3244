/* Point sets and the thorax side of bench/delaunay.sh.
 *
 *   delaunay_gen gen KIND N SEED OUT.node OUT.qh
 *       KIND cube:   N random points in a 100 mm cube (uniform, fixed seed);
 *       KIND layers: a thorax-like layered set (N ignored): 60 planes 5 mm
 *                    apart, a 5 mm grid inside a 330 x 220 mm ellipse, the
 *                    outer boundary loop and three inner loops (two lungs,
 *                    heart) per plane at ~2.5 mm spacing with 0.5 mm jitter.
 *       Writes the points as a TetGen .node file (1-based) and as qhull input.
 *   delaunay_gen run FILE.node [REPEAT]
 *       Reads the .node file, runs thx_delaunay3d REPEAT times (default 1) and
 *       prints "tets T seconds S" (best run) and the stage figures.
 * Built by bench/delaunay.sh against build/libthorax.a. */
#include "thorax/mesh/delaunay.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static uint64_t state;
static double urand(void)
{
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return (double)(state >> 11) / 9007199254740992.0;
}

static size_t add(double **p, size_t *cap, size_t n, double x, double y, double z)
{
    if (n == *cap) {
        *cap = *cap ? 2 * *cap : 1024;
        *p = realloc(*p, 3 * *cap * sizeof **p);
        if (!*p) { perror("realloc"); exit(1); }
    }
    (*p)[3 * n] = x; (*p)[3 * n + 1] = y; (*p)[3 * n + 2] = z;
    return n + 1;
}

static size_t loop(double **p, size_t *cap, size_t n, double cx, double cy, double ax, double by, double z)
{
    double perim = 3.14159265358979 * (3 * (ax + by) - sqrt((3 * ax + by) * (ax + 3 * by)));
    int m = (int)(perim / 2.5);
    for (int k = 0; k < m; k++) {
        double a = 2 * 3.14159265358979 * k / m;
        n = add(p, cap, n, cx + ax * cos(a) + 0.5 * (urand() - 0.5), cy + by * sin(a) + 0.5 * (urand() - 0.5), z);
    }
    return n;
}

static int gen(const char *kind, size_t n, uint64_t seed, const char *node, const char *qh)
{
    state = seed * 2654435761u + 88172645463325252ull;
    double *p = NULL;
    size_t cap = 0, m = 0;
    if (!strcmp(kind, "cube")) {
        for (size_t i = 0; i < n; i++) m = add(&p, &cap, m, 100 * urand(), 100 * urand(), 100 * urand());
    } else if (!strcmp(kind, "layers")) {
        for (int l = 0; l < 60; l++) {
            double z = 5.0 * l;
            for (int i = -33; i <= 33; i++)
                for (int j = -22; j <= 22; j++) {
                    double x = 5.0 * i, y = 5.0 * j;
                    if ((x * x) / (165.0 * 165.0) + (y * y) / (110.0 * 110.0) < 0.97) m = add(&p, &cap, m, x, y, z);
                }
            m = loop(&p, &cap, m, 0, 0, 165, 110, z);
            m = loop(&p, &cap, m, -70, 0, 45, 70, z);
            m = loop(&p, &cap, m, 70, 0, 45, 70, z);
            m = loop(&p, &cap, m, 0, 40, 40, 35, z);
        }
    } else {
        fprintf(stderr, "unknown kind %s\n", kind);
        return 1;
    }
    FILE *f = fopen(node, "w"), *g = fopen(qh, "w");
    if (!f || !g) { perror("open"); return 1; }
    fprintf(f, "%zu 3 0 0\n", m);
    fprintf(g, "3\n%zu\n", m);
    for (size_t i = 0; i < m; i++) {
        fprintf(f, "%zu %.17g %.17g %.17g\n", i + 1, p[3 * i], p[3 * i + 1], p[3 * i + 2]);
        fprintf(g, "%.17g %.17g %.17g\n", p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    }
    fclose(f);
    fclose(g);
    free(p);
    return 0;
}

static int run(const char *node, int repeat)
{
    FILE *f = fopen(node, "r");
    if (!f) { perror(node); return 1; }
    size_t n;
    int dim, na, nb;
    if (fscanf(f, "%zu %d %d %d", &n, &dim, &na, &nb) != 4 || dim != 3) { fprintf(stderr, "bad header\n"); return 1; }
    double *p = malloc(3 * n * sizeof *p);
    for (size_t i = 0; i < n; i++) {
        size_t id;
        if (fscanf(f, "%zu %lf %lf %lf", &id, &p[3 * i], &p[3 * i + 1], &p[3 * i + 2]) != 4) {
            fprintf(stderr, "bad line %zu\n", i);
            return 1;
        }
    }
    fclose(f);
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    double best = 1e30;
    size_t nt = 0;
    thx_delaunay_stats s, sb;
    memset(&sb, 0, sizeof sb);
    for (int r = 0; r < repeat; r++) {
        int32_t *t = NULL, *nbr = NULL;
        double t0 = thx_wtime();
        thx_status st = thx_delaunay3d(ctx, p, n, &t, &nbr, &nt, &s);
        double t1 = thx_wtime();
        if (st != THX_OK) { fprintf(stderr, "error: %s\n", thx_ctx_message(ctx)); return 1; }
        if (t1 - t0 < best) { best = t1 - t0; sb = s; }
        free(t);
        free(nbr);
    }
    printf("tets %zu seconds %.4f\n", nt, best);
    printf("stages: order %.3f s, insertion %.3f s, output %.3f s; walk %.1f steps/point, cavity %.1f tets/point, "
           "%zu perturbed in-sphere decisions, %zu hull faces\n",
           sb.t_sort, sb.t_insert, sb.t_output, (double)sb.walk_steps / n, (double)sb.cavity_tets / n, sb.n_degenerate,
           sb.n_hull_faces);
    thx_ctx_destroy(&ctx);
    free(p);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 7 && !strcmp(argv[1], "gen")) return gen(argv[2], strtoull(argv[3], NULL, 10), strtoull(argv[4], NULL, 10), argv[5], argv[6]);
    if (argc >= 3 && !strcmp(argv[1], "run")) return run(argv[2], argc >= 4 ? atoi(argv[3]) : 1);
    fprintf(stderr, "usage: delaunay_gen gen cube|layers N SEED OUT.node OUT.qh | run FILE.node [REPEAT]\n");
    return 2;
}
