/* thorax check: verify a model's surfaces (closure, orientation, 4 pi, intersections, quality)
 * and, when the model has one, its volume mesh (conformity, positive volumes, surface coverage,
 * containment and region cells, volumes against the surfaces, node tables and Steiner records,
 * tetrahedron quality). */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "thorax/check/check.h"
#include "thorax/check/check_volume.h"
#include "thorax/model/model.h"
#include "thorax/io/model_dir.h"
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

static void print_volume(const thx_volume_report *v)
{
    int indexed = !(v->failures & (THX_VCHECKF_EMPTY | THX_VCHECKF_BAD_INDEX));
    const char *conf = "-", *closed = "-", *pos = "-";
    char diff[32] = "-", dih[32] = "-", re[32] = "-";
    if (indexed) {
        conf = (v->n_nonconforming_faces || v->n_overlapping_faces || v->n_duplicate_tets) ? "no" : "yes";
        closed = (v->boundary_checked && !v->boundary.n_boundary_edges && !v->boundary.n_nonmanifold_edges) ? "yes"
                                                                                                            : "no";
        pos = (v->n_inverted_tets || v->n_flat_tets || v->n_repeated_node_tets) ? "no" : "yes";
    }
    /* percentages that round to zero print as +0.000%, not -0.000% */
    if (v->volume_rel_diff == v->volume_rel_diff)
        snprintf(diff, sizeof diff, "%+.3f%%", fabs(v->volume_rel_diff) < 5e-6 ? 0.0 : 100.0 * v->volume_rel_diff);
    if (v->min_dihedral == v->min_dihedral) snprintf(dih, sizeof dih, "%.2f", v->min_dihedral);
    if (isinf(v->max_radius_edge)) snprintf(re, sizeof re, "inf");
    else if (v->max_radius_edge == v->max_radius_edge) snprintf(re, sizeof re, "%.3g", v->max_radius_edge);
    printf("\n%-8s %9s %8s %10s %7s %8s %9s %9s %9s  %s\n", "volume", "tets", "nodes", "conforming", "closed",
           "positive", "vol diff", "min dihed", "worst RE", "result");
    printf("%-8s %9zu %8zu %10s %7s %8s %9s %9s %9s  %s\n", "volume", v->n_tets, v->n_nodes, conf, closed, pos, diff,
           dih, re, v->ok ? "ok" : "FAIL");
    if (v->coverage_checked) {
        printf("\n%-16s %9s %9s %8s %8s  %s\n", "surface", "triangles", "covered", "share", "steiner", "inside");
        for (size_t s = 0; s < v->n_surface_reports; s++) {
            const thx_volume_surface_report *sr = &v->surfaces[s];
            const char *in = sr->parent >= 0 ? v->surfaces[sr->parent].name : "-";
            /* a share just short of 1 prints as 99.99%, never as a rounded 100% */
            double pct = sr->n_covered == sr->n_tris ? 100.0 : fmin(99.99, 100.0 * sr->share);
            printf("%-16s %9zu %9zu %7.2f%% %8zu  %s\n", sr->name, sr->n_tris, sr->n_covered, pct, sr->n_steiner, in);
        }
        printf("interface faces %zu, on no surface %zu\n", v->n_interface_faces, v->n_faces_off_surfaces);
    }
    if (v->n_regions) {
        printf("\n%-16s %9s %14s %14s %9s %-18s %8s  %s\n", "region", "tets", "volume mm^3", "surfaces mm^3", "diff",
               "cell", "outside", "from");
        for (size_t k = 0; k < v->n_regions; k++) {
            const thx_volume_region_report *g = &v->regions[k];
            char e[32] = "-", d[32] = "-";
            if (g->expected == g->expected) snprintf(e, sizeof e, "%.6g", g->expected);
            if (g->rel_diff == g->rel_diff)
                snprintf(d, sizeof d, "%+.3f%%", fabs(g->rel_diff) < 5e-6 ? 0.0 : 100.0 * g->rel_diff);
            char cell[80] = "-";
            if (g->cell >= 0 && (size_t)g->cell < v->n_surface_reports)
                snprintf(cell, sizeof cell, "in %s", v->surfaces[g->cell].name);
            else if (g->cell == -1)
                snprintf(cell, sizeof cell, "outside all");
            printf("%-16s %9zu %14.6g %14s %9s %-18s %8zu  %s\n", g->name, g->n_tets, g->volume, e, d, cell,
                   g->n_outside, g->definition[0] ? g->definition : "-");
        }
    }
    printf("\ntetrahedra per bin:\n%-16s %10s    %-16s %10s\n", "min dihedral deg", "tets", "radius-edge", "tets");
    int nb = THX_VCHECK_DIHEDRAL_BINS > THX_VCHECK_RADIUS_EDGE_BINS ? THX_VCHECK_DIHEDRAL_BINS
                                                                     : THX_VCHECK_RADIUS_EDGE_BINS;
    for (int b = 0; b < nb; b++) {
        char l1[32] = "", l2[32] = "", c1[32] = "", c2[32] = "";
        if (b < THX_VCHECK_DIHEDRAL_BINS) {
            if (isinf(thx_vcheck_dihedral_edges[b + 1]))
                snprintf(l1, sizeof l1, ">= %g", thx_vcheck_dihedral_edges[b]);
            else
                snprintf(l1, sizeof l1, "[%g, %g)", thx_vcheck_dihedral_edges[b], thx_vcheck_dihedral_edges[b + 1]);
            snprintf(c1, sizeof c1, "%zu", v->dihedral_hist[b]);
        }
        if (b < THX_VCHECK_RADIUS_EDGE_BINS) {
            if (isinf(thx_vcheck_radius_edge_edges[b + 1]))
                snprintf(l2, sizeof l2, ">= %.3g", thx_vcheck_radius_edge_edges[b]);
            else
                snprintf(l2, sizeof l2, "[%.3g, %.3g)", thx_vcheck_radius_edge_edges[b],
                         thx_vcheck_radius_edge_edges[b + 1]);
            snprintf(c2, sizeof c2, "%zu", v->radius_edge_hist[b]);
        }
        printf("%-16s %10s    %-16s %10s\n", l1, c1, l2, c2);
    }
}

int cmd_check(int argc, char **argv)
{
    const char *cmd = "check";
    int json = 0, verbose = 0, quiet = 0, rc = 0, no_intersections = 0;
    thx_check_opts opts;
    thx_check_opts_default(&opts);
    thx_volume_check_opts vopts;
    thx_volume_check_opts_default(&vopts);
    cli_opt table[] = {
        {.name = "--json", .type = CLI_FLAG, .i = &json,
         .help = "print all figures as JSON on stdout (node and triangle numbers 1-based, as in the .fac files)"},
        {.name = "--tol", .type = CLI_REAL, .meta = "T", .d = &opts.solid_angle_tol, .rule = CLI_GE | CLI_FINITE,
         .bad = "--tol must be a finite number >= 0", .help = "tolerance of the 4 pi check, relative"},
        {.name = "--min-angle", .type = CLI_REAL, .meta = "DEG", .unit = "deg", .d = &opts.min_angle_deg,
         .rule = CLI_GE | CLI_LE, .lo = 0, .hi = 60, .bad = "--min-angle must be in [0, 60] degrees",
         .help = "fail if a triangle has a smaller angle (the default is the smallest thorax mesh can take: the "
                 "tetrahedra on a triangle are as flat as its smallest angle; 0 only reports)"},
        {.name = "--max-aspect", .type = CLI_REAL, .meta = "A", .d = &opts.max_aspect, .rule = CLI_GE | CLI_FINITE,
         .lo = 1, .bad = "--max-aspect must be a finite number >= 1", .def = "none",
         .help = "also fail if a triangle's aspect ratio exceeds A"},
        {.name = "--no-intersections", .type = CLI_FLAG, .i = &no_intersections,
         .help = "skip the self-intersection search (surfaces and the volume's boundary)"},
        {.name = "--volume-tol", .type = CLI_REAL, .meta = "R", .d = &vopts.volume_tol, .rule = CLI_GE | CLI_FINITE,
         .bad = "--volume-tol must be a finite number >= 0", .note = "0 reports only",
         .help = "volume: fail if |total volume difference| > R, relative"},
        {.name = "--region-tol", .type = CLI_REAL, .meta = "R", .d = &vopts.region_volume_tol,
         .rule = CLI_GE | CLI_FINITE, .bad = "--region-tol must be a finite number >= 0", .note = "0 reports only",
         .help = "volume: fail if a region's |volume difference| > R"},
        {.name = "--min-dihedral", .type = CLI_REAL, .meta = "DEG", .unit = "deg", .d = &vopts.min_dihedral_deg,
         .rule = CLI_GE | CLI_LE, .lo = 0, .hi = 70.6, .bad = "--min-dihedral must be in [0, 70.6] degrees",
         .note = "0 turns it off", .help = "volume: fail if a dihedral angle is smaller"},
        {.name = "--max-radius-edge", .type = CLI_REAL, .meta = "X", .d = &vopts.max_radius_edge,
         .rule = CLI_GE | CLI_FINITE, .lo = 0.6, .bad = "--max-radius-edge must be a finite number >= 0.6",
         .def = "none", .help = "volume: fail if a radius-edge ratio exceeds X"},
        {.name = "-q", .type = CLI_COUNT, .i = &quiet, .ival = 1, .help = "print only failures (no table)"},
        {.name = "-v", .type = CLI_COUNT, .i = &verbose, .ival = 1, .help = "more logging"},
    };
    cli_command c = {
        .name = cmd,
        .usage = "MODEL [--json] [--tol] [--min-angle] [--max-aspect] [--no-intersections] [--volume-tol] "
                 "[--region-tol] [--min-dihedral] [--max-radius-edge] [-q] [-v]",
        .about =
            "Verifies every surface of the model directory MODEL (paper 3.2):\n"
            "  closed 2-manifold   every edge in exactly two triangles, every vertex one fan,\n"
            "                      no unused nodes, no duplicate or zero-area triangles\n"
            "  orientation         neighbouring triangles traverse their edge in opposite\n"
            "                      directions; the enclosed signed volume is positive\n"
            "  4 pi                the total solid angle about an interior point (the model's,\n"
            "                      else one found by ray parity) is 4 pi: |Omega/4pi - 1| <= T\n"
            "  intersections       no two triangles meet except where they share nodes\n"
            "                      (exact predicates)\n"
            "  quality             no angle below --min-angle (1 deg: thorax mesh cannot take a\n"
            "                      flatter triangle); largest angle and the aspect ratio\n"
            "                      histogram reported (a failure only with --max-aspect)\n"
            "\n"
            "Aspect ratio = longest edge / (2 sqrt(3) inradius): 1 for an equilateral triangle.\n"
            "\n"
            "If the model has a volume mesh (volume.pts/volume.tet), it is checked too (paper 3.3):\n"
            "  validity            node numbers in range, four distinct nodes, positive volume\n"
            "                      (exact sign), no unused or coincident nodes, no duplicate\n"
            "                      tetrahedra, region numbers in the table\n"
            "  conformity          every face in at most two tetrahedra, on opposite sides;\n"
            "                      the boundary faces pass the surface checks above; boundary\n"
            "                      shells and cavities as expected (the heart's cavity when no\n"
            "                      region is the heart; other cavities are voids)\n"
            "  coverage            every surface triangle covered by mesh faces on the boundary\n"
            "                      or between two regions (areas sum to its area), and no such\n"
            "                      face off the surfaces (decided from the geometry alone)\n"
            "  containment         no centroid outside the outer surface, none inside an\n"
            "                      excluded heart\n"
            "  region cells        the cell of a tetrahedron = the innermost surface holding\n"
            "                      its centroid; each cell holds one region (no tetrahedron\n"
            "                      outside its region)\n"
            "  volume              total tetrahedral volume against the volume the surfaces\n"
            "                      enclose (outer - excluded heart): |difference| <= R\n"
            "  regions             each region's volume against its surfaces' (the surface less\n"
            "                      the surfaces nested directly in it): |difference| <= R\n"
            "  node tables         each surface node on a volume node of the same coordinates,\n"
            "                      and listed back; each Steiner node on its triangle's point\n"
            "  quality             smallest dihedral angle >= DEG (default 1); radius-edge\n"
            "                      ratio (circumradius / shortest edge; regular tetrahedron\n"
            "                      0.612), histograms (reported)\n",
        .epilog =
            "Exit status: 0 every surface (and the volume) passed, 1 a check failed or the\n"
            "model could not be read, 2 bad usage.\n",
        .group = {{NULL, table, sizeof table / sizeof table[0]}},
    };
    int pr = cli_parse(&c, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (c.n_pos > 1) return cli_usage_error(cmd, "unexpected argument '%s' (one MODEL directory expected)", c.pos[1]);
    const char *model_dir = c.n_pos ? c.pos[0] : NULL;
    verbose -= quiet; /* -q: less logging, and only the failures */
    quiet = quiet > 0;
    if (no_intersections) {
        opts.check_intersections = 0;
        vopts.check_intersections = 0;
    }
    if (!model_dir) return cli_usage_error(cmd, "no MODEL directory given");

    thx_ctx *ctx = cli_ctx(verbose);
    thx_model *m = NULL;
    thx_model_report *rep = NULL;
    thx_volume_report vrep;
    memset(&vrep, 0, sizeof vrep);
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
    if (m->volume) {
        t0 = thx_wtime();
        st = thx_volume_check(ctx, m->volume, m, &vopts, &vrep);
        if (st != THX_OK && st != THX_ECHECK) {
            rc = cli_fail(ctx, cmd, st);
            goto out;
        }
        thx_log(ctx, THX_LOG_DEBUG, "checked the volume (%zu tetrahedra) in %.3f s", m->volume->n_tets,
                thx_wtime() - t0);
    }
    int vol_ok = !m->volume || vrep.ok;
    if (json) {
        cJSON *j = thx_model_report_json(ctx, rep, m);
        if (j) cJSON_AddStringToObject(j, "model", model_dir);
        if (j && m->volume) {
            cJSON *vj = thx_volume_report_json(ctx, &vrep);
            if (!vj) {
                cJSON_Delete(j);
                j = NULL;
            } else {
                cJSON_AddItemToObject(j, "volume", vj);
                /* the top-level verdict covers the volume too */
                cJSON_ReplaceItemInObject(j, "ok", cJSON_CreateBool(rep->ok && vrep.ok));
            }
        }
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
        if (m->volume) print_volume(&vrep);
    }
    /* failures go to stderr in every mode, so --json output stays pure JSON */
    for (size_t i = 0; i < rep->n_surfaces; i++)
        for (size_t k = 0; k < rep->surf[i].n_reasons; k++)
            fprintf(stderr, "thorax check: %s: surface \"%s\": %s\n", model_dir, rep->surf[i].name,
                    rep->surf[i].reasons[k]);
    if (rep->n_meeting_pairs)
        fprintf(stderr, "thorax check: %s: %s%s\n", model_dir, rep->meet_reason,
                rep->n_meeting_pairs > 1 ? " (and other pairs)" : "");
    if (m->volume)
        for (size_t k = 0; k < vrep.n_reasons; k++)
            fprintf(stderr, "thorax check: %s: volume: %s\n", model_dir, vrep.reasons[k]);
    /* a model with nothing to check is not a model that passed */
    int pass = rep->ok && vol_ok && m->n_surfaces > 0;
    if (m->n_surfaces == 0) fprintf(stderr, "thorax check: %s: the model has no surfaces\n", model_dir);
    if (!json && !quiet) printf("\n%s: %s\n", model_dir, pass ? "all checks passed" : "CHECK FAILED");
    rc = pass ? 0 : 1;
out:
    thx_volume_report_free(&vrep);
    thx_model_report_destroy(&rep);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return rc;
}
