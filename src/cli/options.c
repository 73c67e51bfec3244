/* Command-line options from one table per command: the parser, the help, the manual's sections
 * and the tables' check (src/cli/options.h). */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "cli/options.h"
#include "thorax/core/core.h"

#define HELP_WIDTH 79 /* the help's lines are at most this long */
#define HELP_COLUMN 22 /* where an option's text starts ("  " + 18 for its name, then 2 spaces) */
#define MD_WIDTH 100   /* the manual's usage lines (a code block, indented 4) */
#define MAX_OPTS 96    /* options of one command (defaults remembered for its help) */
#define MAX_OUTPUTS 64

static cli_help_mode help_mode = CLI_HELP_TEXT;
static int check_problems;

/* the values of CLI_OUTPUT options in the last parse, by address */
static const char *outputs[MAX_OUTPUTS];
static int n_outputs;

/* the defaults of the command last parsed, as its options held them before the parse (the help
   printed for -h shows these, not the values of the options before it) */
static const cli_command *snap_of;
static char snap[MAX_OPTS][48];

void cli_set_help_mode(cli_help_mode mode) { help_mode = mode; }

int cli_check_problems(void) { return check_problems; }

int cli_is_output_arg(const char *arg)
{
    for (int k = 0; k < n_outputs; k++)
        if (outputs[k] == arg) return 1;
    return 0;
}

int cli_usage_error(const char *cmd, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "thorax %s: ", cmd);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\n(see 'thorax %s --help')\n", cmd);
    return 2;
}

/* Appends to buf (cap bytes, *len of them used), truncating at its end. */
static void appendf(char *buf, size_t cap, size_t *len, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static void appendf(char *buf, size_t cap, size_t *len, const char *fmt, ...)
{
    if (*len + 1 >= cap) return;
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(buf + *len, cap - *len, fmt, ap);
    va_end(ap);
    if (n > 0) *len = *len + (size_t)n < cap ? *len + (size_t)n : cap - 1;
}

/* ---------------------------------------------------------------- the table */

/* The k-th option of c (over its groups in order), or NULL past the last. */
static cli_opt *nth(const cli_command *c, size_t k)
{
    for (int g = 0; g < CLI_MAX_GROUPS; g++) {
        if (k < c->group[g].n) return &c->group[g].opt[k];
        k -= c->group[g].n;
    }
    return NULL;
}

static size_t index_of(const cli_command *c, const cli_opt *o)
{
    size_t k = 0;
    for (int g = 0; g < CLI_MAX_GROUPS; g++) {
        if (o >= c->group[g].opt && o < c->group[g].opt + c->group[g].n) return k + (size_t)(o - c->group[g].opt);
        k += c->group[g].n;
    }
    return k;
}

static cli_opt *find(const cli_command *c, const char *name)
{
    cli_opt *o;
    for (size_t k = 0; (o = nth(c, k)); k++)
        if (!strcmp(o->name, name) || (o->alias && !strcmp(o->alias, name))) return o;
    return NULL;
}

static int takes_value(const cli_opt *o) { return o->type != CLI_FLAG && o->type != CLI_SET && o->type != CLI_COUNT; }

/* A number as the help shows it: %g without the exponent's padding (1e-06 -> 1e-6, 1e+06 -> 1e6). */
static void format_number(double v, char *buf, size_t cap)
{
    char t[40];
    snprintf(t, sizeof t, "%g", v);
    char *e = strchr(t, 'e');
    if (!e) {
        snprintf(buf, cap, "%s", t);
        return;
    }
    const char *d = e + 2; /* past the exponent's sign */
    while (*d == '0' && d[1]) d++;
    snprintf(buf, cap, "%.*se%s%s", (int)(e - t), t, e[1] == '-' ? "-" : "", d);
}

/* The default of o as text (from the table, else from its destination now), "" for none. */
static void default_now(const cli_opt *o, char *buf, size_t cap)
{
    buf[0] = '\0';
    if (o->def) {
        snprintf(buf, cap, "%s", o->def);
        return;
    }
    if (o->flags & CLI_REPEAT) return;
    switch (o->type) {
    case CLI_INT:
        if (o->l) snprintf(buf, cap, "%ld", *o->l);
        else if (o->i) snprintf(buf, cap, "%d", *o->i);
        break;
    case CLI_REAL:
        if (o->d) format_number(*o->d, buf, cap);
        break;
    case CLI_CHOICE:
        for (const cli_choice *w = o->choices; o->i && w && w->word; w++)
            if (w->value == *o->i) {
                snprintf(buf, cap, "%s", w->word);
                break;
            }
        break;
    case CLI_STRING: case CLI_PATH: case CLI_INPUT: case CLI_OUTPUT:
        if (o->s && *o->s) snprintf(buf, cap, "%s", *o->s);
        break;
    default:
        break;
    }
}

static void default_text(const cli_command *c, const cli_opt *o, char *buf, size_t cap)
{
    size_t k = index_of(c, o);
    if (!o->def && snap_of == c && k < MAX_OPTS) snprintf(buf, cap, "%s", snap[k]);
    else default_now(o, buf, cap);
}

/* A choice's words joined by sep, the last by last ("a|b|c", or "a, b or c"). */
static void choice_words(const cli_opt *o, const char *sep, const char *last, char *buf, size_t cap)
{
    size_t len = 0, n = 0;
    buf[0] = '\0';
    while (o->choices && o->choices[n].word) n++;
    for (size_t k = 0; k < n; k++)
        appendf(buf, cap, &len, "%s%s", k == 0 ? "" : k + 1 == n ? last : sep, o->choices[k].word);
}

/* What the value of o is shown as: its metavariable, or a choice's words a|b|c. */
static void value_name(const cli_opt *o, char *buf, size_t cap)
{
    if (o->meta) snprintf(buf, cap, "%s", o->meta);
    else if (o->type == CLI_CHOICE) choice_words(o, "|", "|", buf, cap);
    else snprintf(buf, cap, "VALUE");
}

/* "-o, --output DIR" */
static void spec_of(const cli_opt *o, char *buf, size_t cap)
{
    char v[160] = "";
    if (takes_value(o)) value_name(o, v, sizeof v);
    snprintf(buf, cap, "%s%s%s%s%s", o->alias ? o->alias : "", o->alias ? ", " : "", o->name, v[0] ? " " : "", v);
}

/* Whether the metavariable already names the unit (MM for mm, V/CM for V/cm). */
static int unit_in_meta(const cli_opt *o) { return o->meta && o->unit && !strcasecmp(o->meta, o->unit); }

/* Whether s is a number and nothing else (a unit may follow it). */
static int numeric_text(const char *s)
{
    char *end = NULL;
    strtod(s, &end);
    return end != s && !*end;
}

/* The parenthesis after an option's help: "(default 5 mm; 0 = off)", "(repeatable; in S/m)", or "". */
static void help_tail(const cli_command *c, const cli_opt *o, char *buf, size_t cap)
{
    char def[256];
    default_text(c, o, def, sizeof def);
    int show_unit = o->unit && !unit_in_meta(o);
    size_t len = 0;
    buf[0] = '\0';
    if (o->flags & CLI_REPEAT) appendf(buf, cap, &len, "repeatable");
    if (def[0]) {
        int attach = show_unit && numeric_text(def); /* "5 mm", but "the node spacing" alone */
        appendf(buf, cap, &len, "%sdefault%s%s", len ? "; " : "", strchr(def, ' ') ? ": " : " ", def);
        if (attach) appendf(buf, cap, &len, " %s", o->unit);
        if (attach) show_unit = 0;
    }
    if (show_unit) appendf(buf, cap, &len, "%sin %s", len ? "; " : "", o->unit);
    if (o->note) appendf(buf, cap, &len, "%s%s", len ? "; " : "", o->note);
}

/* --------------------------------------------------------------- the parser */

/* A number x (text v) against o's rule; 0, or 2 after the usage error. */
static int check_rule(const cli_command *c, const cli_opt *o, const char *typed, const char *v, double x)
{
    unsigned r = o->rule;
    int ok = !((r & CLI_GE) && !(x >= o->lo)) && !((r & CLI_GT) && !(x > o->lo)) && !((r & CLI_LE) && !(x <= o->hi)) &&
             !((r & CLI_LT) && !(x < o->hi)) && !((r & CLI_FINITE) && isinf(x));
    if (ok) return 0;
    if (o->bad) return cli_usage_error(c->name, "%s", o->bad);
    char lo[40], hi[40], what[120];
    format_number(o->lo, lo, sizeof lo);
    format_number(o->hi, hi, sizeof hi);
    if ((r & (CLI_GE | CLI_GT)) && (r & (CLI_LE | CLI_LT)))
        snprintf(what, sizeof what, "in %c%s, %s%c", r & CLI_GT ? '(' : '[', lo, hi, r & CLI_LT ? ')' : ']');
    else if (r & (CLI_GE | CLI_GT))
        snprintf(what, sizeof what, "%s %s", r & CLI_GT ? ">" : ">=", lo);
    else if (r & (CLI_LE | CLI_LT))
        snprintf(what, sizeof what, "%s %s", r & CLI_LT ? "<" : "<=", hi);
    else
        snprintf(what, sizeof what, "finite");
    return cli_usage_error(c->name, "%s: '%s' is out of range (%s%s%s)", typed, v, what, o->unit ? " " : "",
                           o->unit ? o->unit : "");
}

/* Stores value v of option o (given as typed); 0, or 2 after the usage error. */
static int store(const cli_command *c, const cli_opt *o, const char *typed, const char *v)
{
    char *end = NULL;
    switch (o->type) {
    case CLI_FLAG:
        if (o->i) *o->i = 1;
        return 0;
    case CLI_SET:
        if (o->i) *o->i = o->ival;
        return 0;
    case CLI_COUNT:
        if (o->i) *o->i += o->ival;
        return 0;
    case CLI_OUTPUT:
        if (n_outputs < MAX_OUTPUTS) outputs[n_outputs++] = v;
        /* fall through */
    case CLI_STRING: case CLI_PATH: case CLI_INPUT:
        if ((o->flags & CLI_REPEAT) && o->sv && o->count) {
            if (*o->count >= o->max) return cli_usage_error(c->name, "%s: at most %d", typed, o->max);
            o->sv[(*o->count)++] = v;
        } else if (o->s) {
            *o->s = v;
        }
        return 0;
    case CLI_INT: {
        long x;
        if (cli_parse_long(v, LONG_MIN, LONG_MAX, &x, NULL))
            return cli_usage_error(c->name, "%s: '%s' is %s", typed, v,
                                   *v && strspn(v + (*v == '-' || *v == '+'), "0123456789") == strlen(v + (*v == '-' || *v == '+'))
                                       ? "out of range (it overflows a long)" : "not an integer");
        int r = check_rule(c, o, typed, v, (double)x);
        if (r) return r;
        if (o->l) *o->l = x;
        else if (o->i) {
            if (x < INT_MIN || x > INT_MAX) return cli_usage_error(c->name, "%s: '%s' is out of range", typed, v);
            *o->i = (int)x;
        }
        return 0;
    }
    case CLI_REAL: {
        double x = strtod(v, &end);
        if (end == v || *end || x != x) return cli_usage_error(c->name, "%s: '%s' is not a number", typed, v);
        int r = check_rule(c, o, typed, v, x);
        if (r) return r;
        if (o->d) *o->d = x;
        return 0;
    }
    case CLI_CHOICE:
        for (const cli_choice *w = o->choices; w && w->word; w++)
            if (!strcmp(w->word, v)) {
                if (o->i) *o->i = w->value;
                return 0;
            }
        char words[512];
        choice_words(o, ", ", " or ", words, sizeof words);
        return cli_usage_error(c->name, "%s: '%s': expected %s", typed, v, words);
    }
    return 0;
}

static int answer_help(const cli_command *c)
{
    switch (help_mode) {
    case CLI_HELP_TEXT: cli_help(c, stdout); break;
    case CLI_HELP_USAGE_MD: cli_usage_markdown(c, stdout); break;
    case CLI_HELP_OPTIONS_MD: cli_options_markdown(c, stdout); break;
    case CLI_HELP_CHECK: check_problems += cli_check(c, stderr); break;
    }
    return CLI_HELP_DONE;
}

int cli_parse(cli_command *c, int argc, char **argv)
{
    cli_opt *o;
    snap_of = c;
    for (size_t k = 0; k < MAX_OPTS && (o = nth(c, k)); k++) default_now(o, snap[k], sizeof snap[k]);
    n_outputs = 0;
    c->n_pos = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) return answer_help(c);
        if (a[0] != '-' || !a[1]) {
            if (c->positional) {
                int r = c->positional(c->user, a);
                if (r) return r;
            } else if (c->n_pos < CLI_MAX_POS) {
                c->pos[c->n_pos++] = a;
            } else {
                return cli_usage_error(c->name, "too many arguments ('%s')", a);
            }
            continue;
        }
        o = find(c, a);
        if (!o && c->pass && a[1] != '-') {
            i += c->pass(c->user, argv, argc, i);
            continue;
        }
        if (!o) {
            char near[200];
            if (cli_suggest(c, a, near, sizeof near))
                return cli_usage_error(c->name, "unknown option '%s' (did you mean %s?)", a, near);
            return cli_usage_error(c->name, "unknown option '%s'", a);
        }
        const char *v = NULL;
        if (takes_value(o)) {
            if (i + 1 >= argc) {
                char what[512];
                if (o->type == CLI_CHOICE && !o->meta) choice_words(o, ", ", " or ", what, sizeof what);
                else value_name(o, what, sizeof what);
                return cli_usage_error(c->name, "%s needs a value (%s)", a, what);
            }
            v = argv[++i];
        }
        int r = store(c, o, a, v);
        if (!r && o->fn) r = o->fn(c->user, o, v);
        if (r) return r;
    }
    return 0;
}

/* ------------------------------------------------------------ "did you mean" */

static const char *undash(const char *s)
{
    while (*s == '-') s++;
    return s;
}

int cli_suggest(const cli_command *c, const char *word, char *buf, size_t cap)
{
    const char *names[2 * MAX_OPTS + 2];
    size_t n = 0;
    cli_opt *o;
    for (size_t k = 0; (o = nth(c, k)) && n + 2 < sizeof names / sizeof names[0]; k++) {
        names[n++] = o->name;
        if (o->alias) names[n++] = o->alias;
    }
    names[n++] = "--help";
    const char *w = undash(word);
    size_t wl = strlen(w);
    /* the nearest names by edit distance (without the dashes), within a quarter of their length
       (at least 1, at most 3); no guesses at names shorter than 3 (-o, -v) */
    const char *best[3];
    size_t nb = 0, bd = 64;
    for (size_t k = 0; k < n; k++) {
        const char *cn = undash(names[k]);
        size_t len = strlen(cn), limit = len / 4 > 1 ? (len / 4 < 3 ? len / 4 : 3) : 1;
        if (len < 3) continue;
        size_t d = thx_name_distance(w, cn);
        if (d > limit || d > bd) continue;
        if (d < bd) nb = 0, bd = d;
        if (nb < 3) best[nb++] = names[k];
    }
    /* else the names it begins (--no-inter), or that begin it up to an '=' (--grid=5) */
    if (!nb && wl >= 2)
        for (size_t k = 0; k < n && nb < 3; k++) {
            const char *cn = undash(names[k]);
            size_t len = strlen(cn);
            if (!strncmp(cn, w, wl) || (!strncmp(w, cn, len) && w[len] == '=')) best[nb++] = names[k];
        }
    if (!nb) return 0;
    size_t len = 0;
    buf[0] = '\0';
    for (size_t k = 0; k < nb; k++) appendf(buf, cap, &len, "%s%s", k == 0 ? "" : k + 1 == nb ? " or " : ", ", best[k]);
    return 1;
}

/* ------------------------------------------------------------------ the help */

/* Prints text's words from column col, wrapped before width, continuation lines indented by
 * indent; returns the column after the last word. */
static int put_wrapped(FILE *f, const char *text, int col, int indent, int width)
{
    int first = 1;
    for (const char *p = text; *p;) {
        while (*p == ' ') p++;
        if (!*p) break;
        const char *e = p;
        while (*e && *e != ' ') e++;
        int len = (int)(e - p);
        if (!first && col + 1 + len > width) {
            fprintf(f, "\n%*s", indent, "");
            col = indent;
        } else if (!first) {
            fputc(' ', f);
            col++;
        }
        fwrite(p, 1, (size_t)len, f);
        col += len;
        first = 0;
        p = e;
    }
    return col;
}

/* One word of a usage line as printed: an option named in it gets its metavariable ("[--grid]" ->
 * "[--grid MM]", "--format=vtu|msh" -> "--format vtu|msh", "MODEL|--solution" -> "MODEL|--solution
 * DIR"), a repeatable one "..." after it. Problems (an unknown option, a word not among a choice's)
 * go to err when it is not NULL; seen[k] is set for every option k named. */
static int usage_word(const cli_command *c, const char *tok, size_t tl, char *out, size_t cap, FILE *err,
                      unsigned char *seen)
{
    size_t a = 0, b = tl;
    while (a < b && (tok[a] == '[' || tok[a] == '(')) a++;
    while (b > a && (tok[b - 1] == ']' || tok[b - 1] == ')' || tok[b - 1] == '.')) b--;
    size_t len = 0;
    out[0] = '\0';
    appendf(out, cap, &len, "%.*s", (int)a, tok);
    int problems = 0, repeat = 0;
    /* alternatives separated by '|', unless an option's '=' gives its own words */
    for (size_t p = a; p < b;) {
        size_t q = p;
        const char *eq = NULL;
        if (tok[p] == '-') {
            while (q < b && tok[q] != '=' && tok[q] != '|') q++;
            if (q < b && tok[q] == '=') eq = tok + q;
        } else {
            while (q < b && tok[q] != '|') q++;
        }
        char name[64];
        snprintf(name, sizeof name, "%.*s", (int)(q - p), tok + p);
        cli_opt *o = name[0] == '-' && name[1] ? find(c, name) : NULL;
        if (name[0] == '-' && name[1] && !o && strcmp(name, "-h") && strcmp(name, "--help")) {
            if (err) fprintf(err, "%s: the usage names %s, which is not one of its options\n", c->name, name);
            problems++;
        }
        if (o && seen) seen[index_of(c, o)] = 1;
        if (o && (o->flags & CLI_REPEAT)) repeat = 1;
        appendf(out, cap, &len, "%s", name);
        if (eq) {
            const char *v = eq + 1;
            size_t vl = (size_t)(tok + b - v);
            if (o && o->type == CLI_CHOICE) /* each word must be one of the choice's */
                for (const char *w = v; w < v + vl;) {
                    const char *e = w;
                    while (e < v + vl && *e != '|') e++;
                    int found = 0;
                    for (const cli_choice *ch = o->choices; ch && ch->word; ch++)
                        found |= strlen(ch->word) == (size_t)(e - w) && !strncmp(ch->word, w, (size_t)(e - w));
                    if (!found) {
                        if (err)
                            fprintf(err, "%s: the usage gives %s '%.*s', not one of its words\n", c->name, name,
                                    (int)(e - w), w);
                        problems++;
                    }
                    w = e + (e < v + vl);
                }
            appendf(out, cap, &len, " %.*s", (int)vl, v);
            p = b;
            break;
        }
        if (o && takes_value(o)) {
            char v[160];
            value_name(o, v, sizeof v);
            appendf(out, cap, &len, " %s", v);
        }
        p = q;
        if (p < b && tok[p] == '|') {
            appendf(out, cap, &len, "|");
            p++;
        }
    }
    appendf(out, cap, &len, "%.*s", (int)(tl - b), tok + b);
    if (repeat && (tl < 3 || strncmp(tok + tl - 3, "...", 3))) appendf(out, cap, &len, "...");
    return problems;
}

/* One form of the usage (line of c->usage, [line, end)) expanded after prefix, wrapped before width
 * under its first word; a bracketed group ("[--grid MM]", "[FILE --name NAME ...]") is never split. */
static void usage_form(const cli_command *c, FILE *f, const char *prefix, const char *line, const char *end, int width)
{
    int col = fprintf(f, "%s", prefix), indent = col, first = 1;
    for (const char *p = line; p < end;) {
        char unit[1024];
        size_t len = 0;
        int depth = 0;
        do { /* the words up to the end of the group the first one opens */
            while (p < end && *p == ' ') p++;
            if (p >= end) break;
            const char *e = p;
            while (e < end && *e != ' ') e++;
            for (const char *q = p; q < e; q++) depth += (*q == '[') - (*q == ']');
            char w[512];
            usage_word(c, p, (size_t)(e - p), w, sizeof w, NULL, NULL);
            appendf(unit, sizeof unit, &len, "%s%s", len ? " " : "", w);
            p = e;
        } while (depth > 0 && p < end);
        if (!len) break;
        if (!first && col + 1 + (int)strlen(unit) > width) {
            fprintf(f, "\n%*s", indent, "");
            col = indent;
        } else if (!first) {
            fputc(' ', f);
            col++;
        }
        col += fprintf(f, "%s", unit);
        first = 0;
    }
    fputc('\n', f);
}

static void put_usage(const cli_command *c, FILE *f, const char *first, const char *next, int width)
{
    char prefix[128];
    int k = 0;
    for (const char *line = c->usage; line && *line; k++) {
        const char *end = strchr(line, '\n');
        if (!end) end = line + strlen(line);
        snprintf(prefix, sizeof prefix, "%sthorax %s ", k ? next : first, c->name);
        usage_form(c, f, prefix, line, end, width);
        line = *end ? end + 1 : end;
    }
}

/* An option's text: its help, then (the help) "(repeatable; default D UNIT; NOTE)" or (the manual,
 * which has the default and the unit in columns of their own) "(repeatable; NOTE)". */
static void option_text(const cli_command *c, const cli_opt *o, char *buf, size_t cap, int markdown)
{
    char tail[512] = "";
    if (!markdown) help_tail(c, o, tail, sizeof tail);
    else snprintf(tail, sizeof tail, "%s%s%s", o->flags & CLI_REPEAT ? "repeatable" : "",
                  (o->flags & CLI_REPEAT) && o->note ? "; " : "", o->note ? o->note : "");
    size_t len = 0;
    buf[0] = '\0';
    appendf(buf, cap, &len, "%s", o->help ? o->help : "");
    if (tail[0]) appendf(buf, cap, &len, " (%s)", tail);
}

void cli_help(const cli_command *c, FILE *f)
{
    put_usage(c, f, "usage: ", "       ", HELP_WIDTH);
    if (c->about) fprintf(f, "\n%s", c->about);
    for (int g = 0; g < CLI_MAX_GROUPS; g++) {
        if (!c->group[g].n) continue;
        fprintf(f, "\n%s:\n", c->group[g].title ? c->group[g].title : "options");
        for (size_t k = 0; k < c->group[g].n; k++) {
            const cli_opt *o = &c->group[g].opt[k];
            char spec[256], text[2048];
            spec_of(o, spec, sizeof spec);
            option_text(c, o, text, sizeof text, 0);
            int col = fprintf(f, "  %s", spec);
            if (col + 2 > HELP_COLUMN) fprintf(f, "\n%*s", HELP_COLUMN, "");
            else fprintf(f, "%*s", HELP_COLUMN - col, "");
            put_wrapped(f, text, HELP_COLUMN, HELP_COLUMN, HELP_WIDTH);
            fputc('\n', f);
        }
    }
    fprintf(f, "  %-*s%s\n", HELP_COLUMN - 2, "-h, --help", "this text");
    if (c->epilog) fprintf(f, "\n%s", c->epilog);
}

/* ---------------------------------------------------------------- the manual */

/* text with every '|' escaped (a Markdown table cell) */
static void put_cell(FILE *f, const char *text)
{
    for (const char *p = text; *p; p++) {
        if (*p == '|') fputc('\\', f);
        fputc(*p, f);
    }
}

void cli_usage_markdown(const cli_command *c, FILE *f) { put_usage(c, f, "    ", "    ", MD_WIDTH); }

void cli_options_markdown(const cli_command *c, FILE *f)
{
    int tables = 0, groups = 0;
    for (int g = 0; g < CLI_MAX_GROUPS; g++) groups += c->group[g].n > 0;
    for (int g = 0; g < CLI_MAX_GROUPS; g++) {
        if (!c->group[g].n) continue;
        if (tables++) fputc('\n', f);
        /* several tables: each under its title, as in the help */
        if (groups > 1) fprintf(f, "%s:\n\n", c->group[g].title ? c->group[g].title : "options");
        fprintf(f, "| option | default | unit | meaning |\n|---|---|---|---|\n");
        for (size_t k = 0; k < c->group[g].n; k++) {
            const cli_opt *o = &c->group[g].opt[k];
            char spec[256], def[256], text[2048];
            spec_of(o, spec, sizeof spec);
            default_text(c, o, def, sizeof def);
            option_text(c, o, text, sizeof text, 1);
            fprintf(f, "| `");
            put_cell(f, spec);
            fprintf(f, "` | ");
            put_cell(f, def);
            fprintf(f, " | %s | ", o->unit ? o->unit : "");
            put_cell(f, text);
            fprintf(f, " |\n");
        }
    }
}

/* ----------------------------------------------------------------- the check */

int cli_check(const cli_command *c, FILE *f)
{
    int problems = 0;
    cli_opt *o;
    size_t n = 0;
    while (nth(c, n)) n++;
    if (n > MAX_OPTS) {
        fprintf(f, "%s: %zu options, more than %d\n", c->name, n, MAX_OPTS);
        return 1;
    }
    unsigned char seen[MAX_OPTS] = {0};
    if (!c->usage || !c->usage[0]) fprintf(f, "%s: no usage line\n", c->name), problems++;
    if (!c->about || !c->about[0]) fprintf(f, "%s: no description\n", c->name), problems++;
    for (size_t k = 0; (o = nth(c, k)); k++) {
        const char *names[2] = {o->name, o->alias};
        for (int q = 0; q < 2; q++) {
            const char *nm = names[q];
            if (!nm) continue;
            if (nm[0] != '-' || !nm[1] || (q == 1 && nm[1] == '-'))
                fprintf(f, "%s: option name '%s'\n", c->name, nm), problems++;
            if (!strcmp(nm, "-h") || !strcmp(nm, "--help"))
                fprintf(f, "%s: %s is every command's help\n", c->name, nm), problems++;
            cli_opt *first = find(c, nm);
            if (first != o) fprintf(f, "%s: %s is declared twice\n", c->name, nm), problems++;
        }
        if (!o->help || !o->help[0]) fprintf(f, "%s: %s has no help text\n", c->name, o->name), problems++;
        if (takes_value(o) && !o->meta && o->type != CLI_CHOICE)
            fprintf(f, "%s: %s has no metavariable\n", c->name, o->name), problems++;
        if (o->type == CLI_CHOICE && (!o->choices || !o->choices[0].word))
            fprintf(f, "%s: %s has no words to choose from\n", c->name, o->name), problems++;
        /* a choice shown by its metavariable lists its words in its help */
        if (o->type == CLI_CHOICE && o->meta && o->help)
            for (const cli_choice *w = o->choices; w && w->word; w++)
                if (!strstr(o->help, w->word))
                    fprintf(f, "%s: %s: the help does not name the word '%s'\n", c->name, o->name, w->word), problems++;
        if ((o->flags & CLI_REPEAT) && !o->fn && !(o->sv && o->count && o->max > 0))
            fprintf(f, "%s: %s is repeatable but keeps no list\n", c->name, o->name), problems++;
        if ((o->type == CLI_FLAG || o->type == CLI_SET || o->type == CLI_COUNT) && !o->i && !o->fn)
            fprintf(f, "%s: %s sets nothing\n", c->name, o->name), problems++;
    }
    int catch_all = 0;
    for (const char *line = c->usage; line && *line;) {
        const char *end = strchr(line, '\n');
        if (!end) end = line + strlen(line);
        for (const char *p = line; p < end;) {
            while (p < end && *p == ' ') p++;
            const char *e = p;
            while (e < end && *e != ' ') e++;
            if (e > p) {
                char w[512];
                problems += usage_word(c, p, (size_t)(e - p), w, sizeof w, f, seen);
                if (e - p == 9 && !strncmp(p, "[options]", 9)) catch_all = 1;
            }
            p = e;
        }
        line = *end ? end + 1 : end;
    }
    for (size_t k = 0; !catch_all && (o = nth(c, k)); k++)
        if (!seen[k] && !(o->flags & CLI_NOUSAGE))
            fprintf(f, "%s: %s is in no usage line (and no line says [options])\n", c->name, o->name), problems++;
    return problems;
}

/* ------------------------------------------- integers, frame lists, counts */

int cli_parse_long(const char *s, long lo, long hi, long *out, const char **end)
{
    const char *p = s;
    if (*p == '+' || *p == '-') p++;
    if (*p < '0' || *p > '9') return -1; /* strtol would skip blanks and take "" as 0 */
    char *e = NULL;
    errno = 0;
    long x = strtol(s, &e, 10);
    if (errno || e == s || (!end && *e) || x < lo || x > hi) return -1;
    if (end) *end = e;
    *out = x;
    return 0;
}

int cli_parse_pair(const char *s, char sep, long lo, long hi, long *a, long *b)
{
    const char *e;
    if (cli_parse_long(s, lo, hi, a, &e) || *e != sep) return -1;
    if (cli_parse_long(e + 1, lo, hi, b, NULL)) return -1;
    return sep != 'x' && *b < *a ? -1 : 0;
}

int cli_parse_frames(const char *s, size_t n, unsigned char *sel)
{
    memset(sel, 0, n);
    if (!strcmp(s, "all")) {
        memset(sel, 1, n);
        return 0;
    }
    long top = n > (size_t)LONG_MAX ? LONG_MAX : (long)n;
    const char *p = s;
    do {
        const char *e;
        long a, b, step = 1;
        if (cli_parse_long(p, 1, top, &a, &e)) return -1;
        b = a;
        if (*e == ':' || *e == '-') {
            int colon = *e == ':';
            if (cli_parse_long(e + 1, a, top, &b, &e)) return -1;
            if (colon && *e == ':' && cli_parse_long(e + 1, 1, LONG_MAX, &step, &e)) return -1;
        }
        /* a <= b <= n: the step is added only while it stays within b (no overflow) */
        for (long k = a;; k += step) {
            sel[k - 1] = 1;
            if (b - k < step) break;
        }
        if (*e == ',') p = e + 1;
        else if (*e) return -1;
        else p = e;
    } while (*p);
    return p > s && p[-1] == ',' ? -1 : 0;
}

double cli_count_limit(double each)
{
    double mem = 0;
    const char *env = getenv("THORAX_MAX_MEMORY");
    if (env && *env) mem = strtod(env, NULL);
    if (!(mem > 0)) {
        long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
        mem = pages > 0 && page > 0 ? (double)pages * (double)page / 2 : 4e9;
    }
    return floor(mem / (each > 1 ? each : 1));
}

/* "10.8 GB" */
static void bytes_text(double b, char *buf, size_t cap)
{
    if (b >= 1e9) snprintf(buf, cap, "%.1f GB", b / 1e9);
    else if (b >= 1e6) snprintf(buf, cap, "%.1f MB", b / 1e6);
    else snprintf(buf, cap, "%.0f kB", ceil(b / 1e3));
}

int cli_check_count(const char *cmd, const char *what, double n, double each)
{
    double lim = cli_count_limit(each);
    if (n <= lim) return 0;
    char need[32], have[32];
    bytes_text(n * each, need, sizeof need);
    bytes_text(lim * each, have, sizeof have);
    return cli_usage_error(cmd, "%s: %.4g items need %s, more than the limit of %s (half this machine's memory, or "
                           "THORAX_MAX_MEMORY): at most %.0f", what, n, need, have, lim);
}
