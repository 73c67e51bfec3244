/* thorax electrodes / thorax beat: the phantom's electrodes on a model's outer
 * surface (the 12-lead positions and a body-surface-mapping array), and the
 * phantom's heartbeat as epicardial potentials (paper 4.1); both in the
 * model's anatomical frame (model.json "frame"; a model without one is refused). */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include <cjson/cJSON.h>

#include "cli/cli.h"
#include "cli/cli_fem.h"
#include "thorax/io/series_file.h"
#include "thorax/io/model_dir.h"
#include "thorax/model/electrodes.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/leads/leads.h"
#include "thorax/phantom/phantom.h"
/* ------------------------------------------------------------ electrodes */

static void help_electrodes(void)
{
    printf("usage: thorax electrodes MODEL [--array N] [-o DIR]\n\n"
           "Places the phantom's electrodes on the model's outer surface (role outer),\n"
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
           "them from `thorax phantom` contours). The 12 leads are printed (nodes 1-based).\n\n"
           "options:\n"
           "  -o, --output DIR   directory to write into (created if missing; default\n"
           "                     MODEL/electrodes; note that commands that rewrite the\n"
           "                     model, such as `thorax mesh`, replace MODEL whole)\n"
           "  --array N          electrodes in the array (default 192; 0 = no array.txt)\n"
           "  -v, -q             more / less logging\n"
           "  -h, --help         this text\n\n"
           "Exit status: 0 ok, 1 error (nothing written), 2 bad usage.\n");
}

int cmd_electrodes(int argc, char **argv)
{
    const char *cmd = "electrodes";
    const char *in = NULL, *out = NULL;
    long n_array = 192;
    int verbose = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            help_electrodes();
            return 0;
        } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            if (!v) return cli_usage_error(cmd, "%s needs a value", a);
            out = v;
            i++;
        } else if (!strcmp(a, "--array")) {
            if (cli_parse_int(cmd, a, v, &n_array)) return 2;
            i++;
            if (n_array < 0 || n_array > 100000) return cli_usage_error(cmd, "--array must be between 0 and 100000");
        } else if (!strcmp(a, "-v")) {
            verbose = 1;
        } else if (!strcmp(a, "-q")) {
            verbose = -1;
        } else if (a[0] == '-' && a[1]) {
            return cli_usage_error(cmd, "unknown option '%s'", a);
        } else if (!in) {
            in = a;
        } else {
            return cli_usage_error(cmd, "more than one model given");
        }
    }
    if (!in) return cli_usage_error(cmd, "no model given");
    char dir[2048], p12[2100], parr[2100];
    if (out) snprintf(dir, sizeof dir, "%s", out);
    else snprintf(dir, sizeof dir, "%s/electrodes", in);
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
    if (mkdir(dir, 0755) != 0 && errno != EEXIST) {
        fprintf(stderr, "thorax %s: cannot create directory %s: %s\n", cmd, dir, strerror(errno));
        rc = 1;
        goto done;
    }
    st = thx_electrodes_write(ctx, e12, p12);
    if (st == THX_OK && ea) st = thx_electrodes_write(ctx, ea, parr);
    if (st == THX_OK) {
        /* the folder's manifest: it marks the folder as thorax's, so that a model holding it (the
           default place) can still be rewritten (thorax/core/fileio.h) */
        cJSON *j = cJSON_CreateObject(), *files = j ? cJSON_AddObjectToObject(j, "files") : NULL;
        char mpath[PATH_MAX + 32];
        snprintf(mpath, sizeof mpath, "%s/electrodes.json", dir);
        if (!files) { cJSON_Delete(j); st = thx_error(ctx, THX_ENOMEM, "out of memory"); }
        else {
            cJSON_AddStringToObject(j, "format", "thorax-electrodes");
            cJSON_AddNumberToObject(j, "version", 1);
            cJSON_AddStringToObject(files, "12lead", "12lead.txt");
            if (ea) cJSON_AddStringToObject(files, "array", "array.txt");
            st = cli_write_json(ctx, mpath, j);
        }
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

static void help_beat(void)
{
    printf("usage: thorax beat MODEL -o FILE [--frames N] [--dt MS] [--peak MV] [--format text|raw|mat]\n\n"
           "The phantom's heartbeat as epicardial potentials: a current dipole at the\n"
           "centre of the model's heart surface (role heart) traces a vectorcardiogram -\n"
           "P loop, PR segment, QRS loop (90 ms, left-inferior-posterior), ST segment,\n"
           "T loop, baseline (heart rate about 90/min; docs/decisions.md; directions in\n"
           "the model's anatomical frame, model.json \"frame\": a model without one is\n"
           "refused, give --up/--front to thorax import) - in an\n"
           "unbounded homogeneous medium; the potentials at the heart's nodes are scaled\n"
           "so that the largest |potential| over the beat is the peak. Writes a time\n"
           "series (docs/formats.md, \"Time series\"): rows = the heart surface's nodes in\n"
           "order, frames at t = f * dt ms, unit mV.\n\n"
           "options:\n"
           "  -o, --output FILE  series to write (atomically)\n"
           "  --frames N         number of frames (default 500)\n"
           "  --dt MS            time step in ms (default 1)\n"
           "  --peak MV          largest |potential| on the heart over the beat (default 40)\n"
           "  --format F         text, raw or mat (default: from FILE's extension .txt,\n"
           "                     .dat, .raw, .mat)\n"
           "  -v, -q             more / less logging\n"
           "  -h, --help         this text\n\n"
           "Exit status: 0 ok, 1 error (nothing written), 2 bad usage.\n");
}

int cmd_beat(int argc, char **argv)
{
    const char *cmd = "beat";
    const char *in = NULL, *out = NULL, *format = NULL;
    int verbose = 0;
    thx_beat_opts o;
    thx_beat_opts_default(&o);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            help_beat();
            return 0;
        } else if (!strcmp(a, "-o") || !strcmp(a, "--output") || !strcmp(a, "--format")) {
            if (!v) return cli_usage_error(cmd, "%s needs a value", a);
            if (!strcmp(a, "--format")) format = v;
            else out = v;
            i++;
        } else if (!strcmp(a, "--frames")) {
            long n;
            if (cli_parse_int(cmd, a, v, &n)) return 2;
            i++;
            if (n < 1 || n > 10000000) return cli_usage_error(cmd, "--frames must be between 1 and 10000000");
            o.n_frames = (size_t)n;
        } else if (!strcmp(a, "--dt")) {
            if (cli_parse_double(cmd, a, v, &o.dt_ms)) return 2;
            i++;
            if (!(o.dt_ms > 0) || o.dt_ms > 1e6) return cli_usage_error(cmd, "--dt must be a positive number of ms");
        } else if (!strcmp(a, "--peak")) {
            if (cli_parse_double(cmd, a, v, &o.peak_mv)) return 2;
            i++;
            if (!(o.peak_mv > 0) || o.peak_mv > 1e12) return cli_usage_error(cmd, "--peak must be a positive number of mV");
        } else if (!strcmp(a, "-v")) {
            verbose = 1;
        } else if (!strcmp(a, "-q")) {
            verbose = -1;
        } else if (a[0] == '-' && a[1]) {
            return cli_usage_error(cmd, "unknown option '%s'", a);
        } else if (!in) {
            in = a;
        } else {
            return cli_usage_error(cmd, "more than one model given");
        }
    }
    if (!in) return cli_usage_error(cmd, "no model given");
    if (!out) return cli_usage_error(cmd, "no output file given (-o FILE)");
    thx_series_format fmt = THX_SERIES_AUTO;
    if (thx_series_output_format(format, out, &fmt) != 0) {
        if (format) return cli_usage_error(cmd, "unknown format '%s' (text, raw or mat)", format);
        return cli_usage_error(cmd, "cannot tell the format of '%s' from its extension (.txt, .dat, .raw, .mat); "
                                    "give --format",
                               out);
    }

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
        printf("wrote %s: %zu nodes of surface %s x %zu frames (0 .. %g ms), peak %g mV\n%s\n", out, s->n_rows,
               heart->name, s->n_frames, s->time[s->n_frames - 1], o.peak_mv, s->label);
    thx_series_destroy(&s);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return rc;
}
