/* thorax electrodes / thorax beat: the phantom's electrodes on a model's outer
 * surface (the 12-lead positions and a body-surface-mapping array), and the
 * phantom's heartbeat as epicardial potentials (paper 4.1); both in the
 * model's anatomical frame (model.json "frame"; a model without one is refused). */
#include <errno.h>
#include <math.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "cli/cli.h"
#include "cli/cli_fem.h"
#include "thorax/io/series_file.h"
#include "thorax/io/model_dir.h"
#include "thorax/model/electrodes.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/leads/leads.h"
#include "thorax/phantom/phantom.h"
#include "thorax/core/fileio.h"
/* ------------------------------------------------------------ electrodes */

/* The folder's manifest electrodes.json, naming files[key] = name in it besides those already
 * there (an existing manifest is thorax's own: it was claimed). */
static thx_status write_manifest(thx_ctx *ctx, const char *dir, const char *const *keys, const char *const *names, int n)
{
    char mpath[PATH_MAX + 32];
    snprintf(mpath, sizeof mpath, "%s/electrodes.json", dir);
    cJSON *j = NULL;
    char *text = NULL;
    size_t len = 0;
    if (access(mpath, F_OK) == 0 && thx_read_file(ctx, mpath, &text, &len) == THX_OK) j = cJSON_Parse(text);
    free(text);
    cJSON *fmt = j ? cJSON_GetObjectItem(j, "format") : NULL;
    if (!j || !cJSON_IsString(fmt) || strcmp(fmt->valuestring, "thorax-electrodes") != 0 ||
        !cJSON_IsObject(cJSON_GetObjectItem(j, "files"))) {
        cJSON_Delete(j);
        j = cJSON_CreateObject();
        if (!j) return thx_error(ctx, THX_ENOMEM, "out of memory");
        cJSON_AddStringToObject(j, "format", "thorax-electrodes");
        cJSON_AddNumberToObject(j, "version", 1);
        cJSON_AddObjectToObject(j, "files");
    }
    cJSON *files = cJSON_GetObjectItem(j, "files");
    for (int k = 0; k < n; k++) {
        cJSON_DeleteItemFromObject(files, keys[k]);
        cJSON_AddStringToObject(files, keys[k], names[k]);
    }
    return cli_write_json(ctx, mpath, j);
}

/* thorax electrodes MODEL --from FILE: any electrode set placed on the model, as a thorax file. */
static int electrodes_from(const char *in, const char *dir, const char *from, const char *surface, double max_offset,
                           int verbose)
{
    const char *cmd = "electrodes";
    /* the file's name without folder and extension, in the characters a file name of thorax keeps */
    char stem[64] = "";
    const char *b = strrchr(from, '/');
    b = b ? b + 1 : from;
    size_t k = 0;
    for (; *b && *b != '.' && k + 1 < sizeof stem; b++)
        stem[k++] = ((*b >= 'A' && *b <= 'Z') || (*b >= 'a' && *b <= 'z') || (*b >= '0' && *b <= '9') || *b == '_' ||
                     *b == '-') ? *b : '_';
    stem[k] = '\0';
    if (!stem[0]) snprintf(stem, sizeof stem, "electrodes");
    char path[PATH_MAX + 80], mpath[PATH_MAX + 32], name[80];
    snprintf(name, sizeof name, "%s.txt", stem);
    snprintf(path, sizeof path, "%s/%s", dir, name);
    snprintf(mpath, sizeof mpath, "%s/electrodes.json", dir);
    thx_ctx *ctx = cli_ctx(verbose);
    thx_model *m = NULL;
    thx_electrodes *e = NULL;
    thx_electrodes_kind kind = THX_ELECTRODES_FILE;
    double moved = 0;
    int rc = 0, made = 0;
    thx_status st = thx_model_read(ctx, in, &m);
    if (st == THX_OK) st = thx_electrodes_load(ctx, from, m, surface, max_offset, &e, &kind, &moved);
    struct stat sb;
    if (st == THX_OK && stat(dir, &sb) != 0) {
        if (mkdir(dir, 0755) != 0) st = thx_error(ctx, THX_EIO, "cannot create directory %s: %s", dir, strerror(errno));
        else made = 1;
    }
    thx_atomic_file af;
    if (st == THX_OK) st = thx_output_claim(ctx, path, "thorax-electrodes", 17, NULL, 0, &af);
    if (st == THX_OK) st = thx_output_claim(ctx, mpath, "\"thorax-electrodes\"", 19, NULL, 0, &af);
    if (st == THX_OK) st = thx_electrodes_write(ctx, e, path);
    if (st == THX_OK) {
        const char *keys[1] = {stem}, *names[1] = {name};
        st = write_manifest(ctx, dir, keys, names, 1);
        if (st != THX_OK) unlink(path);
    }
    if (st != THX_OK) {
        if (made) rmdir(dir);
        rc = cli_fail(ctx, cmd, st);
    } else if (verbose >= 0) {
        size_t off = 0;
        for (size_t i = 0; i < e->n; i++) off += e->node[i] < 0;
        printf("%s: %zu electrodes (%s) on surface %s: %zu on nodes, %zu between nodes (moved onto the surface by up to "
               "%.3g mm)\n",
               from, e->n, thx_electrodes_kind_name(kind), e->surface, e->n - off, off, moved);
        if (verbose > 0 || e->n <= 24)
            for (size_t i = 0; i < e->n; i++) {
                char nd[16] = "-";
                if (e->node[i] >= 0) snprintf(nd, sizeof nd, "%d", (int)e->node[i] + 1);
                printf("%-9s %5s %10.2f %10.2f %10.2f\n", e->name[i], nd, e->xyz[3 * i], e->xyz[3 * i + 1], e->xyz[3 * i + 2]);
            }
        printf("wrote %s\n", path);
    }
    thx_electrodes_destroy(&e);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return rc;
}

int cmd_electrodes(int argc, char **argv)
{
    const char *cmd = "electrodes";
    const char *out = NULL, *from = NULL, *surface = NULL;
    long n_array = 192;
    double max_offset = THX_ELECTRODE_MAX_OFFSET_MM;
    int verbose = 0;
    cli_opt opts[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "DIR", .s = &out, .def = "MODEL/electrodes",
         .help = "directory to write into, created if missing (commands that rewrite the model, such as `thorax "
                 "mesh`, replace MODEL whole)"},
        {.name = "--array", .type = CLI_INT, .meta = "N", .l = &n_array, .rule = CLI_GE | CLI_LE, .lo = 0, .hi = 100000,
         .bad = "--array must be between 0 and 100000", .note = "0 = no array.txt",
         .help = "electrodes in the array, in round(sqrt(3N/4)) rings"},
        {.name = "--from", .type = CLI_INPUT, .meta = "FILE", .s = &from,
         .help = "instead of the phantom's sets: any electrode set (a thorax electrode file, a map3d .leadlinks, a node "
                 "list, or X Y Z positions, projected onto the surface) written as DIR/STEM.txt, STEM FILE's name"},
        {.name = "--surface", .type = CLI_STRING, .meta = "NAME", .s = &surface, .def = "the outer surface",
         .help = "the surface the --from electrodes are on"},
        {.name = "--max-offset", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &max_offset, .rule = CLI_GE, .lo = 0,
         .bad = "--max-offset must be a number of mm >= 0",
         .help = "farthest a --from position may lie from the surface"},
        {.name = "-v", .type = CLI_SET, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_SET, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE,
         .help = "less logging (no table)"},
    };
    cli_command c = {
        .name = cmd,
        .usage = "MODEL [--array] [-o]\nMODEL --from FILE [--surface] [--max-offset] [-o]",
        .about = "Places the phantom's electrodes on the model's outer surface (role outer),\n"
                 "each on the surface node nearest its landmark, and writes them as electrode\n"
                 "files (docs/formats.md, \"Electrodes\"). Heights are along the model's\n"
                 "superior axis, \"front\" and \"left\" its anterior and left axes: the model's\n"
                 "anatomical frame (model.json \"frame\", from `thorax import --up --front` or the\n"
                 "contours' 'frame' line); a model without one is refused.\n"
                 "  DIR/12lead.txt  RA, LA, LL (Mason-Likar: front of the shoulders, left lower\n"
                 "                  torso), V1-V6 (4th intercostal space beside the sternum, V4\n"
                 "                  5th space mid-clavicular over the apex, V5 anterior axillary,\n"
                 "                  V6 mid-axillary, at V4's height), from the torso's own\n"
                 "                  cross-sections and the heart's height\n"
                 "  DIR/array.txt   N electrodes A001... on distinct nodes in rings around the\n"
                 "                  torso (192: 16 around at each of 12 heights), each ring from\n"
                 "                  the anterior midline toward the subject's left\n"
                 "The model needs an outer and a heart surface (as `thorax surfaces` builds\n"
                 "them from `thorax phantom` contours). The 12 leads are printed (nodes 1-based).\n"
                 "With --from FILE, any electrode set is placed on the model instead and written\n"
                 "as DIR/STEM.txt (electrodes between nodes with node '-', at their projected\n"
                 "positions); no anatomical frame is needed.\n"
                 "Files already in DIR are replaced only if thorax wrote them.\n",
        .epilog = "Exit status: 0 ok, 1 error (nothing written), 2 bad usage.\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
    };
    int pr = cli_parse(&c, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (c.n_pos > 1) return cli_usage_error(cmd, "more than one model given");
    const char *in = c.n_pos ? c.pos[0] : NULL;
    if (!in) return cli_usage_error(cmd, "no model given");
    char dir[2048], p12[2100], parr[2100];
    if (out) snprintf(dir, sizeof dir, "%s", out);
    else snprintf(dir, sizeof dir, "%s/electrodes", in);
    if (from) return electrodes_from(in, dir, from, surface, max_offset, verbose);
    if (surface || max_offset != THX_ELECTRODE_MAX_OFFSET_MM)
        return cli_usage_error(cmd, "--surface and --max-offset go with --from");
    snprintf(p12, sizeof p12, "%s/12lead.txt", dir);
    snprintf(parr, sizeof parr, "%s/array.txt", dir);

    thx_ctx *ctx = cli_ctx(verbose);
    thx_model *m = NULL;
    thx_electrodes *e12 = NULL, *ea = NULL;
    int rc = 0;
    thx_status st = thx_model_read(ctx, in, &m);
    if (st == THX_OK) st = thx_frame_require(ctx, &m->frame, in, "the electrode landmarks");
    if (st == THX_OK) st = thx_torso_electrodes(ctx, m, &m->frame, &e12, (size_t)n_array, &ea);
    if (st == THX_OK) st = thx_electrodes_check(ctx, e12, m);
    if (st == THX_OK && ea) st = thx_electrodes_check(ctx, ea, m);
    if (st != THX_OK) {
        rc = cli_fail(ctx, cmd, st);
        goto done;
    }
    int made = 0;
    if (mkdir(dir, 0755) == 0) made = 1;
    else if (errno != EEXIST) {
        fprintf(stderr, "thorax %s: cannot create directory %s: %s\n", cmd, dir, strerror(errno));
        rc = 1;
        goto done;
    }
    /* every output claimed before any is written: a user's file there stops the run, untouched */
    {
        thx_atomic_file af;
        char mp[2100];
        snprintf(mp, sizeof mp, "%s/electrodes.json", dir);
        st = thx_output_claim(ctx, p12, "thorax-electrodes", 17, NULL, 0, &af);
        if (st == THX_OK && ea) st = thx_output_claim(ctx, parr, "thorax-electrodes", 17, NULL, 0, &af);
        if (st == THX_OK) st = thx_output_claim(ctx, mp, "\"thorax-electrodes\"", 19, NULL, 0, &af);
        if (st != THX_OK) {
            if (made) rmdir(dir);
            rc = cli_fail(ctx, cmd, st);
            goto done;
        }
    }
    st = thx_electrodes_write(ctx, e12, p12);
    if (st == THX_OK && ea) st = thx_electrodes_write(ctx, ea, parr);
    if (st == THX_OK) {
        /* the folder's manifest: it marks the folder as thorax's, so that a model holding it (the
           default place) can still be rewritten (thorax/core/fileio.h) */
        const char *keys[2] = {"12lead", "array"}, *names[2] = {"12lead.txt", "array.txt"};
        st = write_manifest(ctx, dir, keys, names, ea ? 2 : 1);
    }
    if (st != THX_OK) {
        rc = cli_fail(ctx, cmd, st);
        goto done;
    }
    if (verbose >= 0) {
        printf("electrode  node        x          y          z   (surface %s, mm)\n", e12->surface);
        for (size_t i = 0; i < e12->n; i++)
            printf("%-9s %5d %10.2f %10.2f %10.2f\n", e12->name[i], (int)e12->node[i] + 1, e12->xyz[3 * i],
                   e12->xyz[3 * i + 1], e12->xyz[3 * i + 2]);
        if (ea) printf("wrote %s (%zu electrodes) and %s (%zu electrodes)\n", p12, e12->n, parr, ea->n);
        else printf("wrote %s (%zu electrodes)\n", p12, e12->n);
    }
done:
    thx_electrodes_destroy(&e12);
    thx_electrodes_destroy(&ea);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return rc;
}

/* ------------------------------------------------------------ beat */

int cmd_beat(int argc, char **argv)
{
    const char *cmd = "beat";
    const char *out = NULL;
    int verbose = 0, format = THX_SERIES_AUTO;
    long frames;
    thx_beat_opts o;
    thx_beat_opts_default(&o);
    frames = (long)o.n_frames;
    static const cli_choice formats[] = {{"text", THX_SERIES_TEXT}, {"raw", THX_SERIES_RAW}, {"mat", THX_SERIES_MAT},
                                         {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "FILE", .s = &out,
         .help = "series to write (atomically)"},
        {.name = "--frames", .type = CLI_INT, .meta = "N", .l = &frames, .rule = CLI_GE | CLI_LE, .lo = 1,
         .hi = 10000000, .bad = "--frames must be between 1 and 10000000", .help = "number of frames (the beat ends at 470 ms)"},
        {.name = "--dt", .type = CLI_REAL, .meta = "MS", .unit = "ms", .d = &o.dt_ms, .rule = CLI_GT | CLI_LE, .lo = 0,
         .hi = 1e6, .bad = "--dt must be a positive number of ms", .help = "time step"},
        {.name = "--peak", .type = CLI_REAL, .meta = "MV", .unit = "mV", .d = &o.peak_mv, .rule = CLI_GT | CLI_LE,
         .lo = 0, .hi = 1e12, .bad = "--peak must be a positive number of mV", .def = "none: --dipole sets the scale",
         .help = "largest |potential| on the heart over the beat (instead of --dipole)"},
        {.name = "--dipole", .type = CLI_REAL, .meta = "MAM", .unit = "mA m", .d = &o.dipole_mam,
         .rule = CLI_GT | CLI_LE, .lo = 0, .hi = 1e6, .bad = "--dipole must be a positive dipole moment in mA m",
         .help = "the dipole moment at the QRS peak (16 uA m: lead II about 1.5 mV on the phantom)"},
        {.name = "--format", .type = CLI_CHOICE, .choices = formats, .i = &format,
         .def = "from FILE's extension: .txt or .dat, .raw, .mat", .help = "the series' format"},
        {.name = "-v", .type = CLI_SET, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_SET, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE, .help = "less logging"},
    };
    cli_command c = {
        .name = cmd,
        .usage = "MODEL -o [--frames] [--dt] [--dipole|--peak] [--format]",
        .about = "The phantom's heartbeat as epicardial potentials: a current dipole at the\n"
                 "centre of the model's heart surface (role heart) traces a vectorcardiogram -\n"
                 "P loop, PR segment, QRS loop (90 ms, left-inferior-posterior), ST segment,\n"
                 "T loop, baseline (heart rate about 90/min; docs/decisions.md; directions in\n"
                 "the model's anatomical frame, model.json \"frame\": a model without one is\n"
                 "refused, give --up/--front to thorax import) - in an\n"
                 "unbounded homogeneous medium, of the given moment at the QRS peak (or scaled\n"
                 "so that the largest |potential| on the heart is --peak). Writes a time\n"
                 "series (docs/formats.md, \"Time series\"): rows = the heart surface's nodes in\n"
                 "order, frames at t = f * dt ms, unit mV. `thorax phantom --beat MODEL ...` is\n"
                 "the same.\n",
        .epilog = "Exit status: 0 ok, 1 error (nothing written), 2 bad usage.\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
    };
    int pr = cli_parse(&c, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (c.n_pos > 1) return cli_usage_error(cmd, "more than one model given");
    const char *in = c.n_pos ? c.pos[0] : NULL;
    o.n_frames = (size_t)frames;
    if (!in) return cli_usage_error(cmd, "no model given");
    if (!out) return cli_usage_error(cmd, "no output file given (-o FILE)");
    thx_series_format fmt = (thx_series_format)format;
    if (fmt == THX_SERIES_AUTO && thx_series_output_format(NULL, out, &fmt) != 0)
        return cli_usage_error(cmd, "cannot tell the format of '%s' from its extension (.txt, .dat, .raw, .mat); "
                                    "give --format",
                               out);

    thx_ctx *ctx = cli_ctx(verbose);
    thx_model *m = NULL;
    thx_series *s = NULL;
    int rc = 0;
    thx_status st = thx_model_read(ctx, in, &m);
    const thx_surface *heart = NULL;
    if (st == THX_OK) {
        for (size_t k = 0; k < m->n_surfaces && !heart; k++)
            if (m->surf[k]->role == THX_ROLE_HEART) heart = m->surf[k];
        if (!heart) st = thx_error(ctx, THX_EINPUT, "%s: the model has no heart surface (role \"heart\")", in);
    }
    if (st == THX_OK) st = thx_frame_require(ctx, &m->frame, in, "the dipole's directions");
    if (st == THX_OK) st = thx_torso_epicardial(ctx, heart, &m->frame, &o, &s);
    if (st == THX_OK) st = thx_series_write(ctx, s, out, fmt);
    if (st != THX_OK) rc = cli_fail(ctx, cmd, st);
    else if (verbose >= 0)
    {
        double vmax = 0;
        for (size_t i = 0; i < s->n_rows * s->n_frames; i++) vmax = vmax > fabs(s->v[i]) ? vmax : fabs(s->v[i]);
        printf("wrote %s: %zu nodes of surface %s x %zu frames (0 .. %g ms), peak %g mV\n%s\n", out, s->n_rows,
               heart->name, s->n_frames, s->time[s->n_frames - 1], vmax, s->label);
    }
    thx_series_destroy(&s);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return rc;
}
