/* thorax animate: one picture per frame (as thorax render draws them, cli/render_cli.h) and an MP4
 * movie through ffmpeg; resumable. */
#include <errno.h>
#include <limits.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

#include "cli/cli.h"
#include "cli/cli_fem.h"
#include "cli/render_cli.h"
#include "cli/cli_share.h"
#include "cli/cli_raytrace.h"
#include "thorax/core/fileio.h"
#include "thorax/picture/movie.h"
#include "thorax/render/camera_path.h"
/* ---- what the frames of an animation were drawn with ---- */

/* Appends "path:size:mtime" of a file (or "path:-" if it cannot be read). */
static void sig_file(char *sig, size_t cap, const char *path)
{
    struct stat sb;
    size_t len = strlen(sig);
    if (stat(path, &sb) == 0)
        snprintf(sig + len, cap - len, " %s:%lld:%lld.%09ld", path, (long long)sb.st_size, (long long)sb.st_mtim.tv_sec,
                 sb.st_mtim.tv_nsec);
    else
        snprintf(sig + len, cap - len, " %s:-", path);
}

/* The settings that decide a frame's pixels: every option but the frame range, the rate, the movie
 * and the verbosity (so --motion-blur too: another shutter redraws); the data files and the program (size and time of each), so a changed solution
 * or a rebuilt thorax redraws. */
static void animation_signature(int argc, char **argv, const ropts *o, const char *keys, char *sig, size_t cap)
{
    snprintf(sig, cap, "thorax-animation 1;");
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--frames") || !strcmp(a, "--fps") || !strcmp(a, "--mp4") || !strcmp(a, "-o") || !strcmp(a, "--output")) {
            i++;
            continue;
        }
        if (!strcmp(a, "-q") || !strcmp(a, "-v")) continue;
        size_t len = strlen(sig);
        snprintf(sig + len, cap - len, " %s", a);
    }
    char path[PATH_MAX + 64];
    if (o->p.solution) {
        snprintf(path, sizeof path, "%s/solution.json", o->p.solution);
        sig_file(sig, cap, path);
    }
    for (int k = 0; k < o->p.n_data; k++) sig_file(sig, cap, o->p.data[k]);
    if (o->p.channels) sig_file(sig, cap, o->p.channels);
    for (int k = 1; k < o->p.n_data; k++)
        if (o->p.data_channels[k]) sig_file(sig, cap, o->p.data_channels[k]);
    for (int k = 0; k < o->p.n_files; k++) sig_file(sig, cap, o->p.files[k]);
    if (o->p.model_dir) {
        snprintf(path, sizeof path, "%s/model.json", o->p.model_dir);
        sig_file(sig, cap, path);
    }
    if (keys) { /* the key file by its content too (a file copied over another keeping its time) */
        sig_file(sig, cap, keys);
        char *text = NULL;
        size_t n = 0, len = strlen(sig);
        unsigned long long h = 1469598103934665603ull; /* FNV-1a, 64 bits */
        thx_ctx *quiet = NULL;
        thx_ctx_create(&quiet);
        if (thx_read_file(quiet, keys, &text, &n) == THX_OK)
            for (size_t i = 0; i < n; i++) h = (h ^ (unsigned char)text[i]) * 1099511628211ull;
        free(text);
        thx_ctx_destroy(&quiet);
        snprintf(sig + len, cap - len, " keys:%016llx", h);
    }
    sig_file(sig, cap, "/proc/self/exe");
}

int cmd_animate(int argc, char **argv)
{
    ropts o;
    render_opts_default(&o);
    o.cmd = "animate";
    const char *mp4 = NULL, *frames = NULL, *keys_path = NULL;
    int a_first = 1, a_last = -1;
    cli_opt own[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "DIR", .s = &o.out,
         .help = "the frames' directory, DIR/frame_00001.png ..."},
        {.name = "--frames", .type = CLI_STRING, .meta = "A:B", .s = &frames, .def = "all",
         .help = "frame range, 1-based, inclusive"},
        {.name = "--fps", .type = CLI_INT, .meta = "N", .i = &o.fps, .rule = CLI_GE | CLI_LE, .lo = 1, .hi = 240,
         .bad = "--fps: 1..240", .help = "frames per second of the movie, 1 to 240"},
        {.name = "--keys", .type = CLI_INPUT, .meta = "FILE", .s = &keys_path,
         .help = "a camera flight: camera keys at movie frames (docs/formats.md, \"Camera key files\"), the camera "
                 "between them on a C2 path; the movie runs to the last key's frame, each frame showing the data frame "
                 "the keys give (else its own number)"},
        {.name = "--mp4", .type = CLI_OUTPUT, .meta = "FILE|none", .s = &mp4, .def = "DIR/animation.mp4",
         .note = "none: no movie", .help = "the movie"},
    };
    cli_opt common[N_RENDER_OPTS], rt[N_RAYTRACE_OPTS];
    cli_command cmd = {
        .name = "animate",
        .usage = "MODEL|--solution -o [--frames] [--fps] [--mp4] [options]",
        .about = "One image per frame (DIR/frame_00001.png ...), unattended and resumable (frames\n"
                 "whose PNG exists are kept if drawn with the same options, data and program:\n"
                 "DIR/frames.settings), a progress bar on a terminal, then an MP4 (H.264) through\n"
                 "ffmpeg. Under mpirun -np N the frames are dealt to the ranks (frame k to rank\n"
                 "k mod N) and rank 0 makes the movie: the same frames and movie as one process.\n"
                 "A --solution whose volume is in N parts (forward --volume on N ranks) is drawn\n"
                 "sort-last instead: every frame by all ranks, each its part (thorax render).\n",
        .group = {{NULL, own, sizeof own / sizeof own[0]}, {"what is drawn, and how", common, render_options(common, &o)},
                  {"ray tracing (--renderer trace)", rt, raytrace_options(rt, &o)}},
        .positional = render_positional,
        .user = &o,
    };
    int pr = cli_parse(&cmd, argc, argv);
    if (pr) return CLI_EXIT(pr);
    if (o.p.volume_render && o.p.renderer != 1) return cli_usage_error("animate", "--volume: volume rendering is the ray tracer's (--renderer trace)");
    if (o.p.rt.shutter > 0 && o.p.renderer != 1)
        return cli_usage_error("animate", "--motion-blur: motion blur is the ray tracer's (--renderer trace)");
    if (frames) {
        long fa, fb;
        if (cli_parse_pair(frames, ':', 1, INT_MAX, &fa, &fb))
            return cli_usage_error("animate", "--frames '%s': A:B (1-based, A <= B <= %d)", frames, INT_MAX);
        a_first = (int)fa;
        a_last = (int)fb;
    }
    if (!o.p.model_dir && !o.p.n_files && !o.p.solution) return cli_usage_error("animate", "no model, surface file or --solution given");
    if (!o.out) return cli_usage_error("animate", "no output directory given (-o DIR)");
    if (keys_path && o.p.have_camera) return cli_usage_error("animate", "--keys and --camera: the key file gives the camera");
    o.last = 0; /* frames checked below */
    /* under mpirun: the frames dealt among the ranks (frame k of the range to rank k mod N), each
       rank writing its own; rank 0 keeps the settings and makes the movie */
    int prc = cli_share_start("animate", &o.verbose);
    if (prc) return prc;
    int rank = thx_par_rank(), ranks = thx_par_size();
    thx_ctx *ctx = cli_ctx(o.verbose);
    thx_camera_keys keys = {0};
    thx_camera_path *flight = NULL;
    thx_picture_data d;
    thx_renderer *rr = NULL;
    thx_font *font = NULL;
    thx_raster *img = NULL;
    int rc = 0;
    size_t nan = 0;
    double t0 = thx_wtime();
    char path[PATH_MAX + 64], movie[PATH_MAX + 64];
    const char *out_dir = o.out;
    memset(&d, 0, sizeof d);
    thx_status st = THX_OK;
    int named_views = 0;
    if (keys_path) { /* the key file read first: its errors before any data is loaded */
        st = thx_camera_keys_read(ctx, keys_path, &keys);
        for (size_t j = 0; st == THX_OK && j < keys.n; j++) named_views |= keys.keys[j].view >= 0;
        /* keys with coordinates only need no anatomical frame of the model (as --camera) */
        if (st == THX_OK && !named_views) o.p.have_camera = 1;
    }
    if (st == THX_OK) st = render_setup(ctx, &o, &d, &rr, &font, &img);
    st = thx_picture_parts_settle(ctx, &o.p, &d, st); /* sort-last: the parts made one (collective) */
    /* a solution in parts for these ranks: every frame drawn by all of them together (sort-last), else
       the frames dealt round the ranks, each drawn whole (sort-first) */
    int joint = st == THX_OK && d.part_size > 1;
    size_t nf = 0;
    if (st == THX_OK) {
        for (size_t s = 0; s < d.m->n_surfaces && s < 64; s++)
            if (d.series[s] && d.series[s]->n_frames > nf) nf = d.series[s]->n_frames;
        if (!nf && !keys_path) st = thx_error(ctx, THX_EINPUT, "animate: no time series to animate (give --solution or --data)");
    }
    if (st == THX_OK && keys_path) {
        thx_camera views[6];
        for (int v = 0; v < 6; v++) thx_picture_view_camera(&o.p, &d, v, (double)o.p.w / o.p.h, &views[v]);
        st = thx_camera_keys_resolve(ctx, &keys, views);
        if (st == THX_OK) st = thx_camera_path_create(ctx, &keys, &flight);
    }
    if (st == THX_OK) {
        int n_movie = flight ? thx_camera_path_last(flight) : (int)nf;
        if (a_last < 0) a_last = n_movie;
        if (a_last > n_movie)
            st = flight ? thx_error(ctx, THX_EINPUT, "--frames %d:%d: the flight %s ends at frame %d", a_first, a_last, keys_path, n_movie)
                        : thx_error(ctx, THX_EINPUT, "--frames %d:%d: the data has %zu frames", a_first, a_last, nf);
        if (flight && !nf && thx_camera_path_data_frame(flight, 1) && o.verbose >= 0)
            thx_log(ctx, THX_LOG_WARN, "%s: no data is drawn: the keys' data frames are not used", keys_path);
        /* every movie frame's data frame, checked before anything is drawn */
        for (int f = a_first; st == THX_OK && f <= a_last; f++) {
            int df = !nf ? 0 : flight && thx_camera_path_data_frame(flight, f) ? thx_camera_path_data_frame(flight, f) : f;
            if ((size_t)df > nf)
                st = nf && flight && !thx_camera_path_data_frame(flight, f)
                         ? thx_error(ctx, THX_EINPUT, "%s: the flight runs to frame %d, the data has %zu frames: give the data "
                                     "frame of some keys (data N)", keys_path, a_last, nf)
                         : thx_error(ctx, THX_EINPUT, "%s: movie frame %d shows data frame %d: the data has %zu frames",
                                     keys_path, f, df, nf);
            /* arrows on every frame: refused before anything is drawn when some frame has no currents */
            else if (o.p.arrows && (!df || thx_picture_currents_column(&d, df - 1) < 0))
                st = thx_error(ctx, THX_EINPUT, "--arrows: the solution has no currents for frame %d of --frames %d:%d "
                               "(thorax forward --currents %d-%d)", df, a_first, a_last, a_first, a_last);
        }
    }
    st = thx_par_agree(ctx, st, NULL); /* every rank read the same data and found the same frames */
    /* the movie is claimed before any frame is drawn: a user's file of that name stops the run */
    int want_movie = !(mp4 && !strcmp(mp4, "none"));
    thx_atomic_file maf;
    if (want_movie) {
        if (mp4) snprintf(movie, sizeof movie, "%s", mp4);
        else snprintf(movie, sizeof movie, "%s/animation.mp4", out_dir);
    }
    if (st == THX_OK && want_movie && rank == 0)
        st = thx_movie_claim(ctx, movie, &maf);
    if (st == THX_OK && rank == 0 && mkdir(out_dir, 0777) != 0 && errno != EEXIST)
        st = thx_error(ctx, THX_EIO, "%s: cannot create the directory", out_dir);
    /* frames are kept only if drawn with the same settings (DIR/frames.settings), else redrawn:
       rank 0 decides and tells the others */
    int may_keep = 0;
    if (st == THX_OK && rank == 0) {
        char sig[8192], sigpath[PATH_MAX + 64];
        animation_signature(argc, argv, &o, keys_path, sig, sizeof sig);
        snprintf(sigpath, sizeof sigpath, "%s/frames.settings", out_dir);
        char *old = NULL;
        size_t olen = 0;
        thx_ctx *quiet = NULL;
        thx_ctx_create(&quiet);
        if (thx_read_file(quiet, sigpath, &old, &olen) == THX_OK) {
            may_keep = olen == strlen(sig) + 1 && !strncmp(old, sig, strlen(sig));
            if (!may_keep && o.verbose >= 0)
                fprintf(stderr, "thorax animate: %s was drawn with other settings, data or program: redrawing every frame\n", out_dir);
        }
        free(old);
        thx_ctx_destroy(&quiet);
        if (!may_keep) {
            thx_atomic_file af;
            st = thx_atomic_open(ctx, sigpath, &af);
            if (st == THX_OK) {
                fprintf(af.f, "%s\n", sig);
                st = thx_atomic_commit(ctx, &af);
            }
        }
    }
    st = thx_par_agree(ctx, st, NULL);
    if (st == THX_OK) st = thx_par_bcast(ctx, &may_keep, sizeof may_keep, 0);
    int done = 0, kept = 0, total = a_last - a_first + 1, mine = joint ? total : total / ranks + (rank < total % ranks);
    for (int f = a_first + (joint ? 0 : rank); st == THX_OK && f <= a_last; f += joint ? 1 : ranks) {
        snprintf(path, sizeof path, "%s/frame_%05d.png", out_dir, f);
        thx_raster *old = NULL;
        thx_ctx *quiet = NULL;
        thx_ctx_create(&quiet);
        int keep = (!joint || rank == 0) && may_keep && access(path, R_OK) == 0 &&
                   thx_raster_read_png(quiet, path, &old) == THX_OK && old->w == o.p.w && old->h == o.p.h;
        if (joint) st = thx_par_bcast(ctx, &keep, sizeof keep, 0); /* rank 0's files: its word */
        if (st == THX_OK && keep) {
            kept += !joint || rank == 0; /* resumable: a complete PNG of the right size is kept */
        } else if (st == THX_OK) {
            int df = f;
            if (flight) { /* the flight's camera, and its data frame (else the movie frame's own, or none) */
                o.p.have_camera = 1;
                thx_camera_path_camera(flight, f, &o.p.cam);
                df = !nf ? 1 : thx_camera_path_data_frame(flight, f) ? thx_camera_path_data_frame(flight, f) : f;
                /* motion blur: towards the next movie frame's camera and data frame (past the flight's
                   end, its last camera; past the data's, its last frame) */
                o.p.have_next_cam = 1;
                thx_camera_path_camera(flight, f + 1, &o.p.next_cam);
                int dn = thx_camera_path_data_frame(flight, f + 1);
                o.p.next_frame = !nf ? 0 : dn ? dn - 1 : f;
            }
            if (joint) { /* every rank its part; rank 0 composites, annotates and writes */
                st = cli_share_picture(ctx, &o.p, &d, rr, font, df - 1, img, &nan);
                if (st == THX_OK && rank == 0) st = thx_raster_write_png(ctx, img, path);
                st = thx_par_agree(ctx, st, NULL);
            } else {
                st = thx_picture_draw(ctx, &o.p, &d, rr, font, df - 1, img, &nan);
                if (st == THX_OK) st = thx_raster_write_png(ctx, img, path);
            }
        }
        thx_raster_destroy(&old);
        thx_ctx_destroy(&quiet);
        done++;
        if (o.verbose >= 0 && isatty(2)) cli_progress((void *)"animate", (size_t)done, (size_t)mine);
    }
    /* every rank's frames written before the movie is made of them */
    st = thx_par_agree(ctx, st, NULL);
    long long counts[2] = {kept, (long long)nan};
    if (st == THX_OK) st = thx_par_sum(ctx, counts, 2);
    if (st == THX_OK && want_movie && rank == 0) {
        st = thx_movie_make(ctx, &maf, out_dir, a_first, total, o.fps);
    }
    rc = cli_share_end(ctx, "animate", st);
    if (!rc && o.verbose >= 0) {
        if (counts[1]) thx_log(ctx, THX_LOG_WARN, "%lld values are not numbers (drawn in the NaN colour)", counts[1]);
        printf("%d frames (%lld drawn, %lld kept from an earlier run) in %.1f s", total, total - counts[0], counts[0],
               thx_wtime() - t0);
        if (ranks > 1) printf(" by %d ranks", ranks);
        printf(" -> %s", out_dir);
        if (want_movie) printf(", %s", movie);
        printf("\n");
    }
    thx_raster_destroy(&img);
    thx_font_close(&font);
    thx_renderer_destroy(&rr);
    thx_picture_data_free(&d);
    thx_camera_path_destroy(&flight);
    thx_camera_keys_free(&keys);
    thx_ctx_destroy(&ctx);
    return rc;
}
