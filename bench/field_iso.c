/* bench/field.sh's thorax side: equipotential surfaces of a solution's volume potentials timed in
 * memory (thx_field_isosurface alone, the solution read first), beside VTK's filter timed the same
 * way (bench/field_vtk.py).
 *
 * usage: field_iso SOLUTION FRAME VALUES REPEATS [LOOP_FRAMES LOOP_SPEC]
 *   FRAME 1-based; VALUES as thorax field --isosurface (a list, a count, percentages); the best of
 *   REPEATS runs is printed with the triangle count and the area of each value; then, if given,
 *   LOOP_FRAMES frames (cycling through the series) with LOOP_SPEC's values each (geometry only).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "thorax/field/field.h"
#include "thorax/io/solution_file.h"

int main(int argc, char **argv)
{
    if (argc != 5 && argc != 7) {
        fprintf(stderr, "usage: field_iso SOLUTION FRAME VALUES REPEATS [LOOP_FRAMES LOOP_SPEC]\n");
        return 2;
    }
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    thx_model *m = NULL;
    thx_series *s = NULL;
    if (thx_solution_read_volume(ctx, argv[1], &m, &s, NULL, 0)) {
        fprintf(stderr, "field_iso: %s\n", thx_ctx_message(ctx));
        return 1;
    }
    const thx_volume *v = m->volume;
    size_t f = (size_t)atol(argv[2]) - 1, reps = (size_t)atol(argv[4]);
    if (f >= s->n_frames) f = s->n_frames - 1;
    const double *phi = s->v + f * s->n_rows;
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < v->n_nodes; i++) lo = fmin(lo, phi[i]), hi = fmax(hi, phi[i]);
    double *val = NULL;
    size_t nv = 0;
    if (thx_field_values_parse(ctx, argv[3], lo, hi, &val, &nv)) {
        fprintf(stderr, "field_iso: %s\n", thx_ctx_message(ctx));
        return 1;
    }
    thx_field_mesh *mesh = NULL;
    thx_field_mesh_create(ctx, &mesh);
    double best = INFINITY;
    for (size_t r = 0; r < reps; r++) {
        thx_field_mesh_clear(mesh);
        double t0 = thx_wtime();
        if (thx_field_isosurface(ctx, v, phi, val, nv, NULL, mesh)) {
            fprintf(stderr, "field_iso: %s\n", thx_ctx_message(ctx));
            return 1;
        }
        best = fmin(best, thx_wtime() - t0);
    }
    printf("thorax: %zu nodes, %zu tetrahedra, frame %zu, %zu values: best of %zu %.4f s, %zu triangles, %zu points\n",
           v->n_nodes, v->n_tets, f + 1, nv, reps, best, mesh->n_tris, mesh->n_points);
    for (size_t k = 0; k < nv; k++) {
        size_t n = 0;
        for (size_t t = 0; t < mesh->n_tris; t++) n += mesh->tag[t] == (int32_t)k;
        printf("thorax value %.17g: %zu triangles, area %.15g mm^2\n", val[k], n, thx_field_mesh_area(mesh, (int)k));
    }
    if (argc == 7) {
        size_t nf = (size_t)atol(argv[5]);
        double t0 = thx_wtime();
        size_t tris = 0;
        for (size_t k = 0; k < nf; k++) {
            const double *p = s->v + (k % s->n_frames) * s->n_rows;
            double l = INFINITY, h = -INFINITY, *vv = NULL;
            size_t n = 0;
            for (size_t i = 0; i < v->n_nodes; i++) l = fmin(l, p[i]), h = fmax(h, p[i]);
            thx_field_mesh_clear(mesh);
            if (h > l && thx_field_values_parse(ctx, argv[6], l, h, &vv, &n) == THX_OK)
                thx_field_isosurface(ctx, v, p, vv, n, NULL, mesh);
            tris += mesh->n_tris;
            free(vv);
        }
        double t = thx_wtime() - t0;
        printf("thorax loop: %zu frames x \"%s\": %.3f s (%.2f ms a frame), %zu triangles in all\n", nf, argv[6], t,
               1000 * t / (double)nf, tris);
    }
    free(val);
    thx_field_mesh_destroy(&mesh);
    thx_series_destroy(&s);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return 0;
}
