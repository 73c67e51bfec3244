/* A program built against the installed library only (tests/e2e_install.sh): reads a map3d .pts/.fac
 * surface with thorax's reader and prints what thorax computes of it, for the test to compare with
 * an independent computation.
 *   usage: surface_facts PTS FAC
 *   prints: nodes N, triangles T, base B (the .fac index base detected), volume V (mm^3, enclosed,
 *           positive when outward-oriented), euler X (V - E + F; 2 for a closed sphere-like surface) */
#include <stdio.h>
#include <stdlib.h>

#include <thorax/capi/capi.h>
#include <thorax/core/core.h>
#include <thorax/io/model_dir.h>
#include <thorax/model/surface.h>

static int cmp_edge(const void *a, const void *b)
{
    const long long *x = a, *y = b;
    return *x < *y ? -1 : *x > *y;
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: surface_facts PTS FAC\n");
        return 2;
    }
    thx_ctx *ctx = NULL;
    thx_surface *s = NULL;
    int base = -1;
    if (thx_ctx_create(&ctx) != THX_OK) return 1;
    thx_status st = thx_surface_read_ptsfac(ctx, argv[1], argv[2], "surface", THX_ROLE_OUTER, &s, &base);
    if (st != THX_OK) {
        fprintf(stderr, "surface_facts: %s\n", thx_ctx_message(ctx));
        thx_ctx_destroy(&ctx);
        return 1;
    }
    /* distinct undirected edges, for the Euler characteristic */
    size_t ne = 3 * s->n_tris, distinct = 0;
    long long *e = malloc(ne * sizeof *e);
    for (size_t t = 0; t < s->n_tris; t++)
        for (int k = 0; k < 3; k++) {
            long long a = s->tri[3 * t + k], b = s->tri[3 * t + (k + 1) % 3];
            e[3 * t + (size_t)k] = a < b ? a * 1000000 + b : b * 1000000 + a;
        }
    qsort(e, ne, sizeof *e, cmp_edge);
    for (size_t i = 0; i < ne; i++) distinct += i == 0 || e[i] != e[i - 1];
    free(e);
    printf("thorax %s\n", thx_capi_version());
    printf("nodes %zu\ntriangles %zu\nbase %d\nvolume %.3f\neuler %ld\n", s->n_nodes, s->n_tris, base,
           thx_surface_volume(s), (long)s->n_nodes - (long)distinct + (long)s->n_tris);
    thx_surface_destroy(&s);
    thx_ctx_destroy(&ctx);
    return 0;
}
