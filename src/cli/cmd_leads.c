/* thorax leads: ECG leads and electrode signals from a forward solution. */
#include <cjson/cJSON.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli/cli.h"
#include "cli/cli_fem.h"
#include "thorax/io/series_file.h"
#include "thorax/io/model_dir.h"
#include "thorax/model/electrodes.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/leads/leads.h"
#include "thorax/phantom/phantom.h"
#include "thorax/core/fileio.h"
#include "thorax/picture/ecg_plot.h"
int cmd_leads(int argc, char **argv)
{
    const char *out = NULL, *twelve = NULL, *array = NULL, *plot = NULL;
    int verbose = 0, format = THX_SERIES_TEXT;
    static const cli_choice formats[] = {{"text", THX_SERIES_TEXT}, {"raw", THX_SERIES_RAW}, {"mat", THX_SERIES_MAT},
                                         {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "DIR", .s = &out, .def = "SOLUTION itself",
         .help = "where to write"},
        {.name = "--twelve", .type = CLI_INPUT, .meta = "FILE", .s = &twelve, .def = "MODEL/electrodes/12lead.txt",
         .help = "electrodes with RA, LA, LL, V1..V6 (made by thorax electrodes)"},
        {.name = "--array", .type = CLI_INPUT, .meta = "FILE", .s = &array,
         .def = "MODEL/electrodes/array.txt, if present", .help = "an electrode array"},
        {.name = "--format", .type = CLI_CHOICE, .choices = formats, .i = &format, .help = "the series' format"},
        {.name = "--plot", .type = CLI_OUTPUT, .meta = "FILE.svg|.png", .s = &plot,
         .help = "the 12-lead ECG on ECG paper (3 x 4 layout, 25 mm/s, 10 mm/mV, 1 mm grid), SVG or PNG"},
        {.name = "-v", .type = CLI_SET, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_SET, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE, .help = "less logging"},
    };
    cli_command c = {
        .name = "leads",
        .usage = "SOLUTION [-o] [--twelve] [--array] [--format] [--plot]",
        .about = "Reads a solution of thorax forward (its torso potentials and its model) and\n"
                 "writes the standard 12-lead ECG (I, II, III, aVR, aVL, aVF, V1-V6; the\n"
                 "precordial leads against Wilson's central terminal) as DIR/ecg12.EXT and the\n"
                 "signals of an electrode array as DIR/array.EXT (rows: the electrodes).\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
    };
    int pr = cli_parse(&c, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (c.n_pos > 1) return cli_usage_error("leads", "more than one solution given");
    const char *sol = c.n_pos ? c.pos[0] : NULL;
    if (!sol) return cli_usage_error("leads", "no solution given");
    if (!out) out = sol;
    if (plot) { /* checked before anything is written */
        size_t pl = strlen(plot);
        if (pl < 5 || (strcasecmp(plot + pl - 4, ".svg") && strcasecmp(plot + pl - 4, ".png")))
            return cli_usage_error("leads", "--plot %s: give a file ending in .svg or .png", plot);
    }
    thx_ctx *ctx = cli_ctx(verbose);
    thx_series_format fmt = (thx_series_format)format;
    const char *ext = fmt == THX_SERIES_TEXT ? "txt" : fmt == THX_SERIES_MAT ? "mat" : "raw";
    char path[PATH_MAX + 64], model_dir[PATH_MAX] = "", torso_file[256] = "", p12[PATH_MAX + 64], parr[PATH_MAX + 64];
    char *text = NULL;
    size_t len = 0;
    int rc = 0;
    thx_model *m = NULL;
    thx_series *torso = NULL, *ecg = NULL, *arr = NULL;
    thx_electrodes *e12 = NULL, *ea = NULL;
    snprintf(path, sizeof path, "%s/solution.json", sol);
    thx_status st = thx_read_file(ctx, path, &text, &len);
    if (st == THX_OK) {
        cJSON *j = cJSON_Parse(text);
        cJSON *mo = cJSON_GetObjectItem(j, "model"), *files = cJSON_GetObjectItem(j, "files");
        cJSON *to = files ? cJSON_GetObjectItem(files, "torso") : NULL;
        if (!j || !cJSON_IsString(mo) || !cJSON_IsString(to))
            st = thx_error(ctx, THX_EINPUT, "%s: not a thorax solution with torso potentials (model, files.torso)", path);
        else {
            snprintf(model_dir, sizeof model_dir, "%s", mo->valuestring);
            snprintf(torso_file, sizeof torso_file, "%s", to->valuestring);
        }
        cJSON_Delete(j);
    }
    if (st == THX_OK) st = thx_model_read(ctx, model_dir, &m);
    if (st == THX_OK) {
        snprintf(path, sizeof path, "%s/%s", sol, torso_file);
        st = thx_series_read(ctx, path, THX_SERIES_AUTO, &torso);
    }
    snprintf(p12, sizeof p12, "%s", twelve ? twelve : "");
    if (!twelve) snprintf(p12, sizeof p12, "%s/electrodes/12lead.txt", model_dir);
    if (st == THX_OK) st = thx_electrodes_read(ctx, p12, &e12);
    if (st == THX_OK) st = thx_electrodes_check(ctx, e12, m);
    if (st == THX_OK) st = thx_ecg12(ctx, e12, torso, &ecg);
    if (st == THX_OK) {
        if (array) snprintf(parr, sizeof parr, "%s", array);
        else snprintf(parr, sizeof parr, "%s/electrodes/array.txt", model_dir);
        FILE *f = fopen(parr, "r");
        if (f || array) {
            if (f) fclose(f);
            st = thx_electrodes_read(ctx, parr, &ea);
            if (st == THX_OK) st = thx_electrodes_check(ctx, ea, m);
            if (st == THX_OK) st = thx_electrodes_sample(ctx, ea, torso, &arr);
        }
    }
    if (st == THX_OK) {
        snprintf(path, sizeof path, "%s/ecg12.%s", out, ext);
        st = thx_series_write(ctx, ecg, path, fmt);
    }
    if (st == THX_OK && plot) {
        thx_ecg_plot_opts po;
        thx_ecg_plot_opts_default(&po);
        char title[PATH_MAX + 32];
        const char *base = strrchr(sol, '/');
        base = base && base[1] ? base + 1 : sol;
        snprintf(title, sizeof title, "12-lead ECG of %s", base);
        po.title = title;
        snprintf(path, sizeof path, "%s/%s", sol, torso_file);
        const char *in[1] = {path};
        st = thx_ecg_plot_write(ctx, ecg, &po, plot, in, 1);
    }
    if (st == THX_OK && arr) {
        snprintf(path, sizeof path, "%s/array.%s", out, ext);
        st = thx_series_write(ctx, arr, path, fmt);
    }
    if (st == THX_OK) {
        /* written into the solution itself: its manifest names the new files, so that the solution
           stays thorax's own and can be written again (thorax/core/fileio.h) */
        char rs[PATH_MAX], ro[PATH_MAX];
        if (realpath(sol, rs) && realpath(out, ro) && !strcmp(rs, ro)) {
            cJSON *j = cJSON_Parse(text), *files = j ? cJSON_GetObjectItem(j, "files") : NULL;
            if (!cJSON_IsObject(files)) st = thx_error(ctx, THX_EINPUT, "%s/solution.json: no \"files\"", sol);
            else {
                /* one entry per format written (ecg12 for text, ecg12_raw, ecg12_mat) */
                char key[32], name[64];
                snprintf(key, sizeof key, fmt == THX_SERIES_TEXT ? "ecg12" : "ecg12_%s", ext);
                snprintf(name, sizeof name, "ecg12.%s", ext);
                cJSON_DeleteItemFromObject(files, key);
                cJSON_AddStringToObject(files, key, name);
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
    }
    if (st != THX_OK) rc = cli_fail(ctx, "leads", st);
    else if (verbose >= 0) {
        printf("12-lead ECG: %zu frames -> %s/ecg12.%s\n", ecg->n_frames, out, ext);
        if (arr) printf("array: %zu electrodes -> %s/array.%s\n", arr->n_rows, out, ext);
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
