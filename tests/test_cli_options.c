/*
 * Tests of the command-line option tables (src/cli/options.c, cli/options.h), the CLI's own code
 * compiled into this test: typed values and their range rules, positional arguments, the values
 * of output options, unknown options and "did you mean", PETSc-style pass-through, the help
 * (wrapping, defaults taken from the code before the parse, units, notes, repeatable options),
 * the usage lines expanded from their templates, the manual's Markdown table and the tables'
 * check.
 */
#define _POSIX_C_SOURCE 200809L
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/options.h"
#include "testlib.h"

/* ---- stderr captured (usage errors) ---- */

static FILE *err_file;
static int err_saved = -1;
static char err_text[4096];

static void err_begin(void)
{
    fflush(stderr);
    err_file = tmpfile();
    err_saved = dup(2);
    dup2(fileno(err_file), 2);
}

static const char *err_end(void)
{
    fflush(stderr);
    dup2(err_saved, 2);
    close(err_saved);
    rewind(err_file);
    size_t n = fread(err_text, 1, sizeof err_text - 1, err_file);
    err_text[n] = '\0';
    fclose(err_file);
    return err_text;
}

/* ---- a command of every kind of option ---- */

typedef struct {
    int flag, set, count, choice, small, positional_calls, passed;
    long seed;
    double grid, tol;
    const char *name, *in, *out, *list[3];
    int n_list;
} vals;

static int count_positional(void *user, const char *arg)
{
    ((vals *)user)->positional_calls++;
    return strcmp(arg, "bad") ? 0 : cli_usage_error("demo", "bad positional");
}

static int take_two(void *user, char **argv, int argc, int i)
{
    ((vals *)user)->passed++;
    return i + 1 < argc ? 1 : 0;
}

static const cli_choice sizes[] = {{"small", 1}, {"large", 2}, {NULL, 0}};

/* The table over v (defaults set first); c gets it. */
static void demo(cli_command *c, cli_opt *t, size_t *n, vals *v)
{
    memset(v, 0, sizeof *v);
    v->seed = 7;
    v->grid = 6.5;
    v->tol = 0.25;
    v->set = 1;
    v->choice = 2;
    cli_opt opts[] = {
        {.name = "--output", .alias = "-o", .type = CLI_OUTPUT, .meta = "DIR", .s = &v->out, .help = "where to write"},
        {.name = "--input", .type = CLI_INPUT, .meta = "FILE", .s = &v->in, .help = "what to read"},
        {.name = "--grid", .type = CLI_REAL, .meta = "MM", .unit = "mm", .d = &v->grid, .rule = CLI_GT,
         .bad = "--grid must be positive", .help = "grid spacing"},
        {.name = "--tol", .type = CLI_REAL, .meta = "T", .unit = "mm", .d = &v->tol,
         .rule = CLI_GE | CLI_LE | CLI_FINITE, .lo = 0, .hi = 1, .note = "0 = exact", .help = "a tolerance"},
        {.name = "--seed", .alias = "-s", .type = CLI_INT, .meta = "N", .l = &v->seed, .rule = CLI_GE, .help = "seed"},
        {.name = "--small", .type = CLI_INT, .meta = "K", .i = &v->small, .help = "an int"},
        {.name = "--size", .type = CLI_CHOICE, .choices = sizes, .i = &v->choice, .help = "how big"},
        {.name = "--name", .type = CLI_STRING, .meta = "NAME", .s = &v->name, .def = "the file's own name",
         .help = "a name"},
        {.name = "--only", .type = CLI_STRING, .meta = "NAME", .flags = CLI_REPEAT, .sv = v->list, .count = &v->n_list,
         .max = 3, .unit = "S/m", .help = "keep these"},
        {.name = "--flag", .type = CLI_FLAG, .i = &v->flag, .help = "a flag"},
        {.name = "--off", .type = CLI_SET, .i = &v->set, .ival = 0, .help = "turns set off"},
        {.name = "-v", .type = CLI_COUNT, .i = &v->count, .ival = 1, .flags = CLI_NOUSAGE, .help = "more"},
        {.name = "-q", .type = CLI_COUNT, .i = &v->count, .ival = -1, .flags = CLI_NOUSAGE, .help = "less"},
    };
    memcpy(t, opts, sizeof opts);
    *n = sizeof opts / sizeof opts[0];
    memset(c, 0, sizeof *c);
    c->name = "demo";
    c->usage = "IN -o [--input] [--grid] [--tol] [--seed] [--small] [--size] [--name] [--only] [--flag] [--off]\n"
               "IN --size=small -o";
    c->about = "A demonstration.\n";
    c->group[0] = (cli_group){NULL, t, *n};
    c->user = v;
}

/* parse of a NULL-terminated list of words after "demo" */
static int parse(cli_command *c, const char *const *words)
{
    char *argv[64];
    int argc = 0;
    argv[argc++] = "demo";
    for (int k = 0; words[k]; k++) argv[argc++] = (char *)words[k];
    argv[argc] = NULL;
    err_begin();
    int r = cli_parse(c, argc, argv);
    err_end();
    return r;
}

static void test_values(void)
{
    cli_command c;
    cli_opt t[32];
    size_t n;
    vals v;
    demo(&c, t, &n, &v);
    const char *w[] = {"in1",    "-o",     "out",    "--grid", "2.5",   "--tol",   "0",      "-s",  "42",
                       "--small", "-3",    "--size", "small",  "--name", "-dash-", "--only", "a",    "--only",
                       "b",      "--flag", "--off",  "-v",     "-v",    "-q",      "-",      "in2", NULL};
    CHECK(parse(&c, w) == 0);
    CHECK(c.n_pos == 3 && !strcmp(c.pos[0], "in1") && !strcmp(c.pos[1], "-") && !strcmp(c.pos[2], "in2"));
    CHECK(v.out && !strcmp(v.out, "out"));
    CHECK(v.grid == 2.5 && v.tol == 0 && v.seed == 42 && v.small == -3 && v.choice == 1);
    CHECK(v.name && !strcmp(v.name, "-dash-")); /* a value is the next word, whatever it starts with */
    CHECK(v.n_list == 2 && !strcmp(v.list[0], "a") && !strcmp(v.list[1], "b"));
    CHECK(v.flag == 1 && v.set == 0 && v.count == 1);
    /* the output's value is recorded by address, the others are not */
    CHECK(cli_is_output_arg(v.out));
    CHECK(!cli_is_output_arg(c.pos[0]));
    char copy[] = "out";
    CHECK(!cli_is_output_arg(copy));
}

static void test_errors(void)
{
    static const struct {
        const char *w[4];
        const char *msg; /* in the usage error */
    } cases[] = {
        {{"--grid", NULL}, "demo: --grid needs a value (MM)"},
        {{"--size", NULL}, "demo: --size needs a value (small or large)"},
        {{"--grid", "abc", NULL}, "demo: --grid: 'abc' is not a number"},
        {{"--grid", "nan", NULL}, "'nan' is not a number"},
        {{"--grid", "2x", NULL}, "'2x' is not a number"},
        {{"--grid", "0", NULL}, "demo: --grid must be positive"},
        {{"--tol", "1.5", NULL}, "demo: --tol: '1.5' is out of range (in [0, 1] mm)"},
        {{"--tol", "inf", NULL}, "is out of range"},
        {{"-s", "-1", NULL}, "demo: -s: '-1' is out of range (>= 0)"},
        {{"--seed", "1.5", NULL}, "demo: --seed: '1.5' is not an integer"},
        {{"--seed", "99999999999999999999", NULL}, "is out of range (it overflows a long)"}, {{"--seed", " 5", NULL}, "is not an integer"},
        {{"--small", "3000000000", NULL}, "demo: --small: '3000000000' is out of range"},
        {{"--size", "huge", NULL}, "demo: --size: 'huge': expected small or large"},
        {{"--only", "a", "--only", NULL}, "--only needs a value"},
        {{"--gird", "5", NULL}, "demo: unknown option '--gird' (did you mean --grid?)"},
        {{"-grid", NULL}, "did you mean --grid?"},
        {{"--no-such-thing", NULL}, "demo: unknown option '--no-such-thing'\n(see 'thorax demo --help')"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        cli_command c;
        cli_opt t[32];
        size_t n;
        vals v;
        demo(&c, t, &n, &v);
        int r = parse(&c, cases[k].w);
        int ok = r == 2 && strstr(err_text, cases[k].msg);
        CHECK(ok);
        if (!ok) fprintf(stderr, "  case %zu: %d, '%s'\n", k, r, err_text);
    }
    /* a repeatable option beyond its list */
    cli_command c;
    cli_opt t[32];
    size_t n;
    vals v;
    demo(&c, t, &n, &v);
    const char *w[] = {"--only", "a", "--only", "b", "--only", "c", "--only", "d", NULL};
    CHECK(parse(&c, w) == 2 && strstr(err_text, "--only: at most 3"));
    /* more positional arguments than pos[] holds */
    const char *many[CLI_MAX_POS + 2];
    for (int k = 0; k < CLI_MAX_POS + 1; k++) many[k] = "p";
    many[CLI_MAX_POS + 1] = NULL;
    demo(&c, t, &n, &v);
    CHECK(parse(&c, many) == 2 && strstr(err_text, "too many arguments"));
    /* the first problem stops the parse; --help after it is not reached */
    demo(&c, t, &n, &v);
    const char *w2[] = {"--bogus", "--help", NULL};
    CHECK(parse(&c, w2) == 2);
}

static void test_callbacks(void)
{
    cli_command c;
    cli_opt t[32];
    size_t n;
    vals v;
    demo(&c, t, &n, &v);
    c.positional = count_positional;
    c.pass = take_two;
    const char *w[] = {"a", "-ksp_type", "cg", "b", "-ksp_monitor", NULL};
    CHECK(parse(&c, w) == 0);
    CHECK(v.positional_calls == 2 && c.n_pos == 0 && v.passed == 2);
    demo(&c, t, &n, &v);
    c.positional = count_positional;
    c.pass = take_two;
    const char *w2[] = {"bad", NULL};
    CHECK(parse(&c, w2) == 2 && strstr(err_text, "bad positional"));
    /* two dashes are never passed on */
    demo(&c, t, &n, &v);
    c.pass = take_two;
    const char *w3[] = {"--ksp_type", "cg", NULL};
    CHECK(parse(&c, w3) == 2 && v.passed == 0 && strstr(err_text, "unknown option '--ksp_type'"));
}

static void test_suggest(void)
{
    cli_command c;
    cli_opt t[32];
    size_t n;
    vals v;
    demo(&c, t, &n, &v);
    char buf[200];
    CHECK(cli_suggest(&c, "--gird", buf, sizeof buf) && !strcmp(buf, "--grid"));
    CHECK(cli_suggest(&c, "--sede", buf, sizeof buf) && !strcmp(buf, "--seed"));
    CHECK(cli_suggest(&c, "--grid=5", buf, sizeof buf) && !strcmp(buf, "--grid"));
    CHECK(cli_suggest(&c, "--inp", buf, sizeof buf) && !strcmp(buf, "--input"));
    CHECK(cli_suggest(&c, "--hlep", buf, sizeof buf) && !strcmp(buf, "--help"));
    CHECK(!cli_suggest(&c, "--frobnicate", buf, sizeof buf));
    CHECK(!cli_suggest(&c, "-x", buf, sizeof buf)); /* no guess from one letter */
    CHECK(cli_suggest(&c, "--sizd", buf, sizeof buf) && !strcmp(buf, "--size"));
    CHECK(cli_suggest(&c, "--of", buf, sizeof buf) && !strcmp(buf, "--off"));
    /* the names a word begins, all of them: "--a or --b" */
    CHECK(cli_suggest(&c, "--in", buf, sizeof buf) && !strcmp(buf, "--input"));
    CHECK(cli_suggest(&c, "--s", buf, sizeof buf) == 0);
}

static int starts(const char *s, const char *prefix) { return !strncmp(s, prefix, strlen(prefix)); }

static void test_help(void)
{
    cli_command c;
    cli_opt t[32];
    size_t n;
    vals v;
    demo(&c, t, &n, &v);
    /* a parse that changes values first: the help still shows the defaults of the code */
    const char *w[] = {"--grid", "3", "--tol", "0.5", NULL};
    CHECK(parse(&c, w) == 0);
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    cli_help(&c, f);
    fclose(f);
    char *h = buf;
    CHECK(starts(h, "usage: thorax demo IN -o DIR [--input FILE] [--grid MM]"));
    CHECK(strstr(h, "\n       thorax demo IN --size small -o DIR\n"));
    CHECK(strstr(h, "\nA demonstration.\n\noptions:\n"));
    CHECK(strstr(h, "\n  -o, --output DIR    where to write\n"));
    CHECK(strstr(h, "\n  --grid MM           grid spacing (default 6.5)\n")); /* MM names the unit */
    CHECK(strstr(h, "\n  --tol T             a tolerance (default 0.25 mm; 0 = exact)\n"));
    CHECK(strstr(h, "\n  -s, --seed N        seed (default 7)\n"));
    CHECK(strstr(h, "\n  --size small|large  how big (default large)\n"));
    CHECK(strstr(h, "\n  --name NAME         a name (default: the file's own name)\n"));
    CHECK(strstr(h, "\n  --only NAME         keep these (repeatable; in S/m)\n"));
    CHECK(strstr(h, "\n  -h, --help          this text\n"));
    /* wrapped to 79 columns; the usage's bracketed words are never split */
    int longest = 0, col = 0;
    for (const char *p = h; *p; p++) {
        col = *p == '\n' ? 0 : col + 1;
        if (col > longest) longest = col;
    }
    CHECK(longest <= 79);
    CHECK(!strstr(h, "[--grid\n") && !strstr(h, "[--only\n"));
    free(buf);

    /* the manual's table: the defaults and units in columns, '|' escaped */
    buf = NULL;
    f = open_memstream(&buf, &len);
    cli_options_markdown(&c, f);
    fclose(f);
    h = buf;
    CHECK(starts(h, "| option | default | unit | meaning |\n|---|---|---|---|\n"));
    CHECK(strstr(h, "\n| `--tol T` | 0.25 | mm | a tolerance (0 = exact) |\n"));
    CHECK(strstr(h, "\n| `--size small\\|large` | large |  | how big |\n"));
    CHECK(strstr(h, "\n| `--only NAME` |  | S/m | keep these (repeatable) |\n"));
    free(buf);

    buf = NULL;
    f = open_memstream(&buf, &len);
    cli_usage_markdown(&c, f);
    fclose(f);
    h = buf;
    CHECK(starts(h, "    thorax demo IN -o DIR [--input FILE]"));
    CHECK(strstr(h, "[--only NAME]...")); /* a repeatable option */
    free(buf);

    /* -h answers with the help (here: the check, which prints nothing for a sound table) */
    demo(&c, t, &n, &v);
    cli_set_help_mode(CLI_HELP_CHECK);
    const char *hw[] = {"--grid", "3", "-h", "--bogus", NULL};
    CHECK(parse(&c, hw) == CLI_HELP_DONE && CLI_EXIT(CLI_HELP_DONE) == 0);
    CHECK(cli_check_problems() == 0 && err_text[0] == '\0');
    cli_set_help_mode(CLI_HELP_TEXT);
}

static void test_check(void)
{
    cli_command c;
    cli_opt t[32];
    size_t n;
    vals v;
    demo(&c, t, &n, &v);
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    CHECK(cli_check(&c, f) == 0);
    fclose(f);
    free(buf);
    /* each fault found and named */
    static const char *faults[] = {"names --frobnicate", "--size 'medium'", "--grid is in no usage line",
                                   "--tol has no help", "--seed is declared twice", "help does not name the word"};
    for (size_t k = 0; k < sizeof faults / sizeof faults[0]; k++) {
        demo(&c, t, &n, &v);
        switch (k) {
        case 0: c.usage = "IN -o [--input] [--grid] [--tol] [--seed] [--small] [--size] [--name] [--only] [--flag] "
                          "[--off] [--frobnicate]"; break;
        case 1: c.usage = "IN -o [--input] [--grid] [--tol] [--seed] [--small] [--size=medium] [--name] [--only] "
                          "[--flag] [--off]"; break;
        case 2: c.usage = "IN -o [--input] [--tol] [--seed] [--small] [--size] [--name] [--only] [--flag] [--off]"; break;
        case 3: t[3].help = NULL; break;
        case 4: t[5].name = "--seed"; break;
        case 5: t[6].meta = "S"; break;
        }
        buf = NULL;
        f = open_memstream(&buf, &len);
        int problems = cli_check(&c, f);
        fclose(f);
        int ok = problems >= 1 && strstr(buf, faults[k]);
        CHECK(ok);
        if (!ok) fprintf(stderr, "  fault %zu: %d problems: %s\n", k, problems, buf);
        free(buf);
    }
    /* "[options]" stands for every option */
    demo(&c, t, &n, &v);
    c.usage = "IN -o [options]";
    buf = NULL;
    f = open_memstream(&buf, &len);
    CHECK(cli_check(&c, f) == 0);
    fclose(f);
    free(buf);
}


/* The one integer parser and the frame lists and ranges made of it (issue 24: thorax field --frame
 * 1:1:9223372036854775807 overflowed k += step and wrote far outside sel, a segfault). */
static void test_integers(void)
{
    long x = 0, a = 0, b = 0;
    const char *e = NULL;
    CHECK(cli_parse_long("42", 0, 100, &x, NULL) == 0 && x == 42);
    CHECK(cli_parse_long("-7", -10, 10, &x, NULL) == 0 && x == -7);
    CHECK(cli_parse_long("9223372036854775807", 0, LONG_MAX, &x, NULL) == 0 && x == LONG_MAX);
    CHECK(cli_parse_long("9223372036854775808", 0, LONG_MAX, &x, NULL) == -1);   /* overflows */
    CHECK(cli_parse_long("-9223372036854775809", LONG_MIN, 0, &x, NULL) == -1);  /* underflows */
    CHECK(cli_parse_long("101", 0, 100, &x, NULL) == -1);
    CHECK(cli_parse_long("", 0, 100, &x, NULL) == -1);
    CHECK(cli_parse_long(" 5", 0, 100, &x, NULL) == -1);
    CHECK(cli_parse_long("5x", 0, 100, &x, NULL) == -1);
    CHECK(cli_parse_long("5x", 0, 100, &x, &e) == 0 && x == 5 && *e == 'x');
    CHECK(cli_parse_pair("1:40", ':', 1, 100, &a, &b) == 0 && a == 1 && b == 40);
    CHECK(cli_parse_pair("40:1", ':', 1, 100, &a, &b) == -1);
    CHECK(cli_parse_pair("1:99999999999999999999", ':', 1, INT_MAX, &a, &b) == -1);
    CHECK(cli_parse_pair("1:2junk", ':', 1, 100, &a, &b) == -1);
    CHECK(cli_parse_pair("800x600", 'x', 16, 8192, &a, &b) == 0 && a == 800 && b == 600);
    CHECK(cli_parse_pair("4294967312x16", 'x', 16, 8192, &a, &b) == -1); /* 2^32 + 16: not 16 as an int */

    unsigned char sel[12];
    CHECK(cli_parse_frames("all", 12, sel) == 0 && sel[0] && sel[11]);
    CHECK(cli_parse_frames("1:9:4,12", 12, sel) == 0);
    int want[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1}, same = 1;
    for (int k = 0; k < 12; k++) same &= sel[k] == want[k];
    CHECK(same);
    CHECK(cli_parse_frames("2-4", 12, sel) == 0 && !sel[0] && sel[1] && sel[2] && sel[3] && !sel[4]); /* forward's form */
    /* the step and the bounds at the ends of long: no overflow, nothing outside sel */
    CHECK(cli_parse_frames("1:1:9223372036854775807", 12, sel) == 0 && sel[0] && !sel[1]);
    CHECK(cli_parse_frames("1:12:9223372036854775807", 12, sel) == 0 && sel[0] && !sel[11]);
    CHECK(cli_parse_frames("1:12:9223372036854775808", 12, sel) == -1);
    CHECK(cli_parse_frames("9223372036854775807", 12, sel) == -1);
    CHECK(cli_parse_frames("1:9223372036854775807", 12, sel) == -1);
    CHECK(cli_parse_frames("-1", 12, sel) == -1);
    CHECK(cli_parse_frames("0", 12, sel) == -1);
    CHECK(cli_parse_frames("13", 12, sel) == -1);
    CHECK(cli_parse_frames("5:3", 12, sel) == -1);
    CHECK(cli_parse_frames("1:5:0", 12, sel) == -1);
    CHECK(cli_parse_frames("2-4:2", 12, sel) == -1);
    /* an empty list selects nothing: refused (it left an empty output folder) */
    CHECK(cli_parse_frames("", 12, sel) == -1);
    CHECK(cli_parse_frames(",", 12, sel) == -1);
    CHECK(cli_parse_frames("1,", 12, sel) == -1);
    CHECK(cli_parse_frames("1,,2", 12, sel) == -1);
    CHECK(cli_parse_frames(" 1", 12, sel) == -1);
    {
        size_t big = 200000;
        unsigned char *s = malloc(big);
        CHECK(s && cli_parse_frames("3:200000:99991", big, s) == 0 && s[2] && s[99993] && !s[199999]);
        free(s);
    }

    /* counts bounded by memory, the limit named */
    setenv("THORAX_MAX_MEMORY", "1e9", 1);
    CHECK(cli_count_limit(100) == 1e7);
    err_begin();
    int r = cli_check_count("field", "--seed density:100000000", 1e8, 108);
    err_end();
    CHECK(r == 2 && strstr(err_text, "--seed density:100000000: 1e+08 items need 10.8 GB") &&
          strstr(err_text, "at most 9259259"));
    err_begin();
    r = cli_check_count("field", "--seed density:1000", 1000, 108);
    err_end();
    CHECK(r == 0 && !err_text[0]);
    unsetenv("THORAX_MAX_MEMORY");
    CHECK(cli_count_limit(1) >= 1e6); /* half this machine's memory */
}

int main(void)
{
    test_integers();
    test_values();
    test_errors();
    test_callbacks();
    test_suggest();
    test_help();
    test_check();
    return tl_finish();
}
