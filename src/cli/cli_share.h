/* Sort-first rendering for thorax render, trace and animate under mpirun (thorax/parallel/parallel.h):
 * one picture's pixels shared among the ranks and gathered on rank 0, which writes. */
#ifndef THORAX_CLI_SHARE_H
#define THORAX_CLI_SHARE_H
#include "cli/render_cli.h"
#include "thorax/parallel/parallel.h"

/* Starts the ranks (MPI when mpirun started more than one): 0, or the exit code after printing why.
 * On a rank but 0, *verbose becomes -1 (rank 0 alone reports). */
int cli_share_start(const char *cmd, int *verbose);

/* Collective: frame's picture into img, the whole by one rank, or each rank's share of its pixels
 * (thx_picture_draw_share) gathered on rank 0 and annotated there; img holds the picture on rank 0
 * alone. The status is every rank's (thx_par_agree). */
thx_status cli_share_picture(thx_ctx *ctx, const thx_picture_opts *p, thx_picture_data *d, thx_renderer *rr,
                             thx_font *font, int frame, thx_raster *img, size_t *nan);

/* Collective, the end of the command: every rank's st agreed, a failure printed once (by the lowest
 * rank that failed, with its own message), MPI ended. Returns the exit code (1 on every rank when any
 * failed). */
int cli_share_end(thx_ctx *ctx, const char *cmd, thx_status st);
#endif
