/* thorax leads: ECG leads and electrode signals from a forward solution or a recording. */
#include <cjson/cJSON.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli/cli.h"
#include "cli/cli_fem.h"
#include "cli/cli_bad_leads.h"
#include "thorax/io/series_file.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/channels_file.h"
#include "thorax/model/electrodes.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/leads/leads.h"
#include "thorax/core/fileio.h"
#include "thorax/picture/ecg_plot.h"

static int exists(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0;
}

/* The signature each series writer puts in its first bytes (thorax/core/fileio.h): the claim of
 * an output file looks for it. */
static const char *marker_of(thx_series_format f, size_t *len)
{
    const char *m = f == THX_SERIES_TEXT ? "thorax-series" : f == THX_SERIES_MAT ? "Created by: thorax" : "THXSER01";
    *len = strlen(m);
    return m;
}

/* An electrode set on surface s of m: FILE if given, else the default if it exists (else none). */
static thx_status load_set(thx_ctx *ctx, const char *given, const char *def, const thx_model *m, const char *surface,
                           double max_offset, thx_electrodes **e, char *used, size_t cap, thx_electrodes_kind *kind,
                           double *moved)
{
    *e = NULL;
    used[0] = '\0';
    if (!given && !exists(def)) return THX_OK;
    snprintf(used, cap, "%s", given ? given : def);
    return thx_electrodes_load(ctx, used, m, surface, max_offset, e, kind, moved);
}

int cmd_leads(int argc, char **argv)
{
    const char *out = NULL, *twelve = NULL, *array = NULL, *data = NULL, *channels = NULL, *surface = NULL, *bad_leads = NULL,
               *plot = NULL;
    double max_offset = THX_ELECTRODE_MAX_OFFSET_MM;
    int verbose = 0, format = THX_SERIES_TEXT;
    static const cli_choice formats[] = {{"text", THX_SERIES_TEXT}, {"raw", THX_SERIES_RAW}, {"mat", THX_SERIES_MAT},
                                         {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "DIR", .s = &out, .def = "SOLUTION itself",
         .help = "where to write (created if missing; a file of the same name there is replaced only if thorax wrote it)"},
        {.name = "--twelve", .type = CLI_INPUT, .meta = "FILE", .s = &twelve,
         .def = "MODEL/electrodes/12lead.txt, if present",
         .help = "electrodes named RA, LA, LL, V1..V6 (thorax electrodes, or any electrode file below)"},
        {.name = "--array", .type = CLI_INPUT, .meta = "FILE", .s = &array,
         .def = "MODEL/electrodes/array.txt, if present",
         .help = "any electrode set: a thorax electrode file, a map3d .leadlinks, a node list (one node a line) or "
                 "positions (X Y Z a line, projected onto the surface and interpolated on their triangle)"},
        {.name = "--data", .type = CLI_INPUT, .meta = "SERIES", .s = &data,
         .help = "potentials on the surface (rows its nodes, or recording channels with --channels): the first "
                 "argument is then a MODEL"},
        {.name = "--channels", .type = CLI_INPUT, .meta = "FILE", .s = &channels,
         .help = "map3d .channels: the --data rows are recording channels, node i takes channel c"},
        CLI_BAD_LEADS_OPT(&bad_leads, "filled by Laplacian interpolation on the surface before the leads are sampled"),
        {.name = "--surface", .type = CLI_STRING, .meta = "NAME", .s = &surface, .def = "the outer surface",
         .help = "the surface the potentials and the electrodes are on"},
        {.name = "--max-offset", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &max_offset, .rule = CLI_GE, .lo = 0,
         .bad = "--max-offset must be a number of mm >= 0",
         .help = "farthest an electrode's position may lie from the surface (it is projected onto it)"},
        {.name = "--format", .type = CLI_CHOICE, .choices = formats, .i = &format, .help = "the series' format"},
        {.name = "--plot", .type = CLI_OUTPUT, .meta = "FILE.svg|.png", .s = &plot,
         .help = "the 12-lead ECG on ECG paper (3 x 4 layout, 25 mm/s, 10 mm/mV, 1 mm grid), SVG or PNG"},
        {.name = "-v", .type = CLI_SET, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_SET, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE, .help = "less logging"},
    };
    cli_command c = {
        .name = "leads",
        .usage = "SOLUTION [-o] [--twelve] [--array] [--max-offset] [--format] [--plot]\n"
                 "MODEL --data [--channels] [--bad-leads] -o [--twelve] [--array] [--surface] [--max-offset] [--format] [--plot]",
        .about = "Reads potentials on the torso - a solution of thorax forward (its torso\n"
                 "potentials and its model), or a MODEL and --data SERIES (a recording, its\n"
                 "channels mapped to nodes by --channels) - and writes the standard 12-lead\n"
                 "ECG (I, II, III, aVR, aVL, aVF, V1-V6; the precordial leads against Wilson's\n"
                 "central terminal) as DIR/ecg12.EXT, and the signals of an electrode set as\n"
                 "DIR/array.EXT (rows: the electrodes, in the set's order). Each is written\n"
                 "when its electrodes are there: --twelve or MODEL/electrodes/12lead.txt,\n"
                 "--array or MODEL/electrodes/array.txt; at least one is needed.\n"
                 "An electrode between nodes takes the potential interpolated on its triangle.\n",
        .epilog = "Exit status: 0 ok, 1 error (nothing written), 2 bad usage.\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
    };
    int pr = cli_parse(&c, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (c.n_pos > 1) return cli_usage_error("leads", "more than one %s given", data ? "model" : "solution");
    const char *sol = c.n_pos ? c.pos[0] : NULL;
    if (!sol) return cli_usage_error("leads", "no %s given", data ? "model" : "solution");
    if ((channels || bad_leads) && !data) return cli_usage_error("leads", "--channels and --bad-leads go with --data (its rows are the channels)");
    if (data && !out) return cli_usage_error("leads", "--data needs -o DIR (the model is not written into)");
    if (!out) out = sol;
    if (plot) { /* checked before anything is read or written */
        size_t pl = strlen(plot);
        if (pl < 5 || (strcasecmp(plot + pl - 4, ".svg") && strcasecmp(plot + pl - 4, ".png")))
            return cli_usage_error("leads", "--plot %s: give a file ending in .svg or .png", plot);
    }
    thx_ctx *ctx = cli_ctx(verbose);
    thx_series_format fmt = (thx_series_format)format;
    const char *ext = fmt == THX_SERIES_TEXT ? "txt" : fmt == THX_SERIES_MAT ? "mat" : "raw";
    char path[PATH_MAX + 64], model_dir[PATH_MAX] = "", torso_file[256] = "", surf_name[64] = "";
    char p12[PATH_MAX + 64], parr[PATH_MAX + 64], def[PATH_MAX + 64], ecg_path[PATH_MAX + 64] = "",
        arr_path[PATH_MAX + 64] = "";
    char *text = NULL;
    size_t len = 0;
    int rc = 0, made_dir = 0, into_solution = 0, wrote_ecg = 0, wrote_arr = 0;
    thx_model *m = NULL;
    thx_series *torso = NULL, *ecg = NULL, *arr = NULL;
    thx_electrodes *e12 = NULL, *ea = NULL;
    thx_electrodes_kind kind12 = THX_ELECTRODES_FILE, kinda = THX_ELECTRODES_FILE;
    double moved12 = 0, moveda = 0;
    thx_status st = THX_OK;
    if (data) {
        snprintf(model_dir, sizeof model_dir, "%s", sol);
    } else {
        snprintf(path, sizeof path, "%s/solution.json", sol);
        st = thx_read_file(ctx, path, &text, &len);
        if (st == THX_OK) {
            cJSON *j = cJSON_Parse(text);
            cJSON *mo = cJSON_GetObjectItem(j, "model"), *files = cJSON_GetObjectItem(j, "files");
            cJSON *to = files ? cJSON_GetObjectItem(files, "torso") : NULL;
            cJSON *el = files ? cJSON_GetObjectItem(files, "electrodes") : NULL;
            cJSON *su = cJSON_GetObjectItem(j, "surface");
            if (j && cJSON_IsString(mo) && !cJSON_IsString(to) && cJSON_IsString(el))
                st = thx_error(ctx, THX_EINPUT,
                               "%s: the solution holds the potentials at its electrodes (%s, forward --rows), not on the "
                               "torso's nodes: its rows are the signals already",
                               path, el->valuestring);
            else if (!j || !cJSON_IsString(mo) || !cJSON_IsString(to))
                st = thx_error(ctx, THX_EINPUT, "%s: not a thorax solution with torso potentials (model, files.torso)", path);
            else {
                snprintf(model_dir, sizeof model_dir, "%s", mo->valuestring);
                snprintf(torso_file, sizeof torso_file, "%s", to->valuestring);
                if (cJSON_IsString(su)) snprintf(surf_name, sizeof surf_name, "%s", su->valuestring);
            }
            cJSON_Delete(j);
        }
    }
    if (st == THX_OK) st = thx_model_read(ctx, model_dir, &m);
    /* the surface the potentials are on: --surface, the solution's, or the model's outer one */
    const thx_surface *s = NULL;
    if (st == THX_OK) {
        if (surface) snprintf(surf_name, sizeof surf_name, "%s", surface);
        int n = 0;
        for (size_t k = 0; k < m->n_surfaces; k++)
            if (surf_name[0] ? !strcmp(m->surf[k]->name, surf_name) : m->surf[k]->role == THX_ROLE_OUTER) {
                s = m->surf[k];
                n++;
            }
        if (!s) st = thx_error(ctx, THX_EINPUT, "%s: no surface %s%s%s", model_dir, surf_name[0] ? "\"" : "(role outer)",
                               surf_name, surf_name[0] ? "\"" : "");
        else if (n > 1) st = thx_error(ctx, THX_EINPUT, "%s: %d outer surfaces; give --surface", model_dir, n);
    }
    if (st == THX_OK) {
        if (data) {
            st = thx_series_read(ctx, data, THX_SERIES_AUTO, &torso);
            if (st == THX_OK && channels) {
                thx_channels *ch = NULL;
                thx_series *mapped = NULL;
                st = thx_channels_read(ctx, channels, &ch);
                if (st == THX_OK) st = thx_channels_apply(ctx, ch, torso, &mapped);
                if (st == THX_OK) {
                    thx_series_destroy(&torso);
                    torso = mapped;
                }
                thx_channels_destroy(&ch);
            }
            if (st == THX_OK && torso->n_rows != s->n_nodes)
                st = thx_error(ctx, THX_EINPUT, "%s%s%s: %zu rows, but surface \"%s\" has %zu nodes%s", data,
                               channels ? " mapped by " : "", channels ? channels : "", torso->n_rows, s->name, s->n_nodes,
                               channels ? "" : " (a recording's channels need --channels)");
            if (st == THX_OK) st = cli_bad_leads_fill(ctx, bad_leads, channels, s, torso);
        } else {
            snprintf(path, sizeof path, "%s/%s", sol, torso_file);
            st = thx_series_read(ctx, path, THX_SERIES_AUTO, &torso);
        }
    }
    if (st == THX_OK) {
        snprintf(def, sizeof def, "%s/electrodes/12lead.txt", model_dir);
        st = load_set(ctx, twelve, def, m, s->name, max_offset, &e12, p12, sizeof p12, &kind12, &moved12);
    }
    if (st == THX_OK) {
        snprintf(def, sizeof def, "%s/electrodes/array.txt", model_dir);
        st = load_set(ctx, array, def, m, s->name, max_offset, &ea, parr, sizeof parr, &kinda, &moveda);
    }
    if (st == THX_OK && !e12 && !ea)
        st = thx_error(ctx, THX_EINPUT,
                       "no electrodes: %s/electrodes has no 12lead.txt or array.txt (thorax electrodes makes them); give "
                       "--twelve FILE or --array FILE",
                       model_dir);
    if (st == THX_OK && e12) st = thx_ecg12(ctx, e12, torso, &ecg);
    if (st == THX_OK && ea) st = thx_electrodes_sample(ctx, ea, torso, &arr);
    if (st == THX_OK && plot && !ecg)
        st = thx_error(ctx, THX_EINPUT, "--plot %s: the plot is of the 12-lead ECG, and there is no 12-lead set "
                       "(give --twelve FILE)", plot);
    /* where: into the solution itself (its manifest names the files), or DIR, created if missing */
    if (st == THX_OK) {
        char rs[PATH_MAX], ro[PATH_MAX];
        into_solution = !data && realpath(sol, rs) && realpath(out, ro) && !strcmp(rs, ro);
        struct stat sb;
        if (!into_solution) {
            if (stat(out, &sb) != 0) {
                if (mkdir(out, 0777) != 0)
                    st = thx_error(ctx, THX_EIO, "cannot create directory %s: %s", out, strerror(errno));
                else made_dir = 1;
            } else if (!S_ISDIR(sb.st_mode)) {
                st = thx_error(ctx, THX_EINPUT, "-o %s: not a directory", out);
            }
        }
        if (st == THX_OK && ecg) snprintf(ecg_path, sizeof ecg_path, "%s/ecg12.%s", out, ext);
        if (st == THX_OK && arr) snprintf(arr_path, sizeof arr_path, "%s/array.%s", out, ext);
        /* every output claimed before any is written: one refusal leaves everything as it was */
        size_t ml;
        const char *mk = marker_of(fmt, &ml);
        thx_atomic_file af;
        if (st == THX_OK && ecg) st = thx_output_claim(ctx, ecg_path, mk, ml, NULL, 0, &af);
        if (st == THX_OK && arr) st = thx_output_claim(ctx, arr_path, mk, ml, NULL, 0, &af);
    }
    /* the plot first: its refusal (a user's file there) comes before any series is written */
    if (st == THX_OK && plot) {
        thx_ecg_plot_opts po;
        thx_ecg_plot_opts_default(&po);
        char title[PATH_MAX + 32];
        const char *base = strrchr(sol, '/');
        base = base && base[1] ? base + 1 : sol;
        snprintf(title, sizeof title, "12-lead ECG of %s", data ? data : base);
        po.title = title;
        if (!data) snprintf(path, sizeof path, "%s/%s", sol, torso_file);
        const char *in[1] = {data ? data : path};
        st = thx_ecg_plot_write(ctx, ecg, &po, plot, in, 1);
    }
    if (st == THX_OK && ecg && (st = thx_series_write(ctx, ecg, ecg_path, fmt)) == THX_OK) wrote_ecg = 1;
    if (st == THX_OK && arr && (st = thx_series_write(ctx, arr, arr_path, fmt)) == THX_OK) wrote_arr = 1;
    if (st == THX_OK && into_solution) {
        /* written into the solution itself: its manifest names the new files, so that the solution
           stays thorax's own and can be written again (thorax/core/fileio.h) */
        cJSON *j = cJSON_Parse(text), *files = j ? cJSON_GetObjectItem(j, "files") : NULL;
        if (!cJSON_IsObject(files)) st = thx_error(ctx, THX_EINPUT, "%s/solution.json: no \"files\"", sol);
        else {
            /* one entry per format written (ecg12 for text, ecg12_raw, ecg12_mat) */
            char key[32], name[64];
            if (ecg) {
                snprintf(key, sizeof key, fmt == THX_SERIES_TEXT ? "ecg12" : "ecg12_%s", ext);
                snprintf(name, sizeof name, "ecg12.%s", ext);
                cJSON_DeleteItemFromObject(files, key);
                cJSON_AddStringToObject(files, key, name);
            }
            if (arr) {
                snprintf(key, sizeof key, fmt == THX_SERIES_TEXT ? "array" : "array_%s", ext);
                snprintf(name, sizeof name, "array.%s", ext);
                cJSON_DeleteItemFromObject(files, key);
                cJSON_AddStringToObject(files, key, name);
            }
            snprintf(path, sizeof path, "%s/solution.json", sol);
            st = cli_write_json(ctx, path, j);
            j = NULL; /* taken */
        }
        cJSON_Delete(j);
    }
    if (st != THX_OK) {
        /* nothing half-written: what this run wrote goes, and the folder it made */
        if (wrote_ecg) unlink(ecg_path);
        if (wrote_arr) unlink(arr_path);
        if (made_dir) rmdir(out);
        rc = cli_fail(ctx, "leads", st);
    } else if (verbose >= 0) {
        if (ecg)
            printf("12-lead ECG: %zu frames -> %s (electrodes: %s, %s%s)\n", ecg->n_frames, ecg_path, p12,
                   thx_electrodes_kind_name(kind12), moved12 > 0 ? ", some between nodes" : "");
        if (arr) {
            size_t off = 0;
            for (size_t i = 0; i < ea->n; i++) off += ea->node[i] < 0;
            printf("array: %zu electrodes (%s, %s; %zu between nodes, moved onto the surface by up to %.3g mm) -> %s\n",
                   arr->n_rows, parr, thx_electrodes_kind_name(kinda), off, moveda, arr_path);
        }
        if (plot) printf("plot: %s\n", plot);
    }
    free(text);
    thx_series_destroy(&torso);
    thx_series_destroy(&ecg);
    thx_series_destroy(&arr);
    thx_electrodes_destroy(&e12);
    thx_electrodes_destroy(&ea);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return rc;
}
