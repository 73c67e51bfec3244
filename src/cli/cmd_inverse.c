/* thorax inverse: heart-surface potentials from body-surface potentials (paper 4.1, the inverse
 * problem), through a transfer matrix (thorax forward --transfer-out, or a .mat from elsewhere). */
#include <cjson/cJSON.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "cli/cli_fem.h"
#include "thorax/core/fileio.h"
#include "thorax/inverse/inverse.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/series_file.h"
#include "thorax/picture/lcurve_plot.h"
#include "cli/cli_bad_leads.h"

static const char *ext_of(thx_series_format f)
{
    return f == THX_SERIES_TEXT ? "txt" : f == THX_SERIES_MAT ? "mat" : "raw";
}

/* The heart surface of a model directory (or of the model a thorax solution directory names). */
static thx_status load_heart(thx_ctx *ctx, const char *dir, thx_model **m, const thx_surface **heart, char *used,
                             size_t n_used)
{
    char path[PATH_MAX + 32];
    *heart = NULL;
    snprintf(path, sizeof path, "%s/model.json", dir);
    FILE *f = fopen(path, "r");
    if (f) fclose(f);
    else {
        /* a solution directory: its solution.json names the model */
        char *text = NULL;
        size_t len = 0;
        snprintf(path, sizeof path, "%s/solution.json", dir);
        THX_CHECK(thx_read_file(ctx, path, &text, &len));
        cJSON *j = cJSON_Parse(text);
        free(text);
        const cJSON *mm = j ? cJSON_GetObjectItemCaseSensitive(j, "model") : NULL;
        if (!cJSON_IsString(mm)) {
            cJSON_Delete(j);
            return thx_error(ctx, THX_EINPUT, "%s: no \"model\" (the model the transfer matrix belongs to)", path);
        }
        snprintf(path, sizeof path, "%s", mm->valuestring);
        cJSON_Delete(j);
        dir = path;
    }
    if (used) {
        size_t l = strlen(dir);
        if (l >= n_used) l = n_used - 1;
        memcpy(used, dir, l);
        used[l] = '\0';
    }
    THX_CHECK(thx_model_read(ctx, dir, m));
    for (size_t k = 0; k < (*m)->n_surfaces; k++)
        if ((*m)->surf[k]->role == THX_ROLE_HEART) {
            if (*heart) return thx_error(ctx, THX_EINPUT, "%s: more than one heart surface", dir);
            *heart = (*m)->surf[k];
        }
    if (!*heart) return thx_error(ctx, THX_EINPUT, "%s: no heart surface (role \"heart\")", dir);
    return THX_OK;
}

/* The directory of a file path ("." for a bare name); the part before ':' of FILE.mat:NAME dropped. */
static void dir_of(const char *file, char *dir, size_t n)
{
    snprintf(dir, n, "%s", file);
    char *colon = strstr(dir, ".mat:");
    if (colon) colon[4] = '\0';
    char *slash = strrchr(dir, '/');
    if (slash) *slash = '\0';
    else snprintf(dir, n, ".");
}

static const char *const flag_names[4] = {"range_low", "range_high", "no_corner", "below_noise"};

/* the THX_LAMBDA_* bits as an array of names (empty: the rule found its λ inside the range) */
static void add_flags(cJSON *o, const char *key, int flags)
{
    cJSON *a = cJSON_AddArrayToObject(o, key);
    for (int b = 0; b < 4 && a; b++)
        if (flags >> b & 1) cJSON_AddItemToArray(a, cJSON_CreateString(flag_names[b]));
}

/* one warning line for the frames with a flag: how many, and the first few (1-based) */
static void warn_flag(const thx_inverse_report *R, int bit, const char *what)
{
    size_t c = 0;
    for (size_t k = 0; k < R->n_frames; k++) c += (R->flags[k] & bit) != 0;
    if (!c) return;
    fprintf(stderr, "thorax inverse: warning: %s on %zu of %zu frames (", what, c, R->n_frames);
    size_t shown = 0;
    for (size_t k = 0; k < R->n_frames && shown < 10; k++)
        if (R->flags[k] & bit) fprintf(stderr, "%s%zu", shown++ ? ", " : "", k + 1);
    fprintf(stderr, "%s; inverse.json per_frame flags)\n", c > shown ? ", ..." : "");
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* the q-quantile (0..1) of n values, NaN skipped; linear interpolation between order statistics */
static double quantile(const double *v, size_t n, double q)
{
    double *c = malloc((n ? n : 1) * sizeof *c);
    size_t k = 0;
    if (!c) return NAN;
    for (size_t i = 0; i < n; i++)
        if (!isnan(v[i])) c[k++] = v[i];
    if (!k) {
        free(c);
        return NAN;
    }
    qsort(c, k, sizeof *c, cmp_d);
    double p = q * (double)(k - 1), r;
    size_t i = (size_t)p;
    r = i + 1 < k ? c[i] + (p - (double)i) * (c[i + 1] - c[i]) : c[k - 1];
    free(c);
    return r;
}

int cmd_inverse(int argc, char **argv)
{
    const char *transfer = NULL, *data = NULL, *out = NULL, *lambda_s = "lcurve", *noise_s = NULL, *heart_dir = NULL;
    const char *truth_path = NULL, *truth_model = NULL, *bad_leads = NULL;
    int verbose = 0, method = THX_INVERSE_TIKHONOV0, per = 0, format = THX_SERIES_RAW, gs_rank = 0, tv_it = 10;
    int no_fallback = 0;
    char heart_used[PATH_MAX];
    static const cli_choice methods[] = {{"tikhonov0", THX_INVERSE_TIKHONOV0}, {"tikhonov1", THX_INVERSE_TIKHONOV1},
                                         {"tikhonov2", THX_INVERSE_TIKHONOV2}, {"tsvd", THX_INVERSE_TSVD},
                                         {"greensite", THX_INVERSE_GREENSITE}, {"tv", THX_INVERSE_TV}, {NULL, 0}};
    static const cli_choice pers[] = {{"frame", 0}, {"series", 1}, {NULL, 0}};
    static const cli_choice formats[] = {{"raw", THX_SERIES_RAW}, {"text", THX_SERIES_TEXT}, {"mat", THX_SERIES_MAT},
                                         {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--transfer", .type = CLI_INPUT, .meta = "FILE", .s = &transfer,
         .help = "the transfer matrix, rows the body-surface leads, columns the heart's nodes: thorax forward "
                 "--transfer-out's transfer.EXT or transfer_electrodes.EXT, or any series file (FILE.mat:NAME picks "
                 "a variable)"},
        {.name = "--data", .type = CLI_INPUT, .meta = "SERIES", .s = &data,
         .help = "the body-surface potentials, rows the transfer matrix's rows, one column per frame"},
        CLI_BAD_LEADS_OPT(&bad_leads, "left out (their rows of --data and of the transfer matrix; channel = row of --data)"),
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "DIR", .s = &out,
         .help = "the result directory (written whole or not at all): heart.EXT, lambda.txt, lcurve.svg, lcurve.png, "
                 "inverse.json"},
        {.name = "--method", .type = CLI_CHOICE, .choices = methods, .i = &method,
         .help = "Tikhonov of order 0, 1 (surface gradient) or 2 (surface Laplacian), truncated SVD, Greensite's "
                 "temporal-SVD method, or total variation (IRLS)"},
        {.name = "--lambda", .type = CLI_STRING, .meta = "RULE", .s = &lambda_s,
         .help = "how λ is chosen: lcurve (maximum curvature), creso, gcv, discrepancy (needs --noise), or a number"},
        {.name = "--lambda-per", .type = CLI_CHOICE, .choices = pers, .i = &per,
         .help = "a λ for every frame (greensite: every temporal component), or one for the whole series"},
        {.name = "--noise", .type = CLI_STRING, .meta = "SIGMA", .s = &noise_s,
         .help = "the data's noise for the discrepancy principle, Greensite's rank and the frames below the noise (a "
                 "λ per frame): a standard deviation per lead in the data's unit, or a signal-to-noise ratio such as "
                 "30dB"},
        {.name = "--heart", .type = CLI_INPUT, .meta = "MODEL", .s = &heart_dir,
         .def = "the model of the solution.json beside --transfer",
         .help = "the model (or solution directory) whose heart surface's nodes are the matrix's columns: the mesh of "
                 "the gradient and Laplacian (tikhonov1, tikhonov2, tv); with any method its node count is checked "
                 "against the matrix's columns"},
        {.name = "--truth", .type = CLI_INPUT, .meta = "SERIES", .s = &truth_path,
         .help = "the true heart potentials: CC and RE per frame printed, with their median and 10th percentile"},
        {.name = "--truth-model", .type = CLI_INPUT, .meta = "MODEL", .s = &truth_model,
         .help = "the --truth rows are this model's heart nodes: each of our heart nodes is compared with the nearest "
                 "of them"},
        {.name = "--rank", .type = CLI_INT, .meta = "K", .i = &gs_rank, .rule = CLI_GE, .lo = 0,
         .note = "0: the components above the noise (--noise), else 99.99% of the energy",
         .help = "greensite: the temporal components kept"},
        {.name = "--iterations", .type = CLI_INT, .meta = "N", .i = &tv_it, .rule = CLI_GE, .lo = 1,
         .help = "tv: reweighted least-squares iterations at most"},
        {.name = "--no-fallback", .type = CLI_SET, .i = &no_fallback, .ival = 1,
         .help = "a λ per frame: keep each frame's own λ on frames whose data is below the noise level (by default "
                 "they take the series' λ by the same rule; the noise: --noise, else the series' GCV estimate)"},
        {.name = "--format", .type = CLI_CHOICE, .choices = formats, .i = &format, .help = "format of the series written"},
        {.name = "-v", .type = CLI_SET, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_SET, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE, .help = "less logging"},
    };
    cli_command cmd = {
        .name = "inverse",
        .usage = "--transfer --data [--bad-leads] -o [--method] [--lambda] [--lambda-per] [--noise] [--heart] [--truth] "
                 "[--truth-model] [--rank] [--iterations] [--no-fallback] [--format]",
        .about = "The inverse problem (paper 4.1): heart-surface potentials from body-surface\n"
                 "potentials through a transfer matrix, regularized. Tikhonov of order 0, 1, 2\n"
                 "(orders 1 and 2 brought to standard form, so one SVD serves every λ), TSVD,\n"
                 "Greensite's temporal-SVD method, total variation. λ by the L-curve's corner,\n"
                 "CRESO, GCV, the discrepancy principle, or given; per frame or per series.\n"
                 "Writes DIR/heart.EXT (rows: the matrix's columns, the heart's nodes),\n"
                 "DIR/lambda.txt (λ, residual and solution norm per frame), DIR/lcurve.svg\n"
                 "(the series' L-curve, its corner and the λ used marked), DIR/lcurve.png (the\n"
                 "same picture; with a λ per frame the curve of the frame with the largest\n"
                 "data norm bold, its λ marked, up to 48 other frames' curves faint) and\n"
                 "DIR/inverse.json.\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
    };
    int pr = cli_parse(&cmd, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (cmd.n_pos) return cli_usage_error("inverse", "unexpected argument '%s'", cmd.pos[0]);
    if (!transfer) return cli_usage_error("inverse", "no transfer matrix given (--transfer FILE)");
    if (!data) return cli_usage_error("inverse", "no data given (--data SERIES)");
    if (!out) return cli_usage_error("inverse", "no output directory given (-o DIR)");
    if (truth_model && !truth_path) return cli_usage_error("inverse", "--truth-model goes with --truth");
    thx_inverse_opts o;
    thx_inverse_opts_default(&o);
    o.method = (thx_inverse_method)method;
    o.per_series = per;
    o.greensite_rank = gs_rank;
    o.tv_iterations = tv_it;
    o.no_fallback = no_fallback;
    o.matrix_name = transfer;
    o.data_name = data;
    static const cli_choice rules[] = {{"lcurve", THX_LAMBDA_LCURVE}, {"creso", THX_LAMBDA_CRESO},
                                       {"gcv", THX_LAMBDA_GCV}, {"discrepancy", THX_LAMBDA_DISCREPANCY}, {NULL, 0}};
    int known = 0;
    for (const cli_choice *c = rules; c->word; c++)
        if (!strcmp(lambda_s, c->word)) o.rule = (thx_lambda_rule)c->value, known = 1;
    if (!known) {
        char *e;
        o.lambda = strtod(lambda_s, &e);
        if (e == lambda_s || *e || !(o.lambda >= 0) || !isfinite(o.lambda))
            return cli_usage_error("inverse", "--lambda '%s': lcurve, creso, gcv, discrepancy or a number >= 0", lambda_s);
        o.rule = THX_LAMBDA_FIXED;
    }
    if (noise_s) {
        char *e;
        double v = strtod(noise_s, &e);
        if (e != noise_s && (!strcmp(e, "dB") || !strcmp(e, "db")) && v > 0 && isfinite(v)) o.snr_db = v;
        else if (e != noise_s && !*e && v > 0 && isfinite(v)) o.noise = v;
        else return cli_usage_error("inverse", "--noise '%s': a standard deviation > 0, or a ratio such as 30dB", noise_s);
    }
    if (o.rule == THX_LAMBDA_DISCREPANCY && !noise_s)
        return cli_usage_error("inverse", "--lambda discrepancy needs --noise (SIGMA, or a ratio such as 30dB)");

    thx_ctx *ctx = cli_ctx(verbose);
    thx_status st = THX_OK;
    int rc = 0;
    thx_series *A = NULL, *B = NULL, *X = NULL, *truth = NULL;
    thx_model *hm = NULL, *tm = NULL;
    const thx_surface *heart = NULL, *theart = NULL;
    thx_inverse_report R;
    memset(&R, 0, sizeof R);
    double *cc = NULL, *re = NULL, *tv = NULL;
    size_t *near = NULL;
    thx_outdir od;
    memset(&od, 0, sizeof od);
    thx_series_format fmt = (thx_series_format)format;
    double t0 = thx_wtime();
    const char *inputs[] = {transfer, data, heart_dir, truth_path, truth_model};
    st = thx_outdir_claim(ctx, &od, out, "inverse.json", "thorax-inverse", inputs, 5);
    if (st == THX_OK) st = thx_series_read(ctx, transfer, THX_SERIES_AUTO, &A);
    if (st == THX_OK) st = thx_series_read(ctx, data, THX_SERIES_AUTO, &B);
    if (st == THX_OK) st = cli_bad_leads_drop(ctx, bad_leads, &A, &B);
    int needs_heart = method == THX_INVERSE_TIKHONOV1 || method == THX_INVERSE_TIKHONOV2 || method == THX_INVERSE_TV;
    if (st == THX_OK && (needs_heart || heart_dir || truth_model)) {
        char dir[PATH_MAX];
        if (heart_dir) snprintf(dir, sizeof dir, "%s", heart_dir);
        else dir_of(transfer, dir, sizeof dir);
        st = load_heart(ctx, dir, &hm, &heart, heart_used, sizeof heart_used);
        o.heart_name = heart_used;
        if (st != THX_OK && !heart_dir) {
            char msg[1024];
            snprintf(msg, sizeof msg, "%s", thx_ctx_message(ctx));
            st = thx_error(ctx, st, "%s needs the heart surface the matrix's columns are the nodes of: %s (give --heart MODEL)",
                           needs_heart ? thx_inverse_method_name(o.method) : "--truth-model", msg);
        }
    }
    if (st == THX_OK && truth_path) st = thx_series_read(ctx, truth_path, THX_SERIES_AUTO, &truth);
    if (st == THX_OK && truth_model) {
        st = load_heart(ctx, truth_model, &tm, &theart, NULL, 0);
        if (st == THX_OK && theart->n_nodes != truth->n_rows)
            st = thx_error(ctx, THX_EINPUT, "%s has %zu rows but the heart of %s has %zu nodes", truth_path,
                           truth->n_rows, truth_model, theart->n_nodes);
    }
    if (st != THX_OK) goto fail;
    if (truth) {
        if (truth->n_frames != B->n_frames) {
            st = thx_error(ctx, THX_EINPUT, "%s has %zu frames but %s has %zu", truth_path, truth->n_frames, data,
                           B->n_frames);
            goto fail;
        }
        if (!theart && truth->n_rows != A->n_frames) {
            st = thx_error(ctx, THX_EINPUT, "%s has %zu rows but the transfer matrix has %zu columns (heart nodes); "
                           "--truth-model maps another model's heart", truth_path, truth->n_rows, A->n_frames);
            goto fail;
        }
    }
    st = thx_inverse_solve(ctx, A, B, heart, &o, &X, &R);
    if (st != THX_OK) goto fail;
    if (truth) {
        size_t n = X->n_rows, F = X->n_frames;
        cc = malloc(F * sizeof *cc);
        re = malloc(F * sizeof *re);
        tv = malloc(n * sizeof *tv);
        near = malloc(n * sizeof *near);
        if (!cc || !re || !tv || !near) {
            st = thx_error(ctx, THX_ENOMEM, "out of memory comparing with %s", truth_path);
            goto fail;
        }
        for (size_t i = 0; i < n; i++) {
            near[i] = i;
            if (theart) { /* the nearest node of the truth's heart */
                if (heart->n_nodes != n) {
                    st = thx_error(ctx, THX_EINPUT, "the heart surface has %zu nodes, the solution %zu rows", heart->n_nodes, n);
                    goto fail;
                }
                double best = INFINITY;
                const double *p = heart->xyz + 3 * i;
                for (size_t j = 0; j < theart->n_nodes; j++) {
                    const double *q = theart->xyz + 3 * j;
                    double d = (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
                    if (d < best) best = d, near[i] = j;
                }
            }
        }
        for (size_t f = 0; f < F; f++) {
            for (size_t i = 0; i < n; i++) tv[i] = truth->v[f * truth->n_rows + near[i]];
            thx_inverse_compare(X->v + f * n, tv, n, &cc[f], &re[f]);
        }
    }
    /* write: a temporary directory renamed as a whole */
    {
        char path[4400];
        const char *ext = ext_of(fmt);
        FILE *f = NULL;
        st = thx_outdir_begin(ctx, &od);
        if (st != THX_OK) goto fail;
        snprintf(path, sizeof path, "%s/heart.%s", od.tmp, ext);
        st = thx_series_write(ctx, X, path, fmt);
        char title[256];
        snprintf(title, sizeof title, "L-curve: %s, lambda by %s (%s), %zu frames", thx_inverse_method_name(o.method),
                 thx_lambda_rule_name(o.rule), per ? "one for the series" : "per frame", X->n_frames);
        /* a curve with fewer than two points that a log-log picture can show (one row; a matrix of
           rank 1 with its one component fitting exactly): no picture, and a note */
        size_t n_pts = 0;
        for (size_t q = 0; q < R.n_curve; q++)
            n_pts += R.curve_residual[q] > 0 && R.curve_seminorm[q] > 0 && isfinite(R.curve_residual[q]) &&
                     isfinite(R.curve_seminorm[q]);
        int pictures = n_pts >= 2;
        if (!pictures && R.n_curve && verbose >= 0)
            fprintf(stderr, "thorax inverse: warning: no L-curve picture: the curve has %zu point%s with a positive "
                            "residual and norm (a %zu x %zu matrix)\n",
                    n_pts, n_pts == 1 ? "" : "s", A->n_rows, A->n_frames);
        if (st == THX_OK && R.n_curve && pictures) {
            snprintf(path, sizeof path, "%s/lcurve.svg", od.tmp);
            st = thx_inverse_write_svg(ctx, &R, title, path);
        }
        if (st == THX_OK && R.n_curve && pictures) {
            /* the same curve as a PNG (thorax/picture/lcurve_plot.h); a λ per frame: the
               representative frame's curve bold, others faint */
            thx_lcurve_plot_opts po;
            thx_lcurve_plot_opts_default(&po);
            char ptitle[256], rule[96];
            snprintf(ptitle, sizeof ptitle, "L-curve: %s, %zu x %zu matrix, %zu frames", thx_inverse_method_name(o.method),
                     A->n_rows, A->n_frames, X->n_frames);
            if (o.rule == THX_LAMBDA_FIXED) snprintf(rule, sizeof rule, "fixed (%s)", lambda_s);
            else snprintf(rule, sizeof rule, "%s", thx_lambda_rule_name(o.rule));
            po.title = ptitle;
            po.rule = rule;
            snprintf(path, sizeof path, "%s/lcurve.png", od.tmp);
            st = thx_lcurve_plot_write(ctx, &R, &po, path);
        }
        /* lambda.txt: one line per frame */
        if (st == THX_OK) {
            thx_atomic_file af;
            snprintf(path, sizeof path, "%s/lambda.txt", od.tmp);
            st = thx_atomic_open(ctx, path, &af);
            if (st == THX_OK) {
                f = af.f;
                fprintf(f, "# thorax inverse: method %s, lambda %s (%s)\n", thx_inverse_method_name(o.method),
                        o.rule == THX_LAMBDA_FIXED ? lambda_s : thx_lambda_rule_name(o.rule), per ? "series" : "frame");
                fprintf(f, "# frame (1-based), time (%s), lambda, kept (tsvd), residual ||Ax-b||, solution norm ||Lx||%s\n",
                        X->time_unit, truth ? ", CC, RE" : "");
                for (size_t k = 0; k < X->n_frames; k++) {
                    fprintf(f, "%zu %.9g %.9g %d %.9g %.9g", k + 1, X->time[k], R.lambda[k], R.k[k], R.residual[k],
                            R.seminorm[k]);
                    if (truth) fprintf(f, " %.6f %.6f", cc[k], re[k]);
                    fputc('\n', f);
                }
                st = thx_atomic_commit(ctx, &af);
            }
        }
        cJSON *j = cJSON_CreateObject(), *files = cJSON_CreateObject(), *fr = cJSON_CreateArray();
        char abs[PATH_MAX];
        cJSON_AddStringToObject(j, "format", "thorax-inverse");
        cJSON_AddNumberToObject(j, "version", 1);
        cJSON_AddStringToObject(j, "command", cli_command_line());
        cJSON_AddStringToObject(j, "transfer", realpath(transfer, abs) ? abs : transfer);
        cJSON_AddStringToObject(j, "data", realpath(data, abs) ? abs : data);
        cJSON_AddStringToObject(j, "method", thx_inverse_method_name(o.method));
        cJSON_AddStringToObject(j, "lambda_rule", thx_lambda_rule_name(o.rule));
        cJSON_AddStringToObject(j, "lambda_per", per ? "series" : "frame");
        if (o.rule == THX_LAMBDA_DISCREPANCY) cJSON_AddNumberToObject(j, "noise_sigma", R.noise_sigma);
        cJSON_AddNumberToObject(j, "rows", (double)A->n_rows);
        cJSON_AddNumberToObject(j, "heart_nodes", (double)A->n_frames);
        cJSON_AddNumberToObject(j, "frames", (double)X->n_frames);
        cJSON_AddNumberToObject(j, "lambda_used", R.chosen_lambda);
        cJSON_AddNumberToObject(j, "lambda_corner", R.corner_lambda);
        cJSON_AddNumberToObject(j, "null_space_dim", (double)R.null_dim);
        if (!per && o.rule != THX_LAMBDA_FIXED && o.method != THX_INVERSE_GREENSITE) {
            cJSON *fb = cJSON_AddObjectToObject(j, "fallback");
            cJSON_AddBoolToObject(fb, "on", !no_fallback);
            cJSON_AddNumberToObject(fb, "series_lambda", R.series_lambda);
            add_flags(fb, "series_flags", R.series_flags);
            cJSON_AddNumberToObject(fb, "noise_sigma", R.frame_noise);
            cJSON_AddStringToObject(fb, "noise_from", R.frame_noise_estimated ? "gcv" : "noise");
            cJSON_AddNumberToObject(fb, "frames", (double)R.n_fallback);
        } else if (per && o.rule != THX_LAMBDA_FIXED)
            add_flags(j, "series_flags", R.series_flags);
        {
            cJSON *cnt = cJSON_AddObjectToObject(j, "lambda_flag_frames");
            for (int b = 0; b < 4; b++) {
                size_t c = 0;
                for (size_t k = 0; k < X->n_frames; k++) c += (R.flags[k] >> b) & 1;
                cJSON_AddNumberToObject(cnt, flag_names[b], (double)c);
            }
        }
        cJSON_AddNumberToObject(j, "seconds_svd", R.t_svd);
        cJSON_AddNumberToObject(j, "seconds_frames", R.t_frames);
        cJSON_AddNumberToObject(j, "seconds_total", thx_wtime() - t0);
        if (R.n_components) {
            cJSON *cl = cJSON_AddArrayToObject(j, "component_lambda");
            for (size_t k = 0; k < R.n_components; k++) cJSON_AddItemToArray(cl, cJSON_CreateNumber(R.component_lambda[k]));
        }
        cJSON *sv = cJSON_AddArrayToObject(j, "singular_values");
        for (size_t k = 0; k < R.rank && sv; k++) cJSON_AddItemToArray(sv, cJSON_CreateNumber(R.sv[k]));
        for (size_t k = 0; k < X->n_frames; k++) {
            cJSON *e = cJSON_CreateObject();
            cJSON_AddNumberToObject(e, "frame", (double)(k + 1));
            if (isfinite(R.lambda[k])) cJSON_AddNumberToObject(e, "lambda", R.lambda[k]);
            else cJSON_AddNullToObject(e, "lambda");
            if (o.method == THX_INVERSE_TSVD) cJSON_AddNumberToObject(e, "kept", R.k[k]);
            add_flags(e, "flags", R.flags[k]);
            cJSON_AddNumberToObject(e, "residual", R.residual[k]);
            cJSON_AddNumberToObject(e, "solution_norm", R.seminorm[k]);
            if (truth) {
                if (isfinite(cc[k])) cJSON_AddNumberToObject(e, "cc", cc[k]);
                else cJSON_AddNullToObject(e, "cc");
                cJSON_AddNumberToObject(e, "re", re[k]);
            }
            cJSON_AddItemToArray(fr, e);
        }
        cJSON_AddItemToObject(j, "per_frame", fr);
        if (truth) {
            cJSON *c = cJSON_AddObjectToObject(j, "truth");
            cJSON_AddStringToObject(c, "series", realpath(truth_path, abs) ? abs : truth_path);
            if (truth_model) cJSON_AddStringToObject(c, "model", realpath(truth_model, abs) ? abs : truth_model);
            cJSON_AddNumberToObject(c, "cc_median", quantile(cc, X->n_frames, 0.5));
            cJSON_AddNumberToObject(c, "cc_p10", quantile(cc, X->n_frames, 0.1));
            cJSON_AddNumberToObject(c, "re_median", quantile(re, X->n_frames, 0.5));
            cJSON_AddNumberToObject(c, "re_p90", quantile(re, X->n_frames, 0.9));
        }
        char name[64];
        snprintf(name, sizeof name, "heart.%s", ext);
        cJSON_AddStringToObject(files, "heart", name);
        cJSON_AddStringToObject(files, "lambda", "lambda.txt");
        if (R.n_curve && pictures) {
            cJSON_AddStringToObject(files, "lcurve", "lcurve.svg");
            cJSON_AddStringToObject(files, "lcurve_png", "lcurve.png");
            cJSON *lc = cJSON_AddObjectToObject(j, "lcurve_mark");
            if (R.mark_frame >= 0) cJSON_AddNumberToObject(lc, "frame", (double)(R.mark_frame + 1));
            else cJSON_AddNullToObject(lc, "frame");
            cJSON_AddNumberToObject(lc, "lambda", R.mark_lambda);
            cJSON_AddNumberToObject(lc, "residual", R.mark_residual);
            cJSON_AddNumberToObject(lc, "solution_norm", R.mark_seminorm);
            cJSON_AddNumberToObject(lc, "corner_lambda", R.mark_corner_lambda);
        }
        cJSON_AddItemToObject(j, "files", files);
        st = cli_outdir_finish(ctx, &od, "inverse.json", j, st);
        if (st != THX_OK) goto fail;
    }
    if (verbose >= 0) {
        const char *rn = o.rule == THX_LAMBDA_FIXED ? "fixed" : thx_lambda_rule_name(o.rule);
        char w[256];
        snprintf(w, sizeof w, "λ (%s) at the small end of its search range (%s)", rn,
                 o.method == THX_INVERSE_TSVD ? "every nonzero component kept" : "the smallest nonzero singular value");
        warn_flag(&R, THX_LAMBDA_AT_LOW, w);
        snprintf(w, sizeof w, "λ (%s) at the large end of its search range (%s)", rn,
                 o.method == THX_INVERSE_TSVD ? "one component kept" : "the largest singular value");
        warn_flag(&R, THX_LAMBDA_AT_HIGH, w);
        snprintf(w, sizeof w, "%s found no %s", rn, o.rule == THX_LAMBDA_CRESO ? "local maximum" : "corner");
        warn_flag(&R, THX_LAMBDA_NO_CORNER, w);
        if (R.series_flags & (THX_LAMBDA_AT_LOW | THX_LAMBDA_AT_HIGH | THX_LAMBDA_NO_CORNER))
            fprintf(stderr, "thorax inverse: warning: the series' λ %.4g (%s) is %s\n",
                    per ? R.chosen_lambda : R.series_lambda, rn,
                    R.series_flags & THX_LAMBDA_NO_CORNER ? "not at a corner"
                    : R.series_flags & THX_LAMBDA_AT_LOW  ? "at the small end of its search range"
                                                          : "at the large end of its search range");
        if (R.flags) {
            snprintf(w, sizeof w, "data below the noise level (σ %.4g%s): %s", R.frame_noise,
                     R.frame_noise_estimated ? ", the series' GCV estimate" : "",
                     no_fallback ? "their own λ kept (--no-fallback)" : "the series' λ used");
            warn_flag(&R, THX_LAMBDA_BELOW_NOISE, w);
        }
        if (truth) {
            printf("frame CC RE\n");
            for (size_t k = 0; k < X->n_frames; k++) printf("%zu %.4f %.4f\n", k + 1, cc[k], re[k]);
            printf("median CC %.4f, 10th percentile CC %.4f; median RE %.4f, 90th percentile RE %.4f\n",
                   quantile(cc, X->n_frames, 0.5), quantile(cc, X->n_frames, 0.1), quantile(re, X->n_frames, 0.5),
                   quantile(re, X->n_frames, 0.9));
        }
        printf("%zu frames, %zu x %zu matrix, %s, lambda %s (%s): SVD %.3f s, frames %.3f s\n", X->n_frames, A->n_rows,
               A->n_frames, thx_inverse_method_name(o.method), o.rule == THX_LAMBDA_FIXED ? lambda_s : thx_lambda_rule_name(o.rule),
               per ? "series" : "frame", R.t_svd, R.t_frames);
        printf("wrote %s\n", out);
    }
    goto end;
fail:
    /* a message naming the temporary directory names the output instead */
    if (od.tmp[0] && strstr(thx_ctx_message(ctx), od.tmp)) {
        char msg[8192], *at;
        snprintf(msg, sizeof msg, "%s", thx_ctx_message(ctx));
        at = strstr(msg, od.tmp);
        if (at) {
            char rest[8192];
            snprintf(rest, sizeof rest, "%s", at + strlen(od.tmp));
            *at = '\0';
            st = thx_error(ctx, st, "%s%s%s", msg, out, rest);
        }
    }
    rc = cli_fail(ctx, "inverse", st);
end:
    free(cc);
    free(re);
    free(tv);
    free(near);
    thx_inverse_report_free(&R);
    thx_series_destroy(&A);
    thx_series_destroy(&B);
    thx_series_destroy(&X);
    thx_series_destroy(&truth);
    thx_model_destroy(&hm);
    thx_model_destroy(&tm);
    thx_ctx_destroy(&ctx);
    return rc;
}
