/* thorax field SOLUTION --streamlines (registered as `thorax streamlines` until `thorax field` takes
 * it): current streamlines of one frame of a forward solution's volume potentials
 * (thorax/field/streamline.h), written as VTP or OBJ lines or tubes. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "cli/cli_field.h"
#include "thorax/parallel/parallel.h"
#include "thorax/core/fileio.h"
#include "thorax/fem/fem.h"
#include "thorax/field/streamline.h"
#include "thorax/io/solution_file.h"
#include "thorax/model/model.h"
#include "thorax/model/series.h"

/* Streamline seeds cost memory before a line is traced: a seed's position and tetrahedron, its line
 * record and its first points, at least THX_SEED_BYTES each (measured: density:100000000 took
 * 10.8 GB, 108 bytes a seed for the draw alone). The seed specs' counts added up are bounded by
 * cli_count_limit before anything is read (issue 24: density:1e8 had no bound). 0 when they fit,
 * else the exit code after a message naming the limit; a malformed spec is left to its parser. */
#define THX_SEED_BYTES 256.0
int cli_check_seed_counts(const char *cmd, const char *const *specs, int n)
{
    double total = 0;
    thx_ctx *quiet = NULL;
    if (thx_ctx_create(&quiet) != THX_OK) return 0; /* the parse below will say it */
    for (int i = 0; i < n; i++) {
        thx_seed_spec sp;
        if (thx_seed_spec_parse(quiet, specs[i], &sp) == THX_OK) total += (double)sp.n;
    }
    thx_ctx_destroy(&quiet);
    return cli_check_count(cmd, "--seed/--streamlines: streamline seeds", total, THX_SEED_BYTES);
}

int cmd_field_streamlines(int argc, char **argv)
{
    const char *cmd = argv[0];
    const char *out = NULL;
    const char **seeds = calloc((size_t)argc + 1, sizeof *seeds);
    int n_seeds = 0, verbose = 0, streamlines = 0, frame = 1, sides = 8, caps = 0, loops = 1, integ = THX_STREAM_RK2,
        dir = THX_STREAM_BOTH;
    long rng = 1, max_steps = 100000;
    double tubes = 0;
    thx_stream_opts so;
    thx_stream_opts_default(&so);
    if (!seeds) {
        fprintf(stderr, "thorax %s: out of memory\n", cmd);
        return 1;
    }
    static const cli_choice integrators[] = {{"rk2", THX_STREAM_RK2}, {"rk4", THX_STREAM_RK4}, {"rk45", THX_STREAM_RK45}, {NULL, 0}};
    static const cli_choice directions[] = {{"forward", THX_STREAM_FORWARD}, {"backward", THX_STREAM_BACKWARD},
                                            {"both", THX_STREAM_BOTH}, {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--streamlines", .type = CLI_FLAG, .i = &streamlines,
         .help = "current streamlines (what this command draws; the word `thorax field` will choose it by)"},
        {.name = "--frame", .type = CLI_INT, .meta = "N", .i = &frame, .rule = CLI_GE, .lo = 1,
         .help = "the frame of the volume potentials (1-based)"},
        {.name = "--seed", .type = CLI_STRING, .meta = "SPEC", .flags = CLI_REPEAT, .sv = seeds, .count = &n_seeds,
         .max = argc, .def = "density:100",
         .help = "where lines start (repeatable): point:X,Y,Z; line:X,Y,Z:X,Y,Z:N (N evenly from one point to "
                 "the other); sphere:X,Y,Z:R:N (N spread evenly on the sphere, a Fibonacci lattice); region:NAME:N (N "
                 "uniformly in the region's volume; a region without current, the heart of an epicardial solution, on "
                 "its surface); density:N (drawn with probability proportional to |J| x volume); mm"},
        {.name = "--integrator", .type = CLI_CHOICE, .choices = integrators, .i = &integ,
         .help = "rk2: second-order Runge-Kutta (midpoint, the paper's); rk4: classical fourth-order; rk45: "
                 "Dormand-Prince 5(4) with error control (--tolerance)"},
        {.name = "--direction", .type = CLI_CHOICE, .choices = directions, .i = &dir,
         .help = "along J, against it, or both (two lines per seed; one when the forward line closes a loop)"},
        {.name = "--step", .type = CLI_REAL, .meta = "FRACTION", .d = &so.step, .rule = CLI_GT | CLI_LE, .lo = 0, .hi = 10,
         .help = "the step (rk45: the first) as a fraction of the local tetrahedron's mean edge length"},
        {.name = "--step-mm", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &so.step_mm, .rule = CLI_GE | CLI_FINITE,
         .lo = 0, .note = "0: --step", .help = "the step (rk45: the first) in mm instead of --step's fraction"},
        {.name = "--tolerance", .type = CLI_REAL, .meta = "FRACTION", .d = &so.tolerance, .rule = CLI_GT, .lo = 0,
         .help = "rk45: the largest error per step, as a fraction of the local mean edge length"},
        {.name = "--max-length", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &so.max_length, .rule = CLI_GE | CLI_FINITE,
         .lo = 0, .note = "0: 4 x the mesh's bounding-box diagonal", .help = "the longest line (each direction)"},
        {.name = "--max-steps", .type = CLI_INT, .meta = "N", .l = &max_steps, .rule = CLI_GE, .lo = 1,
         .help = "the most steps per line (each direction)"},
        {.name = "--min-current", .type = CLI_REAL, .meta = "FRACTION", .d = &so.min_current, .rule = CLI_GE | CLI_LT, .lo = 0,
         .hi = 1, .help = "a line stops where |J| falls below this fraction of the largest |J| at the nodes"},
        {.name = "--no-loops", .type = CLI_SET, .i = &loops, .ival = 0,
         .help = "do not stop a line that comes back to its seed (a closed current loop)"},
        {.name = "--loop-tol", .type = CLI_REAL, .meta = "FRACTION", .d = &so.loop_tol, .rule = CLI_GT, .lo = 0,
         .help = "a loop closes when the line passes this close to its seed, as a fraction of the seed tetrahedron's "
                 "mean edge length"},
        {.name = "--rng-seed", .type = CLI_INT, .meta = "N", .l = &rng, .rule = CLI_GE, .lo = 0,
         .help = "the random stream of region and density seeds (the same N, the same seeds)"},
        {.name = "--tubes", .type = CLI_REAL, .meta = "RADIUS", .unit = "mm", .d = &tubes, .rule = CLI_GE | CLI_FINITE,
         .lo = 0, .note = "0: lines", .help = "write tubes of this radius around the lines (a triangle mesh) instead of the lines"},
        {.name = "--sides", .type = CLI_INT, .meta = "N", .i = &sides, .rule = CLI_GE | CLI_LE, .lo = 3, .hi = 64,
         .help = "the sides of each tube"},
        {.name = "--caps", .type = CLI_FLAG, .i = &caps, .help = "close the tubes' ends"},
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "OUT", .s = &out,
         .help = "the file (required): OUT.vtp (VTK XML PolyData) or OUT.obj (Wavefront)"},
        {.name = "-v", .type = CLI_COUNT, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_COUNT, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE, .help = "less logging"},
    };
    cli_command c = {
        .name = cmd,
        .usage = "SOLUTION --streamlines --frame [--seed]... [--integrator] [--direction] [--max-length] [--min-current] "
                 "[--tubes] -o\n"
                 "SOLUTION --streamlines [--seed]... [--step] [--step-mm] [--tolerance] [--max-steps] [--no-loops] [--loop-tol] "
                 "[--rng-seed] [--tubes] [--sides] [--caps] -o",
        .about = "Current streamlines of one frame of a forward solution (thorax forward ...\n"
                 "--volume): J = -sigma grad phi per tetrahedron, averaged to the nodes and\n"
                 "interpolated linearly inside each tetrahedron, integrated in arc length from\n"
                 "each seed (paper 4.3), the containing tetrahedron found by walking from the\n"
                 "last one. A line stops where it leaves the domain (the torso's surface, or the\n"
                 "heart's, which an epicardial solution leaves out), where |J| is low, at the\n"
                 "length or step limit, or when it closes a loop back to its seed. Without\n"
                 "--seed, 100 seeds are drawn with probability |J| x volume (density:100).\n",
        .epilog = "Point data current_magnitude (|J|, mA/m^2 for potentials in mV), potential; cell\n"
                  "data stop_reason (0 boundary, 1 low_current, 2 max_length, 3 max_steps, 4 loop),\n"
                  "direction (+1, -1), seed, line, length (docs/formats.md, \"Streamlines\").\n"
                  "The file is written atomically. Exit status: 0 ok, 1 error, 2 bad usage.\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
    };
    int rc = cli_parse(&c, argc, argv);
    if (rc) {
        free(seeds);
        return CLI_EXIT(rc);
    }
    thx_ctx *ctx = NULL;
    thx_model *m = NULL;
    thx_series *vol = NULL;
    thx_stream_field *f = NULL;
    thx_streamlines *sl = NULL;
    thx_stream_tubes *T = NULL;
    double *sx = NULL, *jn = NULL;
    long *st_tet = NULL;
    unsigned char *use = NULL;
    size_t ns = 0;
    thx_status st = THX_OK;
    if (c.n_pos != 1) {
        rc = cli_usage_error(cmd, c.n_pos ? "one SOLUTION directory expected, not '%s' too" : "no SOLUTION directory given%s",
                             c.n_pos ? c.pos[1] : "");
        goto out;
    }
    if (!streamlines) {
        rc = cli_usage_error(cmd, "say what to draw: --streamlines");
        goto out;
    }
    if (!n_seeds) /* seeded by |J| x volume, as ParaView's and SCIRun's default seeding does (issue 24) */
        seeds[n_seeds++] = "density:100";
    if ((rc = cli_check_seed_counts(cmd, seeds, n_seeds))) goto out;
    if (!out) {
        rc = cli_usage_error(cmd, "no output file given (-o OUT.vtp or OUT.obj)");
        goto out;
    }
    {
        const char *dot = strrchr(out, '.');
        if (!dot || (strcmp(dot, ".vtp") && strcmp(dot, ".obj"))) {
            rc = cli_usage_error(cmd, "-o %s: the output is a .vtp or an .obj file", out);
            goto out;
        }
    }
    ctx = cli_ctx(verbose);
    thx_seed_spec *specs = calloc((size_t)n_seeds, sizeof *specs);
    if (!specs) {
        rc = cli_fail(ctx, cmd, THX_ENOMEM);
        goto out;
    }
    for (int i = 0; i < n_seeds && !st; i++) {
        st = thx_seed_spec_parse(ctx, seeds[i], &specs[i]);
        specs[i].rng_seed = (uint64_t)rng + (uint64_t)i;
    }
    if (st) {
        free(specs);
        rc = cli_fail(ctx, cmd, st);
        goto out;
    }
    if (thx_par_launched() != 1) { /* under mpirun: a solution in parts, the lines traced across them */
        so.integrator = integ;
        so.direction = dir;
        so.max_steps = (size_t)max_steps;
        so.loops = loops;
        thx_ctx_destroy(&ctx);
        rc = cli_field_streamlines_parts(cmd, c.pos[0], specs, n_seeds, &so, frame, tubes, sides, caps, out, verbose);
        free(specs);
        goto out;
    }
    double t0 = thx_wtime();
    const char *sol = c.pos[0];
    THX_TRY(thx_solution_read_volume(ctx, sol, &m, &vol, NULL, 0));
    if ((size_t)frame > vol->n_frames) {
        st = thx_error(ctx, THX_EINPUT, "%s: --frame %d: the volume potentials have %zu frames", sol, frame, vol->n_frames);
        goto done;
    }
    const thx_volume *v = m->volume;
    use = calloc(v->n_regions + 1, 1);
    jn = malloc((3 * v->n_nodes + 1) * sizeof *jn);
    if (!use || !jn) {
        st = thx_error(ctx, THX_ENOMEM, "out of memory");
        goto done;
    }
    THX_TRY(thx_solution_domain(ctx, sol, v, use)); /* the regions the solution covers */
    const double *phi = vol->v + (size_t)(frame - 1) * vol->n_rows;
    thx_fem_currents(v, use, phi, NULL, jn);
    double tf = thx_wtime();
    THX_TRY(thx_stream_field_create(ctx, v, jn, phi, use, &f));
    tf = thx_wtime() - tf;
    for (int i = 0; i < n_seeds; i++) THX_TRY(thx_stream_seeds(ctx, f, &specs[i], &sx, &st_tet, &ns));
    so.integrator = integ;
    so.direction = dir;
    so.max_steps = (size_t)max_steps;
    so.loops = loops;
    double t1 = thx_wtime();
    THX_TRY(thx_streamlines_trace(ctx, f, sx, st_tet, ns, &so, &sl));
    double t2 = thx_wtime();
    if (tubes > 0) THX_TRY(thx_stream_tubes_make(ctx, sl, tubes, sides, caps, &T));
    THX_TRY(thx_streamlines_write(ctx, sl, T, out));
    size_t count[THX_STOP_COUNT] = {0};
    for (size_t l = 0; l < sl->n_lines; l++) count[sl->stop[l]]++;
    thx_log(ctx, THX_LOG_INFO,
            "wrote %s: %zu lines from %zu seeds, %zu points (%s); stops: %zu boundary, %zu low_current, %zu max_length, "
            "%zu max_steps, %zu loop; frame %d, max |J| %.4g; field %.3f s, tracing %.3f s (%zu steps, %zu evaluations), all %.2f s",
            out, sl->n_lines, ns, sl->n_points, T ? "as tubes" : "lines", count[0], count[1], count[2], count[3], count[4],
            frame, thx_stream_field_max(f), tf, t2 - t1, sl->n_steps, sl->n_evals, thx_wtime() - t0);
done:
    free(specs);
    if (st) rc = cli_fail(ctx, cmd, st);
out:
    thx_stream_tubes_destroy(&T);
    thx_streamlines_destroy(&sl);
    thx_stream_field_destroy(&f);
    thx_series_destroy(&vol);
    thx_model_destroy(&m);
    free(sx), free(st_tet), free(jn), free(use), free(seeds);
    thx_ctx_destroy(&ctx);
    return rc;
}
