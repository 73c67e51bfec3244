/* --bad-leads FILE|auto, shared by forward, inverse, leads, render and view (src/cli/cli_bad_leads.c;
 * docs/cli.md "Bad leads"; the library is thorax/leads/bad_leads.h). A recording's bad channels are
 * either filled from their neighbours on the surface the series lies on (Laplacian interpolation,
 * as map3d does: forward's heart, leads' torso, render's and view's data surfaces) or left out
 * (inverse: the rows of the transfer matrix and of the data). FILE is a bad-lead list (thorax series
 * check -o FILE, or written by hand; channels 1-based, the recording's rows before --channels maps
 * them); "auto" runs the checks of `thorax series check` on the series itself. */
#ifndef THORAX_CLI_BAD_LEADS_H
#define THORAX_CLI_BAD_LEADS_H
#include "cli/options.h"
#include "thorax/core/core.h"
#include "thorax/model/series.h"
#include "thorax/model/model.h"
#include "thorax/model/surface.h"

/* The option's table entry (value into *spec); what: what the command does with them. */
#define CLI_BAD_LEADS_OPT(spec_ptr, what)                                                                            \
    {.name = "--bad-leads", .type = CLI_STRING, .meta = "FILE|auto", .s = (spec_ptr),                            \
     .help = "bad channels (a list from thorax series check -o, 1-based recording channels; or auto: run its "  \
             "checks here): " what}

/*
 * Fills the bad rows of s (rows = surf's nodes) by Laplacian interpolation on surf. channels: the
 * .channels file that mapped the recording's channels onto the nodes (NULL: row i is channel i + 1);
 * a listed channel no node takes is ignored (logged). Logs the channels filled (or "none").
 * spec NULL: does nothing.
 */
thx_status cli_bad_leads_fill(thx_ctx *ctx, const char *spec, const char *channels, const thx_surface *surf, thx_series *s);

/* The same on the model's surface of that role (forward: the heart); an error if it has none. */
thx_status cli_bad_leads_fill_role(thx_ctx *ctx, const char *spec, const char *channels, const thx_model *m, thx_role role,
                                   thx_series *s);

/*
 * Leaves the bad rows out of the data B (rows = leads = channels) and the same rows out of the
 * transfer matrix A (rows = leads); "auto" checks B without a surface (flat, saturated, exact
 * copies). Both are replaced by new series. spec NULL: does nothing.
 */
thx_status cli_bad_leads_drop(thx_ctx *ctx, const char *spec, thx_series **A, thx_series **B);
#endif
