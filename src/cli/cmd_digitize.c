/* thorax digitize: a label map -> contours (paper 3.1: one closed loop per tissue boundary per
 * image plane, "a layer"; issue 25 item 2). The tracing is thorax/image/trace.h; this file parses
 * the --label specs, prints the report, and is shared with `thorax surfaces LABELS --label ...`. */
#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "thorax/geom/contours_valid.h"
#include "thorax/geom/surfaces.h"
#include "thorax/image/image.h"
#include "thorax/image/trace.h"
#include "thorax/io/contours_file.h"

#define MAX_TISSUES 64
#define MAX_VALUES 1024

/* One --label spec: VALUE[,VALUE...]=NAME:ROLE, VALUE an integer or "all" (every non-zero value).
 * 0, or the usage error's exit status (2) after the message. */
static int parse_label(const char *cmd, const char *spec, long *vals, size_t *nv, size_t cap, thx_trace_tissue *t,
                       char name[64])
{
    const char *eq = strchr(spec, '='), *colon = eq ? strchr(eq, ':') : NULL;
    if (!eq || !colon || eq == spec) {
        fprintf(stderr, "thorax %s: --label '%s': expected VALUE[,VALUE...]=NAME:ROLE (e.g. 1,2,3=torso:outer)\n", cmd, spec);
        return 2;
    }
    memset(t, 0, sizeof *t);
    t->values = vals + *nv;
    const char *p = spec;
    while (p < eq) {
        const char *e = p;
        while (e < eq && *e != ',') e++;
        char word[32];
        size_t len = (size_t)(e - p);
        if (len == 0 || len >= sizeof word) {
            fprintf(stderr, "thorax %s: --label '%s': an empty or overlong label value\n", cmd, spec);
            return 2;
        }
        memcpy(word, p, len);
        word[len] = '\0';
        if (strcmp(word, "all") == 0) t->all = 1;
        else {
            char *end;
            errno = 0;
            long v = strtol(word, &end, 10);
            if (*end || errno || end == word) {
                fprintf(stderr, "thorax %s: --label '%s': label value '%s' is not an integer (or 'all')\n", cmd, spec, word);
                return 2;
            }
            if (*nv >= cap) {
                fprintf(stderr, "thorax %s: more than %zu label values\n", cmd, cap);
                return 2;
            }
            vals[(*nv)++] = v;
            t->n_values++;
        }
        p = e < eq ? e + 1 : e;
        if (e < eq && p == eq) {
            fprintf(stderr, "thorax %s: --label '%s': an empty label value\n", cmd, spec);
            return 2;
        }
    }
    size_t nl = (size_t)(colon - eq - 1);
    int ok = nl >= 1 && nl <= 63;
    for (size_t k = 0; ok && k < nl; k++) {
        char ch = eq[1 + k];
        ok = isalnum((unsigned char)ch) || ch == '_' || ch == '.' || ch == '-';
    }
    if (!ok) {
        fprintf(stderr, "thorax %s: --label '%s': the name must be 1-63 characters of [A-Za-z0-9_.-]\n", cmd, spec);
        return 2;
    }
    memcpy(name, eq + 1, nl);
    name[nl] = '\0';
    t->name = name;
    if (thx_role_parse(colon + 1, &t->role) != 0) {
        fprintf(stderr, "thorax %s: --label '%s': unknown role '%s' (outer, fat, muscle, lung, heart, other)\n", cmd, spec,
                colon + 1);
        return 2;
    }
    return 0;
}

int cli_trace_labels(const char *cmd, const char *image, cli_trace_args *a, int verbose, thx_ctx *ctx,
                     thx_contours **out)
{
    static long vals[MAX_VALUES];
    static thx_trace_tissue tis[MAX_TISSUES];
    static char names[MAX_TISSUES][64];
    *out = NULL;
    size_t nv = 0;
    if (a->n_labels < 1) {
        fprintf(stderr, "thorax %s: no --label given: which label values make which surface (e.g. --label 1,2,3=torso:outer)\n", cmd);
        return 2;
    }
    if (a->n_labels > MAX_TISSUES) {
        fprintf(stderr, "thorax %s: more than %d --label options\n", cmd, MAX_TISSUES);
        return 2;
    }
    for (int k = 0; k < a->n_labels; k++) {
        int r = parse_label(cmd, a->labels[k], vals, &nv, MAX_VALUES, &tis[k], names[k]);
        if (r) return r;
        for (int j = 0; j < k; j++)
            if (strcmp(names[j], names[k]) == 0) {
                fprintf(stderr, "thorax %s: --label '%s': surface \"%s\" named twice\n", cmd, a->labels[k], names[k]);
                return 2;
            }
    }
    thx_trace_opts o;
    thx_trace_opts_default(&o);
    o.tissues = tis;
    o.n_tissues = (size_t)a->n_labels;
    o.spacing = a->spacing;
    if (a->min_size >= 0) o.min_size = (size_t)a->min_size;
    o.node_spacing = a->node_spacing;
    o.holes = a->holes;
    thx_image img;
    memset(&img, 0, sizeof img);
    thx_trace_report rep;
    memset(&rep, 0, sizeof rep);
    thx_contours *c = NULL;
    thx_status st = thx_image_read(ctx, image, NULL, &img);
    if (st == THX_OK) st = thx_image_trace(ctx, &img, &o, &c, &rep);
    /* loops the lacing would find without a partner once its splines resample them (small loops move):
       dropped here, as thorax surfaces will see them, and counted with the tracer's flat loops */
    if (st == THX_OK) {
        thx_surfaces_opts so;
        thx_surfaces_opts_default(&so);
        so.spacing = a->surfaces_spacing;
        if (a->surfaces_smoothing >= 0) so.smoothing = a->surfaces_smoothing;
        size_t *gone = calloc(c->n_surfaces ? c->n_surfaces : 1, sizeof *gone);
        st = gone ? thx_contours_drop_flat(ctx, c, &so, gone) : THX_ENOMEM;
        for (size_t k = 0; st == THX_OK && k < c->n_surfaces && k < rep.n_tissues; k++) {
            rep.tissue[k].n_flat_dropped += gone[k];
            rep.tissue[k].n_loops -= gone[k];
            rep.tissue[k].n_layers = c->surf[k].n_layers;
        }
        free(gone);
    }
    /* the contours' invariants (exact predicates), before anything is written */
    if (st == THX_OK) st = thx_contours_validate(ctx, c);
    if (st != THX_OK) {
        thx_image_free(&img);
        thx_trace_report_free(&rep);
        thx_contours_destroy(&c);
        return cli_fail(ctx, cmd, st);
    }
    for (size_t k = 0; k < rep.n_absent && k < THX_TRACE_SIZES_KEPT; k++)
        thx_log(ctx, THX_LOG_WARN, "%s: label value %ld (--label) is not in the image", image, rep.absent[k]);
    if (rep.oblique_deg > 1e-6)
        thx_log(ctx, THX_LOG_WARN,
                "%s: the image is oblique (its superior axis %.3g deg from RAS superior): the model's axes are the "
                "image's (z across the planes, y nearest anterior); frame +z +y is the nearest",
                image, rep.oblique_deg);
    for (size_t t = 0; t < rep.n_tissues; t++)
        if (rep.tissue[t].n_holes_open)
            thx_log(ctx, THX_LOG_WARN,
                    "%s: surface \"%s\": %zu filled hole%s open%s onto the tissue's outside on the next plane (the first "
                    "at z=%g mm): filled, the surface closes over what is not the tissue there (a lung around the "
                    "diaphragm's dome); --holes keep traces %s",
                    image, rep.tissue[t].name, rep.tissue[t].n_holes_open, rep.tissue[t].n_holes_open == 1 ? "" : "s",
                    rep.tissue[t].n_holes_open == 1 ? "s" : "", rep.tissue[t].z_hole_open,
                    rep.tissue[t].n_holes_open == 1 ? "it" : "them");
    if (verbose >= 0) {
        static const char axis[] = "ijk";
        printf("%s: %zu planes across index axis %c (superior), %g mm apart, z = %g .. %g mm; nodes %g mm apart\n",
               image, rep.n_planes, axis[rep.sup_axis], rep.plane_spacing, rep.z_first,
               rep.z_first + rep.plane_spacing * (double)(rep.n_planes - 1), rep.node_spacing);
        printf("%-16s %7s %7s %7s %7s %9s %7s %8s %9s %10s\n", "surface", "voxels", "layers", "loops", "holes",
               "islands", "flat", "trimmed", "removed", "cavities");
        for (size_t t = 0; t < rep.n_tissues; t++) {
            const thx_trace_tissue_report *r = &rep.tissue[t];
            printf("%-16s %7zu %7zu %7zu %7zu %9zu %7zu %8zu %9zu %10zu\n", r->name, r->voxels, r->n_layers,
                   r->n_loops, r->n_holes, r->n_islands_filled, r->n_flat_dropped, r->n_trimmed_layers, r->n_removed,
                   r->n_cavities);
        }
        printf("holes: %s; islands: loops inside a filled hole; flat: loops with no partner on either neighbouring "
               "plane, dropped; trimmed: layers on or beyond the end planes of the surface holding it (outer > fat > muscle > organs), dropped; removed/cavities: 3D components/cavities under %zu voxels (--min-size)\n",
               o.holes == THX_TRACE_HOLES_FILL ? "filled" : "kept as clockwise loops", o.min_size);
        for (size_t t = 0; t < rep.n_tissues; t++) {
            const thx_trace_tissue_report *r = &rep.tissue[t];
            if (r->n_components > 1 && r->component == 0) {
                printf("%s: %zu components (6-connected in 3D), a surface each, right to left:", r->tissue, r->n_components);
                for (size_t k = t; k < rep.n_tissues && k < t + r->n_components; k++)
                    printf(" %s (%zu voxels, centroid RAS x %.1f mm)", rep.tissue[k].name, rep.tissue[k].voxels,
                           rep.tissue[k].centroid_ras[0]);
                printf("\n");
            }
            if (r->component == 0 && r->components_dropped)
                printf("%s: %zu component%s one plane thick dropped\n", r->tissue, r->components_dropped,
                       r->components_dropped == 1 ? "" : "s");
            if (r->n_tiny)
                printf("%s: %zu loop%s of less than a voxel's in-plane area dropped (beads of a gently sloping "
                       "boundary; none with --min-size 0 or 1)\n", r->name, r->n_tiny, r->n_tiny == 1 ? "" : "s");
            if (r->contact_voxels)
                printf("%s: %zu voxels face a sibling tissue's (no voxel between): its boundary pulled in there\n",
                       r->name, r->contact_voxels);
        }
        for (size_t t = 0; t < rep.n_tissues; t++) {
            const thx_trace_tissue_report *r = &rep.tissue[t];
            if (!r->n_removed || r->component) continue;
            printf("%s: removed %zu component%s of %zu voxel%s in all (sizes:", r->tissue, r->n_removed,
                   r->n_removed == 1 ? "" : "s", r->removed_voxels, r->removed_voxels == 1 ? "" : "s");
            for (size_t k = 0; k < r->n_removed && k < THX_TRACE_SIZES_KEPT; k++) printf(" %zu", r->removed_size[k]);
            printf("%s)\n", r->n_removed > THX_TRACE_SIZES_KEPT ? " ..." : "");
        }
    }
    snprintf(a->format, sizeof a->format, "%s", img.format);
    snprintf(a->source_frame, sizeof a->source_frame, "%s", img.source_frame);
    memcpy(a->to_ras, rep.to_ras, sizeof a->to_ras);
    thx_image_free(&img);
    thx_trace_report_free(&rep);
    *out = c;
    return 0;
}

int cmd_digitize(int argc, char **argv)
{
    const char *out = NULL, *labels[MAX_TISSUES];
    int n_labels = 0, verbose = 0, axis = 0;
    long min_size = 8;
    cli_trace_args a = {0};
    a.surfaces_smoothing = -1; /* thorax surfaces' defaults */
    static const cli_choice axes[] = {{"superior", 0}, {NULL, 0}};
    static const cli_choice holes[] = {{"fill", THX_TRACE_HOLES_FILL}, {"keep", THX_TRACE_HOLES_KEEP}, {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "CONTOURS", .s = &out,
         .help = "contour file to write (replaced atomically; only over thorax's own contours)"},
        CLI_TRACE_OPTIONS(a, labels, n_labels, min_size, axis, axes, holes, "--spacing"),
        {.name = "--node-spacing", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &a.node_spacing,
         .rule = CLI_GE | CLI_FINITE, .bad = "--node-spacing must be >= 0", .def = "0",
         .note = "0 = the larger of the in-plane voxel size and the plane spacing",
         .help = "distance between the loops' nodes (the file's 'spacing', at which thorax surfaces resamples)"},
        {.name = "-v", .type = CLI_SET, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_SET, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE,
         .help = "less logging: no report, warnings and errors only"},
    };
    cli_command cmd = {
        .name = "digitize",
        .usage = "LABELS --label [--spacing] [--axis] [--min-size] [--node-spacing] [--holes] -o\n"
                 "SCAN",
        .about = "Traces a label map (NIfTI, or any image thorax reads, of integer labels) into\n"
                 "the contour file thorax surfaces reads: one closed loop per tissue boundary per\n"
                 "plane (paper 3.1, \"a layer\"). Planes are cut across the image's superior axis:\n"
                 "every image plane, or --spacing MM apart (the smoothed indicator interpolated).\n"
                 "Each tissue's indicator (1 inside its labels) is smoothed by a Gaussian of half a\n"
                 "voxel and traced by marching squares at 0.5 (sub-voxel vertices); the loops are\n"
                 "resampled at the node spacing. A surface of role 'outer' (the torso) is the\n"
                 "union of its labels and every other --label's (the paper's nesting). Components\n"
                 "under --min-size voxels are removed and reported. The file records the frame\n"
                 "(+z superior, +y anterior: model coordinates are RAS mm for an axis-aligned\n"
                 "image) and the image's path and SHA-256. Nothing is written on an error.\n"
                 "A SCAN alone (no --label: an MR or CT without labels) opens the viewer to trace it\n"
                 "by hand, surface by surface (thorax view --image SCAN; docs/cli.md, \"Tracing a\n"
                 "scan\"); its trace-save action writes the contours, the model and the label map.\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
    };
    int pr = cli_parse(&cmd, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (cmd.n_pos != 1) return cli_usage_error("digitize", "%s", cmd.n_pos ? "more than one label map" : "no label map given");
    if (!n_labels && !out) { /* a scan to trace by hand: the viewer's slice pane */
        char *view_argv[] = {"view", "--image", (char *)cmd.pos[0], verbose > 0 ? "-v" : verbose < 0 ? "-q" : NULL, NULL};
        return cmd_view(verbose ? 4 : 3, view_argv);
    }
    if (!out) return cli_usage_error("digitize", "no output file given (-o CONTOURS)");
    a.labels = labels;
    a.n_labels = n_labels;
    a.min_size = min_size;
    thx_ctx *ctx = cli_ctx(verbose);
    thx_contours *c = NULL;
    int rc = cli_trace_labels("digitize", cmd.pos[0], &a, verbose, ctx, &c);
    if (rc == 0) {
        char comment[4200];
        snprintf(comment, sizeof comment, "traced from %s by: %s", cmd.pos[0], cli_command_line());
        thx_status st = thx_contours_write(ctx, c, out, comment);
        if (st != THX_OK) rc = cli_fail(ctx, "digitize", st);
        else if (verbose >= 0) printf("wrote %s\n", out);
    }
    thx_contours_destroy(&c);
    thx_ctx_destroy(&ctx);
    return rc;
}
