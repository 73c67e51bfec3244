/* thorax forward: finite-element forward solutions (paper 4.1). */
#include <cjson/cJSON.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/cli.h"
#include "thorax/core/blas_kernels.h"
#include "cli/cli_fem.h"
#include "thorax/parallel/parallel.h"
#include "thorax/model/electrodes.h"
#include "thorax/io/electrodes_file.h"
#include "thorax/io/channels_file.h"
#include "cli/cli_bad_leads.h"
#include "thorax/io/series_file.h"
#include "thorax/leads/leads.h"
#include "thorax/phantom/phantom.h"
#include "thorax/fem/fem.h"
#include "thorax/core/fileio.h"
static const char *ext_of(thx_series_format f)
{
    return f == THX_SERIES_TEXT ? "txt" : f == THX_SERIES_MAT ? "mat" : "raw";
}

int cmd_forward(int argc, char **argv)
{
    const char *out = NULL, *epi_path = NULL, *currents = NULL, *transfer_in = NULL, *rows_path = NULL, *dump = NULL;
    const char *channels = NULL, *dipoles = NULL, *bad_leads = NULL;
    int dip_method = THX_DIPOLE_VENANT;
    double max_offset = THX_ELECTRODE_MAX_OFFSET_MM;
    int verbose = 0, want_volume = 0, transfer_out = 0, warm = 1, force = 0, format = THX_SERIES_RAW, meth = -1;
    int rows_only = 0, route = -1; /* route: 0 a solve per frame, 1 the electrodes' transfer matrix, -1 the fewer solves */
    double threshold = 5.0;
    const char *electrodes[16];
    int n_electrodes = 0;
    cli_petsc_args pa;
    cli_petsc_args_init(&pa, argv[0]);
    static const cli_choice formats[] = {{"raw", THX_SERIES_RAW}, {"text", THX_SERIES_TEXT}, {"mat", THX_SERIES_MAT},
                                         {NULL, 0}};
    static const cli_choice dip_methods[] = {{"venant", THX_DIPOLE_VENANT}, {"partial", THX_DIPOLE_PARTIAL}, {NULL, 0}};
    static const cli_choice methods[] = {{"forward", 0}, {"adjoint", 1}, {"auto", -1}, {NULL, 0}};
    static const cli_choice routes[] = {{"frames", 0}, {"transfer", 1}, {"auto", -1}, {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--epicardial", .type = CLI_INPUT, .meta = "SERIES", .s = &epi_path,
         .help = "heart-surface potentials, rows the heart surface's nodes (text, raw or .mat; see thorax series)"},
        {.name = "--dipoles", .type = CLI_INPUT, .meta = "FILE", .s = &dipoles,
         .help = "current dipole sources in the whole volume (positions mm, moments mA*m; OpenMEEG's .dip, a line "
                 "'px py pz qx qy qz' per dipole and frame, or thorax-dipoles moments over time; docs/formats.md): "
                 "DIR/torso.EXT in mV, with --rows DIR/electrodes.EXT"},
        {.name = "--dipole-method", .type = CLI_CHOICE, .choices = dip_methods, .i = &dip_method,
         .help = "venant: monopoles on the nodes around the dipole matching its moment (partial integration where "
                 "its nearest node is on an interface); partial: partial integration (docs/decisions.md)"},
        {.name = "--channels", .type = CLI_INPUT, .meta = "FILE", .s = &channels,
         .help = "map3d .channels: the --epicardial rows are recording channels, heart node i takes channel c "
                 "(a node with no channel is refused)"},
        CLI_BAD_LEADS_OPT(&bad_leads, "filled by Laplacian interpolation on the heart surface before the solve"),
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "DIR", .s = &out,
         .help = "the solution directory (written whole or not at all)"},
        {.name = "--format", .type = CLI_CHOICE, .choices = formats, .i = &format, .help = "format of the series written"},
        {.name = "--volume", .type = CLI_FLAG, .i = &want_volume,
         .help = "also write DIR/volume.EXT: the potential at every volume node"},
        {.name = "--currents", .type = CLI_STRING, .meta = "LIST", .s = &currents,
         .help = "frames (1-based: 5,10,20-30, or all) for which to write the current density J = -sigma grad phi "
                 "(A/m^2 for V, mm) per tetrahedron (DIR/currents_tet.EXT, rows 3 x tetrahedra: Jx Jy Jz) and per node "
                 "(DIR/currents_node.EXT, volume-weighted)"},
        {.name = "--transfer", .type = CLI_INPUT, .meta = "FILE", .s = &transfer_in,
         .help = "apply this transfer matrix to the epicardial series instead of solving"},
        {.name = "--no-warm", .type = CLI_SET, .i = &warm, .ival = 0,
         .help = "start every frame's solve from zero, not from the previous frame's solution"},
        {.name = "--dump-system", .type = CLI_OUTPUT, .meta = "FILE", .s = &dump,
         .help = "write the first frame's K_ff and right-hand side there (PETSc binary)"},
        {.name = "--transfer-out", .type = CLI_FLAG, .i = &transfer_out,
         .help = "compute the transfer matrix (torso nodes, or --rows, from heart nodes) and write DIR/transfer.EXT"},
        {.name = "--rows", .type = CLI_INPUT, .meta = "ELECTRODES", .s = &rows_path, .def = "the outer surface's nodes",
         .help = "electrodes on the outer surface: the rows of --transfer-out's matrix (DIR/transfer_electrodes.EXT), or "
                 "with --epicardial the signals written as DIR/electrodes.EXT; a thorax electrode file, a map3d "
                 ".leadlinks, a node list or positions (X Y Z a line; between nodes: interpolated on the triangle)"},
        {.name = "--rows-only", .type = CLI_FLAG, .i = &rows_only,
         .help = "with --epicardial and --rows: write the electrodes' signals alone (DIR/electrodes.EXT, no torso.EXT); "
                 "when the electrodes are fewer than the frames they are computed through the electrodes' transfer "
                 "matrix (a solve per electrode, applied to every frame at once) instead of a solve per frame"},
        {.name = "--route", .type = CLI_CHOICE, .choices = routes, .i = &route,
         .help = "with --rows-only: frames (a solve per frame), transfer (a solve per electrode), auto (the fewer "
                 "solves; said in solution.json)"},
        {.name = "--max-offset", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &max_offset, .rule = CLI_GE,
         .lo = 0, .bad = "--max-offset must be a number of mm >= 0",
         .help = "farthest a --rows position may lie from the outer surface (it is projected onto it)"},
        {.name = "--method", .type = CLI_CHOICE, .choices = methods, .i = &meth,
         .help = "forward: a solve per heart node; adjoint: a solve per row; auto: the fewer solves"},
        {.name = "--electrode", .type = CLI_STRING, .meta = "SPEC", .flags = CLI_REPEAT, .sv = electrodes,
         .count = &n_electrodes, .max = 16,
         .help = "a defibrillation electrode (up to 16): NAME,at=X:Y:Z,radius=R,voltage=V (mm, V), current=I (A) "
                 "instead of voltage, surface=NAME, or nodes=FILE instead of at and radius (docs/cli.md)"},
        {.name = "--threshold", .type = CLI_REAL, .meta = "V/CM", .unit = "V/cm", .d = &threshold, .rule = CLI_GT,
         .bad = "--threshold must be positive", .help = "field threshold for the fraction of the heart's volume above it"},
        {.name = "--force", .type = CLI_FLAG, .i = &force,
         .help = "solve even if the volume mesh fails the check (a warning in solution.json: \"warnings\", "
                 "\"volume_check\")"},
        {.name = "-v", .type = CLI_SET, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_SET, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE, .help = "less logging"},
    };
    cli_command cmd = {
        .name = "forward",
        .usage = "MODEL --dipoles -o [--dipole-method] [--rows] [--max-offset] [--format] [--volume] [--no-warm] [--force] [PETSc options]\n"
                 "MODEL --epicardial [--channels] [--bad-leads] -o [--rows [--rows-only [--route]]] [--format] [--volume] [--currents] [--transfer] "
                 "[--no-warm] [--dump-system] [--force] [PETSc options]\n"
                 "MODEL --transfer-out -o [--rows] [--max-offset] [--method] [--format] [--force] [PETSc options]\n"
                 "MODEL --electrode... -o [--threshold] [--format] [--force] [PETSc options]",
        .about = "Finite-element forward solutions on the model's volume mesh (paper 4.1):\n"
                 "linear tetrahedra, the conductivity of each tissue region, PETSc solvers.\n\n"
                 "Epicardial problem: the potentials of SERIES (rows: the heart surface's nodes)\n"
                 "prescribed on the heart surface, no current through the torso surface, the\n"
                 "heart's interior left out. Writes DIR/torso.EXT (the outer surface's nodes x\n"
                 "frames) and DIR/solution.json (what was solved, solver figures, timings);\n"
                 "with --rows ELECTRODES also DIR/electrodes.EXT (rows: the electrodes). A\n"
                 "recording whose rows are channels is mapped to the heart's nodes by\n"
                 "--channels (map3d .channels).\n"
                 "Transfer matrix: DIR/transfer.EXT (rows: the outer surface's nodes) or, with\n"
                 "--rows, DIR/transfer_electrodes.EXT; applied with --transfer, a matrix whose\n"
                 "rows are electrodes writes DIR/electrodes.EXT, never torso.EXT.\n"
                 "Dipoles: current dipoles (Saint-Venant or partial integration) in the whole\n"
                 "volume, no current through the outer surface, the potential's integral over it\n"
                 "zero; DIR/torso.EXT (mV) and with --rows DIR/electrodes.EXT.\n"
                 "Defibrillation: the whole domain, the electrodes' currents and potentials,\n"
                 "the field in the heart.\n\n"
                 "Before solving, the volume mesh is checked as thorax check does (conformity,\n"
                 "coverage of every surface, regions, volumes, node tables, smallest dihedral\n"
                 "angle 1 degree); a volume that fails is refused (exit 1, the reasons on stderr)\n"
                 "unless --force, which solves anyway and records the reasons in solution.json.\n",
        .epilog = "PETSc options are passed through: -ksp_type, -pc_type, -ksp_rtol, -ksp_monitor,\n"
                  "-pc_factor_mat_solver_type mumps, ... Default: -ksp_type cg -pc_type gamg\n"
                  "-ksp_rtol 1e-10. Runs under mpirun -np N (rank 0 writes).\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
        .pass = cli_petsc_pass,
        .user = &pa,
    };
    int pr = cli_parse(&cmd, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (cmd.n_pos > 1) return cli_usage_error("forward", "more than one model given");
    const char *model_dir = cmd.n_pos ? cmd.pos[0] : NULL;
    const char *format_name = format == THX_SERIES_TEXT ? "text" : format == THX_SERIES_MAT ? "mat" : "raw";
    if (!model_dir) return cli_usage_error("forward", "no model given");
    if (!out) return cli_usage_error("forward", "no output directory given (-o DIR)");
    int modes = (epi_path != NULL) + transfer_out + (n_electrodes > 0) + (dipoles != NULL);
    if (modes != 1) return cli_usage_error("forward", "give exactly one of --epicardial, --transfer-out, --electrode, --dipoles");
    if (dipoles && (transfer_in || channels || currents || dump))
        return cli_usage_error("forward", "--dipoles goes with --dipole-method, --rows, --max-offset, --volume, --format, "
                                          "--no-warm and --force only");
    if (dipoles)
        return cli_forward_dipoles(model_dir, out, dipoles, dip_method, rows_path, max_offset, format_name, want_volume, warm,
                                   &pa, verbose, force);
    if (transfer_in && !epi_path) return cli_usage_error("forward", "--transfer needs --epicardial");
    if (rows_only && (!epi_path || !rows_path))
        return cli_usage_error("forward", "--rows-only needs --epicardial and --rows");
    if (rows_only && (want_volume || currents || transfer_in || dump))
        return cli_usage_error("forward", "--rows-only writes the electrodes alone: not with --volume, --currents, "
                                          "--transfer or --dump-system");
    if (route != -1 && !rows_only) return cli_usage_error("forward", "--route goes with --rows-only");
    if (rows_path && !transfer_out && !epi_path) return cli_usage_error("forward", "--rows goes with --transfer-out, --epicardial or --dipoles");
    if ((channels || bad_leads) && !epi_path) return cli_usage_error("forward", "--channels and --bad-leads need --epicardial (its rows are the channels)");
    if (n_electrodes)
        return cli_forward_defib(model_dir, out, electrodes, n_electrodes, threshold, format_name, &pa, verbose, force);

    thx_ctx *ctx = cli_ctx(verbose);
    int rank = 0, rc = 0;
    thx_status st = THX_OK;
    thx_model *m = NULL;
    thx_series *epi = NULL, *T = NULL, *torso = NULL, *at_electrodes = NULL;
    thx_electrodes *rowset = NULL;
    int t_electrodes = 0; /* --transfer's rows are electrodes, not the outer surface's nodes */
    thx_forward_result R;
    memset(&R, 0, sizeof R);
    unsigned char *sel = NULL;
    double *jt = NULL, *jn = NULL;
    thx_series *cur_t = NULL, *cur_n = NULL;
    cJSON *vcheck = NULL, *warnings = NULL;
    thx_outdir od;
    memset(&od, 0, sizeof od);
    double t0 = thx_wtime();
    thx_series_format fmt = (thx_series_format)format;
    const char *ext = ext_of(fmt);

    /* the output directory first: refused before any work if it is not thorax's own solution */
    const char *inputs[] = {model_dir, epi_path, rows_path, transfer_in, channels};
    st = thx_outdir_claim(ctx, &od, out, "solution.json", "thorax-solution", inputs, 5);
    /* the kept verdict's digest beside the model's reading (the gate below takes it) */
    if (st == THX_OK && !(transfer_in && !want_volume && !currents)) cli_volume_gate_prefetch(model_dir);
    if (st == THX_OK) st = thx_model_read(ctx, model_dir, &m);
    if (st == THX_OK && epi_path) st = thx_series_read(ctx, epi_path, THX_SERIES_AUTO, &epi);
    if (st == THX_OK && channels) { /* the recording's channels as the heart's nodes */
        thx_channels *ch = NULL;
        thx_series *mapped = NULL;
        st = thx_channels_read(ctx, channels, &ch);
        if (st == THX_OK) st = thx_channels_apply(ctx, ch, epi, &mapped);
        if (st == THX_OK && thx_channels_unmapped(ch)) {
            size_t i = 0;
            while (ch->channel[i] >= 0) i++;
            st = thx_error(ctx, THX_EINPUT, "%s: %zu of %zu nodes have no channel (first: node %zu); the heart's potentials "
                           "must be known at every node", channels, thx_channels_unmapped(ch), ch->n, i + 1);
        }
        if (st == THX_OK) {
            thx_series_destroy(&epi);
            epi = mapped;
            mapped = NULL;
        }
        thx_series_destroy(&mapped);
        thx_channels_destroy(&ch);
    }
    if (st == THX_OK) st = cli_bad_leads_fill_role(ctx, bad_leads, channels, m, THX_ROLE_HEART, epi);
    if (st == THX_OK && rows_path) {
        /* any electrode set on the outer surface: the transfer rows, or the signals sampled */
        const char *outer = NULL;
        for (size_t k = 0; k < m->n_surfaces; k++)
            if (m->surf[k]->role == THX_ROLE_OUTER) outer = m->surf[k]->name;
        double moved = 0;
        st = thx_electrodes_load(ctx, rows_path, m, outer, max_offset, &rowset, NULL, &moved);
        if (st == THX_OK && moved > 0)
            thx_log(ctx, THX_LOG_INFO, "%s: electrodes moved onto the surface by up to %.3g mm", rows_path, moved);
    }
    if (st == THX_OK && transfer_in) st = thx_series_read(ctx, transfer_in, THX_SERIES_AUTO, &T);
    /* a matrix whose rows are electrodes writes electrodes.EXT, not torso.EXT */
    if (st == THX_OK && T && !transfer_out) {
        const thx_surface *os = NULL;
        for (size_t k = 0; k < m->n_surfaces; k++)
            if (m->surf[k]->role == THX_ROLE_OUTER) os = m->surf[k];
        t_electrodes = !strncmp(T->label, "transfer matrix electrodes", 26) || (os && T->n_rows != os->n_nodes);
        if (t_electrodes && rowset && T->n_rows != rowset->n)
            st = thx_error(ctx, THX_EINPUT, "%s: %zu rows, but --rows %s holds %zu electrodes", transfer_in, T->n_rows,
                           rows_path, rowset->n);
    }
    if (st == THX_OK && currents) {
        size_t nf = epi ? epi->n_frames : 0;
        sel = thx_malloc(ctx, nf ? nf : 1);
        if (!sel) st = THX_ENOMEM;
        else if (cli_parse_frames(currents, nf, sel)) { rc = cli_usage_error("forward", "--currents '%s': frames 1..%zu, as 5,10,20-30 or all", currents, nf); goto end; }
    }
    if (st != THX_OK) goto fail;
    /* PETSc only where a solve is needed, or under mpirun with more than one rank (applying a
       transfer matrix needs no solve, but the ranks must know who writes: rank 0) */
    int need_solver = !(T && !want_volume && !currents);
    if (need_solver || thx_par_launched() > 1) {
        st = cli_petsc_init(ctx, &pa, &rank);
        if (st != THX_OK) goto fail;
    }
    if (need_solver) {
        /* the volume the solve runs on must pass the volume check (or --force) */
        st = cli_volume_gate(ctx, "forward", model_dir, m, force, rank, &vcheck, &warnings);
        if (st != THX_OK) goto fail;
    }
    thx_forward_opts fo;
    thx_forward_opts_default(&fo);
    fo.warm = warm;
    fo.dump_system = dump;
    fo.keep_volume = want_volume || currents;
    if (rank == 0 && isatty(2) && verbose >= 0) { fo.progress = cli_progress; fo.user = (void *)"forward"; }
    if (transfer_out) {
        if (rowset) st = thx_forward_transfer_weighted(ctx, m, rowset->corner, rowset->weight, rowset->n, meth, &fo, &T, &R);
        else st = thx_forward_transfer(ctx, m, NULL, 0, meth, &fo, &T, &R);
        if (st != THX_OK) goto fail;
    } else if (T && !fo.keep_volume) {
        double t1 = thx_wtime();
        st = thx_transfer_apply(ctx, T, epi, &torso);
        if (st != THX_OK) goto fail;
        R.t_solve = thx_wtime() - t1;
    } else if (rows_only && (route == 1 || (route == -1 && rowset->n < epi->n_frames))) {
        /* the electrodes' transfer matrix (a solve per electrode with the adjoint method, or per heart node if
           fewer), applied to the frames as one product */
        thx_series *Te = NULL;
        fo.direct = 1; /* the factorization (unless the command line names a solver): both routes give the same signals */
        st = thx_forward_transfer_weighted(ctx, m, rowset->corner, rowset->weight, rowset->n, meth, &fo, &Te, &R);
        if (st == THX_OK) {
            double t1 = thx_wtime();
            st = thx_transfer_apply(ctx, Te, epi, &at_electrodes);
            R.t_solve += thx_wtime() - t1;
            route = 1;
        }
        thx_series_destroy(&Te);
        if (st != THX_OK) goto fail;
    } else {
        st = thx_forward_epicardial(ctx, m, epi, &fo, &R);
        if (st != THX_OK) goto fail;
        torso = R.torso;
        R.torso = NULL;
        if (rows_only) route = 0;
    }
    /* the electrodes' signals: from the torso's nodes (the matrix applied gave them directly) */
    if (!transfer_out) {
        if (T && !fo.keep_volume && t_electrodes) {
            at_electrodes = torso;
            torso = NULL;
        } else if (rowset && rank == 0 && !at_electrodes) { /* rank 0 holds the torso's potentials and writes */
            st = thx_electrodes_sample(ctx, rowset, torso, &at_electrodes);
            if (st != THX_OK) goto fail;
        }
        if (rows_only) thx_series_destroy(&torso); /* the electrodes alone are written */
    }
    /* currents for the chosen frames */
    if (currents && R.volume) {
        const thx_volume *v = m->volume;
        size_t nsel = 0;
        for (size_t f = 0; f < epi->n_frames; f++) nsel += sel[f];
        st = thx_series_create(ctx, 3 * v->n_tets, nsel, &cur_t);
        if (st == THX_OK) st = thx_series_create(ctx, 3 * v->n_nodes, nsel, &cur_n);
        unsigned char *use = malloc(v->n_regions ? v->n_regions : 1);
        if (st == THX_OK && !use) st = THX_ENOMEM;
        if (st != THX_OK) { free(use); goto fail; }
        for (size_t r = 0; r < v->n_regions; r++) use[r] = strcmp(v->regions[r].name, "heart") != 0;
        for (size_t f = 0, k = 0; f < epi->n_frames; f++) {
            if (!sel[f]) continue;
            thx_fem_currents(v, use, R.volume->v + f * v->n_nodes, cur_t->v + k * 3 * v->n_tets, cur_n->v + k * 3 * v->n_nodes);
            cur_t->time[k] = cur_n->time[k] = epi->time[f];
            k++;
        }
        free(use);
        for (int q = 0; q < 2; q++) {
            thx_series *c = q ? cur_n : cur_t;
            snprintf(c->unit, sizeof c->unit, "A/m^2 per %.20s", epi->unit[0] ? epi->unit : "unit");
            snprintf(c->time_unit, sizeof c->time_unit, "%s", epi->time_unit);
            snprintf(c->label, sizeof c->label, "current density J = -sigma grad phi per %s (rows: x, y, z of each)",
                     q ? "node (volume-weighted)" : "tetrahedron");
        }
    }
    /* under mpirun with the volume: each rank's part of it too (sort-last's data) */
    int parts = want_volume && R.volume && R.ranks > 1;
    if (parts) {
        st = cli_forward_parts(ctx, &od, m, R.volume, rank, R.ranks);
        if (st != THX_OK) goto fail;
    }
    /* write (rank 0): a temporary directory renamed as a whole */
    if (rank == 0) {
        char path[4400];
        if (!parts) st = thx_outdir_begin(ctx, &od);
        if (st != THX_OK) goto fail;
        cJSON *j = cJSON_CreateObject(), *files = cJSON_CreateObject(), *solver = cJSON_CreateObject();
        cJSON_AddStringToObject(j, "format", "thorax-solution");
        cJSON_AddNumberToObject(j, "version", 1);
        char absmodel[PATH_MAX];
        cJSON_AddStringToObject(j, "model", realpath(model_dir, absmodel) ? absmodel : model_dir);
        cJSON_AddStringToObject(j, "problem", transfer_out ? "transfer matrix (epicardial)" : "epicardial");
        char route_txt[200] = "";
        if (rows_only) {
            if (route == 1)
                snprintf(route_txt, sizeof route_txt, "transfer: the %zu electrodes' transfer matrix (%ld solves), applied to "
                         "the %zu frames", rowset->n, R.it_total > 0 && R.it_min == 1 && R.it_max == 1 ? R.it_total : (long)rowset->n,
                         epi->n_frames);
            else snprintf(route_txt, sizeof route_txt, "frames: a solve per frame (%zu frames, %zu electrodes)", epi->n_frames,
                          rowset->n);
            cJSON_AddStringToObject(j, "route", route_txt);
        }
        cJSON_AddStringToObject(j, "command", cli_command_line());
        if (epi_path) {
            char abs[PATH_MAX];
            cJSON_AddStringToObject(j, "epicardial", realpath(epi_path, abs) ? abs : epi_path);
            cJSON_AddNumberToObject(j, "frames", (double)epi->n_frames);
            cJSON_AddStringToObject(j, "unit", epi->unit);
        }
        for (size_t s = 0; s < m->n_surfaces; s++)
            if (m->surf[s]->role == THX_ROLE_OUTER) cJSON_AddStringToObject(j, "surface", m->surf[s]->name);
        struct { const char *key; thx_series *s; } w[] = {
            {"torso", torso}, {"electrodes", at_electrodes}, {"volume", R.volume}, {"currents_tet", cur_t},
            {"currents_node", cur_n}, {rowset ? "transfer_electrodes" : "transfer", transfer_out ? T : NULL}};
        for (size_t k = 0; k < sizeof w / sizeof w[0] && st == THX_OK; k++) {
            if (!w[k].s) continue;
            snprintf(path, sizeof path, "%s/%s.%s", od.tmp, w[k].key, ext);
            st = thx_series_write(ctx, w[k].s, path, fmt);
            char name[64];
            snprintf(name, sizeof name, "%s.%s", w[k].key, ext);
            cJSON_AddStringToObject(files, w[k].key, name);
        }
        if (rowset && st == THX_OK) {
            char abs[PATH_MAX];
            cJSON_AddStringToObject(j, "rows", realpath(rows_path, abs) ? abs : rows_path);
        }
        if (channels && st == THX_OK) {
            char abs[PATH_MAX];
            cJSON_AddStringToObject(j, "channels", realpath(channels, abs) ? abs : channels);
        }
        cJSON_AddItemToObject(j, "files", files);
        if (parts) { /* DIR/parts, its own manifest naming the parts */
            cJSON *pj = cJSON_CreateObject();
            cJSON_AddStringToObject(pj, "dir", "parts");
            cJSON_AddStringToObject(pj, "manifest", "parts/parts.json");
            cJSON_AddNumberToObject(pj, "ranks", R.ranks);
            cJSON_AddItemToObject(j, "volume_parts", pj);
        }
        if (vcheck) {
            cJSON_AddItemToObject(j, "volume_check", vcheck);
            vcheck = NULL;
        }
        if (warnings) {
            cJSON_AddItemToObject(j, "warnings", warnings);
            warnings = NULL;
        }
        if (R.ranks) {
            cJSON_AddStringToObject(solver, "ksp", R.ksp);
            cJSON_AddStringToObject(solver, "pc", R.pc);
            cJSON_AddNumberToObject(solver, "ranks", R.ranks);
            cJSON_AddNumberToObject(solver, "free_nodes", (double)R.n_free);
            cJSON_AddNumberToObject(solver, "prescribed_nodes", (double)R.n_prescribed);
            cJSON_AddNumberToObject(solver, "iterations_min", R.it_min);
            cJSON_AddNumberToObject(solver, "iterations_max", R.it_max);
            cJSON_AddNumberToObject(solver, "iterations_total", (double)R.it_total);
            cJSON_AddNumberToObject(solver, "max_relative_residual", R.max_residual);
            if (R.backward_share > 0) {
                /* the outer surface alone: the backward sweep pruned, the residual of two combinations of each thread's
                   frames in a block, and how far the frames' answers combined are from theirs */
                cJSON_AddStringToObject(solver, "residual_of", "two combinations of each thread's frames in a block, solved in full beside them");
                cJSON_AddNumberToObject(solver, "backward_sweep_share", R.backward_share);
                cJSON_AddNumberToObject(solver, "combination_check", R.check);
            }
            cJSON_AddNumberToObject(solver, "block", (double)R.block); /* right-hand sides per solve (1: one by one) */
            cJSON_AddNumberToObject(solver, "seconds_assembly", R.t_assemble);
            cJSON_AddBoolToObject(solver, "assembly_kept", R.assembly.kept);
            if (R.assembly.note[0]) cJSON_AddStringToObject(solver, "assembly_note", R.assembly.note);
            cJSON_AddNumberToObject(solver, "seconds_setup", R.t_setup);
            cJSON_AddNumberToObject(solver, "seconds_matrix", R.t_matrix);
            if (R.factor.used) {
                /* thorax's own direct path (docs/design/parallel.md): the factor's figures, so that a reader can
                   put the time beside the flops */
                cJSON *f = cJSON_CreateObject();
                cJSON_AddStringToObject(f, "package", "CHOLMOD's analysis (supernodal), driven by thorax");
                cJSON_AddStringToObject(f, "numeric", R.factor.numeric);
                if (R.factor.threads) {
                    cJSON_AddNumberToObject(f, "threads", R.factor.threads);
                    cJSON_AddNumberToObject(f, "subtrees", (double)R.factor.subtrees);
                    cJSON_AddNumberToObject(f, "top_supernodes", (double)R.factor.top);
                    cJSON_AddNumberToObject(f, "top_share", R.factor.top_share);
                    cJSON_AddNumberToObject(f, "seconds_subtrees", R.factor.t_subtrees);
                    cJSON_AddNumberToObject(f, "seconds_top", R.factor.t_top);
                    cJSON_AddBoolToObject(f, "top_beside_solves", R.factor.top_beside);
                }
                cJSON_AddStringToObject(f, "ordering", "METIS nested dissection");
                cJSON_AddBoolToObject(f, "ordering_cached", R.factor.ordering_cached);
                cJSON_AddBoolToObject(f, "symbolic_cached", R.factor.symbolic_cached);
                if (R.factor.cache_note[0]) cJSON_AddStringToObject(f, "cache_note", R.factor.cache_note);
                cJSON_AddNumberToObject(f, "seconds_ordering", R.factor.t_ordering);
                cJSON_AddNumberToObject(f, "seconds_analysis", R.factor.t_analysis);
                cJSON_AddNumberToObject(f, "seconds_factorization", R.factor.t_factor);
                cJSON_AddNumberToObject(f, "flops_factorization", R.factor.flops);
                cJSON_AddNumberToObject(f, "flops_solves", R.factor.solve_flops);
                cJSON_AddNumberToObject(f, "nonzeros", R.factor.nonzeros);
                cJSON_AddNumberToObject(f, "bytes", (double)R.factor.factor_bytes);
                if (R.factor.blas_threads) cJSON_AddNumberToObject(f, "blas_threads_factorization", R.factor.blas_threads);
                /* the kernels the BLAS ran (OpenBLAS's core: the machine's choice, thorax/core/blas_kernels.h) */
                if (thx_blas_loaded_core()) cJSON_AddStringToObject(f, "blas_kernels", thx_blas_loaded_core());
                cJSON_AddItemToObject(solver, "factor", f);
            }
        } else {
            cJSON_AddStringToObject(solver, "method", "transfer matrix applied");
            char abs[PATH_MAX];
            cJSON_AddStringToObject(solver, "transfer", realpath(transfer_in, abs) ? abs : transfer_in);
        }
        cJSON_AddNumberToObject(solver, "seconds_solve", R.t_solve);
        cJSON_AddNumberToObject(solver, "seconds_total", thx_wtime() - t0);
        cJSON_AddItemToObject(j, "solver", solver);
        st = cli_outdir_finish(ctx, &od, "solution.json", j, st);
        if (st != THX_OK) goto fail;
        if (verbose >= 0) {
            if (transfer_out)
                printf("transfer matrix %zu x %zu (%s solves: %d..%d iterations), %.2f s\n", T->n_rows, T->n_frames,
                       strstr(T->label, "adjoint") ? "adjoint" : "forward", R.it_min, R.it_max, R.t_solve);
            else if (R.ranks)
                printf("%zu frames: %zu free nodes, %zu prescribed; %s + %s on %d rank%s, %d..%d iterations per frame; "
                       "assembly %.2f s%s, setup %.2f s, solves %.2f s\n",
                       epi->n_frames, R.n_free, R.n_prescribed, R.ksp, R.pc, R.ranks, R.ranks > 1 ? "s" : "", R.it_min,
                       R.it_max, R.t_assemble, R.assembly.kept ? " (kept)" : "", R.t_setup, R.t_solve);
            else
                printf("%zu frames by the transfer matrix, %.3f s\n", epi->n_frames, R.t_solve);
            if (route_txt[0]) printf("route: %s\n", route_txt);
            char subtrees_txt[160] = "";
            if (R.factor.threads)
                snprintf(subtrees_txt, sizeof subtrees_txt, ": %zu subtrees on %d thread%s %.2f s, then %zu supernodes above "
                         "them (%.0f %% of the work) %.2f s%s", R.factor.subtrees, R.factor.threads, R.factor.threads == 1 ? "" : "s",
                         R.factor.t_subtrees, R.factor.top, 100 * R.factor.top_share, R.factor.t_top,
                         R.factor.top_beside ? " on one thread beside the solves' start" : "");
            if (verbose > 0 && R.factor.used)
                printf("factor (CHOLMOD's analysis, %s): ordering %.2f s (%s), analysis %.2f s%s, factorization %.2f s "
                       "(%.3g flops, %.1f GF/s, %d BLAS thread%s%s), %.3g nonzeros, %.0f MB; solves %.3g flops, %.1f GF/s%s%s\n",
                       R.factor.numeric, R.factor.t_ordering, R.factor.ordering_cached ? "cached" : "METIS", R.factor.t_analysis,
                       R.factor.symbolic_cached ? " (cached)" : "",
                       R.factor.t_factor, R.factor.flops, R.factor.t_factor > 0 ? R.factor.flops / R.factor.t_factor * 1e-9 : 0,
                       R.factor.blas_threads, R.factor.blas_threads == 1 ? "" : "s", subtrees_txt,
                       R.factor.nonzeros, (double)R.factor.factor_bytes / 1048576, R.factor.solve_flops,
                       R.t_solve > 0 ? R.factor.solve_flops / R.t_solve * 1e-9 : 0, R.factor.cache_note[0] ? "; " : "",
                       R.factor.cache_note);
            if (verbose > 0 && R.backward_share > 0)
                printf("outer surface alone: the backward sweep on %.0f %% of its flops; each thread's frames checked by two "
                       "combinations of them solved in full beside them (residual %.1e, the frames' answers %.1e from theirs)\n",
                       100 * R.backward_share, R.max_residual, R.check);
            printf("wrote %s\n", out);
        }
    }
    goto end;
fail:
    rc = cli_fail(ctx, "forward", st);
    if (rank == 0) thx_outdir_abort(&od); /* (begun early for the parts: nothing left behind) */
end:
    cli_volume_gate_end();
    cJSON_Delete(vcheck);
    cJSON_Delete(warnings);
    free(sel);
    free(jt);
    free(jn);
    thx_series_destroy(&cur_t);
    thx_series_destroy(&cur_n);
    thx_series_destroy(&torso);
    thx_series_destroy(&at_electrodes);
    thx_series_destroy(&T);
    thx_series_destroy(&epi);
    thx_electrodes_destroy(&rowset);
    thx_forward_result_free(&R);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    cli_petsc_finish(&pa);
    return rc;
}
