/*
 * thorax phantom: writes the built-in synthetic thorax (include/thorax/phantom/phantom.h)
 * as hand-digitized contours, the input of `thorax surfaces`; or (--image) as a label map or a
 * simulated CT or MR scan, or any model's closed surfaces voxelized (--from;
 * thorax/phantom/voxelize.h).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/cli.h"
#include "thorax/io/contours_file.h"
#include "thorax/io/model_dir.h"
#include "thorax/image/image.h"
#include "thorax/model/model.h"
#include "thorax/phantom/voxelize.h"
#include "thorax/core/fileio.h"
#include "thorax/phantom/phantom.h"
static const char *CMD = "phantom";

/* Writes contours to standard output through a temporary file: the writer is
 * atomic by path, and the text must be complete before any of it is shown. The
 * file goes into a private temporary directory (the writer replaces only a file
 * that is thorax's own, so it must not exist beforehand). */
static thx_status write_stdout(thx_ctx *ctx, const thx_contours *c, const char *comment)
{
    const char *tmp = getenv("TMPDIR");
    char dir[1024], path[1100];
    snprintf(dir, sizeof dir, "%s/thorax-phantom-XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
    if (!mkdtemp(dir)) return thx_error(ctx, THX_EIO, "%s: cannot create a temporary directory", dir);
    snprintf(path, sizeof path, "%s/contours.txt", dir);
    thx_status st = thx_contours_write(ctx, c, path, comment);
    char *text = NULL;
    size_t len = 0;
    if (st == THX_OK) st = thx_read_file(ctx, path, &text, &len);
    if (st == THX_OK && (fwrite(text, 1, len, stdout) != len || fflush(stdout) != 0))
        st = thx_error(ctx, THX_EIO, "standard output: write failed");
    free(text);
    remove(path);
    rmdir(dir);
    return st;
}

/* --image: the phantom's anatomy (from == NULL) or MODEL's surfaces voxelized, written as a label map
 * or a simulated scan; the label table on standard output. */
typedef struct {
    const char *path, *from;
    double voxel, noise, bias;
    int modality, noise_kind;
    long sub;
    unsigned long seed;
} image_job;

static thx_status write_image(thx_ctx *ctx, const image_job *J)
{
    thx_status st = THX_OK;
    thx_model *m = NULL;
    thx_phantom_field *fld = NULL;
    thx_image lab, mix;
    memset(&lab, 0, sizeof lab);
    memset(&mix, 0, sizeof mix);
    enum { MAXR = 256 };
    char names[MAXR][64];
    thx_tissue tissue[MAXR];
    double values[MAXR];
    size_t nr = 0, mixed = 0;
    const int scan = J->modality != THX_MODALITY_LABELS;
    thx_voxelize_opts vo;
    thx_voxelize_opts_default(&vo);
    vo.sub = (int)J->sub;
    vo.values = scan ? values : NULL;
    int have_frame = 1;
    thx_frame fr = thx_frame_ras();
    double lo[3], hi[3];
    if (J->from) {
        THX_TRY(thx_model_read(ctx, J->from, &m));
        if (m->n_surfaces == 0 || m->n_surfaces + 1 > MAXR) {
            st = thx_error(ctx, THX_EINPUT, "%s: %zu surfaces (1..%d)", J->from, m->n_surfaces, MAXR - 1);
            goto done;
        }
        int has_fat = 0;
        for (size_t a = 0; a < m->n_surfaces; a++) has_fat |= m->surf[a]->role == THX_ROLE_FAT;
        nr = m->n_surfaces + 1;
        snprintf(names[0], sizeof names[0], "outside");
        tissue[0] = THX_TISSUE_AIR;
        for (size_t a = 0; a < m->n_surfaces; a++) {
            snprintf(names[a + 1], sizeof names[a + 1], "%s", m->surf[a]->name);
            tissue[a + 1] = thx_tissue_of_role(m->surf[a]->role, has_fat);
        }
        lo[0] = lo[1] = lo[2] = 1e300;
        hi[0] = hi[1] = hi[2] = -1e300;
        for (size_t a = 0; a < m->n_surfaces; a++)
            for (size_t q = 0; q < m->surf[a]->n_nodes * 3; q++) {
                lo[q % 3] = fmin(lo[q % 3], m->surf[a]->xyz[q]);
                hi[q % 3] = fmax(hi[q % 3], m->surf[a]->xyz[q]);
            }
        have_frame = m->frame.set;
        if (have_frame) fr = m->frame;
        else
            thx_log(ctx, THX_LOG_WARN, "%s has no anatomical frame: the image takes the model's axes as RAS "
                                       "(x right, y anterior, z superior)", J->from);
    } else {
        THX_TRY(thx_phantom_field_create(ctx, &fld));
        thx_phantom_bounds(fld, lo, hi);
        static const char *const PH[] = {"outside", "torso", "fat", "muscle", "lung_r", "lung_l", "heart"};
        static const thx_role ROLE[] = {THX_ROLE_OUTER, THX_ROLE_FAT, THX_ROLE_MUSCLE, THX_ROLE_LUNG, THX_ROLE_LUNG,
                                        THX_ROLE_HEART};
        nr = 7;
        tissue[0] = THX_TISSUE_AIR;
        for (size_t r = 0; r < nr; r++) {
            snprintf(names[r], sizeof names[r], "%s", PH[r]);
            if (r) tissue[r] = thx_tissue_of_role(ROLE[r - 1], 1);
        }
    }
    for (size_t r = 0; r < nr; r++) values[r] = thx_tissue_value((thx_modality)J->modality, tissue[r]);
    THX_TRY(thx_voxel_grid(ctx, lo, hi, J->voxel, 2, &lab));
    if (scan) {
        THX_TRY(thx_image_alloc(ctx, lab.n, &mix));
        memcpy(mix.spacing, lab.spacing, sizeof mix.spacing);
        memcpy(mix.origin, lab.origin, sizeof mix.origin);
        memcpy(mix.dir, lab.dir, sizeof mix.dir);
    }
    if (J->from) {
        const thx_surface **ss = thx_malloc(ctx, m->n_surfaces * sizeof *ss);
        if (!ss) { st = THX_ENOMEM; goto done; }
        for (size_t a = 0; a < m->n_surfaces; a++) ss[a] = m->surf[a];
        st = thx_voxelize(ctx, ss, m->n_surfaces, &vo, &lab, scan ? &mix : NULL);
        free(ss);
        if (st != THX_OK) goto done;
    } else {
        THX_TRY(thx_phantom_voxelize(ctx, &vo, &lab, scan ? &mix : NULL, &mixed));
    }
    /* model axes -> RAS: a signed permutation, so the voxels stay as they are and the geometry turns */
    if (have_frame) {
        double o[3];
        thx_frame_to_ras(&fr, lab.origin, o);
        for (int c = 0; c < 3; c++) {
            double e[3] = {c == 0, c == 1, c == 2}, q[3];
            thx_frame_to_ras(&fr, e, q);
            for (int r = 0; r < 3; r++) lab.dir[3 * r + c] = q[r];
        }
        memcpy(lab.origin, o, sizeof o);
        memcpy(mix.dir, lab.dir, sizeof mix.dir);
        memcpy(mix.origin, lab.origin, sizeof mix.origin);
    }
    snprintf(lab.source_frame, sizeof lab.source_frame, "%s", have_frame ? "RAS" : "model");
    snprintf(mix.source_frame, sizeof mix.source_frame, "%s", lab.source_frame);
    if (scan) THX_TRY(thx_scan_degrade(ctx, &mix, (thx_modality)J->modality, J->bias, J->noise,
                                       (thx_noise_kind)J->noise_kind, J->seed));
    THX_TRY(thx_image_write(ctx, scan ? &mix : &lab, J->path, scan ? "float32" : NULL));
    {
        size_t cnt[MAXR] = {0}, nv = thx_image_count(&lab);
        for (size_t q = 0; q < nv; q++) cnt[(size_t)lab.v[q]]++;
        double vv = lab.spacing[0] * lab.spacing[1] * lab.spacing[2];
        printf("# %s: %zu x %zu x %zu voxels of %g mm, %s; label table\n", J->path, lab.n[0], lab.n[1], lab.n[2],
               J->voxel, J->modality == THX_MODALITY_CT ? "CT (HU)" : J->modality == THX_MODALITY_MR ? "MR (T1-like)" : "labels");
        printf("# label region tissue value voxels volume_mm3\n");
        for (size_t r = 0; r < nr; r++)
            printf("%zu %s %s %g %zu %.1f\n", r, names[r], thx_tissue_name(tissue[r]),
                   scan ? values[r] : (double)r, cnt[r], (double)cnt[r] * vv);
        if (fflush(stdout) != 0) st = thx_error(ctx, THX_EIO, "standard output: write failed");
        if (!J->from) thx_log(ctx, THX_LOG_INFO, "%zu of %zu voxels on a boundary, sub-sampled %ld^3", mixed, nv, J->sub);
        thx_log(ctx, THX_LOG_INFO, "wrote %s", J->path);
    }
done:
    thx_image_free(&lab);
    thx_image_free(&mix);
    thx_model_destroy(&m);
    thx_phantom_field_destroy(&fld);
    return st;
}

int cmd_phantom(int argc, char **argv)
{
    thx_phantom_opts o;
    thx_phantom_opts_default(&o);
    const char *out = NULL, *beat = NULL;
    int verbose = 0;
    long seed = (long)o.seed;
    image_job J = {.voxel = 2.0, .sub = 4, .modality = THX_MODALITY_LABELS, .noise_kind = THX_NOISE_GAUSSIAN};
    static const cli_choice modalities[] = {
        {"labels", THX_MODALITY_LABELS}, {"ct", THX_MODALITY_CT}, {"mr", THX_MODALITY_MR}, {NULL, 0}};
    static const cli_choice kinds[] = {{"gaussian", THX_NOISE_GAUSSIAN}, {"rician", THX_NOISE_RICIAN}, {NULL, 0}};
    static const cli_choice resolutions[] = {{"high", THX_PHANTOM_HIGH}, {"medium", THX_PHANTOM_MEDIUM}, {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--resolution", .alias = "-r", .type = CLI_CHOICE, .choices = resolutions, .i = &o.resolution,
         .help = "high: every layer, 5 mm apart, node spacing 5 mm (thorax surfaces builds about 42,400 nodes and "
                 "84,800 triangles from it); medium: every second layer, node spacing 11 mm (about 9,400 nodes and "
                 "18,800 triangles)"},
        {.name = "--seed", .alias = "-s", .type = CLI_INT, .meta = "N", .l = &seed, .rule = CLI_GE,
         .bad = "--seed: the seed must be >= 0", .help = "random seed; the same seed gives byte-identical files"},
        {.name = "--jitter", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o.jitter_mm, .rule = CLI_GE,
         .bad = "--jitter: must be >= 0 mm",
         .help = "standard deviation of the point jitter normal to the outline; each point moves at most "
                 "min(2.5 sd, 1.5 mm)"},
        {.name = "--shift", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o.shift_mm, .rule = CLI_GE,
         .bad = "--shift: must be >= 0 mm", .help = "standard deviation of the whole-layer shifts (breathing)"},
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "FILE", .s = &out,
         .help = "output file, '-' for standard output; written atomically"},
        {.name = "-v", .type = CLI_SET, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE,
         .help = "more messages on standard error"},
        {.name = "-q", .type = CLI_SET, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE,
         .help = "fewer messages on standard error"},
        {.name = "--image", .type = CLI_OUTPUT, .meta = "IMG", .s = &J.path,
         .help = "instead of contours: the phantom's smooth anatomy (or --from MODEL's surfaces) as an image (.nii, "
                 ".nii.gz): a label map, or a simulated scan with --modality; prints the label table"},
        {.name = "--from", .type = CLI_INPUT, .meta = "MODEL", .s = &J.from,
         .help = "with --image: voxelize MODEL's closed surfaces (label 1 + the surface's number in the model; a "
                 "voxel takes the innermost surface, the smallest enclosing one) instead of the phantom"},
        {.name = "--voxel", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &J.voxel, .rule = CLI_GT | CLI_LE,
         .lo = 0, .hi = 100, .help = "with --image: voxel size (cubic voxels; faces on multiples of it)"},
        {.name = "--modality", .type = CLI_CHOICE, .choices = modalities, .i = &J.modality,
         .help = "with --image: labels (region numbers), ct (Hounsfield units) or mr (T1-weighted-like); ct and mr "
                 "mix the tissues by their partial volumes"},
        {.name = "--noise", .type = CLI_REAL, .meta = "SIGMA", .d = &J.noise, .rule = CLI_GE | CLI_FINITE,
         .help = "with --modality ct|mr: standard deviation of the noise, in the image's units"},
        {.name = "--noise-kind", .type = CLI_CHOICE, .choices = kinds, .i = &J.noise_kind,
         .help = "with --noise: gaussian (added) or rician (magnitude of a complex signal; mr only)"},
        {.name = "--bias", .type = CLI_REAL, .meta = "AMPL", .d = &J.bias, .rule = CLI_GT | CLI_LT, .lo = -1, .hi = 1,
         .help = "with --modality ct|mr: amplitude of the smooth multiplicative bias field 1 + AMPL q (|q| <= 1, "
                 "linear and quadratic across the grid; on CT it scales HU + 1000)"},
        {.name = "--sub", .type = CLI_INT, .meta = "N", .l = &J.sub, .rule = CLI_GE | CLI_LE, .lo = 1, .hi = 16,
         .help = "with --image: sub-samples per voxel side for the partial volume (N^3 points per boundary voxel "
                 "of the phantom; N x N exact rays per voxel of a model)"},
        {.name = "--beat", .type = CLI_INPUT, .meta = "MODEL", .s = &beat,
         .help = "instead: the phantom's heartbeat on MODEL's heart surface, the same as 'thorax beat MODEL' with the "
                 "other options (see thorax beat --help)"},
    };
    cli_command cmd = {
        .name = CMD,
        .usage = "[--resolution] [--seed] [--jitter] [--shift] -o\n"
                 "--image [--voxel] [--modality] [--noise] [--noise-kind] [--bias] [--seed] [--sub]\n"
                 "--image --from [--voxel] [--modality] [--noise] [--noise-kind] [--bias] [--seed] [--sub]\n"
                 "--beat -o=SERIES [beat options]",
        .about = "Writes a synthetic human thorax as hand-digitized contours (text format\n"
                 "'thorax-contours 1'): outer torso, subcutaneous fat/muscle interface, inner\n"
                 "border of the skeletal muscle, right and left lungs (crescent-shaped lower\n"
                 "layers around the heart and diaphragm), and the epicardium. The points imitate\n"
                 "hand digitization: uneven spacing, jitter, a shift of each whole layer\n"
                 "(breathing), random start points and directions. Deterministic for a seed.\n"
                 "With --image: the phantom's smooth anatomy as an image in RAS millimetres, a\n"
                 "label map (0 outside, 1 subcutaneous fat inside torso, 2 skeletal muscle inside\n"
                 "fat, 3 the rest inside muscle, 4 right lung, 5 left lung, 6 heart) or a scan\n"
                 "(--modality ct|mr: tissue intensities mixed by partial volume, noise, bias); with\n"
                 "--from MODEL, MODEL's closed surfaces instead. The label table goes to standard\n"
                 "output (docs/formats.md, \"Phantom images and voxelized models\").\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
    };
    /* --beat MODEL: the heartbeat (epicardial sequence) of a phantom model, as thorax beat, which
       reads the other options */
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], "--beat")) {
            if (i + 1 >= argc) return cli_usage_error(CMD, "--beat needs a model directory");
            char *args[64];
            int n = 0;
            args[n++] = "beat";
            args[n++] = argv[i + 1];
            for (int k = 1; k < argc && n < 63; k++)
                if (k != i && k != i + 1) args[n++] = argv[k];
            args[n] = NULL;
            return cmd_beat(n, args);
        }
    int pr = cli_parse(&cmd, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (cmd.n_pos) return cli_usage_error(CMD, "unknown argument '%s'", cmd.pos[0]);
    o.seed = (unsigned long)seed;
    if (J.path) {
        if (out) return cli_usage_error(CMD, "--image and -o: one output at a time");
        if (J.modality == THX_MODALITY_LABELS && (J.noise != 0 || J.bias != 0))
            return cli_usage_error(CMD, "--noise and --bias need --modality ct or mr (a label map is exact)");
        if (J.noise_kind == THX_NOISE_RICIAN && J.modality != THX_MODALITY_MR)
            return cli_usage_error(CMD, "--noise-kind rician is for --modality mr (a magnitude image)");
        J.seed = (unsigned long)seed;
        thx_ctx *ictx = cli_ctx(verbose);
        thx_status ist = write_image(ictx, &J);
        int irc = ist == THX_OK ? 0 : cli_fail(ictx, CMD, ist);
        thx_ctx_destroy(&ictx);
        return irc;
    }
    if (J.from) return cli_usage_error(CMD, "--from needs --image");
    if (!out) return cli_usage_error(CMD, "no output given (-o FILE, or -o - for standard output)");

    thx_ctx *ctx = cli_ctx(verbose);
    thx_contours *c = NULL;
    thx_phantom_counts est;
    thx_status st = thx_phantom_contours(ctx, &o, &c);
    if (st == THX_OK) st = thx_phantom_estimate(ctx, &o, &est);
    if (st == THX_OK) {
        /* The header records the options, not the raw command line: the output
         * then depends only on them, not on the name of the file. */
        const char *res = o.resolution == THX_PHANTOM_HIGH ? "high" : "medium";
        size_t loops = 0, points = 0;
        for (size_t s = 0; s < c->n_surfaces; s++)
            for (size_t l = 0; l < c->surf[s].n_layers; l++)
                for (size_t k = 0; k < c->surf[s].layers[l].n_loops; k++) {
                    loops++;
                    points += c->surf[s].layers[l].loops[k].n;
                }
        char comment[1024];
        snprintf(comment, sizeof comment,
                 "synthetic thorax, imitated hand digitization (thorax phantom)\n"
                 "command: thorax phantom --resolution %s --seed %lu --jitter %g --shift %g\n"
                 "%zu layers %g mm apart, %zu loops, %zu points; RAS coordinates, mm\n"
                 "expected model at spacing %g: about %zu surface nodes, %zu triangles",
                 res, o.seed, o.jitter_mm, o.shift_mm, est.layers,
                 o.resolution == THX_PHANTOM_HIGH ? 5.0 : 10.0, loops, points, c->spacing, est.nodes,
                 est.triangles);
        if (!strcmp(out, "-")) st = write_stdout(ctx, c, comment);
        else st = thx_contours_write(ctx, c, out, comment);
        if (st == THX_OK)
            thx_log(ctx, THX_LOG_INFO, "phantom (%s, seed %lu): %zu layers, %zu loops, %zu points -> %s", res, o.seed,
                    est.layers, loops, points, strcmp(out, "-") ? out : "standard output");
    }
    int rc = st == THX_OK ? 0 : cli_fail(ctx, CMD, st);
    thx_contours_destroy(&c);
    thx_ctx_destroy(&ctx);
    return rc;
}
