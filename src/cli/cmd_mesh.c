/* thorax mesh: the tetrahedral volume mesh of a surface model (paper 3.3). */
#include <cjson/cJSON.h>
#include <limits.h>
#include <errno.h>
#include <math.h>
#include <unistd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "thorax/check/check_volume.h"
#include "thorax/check/verdict.h"
#include "thorax/mesh/mesh.h"
/* A progress bar on a terminal (stderr) for a stage once it has run a second; one line per stage. */
typedef struct { char stage[32]; double t0; int shown; } progress_state;
static void mesh_progress(void *user, const char *stage, double done)
{
    progress_state *p = user;
    double now = thx_wtime();
    if (strcmp(p->stage, stage) != 0) {
        if (p->shown) fputc('\n', stderr);
        snprintf(p->stage, sizeof p->stage, "%s", stage);
        p->t0 = now;
        p->shown = 0;
    }
    if (now - p->t0 < 1.0 && !p->shown) return;
    int width = 30, fill = (int)(done * width);
    if (fill > width) fill = width;
    char bar[40];
    for (int i = 0; i < width; i++) bar[i] = i < fill ? '=' : (i == fill ? '>' : ' ');
    bar[width] = 0;
    fprintf(stderr, "\rthorax mesh %-11s [%s] %3.0f%% %5.1f s", stage, bar, 100 * (done > 1 ? 1 : done), now - p->t0);
    fflush(stderr);
    p->shown = 1;
}

/* The surface triangle nearest point c and its smallest corner angle (degrees): where a mesh fault
 * sits on the model. */
static double nearest_triangle(const thx_model *m, const double c[3], size_t *ws, size_t *wt)
{
    double best = INFINITY, angle = 180;
    for (size_t s = 0; s < m->n_surfaces; s++) {
        const thx_surface *su = m->surf[s];
        for (size_t t = 0; t < su->n_tris; t++) {
            const double *p[3];
            double d = 0;
            for (int k = 0; k < 3; k++) p[k] = su->xyz + 3 * (size_t)su->tri[3 * t + (size_t)k];
            for (int a = 0; a < 3; a++) {
                double g = (p[0][a] + p[1][a] + p[2][a]) / 3 - c[a];
                d += g * g;
            }
            if (d >= best) continue;
            best = d;
            *ws = s;
            *wt = t;
            angle = 180;
            for (int k = 0; k < 3; k++) {
                const double *o = p[k], *u = p[(k + 1) % 3], *w = p[(k + 2) % 3];
                double x[3], y[3], xx = 0, yy = 0, xy = 0;
                for (int a = 0; a < 3; a++) { x[a] = u[a] - o[a]; y[a] = w[a] - o[a]; xx += x[a] * x[a]; yy += y[a] * y[a]; xy += x[a] * y[a]; }
                double ang = acos(fmax(-1, fmin(1, xy / sqrt(xx * yy)))) * 180 / M_PI;
                if (ang < angle) angle = ang;
            }
        }
    }
    return angle;
}

/* --min-dihedral: the mesh passed with the bar lowered below the check's default. Warns and records
 * it in the model's provenance ("mesh": the bar, the smallest angle and the warning), so that the
 * model says what thorax check without the option will say. */
static thx_status record_low_bar(thx_ctx *ctx, thx_model *m, const char *in, double got, double bar, double def)
{
    int low = got < def;
    if (!low && (!m->provenance_json || !strstr(m->provenance_json, "\"mesh\""))) return THX_OK;
    char warn[256];
    snprintf(warn, sizeof warn, "smallest dihedral angle %.3g deg is below thorax check's %g deg; accepted by --min-dihedral "
             "%g (thorax check fails this mesh unless given --min-dihedral %g)", got, def, bar, bar);
    if (low) fprintf(stderr, "thorax mesh: %s: warning: %s\n", in, warn);
    cJSON *prov = m->provenance_json ? cJSON_Parse(m->provenance_json) : cJSON_CreateObject();
    if (!prov || !cJSON_IsObject(prov)) { cJSON_Delete(prov); return thx_error(ctx, THX_EINPUT, "mesh: the model's provenance is not a JSON object"); }
    cJSON_DeleteItemFromObjectCaseSensitive(prov, "mesh"); /* an earlier mesh's warning goes with it */
    cJSON *mj = NULL;
    if (low)
        mj = cJSON_AddObjectToObject(prov, "mesh");
    if (low && (!mj || !cJSON_AddNumberToObject(mj, "min_dihedral_limit_deg", bar) || !cJSON_AddNumberToObject(mj, "min_dihedral_deg", got) ||
        !cJSON_AddStringToObject(mj, "warning", warn))) { cJSON_Delete(prov); return THX_ENOMEM; }
    char *txt = cJSON_PrintUnformatted(prov);
    cJSON_Delete(prov);
    if (!txt) return THX_ENOMEM;
    free(m->provenance_json);
    m->provenance_json = txt;
    return THX_OK;
}

/* --folds DEG[/MM] (or 0): the excluded heart's fold angle and the size at its folds */
static int parse_folds(void *user, const cli_opt *opt, const char *v)
{
    (void)opt;
    thx_mesh_opts *o = user;
    char *end;
    errno = 0;
    o->fold_deg = strtod(v, &end);
    o->fold_size = 0;
    if (end != v && *end == '/') {
        const char *w = end + 1;
        o->fold_size = strtod(w, &end);
        if (end == w || !(o->fold_size > 0) || o->fold_size > 1e3) end = (char *)v;
    }
    if (end == v || *end || errno || !(o->fold_deg >= 0) || o->fold_deg >= 180)
        return cli_usage_error("mesh", "--folds takes DEG[/MM]: an interior dihedral angle from 0 (off) to below 180 "
                               "degrees, and optionally a positive size in mm, got '%s'", v);
    return 0;
}

/* --quality R/D (or 0): the Delaunay refinement's radius-edge ratio and dihedral angle */
static int parse_quality(void *user, const cli_opt *opt, const char *v)
{
    thx_mesh_opts *o = user;
    char *end = NULL;
    o->radius_edge = strtod(v, &end);
    o->refine_deg = 0;
    if (*end == '/') o->refine_deg = strtod(end + 1, &end);
    if (end == v || *end || o->radius_edge < 0 || (o->radius_edge > 0 && o->radius_edge < 1) || o->refine_deg < 0 || o->refine_deg > 30)
        return cli_usage_error("mesh", "--quality takes RATIO/DEG: a radius-edge ratio of at least 1 (0: off) and a dihedral angle of 0 to 30 degrees, got '%s'", v);
    return 0;
}

/* --region NAME[=NEWNAME][:SIGMA] */
static int parse_region(void *user, const cli_opt *opt, const char *v)
{
    thx_mesh_opts *o = user;
    if (o->n_region_set >= 16) return cli_usage_error("mesh", "at most 16 --region options");
    char buf[256];
    snprintf(buf, sizeof buf, "%s", v);
    char *colon = strchr(buf, ':'), *eq = strchr(buf, '=');
    double sigma = 0;
    if (colon) {
        *colon = 0;
        char *end = NULL;
        sigma = strtod(colon + 1, &end);
        if (end == colon + 1 || *end || !(sigma >= THX_SIGMA_MIN && sigma <= THX_SIGMA_MAX))
            return cli_usage_error("mesh", "--region %s: the conductivity must be a number from %g to %g (S/m)", v,
                                   THX_SIGMA_MIN, THX_SIGMA_MAX);
    }
    if (eq) *eq = 0;
    if (!buf[0] || strlen(buf) >= 64 || (eq && (!eq[1] || strlen(eq + 1) >= 64)) || (!colon && !eq))
        return cli_usage_error("mesh", "--region %s: expected NAME=NEWNAME, NAME:SIGMA or NAME=NEWNAME:SIGMA", v);
    /* both are shorter than 64 (checked above): copied whole, with their NUL */
    memcpy(o->region_set[o->n_region_set].name, buf, strlen(buf) + 1);
    memcpy(o->region_set[o->n_region_set].rename, eq ? eq + 1 : "", eq ? strlen(eq + 1) + 1 : 1);
    o->region_set[o->n_region_set].sigma = sigma;
    o->n_region_set++;
    return 0;
}

/* --sigma NAME=SIGMA: checked here (the number or tensor), the name when the regions exist */
static int parse_sigma(void *user, const cli_opt *opt, const char *v)
{
    thx_mesh_opts *o = user;
    (void)opt;
    if (o->n_sigma_set >= sizeof o->sigma_set / sizeof o->sigma_set[0])
        return cli_usage_error("mesh", "at most %zu --sigma options", sizeof o->sigma_set / sizeof o->sigma_set[0]);
    const char *eq = strchr(v, '=');
    thx_ctx *ctx = NULL;
    if (thx_ctx_create(&ctx) != THX_OK) return cli_usage_error("mesh", "out of memory");
    double s[9];
    int aniso = 0;
    int bad = !eq || eq == v ? 1 : thx_sigma_parse(ctx, eq + 1, s, &aniso) != THX_OK ? 2 : 0;
    int rc = 0;
    if (bad == 1) rc = cli_usage_error("mesh", "--sigma %s: expected NAME=SIGMA", v);
    else if (bad == 2) rc = cli_usage_error("mesh", "--sigma %s", thx_ctx_message(ctx));
    thx_ctx_destroy(&ctx);
    if (!rc) o->sigma_set[o->n_sigma_set++] = v;
    return rc;
}

int cmd_mesh(int argc, char **argv)
{
    progress_state ps = {"", 0, 0};
    const char *out = NULL;
    int verbose = 0, want_stats = 0;
    double min_dihedral = -1; /* the check's bar; < 0: its default (1 deg) */
    thx_mesh_opts o;
    thx_mesh_opts_default(&o);
    char quality[40];
    snprintf(quality, sizeof quality, "%g/%g", o.radius_edge, o.refine_deg);
    cli_opt opts[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "MODEL", .s = &out, .def = "MODEL itself",
         .help = "write the meshed model here"},
        {.name = "--grid", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o.grid, .rule = CLI_GT,
         .bad = "--grid must be positive", .def = "6.5 + 0.3 (d - 5) for layers d mm apart: 6.5 mm for 5, 8 mm for 10",
         .help = "grid spacing in the layer planes"},
        {.name = "--tol", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o.tol, .rule = CLI_GT,
         .bad = "--tol must be positive", .def = "grid/2", .help = "drop grid points closer than this to a surface"},
        {.name = "--layer-spacing", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &o.layer_spacing, .rule = CLI_GT,
         .bad = "--layer-spacing must be positive",
         .def = "the layers of the outer surface when it was built from contours, else --grid",
         .help = "grid planes this far apart"},
        {.name = "--no-heart", .type = CLI_FLAG, .i = &o.no_heart, .help = "leave the heart's interior out of the domain"},
        {.name = "--quality", .type = CLI_STRING, .meta = "R/D", .def = quality, .note = "0 = off", .fn = parse_quality,
         .help = "Delaunay refinement: circumcentres of tetrahedra whose radius-edge ratio exceeds R or whose smallest "
                 "dihedral angle is below D degrees; with 0 the repair still removes the slivers"},
        {.name = "--folds", .type = CLI_STRING, .meta = "DEG[/MM]", .def = "120/grid÷14", .note = "0 = off",
         .fn = parse_folds,
         .help = "with --no-heart, the heart's sharp folds (edges whose interior dihedral angle is below DEG, such "
                 "as the rim where an endocardium meets the epicardium) are re-entrant edges of the domain: the "
                 "tetrahedra around them are refined to a circumradius of MM there, growing by 0.2 mm per mm away "
                 "(without it the transfer columns of nodes in the cavities behind them come out too small)"},
        {.name = "--repair", .type = CLI_REAL, .meta = "DEG", .unit = "deg", .d = &o.repair_deg, .rule = CLI_GE | CLI_LT,
         .lo = 0, .hi = 70, .bad = "--repair must be between 0 and 70 degrees", .note = "0: 5",
         .help = "repair tetrahedra inside with a dihedral angle below DEG by edge/face flips, moving nodes and "
                 "inserting nodes; never less than 5 deg, so that the mesh passes thorax check: --repair 0 "
                 "repairs only the slivers below 5 deg"},
        {.name = "--region", .type = CLI_STRING, .meta = "NAME[=NEW][:SIGMA]", .unit = "S/m", .flags = CLI_REPEAT,
         .fn = parse_region,
         .help = "rename a tissue region and/or set its isotropic conductivity SIGMA, e.g. --region "
                 "mean_thorax=scalp:1 --region skull:0.0125"},
        {.name = "--sigma", .type = CLI_STRING, .meta = "NAME=S|SXX,SYY,SZZ[,SXY,SXZ,SYZ]", .unit = "S/m",
         .flags = CLI_REPEAT, .fn = parse_sigma,
         .help = "the conductivity of region NAME (its name after --region): a number (isotropic), or a tensor in "
                 "the model's axes, its diagonal or all six entries; e.g. --sigma lung_l=0.08 --sigma "
                 "muscle=0.04,0.04,0.4 (docs/decisions.md lists the defaults and their sources; thorax sigma "
                 "changes them later)"},
        {.name = "--min-dihedral", .type = CLI_REAL, .meta = "DEG", .unit = "deg", .d = &min_dihedral,
         .rule = CLI_GE | CLI_LE, .lo = 0, .hi = 1, .bad = "--min-dihedral must be between 0 and 1 degree (the check's default)",
         .def = "1 (thorax check's default)",
         .help = "accept a mesh whose smallest dihedral angle is below the check's 1 deg but at least DEG (0: any "
                 "positive): a last resort where a sliver truly remains; a warning is printed and recorded in "
                 "model.json (provenance.mesh), and thorax check without --min-dihedral DEG fails the mesh"},
        {.name = "--stats", .type = CLI_FLAG, .i = &want_stats, .help = "print counts and times"},
        {.name = "-v", .type = CLI_SET, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_SET, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE, .help = "less logging"},
    };
    cli_command cmd = {
        .name = "mesh",
        .usage = "MODEL [-o] [--grid] [--tol] [--layer-spacing] [--no-heart] [--quality] [--folds] [--repair] [--min-dihedral] [--region]... [--sigma]... [--stats]",
        .about = "Tetrahedralizes the domain inside the model's outer surface (paper 3.3, the\n"
                 "hybrid method, made conforming): the surface nodes plus a square grid on each\n"
                 "layer plane, points within a tolerance of any surface dropped; Delaunay; points\n"
                 "added on the surfaces until every surface triangle is a union of mesh faces\n"
                 "(Steiner points, recorded in volume.steiner); the pieces the surfaces cut the\n"
                 "mesh into get their tissue regions by inside/outside tests, those outside the\n"
                 "outer surface are removed; flat tetrahedra repaired (flips, moving grid nodes)\n"
                 "keeping every face on a surface; the default conductivity table. Writes\n"
                 "volume.pts, volume.tet and the node tables into the model directory (or the\n"
                 "one given by -o).\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
        .user = &o,
    };
    int pr = cli_parse(&cmd, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (cmd.n_pos > 1) return cli_usage_error("mesh", "more than one model given");
    const char *in = cmd.n_pos ? cmd.pos[0] : NULL;
    if (!in) return cli_usage_error("mesh", "no model given");
    if (!out) out = in;
    thx_ctx *ctx = cli_ctx(verbose);
    thx_model *m = NULL;
    thx_mesh_stats S;
    int rc = 0;
    if (verbose >= 0 && isatty(2)) { o.progress = mesh_progress; o.progress_user = &ps; }
    /* the output first: the model itself (meshed in place), or absent, or another thorax model; an
       output elsewhere must not hold the input model */
    thx_outdir od;
    char rin[PATH_MAX], rout[PATH_MAX];
    int in_place = realpath(in, rin) && realpath(out, rout) && !strcmp(rin, rout);
    const char *inputs[] = {in};
    thx_status st = thx_outdir_claim(ctx, &od, out, THX_MODEL_MANIFEST, THX_MODEL_FORMAT, inputs, in_place ? 0 : 1);
    if (st == THX_OK) st = thx_model_read(ctx, in, &m);
    if (st == THX_OK) st = thx_mesh_build(ctx, m, &o, &S);
    if (ps.shown) fputc('\n', stderr);
    /* never write a mesh its own check fails: refuse it, naming the fault and where it sits. The surfaces
       are checked at the values their files will give back (volume.pts is written exactly), so that the
       verdict kept in model.json covers the files a solver reads (thorax/check/verdict.h) */
    int default_check = min_dihedral < 0;
    if (st == THX_OK)
        for (size_t k = 0; k < m->n_surfaces; k++)
            for (size_t i = 0; i < 3 * m->surf[k]->n_nodes; i++) m->surf[k]->xyz[i] = thx_surface_stored_coord(m->surf[k]->xyz[i]);
    if (st == THX_OK) {
        thx_volume_report r;
        memset(&r, 0, sizeof r);
        thx_volume_check_opts co;
        thx_volume_check_opts_default(&co);
        double bar = co.min_dihedral_deg;
        if (min_dihedral >= 0) co.min_dihedral_deg = min_dihedral;
        thx_status cs = thx_volume_check(ctx, m->volume, m, &co, &r);
        if (cs == THX_ECHECK) {
            for (size_t k = 0; k < r.n_reasons; k++) fprintf(stderr, "thorax mesh: %s: %s\n", in, r.reasons[k]);
            if (r.failures & THX_VCHECKF_QUALITY) {
                const int32_t *q = m->volume->tet + 4 * r.min_dihedral_tet;
                double c[3] = {0, 0, 0};
                for (int k = 0; k < 4; k++)
                    for (int a = 0; a < 3; a++) c[a] += 0.25 * m->volume->xyz[3 * (size_t)q[k] + (size_t)a];
                size_t ws = 0, wt = 0;
                double ang = nearest_triangle(m, c, &ws, &wt);
                fprintf(stderr, "thorax mesh: the worst tetrahedron is at (%.3f, %.3f, %.3f), by surface \"%s\" triangle %zu, "
                        "whose smallest angle is %.2f deg%s\n", c[0], c[1], c[2], m->surf[ws]->name, wt + 1, ang,
                        ang < 5 ? ": a needle in the surface forces flat tetrahedra there (repair the surface)" : "");
                if (min_dihedral < 0 && r.min_dihedral > 0 && !(r.failures & ~THX_VCHECKF_QUALITY))
                    fprintf(stderr, "thorax mesh: only the dihedral angle fails: --min-dihedral %.2g accepts this mesh, "
                            "with a warning recorded in model.json\n", floor(r.min_dihedral * 100) / 100);
            }
            st = thx_error(ctx, THX_ECHECK, "mesh: the volume fails its check (above); nothing written");
        } else if (cs != THX_OK) st = cs;
        if (st == THX_OK) st = record_low_bar(ctx, m, in, r.min_dihedral, co.min_dihedral_deg, bar);
        thx_volume_report_free(&r);
    }
    if (st == THX_OK) mesh_progress(&ps, "writing", 0.0);
    if (st == THX_OK) st = thx_model_write_claimed(ctx, m, &od);
    if (st == THX_OK && default_check) st = thx_volume_verdict_record(ctx, out);
    if (ps.shown && !strcmp(ps.stage, "writing")) { mesh_progress(&ps, "writing", 1.0); fputc('\n', stderr); }
    if (st != THX_OK) rc = cli_fail(ctx, "mesh", st);
    else {
        if (verbose >= 0) {
            printf("%zu nodes (%zu on surfaces, %zu grid points on %zu planes, grid %.2f mm), %zu tetrahedra\n", S.n_nodes,
                   S.n_surface_nodes, S.n_grid_nodes, S.n_planes, S.grid, S.n_tets);
            for (size_t r = 0; r < m->volume->n_regions && r < 16; r++)
                printf("  region %-12s %9zu tetrahedra\n", m->volume->regions[r].name, S.per_region[r]);
            printf("wrote %s\n", out);
        }
        if (want_stats)
            printf("Delaunay %zu tetrahedra, %zu pieces between the surfaces (of %zu tetrahedra classified, %zu "
                   "disagreed with their piece), %zu removed outside, %zu inside the heart; times (s): points %.3f, "
                   "Delaunay %.3f, conformity %.3f, classification %.3f, total %.3f\n",
                   S.n_delaunay_tets, S.n_pieces, S.n_centroid_tested, S.n_centroid_disagree, S.n_outside, S.n_heart, S.t_points,
                   S.t_delaunay, S.t_conform, S.t_classify, S.t_total);
        if (want_stats)
            printf("conformity: %zu of %zu surface triangles were not faces of the Delaunay tetrahedralization; "
                   "%zu Steiner points on edges and %zu inside triangles in %zu rounds; %zu triangles are several "
                   "faces, shortest edge piece %.4f mm; %.3f s\n",
                   S.n_missing_before, S.n_surface_tris, S.n_steiner_edge, S.n_steiner_face, S.conform_rounds,
                   S.n_split_triangles, S.min_piece, S.t_conform);
        if (want_stats && (o.radius_edge > 0 || o.refine_deg > 0))
            printf("refinement (radius-edge %g, dihedral %g deg): %zu circumcentres (%zu close to small surface pieces), "
                   "%zu points on the surfaces instead, %zu tetrahedra left at small pieces, %zu rounds%s; %.3f s\n",
                   o.radius_edge, o.refine_deg, S.n_refine_points, S.n_refine_near, S.n_refine_surface, S.n_refine_left,
                   S.refine_rounds, S.refine_limited ? " (stopped at its point limit)" : "", S.t_refine);
        if (want_stats && o.no_heart && o.fold_deg > 0)
            printf("folds: %zu edges of the heart with an interior dihedral angle below %g deg, tetrahedra there "
                   "refined to %.3g mm (+%g mm per mm)\n", S.n_folds, o.fold_deg, S.fold_size, THX_MESH_FOLD_GRADE);
        if (want_stats)
            printf("repair below %g deg: %zu -> %zu tetrahedra, smallest dihedral %.2f -> %.2f deg; %zu edge removals, "
                   "%zu face removals, %zu grid nodes moved, %zu Steiner nodes slid, %zu collapsed, %zu inserted; %zu surface nodes in pockets of their own surface, %zu given a free node; %.3f s\n",
                   fmax(o.repair_deg, THX_MESH_REPAIR_FLOOR), S.repair_below_before, S.repair_below_after, S.repair_min_before, S.repair_min_after,
                   S.n_edge_removals, S.n_face_removals, S.n_moves, S.n_slides, S.n_collapses, S.n_inserts, S.n_pockets, S.n_pocket_nodes, S.t_repair);
    }
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return rc;
}
