/* thorax field: inside the volume of a forward solution (paper 4.3, issue 16) as data for ParaView
 * and other tools: equipotential surfaces (--isosurface) and slices (--slice, with --contours),
 * per frame, written as VTK XML PolyData (.vtp; a directory of them with a .pvd for several
 * frames) or OBJ. The library does the work (thorax/field/field.h); here the solution is read,
 * the regions and frames chosen, |J| per tetrahedron computed (thx_fem_currents) and every output
 * claimed before anything is written. Under mpirun the work goes to cli_field_parts.c (each rank
 * its part of a solution in parts), which shares the steps below (cli/cli_field.h). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "cli/cli_field.h"
#include "thorax/core/fileio.h"
#include "cli/cli_export.h"
#include "thorax/fem/fem.h"
#include "thorax/field/field.h"
#include "thorax/io/export_data.h"
#include "thorax/io/solution_file.h"
#include "thorax/parallel/parallel.h"

#define MAX_SLICES CLI_FIELD_MAX_SLICES

static int ends_with(const char *s, const char *tail)
{
    size_t a = strlen(s), b = strlen(tail);
    return a >= b && !strcmp(s + a - b, tail);
}

/* The values of SPEC for a frame whose potentials span [lo, hi]. A frame whose potentials are all
 * one value (before the beat, a silent interval) has no range for a count or percentages: no
 * values there, with a warning (the texts were checked once before the first frame). */
thx_status cli_field_values(thx_ctx *ctx, const char *spec, const char *what, double lo, double hi, double **v,
                            size_t *n)
{
    if (hi > lo) return thx_field_values_parse(ctx, spec, lo, hi, v, n);
    thx_ctx *quiet = NULL;
    if (thx_ctx_create(&quiet)) return THX_ENOMEM;
    thx_status st = thx_field_values_parse(quiet, spec, lo, hi, v, n);
    thx_ctx_destroy(&quiet);
    if (st == THX_ENOMEM) return thx_error(ctx, THX_ENOMEM, "out of memory");
    if (st) thx_log(ctx, THX_LOG_WARN, "the potentials are all %g in this frame: no %s at \"%s\"", lo, what, spec);
    return THX_OK;
}

/* The range of phi over the nodes of the tetrahedra of the regions cut (lo > hi: none). */
void cli_field_range(const thx_volume *v, const double *phi, const unsigned char *use, double *lo, double *hi)
{
    *lo = INFINITY;
    *hi = -INFINITY;
    for (size_t t = 0; t < v->n_tets; t++) {
        if (!use[v->region[t]]) continue;
        for (int k = 0; k < 4; k++) {
            double p = phi[v->tet[4 * t + k]];
            if (p < *lo) *lo = p;
            if (p > *hi) *hi = p;
        }
    }
}

/*
 * Empty results (issue 24): a slice whose plane misses the regions cut, or a value outside the
 * potentials of every frame asked for, is refused before anything is written (exit status 1, the
 * cut and the range named); a value outside some frames' range only is a warning for each such
 * frame, whose file is written (a series keeps every frame).
 */
thx_status cli_field_check_empty(thx_ctx *ctx, const char *sol, const size_t *frame, size_t nsel,
                                 const cli_field_request *rq, const double *frame_lo, const double *frame_hi,
                                 const double *span)
{
    double glo = INFINITY, ghi = -INFINITY;
    for (size_t k = 0; k < nsel; k++) {
        if (frame_lo[k] < glo) glo = frame_lo[k];
        if (frame_hi[k] > ghi) ghi = frame_hi[k];
    }
    for (size_t p = 0; p < rq->n_planes; p++) {
        double dmin = span[2 * p], dmax = span[2 * p + 1];
        if (!(dmin <= 0 && dmax >= 0))
            return thx_error(ctx, THX_EINPUT, "--slice %s misses the regions cut of %s: they lie %.6g to %.6g mm from the "
                             "plane (all on one side): no slice; nothing written", rq->plane_text[p], sol, dmin, dmax);
    }
    const char *specs[2] = {rq->iso, rq->contours}, *names[2] = {"--isosurface", "--contours"};
    for (int s = 0; s < 2; s++) {
        if (!specs[s]) continue;
        double *x = NULL;
        size_t nx = 0;
        THX_CHECK(thx_field_values_explicit(ctx, specs[s], &x, &nx));
        for (size_t i = 0; i < nx; i++) {
            size_t hit = 0;
            for (size_t k = 0; k < nsel; k++) hit += frame_lo[k] <= x[i] && x[i] <= frame_hi[k];
            if (!hit) {
                thx_status st = thx_error(ctx, THX_EINPUT, "%s %s: the value %g is outside the potentials of %s in the "
                                          "frames asked for (%g to %g over the regions cut): it cuts nothing; nothing written",
                                          names[s], specs[s], x[i], sol, glo, ghi);
                free(x);
                return st;
            }
            if (hit == nsel) continue;
            /* one warning per value, naming the first frames without it (not one line per frame) */
            char list[160] = "";
            size_t len = 0, shown = 0;
            for (size_t k = 0; k < nsel && shown < 6; k++)
                if (!(frame_lo[k] <= x[i] && x[i] <= frame_hi[k]) && len < sizeof list - 24) {
                    len += (size_t)snprintf(list + len, sizeof list - len, "%s%zu", shown ? ", " : "",
                                            shown == 5 ? (size_t)0 : frame[k] + 1);
                    if (shown == 5) snprintf(list + len - 1, sizeof list - len + 1, "...");
                    shown++;
                }
            thx_log(ctx, THX_LOG_WARN, "%s value %g is outside the potentials of %zu of the %zu frames (frame%s %s): nothing "
                    "at it there", names[s], x[i], nsel - hit, nsel, nsel - hit > 1 ? "s" : "", list);
        }
        free(x);
    }
    return THX_OK;
}

/* The frame's cut: isosurfaces (tags 0..ni-1) then slices (tags ni..), contours on the slices. The
 * values go to *iso (n_iso) and *cvals (n_c) (caller frees). */
static thx_status make_frame(thx_ctx *ctx, const thx_volume *v, const double *phi, const cli_field_request *rq,
                             thx_field_mesh *out, double **iso, size_t *n_iso, double **cvals, size_t *n_c)
{
    thx_status st = THX_OK;
    thx_field_mesh *s = NULL;
    *iso = *cvals = NULL;
    *n_iso = *n_c = 0;
    /* the range of the potentials over the nodes of the regions cut */
    double lo, hi;
    cli_field_range(v, phi, rq->use, &lo, &hi);
    if (!(lo <= hi)) return thx_error(ctx, THX_EINPUT, "no tetrahedron in the regions chosen");
    thx_field_mesh_clear(out);
    if (rq->iso) {
        THX_TRY(cli_field_values(ctx, rq->iso, "equipotential surface", lo, hi, iso, n_iso));
        THX_TRY(thx_field_isosurface(ctx, v, phi, *iso, *n_iso, rq->use, out));
    }
    if (rq->n_planes) {
        THX_TRY(thx_field_mesh_create(ctx, &s));
        THX_TRY(thx_field_slice(ctx, v, phi, rq->plane, rq->n_planes, rq->use, s));
        if (rq->contours) {
            THX_TRY(cli_field_values(ctx, rq->contours, "contour", lo, hi, cvals, n_c));
            THX_TRY(thx_field_contours(ctx, s, *cvals, *n_c));
        }
        THX_TRY(thx_field_mesh_append(ctx, out, s, (int32_t)*n_iso));
    }
done:
    thx_field_mesh_destroy(&s);
    return st;
}

typedef struct {
    cli_field_request *rq;
} parse_user;

static int add_slice(void *user, const cli_opt *opt, const char *arg)
{
    (void)opt;
    cli_field_request *rq = ((parse_user *)user)->rq;
    if (rq->n_planes == MAX_SLICES) return cli_usage_error("field", "at most %d --slice planes", MAX_SLICES);
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    thx_status st = thx_field_plane_parse(ctx, arg, &rq->plane[rq->n_planes]);
    int rc = st ? cli_usage_error("field", "--slice %s", thx_ctx_message(ctx)) : 0;
    thx_ctx_destroy(&ctx);
    if (!rc) rq->plane_text[rq->n_planes++] = arg;
    return rc;
}

static int field_main(int argc, char **argv, int mpi);

int cmd_field(int argc, char **argv)
{
    /* under mpirun: each rank cuts its part of a solution in parts (cli_field_parts.c) */
    int mpi = thx_par_launched() != 1;
    /* thorax field SOLUTION --streamlines ...: the streamlines' own options (cmd_field_streamlines.c) */
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], "--streamlines")) { /* under mpirun: traced across the parts (cli_field_parts.c) */
            if (mpi) cli_field_mute(1); /* the command line checked by every rank, its errors told by rank 0 */
            int rc = cmd_field_streamlines(argc, argv);
            if (mpi) cli_field_mute(0);
            return rc;
        }
    if (mpi) cli_field_mute(1); /* the command line checked by every rank, its errors told by rank 0 */
    int rc = field_main(argc, argv, mpi);
    if (mpi) cli_field_mute(0);
    return rc;
}

static int field_main(int argc, char **argv, int mpi)
{
    int streamlines_flag = 0;
    const char *cmd = "field";
    const char *out = NULL, *frames = "1";
    const char **regions = calloc((size_t)argc + 1, sizeof *regions);
    int n_regions = 0, verbose = 0, rc = 0;
    cli_field_request rq;
    memset(&rq, 0, sizeof rq);
    parse_user pu = {&rq};
    if (!regions) {
        fprintf(stderr, "thorax field: out of memory\n");
        return 1;
    }
    cli_opt opts[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "OUT", .s = &out,
         .help = "OUT.vtp (VTK XML PolyData) or OUT.obj for one frame; a directory for several (OUT/field_FFFF.vtp per "
                 "frame and OUT/field.pvd with the series' times)"},
        {.name = "--frame", .type = CLI_STRING, .meta = "N|LIST|all", .s = &frames,
         .help = "the frames: 1-based N, A:B[:STEP] items separated by commas, or all"},
        {.name = "--isosurface", .type = CLI_STRING, .meta = "SPEC", .s = &rq.iso,
         .help = "equipotential surfaces: values (-5,0,5; 0 is the zero equipotential), a count (count:10: evenly "
                 "inside the frame's range, ends excluded) or percentages of the range (25%,50%)"},
        {.name = "--slice", .type = CLI_STRING, .meta = "PLANE", .flags = CLI_REPEAT, .fn = add_slice, .max = MAX_SLICES,
         .help = "a plane cut exactly through the tetrahedra: x=MM, y=MM, z=MM or PX,PY,PZ:NX,NY,NZ (a point and a "
                 "normal, mm)"},
        {.name = "--contours", .type = CLI_STRING, .meta = "SPEC", .s = &rq.contours,
         .help = "contour lines on the slices at these potentials (as --isosurface's SPEC)"},
        {.name = "--region", .type = CLI_STRING, .meta = "NAME", .flags = CLI_REPEAT, .sv = regions, .count = &n_regions,
         .max = argc, .def = "the regions the solution covers (all but \"heart\" for heart-surface problems)",
         .help = "cut only this tissue region's tetrahedra"},
        {.name = "--streamlines", .type = CLI_FLAG, .i = &streamlines_flag,
         .help = "current streamlines instead of cuts: thorax field SOLUTION --streamlines [--seed ...] (seeded by |J| x "
                 "volume, density:100, without --seed; the same as "
                 "thorax streamlines; its options: thorax field --streamlines --help)"},
        {.name = "-v", .type = CLI_COUNT, .i = &verbose, .ival = 1, .flags = CLI_NOUSAGE, .help = "more logging"},
        {.name = "-q", .type = CLI_COUNT, .i = &verbose, .ival = -1, .flags = CLI_NOUSAGE, .help = "less logging"},
    };
    cli_command c = {
        .name = cmd,
        .usage = "SOLUTION [--isosurface] [--slice]... [--contours] [--frame] [--region]... -o\n"
                 "SOLUTION --streamlines [options of thorax streamlines]",
        .about = "Cuts the volume potentials of SOLUTION (a directory written by\n"
                 "`thorax forward ... --volume`) by marching tetrahedra: equipotential surfaces\n"
                 "at the --isosurface values and slices by the --slice planes, exact for the\n"
                 "piecewise-linear potentials, with the potential at every vertex, per triangle\n"
                 "the value or plane and |J| of the tetrahedron it lies in, and --contours as\n"
                 "lines on the slices. The surfaces are closed wherever they do not reach the\n"
                 "boundary of the regions cut.\n",
        .epilog = "Point data \"potential\"; cell data \"iso_value\" (NaN on slices), \"plane\"\n"
                  "(1-based, 0 on isosurfaces), \"current_magnitude\" (|sigma grad phi| of the\n"
                  "tetrahedron, A/m^2 for V), \"contour_value\" (lines), \"tetrahedron\" (0-based);\n"
                  "docs/formats.md.\n"
                  "Under mpirun -np N, on a solution whose volume is in N parts (thorax forward\n"
                  "--volume under mpirun -np N), each rank cuts its part alone and rank 0 writes\n"
                  "the one process's files, byte for byte.\n"
                  "Each file is written atomically. Exit status: 0 ok, 1 error, 2 bad usage.\n",
        .group = {{NULL, opts, sizeof opts / sizeof opts[0]}},
        .user = &pu,
    };
    int pr = cli_parse(&c, argc, argv);
    if (pr) {
        free(regions);
        return CLI_EXIT(pr);
    }
    if (c.n_pos != 1) {
        rc = c.n_pos ? cli_usage_error(cmd, "unexpected argument '%s' (one SOLUTION directory expected)", c.pos[1])
                     : cli_usage_error(cmd, "no SOLUTION directory given");
        free(regions);
        return rc;
    }
    if (!out || (!rq.iso && !rq.n_planes) || (rq.contours && !rq.n_planes)) {
        rc = cli_usage_error(cmd, !out ? "-o OUT is required"
                                  : rq.contours && !rq.n_planes ? "--contours are drawn on slices: give --slice"
                                                                : "nothing to do: give --isosurface or --slice");
        free(regions);
        return rc;
    }
    const char *specs[2] = {rq.iso, rq.contours}, *spec_opt[2] = {"--isosurface", "--contours"};
    for (int k = 0; k < 2; k++) {
        double *vals = NULL;
        size_t nv = 0;
        thx_ctx *chk = NULL;
        if (!specs[k] || thx_ctx_create(&chk)) continue;
        if (thx_field_values_parse(chk, specs[k], 0, 1, &vals, &nv)) rc = cli_usage_error(cmd, "%s %s", spec_opt[k], thx_ctx_message(chk));
        free(vals);
        thx_ctx_destroy(&chk);
        if (rc) {
            free(regions);
            return rc;
        }
    }
    const char *sol = c.pos[0];
    if (mpi) { /* each rank its part (cli_field_parts.c) */
        cli_field_mute(0);
        rc = cli_field_parts(cmd, sol, &rq, regions, n_regions, frames, out, verbose);
        free(regions);
        return rc;
    }
    thx_ctx *ctx = cli_ctx(verbose);
    thx_model *m = NULL;
    thx_series *vol = NULL;
    thx_field_mesh *mesh = NULL;
    unsigned char *use = NULL, *sel = NULL;
    size_t *frame = NULL, nsel = 0;
    cli_field_files files = {0};
    double *jt = NULL, *jm = NULL, *times = NULL;
    thx_status st = thx_solution_read_volume(ctx, sol, &m, &vol, NULL, 0);
    if (st) goto fail;
    const thx_volume *v = m->volume;
    use = thx_calloc(ctx, v->n_regions + 1, 1);
    sel = thx_calloc(ctx, vol->n_frames + 1, 1);
    frame = thx_calloc(ctx, vol->n_frames + 1, sizeof *frame);
    times = thx_calloc(ctx, vol->n_frames + 1, sizeof *times);
    if (!use || !sel || !frame || !times) {
        st = THX_ENOMEM;
        goto fail;
    }
    st = cli_field_use(ctx, sol, v, regions, n_regions, use);
    if (st) goto fail;
    rq.use = use;
    if (cli_parse_frames(frames, vol->n_frames, sel)) {
        rc = cli_usage_error(cmd, "--frame '%s': 1-based frames 1..%zu of %s, as N, A:B[:STEP] items separated by "
                             "commas, or all", frames, vol->n_frames, sol);
        goto end;
    }
    for (size_t f = 0; f < vol->n_frames; f++)
        if (sel[f]) {
            times[nsel] = vol->time[f];
            frame[nsel++] = f;
        }
    {
        double *flo = thx_calloc(ctx, 2 * (nsel + 1) + 2 * rq.n_planes, sizeof *flo);
        if (!flo) { st = THX_ENOMEM; goto fail; }
        double *fhi = flo + nsel + 1, *span = fhi + nsel + 1;
        for (size_t k = 0; k < nsel; k++) cli_field_range(v, vol->v + frame[k] * vol->n_rows, use, &flo[k], &fhi[k]);
        for (size_t p = 0; p < rq.n_planes; p++) thx_field_plane_span(v, use, &rq.plane[p], &span[2 * p], &span[2 * p + 1]);
        st = cli_field_check_empty(ctx, sol, frame, nsel, &rq, flo, fhi, span);
        free(flo);
        if (st) goto fail;
    }
    st = cli_field_files_name(ctx, out, frame, nsel, vol->n_frames, &files);
    if (st == THX_EINPUT && files.single && nsel > 1) {
        rc = cli_usage_error(cmd, "%s", thx_ctx_message(ctx));
        goto end;
    }
    if (st || (st = cli_field_files_claim(ctx, &files))) goto fail;
    jt = thx_malloc(ctx, 3 * (v->n_tets + 1) * sizeof *jt);
    jm = thx_malloc(ctx, (v->n_tets + 1) * sizeof *jm);
    if (!jt || !jm) {
        st = THX_ENOMEM;
        goto fail;
    }
    THX_TRY(thx_field_mesh_create(ctx, &mesh));
    double t0 = thx_wtime();
    size_t tris = 0;
    for (size_t k = 0; k < nsel; k++) {
        const double *phi = vol->v + frame[k] * vol->n_rows;
        double *iso = NULL, *cv = NULL;
        size_t ni = 0, nc = 0;
        st = make_frame(ctx, v, phi, &rq, mesh, &iso, &ni, &cv, &nc);
        if (!st) {
            thx_fem_currents(v, use, phi, jt, NULL);
            for (size_t t = 0; t < v->n_tets; t++)
                jm[t] = sqrt(jt[3 * t] * jt[3 * t] + jt[3 * t + 1] * jt[3 * t + 1] + jt[3 * t + 2] * jt[3 * t + 2]);
            st = cli_field_write(ctx, sol, &files, k, frame[k], mesh, iso, ni, rq.n_planes, cv, jm, times[k], &tris);
        }
        free(iso);
        free(cv);
        if (st) goto fail;
    }
    if ((st = cli_field_pvd(ctx, &files, times, nsel))) goto fail;
    thx_log(ctx, THX_LOG_INFO, "%zu frames, %zu triangles, %.2f s", nsel, tris, thx_wtime() - t0);
    goto end;
done:
fail:
    rc = cli_fail(ctx, cmd, st);
end:
    cli_field_files_free(&files);
    free(use);
    free(sel);
    free(frame);
    free(times);
    free(jt);
    free(jm);
    free(regions);
    thx_field_mesh_destroy(&mesh);
    thx_series_destroy(&vol);
    thx_model_destroy(&m);
    thx_ctx_destroy(&ctx);
    return rc;
}

thx_status cli_field_use(thx_ctx *ctx, const char *sol, const thx_volume *v, const char *const *regions, int n_regions,
                         unsigned char *use)
{
    if (n_regions == 0) /* the regions the solution holds potentials in (the same rule as thorax render's) */
        return thx_solution_domain(ctx, sol, v, use);
    for (int k = 0; k < n_regions; k++) {
        size_t r = 0;
        while (r < v->n_regions && strcmp(v->regions[r].name, regions[k]) != 0) r++;
        if (r == v->n_regions) {
            char list[1024] = "";
            size_t o = 0;
            for (size_t q = 0; q < v->n_regions && o < sizeof list; q++)
                o += (size_t)snprintf(list + o, sizeof list - o, " %s", v->regions[q].name);
            return thx_error(ctx, THX_EINPUT, "%s: the model's volume has no region \"%s\"; it has:%s", sol, regions[k], list);
        }
        use[r] = 1;
    }
    return THX_OK;
}

thx_status cli_field_files_name(thx_ctx *ctx, const char *out, const size_t *frame, size_t nsel, size_t n_frames,
                                cli_field_files *f)
{
    memset(f, 0, sizeof *f);
    f->out = out;
    f->single = ends_with(out, ".vtp") || ends_with(out, ".obj");
    f->obj = ends_with(out, ".obj");
    if (f->single && nsel > 1)
        return thx_error(ctx, THX_EINPUT, "%zu frames go to a directory (-o DIR), not to the one file %s", nsel, out);
    int width = 4;
    for (size_t x = n_frames; x >= 10000; x /= 10) width++;
    f->n_names = f->single ? 1 : nsel + 1;
    f->names = thx_calloc(ctx, f->n_names, sizeof *f->names);
    if (!f->names) return THX_ENOMEM;
    for (size_t k = 0; k < f->n_names; k++) {
        char nm[4400];
        if (f->single) snprintf(nm, sizeof nm, "%s", out);
        else if (k == nsel) snprintf(nm, sizeof nm, "field.pvd");
        else snprintf(nm, sizeof nm, "field_%0*zu.vtp", width, frame[k] + 1);
        if (!(f->names[k] = strdup(nm))) return thx_error(ctx, THX_ENOMEM, "out of memory");
    }
    return THX_OK;
}

/* The path of file k (OUT itself, or OUT/NAME); THX_EINPUT when too long. */
static thx_status file_path(thx_ctx *ctx, const cli_field_files *f, size_t k, char *path, size_t size)
{
    if (f->single) snprintf(path, size, "%s", f->out);
    else if ((size_t)snprintf(path, size, "%s/%s", f->out, f->names[k]) >= size)
        return thx_error(ctx, THX_EINPUT, "%s: path too long", f->out);
    return THX_OK;
}

thx_status cli_field_files_claim(thx_ctx *ctx, const cli_field_files *f)
{
    char path[4400];
    size_t nsel = f->single ? 1 : f->n_names - 1;
    for (size_t k = 0; k < f->n_names; k++) {
        THX_CHECK(file_path(ctx, f, k, path, sizeof path));
        THX_CHECK(!f->single && k == nsel ? thx_export_pvd_claim(ctx, path) : thx_field_claim(ctx, path));
    }
    if (!f->single && thx_make_dirs(f->out) != 0)
        return thx_error(ctx, THX_EIO, "%s: cannot create directory: %s", f->out, strerror(errno));
    return THX_OK;
}

void cli_field_files_free(cli_field_files *f)
{
    for (size_t i = 0; f->names && i < f->n_names; i++) free(f->names[i]);
    free(f->names);
    f->names = NULL;
    f->n_names = 0;
}

thx_status cli_field_write(thx_ctx *ctx, const char *sol, const cli_field_files *f, size_t k, size_t frame_no,
                           const thx_field_mesh *mesh, const double *iso, size_t ni, size_t n_planes, const double *cv,
                           const double *jm, double time, size_t *tris)
{
    char path[4400];
    THX_CHECK(file_path(ctx, f, f->single ? 0 : k, path, sizeof path));
    size_t nt = ni + n_planes;
    double *tagv = thx_malloc(ctx, 2 * (nt + 1) * sizeof *tagv);
    char (*gname)[32] = f->obj ? thx_calloc(ctx, nt + 1, sizeof *gname) : NULL;
    const char **gp = f->obj ? thx_calloc(ctx, nt + 1, sizeof *gp) : NULL;
    thx_status st = !tagv || (f->obj && (!gname || !gp)) ? THX_ENOMEM : THX_OK;
    /* per tag: iso_value (NaN on a slice) and plane (1-based, 0 on an isosurface) */
    double *isov = tagv, *plv = tagv ? tagv + nt + 1 : NULL;
    for (size_t i = 0; !st && i < nt; i++) {
        isov[i] = i < ni ? iso[i] : NAN;
        plv[i] = i < ni ? 0 : (double)(i - ni + 1);
    }
    for (size_t i = 0; !st && f->obj && i < nt; i++) {
        if (i < ni) snprintf(gname[i], sizeof gname[i], "iso_%zu", i + 1);
        else snprintf(gname[i], sizeof gname[i], "plane_%zu", i - ni + 1);
        gp[i] = gname[i];
    }
    if (!st && f->single && mesh->n_tris == 0 && mesh->n_segs == 0)
        st = thx_error(ctx, THX_EINPUT, "%s: frame %zu: the cuts asked for are empty (no triangle, no contour line): "
                       "nothing written", sol, frame_no + 1);
    thx_field_write_opts o = {.tag_name = {"iso_value", "plane"}, .tag_value = {isov, plv}, .cell_scalar = jm,
                              .cell_scalar_name = "current_magnitude", .seg_value = cv, .has_time = 1, .time = time};
    if (!st) st = f->obj ? thx_field_mesh_write_obj(ctx, mesh, gp, nt, path) : thx_field_mesh_write_vtp(ctx, mesh, &o, path);
    if (!st) {
        thx_log(ctx, THX_LOG_INFO, "frame %zu: %zu triangles (%zu points, %zu contour segments), area %.6g mm^2 -> %s",
                frame_no + 1, mesh->n_tris, mesh->n_points, mesh->n_segs, thx_field_mesh_area(mesh, -1), path);
        *tris += mesh->n_tris;
    }
    free(tagv);
    free(gname);
    free(gp);
    return st;
}

thx_status cli_field_pvd(thx_ctx *ctx, const cli_field_files *f, const double *times, size_t nsel)
{
    if (f->single) return THX_OK;
    char path[4400];
    THX_CHECK(file_path(ctx, f, nsel, path, sizeof path));
    return thx_export_pvd(ctx, path, (const char *const *)f->names, times, nsel);
}
