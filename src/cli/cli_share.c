/* Rendering shared among ranks for render, trace and animate (cli/cli_share.h): sort-first, or
 * sort-last when each rank reads its part of a partitioned solution. */
#include <stdio.h>
#include <stdlib.h>

#include "cli/cli.h"
#include "cli/cli_share.h"

int cli_share_start(const char *cmd, int *verbose)
{
    thx_ctx *ctx = cli_ctx(-1);
    int rank = 0, size = 1;
    thx_status st = thx_par_start(ctx, &rank, &size);
    int rc = st != THX_OK ? cli_fail(ctx, cmd, st) : 0;
    thx_ctx_destroy(&ctx);
    if (!rc && rank != 0) *verbose = -1;
    return rc;
}

thx_status cli_share_picture(thx_ctx *ctx, const thx_picture_opts *p, thx_picture_data *d, thx_renderer *rr,
                             thx_font *font, int frame, thx_raster *img, size_t *nan)
{
    int rank = thx_par_rank(), size = thx_par_size();
    if (size == 1) return thx_picture_draw(ctx, p, d, rr, font, frame, img, nan);
    thx_picture_bars bars;
    if (d->part_size > 1) { /* sort-last: each rank its part of the volume, composited on rank 0 */
        thx_status st = thx_picture_draw_part(ctx, p, d, rr, font, frame, img, &bars, nan);
        if (st == THX_OK && rank == 0 && font) st = thx_picture_bars_check(ctx, p, font, img->w, img->h, &bars);
        if (st == THX_OK && rank == 0) st = thx_picture_annotate(ctx, p, d, font, frame, &bars, img);
        return thx_par_agree(ctx, st, NULL);
    }
    unsigned char *own = thx_malloc(ctx, (size_t)img->w * (size_t)img->h);
    thx_status st = own ? thx_picture_draw_share(ctx, p, d, rr, font, frame, rank, size, img, own, &bars, nan) : THX_ENOMEM;
    st = thx_par_agree(ctx, st, NULL);
    if (st == THX_OK) st = thx_par_gather_pixels(ctx, img->rgba, own, img->w, img->h);
    if (st == THX_OK && rank == 0) st = thx_picture_annotate(ctx, p, d, font, frame, &bars, img);
    free(own);
    return thx_par_agree(ctx, st, NULL); /* rank 0's gather and annotations, known to all */
}

int cli_share_end(thx_ctx *ctx, const char *cmd, thx_status st)
{
    int first = -1;
    st = thx_par_agree(ctx, st, &first);
    if (thx_par_failed_first() >= 0) first = thx_par_failed_first(); /* the rank that failed, not an echo of it */
    int rc = 0;
    if (st != THX_OK) {
        rc = 1;
        if (first == thx_par_rank()) {
            if (thx_par_size() > 1) {
                char what[64];
                snprintf(what, sizeof what, "%s (rank %d of %d)", cmd, first, thx_par_size());
                cli_fail(ctx, what, st);
            } else {
                cli_fail(ctx, cmd, st);
            }
        }
    }
    thx_par_end();
    return rc;
}
