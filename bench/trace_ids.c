/*
 * Benchmark of primary rays (issue 27 item 5): the id image of a model's surfaces (thx_raytrace_ids:
 * the surface and the triangle each pixel's eye ray meets first, one ray a pixel, in packets of 16
 * along a row), the work Embree's own viewer does with its primID shader. Prints the median of N
 * calls (the first, which builds the surfaces' BVHs, left out) in ms and in rays a second.
 * Built with the project; run by bench/trace.sh beside the viewer on the same surfaces and camera:
 *
 *   trace_ids MODEL_DIR W H EYE_X,EYE_Y,EYE_Z CENTRE_X,CENTRE_Y,CENTRE_Z UP_X,UP_Y,UP_Z FOV_DEG [N]
 */
#include <stdio.h>
#include <stdlib.h>

#include "thorax/io/model_dir.h"
#include "thorax/raytrace/raytrace.h"

static int die(thx_ctx *ctx, const char *what)
{
    fprintf(stderr, "trace_ids: %s: %s\n", what, thx_ctx_message(ctx));
    return 1;
}

static int cmp_dbl(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static int vec3(const char *s, double v[3]) { return sscanf(s, "%lf,%lf,%lf", &v[0], &v[1], &v[2]) == 3; }

int main(int argc, char **argv)
{
    thx_camera cam = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, 0, 0};
    if (argc < 8 || !vec3(argv[4], cam.eye) || !vec3(argv[5], cam.center) || !vec3(argv[6], cam.up)) {
        fprintf(stderr, "usage: trace_ids MODEL_DIR W H EYE CENTRE UP FOV_DEG [N]  (EYE etc. as x,y,z)\n");
        return 2;
    }
    int w = atoi(argv[2]), h = atoi(argv[3]), n = argc > 8 ? atoi(argv[8]) : 10;
    cam.fov_deg = atof(argv[7]);
    if (w < 1 || h < 1 || n < 1) return 2;
    thx_ctx *ctx = NULL;
    if (thx_ctx_create(&ctx)) return 1;
    thx_model *m = NULL;
    if (thx_model_read(ctx, argv[1], &m)) return die(ctx, argv[1]);
    thx_render_surface *rs = calloc(m->n_surfaces, sizeof *rs);
    int32_t *sid = malloc((size_t)w * (size_t)h * sizeof *sid), *tid = malloc((size_t)w * (size_t)h * sizeof *tid);
    double *t = malloc((size_t)(n + 1) * sizeof *t);
    if (!rs || !sid || !tid || !t) return 1;
    size_t tris = 0;
    for (size_t s = 0; s < m->n_surfaces; s++) {
        rs[s].surf = m->surf[s];
        rs[s].mode = THX_DRAW_PHONG;
        tris += m->surf[s]->n_tris;
    }
    thx_scene sc = {.surfaces = rs, .n_surfaces = m->n_surfaces, .camera = cam};
    thx_tracer *tr = NULL;
    if (thx_tracer_create(ctx, &tr)) return die(ctx, "Embree");
    for (int k = 0; k <= n; k++) {
        double t0 = thx_wtime();
        if (thx_raytrace_ids(ctx, tr, &sc, w, h, sid, tid)) return die(ctx, "id image");
        t[k] = thx_wtime() - t0;
    }
    size_t hit = 0;
    for (size_t i = 0; i < (size_t)w * (size_t)h; i++) hit += sid[i] >= 0;
    qsort(t + 1, (size_t)n, sizeof *t, cmp_dbl);
    double med = t[1 + n / 2];
    printf("id image: %zu surfaces, %zu triangles, %d x %d (%zu pixels on a surface): first %.1f ms, then median %.1f ms of %d, "
           "%.1f M rays/s\n",
           m->n_surfaces, tris, w, h, hit, 1000 * t[0], 1000 * med, n, (double)w * h / med / 1e6);
    thx_tracer_destroy(&tr);
    free(t);
    free(sid);
    free(tid);
    free(rs);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return 0;
}
