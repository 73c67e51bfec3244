/* forward under mpirun with --volume: the volume potentials in parts, one per rank, into DIR/parts
 * (thorax/fem/parts.h; docs/formats.md, "Partitioned volume potentials"). */
#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli/cli.h"
#include "cli/cli_fem.h"
#include "thorax/core/fileio.h"
#include "thorax/fem/parts.h"
#include "thorax/parallel/parallel.h"

thx_status cli_forward_parts(thx_ctx *ctx, thx_outdir *od, const thx_model *m, const thx_series *volume, int rank, int ranks)
{
    thx_status st = thx_par_start(ctx, NULL, NULL); /* MPI is running (PETSc's): the ranks' calls */
    if (st != THX_OK) return st;
    char dir[4300] = "";
    /* rank 0 begins the output and makes DIR/parts; the others learn where */
    if (rank == 0) {
        st = thx_outdir_begin(ctx, od);
        if (st == THX_OK && (size_t)snprintf(dir, sizeof dir, "%s/parts", od->tmp) >= sizeof dir)
            st = thx_error(ctx, THX_EIO, "%s: the path is too long", od->tmp);
        if (st == THX_OK && mkdir(dir, 0755) != 0) st = thx_error(ctx, THX_EIO, "%s: cannot create the directory", dir);
    }
    st = thx_par_agree(ctx, st, NULL);
    if (st == THX_OK) st = thx_par_bcast(ctx, dir, sizeof dir, 0);
    if (st != THX_OK) return st;
    /* the same boxes on every rank: the active nodes (the heart's cavity left out, as the solve does),
       balanced on their count */
    const thx_volume *v = m->volume;
    unsigned char *use = malloc(v->n_regions ? v->n_regions : 1), *kind = NULL;
    int32_t *part = malloc((v->n_nodes ? v->n_nodes : 1) * sizeof *part);
    thx_fem_cut *cuts = malloc((size_t)ranks * sizeof *cuts);
    thx_fem_part p;
    memset(&p, 0, sizeof p);
    if (!use || !part || !cuts) st = thx_error(ctx, THX_ENOMEM, "out of memory (the volume's parts)");
    for (size_t r = 0; st == THX_OK && r < v->n_regions; r++) use[r] = strcmp(v->regions[r].name, "heart") != 0;
    size_t active = 0; /* the tetrahedra the parts must hold between them, each once */
    for (size_t t = 0; st == THX_OK && t < v->n_tets; t++) {
        int32_t r = v->region[t];
        active += r >= 0 && (size_t)r < v->n_regions && use[r];
    }
    if (st == THX_OK) st = thx_fem_active_nodes(ctx, v, use, &kind);
    if (st == THX_OK) st = thx_fem_partition_cuts(ctx, v, kind, ranks, part, cuts);
    if (st == THX_OK) st = thx_fem_part_make(ctx, v, use, cuts, ranks, rank, volume->v, volume->n_frames, &p);
    char path[4400];
    snprintf(path, sizeof path, "%s/part_%04d.bin", dir, rank);
    if (st == THX_OK) st = thx_fem_part_write(ctx, path, &p);
    long long counts[2] = {(long long)p.n_own, 0};
    thx_fem_part_free(&p);
    free(use);
    free(kind);
    free(part);
    free(cuts);
    st = thx_par_agree(ctx, st, NULL); /* every part written */
    if (st == THX_OK) st = thx_par_sum(ctx, counts, 1);
    if (st == THX_OK && rank == 0 && (size_t)counts[0] != active) /* every tetrahedron in exactly one part */
        st = thx_error(ctx, THX_EINTERNAL, "parts: %lld tetrahedra in the parts, %zu in the volume", counts[0], active);
    if (st == THX_OK && rank == 0) { /* the parts' own manifest */
        cJSON *j = cJSON_CreateObject(), *files = cJSON_AddArrayToObject(j, "files");
        cJSON_AddStringToObject(j, "format", "thorax-parts");
        cJSON_AddNumberToObject(j, "version", 2);
        cJSON_AddNumberToObject(j, "ranks", ranks);
        cJSON_AddStringToObject(j, "partition", "recursive coordinate bisection of the active nodes; each tetrahedron in "
                                "the box of its centroid, with a layer of ghosts (the tetrahedra sharing a node)");
        cJSON_AddNumberToObject(j, "tetrahedra", (double)counts[0]); /* owned: each once */
        cJSON_AddStringToObject(j, "unit", volume->unit); /* the values' (a reader of the parts alone labels with it) */
        for (int r = 0; r < ranks; r++) {
            char name[32];
            snprintf(name, sizeof name, "part_%04d.bin", r);
            cJSON_AddItemToArray(files, cJSON_CreateString(name));
        }
        char *text = cJSON_Print(j);
        cJSON_Delete(j);
        snprintf(path, sizeof path, "%s/parts.json", dir);
        thx_atomic_file af;
        st = text ? thx_atomic_open(ctx, path, &af) : THX_ENOMEM;
        if (st == THX_OK) {
            fprintf(af.f, "%s\n", text);
            st = thx_atomic_commit(ctx, &af);
        }
        free(text);
    }
    return st;
}
