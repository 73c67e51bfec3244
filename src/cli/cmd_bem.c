/* thorax bem: boundary-element forward solutions (paper 4.1): the heart-surface transfer matrix
 * and dipole sources (thorax/bem/bem.h). */
#include <cjson/cJSON.h>
#include <ctype.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "thorax/parallel/parallel.h"
#include "cli/cli_fem.h"
#include "thorax/fem/fem.h"
#include "thorax/bem/bem.h"
#include "thorax/core/fileio.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/io/model_dir.h"
#include "thorax/io/series_file.h"
#include "thorax/model/electrodes.h"

#define THX_BEM_REFINE_STR "4"
_Static_assert(THX_BEM_REFINE_MAX == 4, "THX_BEM_REFINE_STR names THX_BEM_REFINE_MAX");

static int ends_with(const char *s, const char *t)
{
    size_t a = strlen(s), b = strlen(t);
    return a >= b && !strcmp(s + a - b, t);
}

/* Electrode positions "[LABEL] X Y Z" a line (OpenMEEG's .patches, map3d .pts), `#` comments, or a
 * thorax electrode file; placed on the outer surface (projected within max_offset). */
static thx_status load_electrodes(thx_ctx *ctx, const char *path, const thx_model *m, const char *outer,
                                  double max_offset, thx_electrodes **out)
{
    *out = NULL;
    FILE *f = fopen(path, "r");
    if (!f) return thx_error(ctx, THX_EIO, "%s: cannot open", path);
    char line[1024];
    int first = fgets(line, sizeof line, f) != NULL;
    if (first && !strncmp(line, "thorax-electrodes", 17)) {
        fclose(f);
        return thx_electrodes_load(ctx, path, m, outer, max_offset, out, NULL, NULL);
    }
    rewind(f);
    size_t n = 0, cap = 0;
    double *xyz = NULL;
    char (*names)[32] = NULL;
    thx_status st = THX_OK;
    int ln = 0;
    while (fgets(line, sizeof line, f)) {
        ln++;
        char *h = strchr(line, '#');
        if (h) *h = '\0';
        char *s = line;
        while (isspace((unsigned char)*s)) s++;
        if (!*s) continue;
        char lab[32] = "";
        double v[3];
        char extra[4];
        if (sscanf(s, "%lf %lf %lf %3s", &v[0], &v[1], &v[2], extra) != 3) {
            if (sscanf(s, "%31s %lf %lf %lf %3s", lab, &v[0], &v[1], &v[2], extra) != 4) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: expected 'X Y Z' or 'LABEL X Y Z'", path, ln);
                break;
            }
        }
        if (!isfinite(v[0] + v[1] + v[2])) { st = thx_error(ctx, THX_EINPUT, "%s:%d: a coordinate is not finite", path, ln); break; }
        if (n + 1 > cap) {
            size_t c = cap;
            if ((st = thx_grow(ctx, (void **)&xyz, &c, n + 1, 3 * sizeof *xyz)) != THX_OK) break;
            c = cap;
            if ((st = thx_grow(ctx, (void **)&names, &c, n + 1, sizeof *names)) != THX_OK) break;
            cap = c;
        }
        memcpy(xyz + 3 * n, v, sizeof v);
        if (lab[0]) snprintf(names[n], sizeof names[n], "%s", lab);
        else snprintf(names[n], sizeof names[n], "P%zu", n + 1);
        n++;
    }
    fclose(f);
    if (st == THX_OK && n == 0) st = thx_error(ctx, THX_EINPUT, "%s: no electrode", path);
    thx_electrodes *e = NULL;
    if (st == THX_OK) st = thx_electrodes_create(ctx, n, &e);
    if (st == THX_OK) {
        snprintf(e->surface, sizeof e->surface, "%s", outer);
        for (size_t i = 0; i < n; i++) {
            memcpy(e->name[i], names[i], sizeof names[i]);
            e->node[i] = THX_ELECTRODE_OFF_NODE;
            memcpy(e->xyz + 3 * i, xyz + 3 * i, 3 * sizeof *xyz);
        }
        st = thx_electrodes_place(ctx, e, m, max_offset, NULL);
    }
    free(xyz);
    free(names);
    if (st != THX_OK) thx_electrodes_destroy(&e);
    *out = e;
    return st;
}

static const char *ext_of(thx_series_format f)
{
    return f == THX_SERIES_TEXT ? "txt" : f == THX_SERIES_MAT ? "mat" : "raw";
}

int cmd_bem(int argc, char **argv)
{
    const char *out = NULL, *dip_path = NULL, *elec_path = NULL, *cond_path = NULL, *heart_name = NULL;
    int verbose = 0, transfer = 0, refine = 0, no_ipa = 0, format = THX_SERIES_RAW, scalapack = 0, method = THX_BEM_SYMMETRIC;
    cli_petsc_args pa;
    cli_petsc_args_init(&pa, argv[0]);
    double max_offset = THX_ELECTRODE_MAX_OFFSET_MM;
    static const cli_choice formats[] = {{"raw", THX_SERIES_RAW}, {"text", THX_SERIES_TEXT}, {"mat", THX_SERIES_MAT},
                                         {NULL, 0}};
    static const cli_choice methods[] = {{"symmetric", THX_BEM_SYMMETRIC}, {"collocation", THX_BEM_COLLOCATION}, {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "DIR", .s = &out,
         .help = "the result directory (written whole or not at all)"},
        {.name = "--transfer", .type = CLI_FLAG, .i = &transfer,
         .help = "the heart-surface transfer matrix: DIR/transfer.EXT (rows: the outer surface's nodes, columns: the "
                 "heart's), or with --electrodes DIR/transfer_electrodes.EXT, as thorax forward --transfer-out writes"},
        {.name = "--dipoles", .type = CLI_INPUT, .meta = "FILE", .s = &dip_path,
         .help = "current dipoles, one a line 'px py pz qx qy qz' (OpenMEEG .dip; for a thorax model mm and mA*m, "
                 "potentials in mV as thorax forward --dipoles): DIR/outer.EXT (outer surface's "
                 "nodes x dipoles), DIR/nodes.EXT (every surface's nodes), with --electrodes DIR/electrodes.EXT"},
        {.name = "--electrodes", .type = CLI_INPUT, .meta = "FILE", .s = &elec_path,
         .help = "electrodes on the outer surface: positions '[LABEL] X Y Z' a line (OpenMEEG .patches) or a "
                 "thorax electrode file; projected onto the surface and interpolated on its triangle"},
        {.name = "--max-offset", .type = CLI_REAL, .meta = "DIST", .d = &max_offset, .rule = CLI_GE, .lo = 0,
         .bad = "--max-offset must be a number >= 0",
         .help = "farthest an electrode may lie from the outer surface (model units)"},
        {.name = "--cond", .type = CLI_INPUT, .meta = "FILE", .s = &cond_path, .def = "MODEL's name with .cond",
         .help = "OpenMEEG conductivities for a MODEL given as an OpenMEEG .geom file"},
        {.name = "--refine", .type = CLI_INT, .meta = "N", .i = &refine, .rule = CLI_GE, .lo = 0,
         .bad = "--refine must be an integer >= 0 (at most " THX_BEM_REFINE_STR ")",
         .help = "--transfer: the heart surface subdivided N times by edge midpoints (flat: the same geometry; "
                 "each time 4 triangles a triangle) for the solve, the columns combined back onto the heart's own "
                 "nodes (their hat functions on the fine surface): the same rows and columns, converged further where "
                 "the heart's triangles are coarse for its shape (endocardial cavities); at most " THX_BEM_REFINE_STR,
         .note = "0: the heart as it is"},
        {.name = "--heart", .type = CLI_STRING, .meta = "NAME", .s = &heart_name, .def = "the surface of role heart",
         .help = "the surface whose potentials are given (--transfer)"},
        {.name = "--scalapack", .type = CLI_FLAG, .i = &scalapack,
         .help = "the dense system as PETSc's MATSCALAPACK over the MPI ranks, each rank assembling its rows (the "
                 "default under mpirun with more than one rank; dipoles: the symmetric method)"},
        {.name = "--method", .type = CLI_CHOICE, .choices = methods, .i = &method,
         .help = "dipoles: the symmetric Galerkin BEM (potentials and normal currents on every interface; Kybic et "
                 "al. 2005) or linear collocation (one equation a node); --transfer is always by collocation"},
        {.name = "--no-ipa", .type = CLI_FLAG, .i = &no_ipa,
         .help = "dipoles by collocation: no isolated problem approach (Hamalainen & Sarvas 1989)"},
        {.name = "--format", .type = CLI_CHOICE, .choices = formats, .i = &format, .help = "format of the series written"},
        {.name = "-v", .type = CLI_SET, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_SET, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE, .help = "less logging"},
    };
    cli_command cmd = {
        .name = "bem",
        .usage = "MODEL --transfer -o [--refine] [--heart] [--electrodes] [--max-offset] [--cond] [--scalapack] [--format] [PETSc options]\n"
                 "MODEL --dipoles -o [--electrodes] [--max-offset] [--cond] [--method] [--no-ipa] [--scalapack] [--format]",
        .about = "Boundary-element forward solutions on the model's closed surfaces (paper 4.1):\n"
                 "linear collocation with analytic integrals (de Munck 1992), the isolated\n"
                 "problem approach, dense LU by LAPACK (OpenBLAS). MODEL is a model directory\n"
                 "(conductivities from its volume mesh's regions) or an OpenMEEG .geom file\n"
                 "with its .cond. Writes DIR/bem.json (surfaces, conductivities, timings) and\n"
                 "the series (docs/formats.md, \"Boundary-element results\").\n",
        .epilog = "Under mpirun -np N (or with --scalapack), each rank assembles a block of rows and\n"
                  "ScaLAPACK (PETSc MATSCALAPACK) solves; rank 0 writes. PETSc options are passed through.\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
        .pass = cli_petsc_pass,
        .user = &pa,
    };
    int pr = cli_parse(&cmd, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (cmd.n_pos != 1) return cli_usage_error("bem", cmd.n_pos ? "more than one model given" : "no model given");
    const char *model = cmd.pos[0];
    if (!out) return cli_usage_error("bem", "no output directory given (-o DIR)");
    if (transfer + (dip_path != NULL) != 1) return cli_usage_error("bem", "give exactly one of --transfer, --dipoles");
    if (refine && !transfer) return cli_usage_error("bem", "--refine goes with --transfer (the heart's subdivision)");
    int is_geom = ends_with(model, ".geom");
    if (cond_path && !is_geom) return cli_usage_error("bem", "--cond goes with an OpenMEEG .geom MODEL");
    /* under mpirun (more than one rank), or asked: the distributed path */
    int mpi = scalapack || thx_par_launched() > 1;
    if (mpi && !transfer && method == THX_BEM_COLLOCATION)
        return cli_usage_error("bem", "--method collocation runs on one process: under mpirun or with --scalapack, "
                               "dipoles take the symmetric method");
    int rank = 0;

    thx_ctx *ctx = cli_ctx(verbose);
    thx_status st = THX_OK;
    int rc = 0;
    thx_model *m = NULL;
    thx_bem *b = NULL, *bf = NULL;
    thx_bem_refinement W;
    memset(&W, 0, sizeof W);
    double *Tf = NULL;
    thx_electrodes *el = NULL;
    thx_series *S1 = NULL, *S2 = NULL, *S3 = NULL;
    double *sig = NULL, *pos = NULL, *mom = NULL, *phi = NULL, *T = NULL;
    size_t nd = 0;
    char cond_buf[4200];
    thx_outdir od;
    memset(&od, 0, sizeof od);
    thx_bem_info info;
    memset(&info, 0, sizeof info);
    thx_series_format fmt = (thx_series_format)format;
    const char *ext = ext_of(fmt);
    if (is_geom && !cond_path) {
        snprintf(cond_buf, sizeof cond_buf, "%.*s.cond", (int)(strlen(model) - 5), model);
        cond_path = cond_buf;
    }
    const char *inputs[] = {model, dip_path, elec_path, cond_path};
    if (mpi) {
        st = cli_petsc_init(ctx, &pa, &rank);
        if (st != THX_OK) goto fail;
    }
    if (rank == 0) st = thx_outdir_claim(ctx, &od, out, "bem.json", "thorax-bem", inputs, 4);
    if (st != THX_OK) goto fail;
    if (is_geom) {
        st = thx_bem_read_openmeeg(ctx, model, cond_path, &m, &sig);
    } else {
        st = thx_model_read(ctx, model, &m);
        if (st == THX_OK) {
            sig = malloc((m->n_surfaces ? m->n_surfaces : 1) * sizeof *sig);
            st = sig ? thx_bem_sigma_from_volume(ctx, m, model, sig) : THX_ENOMEM;
        }
    }
    if (st != THX_OK) goto fail;
    size_t outer = m->n_surfaces, heart = m->n_surfaces;
    for (size_t k = 0; k < m->n_surfaces; k++) {
        if (m->surf[k]->role == THX_ROLE_OUTER) outer = k;
        if (heart_name ? !strcmp(m->surf[k]->name, heart_name) : m->surf[k]->role == THX_ROLE_HEART) heart = k;
    }
    if (outer == m->n_surfaces) { st = thx_error(ctx, THX_EINPUT, "%s: no surface of role outer", model); goto fail; }
    if (transfer && heart == m->n_surfaces) {
        st = thx_error(ctx, THX_EINPUT, "%s: no surface %s%s%s", model, heart_name ? "named '" : "of role heart",
                       heart_name ? heart_name : "", heart_name ? "'" : "");
        goto fail;
    }
    if (dip_path) { /* a dipole problem needs every compartment conducting: a hole is refused by the solver */
        st = thx_bem_read_dipoles(ctx, dip_path, &pos, &mom, &nd);
        if (st != THX_OK) goto fail;
    }
    if (elec_path) {
        st = load_electrodes(ctx, elec_path, m, m->surf[outer]->name, max_offset, &el);
        if (st != THX_OK) goto fail;
    }
    st = thx_bem_create(ctx, (const thx_surface *const *)m->surf, m->n_surfaces, sig, &b);
    if (st != THX_OK) goto fail;
    if (thx_bem_outer(b) != outer) {
        st = thx_error(ctx, THX_EINPUT, "%s: the surface of role outer '%s' is not the outermost ('%s' holds it)", model,
                       m->surf[outer]->name, m->surf[thx_bem_outer(b)]->name);
        goto fail;
    }
    if (transfer && refine) {
        /* the refined dense system, checked against the machine before anything is allocated */
        size_t nh = m->surf[heart]->n_nodes, nf = 0;
        if (refine > THX_BEM_REFINE_MAX) { /* the counts as numbers: they pass size_t's range soon */
            double n = (double)nh, t = (double)m->surf[heart]->n_tris, e = 1.5 * t;
            for (int l = 0; l < refine; l++) { n += e; e = 2 * e + 3 * t; t *= 4; }
            double Nn = (double)(thx_bem_n_nodes(b) - nh) + n;
            rc = cli_usage_error("bem", "--refine %d: at most %d (each subdivision makes about 4 heart nodes of one): %d "
                                 "would make '%s' %.4g nodes and the dense system %.4g GB", refine, THX_BEM_REFINE_MAX,
                                 refine, m->surf[heart]->name, n, Nn * Nn * sizeof(double) / 1e9);
            goto usage;
        }
        thx_bem_refined_counts(nh, m->surf[heart]->n_tris, refine, &nf, NULL);
        double Nf = (double)(thx_bem_n_nodes(b) - nh) + (double)nf;
        double bytes = mpi ? (Nf * Nf + 2.0 * Nf * (double)nf) * sizeof(double)
                           : thx_bem_transfer_refined_bytes(b, heart, refine);
        char what[160];
        snprintf(what, sizeof what, "--refine %d ('%s' %zu -> %zu nodes, %.0f unknowns): the dense system's doubles",
                 refine, m->surf[heart]->name, nh, nf, Nf);
        if ((rc = cli_check_count("bem", what, bytes / sizeof(double), sizeof(double))) != 0) goto usage;
    }
    thx_bem_opts o;
    thx_bem_opts_default(&o);
    o.ipa = !no_ipa;
    o.method = method;
    size_t N = thx_bem_n_nodes(b), no = m->surf[outer]->n_nodes, oo = thx_bem_offset(b, outer);
    const char *oname = m->surf[outer]->name;
    if (transfer) {
        size_t nh = m->surf[heart]->n_nodes;
        T = malloc(no * nh * sizeof *T);
        if (!T) { st = THX_ENOMEM; goto fail; }
        if (!mpi) {
            st = thx_bem_transfer_refined(ctx, b, heart, refine, &o, T, &info);
        } else if (!refine) {
            st = thx_bem_transfer_parallel(ctx, b, heart, T, &info);
        } else { /* the fine columns on rank 0, combined there */
            st = thx_bem_refine(ctx, b, heart, refine, &bf, &W);
            if (st == THX_OK) {
                Tf = malloc(no * W.n_fine * sizeof *Tf);
                st = Tf ? thx_bem_transfer_parallel(ctx, bf, heart, Tf, &info) : THX_ENOMEM;
            }
            if (st == THX_OK && rank == 0) thx_bem_refinement_apply(&W, Tf, no, T);
        }
        if (st != THX_OK) goto fail;
        size_t nr = el ? el->n : no;
        st = thx_series_create(ctx, nr, nh, &S1);
        if (st != THX_OK) goto fail;
        for (size_t j = 0; j < nh; j++) {
            S1->time[j] = (double)(j + 1);
            for (size_t i = 0; i < nr; i++) S1->v[j * nr + i] = el ? thx_electrode_value(el, i, T + j * no) : T[j * no + i];
        }
        snprintf(S1->time_unit, sizeof S1->time_unit, "node");
        snprintf(S1->unit, sizeof S1->unit, "1");
        if (el)
            snprintf(S1->label, sizeof S1->label, "transfer matrix electrodes on %.40s <- %.40s (bem)", oname, m->surf[heart]->name);
        else
            snprintf(S1->label, sizeof S1->label, "transfer matrix %.40s <- %.40s (bem)", oname, m->surf[heart]->name);
    } else {
        phi = malloc(N * nd * sizeof *phi);
        if (!phi) { st = THX_ENOMEM; goto fail; }
        st = mpi ? thx_bem_dipoles_parallel(ctx, b, pos, mom, nd, phi, &info)
                 : thx_bem_dipoles(ctx, b, pos, mom, nd, &o, phi, &info);
        if (st != THX_OK) goto fail;
        st = thx_series_create(ctx, no, nd, &S1);
        if (st == THX_OK) st = thx_series_create(ctx, N, nd, &S2);
        if (st == THX_OK && el) st = thx_series_create(ctx, el->n, nd, &S3);
        if (st != THX_OK) goto fail;
        /* a thorax model is in mm with moments in mA*m, as thorax forward --dipoles takes them:
         * mA*m / (S/m * mm^2) = 1e3 V = 1e6 mV; an OpenMEEG geometry keeps its own units */
        double unit = is_geom ? 1 : 1e6;
        for (size_t i = 0; i < N * nd; i++) phi[i] *= unit;
        thx_series *all[3] = {S1, S2, S3};
        for (int q = 0; q < 3; q++) {
            if (!all[q]) continue;
            snprintf(all[q]->time_unit, sizeof all[q]->time_unit, "dipole");
            snprintf(all[q]->unit, sizeof all[q]->unit, "%s", is_geom ? "q/(sigma.L^2)" : "mV");
            for (size_t d = 0; d < nd; d++) all[q]->time[d] = (double)(d + 1);
        }
        snprintf(S1->label, sizeof S1->label, "bem dipole potentials on %.40s (zero mean over it)", oname);
        snprintf(S2->label, sizeof S2->label, "bem dipole potentials, every surface's nodes in model order");
        for (size_t d = 0; d < nd; d++) {
            memcpy(S1->v + d * no, phi + d * N + oo, no * sizeof *phi);
            /* model order of surfaces: the bem keeps it */
            memcpy(S2->v + d * N, phi + d * N, N * sizeof *phi);
            if (S3)
                for (size_t i = 0; i < el->n; i++) S3->v[d * el->n + i] = thx_electrode_value(el, i, phi + d * N + oo);
        }
        if (S3) snprintf(S3->label, sizeof S3->label, "bem dipole potentials at electrodes on %.40s", oname);
    }
    /* NaN is never written with exit 0: every method's result checked before anything is written
       (by rank 0, which writes) */
    if (rank == 0) {
        thx_series *res[3] = {S1, S2, S3};
        const char *what[3] = {transfer ? "the transfer matrix" : "the outer surface's potentials", "the nodes' potentials",
                               "the electrodes' potentials"};
        for (int q = 0; q < 3 && st == THX_OK; q++)
            for (size_t i = 0; res[q] && i < res[q]->n_rows * res[q]->n_frames; i++)
                if (!isfinite(res[q]->v[i])) {
                    st = thx_error(ctx, THX_ESOLVER, "bem: %s: row %zu, %s %zu is %g (method %s): nothing written", what[q],
                                   i % res[q]->n_rows + 1, transfer ? "column" : "dipole", i / res[q]->n_rows + 1,
                                   res[q]->v[i], method == THX_BEM_COLLOCATION ? "collocation" : "symmetric");
                    break;
                }
        if (st != THX_OK) goto fail;
    }
    if (rank != 0) goto end; /* rank 0 writes */
    /* write */
    st = thx_outdir_begin(ctx, &od);
    if (st != THX_OK) goto fail;
    {
        char path[4400];
        cJSON *j = cJSON_CreateObject(), *files = cJSON_CreateObject(), *surfs = cJSON_CreateArray();
        cJSON_AddStringToObject(j, "format", "thorax-bem");
        cJSON_AddNumberToObject(j, "version", 1);
        char abs[PATH_MAX];
        cJSON_AddStringToObject(j, "model", realpath(model, abs) ? abs : model);
        cJSON_AddStringToObject(j, "problem", transfer ? "transfer matrix (heart-surface potentials)" : "dipoles");
        cJSON_AddStringToObject(j, "command", cli_command_line());
        cJSON_AddStringToObject(j, "method", !transfer && method == THX_BEM_SYMMETRIC
                                                 ? "symmetric Galerkin (Kybic et al. 2005): P1 potentials, P0 currents"
                                                 : "linear collocation, analytic integrals (de Munck 1992)");
        for (size_t k = 0; k < m->n_surfaces; k++) {
            cJSON *s = cJSON_CreateObject();
            cJSON_AddStringToObject(s, "name", m->surf[k]->name);
            cJSON_AddNumberToObject(s, "nodes", (double)m->surf[k]->n_nodes);
            cJSON_AddNumberToObject(s, "first_row", (double)thx_bem_offset(b, k));
            cJSON_AddNumberToObject(s, "sigma_in", transfer && k == heart ? 0 : thx_bem_sigma_in(b, k));
            cJSON_AddNumberToObject(s, "sigma_out", thx_bem_sigma_out(b, k));
            int p = thx_bem_parent(b, k);
            if (p >= 0) cJSON_AddStringToObject(s, "inside", m->surf[p]->name);
            cJSON_AddItemToArray(surfs, s);
        }
        cJSON_AddItemToObject(j, "surfaces", surfs);
        if (dip_path) cJSON_AddStringToObject(j, "dipoles", realpath(dip_path, abs) ? abs : dip_path);
        if (dip_path) {
            cJSON_AddStringToObject(j, "moment_unit", is_geom ? "the geometry's (OpenMEEG)" : "mA*m");
            cJSON_AddStringToObject(j, "unit", is_geom ? "q/(sigma.L^2)" : "mV");
        }
        if (elec_path) cJSON_AddStringToObject(j, "electrodes", realpath(elec_path, abs) ? abs : elec_path);
        if (transfer) {
            cJSON_AddNumberToObject(j, "heart_refine", refine);
            cJSON_AddNumberToObject(j, "heart_nodes_solved", (double)(info.n_unknowns - (N - m->surf[heart]->n_nodes)));
        }
        if (info.ipa_surface >= 0) cJSON_AddStringToObject(j, "isolated_problem", m->surf[info.ipa_surface]->name);
        cJSON_AddNumberToObject(j, "unknowns", (double)info.n_unknowns);
        if (mpi) {
            int size = 1;
            thx_fem_init(0, NULL, NULL, &size);
            cJSON_AddStringToObject(j, "dense_solver", "ScaLAPACK (PETSc MATSCALAPACK)");
            cJSON_AddNumberToObject(j, "ranks", size);
        } else {
            cJSON_AddStringToObject(j, "dense_solver", transfer || method == THX_BEM_COLLOCATION
                                                           ? "LAPACK dgetrf/dgetrs"
                                                           : "LAPACK dpotrf (currents), dsyrk, dgetrf (Schur complement)");
        }
        cJSON_AddNumberToObject(j, "seconds_assembly", info.t_assemble);
        cJSON_AddNumberToObject(j, "seconds_solve", info.t_solve);
        cJSON_AddNumberToObject(j, "matrix_bytes", info.matrix_bytes);
        const char *keys[3];
        if (transfer) { keys[0] = el ? "transfer_electrodes" : "transfer"; keys[1] = keys[2] = NULL; }
        else { keys[0] = "outer"; keys[1] = "nodes"; keys[2] = "electrodes"; }
        thx_series *ser[3] = {S1, S2, S3};
        for (int q = 0; q < 3 && st == THX_OK; q++) {
            if (!ser[q] || !keys[q]) continue;
            snprintf(path, sizeof path, "%s/%s.%s", od.tmp, keys[q], ext);
            st = thx_series_write(ctx, ser[q], path, fmt);
            char name[64];
            snprintf(name, sizeof name, "%s.%s", keys[q], ext);
            cJSON_AddStringToObject(files, keys[q], name);
        }
        cJSON_AddItemToObject(j, "files", files);
        st = cli_outdir_finish(ctx, &od, "bem.json", j, st);
        if (st != THX_OK) goto fail;
    }
    if (verbose >= 0) {
        printf("%zu unknowns%s: assembly %.2f s, solve %.2f s\n", info.n_unknowns,
               info.ipa_surface >= 0 ? " (isolated problem approach)" : "", info.t_assemble, info.t_solve);
        printf("wrote %s\n", out);
    }
    goto end;
usage:
    if (rank == 0) thx_outdir_abort(&od);
    goto end;
fail:
    if (rank == 0) thx_outdir_abort(&od);
    rc = cli_fail(ctx, "bem", st);
end:
    thx_series_destroy(&S1);
    thx_series_destroy(&S2);
    thx_series_destroy(&S3);
    thx_electrodes_destroy(&el);
    thx_bem_destroy(&b);
    thx_bem_destroy(&bf);
    thx_bem_refinement_free(&W);
    free(Tf);
    thx_model_destroy(&m);
    free(sig);
    free(pos);
    free(mom);
    free(phi);
    free(T);
    thx_ctx_destroy(&ctx);
    if (mpi) cli_petsc_finish(&pa);
    return rc;
}
