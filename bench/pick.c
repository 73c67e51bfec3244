/*
 * Benchmark of picking (thorax/geom/pick.h) on the high-resolution phantom built in memory (six
 * surfaces, ~42,000 nodes, ~85,000 triangles): the index's build time, then N rays as a viewer
 * casts them (origins on a sphere of radius 1 m around the torso, aimed at random points of the
 * torso's box; a third of them with a clip plane through the middle): picks per second and the
 * time per pick with the index and with the brute force over every triangle (the answers compared),
 * and node picks (points) per second. Built and run by bench/pick.sh:
 *
 *   pick [N] [resolution: high|medium]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/geom/pick.h"
#include "thorax/geom/surfaces.h"
#include "thorax/phantom/phantom.h"

static unsigned long long rng = 7;
static double urand(void)
{
    unsigned long long z = (rng += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

static int die(thx_ctx *ctx, const char *what)
{
    fprintf(stderr, "pick bench: %s: %s\n", what, thx_ctx_message(ctx));
    return 1;
}

int main(int argc, char **argv)
{
    int n = argc > 1 ? atoi(argv[1]) : 2000;
    int high = !(argc > 2 && !strcmp(argv[2], "medium"));
    if (n < 1) n = 1;
    thx_ctx *ctx = NULL;
    if (thx_ctx_create(&ctx)) return 1;
    thx_phantom_opts po;
    thx_phantom_opts_default(&po);
    po.resolution = high ? THX_PHANTOM_HIGH : THX_PHANTOM_MEDIUM;
    thx_contours *c = NULL;
    if (thx_phantom_contours(ctx, &po, &c)) return die(ctx, "phantom");
    thx_surfaces_opts so;
    thx_surfaces_opts_default(&so);
    thx_model *m = NULL;
    if (thx_surfaces_build(ctx, c, &so, &m, NULL, NULL)) return die(ctx, "surfaces");
    thx_contours_destroy(&c);
    const thx_surface *const *surf = (const thx_surface *const *)m->surf;
    size_t ns = m->n_surfaces, nodes = 0, tris = 0;
    for (size_t s = 0; s < ns; s++) nodes += surf[s]->n_nodes, tris += surf[s]->n_tris;
    printf("model: %s-resolution phantom, %zu surfaces, %zu nodes, %zu triangles\n", high ? "high" : "medium", ns,
           nodes, tris);

    double t0 = thx_wtime();
    thx_pick_index *x = NULL;
    if (thx_pick_index_create(ctx, surf, ns, &x)) return die(ctx, "index");
    double t_build = thx_wtime() - t0;
    printf("index: built in %.1f ms (one bounding-volume hierarchy per surface)\n", 1e3 * t_build);

    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY}, ctr[3];
    for (size_t i = 0; i < surf[0]->n_nodes; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], surf[0]->xyz[3 * i + k]);
            hi[k] = fmax(hi[k], surf[0]->xyz[3 * i + k]);
        }
    for (int k = 0; k < 3; k++) ctr[k] = 0.5 * (lo[k] + hi[k]);
    double *o = malloc(3 * (size_t)n * sizeof(double)), *d = malloc(3 * (size_t)n * sizeof(double));
    thx_pick_hit *hi_idx = malloc((size_t)n * sizeof *hi_idx), *hi_bf = malloc((size_t)n * sizeof *hi_bf);
    if (!o || !d || !hi_idx || !hi_bf) return 1;
    for (int r = 0; r < n; r++) {
        double u[3], len = 0;
        for (int k = 0; k < 3; k++) u[k] = urand() - 0.5, len += u[k] * u[k];
        for (int k = 0; k < 3; k++) {
            o[3 * r + k] = ctr[k] + 1000 * u[k] / sqrt(len);
            d[3 * r + k] = lo[k] + urand() * (hi[k] - lo[k]) - o[3 * r + k];
        }
    }
    thx_pick_plane plane = {{0, 1, 0}, -ctr[1]}; /* keeps the anterior half */
    thx_pick_opts clip, none;
    thx_pick_opts_default(&none);
    thx_pick_opts_default(&clip);
    clip.clip = &plane;
    clip.n_clip = 1;

    int hits = 0;
    t0 = thx_wtime();
    for (int r = 0; r < n; r++) {
        if (thx_pick_ray(ctx, x, o + 3 * r, d + 3 * r, r % 3 == 0 ? &clip : &none, &hi_idx[r])) return die(ctx, "pick");
        hits += hi_idx[r].surface >= 0;
    }
    double t_idx = thx_wtime() - t0;
    int n_bf = n < 300 ? n : 300;
    t0 = thx_wtime();
    for (int r = 0; r < n_bf; r++)
        if (thx_pick_ray_brute(ctx, surf, ns, o + 3 * r, d + 3 * r, r % 3 == 0 ? &clip : &none, &hi_bf[r]))
            return die(ctx, "brute force");
    double t_bf = thx_wtime() - t0;
    int differ = 0;
    for (int r = 0; r < n_bf; r++)
        differ += hi_idx[r].surface != hi_bf[r].surface || hi_idx[r].tri != hi_bf[r].tri || hi_idx[r].t != hi_bf[r].t;
    printf("ray picks, index:       %d rays (%d hits), %.0f picks/s, %.1f us a pick\n", n, hits, n / t_idx,
           1e6 * t_idx / n);
    printf("ray picks, brute force: %d rays, %.0f picks/s, %.2f ms a pick; answers differing from the index: %d\n",
           n_bf, n_bf / t_bf, 1e3 * t_bf / n_bf, differ);
    /* node picks: a 5-pixel tolerance of an 800-pixel-high view of 400 mm (orthographic) */
    int n_node = n < 1000 ? n : 1000, found = 0;
    t0 = thx_wtime();
    for (int r = 0; r < n_node; r++) {
        thx_pick_hit h;
        if (thx_pick_node(ctx, x, o + 3 * r, d + 3 * r, 5 * 400.0 / 800, 0, &none, &h)) return die(ctx, "node pick");
        found += h.surface >= 0;
    }
    double t_node = thx_wtime() - t0;
    printf("node picks (points):    %d rays (%d found), %.0f picks/s, %.1f us a pick\n", n_node, found,
           n_node / t_node, 1e6 * t_node / n_node);
    printf("pick: %.1f us a pick with the index (%.0f /s), %.2f ms brute force (%.0f /s), index %.1f ms; target < 50 ms\n",
           1e6 * t_idx / n, n / t_idx, 1e3 * t_bf / n_bf, n_bf / t_bf, 1e3 * t_build);
    free(o);
    free(d);
    free(hi_idx);
    free(hi_bf);
    thx_pick_index_destroy(&x);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return differ != 0;
}
