/* thorax field's cuts (cmd_field.c): what one run asks for, and the steps the whole solution (one
 * process) and its parts (under mpirun, cli_field_parts.c) share, so that both make the same files
 * with the same messages. */
#ifndef THORAX_CLI_FIELD_H
#define THORAX_CLI_FIELD_H

#include <stddef.h>

#include "thorax/field/field.h"
#include "thorax/field/streamline.h"

#define CLI_FIELD_MAX_SLICES 64

/* What one run makes of each frame. */
typedef struct {
    const char *iso;           /* --isosurface SPEC, or NULL */
    const char *contours;      /* --contours SPEC, or NULL */
    thx_field_plane plane[CLI_FIELD_MAX_SLICES];
    const char *plane_text[CLI_FIELD_MAX_SLICES];
    size_t n_planes;
    const unsigned char *use;  /* per region */
} cli_field_request;

/* The values of SPEC for a frame whose potentials span [lo, hi] (*v, n of them, the caller's); a
 * frame of one value has none, with a warning naming what ("equipotential surface", "contour"). */
thx_status cli_field_values(thx_ctx *ctx, const char *spec, const char *what, double lo, double hi, double **v,
                            size_t *n);

/* The range of phi over the nodes of the tetrahedra of the regions cut (lo > hi: none). */
void cli_field_range(const thx_volume *v, const double *phi, const unsigned char *use, double *lo, double *hi);

/* use[r] for each of v's regions (only the table is read): the solution's domain, or the n_regions
 * names given (--region), one unknown named with the model's list. */
thx_status cli_field_use(thx_ctx *ctx, const char *sol, const thx_volume *v, const char *const *regions, int n_regions,
                         unsigned char *use);

/* The refusals of empty results (issue 24), before anything is written: a plane whose span
 * (span[2 p], span[2 p + 1]: the least and largest signed distance of the regions' nodes) leaves the
 * regions on one side, a value outside the range of every frame asked for (frame_lo/hi[k] of the
 * nsel frames frame[k]); a value outside some frames' range only is a warning. */
thx_status cli_field_check_empty(thx_ctx *ctx, const char *sol, const size_t *frame, size_t nsel,
                                 const cli_field_request *rq, const double *frame_lo, const double *frame_hi,
                                 const double *span);

/* The files of a run: OUT itself (single: OUT.vtp or OUT.obj, one frame), or OUT/field_FFFF.vtp per
 * frame and OUT/field.pvd (names[nsel]). */
typedef struct {
    const char *out;
    int single, obj;
    size_t n_names;
    char **names;
} cli_field_files;

/* Names the files of the nsel frames frame[k] (of n_frames). */
thx_status cli_field_files_name(thx_ctx *ctx, const char *out, const size_t *frame, size_t nsel, size_t n_frames,
                                cli_field_files *f);
/* Claims every file (nothing written yet), then makes OUT's directory for several frames. */
thx_status cli_field_files_claim(thx_ctx *ctx, const cli_field_files *f);
void cli_field_files_free(cli_field_files *f);

/* Writes frame k's cut (the file's frame number frame_no, 0-based; its time): per tag its value
 * (iso[0..ni), then n_planes planes), jm the |J| of each tetrahedron mesh->cell names, cv the
 * contour values; refuses a single file with nothing in it; logs the frame's counts. *tris grows
 * by the triangles written. */
thx_status cli_field_write(thx_ctx *ctx, const char *sol, const cli_field_files *f, size_t k, size_t frame_no,
                           const thx_field_mesh *mesh, const double *iso, size_t ni, size_t n_planes, const double *cv,
                           const double *jm, double time, size_t *tris);
/* The series' .pvd (several frames; nothing for a single file). */
thx_status cli_field_pvd(thx_ctx *ctx, const cli_field_files *f, const double *times, size_t nsel);

/*
 * thorax field under mpirun (cli_field_parts.c): each rank cuts its part of a solution in parts for
 * exactly as many ranks, rank 0 puts the ranks' own triangles together into the one process's cut,
 * computes the contours and writes. The exit status; every message printed once.
 */
int cli_field_parts(const char *cmd, const char *sol, cli_field_request *rq, const char *const *regions, int n_regions,
                    const char *frames, const char *out, int verbose);

/* thorax field --streamlines under mpirun on a solution in parts for as many ranks: the lines traced
 * across the parts (thx_streamlines_trace_parts), written by rank 0: the one process's file. Seeds
 * from point:, line: and sphere: specs only (region: and density: refused). Exit code, every rank. */
int cli_field_streamlines_parts(const char *cmd, const char *sol, const thx_seed_spec *specs, int n_specs,
                                const thx_stream_opts *so, int frame, double tubes, int sides, int caps, const char *out,
                                int verbose);

/* Under mpirun, a rank but 0 (the launcher's numbering) says nothing while the command line is
 * checked (every rank checks the same line: rank 0 speaks for all): mute 1 before, 0 after. */
void cli_field_mute(int mute);

#endif
