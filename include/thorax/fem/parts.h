/*
 * thorax/fem/parts.h — a solution's volume potentials in parts, one per MPI rank (sort-last's data,
 * docs/design/parallel.md): the tetrahedra whose centroid lies in the rank's box of a bisection
 * (thx_fem_partition_cuts), their nodes (global numbers, coordinates) and the nodes' values at every
 * frame, in one file per part (docs/formats.md, "Partitioned volume potentials"). A rank reads its
 * part alone; one process can read them all back into the whole.
 */
#ifndef THORAX_FEM_PARTS_H
#define THORAX_FEM_PARTS_H

#include <stddef.h>
#include <stdint.h>

#include "thorax/fem/fem.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    uint32_t rank, ranks;
    size_t n_nodes, n_tets, n_frames;
    size_t n_own;           /* the tetrahedra owned (owner == rank); the others are ghosts */
    size_t n_global;        /* the whole volume's nodes */
    size_t n_global_tets;   /* the whole volume's tetrahedra */
    thx_fem_cut *cuts;      /* ranks - 1 */
    int32_t *node;          /* the part's nodes' global numbers, ascending */
    double *xyz;            /* 3 per node */
    int32_t *tet;           /* 4 per tetrahedron, the part's own node numbers, in the whole's corner order */
    int32_t *region;        /* per tetrahedron */
    int32_t *tet_id;        /* per tetrahedron its number in the whole, ascending (own and ghosts mixed) */
    int32_t *owner;         /* per tetrahedron the part that owns it (rank: this part's own) */
    double *values;         /* frame after frame: n_frames x n_nodes */
} thx_fem_part;

/* Part rank of ranks: the tetrahedra of the volume whose region is used (use_region NULL: all)
 * and whose centroid thx_fem_cut_part puts in rank, with their ghosts (the used tetrahedra of other
 * parts that share a node with them or whose bounding box meets the part's box, thx_fem_cut_box), with the values of their nodes from values (n_frames frames
 * of v->n_nodes values each, as a series holds them). */
thx_status thx_fem_part_make(thx_ctx *ctx, const thx_volume *v, const unsigned char *use_region, const thx_fem_cut *cuts,
                             int ranks, int rank, const double *values, size_t n_frames, thx_fem_part *out);
/* Writes the part to path atomically (a temporary file renamed), with its SHA-256 at the end. */
thx_status thx_fem_part_write(thx_ctx *ctx, const char *path, const thx_fem_part *p);
/* Reads a part back whole, or fails naming the file and what is wrong (magic, sizes, a node or
 * tetrahedron out of range, numbers not ascending, an owner that is no part, the checksum): never a
 * part half-read. */
thx_status thx_fem_part_read(thx_ctx *ctx, const char *path, thx_fem_part *out);
void thx_fem_part_free(thx_fem_part *p);

/*
 * This rank's part of a solution's volume in parts, as a reader under mpirun takes it (sort-last
 * pictures, thorax field): manifest is what solution_dir/solution.json's "volume_parts" names
 * ("parts/parts.json"); the manifest is checked (format "thorax-parts", version 2, ranks parts,
 * one file each, the values' unit), part rank read (thx_fem_part_read) and found to be part rank
 * of ranks, each tetrahedron's region one of n_regions, with frames. unit (unit_size bytes) gets
 * the values' unit. On failure *out is empty and the message names the file and what is wrong.
 */
thx_status thx_fem_part_open(thx_ctx *ctx, const char *solution_dir, const char *manifest, int rank, int ranks,
                             size_t n_regions, thx_fem_part *out, char *unit, size_t unit_size);

#ifdef __cplusplus
}
#endif
#endif
