/*
 * Command-line options from one table per command (PETSc's options database, in small): each
 * command declares each of its options once, as a cli_opt (name, type, metavariable, default,
 * unit, help, where the value goes, its range rule), next to its code in cmd_*.c. The same table
 * feeds
 *  - the parser (cli_parse): values typed and range-checked, positional arguments collected,
 *    unknown options refused with a "did you mean" (exit 2), -h/--help answered;
 *  - the help (`thorax CMD --help`): usage lines, description, the option list with defaults and
 *    units;
 *  - the manual: `thorax help --usage CMD` and `thorax help --markdown CMD` print docs/cli.md's
 *    generated sections (scripts/cli_docs.sh rewrites them, tests/e2e_cli_docs.sh compares);
 *  - the input files of the run (cli_ctx): every value of a CLI_OUTPUT option is an output,
 *    never one of the inputs an output may not replace.
 *
 * Invariants the tables keep (cli_check, `thorax help --check`): names start with '-' and are
 * unique within a command; every option has help text; every dash word of the usage lines is an
 * option of the command, and every option is in some usage line unless a line says "[options]"
 * or the option is CLI_NOUSAGE.
 */
#ifndef THORAX_CLI_OPTIONS_H
#define THORAX_CLI_OPTIONS_H
#include <stddef.h>
#include <stdio.h>

typedef enum {
    CLI_FLAG,   /* no value: *i = 1 */
    CLI_SET,    /* no value: *i = ival (-q: -1, --no-warm: 0) */
    CLI_COUNT,  /* no value: *i += ival (-v: +1, -q: -1) */
    CLI_STRING, /* a word, or a spec the command (or fn) reads further: *s */
    CLI_PATH,   /* a file or directory, neither read nor written as such: *s */
    CLI_INPUT,  /* a file or directory the command reads: *s */
    CLI_OUTPUT, /* a file or directory the command writes: *s; never one of its inputs (cli_ctx) */
    CLI_INT,    /* an integer, base 10: *l, else *i (within int's range) */
    CLI_REAL,   /* a number (strtod; NaN refused, infinities left to the range rule): *d */
    CLI_CHOICE  /* one of choices[].word: *i = its value */
} cli_type;

/* One word of a CLI_CHOICE option and the value it stores; a table of them ends with {NULL, 0}. */
typedef struct {
    const char *word;
    int value;
} cli_choice;

/* cli_opt.flags */
enum {
    CLI_REPEAT = 1u << 0,  /* may be given more than once; with sv: every value kept, in order */
    CLI_NOUSAGE = 1u << 1  /* need not appear in the usage lines (-v, -q) */
};

/* cli_opt.rule: the range of a number, against lo and hi */
enum {
    CLI_GE = 1u << 0,    /* v >= lo */
    CLI_GT = 1u << 1,    /* v > lo */
    CLI_LE = 1u << 2,    /* v <= hi */
    CLI_LT = 1u << 3,    /* v < hi */
    CLI_FINITE = 1u << 4 /* not infinite */
};

typedef struct cli_opt cli_opt;
struct cli_opt {
    const char *name;  /* "--grid"; or a short option alone ("-v") */
    const char *alias; /* the short form of a long option ("-o"), or NULL */
    cli_type type;
    const char *meta; /* the value's metavariable ("MM"); NULL for a choice: its words, a|b|c (a choice
                         with a metavariable names its words in its help) */
    const char *def;  /* the default as text; NULL: the destination's value before parsing; "": none */
    const char *unit; /* "mm", "S/m", "deg", "ms", "mV", ...; NULL: none */
    const char *help; /* one sentence, wrapped by the help; no trailing period */
    const char *note; /* after the default: what special values mean ("0 turns it off") */
    unsigned flags;   /* CLI_REPEAT, CLI_NOUSAGE */
    /* where the value goes: the member the type names (none, or fn alone, is fine) */
    int *i;
    long *l;
    double *d;
    const char **s;
    const char **sv; /* CLI_REPEAT: the values in order, at most max of them, count so far */
    int *count;
    int max;
    int ival;                  /* CLI_SET: the value stored; CLI_COUNT: the value added */
    const cli_choice *choices; /* CLI_CHOICE */
    unsigned rule;             /* CLI_GE ... CLI_FINITE, against lo and hi */
    double lo, hi;
    const char *bad; /* the usage error when the rule fails; NULL: one made from the rule */
    /* called after the value is stored (arg: the value's text, NULL for no-value types): 0, or
       the exit status (2) of a usage error it printed */
    int (*fn)(void *user, const cli_opt *opt, const char *arg);
};

/* A titled part of a command's option list ("options", "options after a surface FILE"). */
typedef struct {
    const char *title; /* NULL: "options" */
    cli_opt *opt;
    size_t n;
} cli_group;

#define CLI_MAX_GROUPS 4
#define CLI_MAX_POS 32

typedef struct {
    const char *name;   /* "mesh" */
    const char *usage;  /* one line per form: what follows "thorax NAME"; every option named in it
                           gets its metavariable ("[--grid]" -> "[--grid MM]"; "--format=vtu|msh"
                           names a part of a choice's words); "..." after a repeatable one */
    const char *about;  /* the description after the usage lines, verbatim (ends with '\n') */
    const char *epilog; /* after the option list, verbatim; NULL: none */
    cli_group group[CLI_MAX_GROUPS];
    /* a positional argument: 0, or the exit status of a usage error it printed; NULL: kept in
       pos[] (more than CLI_MAX_POS is a usage error) */
    int (*positional)(void *user, const char *arg);
    /* a single-dash word no option matches (PETSc's -ksp_type ...): how many of the words after
       argv[i] it takes; NULL: an unknown option */
    int (*pass)(void *user, char **argv, int argc, int i);
    void *user; /* given to fn, positional and pass */
    /* after cli_parse: the positional arguments, in order */
    const char *pos[CLI_MAX_POS];
    int n_pos;
} cli_command;

/* cli_parse's results besides 0 (go on) and 2 (a usage error, printed) */
#define CLI_HELP_DONE (-1) /* -h or --help answered: the command exits 0 */

/*
 * Reads argv[1..argc-1] against c's options, in order: an option's value is the next word,
 * whatever it starts with; "-" and words not starting with '-' are positional arguments. The
 * first problem stops it: a usage error on stderr ("thorax NAME: ..." and a pointer to --help).
 * -h or --help prints the help (or, under cli_set_help_mode, the manual's sections or the table
 * check) and returns CLI_HELP_DONE. Returns 0, CLI_HELP_DONE or 2.
 * Values of CLI_OUTPUT options are recorded for cli_is_output_arg.
 */
int cli_parse(cli_command *c, int argc, char **argv);

/* A command's exit status for cli_parse's result r (nonzero: return it): 0 for CLI_HELP_DONE. */
#define CLI_EXIT(r) ((r) == CLI_HELP_DONE ? 0 : (r))

/* What -h/--help prints: the help, or (thorax help --usage/--markdown/--check) the manual's usage
 * block, its option table, or nothing but the problems cli_check finds (counted). */
typedef enum { CLI_HELP_TEXT, CLI_HELP_USAGE_MD, CLI_HELP_OPTIONS_MD, CLI_HELP_CHECK } cli_help_mode;
void cli_set_help_mode(cli_help_mode mode);
/* The problems the CLI_HELP_CHECK answers found so far. */
int cli_check_problems(void);

/* Whether arg (by address, an element of the argv given to cli_parse) was the value of a
 * CLI_OUTPUT option. */
int cli_is_output_arg(const char *arg);

/* Usage error: prints "thorax CMD: <message>" and a pointer to --help; returns 2. */
int cli_usage_error(const char *cmd, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* The help of c as `thorax NAME --help` prints it; the manual's sections (Markdown). */
void cli_help(const cli_command *c, FILE *f);
void cli_usage_markdown(const cli_command *c, FILE *f);
void cli_options_markdown(const cli_command *c, FILE *f);
/* The table's invariants (above); each problem on f. Returns the number of problems. */
int cli_check(const cli_command *c, FILE *f);

/* The closest option names to word (edit distance or prefix): "--grid", or "--a or --b", in buf;
 * 0 if there is none close enough. */
int cli_suggest(const cli_command *c, const char *word, char *buf, size_t cap);

/* ---- integers, ranges, frame lists and counts the user gives: one overflow-safe parser ----
 * Every integer the CLI reads from a word (an option's value, a part of a spec) goes through
 * cli_parse_long: decimal digits with an optional sign, no blank, no overflow (strtol's ERANGE),
 * within [lo, hi]. The frame lists of export, field and forward and the ranges of animate,
 * verify and render are made of such integers. */

/* The integer at the start of s, within [lo, hi]; *end past its digits (NULL: the whole of s must
 * be the integer). 0, or -1 when there is no integer there, it overflows or it is outside [lo, hi]. */
int cli_parse_long(const char *s, long lo, long hi, long *out, const char **end);

/* "A SEP B" (SEP the character sep, "1:40", "800x600"), both within [lo, hi] and A <= B unless
 * sep is 'x'. 0, or -1. */
int cli_parse_pair(const char *s, char sep, long lo, long hi, long *a, long *b);

/* A frame list: items "N", "A:B" or "A:B:STEP" (forward's older "A-B" too) separated by commas,
 * 1-based, inclusive, within 1..n; or "all". Sets sel[0..n-1] (those listed to 1). 0, or -1 when
 * s is not such a list (an empty one included: it would select nothing). No integer overflows
 * and no index leaves sel, whatever the text (tests/fuzz/fuzz_cli_frames.c). */
int cli_parse_frames(const char *s, size_t n, unsigned char *sel);

/* The most items of `each` bytes a command may allocate for a count the user gave: half of
 * this machine's memory (THORAX_MAX_MEMORY bytes when set), over each. */
double cli_count_limit(double each);

/* A count the user gave (seeds, frames, keys, ranks, ...) checked before anything is allocated:
 * 0 when n items of `each` bytes fit cli_count_limit, else 2 after a usage error naming the
 * option, the count, the memory it needs and the limit. what: "--seed density:N" ... */
int cli_check_count(const char *cmd, const char *what, double n, double each);
#endif
