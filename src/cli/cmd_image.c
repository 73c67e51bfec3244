/* thorax image: image volumes (NIfTI, NRRD, MetaImage; DICOM series): what one holds (its grid, its
 * orientation in the patient's frame, its values and, for a label map, the voxels of each label), or
 * a conversion between the formats. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "cli/cli.h"
#include "thorax/image/image.h"
#include "thorax/image/segment.h"

/* Up to 256 distinct values and their voxel counts, in increasing order; *n_out = 257 when there
 * are more. */
static void label_counts(const thx_image *img, float *val, size_t *cnt, int *n_out)
{
    int n = 0;
    size_t count = thx_image_count(img);
    for (size_t q = 0; q < count; q++) {
        float v = img->v[q];
        int lo = 0, hi = n;
        while (lo < hi) {
            int mid = (lo + hi) / 2;
            if (val[mid] < v) lo = mid + 1;
            else hi = mid;
        }
        if (lo < n && val[lo] == v) {
            cnt[lo]++;
            continue;
        }
        if (n == 256) {
            *n_out = 257;
            return;
        }
        memmove(val + lo + 1, val + lo, (size_t)(n - lo) * sizeof *val);
        memmove(cnt + lo + 1, cnt + lo, (size_t)(n - lo) * sizeof *cnt);
        val[lo] = v;
        cnt[lo] = 1;
        n++;
    }
    *n_out = n;
}

/* The RAS letter an index axis points toward (its largest component) and that component's |cosine|. */
static char toward(const thx_image *img, int c, double *cosine)
{
    int k = 0;
    for (int r = 1; r < 3; r++)
        if (fabs(img->dir[r * 3 + c]) > fabs(img->dir[k * 3 + c])) k = r;
    double v = img->dir[k * 3 + c];
    *cosine = fabs(v);
    static const char pos[] = "RAS", neg[] = "LPI";
    return v >= 0 ? pos[k] : neg[k];
}

/* The anatomical meaning of the grid: the index axis pointing most nearly superior, anterior and left,
 * and what the planes of constant k are. */
typedef struct {
    int axis[3], sign[3]; /* superior, anterior, left */
    double cosine[3];
    const char *planes;   /* "axial", "coronal", "sagittal" */
    int oblique;
} meaning;

static void image_meaning(const thx_image *img, meaning *m)
{
    thx_image_axes(img, &m->axis[0], &m->sign[0], &m->axis[1], &m->sign[1], NULL);
    m->axis[2] = 3 - m->axis[0] - m->axis[1];
    m->sign[2] = img->dir[0 * 3 + m->axis[2]] <= 0 ? 1 : -1; /* left is -x in RAS */
    m->cosine[0] = fabs(img->dir[2 * 3 + m->axis[0]]);
    m->cosine[1] = fabs(img->dir[1 * 3 + m->axis[1]]);
    m->cosine[2] = fabs(img->dir[0 * 3 + m->axis[2]]);
    double ck;
    char t = toward(img, 2, &ck);
    m->planes = t == 'S' || t == 'I' ? "axial" : t == 'A' || t == 'P' ? "coronal" : "sagittal";
    m->oblique = !thx_image_axis_aligned(img);
}

static const char *const axis_name[3] = {"i", "j", "k"};

static void print_info(const thx_image *img)
{
    meaning m;
    image_meaning(img, &m);
    float lo, hi;
    thx_image_range(img, &lo, &hi);
    printf("file        %s\n", img->path);
    printf("format      %s\n", img->format);
    printf("stored      %s%s\n", img->stored_type, img->integral ? " (integers: a label map candidate)" : "");
    printf("dimensions  %zu x %zu x %zu (%zu voxels)\n", img->n[0], img->n[1], img->n[2], thx_image_count(img));
    printf("spacing     %.10g x %.10g x %.10g mm\n", img->spacing[0], img->spacing[1], img->spacing[2]);
    printf("origin      %.10g %.10g %.10g mm (RAS, the centre of voxel 0,0,0)\n", img->origin[0], img->origin[1],
           img->origin[2]);
    printf("direction   columns = RAS unit vectors of the index axes i, j, k\n");
    for (int r = 0; r < 3; r++)
        printf("            %c %11.8f %11.8f %11.8f\n", "RAS"[r], img->dir[r * 3 + 0], img->dir[r * 3 + 1],
               img->dir[r * 3 + 2]);
    printf("axes       ");
    for (int c = 0; c < 3; c++) {
        double cs;
        char t = toward(img, c, &cs);
        printf(" %s toward %c (cos %.6f)%s", axis_name[c], t, cs, c < 2 ? "," : "\n");
    }
    static const char *const what[3] = {"superior", "anterior", "left"};
    for (int w = 0; w < 3; w++)
        printf("%-11s %s%s (cos %.6f)\n", what[w], m.sign[w] > 0 ? "+" : "-", axis_name[m.axis[w]], m.cosine[w]);
    printf("planes      %s%s (planes of constant k)\n", m.oblique ? "oblique, nearest " : "", m.planes);
    printf("frame       %s\n", img->source_frame);
    printf("values      %.9g .. %.9g\n", lo, hi);
    if (img->integral) {
        float val[256];
        size_t cnt[256];
        int n = 0;
        label_counts(img, val, cnt, &n);
        double ml = img->spacing[0] * img->spacing[1] * img->spacing[2] / 1000.0;
        if (n > 256) {
            printf("labels      more than 256 distinct values (not a label map)\n");
        } else {
            printf("labels      %d distinct values (value: voxels, mL)\n", n);
            for (int k = 0; k < n; k++) printf("  %10.9g: %zu voxels, %.6g mL\n", val[k], cnt[k], (double)cnt[k] * ml);
        }
    }
    printf("sha256      %s\n", img->sha256);
}

static cJSON *vec3(const double *v)
{
    return cJSON_CreateDoubleArray(v, 3);
}

static int print_json(const thx_image *img)
{
    meaning m;
    image_meaning(img, &m);
    float lo, hi;
    thx_image_range(img, &lo, &hi);
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "file", img->path);
    cJSON_AddStringToObject(j, "format", img->format);
    cJSON_AddStringToObject(j, "stored_type", img->stored_type);
    cJSON_AddBoolToObject(j, "integral", img->integral);
    double dims[3] = {(double)img->n[0], (double)img->n[1], (double)img->n[2]};
    cJSON_AddItemToObject(j, "dimensions", vec3(dims));
    cJSON_AddItemToObject(j, "spacing_mm", vec3(img->spacing));
    cJSON_AddItemToObject(j, "origin_ras_mm", vec3(img->origin));
    cJSON *dir = cJSON_CreateArray();
    for (int r = 0; r < 3; r++) cJSON_AddItemToArray(dir, vec3(img->dir + 3 * r));
    cJSON_AddItemToObject(j, "direction_rows", dir);
    static const char *const what[3] = {"superior", "anterior", "left"};
    for (int w = 0; w < 3; w++) {
        cJSON *a = cJSON_CreateObject();
        cJSON_AddStringToObject(a, "axis", axis_name[m.axis[w]]);
        cJSON_AddNumberToObject(a, "sign", m.sign[w]);
        cJSON_AddNumberToObject(a, "cosine", m.cosine[w]);
        cJSON_AddItemToObject(j, what[w], a);
    }
    cJSON_AddStringToObject(j, "planes", m.planes);
    cJSON_AddBoolToObject(j, "oblique", m.oblique);
    cJSON_AddStringToObject(j, "source_frame", img->source_frame);
    cJSON_AddNumberToObject(j, "min", lo);
    cJSON_AddNumberToObject(j, "max", hi);
    cJSON *labels = cJSON_CreateNull();
    if (img->integral) {
        float val[256];
        size_t cnt[256];
        int n = 0;
        label_counts(img, val, cnt, &n);
        if (n <= 256) {
            cJSON_Delete(labels);
            labels = cJSON_CreateArray();
            double ml = img->spacing[0] * img->spacing[1] * img->spacing[2] / 1000.0;
            for (int k = 0; k < n; k++) {
                cJSON *l = cJSON_CreateObject();
                cJSON_AddNumberToObject(l, "value", val[k]);
                cJSON_AddNumberToObject(l, "voxels", (double)cnt[k]);
                cJSON_AddNumberToObject(l, "ml", (double)cnt[k] * ml);
                cJSON_AddItemToArray(labels, l);
            }
        }
    }
    cJSON_AddItemToObject(j, "labels", labels);
    cJSON_AddStringToObject(j, "sha256", img->sha256);
    char *text = cJSON_Print(j);
    cJSON_Delete(j);
    if (!text) return 1;
    printf("%s\n", text);
    free(text);
    return 0;
}

/* "LO:HI=LABEL[/CLOSE]" (LO or HI may be empty: no bound) -> *t; 0, or -1 with a reason in why. */
static int parse_tissue(const char *spec, thx_threshold *t, const char **why)
{
    char buf[128];
    if (strlen(spec) >= sizeof buf) return *why = "too long", -1;
    snprintf(buf, sizeof buf, "%s", spec);
    char *eq = strchr(buf, '='), *colon = strchr(buf, ':');
    if (!eq || !colon || colon > eq) return *why = "expected LO:HI=LABEL[/CLOSE_MM]", -1;
    *eq = *colon = '\0';
    char *end;
    t->lo = -INFINITY;
    t->hi = INFINITY;
    if (buf[0] && (t->lo = strtod(buf, &end), *end || !isfinite(t->lo))) return *why = "LO is not a number", -1;
    if (colon[1] && (t->hi = strtod(colon + 1, &end), *end || !isfinite(t->hi))) return *why = "HI is not a number", -1;
    char *slash = strchr(eq + 1, '/');
    t->close_mm = 0;
    if (slash) {
        *slash = '\0';
        t->close_mm = strtod(slash + 1, &end);
        if (!slash[1] || *end || !isfinite(t->close_mm) || t->close_mm < 0)
            return *why = "CLOSE_MM is not a number >= 0", -1;
    }
    long lab = strtol(eq + 1, &end, 10);
    if (!eq[1] || *end || lab < 1 || lab > 65535) return *why = "LABEL is not an integer in 1..65535", -1;
    t->label = (int)lab;
    if (!(t->lo <= t->hi)) return *why = "LO is above HI", -1;
    return 0;
}

#define MAX_TISSUES 16

/* thorax image label: thresholds and clean-up (thorax/image/segment.h). */
static int run_label(thx_ctx *ctx, const char *cmd, const thx_image *img, const char *const *specs, int n_specs,
                     int largest, int fill, const char *out)
{
    thx_threshold t[MAX_TISSUES];
    for (int k = 0; k < n_specs; k++) {
        const char *why = "";
        if (parse_tissue(specs[k], &t[k], &why) != 0) {
            fprintf(stderr, "thorax %s: --tissue '%s': %s\n", cmd, specs[k], why);
            return 2;
        }
    }
    thx_segment_opts so = {t, (size_t)n_specs, largest, fill};
    thx_segment_report rep;
    thx_image lab;
    thx_status st = thx_image_segment(ctx, img, &so, &lab, &rep);
    if (st) return cli_fail(ctx, cmd, st);
    double voxel_ml = img->spacing[0] * img->spacing[1] * img->spacing[2] / 1000.0;
    for (int k = 0; k < n_specs && k < 16; k++)
        printf("label %d: %zu voxels (%.1f mL); %zu outside the largest component dropped, %zu filled in the planes\n",
               t[k].label, rep.voxels[k], (double)rep.voxels[k] * voxel_ml, rep.dropped[k], rep.filled[k]);
    st = thx_image_write(ctx, &lab, out, NULL);
    thx_image_free(&lab);
    if (st) return cli_fail(ctx, cmd, st);
    thx_log(ctx, THX_LOG_INFO, "wrote %s", out);
    return 0;
}

int cmd_image(int argc, char **argv)
{
    const char *cmd = "image";
    const char *out = NULL, *type = NULL, *series = NULL;
    int verbose = 0, json = 0, n_tissues = 0, largest = 0, fill = 0;
    const char *tissues[MAX_TISSUES];
    cli_opt opts[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "OUT", .s = &out,
         .help = "image to write (convert); the format by its name: .nii, .nii.gz, .nrrd, .mha"},
        {.name = "--type", .type = CLI_STRING, .meta = "T", .s = &type,
         .def = "int16, uint8 or int32 for integers as their range needs, else float32",
         .help = "convert: the voxel type written: uint8, int16, uint16, int32 or float32 (a value it cannot hold "
                 "exactly is an error)"},
        {.name = "--series", .type = CLI_STRING, .meta = "S", .s = &series,
         .help = "DICOM: the series to read when a folder holds several (its UID, or its number as info lists them)"},
        {.name = "--json", .type = CLI_FLAG, .i = &json, .help = "info: print as JSON"},
        {.name = "--tissue", .type = CLI_STRING, .meta = "LO:HI=LABEL[/MM]", .flags = CLI_REPEAT, .sv = tissues,
         .count = &n_tissues, .max = MAX_TISSUES,
         .help = "label: voxels with LO <= value <= HI (either may be left empty) become LABEL (1..65535), the region "
                 "closed by a ball of MM; outer tissue first (skin, then bone), each later one kept inside it"},
        {.name = "--largest", .type = CLI_FLAG, .i = &largest,
         .help = "label: keep each tissue's largest 6-connected component (drops a CT table, a head holder, speckle)"},
        {.name = "--fill-planes", .type = CLI_FLAG, .i = &fill,
         .help = "label: fill each plane's holes along the superior axis (sinuses join the head; a skull becomes the "
                 "inside of its outer surface), the outside flooding against the region closed in the plane by MM"},
        {.name = "-v", .type = CLI_COUNT, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_COUNT, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE, .help = "less logging"},
    };
    cli_command c = {
        .name = cmd,
        .usage = "info IMG [--json] [--series]\nconvert IMG -o [--type] [--series]\n"
                 "label IMG --tissue... [--largest] [--fill-planes] -o [--series]",
        .about = "Image volumes: scans and label maps, the model's starting point (paper 3.1).\n"
                 "\n"
                 "  info IMG           prints the format, the stored voxel type, the dimensions,\n"
                 "                     the spacing, the origin, the direction matrix and what it\n"
                 "                     means (the index axis pointing superior, anterior and\n"
                 "                     left, with its cosine; axial, coronal or sagittal planes,\n"
                 "                     or oblique), the frame the file declared, the value range,\n"
                 "                     for integer images with at most 256 distinct values each\n"
                 "                     label's voxels and volume (mL), and the file's SHA-256\n"
                 "  convert IMG -o OUT reads IMG and writes it as OUT (atomically; only over an\n"
                 "                     image thorax wrote): the same voxels and geometry\n"
                 "  label IMG -o OUT   a label map from a scan by value ranges (--tissue, outer\n"
                 "                     first), each region closed, cut to its largest component\n"
                 "                     and filled plane by plane as asked; prints each label's\n"
                 "                     voxels and what the clean-up dropped and filled. For\n"
                 "                     thorax digitize or thorax surfaces LABELS --label ...\n"
                 "\n"
                 "Read: NIfTI-1 and NIfTI-2 (.nii, .nii.gz: sform, else qform, else pixdim),\n"
                 "NRRD (.nrrd, .nhdr with its data file: raw, gzip or ascii; space RAS, LAS,\n"
                 "LPS or scanner-xyz), MetaImage (.mha, .mhd with its data file; ITK's LPS).\n"
                 "Written: .nii, .nii.gz, .nrrd (gzip), .mha (zlib). Every image is held in\n"
                 "RAS millimetres (docs/formats.md, \"Images\"). A file whose content is not what\n"
                 "its name says, shorter than its header claims, with NaN values, a spacing\n"
                 "<= 0 or a skewed grid is refused with a message naming the file.\n",
        .epilog = "Exit status: 0 ok, 1 error (a bad image: nothing written), 2 bad usage.\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
    };
    int pr = cli_parse(&c, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (c.n_pos > 2) return cli_usage_error(cmd, "unexpected argument '%s' (one image expected)", c.pos[2]);
    const char *sub = c.n_pos > 0 ? c.pos[0] : NULL, *in = c.n_pos > 1 ? c.pos[1] : NULL;
    if (!sub) return cli_usage_error(cmd, "no subcommand given (info, convert or label)");
    int convert = !strcmp(sub, "convert"), label = !strcmp(sub, "label");
    if (!convert && !label && strcmp(sub, "info") != 0)
        return cli_usage_error(cmd, "unknown subcommand '%s' (info, convert or label)", sub);
    if (!in) return cli_usage_error(cmd, "%s: no image given", sub);
    if ((convert || label) && !out) return cli_usage_error(cmd, "%s: no output file given (-o OUT)", sub);
    if ((convert || label) && json) return cli_usage_error(cmd, "--json goes with info");
    if (!convert && !label && out) return cli_usage_error(cmd, "info: -o applies only to convert and label");
    if (!convert && type) return cli_usage_error(cmd, "--type applies only to convert");
    if (!label && (n_tissues || largest || fill))
        return cli_usage_error(cmd, "--tissue, --largest and --fill-planes apply only to label");
    if (label && n_tissues == 0) return cli_usage_error(cmd, "label: no --tissue LO:HI=LABEL given");

    thx_ctx *ctx = cli_ctx(verbose);
    thx_image img;
    thx_image_read_opts ro = {.series = series};
    int rc = 0;
    thx_status st = thx_image_read(ctx, in, &ro, &img);
    if (st) {
        rc = cli_fail(ctx, cmd, st);
        goto done;
    }
    if (label) {
        rc = run_label(ctx, cmd, &img, tissues, n_tissues, largest, fill, out);
    } else if (!convert) {
        rc = json ? print_json(&img) : (print_info(&img), 0);
    } else if ((st = thx_image_write(ctx, &img, out, type)) != THX_OK) {
        rc = cli_fail(ctx, cmd, st);
    } else {
        thx_log(ctx, THX_LOG_INFO, "wrote %s (%zu x %zu x %zu voxels)", out, img.n[0], img.n[1], img.n[2]);
    }
    thx_image_free(&img);
done:
    thx_ctx_destroy(&ctx);
    return rc;
}
