/* thorax series: time series files (rows x frames matrices with a time axis):
 * a summary of one, or a conversion between text, raw binary and MATLAB .mat. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli/cli.h"
#include "thorax/model/series.h"
#include "thorax/io/series_file.h"
#include "thorax/io/channels_file.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/surface_read.h"
#include "thorax/leads/bad_leads.h"

/* --surface MODEL:NAME (a surface of a model directory: *m holds it) or a surface file (FILE.pts
 * with its .fac, or any format thorax import reads: *own holds it). Caller destroys both. */
static thx_status check_surface(thx_ctx *ctx, const char *spec, thx_model **m, thx_surface **own, const thx_surface **out)
{
    *out = NULL;
    const char *colon = strrchr(spec, ':');
    if (colon && colon > spec) {
        char dir[1024], manifest[1100];
        snprintf(dir, sizeof dir, "%.*s", (int)(colon - spec), spec);
        snprintf(manifest, sizeof manifest, "%s/model.json", dir);
        FILE *f = fopen(manifest, "r");
        if (f) {
            fclose(f);
            THX_CHECK(thx_model_read(ctx, dir, m));
            for (size_t k = 0; k < (*m)->n_surfaces; k++)
                if (!strcmp((*m)->surf[k]->name, colon + 1)) *out = (*m)->surf[k];
            if (!*out) return thx_error(ctx, THX_EINPUT, "--surface %s: the model %s has no surface '%s'", spec, dir, colon + 1);
            return THX_OK;
        }
    }
    char name[64];
    const char *base = strrchr(spec, '/') ? strrchr(spec, '/') + 1 : spec;
    snprintf(name, sizeof name, "%.*s", (int)strcspn(base, ".@"), base);
    THX_CHECK(thx_surface_read_file(ctx, spec, NULL, THX_IMPORT_AUTO, name, THX_ROLE_OTHER, own, NULL));
    *out = *own;
    return THX_OK;
}

/* thorax series check: every row's scores, the bad ones, and the list written to out (if given). */
static thx_status series_check(thx_ctx *ctx, const char *in, const thx_series *s, const thx_surface *surf,
                               const thx_channels *ch, const char *out)
{
    thx_bad_leads *b = NULL;
    THX_CHECK(thx_bad_leads_detect(ctx, s, surf, NULL, &b));
    size_t n = s->n_rows;
    int *chan = malloc((n + 1) * sizeof *chan);
    if (!chan) {
        thx_bad_leads_destroy(&b);
        return thx_error(ctx, THX_ENOMEM, "out of memory");
    }
    for (size_t i = 0; i < n; i++) chan[i] = ch ? (int)ch->channel[i] + 1 : (int)i + 1;
    printf("file        %s\n", in);
    printf("rows        %zu %s\n", n, ch ? "(nodes of the channel map; 'channel' = the recording's row, 1-based)"
                                        : "(channels = rows, 1-based)");
    printf("surface     %s\n", surf ? surf->name : "(none: no neighbour checks)");
    printf("median rms  %.6g %s\n", b->median_rms, s->unit);
    printf("%8s %6s %11s %7s %8s %7s %8s %7s %7s %6s %3s  %s\n", "channel", "node", "rms", "extr%", "nearest", "d",
           "contrast", "unlike", "ratio", "corr", "nb", "verdict");
    char why[512];
    for (size_t i = 0; i < n; i++) {
        thx_bad_leads_reason(b, i, chan, why, sizeof why);
        if (chan[i] > 0) printf("%8d", (int)chan[i]);
        else printf("%8s", "-");
        printf(" %6zu", i + 1);
        if (b->missing[i]) {
            printf(" %11s %7s %8s %7s %8s %7s %7s %6s %3s  missing (NaN or Inf values)\n", "-", "-", "-", "-", "-", "-",
                   "-", "-", "-");
            continue;
        }
        printf(" %11.5g %7.2f", b->rms[i], 100 * b->extreme[i]);
        if (b->nearest[i] >= 0) printf(" %8d %7.4f", (int)chan[b->nearest[i]], b->d[i]);
        else printf(" %8s %7s", "-", "-");
        /* a score that does not apply (no duplicate to contrast, no neighbours) prints as '-', not nan */
        const double score[4] = {b->contrast[i], b->unlike[i], b->ratio[i], b->corr[i]};
        const int width[4] = {8, 7, 7, 6}, prec[4] = {3, 3, 3, 3};
        for (int k = 0; k < 4; k++) {
            if (isfinite(score[k])) printf(" %*.*f", width[k], prec[k], score[k]);
            else printf(" %*s", width[k], "-");
        }
        printf(" %3d  %s\n", (int)b->n_nb[i], b->flags[i] ? why : "ok");
    }
    printf("bad         %zu of %zu%s", b->n_bad, n, b->n_bad ? " (channels:" : "");
    for (size_t i = 0; i < n; i++)
        if (b->flags[i]) printf(" %d", (int)chan[i]);
    printf("%s\n", b->n_bad ? ")" : "");
    if (b->n_missing) printf("missing     %zu rows not checked (NaN or Inf values)\n", b->n_missing);
    thx_status st = THX_OK;
    if (out) {
        char note[1200];
        snprintf(note, sizeof note, "thorax series check %s%s%s", in, surf ? " on surface " : "", surf ? surf->name : "");
        st = thx_bad_list_write(ctx, out, b, chan, note);
        if (st == THX_OK) thx_log(ctx, THX_LOG_INFO, "wrote %s (%zu bad channel%s)", out, b->n_bad, b->n_bad == 1 ? "" : "s");
    }
    free(chan);
    thx_bad_leads_destroy(&b);
    return st;
}
/* map3d fiducials: one line each, values as frames counted from 0 (map3d's convention). */
static void print_fiducials(const thx_series *s)
{
    if (s->group[0]) printf("struct      %s (%zu fields kept)\n", s->group, s->n_fields);
    printf("fiducials   %zu%s\n", s->n_fids, s->n_fids ? " (frames counted from 0)" : "");
    for (size_t k = 0; k < s->n_fids; k++) {
        const thx_fiducial *f = &s->fids[k];
        const char *name = thx_fiducial_type_name(f->type);
        printf("  %-10s type %-3d", name ? name : "?", f->type);
        if (f->fidset) printf(" fidset %d", f->fidset);
        if (f->n == 1) {
            printf(" %.10g (one value)\n", f->v[0]);
            continue;
        }
        double lo = INFINITY, hi = -INFINITY;
        size_t nan = 0;
        for (size_t i = 0; i < f->n; i++) {
            if (!isfinite(f->v[i])) { nan++; continue; }
            if (f->v[i] < lo) lo = f->v[i];
            if (f->v[i] > hi) hi = f->v[i];
        }
        printf(" %zu values (one per row)", f->n);
        if (lo <= hi) printf(", %.10g .. %.10g", lo, hi);
        if (nan) printf(", %zu without a value", nan);
        printf("\n");
    }
}

static void print_info(const char *path, const thx_series *s)
{
    size_t N = s->n_rows, M = s->n_frames;
    printf("file        %s\n", path);
    printf("rows        %zu\n", N);
    printf("frames      %zu\n", M);
    const char *tu = s->time_unit[0] ? s->time_unit : "(no unit)";
    printf("time        %.10g .. %.10g %s", s->time[0], s->time[M - 1], tu);
    if (M >= 2) {
        double dt = s->time[1] - s->time[0];
        int uniform = 1;
        for (size_t f = 2; f < M && uniform; f++)
            uniform = fabs((s->time[f] - s->time[f - 1]) - dt) <= 1e-9 * fabs(dt);
        if (uniform) printf(" (step %.10g)", dt);
        else printf(" (non-uniform steps)");
    }
    printf("\n");
    printf("unit        %s\n", s->unit[0] ? s->unit : "(none)");
    printf("label       %s\n", s->label);
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < N * M; i++)
        if (isfinite(s->v[i])) {
            if (s->v[i] < lo) lo = s->v[i];
            if (s->v[i] > hi) hi = s->v[i];
        }
    if (lo <= hi) printf("min         %.10g\nmax         %.10g\n", lo, hi);
    else printf("min         (no finite value)\nmax         (no finite value)\n");
    size_t row = 0, frame = 0;
    size_t bad = thx_series_find_nonfinite(s, &row, &frame);
    if (bad) printf("non-finite  %zu (first: row %zu, frame %zu)\n", bad, row + 1, frame + 1);
    else printf("non-finite  0\n");
    print_fiducials(s);
}

int cmd_series(int argc, char **argv)
{
    const char *cmd = "series";
    const char *out = NULL, *fids = NULL, *channels = NULL, *surface = NULL;
    int verbose = 0, format = THX_SERIES_AUTO, transpose = 0;
    static const cli_choice formats[] = {{"text", THX_SERIES_TEXT}, {"raw", THX_SERIES_RAW}, {"mat", THX_SERIES_MAT},
                                         {"csv", THX_SERIES_CSV}, {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "OUT", .s = &out,
         .help = "file to write (convert; check: the bad-lead list)"},
        {.name = "--format", .type = CLI_CHOICE, .choices = formats, .i = &format, .def = "from OUT's extension",
         .help = "format of OUT (convert)"},
        {.name = "--fids", .type = CLI_INPUT, .meta = "FIDS", .s = &fids,
         .help = "add the fiducials of a map3d .fids file (one line per lead; its lead count must be the rows)"},
        {.name = "--transpose", .type = CLI_FLAG, .i = &transpose,
         .help = "swap rows and frames after reading (a matrix laid out frames x channels)"},
        {.name = "--channels", .type = CLI_INPUT, .meta = "FILE", .s = &channels,
         .help = "map3d .channels: IN's rows are recording channels; the series taken is one row per node of the "
                 "file (NaN for a node with no channel)"},
        {.name = "--surface", .type = CLI_STRING, .meta = "MODEL:NAME|FILE", .s = &surface,
         .help = "check: the surface whose nodes the rows are (after --channels): its neighbours judge each lead"},
        {.name = "-v", .type = CLI_COUNT, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_COUNT, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE, .help = "less logging"},
    };
    cli_command c = {
        .name = cmd,
        .usage = "info FILE [--fids] [--transpose] [--channels]\nconvert IN -o [--format] [--fids] [--transpose] [--channels]\n"
                 "check SERIES [--surface] [--channels] [-o] [--transpose]",
        .about = "A time series is a rows x frames matrix of values (one row per node or lead,\n"
                 "one column per time instant) with a time axis, units and a label.\n"
                 "\n"
                 "  info FILE          prints rows, frames, the time range, units, label, the\n"
                 "                     smallest and largest finite value and the number of\n"
                 "                     NaN/Inf values (with the first one's row and frame)\n"
                 "  convert IN -o OUT  reads IN and writes it as OUT (atomically)\n"
                 "  check SERIES       flags flat, saturated, duplicated and (with --surface)\n"
                 "                     outlying channels; prints every channel's scores; -o LIST\n"
                 "                     writes the bad-lead list that --bad-leads reads\n"
                 "                     (docs/cli.md \"series check\", docs/formats.md)\n"
                 "  --channels FILE    first takes IN's rows as recording channels and maps them\n"
                 "                     to nodes by a map3d .channels file (docs/formats.md)\n"
                 "\n"
                 "Formats (docs/formats.md, \"Time series\"): text (.txt, .dat), raw binary\n"
                 "(.raw), MATLAB (.mat), CSV (.csv, written with a header of times). Read\n"
                 "also: map3d .pot (one frame), numbered .pot files as one series (a pattern,\n"
                 "'dipole2_%03d.pot', or their directory: frames in number order, gaps\n"
                 "refused), map3d/CVRTI .tsdf (FILE.tsdf@N picks one of several), plain\n"
                 "numeric matrices in text (one line per row, one column per frame, blanks\n"
                 "or commas; --transpose for frames x channels). map3d fiducials (a .mat's\n"
                 "fids, a .tsdf's q/s/t times, a .fids file) are kept, printed by info and\n"
                 "written to .mat; a .mat struct (map3d's ts) is written back whole.\n"
                 "Input files are recognized by their content, else their extension. In a .mat file the values are the variable named as\n"
                 "FILE.mat:NAME, else `potvals`, else the first struct with a `potvals` field\n"
                 "(map3d recordings), else the first 2-D numeric matrix. MATLAB 5/7 files are\n"
                 "read (compressed or not); v7.3 (HDF5) files are refused: save with -v7.\n"
                 "A file is read whole or refused: truncation, stray bytes, NUL bytes or sizes\n"
                 "the file cannot hold are errors naming the file and the line or byte offset.\n",
        .epilog = "Rows and frames are counted from 1 in messages and in `info`.\n"
                  "Exit status: 0 ok, 1 error, 2 bad usage.\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
    };
    int pr = cli_parse(&c, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (c.n_pos > 2) return cli_usage_error(cmd, "unexpected argument '%s' (one input file expected)", c.pos[2]);
    const char *sub = c.n_pos > 0 ? c.pos[0] : NULL, *in = c.n_pos > 1 ? c.pos[1] : NULL;
    if (!sub) return cli_usage_error(cmd, "no subcommand given (info, convert or check)");
    int convert = !strcmp(sub, "convert"), check = !strcmp(sub, "check");
    if (!convert && !check && strcmp(sub, "info") != 0)
        return cli_usage_error(cmd, "unknown subcommand '%s' (info, convert or check)", sub);
    if (surface && !check) return cli_usage_error(cmd, "--surface goes with check");
    if (!in) return cli_usage_error(cmd, "%s: no input file given", sub);
    thx_series_format fmt = (thx_series_format)format;
    if (convert) {
        if (!out) return cli_usage_error(cmd, "convert: no output file given (-o OUT)");
        if (fmt == THX_SERIES_AUTO && thx_series_output_format(NULL, out, &fmt) != 0)
            return cli_usage_error(cmd, "cannot tell the format of '%s' from its extension (.txt, .dat, .raw, .mat, .csv); "
                                        "give --format",
                                   out);
    } else if (check ? format != THX_SERIES_AUTO || fids : out || format != THX_SERIES_AUTO) {
        return cli_usage_error(cmd, check ? "check: --format and --fids do not apply" : "info: -o and --format apply only to convert");
    }

    thx_ctx *ctx = cli_ctx(verbose);
    thx_series *s = NULL;
    thx_channels *ch = NULL;
    thx_model *sm = NULL;
    thx_surface *own = NULL;
    const thx_surface *surf = NULL;
    int rc = 0;
    thx_status st = thx_series_read(ctx, in, THX_SERIES_AUTO, &s);
    if (st == THX_OK && transpose) st = thx_series_transpose(ctx, &s);
    if (st == THX_OK && fids) st = thx_series_read_fids(ctx, fids, s);
    if (st == THX_OK && channels) { /* the recording's channels as the nodes of the .channels file */
        thx_series *mapped = NULL;
        st = thx_channels_read(ctx, channels, &ch);
        if (st == THX_OK) st = thx_channels_apply(ctx, ch, s, &mapped);
        if (st == THX_OK) {
            thx_log(ctx, THX_LOG_INFO, "%s: %zu of %zu channels -> %zu nodes (%zu with no channel)", channels,
                    ch->n - thx_channels_unmapped(ch), s->n_rows, ch->n, thx_channels_unmapped(ch));
            thx_series_destroy(&s);
            s = mapped;
        }
    }
    if (st == THX_OK && surface) st = check_surface(ctx, surface, &sm, &own, &surf);
    if (st) {
        rc = cli_fail(ctx, cmd, st);
        goto done;
    }
    if (check) {
        st = series_check(ctx, in, s, surf, ch, out);
        if (st) rc = cli_fail(ctx, cmd, st);
        goto done;
    }
    if (!convert) {
        print_info(in, s);
        goto done;
    }
    st = thx_series_write(ctx, s, out, fmt);
    if (st) {
        rc = cli_fail(ctx, cmd, st);
        goto done;
    }
    size_t bad = thx_series_find_nonfinite(s, NULL, NULL);
    thx_log(ctx, THX_LOG_INFO, "wrote %s (%zu rows x %zu frames%s)", out, s->n_rows, s->n_frames,
            bad ? ", with NaN/Inf values" : "");
done:
    thx_channels_destroy(&ch);
    thx_model_destroy(&sm);
    thx_surface_destroy(&own);
    thx_series_destroy(&s);
    thx_ctx_destroy(&ctx);
    return rc;
}
