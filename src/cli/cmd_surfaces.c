/* thorax surfaces: contours -> layers -> laced, capped, oriented surfaces (paper 3.1-3.2). */
#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "cli/cli.h"
#include "thorax/core/fileio.h"
#include "thorax/check/check.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/contours_file.h"
#include "thorax/geom/repair.h"
#include "thorax/geom/surfaces.h"
#include "thorax/edit/edit.h"
#include "thorax/image/trace.h"

/* One line per replayed edit: where it is in the log, what it is, what the check found. */
static void replay_line(void *user, const thx_edit_log *log, const thx_edit *e, const thx_edit_result *r)
{
    const int *verbose = user;
    if (*verbose < 0 && r->check_ok && !r->discarded) return;
    char line[512];
    thx_edit_format(e, line, sizeof line);
    printf("%s:%d: %s: %s\n", log->path, e->line, line, r->summary);
    if (r->discarded || (*verbose > 0 && r->note[0])) printf("%s:%d:   %s\n", log->path, e->line, r->note);
}

/* The repairs on stderr (issue 24: a dense loop gave one warning line per merge, tens of
 * thousands): the count per kind, then the first REPAIRS_SHOWN of each kind (in file order) with
 * their FILE:LINE, and how many more; every one with -v, none with -q (as every warning). All are
 * in model.json's provenance. */
#define REPAIRS_SHOWN 3
static void print_repairs(const thx_repair_log *r, int verbose)
{
    static const char *what[THX_REPAIR_KINDS] = {"closing points dropped", "near-coincident point runs merged",
                                                 "spikes removed", "self-crossings untangled", "narrow holes dropped",
                                                 "tiny loops dropped"};
    size_t count[THX_REPAIR_KINDS] = {0}, shown[THX_REPAIR_KINDS] = {0};
    if (!r->n || verbose < 0) return; /* -q hides warnings */
    for (size_t k = 0; k < r->n; k++) count[r->kind[k]]++;
    char line[600];
    int w = snprintf(line, sizeof line, "%zu repair%s of digitization noise:", r->n, r->n == 1 ? "" : "s");
    const char *sep = " ";
    for (int k = 0; k < THX_REPAIR_KINDS; k++)
        if (count[k] && w > 0 && (size_t)w < sizeof line) {
            w += snprintf(line + w, sizeof line - (size_t)w, "%s%zu %s", sep, count[k], what[k]);
            sep = ", ";
        }
    fprintf(stderr, "thorax: warning: %s\n", line);
    for (size_t k = 0; k < r->n; k++)
        if (verbose > 0 || shown[r->kind[k]] < REPAIRS_SHOWN) {
            shown[r->kind[k]]++;
            fprintf(stderr, "thorax: warning: %s\n", r->msg[k]);
        }
    size_t more = 0;
    for (int k = 0; k < THX_REPAIR_KINDS; k++) more += count[k] - shown[k];
    if (more)
        fprintf(stderr, "thorax: warning: ... and %zu more repair%s (the first %d of each kind shown; -v lists them all, "
                        "model.json's provenance keeps them all)\n", more, more == 1 ? "" : "s", REPAIRS_SHOWN);
}

int cmd_surfaces(int argc, char **argv)
{
    const char *outdir = NULL, *start = NULL, *edits = NULL;
    int verbose = 0, want_stats = 0, strict = 0, unchecked = 0;
    double merge_tol = -1, untangle_tol = -1;
    thx_surfaces_opts o;
    thx_surfaces_opts_default(&o);
    /* a label map in (LABELS --label ...): traced as thorax digitize traces it (cmd_digitize.c) */
    const char *labels[64];
    int n_labels = 0, axis = 0;
    long min_size = 8;
    cli_trace_args ta = {0};
    static const cli_choice axes[] = {{"superior", 0}, {NULL, 0}};
    static const cli_choice holes[] = {{"fill", THX_TRACE_HOLES_FILL}, {"keep", THX_TRACE_HOLES_KEEP}, {NULL, 0}};
    cli_opt image_opts[] = {CLI_TRACE_OPTIONS(ta, labels, n_labels, min_size, axis, axes, holes, "--plane-spacing")};
    static const cli_choice caps[] = {{"polygon", THX_CAP_POLYGON}, {"grid", THX_CAP_GRID}, {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "MODEL", .s = &outdir,
         .help = "model directory to write (replaced atomically)"},
        {.name = "--spacing", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o.spacing, .rule = CLI_GT,
         .bad = "--spacing must be positive", .def = "the contour file's 'spacing' line, else 5",
         .help = "node spacing along the layers"},
        {.name = "--smoothing", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o.smoothing, .rule = CLI_GE,
         .bad = "--smoothing must be >= 0", .note = "0 interpolates the digitized points",
         .help = "spline smoothing bandwidth"},
        {.name = "--start", .type = CLI_STRING, .meta = "X,Y", .unit = "mm", .s = &start,
         .def = "1000 mm anterior in the plane by the contours' frame (superior when the planes are stacked along "
                "the anterior axis); 0,1000, the anterior midline, without a frame",
         .help = "anatomical start point of every loop"},
        {.name = "--merge-tol", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &merge_tol, .rule = CLI_GE,
         .bad = "--merge-tol must be >= 0", .def = "a tenth of the node spacing",
         .help = "consecutive points of a loop closer than this are merged into one"},
        {.name = "--untangle-tol", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &untangle_tol, .rule = CLI_GE,
         .bad = "--untangle-tol must be >= 0", .def = "the node spacing",
         .help = "the largest small loop cut off where a loop crosses itself"},
        {.name = "--strict", .type = CLI_FLAG, .i = &strict,
         .help = "refuse the first loop that needs a repair (a repeated closing point, near-coincident points, a "
                 "spike, a self-crossing, a narrow hole) instead of repairing it: exit 1 with the message the "
                 "repair would have given as a warning"},
        {.name = "--cap", .type = CLI_CHOICE, .choices = caps, .i = &o.cap_method,
         .def = "each surface's own, from the contour file", .help = "end-cap method for every surface"},
        {.name = "--cap-grid", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o.cap_grid, .rule = CLI_GT,
         .bad = "--cap-grid must be positive", .def = "the surface's, else the node spacing",
         .help = "grid spacing of grid caps"},
        {.name = "--concave-tol", .type = CLI_REAL, .meta = "F", .d = &o.lace.concave_tol,
         .help = "outside-test tolerance: a laced triangle is outside when its centroid lies more than F * "
                 "(spacing + |dA - dB|) outside the layer curves interpolated to its height"},
        {.name = "--max-edge", .type = CLI_REAL, .meta = "F", .d = &o.lace.max_edge,
         .help = "a triangle edge longer than F * max(spacing, layer gap) counts as too large"},
        {.name = "--phase-weight", .type = CLI_REAL, .meta = "W", .d = &o.lace.phase_weight, .rule = CLI_GE,
         .bad = "--phase-weight must be >= 0", .note = "0 = position only",
         .help = "weight of the arc-length phase in the shortest-diagonal rule, besides the normalized position"},
        {.name = "--fan-limit", .type = CLI_INT, .meta = "N", .i = &o.lace.fan_limit, .rule = CLI_GE | CLI_LE,
         .lo = 0, .hi = 1000000, .bad = "--fan-limit must be between 0 and 1000000", .note = "0 = never",
         .help = "a run of N triangles at one node is cut as a tongue where it is one"},
        {.name = "--projected-aspect", .type = CLI_REAL, .meta = "A", .d = &o.lace.projected_aspect, .rule = CLI_GE,
         .lo = 1, .bad = "--projected-aspect must be >= 1",
         .help = "nested loops whose lacing has a triangle of aspect ratio over A (or a fan over 3 times the fan "
                 "limit) are laced in projection if that is better"},
        {.name = "--unchecked", .type = CLI_FLAG, .i = &unchecked,
         .help = "write the model even when it fails thorax check's surface checks (to correct it by hand in thorax "
                 "view; mesh refuses it until it passes): a warning instead of exit 1"},
        {.name = "--edits", .type = CLI_INPUT, .meta = "LOG", .s = &edits,
         .help = "then apply the edit log LOG (thorax-edits 1: node, triangle and layer edits, as the viewer saves "
                 "them in MODEL/edits.txt) in order, and write the edited model with the log; an edit that no longer "
                 "applies stops the run (LOG:LINE) and nothing is written"},
        {.name = "--stats", .type = CLI_FLAG, .i = &want_stats,
         .help = "print per-stage times and lacing/orientation statistics"},
        {.name = "-v", .type = CLI_SET, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_SET, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE,
         .help = "less logging: no table, warnings and errors only"},
    };
    cli_command cmd = {
        .name = "surfaces",
        .usage = "CONTOURS -o [--edits] [options]\n"
                 "LABELS --label [--plane-spacing] [--axis] [--min-size] [--holes] -o [options]",
        .about = "Builds one closed, outward-oriented triangle surface per contour surface\n"
                 "(paper 3.1-3.2) and writes the model directory MODEL (model.json, NAME.pts,\n"
                 "NAME.fac). Nothing is written unless every surface builds.\n\n"
                 "Digitization noise is repaired and listed in model.json's provenance\n"
                 "(\"repairs\": file:line, surface, layer, loop, what was done); the warnings give\n"
                 "the count per kind and the first 3 of each kind, -v all of them. A repeated\n"
                 "closing point is dropped, near-coincident points are\n"
                 "merged, spikes removed, small self-crossings untangled, holes narrower than the\n"
                 "node spacing dropped, and a loop the merging leaves with fewer than 3 points\n"
                 "dropped where a plane that missed the body would give the same surface (at an\n"
                 "end of the stack, a hole, where a branch begins or ends). --strict refuses\n"
                 "instead.\n\n"
                 "With --edits LOG the surfaces are edited as the log says (paper 3.2, \"Manual\n"
                 "editing\"): its header must name these contours (their SHA-256) and these options\n"
                 "(its 'build' line), each edit's check is printed, and the model is written with\n"
                 "the log as MODEL/edits.txt: the same model the editing session saved.\n"
                 "model.json records the contours' SHA-256 and their path from MODEL, so that an\n"
                 "editing session finds them.\n\n"
                 "With --label the input is a label map (thorax digitize's): it is traced into\n"
                 "contours in memory and the model built from them, its frame from the image;\n"
                 "model.json's provenance records the image (file, SHA-256, format, frame).\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]},
                  {"options for a label map (LABELS --label ...)", image_opts, sizeof image_opts / sizeof image_opts[0]}},
    };
    int pr = cli_parse(&cmd, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (cmd.n_pos > 1) return cli_usage_error("surfaces", "more than one input file");
    const char *in = cmd.n_pos ? cmd.pos[0] : NULL;
    int start_given = start != NULL;
    if (start && sscanf(start, "%lf,%lf", &o.start.x, &o.start.y) != 2) return cli_usage_error("surfaces", "--start needs X,Y");
    if (!in) return cli_usage_error("surfaces", "no contour file given");
    if (!outdir) return cli_usage_error("surfaces", "no output directory given (-o MODEL)");
    if (!n_labels && (ta.spacing != 0 || min_size != 8 || ta.holes != THX_TRACE_HOLES_FILL))
        return cli_usage_error("surfaces", "--plane-spacing, --min-size and --holes are for a label map: give --label");
    if (!n_labels) {
        static const char *const image_ext[] = {".nii", ".nii.gz", ".nrrd", ".nhdr", ".mha", ".mhd", ".dcm", NULL};
        size_t ln = strlen(in);
        for (int k = 0; image_ext[k]; k++) {
            size_t le = strlen(image_ext[k]);
            if (ln >= le && strcasecmp(in + ln - le, image_ext[k]) == 0)
                return cli_usage_error("surfaces", "%s is an image: give the surfaces' labels (--label VALUES=NAME:ROLE ...), "
                                                   "or a contour file", in);
        }
    }
    if (n_labels && edits)
        return cli_usage_error("surfaces", "--edits replays edits on surfaces built from a contour file: digitize the "
                                           "label map first (thorax digitize LABELS --label ... -o CONTOURS)");
    thx_ctx *ctx = cli_ctx(verbose);
    thx_contours *c = NULL;
    thx_model *m = NULL;
    thx_surfaces_stats *per = NULL, tot;
    thx_repair_log rlog = {0};
    rlog.quiet = 1; /* summarized here (print_repairs) */
    thx_repair_opts ro;
    int rc = 0;
    double t0 = thx_wtime();
    /* the output first: refused before any work unless it is absent or thorax's own model */
    thx_outdir od;
    const char *inputs[] = {in};
    thx_status st = thx_outdir_claim(ctx, &od, outdir, THX_MODEL_MANIFEST, THX_MODEL_FORMAT, inputs, 1);
    if (st == THX_OK && n_labels) {
        ta.labels = labels;
        ta.n_labels = n_labels;
        ta.min_size = min_size;
        ta.node_spacing = o.spacing > 0 ? o.spacing : 0;
        ta.surfaces_spacing = o.spacing;
        ta.surfaces_smoothing = o.smoothing;
        int trc = cli_trace_labels("surfaces", in, &ta, verbose, ctx, &c);
        if (trc) {
            thx_ctx_destroy(&ctx);
            return trc;
        }
    } else if (st == THX_OK) st = thx_contours_read_raw(ctx, in, &c);
    if (st == THX_OK) {
        /* digitization noise (paper 3.1): repaired and reported, or refused under --strict */
        thx_repair_opts_default(&ro, o.spacing > 0 ? o.spacing : (c->spacing > 0 ? c->spacing : 5.0));
        if (merge_tol >= 0) ro.merge_tol = merge_tol;
        if (untangle_tol >= 0) ro.untangle_tol = untangle_tol;
        ro.strict = strict;
        st = thx_contours_repair(ctx, c, &ro, &rlog);
        print_repairs(&rlog, verbose);
    }
    if (st != THX_OK) { rc = cli_fail(ctx, "surfaces", st); goto done; }
    /* The lacing start point (paper 3.2, step 1: the anterior midline) follows the contours'
     * frame: 1000 mm anterior in the contour plane, or superior when the contours are stacked
     * along the anterior axis (no anterior direction in their plane); --start overrides. */
    if (!start_given && c->frame.set) {
        thx_axis ax = c->frame.front.axis != 2 ? c->frame.front : c->frame.up;
        o.start.x = ax.axis == 0 ? 1000.0 * ax.sign : 0;
        o.start.y = ax.axis == 1 ? 1000.0 * ax.sign : 0;
    }
    double t_read = thx_wtime() - t0;
    double spacing = o.spacing > 0 ? o.spacing : (c->spacing > 0 ? c->spacing : 5.0);
    /* the recipe: these options with the spacing as used (recorded, and compared with a log's) */
    thx_edit_recipe recipe;
    recipe.surfaces = o;
    recipe.surfaces.spacing = spacing;
    recipe.repair = ro;
    per = calloc(c->n_surfaces, sizeof *per);
    if (!per) { rc = 1; goto done; }
    st = thx_surfaces_build(ctx, c, &o, &m, per, &tot);
    if (st != THX_OK) { rc = cli_fail(ctx, "surfaces", st); goto done; }
    m->frame = c->frame; /* the contours' anatomical frame ("frame UP FRONT") belongs to the model */
    char sha[65] = "";
    {
        cJSON *p = cJSON_CreateObject();
        cJSON_AddStringToObject(p, "program", "thorax 0.1.0");
        cJSON_AddStringToObject(p, "command", cli_command_line());
        cJSON_AddStringToObject(p, "input", in);
        /* where the contours are, for an editing session on the model (thorax/edit/edit.h) */
        if (!n_labels) st = thx_edit_record_contours(ctx, p, in, outdir, sha);
        if (c->image[0]) {
            /* the image the contours were traced from (issue 25): file, SHA-256, format, frame */
            cJSON *im = cJSON_AddObjectToObject(p, "image");
            cJSON_AddStringToObject(im, "file", c->image);
            cJSON_AddStringToObject(im, "sha256", c->image_sha256);
            if (n_labels) {
                cJSON_AddStringToObject(im, "format", ta.format);
                cJSON_AddStringToObject(im, "source_frame", ta.source_frame);
                cJSON_AddItemToObject(im, "model_to_ras", cJSON_CreateDoubleArray(ta.to_ras, 9));
            }
        }
        cJSON *op = cJSON_AddObjectToObject(p, "options");
        if (st == THX_OK) st = thx_edit_recipe_json(ctx, &recipe, op);
        cJSON *rp = cJSON_AddArrayToObject(p, "repairs");
        for (size_t k = 0; k < rlog.n; k++) cJSON_AddItemToArray(rp, cJSON_CreateString(rlog.msg[k]));
        m->provenance_json = cJSON_PrintUnformatted(p);
        cJSON_Delete(p);
        if (st != THX_OK) { rc = cli_fail(ctx, "surfaces", st); goto done; }
    }
    if (edits) {
        /* paper 3.2, "Manual editing": the log's edits, in order, on the surfaces just built */
        thx_edit_log *log = NULL;
        thx_edit_session *es = NULL;
        st = thx_edit_log_read(ctx, edits, &log);
        if (st == THX_OK) st = thx_edit_session_create(ctx, &m, &c, &recipe, in, sha, NULL, &es);
        if (st == THX_OK) st = thx_edit_replay(ctx, es, log, replay_line, &verbose);
        if (st == THX_OK) st = thx_edit_session_finish(ctx, &es, &m, &c);
        thx_edit_session_destroy(&es);
        thx_edit_log_destroy(&log);
        if (st != THX_OK) { rc = cli_fail(ctx, "surfaces", st); goto done; }
        if (verbose >= 0) {
            tot.n_nodes = tot.n_tris = 0;
            for (size_t k = 0; k < m->n_surfaces; k++) {
                per[k].n_nodes = m->surf[k]->n_nodes;
                per[k].n_tris = m->surf[k]->n_tris;
                tot.n_nodes += per[k].n_nodes;
                tot.n_tris += per[k].n_tris;
            }
        }
    }
    {
        /* never write what our own check fails (closure, orientation, 4π, self-intersection): a
           lacing that crossed itself is refused here, naming the surface and the first triangles,
           not found later by thorax check or mesh (issue 24); --unchecked keeps it for hand correction */
        thx_check_opts co;
        thx_check_opts_default(&co);
        thx_model_report *rep = NULL;
        double tc = thx_wtime();
        st = thx_model_check(ctx, m, &co, &rep);
        if (st != THX_OK && st != THX_ECHECK) { rc = cli_fail(ctx, "surfaces", st); goto done; }
        thx_log(ctx, THX_LOG_DEBUG, "checked the surfaces in %.3f s", thx_wtime() - tc);
        if (st == THX_ECHECK) {
            for (size_t k = 0; k < rep->n_surfaces; k++) {
                const thx_surface_report *r = &rep->surf[k];
                for (size_t j = 0; !r->ok && j < r->n_reasons; j++)
                    fprintf(stderr, "thorax surfaces: %s: surface \"%s\" fails the check: %s\n", in, r->name, r->reasons[j]);
            }
            if (rep->n_meeting_pairs) fprintf(stderr, "thorax surfaces: %s: %s\n", in, rep->meet_reason);
            thx_model_report_destroy(&rep);
            if (!unchecked) {
                fprintf(stderr, "thorax surfaces: %s: nothing written: the surfaces built from these contours fail thorax "
                                "check (above); other --spacing, --smoothing or --cap options may lace them, or "
                                "--unchecked writes them to correct by hand (thorax view)\n", in);
                rc = 1;
                goto done;
            }
            fprintf(stderr, "thorax surfaces: warning: %s written failing the check (--unchecked): correct it by hand "
                            "(thorax view) and check it again before meshing\n", outdir);
            st = THX_OK;
        }
        thx_model_report_destroy(&rep);
    }
    double t1 = thx_wtime();
    st = thx_model_write_claimed(ctx, m, &od);
    if (st != THX_OK) { rc = cli_fail(ctx, "surfaces", st); goto done; }
    double t_write = thx_wtime() - t1;
    if (verbose >= 0) {
        printf("%-12s %8s %9s %7s %8s %8s %7s %6s\n", "surface", "nodes", "triangles", "layers", "removed", "relaced", "inplane", "fan");
        for (size_t k = 0; k < c->n_surfaces; k++)
            printf("%-12s %8zu %9zu %7zu %8zu %8zu %7zu %6d\n", c->surf[k].name, per[k].n_nodes, per[k].n_tris,
                   c->surf[k].n_layers, per[k].lace.removed, per[k].lace.relaced_gaps, per[k].lace.inplane_tris,
                   per[k].lace.max_fan);
        printf("%-12s %8zu %9zu\n", "total", tot.n_nodes, tot.n_tris);
        if (rlog.n)
            printf("repairs: %zu (%zu closing points dropped, %zu near-coincident points merged, %zu spikes removed, "
                   "%zu self-crossings untangled, %zu narrow holes dropped, %zu tiny loops dropped; listed in model.json)\n",
                   rlog.n, rlog.closing, rlog.merged, rlog.spikes, rlog.untangled, rlog.holes, rlog.tiny);
        printf("wrote %s (spacing %g mm) in %.3f s\n", outdir, spacing, thx_wtime() - t0);
    }
    if (want_stats) {
        printf("stage times (s): read %.4f, layers %.4f, lacing %.4f, caps %.4f, orientation %.4f, build %.4f, write %.4f\n",
               t_read, tot.t_layers, tot.t_lace, tot.t_caps, tot.t_orient, tot.t_total, t_write);
        printf("lacing: %zu slices (%zu branching, %zu laced in projection), %zu outside triangles removed, "
               "%zu gaps re-laced, %zu tongues cut, %zu in-plane, %zu unresolved, %zu too large, largest fan %d; "
               "%zu crossing lacings laced again, %zu left crossing\n",
               tot.n_slices, tot.n_branch_slices, tot.lace.projected, tot.lace.removed, tot.lace.relaced_gaps, tot.lace.tongues, tot.lace.inplane_tris,
               tot.lace.unresolved, tot.lace.too_large, tot.lace.max_fan, tot.lace.relaced_crossing, tot.lace.crossing);
        printf("orientation: %zu triangles by their own inside test, %zu from neighbours (%zu tests overruled), "
               "%zu flipped; %zu caps; %zu nearly flat triangles swapped with a neighbour\n",
               tot.orient_by_test, tot.orient_by_neighbours, tot.orient_overruled, tot.orient_flipped, tot.n_caps,
               tot.n_flat_flipped);
    }
done:
    thx_repair_log_free(&rlog);
    free(per);
    thx_model_destroy(&m);
    thx_contours_destroy(&c);
    thx_ctx_destroy(&ctx);
    return rc;
}
