/* thorax check: verify a model's surfaces (closure, orientation, 4 pi, intersections, quality). */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "thorax/check.h"
#include "thorax/model.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: thorax check MODEL [--json] [--tol T] [--min-angle DEG] [--max-aspect A]\n"
            "                          [--no-intersections] [-q] [-v]\n"
            "\n"
            "Verifies every surface of the model directory MODEL (paper 3.2):\n"
            "  closed 2-manifold   every edge in exactly two triangles, every vertex one fan,\n"
            "                      no unused nodes, no duplicate or zero-area triangles\n"
            "  orientation         neighbouring triangles traverse their edge in opposite\n"
            "                      directions; the enclosed signed volume is positive\n"
            "  4 pi                the total solid angle about an interior point (the model's,\n"
            "                      else one found by ray parity) is 4 pi: |Omega/4pi - 1| <= T\n"
            "  intersections       no two triangles meet except where they share nodes\n"
            "                      (exact predicates)\n"
            "  quality             smallest/largest angle, aspect ratio histogram (reported;\n"
            "                      a failure only with --min-angle / --max-aspect)\n"
            "\n"
            "Aspect ratio = longest edge / (2 sqrt(3) inradius): 1 for an equilateral triangle.\n"
            "\n"
            "options:\n"
            "  --json              print all figures as JSON on stdout (node and triangle\n"
            "                      numbers 1-based, as in the .fac files)\n"
            "  --tol T             tolerance of the 4 pi check, relative (default 1e-6)\n"
            "  --min-angle DEG     also fail if a triangle has a smaller angle\n"
            "  --max-aspect A      also fail if a triangle's aspect ratio exceeds A\n"
            "  --no-intersections  skip the self-intersection search\n"
            "  -q                  print only failures (no table)\n"
            "  -v                  more logging\n"
            "  -h, --help          this text\n"
            "\n"
            "Exit status: 0 every surface passed, 1 a check failed or the model could not\n"
            "be read, 2 bad usage.\n");
}

static void print_table(const thx_model_report *r, const thx_model *m)
{
    printf("%-16s %7s %9s %6s %-12s %10s %9s %9s %9s  %s\n", "surface", "nodes", "triangles", "closed", "orientation",
           "4pi relerr", "intersect", "min angle", "worst AR", "result");
    for (size_t i = 0; i < r->n_surfaces; i++) {
        const thx_surface_report *s = &r->surf[i];
        const char *closed = "-", *orient = "-";
        char err[32] = "-", isect[32] = "-", ang[32] = "-", asp[32] = "-";
        if (!(s->failures & (THX_CHECKF_EMPTY | THX_CHECKF_BAD_INDEX))) {
            closed = (s->n_boundary_edges || s->n_nonmanifold_edges) ? "no" : "yes";
            orient = s->n_inconsistent_edges ? "inconsistent" : s->volume > 0 ? "outward" : "inward";
        }
        if (s->solid_angle_rel_err == s->solid_angle_rel_err) snprintf(err, sizeof err, "%.2e", s->solid_angle_rel_err);
        else if (s->n_tris) snprintf(err, sizeof err, "no point");
        if (s->intersections_checked) snprintf(isect, sizeof isect, "%zu", s->n_intersecting_pairs);
        if (s->min_angle == s->min_angle) snprintf(ang, sizeof ang, "%.2f", s->min_angle);
        if (isinf(s->max_aspect)) snprintf(asp, sizeof asp, "inf");
        else if (s->max_aspect == s->max_aspect) snprintf(asp, sizeof asp, "%.3g", s->max_aspect);
        printf("%-16s %7zu %9zu %6s %-12s %10s %9s %9s %9s  %s\n", s->name, s->n_nodes, s->n_tris, closed, orient, err,
               isect, ang, asp, s->ok ? "ok" : "FAIL");
    }
    (void)m;
    /* aspect ratio histogram: one column per surface */
    printf("\naspect ratio (longest edge / (2 sqrt(3) inradius); 1 = equilateral), triangles per bin:\n");
    printf("%-14s", "bin");
    for (size_t i = 0; i < r->n_surfaces; i++) printf(" %12.12s", r->surf[i].name);
    printf("\n");
    for (int b = 0; b < THX_CHECK_ASPECT_BINS; b++) {
        char label[32];
        if (isinf(thx_check_aspect_edges[b + 1]))
            snprintf(label, sizeof label, ">= %g", thx_check_aspect_edges[b]);
        else
            snprintf(label, sizeof label, "[%g, %g)", thx_check_aspect_edges[b], thx_check_aspect_edges[b + 1]);
        printf("%-14s", label);
        for (size_t i = 0; i < r->n_surfaces; i++) printf(" %12zu", r->surf[i].aspect_hist[b]);
        printf("\n");
    }
}

int cmd_check(int argc, char **argv)
{
    const char *cmd = "check";
    const char *model_dir = NULL;
    int json = 0, verbose = 0, quiet = 0, rc = 0;
    thx_check_opts opts;
    thx_check_opts_default(&opts);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--json")) {
            json = 1;
        } else if (!strcmp(a, "--tol") || !strcmp(a, "--min-angle") || !strcmp(a, "--max-aspect")) {
            double v;
            if (cli_parse_double(cmd, a, i + 1 < argc ? argv[i + 1] : NULL, &v)) return 2;
            i++;
            if (!strcmp(a, "--tol")) {
                if (!(v >= 0.0) || isinf(v)) return cli_usage_error(cmd, "--tol must be a finite number >= 0");
                opts.solid_angle_tol = v;
            } else if (!strcmp(a, "--min-angle")) {
                if (!(v >= 0.0 && v <= 60.0)) return cli_usage_error(cmd, "--min-angle must be in [0, 60] degrees");
                opts.min_angle_deg = v;
            } else {
                if (!(v >= 1.0) || isinf(v)) return cli_usage_error(cmd, "--max-aspect must be a finite number >= 1");
                opts.max_aspect = v;
            }
        } else if (!strcmp(a, "--no-intersections")) {
            opts.check_intersections = 0;
        } else if (!strcmp(a, "-q")) {
            quiet = 1;
            verbose--;
        } else if (!strcmp(a, "-v")) {
            verbose++;
        } else if (a[0] == '-' && a[1]) {
            return cli_usage_error(cmd, "unknown option '%s'", a);
        } else if (!model_dir) {
            model_dir = a;
        } else {
            return cli_usage_error(cmd, "unexpected argument '%s' (one MODEL directory expected)", a);
        }
    }
    if (!model_dir) return cli_usage_error(cmd, "no MODEL directory given");

    thx_ctx *ctx = cli_ctx(verbose);
    thx_model *m = NULL;
    thx_model_report *rep = NULL;
    thx_status st = thx_model_read(ctx, model_dir, &m);
    if (st != THX_OK) {
        /* the reader's message names the file; say which model too */
        fprintf(stderr, "thorax check: cannot read model '%s': %s: %s\n", model_dir, thx_status_name(st),
                thx_ctx_message(ctx)[0] ? thx_ctx_message(ctx) : "(no detail)");
        rc = 1;
        goto out;
    }
    double t0 = thx_wtime();
    st = thx_model_check(ctx, m, &opts, &rep);
    if (st != THX_OK && st != THX_ECHECK) {
        rc = cli_fail(ctx, cmd, st);
        goto out;
    }
    thx_log(ctx, THX_LOG_DEBUG, "checked %zu surfaces in %.3f s", m->n_surfaces, thx_wtime() - t0);
    if (json) {
        cJSON *j = thx_model_report_json(ctx, rep, m);
        if (j) cJSON_AddStringToObject(j, "model", model_dir);
        char *text = j ? cJSON_Print(j) : NULL;
        cJSON_Delete(j);
        if (!text) {
            rc = cli_fail(ctx, cmd, THX_ENOMEM);
            goto out;
        }
        printf("%s\n", text);
        free(text);
    } else if (!quiet) {
        print_table(rep, m);
    }
    /* failures go to stderr in every mode, so --json output stays pure JSON */
    for (size_t i = 0; i < rep->n_surfaces; i++)
        for (size_t k = 0; k < rep->surf[i].n_reasons; k++)
            fprintf(stderr, "thorax check: %s: surface \"%s\": %s\n", model_dir, rep->surf[i].name,
                    rep->surf[i].reasons[k]);
    /* a model with nothing to check is not a model that passed */
    int pass = rep->ok && m->n_surfaces > 0;
    if (m->n_surfaces == 0) fprintf(stderr, "thorax check: %s: the model has no surfaces\n", model_dir);
    if (!json && !quiet) printf("\n%s: %s\n", model_dir, pass ? "all checks passed" : "CHECK FAILED");
    rc = pass ? 0 : 1;
out:
    thx_model_report_destroy(&rep);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return rc;
}
