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
    const char *out = NULL, *fids = NULL, *channels = NULL;
    int verbose = 0, format = THX_SERIES_AUTO, transpose = 0;
    static const cli_choice formats[] = {{"text", THX_SERIES_TEXT}, {"raw", THX_SERIES_RAW}, {"mat", THX_SERIES_MAT},
                                         {"csv", THX_SERIES_CSV}, {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "OUT", .s = &out,
         .help = "file to write (convert)"},
        {.name = "--format", .type = CLI_CHOICE, .choices = formats, .i = &format, .def = "from OUT's extension",
         .help = "format of OUT (convert)"},
        {.name = "--fids", .type = CLI_INPUT, .meta = "FIDS", .s = &fids,
         .help = "add the fiducials of a map3d .fids file (one line per lead; its lead count must be the rows)"},
        {.name = "--transpose", .type = CLI_FLAG, .i = &transpose,
         .help = "swap rows and frames after reading (a matrix laid out frames x channels)"},
        {.name = "--channels", .type = CLI_INPUT, .meta = "FILE", .s = &channels,
         .help = "map3d .channels: IN's rows are recording channels; the series taken is one row per node of the "
                 "file (NaN for a node with no channel)"},
        {.name = "-v", .type = CLI_COUNT, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_COUNT, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE, .help = "less logging"},
    };
    cli_command c = {
        .name = cmd,
        .usage = "info FILE [--fids] [--transpose] [--channels]\nconvert IN -o [--format] [--fids] [--transpose] [--channels]",
        .about = "A time series is a rows x frames matrix of values (one row per node or lead,\n"
                 "one column per time instant) with a time axis, units and a label.\n"
                 "\n"
                 "  info FILE          prints rows, frames, the time range, units, label, the\n"
                 "                     smallest and largest finite value and the number of\n"
                 "                     NaN/Inf values (with the first one's row and frame)\n"
                 "  convert IN -o OUT  reads IN and writes it as OUT (atomically)\n"
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
    if (!sub) return cli_usage_error(cmd, "no subcommand given (info or convert)");
    int convert = !strcmp(sub, "convert");
    if (!convert && strcmp(sub, "info") != 0)
        return cli_usage_error(cmd, "unknown subcommand '%s' (info or convert)", sub);
    if (!in) return cli_usage_error(cmd, "%s: no input file given", sub);
    thx_series_format fmt = (thx_series_format)format;
    if (convert) {
        if (!out) return cli_usage_error(cmd, "convert: no output file given (-o OUT)");
        if (fmt == THX_SERIES_AUTO && thx_series_output_format(NULL, out, &fmt) != 0)
            return cli_usage_error(cmd, "cannot tell the format of '%s' from its extension (.txt, .dat, .raw, .mat, .csv); "
                                        "give --format",
                                   out);
    } else if (out || format != THX_SERIES_AUTO) {
        return cli_usage_error(cmd, "info: -o and --format apply only to convert");
    }

    thx_ctx *ctx = cli_ctx(verbose);
    thx_series *s = NULL;
    int rc = 0;
    thx_status st = thx_series_read(ctx, in, THX_SERIES_AUTO, &s);
    if (st == THX_OK && transpose) st = thx_series_transpose(ctx, &s);
    if (st == THX_OK && fids) st = thx_series_read_fids(ctx, fids, s);
    if (st == THX_OK && channels) { /* the recording's channels as the nodes of the .channels file */
        thx_channels *ch = NULL;
        thx_series *mapped = NULL;
        st = thx_channels_read(ctx, channels, &ch);
        if (st == THX_OK) st = thx_channels_apply(ctx, ch, s, &mapped);
        if (st == THX_OK) {
            thx_log(ctx, THX_LOG_INFO, "%s: %zu of %zu channels -> %zu nodes (%zu with no channel)", channels,
                    ch->n - thx_channels_unmapped(ch), s->n_rows, ch->n, thx_channels_unmapped(ch));
            thx_series_destroy(&s);
            s = mapped;
        }
        thx_channels_destroy(&ch);
    }
    if (st) {
        rc = cli_fail(ctx, cmd, st);
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
    thx_series_destroy(&s);
    thx_ctx_destroy(&ctx);
    return rc;
}
