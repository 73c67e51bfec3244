/*
 * thorax view: the interactive viewer (thorax/view/view.h) with the options of thorax render (so
 * a window shows what render draws from the same options), the viewer's own, and script files of
 * those same options (paper 4.2, "Program control").
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "cli/render_cli.h"
#include "thorax/core/fileio.h"
#include "thorax/view/view.h"

#ifndef THORAX_VIEW_PROGRAM
#include <errno.h>
#include <limits.h>
#include <unistd.h>

/* Runs thorax-view (the program beside this one, linked with GTK) with this command line. Returns
 * only on failure: 1, after saying why. */
static int cli_exec_viewer(int argc, char **argv)
{
    char self[PATH_MAX], path[PATH_MAX + 32];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0) { fprintf(stderr, "thorax view: cannot find this program's directory: %s\n", strerror(errno)); return 1; }
    self[n] = '\0';
    char *slash = strrchr(self, '/');
    if (slash) *slash = '\0';
    snprintf(path, sizeof path, "%s/thorax-view", self);
    char **args = calloc((size_t)argc + 2, sizeof *args);
    if (!args) return 1;
    args[0] = path;
    for (int k = 0; k < argc; k++) args[k + 1] = argv[k]; /* argv[0] is "view" */
    execv(path, args);
    fprintf(stderr, "thorax view: cannot run the viewer %s: %s (it is built beside thorax: make)\n", path, strerror(errno));
    free(args);
    return 1;
}
#endif

typedef struct {
    ropts r;
    thx_view_opts v;
    int size_given;
    int no_loop;
} vopts;

/* The words of a script's leading option lines, and its other lines (kept for the viewer). */
typedef struct {
    char *text;        /* the file, cut into lines and words in place */
    char **words;
    int n_words, cap;
    int cap_lines;     /* of the view options' lines (grown here) */
} script_text;

static int push_word(script_text *t, char *w)
{
    if (t->n_words == t->cap) {
        int cap = t->cap ? 2 * t->cap : 64;
        char **n = realloc(t->words, (size_t)cap * sizeof *n);
        if (!n) return -1;
        t->words = n;
        t->cap = cap;
    }
    t->words[t->n_words++] = w;
    return 0;
}

static int is_command_line(const char *s)
{
    return !strncmp(s, "action ", 7) || !strcmp(s, "action") || !strncmp(s, "wait ", 5) || !strcmp(s, "quit");
}

/*
 * Reads a script: its lines up to the first action, wait or quit line are options (--name VALUE:
 * the name and the rest of the line as its one value, so a path may hold spaces) and positional
 * arguments (a model directory, surface files); the lines from there on go to the viewer as they
 * are. 0, or 1 after printing an error naming the file and line.
 */
static int read_script(const char *path, script_text *t, thx_view_opts *vo)
{
    thx_ctx *ctx = cli_ctx(0);
    size_t len = 0;
    thx_status st = thx_read_file(ctx, path, &t->text, &len);
    if (st != THX_OK) { int rc = cli_fail(ctx, "view", st); thx_ctx_destroy(&ctx); return rc; }
    thx_ctx_destroy(&ctx);
    if (memchr(t->text, '\0', len)) { fprintf(stderr, "thorax view: %s: a NUL byte: not a text script\n", path); return 1; }
    int in_head = 1, line = 0;
    for (char *p = t->text; p && *p;) {
        char *nl = strchr(p, '\n');
        if (nl) *nl = '\0';
        line++;
        char *s = p;
        p = nl ? nl + 1 : NULL;
        while (*s == ' ' || *s == '\t') s++;
        size_t n = strlen(s);
        while (n && (s[n - 1] == '\r' || s[n - 1] == ' ' || s[n - 1] == '\t')) s[--n] = '\0';
        if (n > 1000) { /* the viewer reads a line into 1024 bytes: refused, never cut */
            fprintf(stderr, "thorax view: %s:%d: a line of %zu characters (at most 1000)\n", path, line, n);
            return 1;
        }
        if (in_head && is_command_line(s)) {
            in_head = 0;
            vo->script_line0 = line;
        }
        if (!in_head) {
            if (vo->n_lines == t->cap_lines) { /* a traced session's log runs to thousands of lines */
                int cap = t->cap_lines ? 2 * t->cap_lines : 256;
                const char **grown = realloc(vo->lines, (size_t)cap * sizeof *grown);
                if (!grown) { fprintf(stderr, "thorax view: %s:%d: out of memory\n", path, line); return 1; }
                vo->lines = grown;
                t->cap_lines = cap;
            }
            vo->lines[vo->n_lines++] = s;
            continue;
        }
        if (!*s || *s == '#') continue;
        char *sp = s + strcspn(s, " \t");
        if (*sp && *s == '-') {
            *sp++ = '\0';
            while (*sp == ' ' || *sp == '\t') sp++;
            if (push_word(t, s) || (*sp && push_word(t, sp))) return 1;
        } else if (push_word(t, s)) {
            return 1;
        }
    }
    vo->script = path;
    return 0;
}

static int set_loop(void *user, const cli_opt *opt, const char *v)
{
    vopts *o = user;
    o->v.loop = strcmp(opt->name, "--no-loop") != 0;
    return 0;
}

/* The options of a running viewer's script line: render's table on a copy of the picture. The
 * data the viewer holds cannot change under it. */
static int live_option(void *user, thx_picture_opts *p, const char *line)
{
    (void)user;
    vopts o;
    memset(&o, 0, sizeof o);
    o.r.p = *p;
    o.r.cmd = "view";
    cli_opt common[N_RENDER_OPTS];
    cli_command cmd = {.name = "view", .usage = "[options]", .about = "", .group = {{NULL, common, render_options(common, &o.r)}}, .user = &o.r};
    /* the words must outlive the viewer's use of them: kept until the process ends */
    char *copy = strdup(line);
    if (!copy) return 1;
    char *sp = copy + strcspn(copy, " \t"), *argv[4] = {"view", copy, NULL, NULL};
    int argc = 2;
    if (*sp) {
        *sp++ = '\0';
        while (*sp == ' ' || *sp == '\t') sp++;
        if (*sp) argv[argc++] = sp;
    }
    int rc = cli_parse(&cmd, argc, argv);
    if (rc) { free(copy); return 1; }
    if (o.r.p.solution != p->solution || o.r.p.n_data != p->n_data || o.r.p.channels != p->channels ||
        o.r.p.n_channels != p->n_channels || o.r.p.bad_leads != p->bad_leads ||
        o.r.p.n_data_surface != p->n_data_surface || o.r.p.trace != p->trace || o.r.p.arrows != p->arrows ||
        o.r.p.model_dir != p->model_dir || o.r.p.n_files != p->n_files || o.r.p.n_landmarks != p->n_landmarks ||
        o.r.p.n_electrodes != p->n_electrodes || o.r.p.tetrahedra != p->tetrahedra) {
        fprintf(stderr, "thorax view: %s: the data of a running viewer cannot change (give it on the command line or at the "
                        "head of the script)\n", line);
        free(copy);
        return 1;
    }
    *p = o.r.p;
    return 0;
}

int cmd_view(int argc, char **argv)
{
    vopts o;
    memset(&o, 0, sizeof o);
    render_opts_default(&o.r);
    thx_view_opts_default(&o.v);
    o.r.cmd = "view";
    int frame = 1;
    const char *script = NULL;
    /* a script's options take the place of --script FILE on the command line */
    script_text st = {0};
    char **args = calloc((size_t)argc + 1, sizeof *args);
    int n_args = 0;
    if (!args) return 1;
    for (int k = 0; k < argc; k++) {
        if (!strcmp(argv[k], "--script") && k + 1 < argc && !script) {
            script = argv[++k];
            if (read_script(script, &st, &o.v)) { free(args); free(st.words); free(st.text); free(o.v.lines); return 1; }
            char **grown = realloc(args, ((size_t)argc + (size_t)st.n_words + 1) * sizeof *args);
            if (!grown) return 1;
            args = grown;
            for (int j = 0; j < st.n_words; j++) args[n_args++] = st.words[j];
            continue;
        }
        args[n_args++] = argv[k];
    }
    args[n_args] = NULL;
    cli_opt own[] = {
        {.name = "--frame", .type = CLI_INT, .meta = "K", .i = &frame, .rule = CLI_GE, .lo = 1, .bad = "--frame: 1, 2, ...",
         .help = "the first frame shown, 1-based"},
        {.name = "--script", .type = CLI_INPUT, .meta = "FILE", .s = &script,
         .help = "options, one a line (the head of the file), then lines run once the windows are up: action NAME "
                 "[VALUE], --option VALUE, wait MS, quit"},
        {.name = "--window", .type = CLI_STRING, .meta = "A,B,...", .flags = CLI_REPEAT, .sv = o.v.windows,
         .count = &o.v.n_windows, .max = THX_VIEW_MAX_WINDOWS,
         .help = "a window with these surfaces (repeat for more windows; default one window with every surface)"},
        {.name = "--separate", .type = CLI_FLAG, .i = &o.v.separate, .help = "one window per surface"},
        {.name = "--rate", .type = CLI_REAL, .meta = "FPS", .d = &o.v.rate, .rule = CLI_GT | CLI_LE, .lo = 0, .hi = 1000,
         .unit = "frames/s", .bad = "--rate: 0 < frames per second <= 1000", .help = "frames per second when playing"},
        {.name = "--step", .type = CLI_INT, .meta = "N", .i = &o.v.step, .rule = CLI_GE, .lo = 1, .bad = "--step: at least 1",
         .help = "frames per step of the arrow keys and of playing"},
        {.name = "--loop", .type = CLI_FLAG, .fn = set_loop, .help = "playing and stepping wrap around (the default)"},
        {.name = "--no-loop", .type = CLI_FLAG, .fn = set_loop, .help = "playing stops at the last frame"},
        {.name = "--play", .type = CLI_FLAG, .i = &o.v.play, .help = "start playing"},
        {.name = "--trace-surface", .type = CLI_STRING, .meta = "NAME[:ROLE]", .flags = CLI_REPEAT, .sv = o.v.trace_names,
         .count = &o.v.n_trace_names, .max = 16,
         .help = "with --image: trace this surface on the image's planes (repeat: the surfaces offered, in order; ROLE "
                 "outer, fat, muscle, lung, heart or other). Without a model --image alone traces torso, fat, muscle, "
                 "lungs and heart; --contours FILE goes on with a contour file traced on the image"},
    };
    cli_opt common[N_RENDER_OPTS];
    cli_command cmd = {
        .name = "view",
        .usage = "MODEL [--data [--data-surface]] [--frame] [--script] [options]\n"
                 "--solution [--frame] [--window]... [--separate] [options]\n"
                 "SURFACE_FILE... [--data [--channels]] [--bad-leads] [options]\n"
                 "--image [--trace-surface]... [--contours] [options]\n"
                 "MODEL --image --trace-surface... [--contours] [options]\n"
                 "--script FILE",
        .about = "The interactive viewer (GTK 4; paper 4.2): the surfaces and their data in one window or\n"
                 "several, frames stepped with the left and right arrow keys (in step on every surface),\n"
                 "the surface a command acts on chosen with up and down, turned with the mouse (arcball),\n"
                 "panned, zoomed and clipped, the field's display standards in the menus and keys, a click\n"
                 "showing the node's time signal (a ring and its number on the node in its trace's colour;\n"
                 "the trace pane keeps the window's size and scrolls). `a` the activation map from the\n"
                 "record's fiducials, else one beat's QRS (never a multi-beat record's whole), `a` again the\n"
                 "potentials; Shift+A the recovery map. The window shows what thorax render draws from the\n"
                 "same options (--size is the drawing area). F9 shows a side panel for the equipotentials,\n"
                 "slices, streamline seeds, colour range and activation window (the colour bar's ends and\n"
                 "the values' marks drag too). `?` lists the keys and mouse gestures; every key and menu\n"
                 "item is an action a script line `action NAME [VALUE]` runs alike. Needs a display (or\n"
                 "xvfb-run).\n"
                 "With --image and no model (or --trace-surface), a slice pane beside the 3D view\n"
                 "traces the scan: loops laid on its axial planes surface by surface (points, the\n"
                 "livewire, threshold and seed, copy and snap, interpolation; undo, redo, a log that\n"
                 "replays), each surface built and checked as it is traced; `trace-save DIR` writes\n"
                 "the contours, the model, the label map and the session (docs/cli.md, \"Tracing\n"
                 "a scan\").\n",
        .group = {{NULL, own, sizeof own / sizeof own[0]}, {"what is drawn, and how (as thorax render)", common, render_options(common, &o.r)}},
        .positional = render_positional,
        .user = &o,
    };
    /* the positional and common options' callbacks take the render options, the own ones vopts:
       r is vopts' first member, so both see what they expect */
    cmd.user = &o.r;
    int pr = cli_parse(&cmd, n_args, args);
    if (pr) { free(args); free(st.words); free(st.text); free(o.v.lines); return CLI_EXIT(pr); }
    int no_model = !o.r.p.model_dir && !o.r.p.n_files && !o.r.p.solution;
    if (o.v.n_trace_names && !o.r.p.image) {
        free(args); free(st.words); free(st.text); free(o.v.lines);
        return cli_usage_error("view", "--trace-surface: give --image IMG (the scan traced)");
    }
    o.v.trace_on = o.r.p.image && (no_model || o.v.n_trace_names);
    if (no_model && !o.r.p.image) {
        free(args); free(st.words); free(st.text); free(o.v.lines);
        return cli_usage_error("view", "no model, surface file, --solution or --image given");
    }
    o.v.pic = o.r.p;
    if (o.v.trace_on) { /* the contours are the tracing's to go on with, not lines drawn on the scan */
        o.v.trace_contours = o.v.pic.contours;
        o.v.pic.contours = NULL;
    }
    o.v.frame = frame - 1;
    o.v.win_w = o.r.p.w;
    o.v.win_h = o.r.p.h;
    o.v.verbose = o.r.verbose;
    o.v.option_fn = live_option;
    o.v.command_line = cli_command_line();
#ifdef THORAX_VIEW_PROGRAM
    thx_ctx *ctx = cli_ctx(o.r.verbose);
    int rc = thx_view_run(ctx, &o.v);
    thx_ctx_destroy(&ctx);
#else
    /* the options are good: the viewer program (beside this one) takes the same command line */
    int rc = cli_exec_viewer(argc, argv);
#endif
    free(args);
    free(st.words);
    free(st.text); free(o.v.lines);
    return rc;
}
