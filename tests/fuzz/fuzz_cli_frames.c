/*
 * Fuzz harness: the command line's integers, ranges and frame lists (src/cli/options.c; issue 24:
 * `--frame 1:1:9223372036854775807` overflowed the frame parser's step and wrote far outside its
 * selection, a segfault), and the option parser itself.
 *
 * Input: two bytes giving the frame count n (1..65536), then the text. Properties:
 *  - cli_parse_frames writes only sel[0..n-1] (sel is exactly n bytes: AddressSanitizer), and
 *    agrees, accepted or refused and frame by frame, with a second parser written here another
 *    way (digits accumulated with a saturation flag, every item checked against n before any
 *    frame is marked);
 *  - cli_parse_long accepts exactly the texts that are a sign and digits within long, with the
 *    value strtoll gives; cli_parse_pair's parts as two cli_parse_long;
 *  - the text cut at its NUL bytes into words is an argv for cli_parse over a table of every
 *    option type: 0, 2 (a usage error) or CLI_HELP_DONE, never a crash; accepted values within
 *    their rules.
 */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <unistd.h>

#include "cli/options.h"
#include "fuzz.h"

/* A number as [+-]digits: 0 and *v, or -1 (no digits, or beyond long). */
static int ref_number(const char **p, long *v)
{
    const char *c = *p;
    int neg = 0, over = 0;
    if (*c == '+' || *c == '-') neg = *c++ == '-';
    if (*c < '0' || *c > '9') return -1;
    unsigned long long m = 0;
    for (; *c >= '0' && *c <= '9'; c++) {
        if (m > (ULLONG_MAX - 9) / 10) over = 1;
        else m = m * 10 + (unsigned long long)(*c - '0');
    }
    if (over || m > (unsigned long long)LONG_MAX + (neg ? 1u : 0u)) return -1;
    *v = neg ? (m == (unsigned long long)LONG_MAX + 1 ? LONG_MIN : -(long)m) : (long)m;
    *p = c;
    return 0;
}

/* The frame list, the second way: items first, then the marks. */
static int ref_frames(const char *s, size_t n, unsigned char *sel)
{
    memset(sel, 0, n);
    if (!strcmp(s, "all")) {
        memset(sel, 1, n);
        return 0;
    }
    long (*item)[3] = malloc((strlen(s) / 2 + 1) * sizeof *item); /* an item takes 2 characters with its comma */
    size_t ni = 0;
    const char *p = s;
    int ok = item != NULL;
    while (ok) {
        long a, b, step = 1;
        if (ref_number(&p, &a)) { ok = 0; break; }
        b = a;
        char sep = *p;
        if (sep == ':' || sep == '-') {
            p++;
            if (ref_number(&p, &b)) { ok = 0; break; }
            if (sep == ':' && *p == ':') {
                p++;
                if (ref_number(&p, &step) || step < 1) { ok = 0; break; }
            }
        }
        if (a < 1 || (unsigned long)a > n || b < a || (unsigned long)b > n) { ok = 0; break; }
        item[ni][0] = a, item[ni][1] = b, item[ni][2] = step, ni++;
        if (*p == '\0') break;
        if (*p != ',') { ok = 0; break; }
        p++;
    }
    for (size_t i = 0; ok && i < ni; i++) {
        unsigned long a = (unsigned long)item[i][0], b = (unsigned long)item[i][1], st = (unsigned long)item[i][2];
        for (unsigned long k = a; k <= b; k = (b - k < st) ? b + 1 : k + st) sel[k - 1] = 1;
    }
    free(item);
    if (!ok) memset(sel, 0, n);
    return ok ? 0 : -1;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 2) return 0;
    size_t n = 1 + (size_t)(data[0] | data[1] << 8);
    size_t len = size - 2;
    char *text = malloc(len + 1);
    unsigned char *sel = malloc(n), *ref = malloc(n);
    if (!text || !sel || !ref) abort();
    memcpy(text, data + 2, len);
    text[len] = '\0';

    /* frame lists (up to the first NUL) against the second parser */
    {
        int r = cli_parse_frames(text, n, sel), q = ref_frames(text, n, ref);
        if (r != q) fprintf(stdout, "'%s' (n %zu): cli_parse_frames %d, the reference %d\n", text, n, r, q);
        FUZZ_ASSERT(r == q);
        if (r == 0) FUZZ_ASSERT(memcmp(sel, ref, n) == 0);
    }

    /* single integers and pairs */
    long v = 0, a = 0, b = 0;
    const char *e = NULL;
    int r = cli_parse_long(text, LONG_MIN, LONG_MAX, &v, NULL);
    errno = 0;
    char *end = NULL;
    long long w = strtoll(text, &end, 10);
    int digits = (text[0] == '+' || text[0] == '-') ? text[1] >= '0' && text[1] <= '9' : text[0] >= '0' && text[0] <= '9';
    FUZZ_ASSERT((r == 0) == (digits && !errno && end && !*end));
    if (r == 0) FUZZ_ASSERT(v == w);
    if (cli_parse_long(text, 1, 100, &v, &e) == 0) FUZZ_ASSERT(v >= 1 && v <= 100 && e > text);
    if (cli_parse_pair(text, ':', -5, 1000, &a, &b) == 0) {
        FUZZ_ASSERT(a >= -5 && b <= 1000 && a <= b);
        const char *c = strchr(text, ':');
        FUZZ_ASSERT(c && cli_parse_long(c + 1, -5, 1000, &v, NULL) == 0 && v == b);
    }

    /* the option parser: words at the NUL bytes */
    char *argv[65];
    int argc = 0;
    argv[argc++] = "fuzz";
    for (size_t i = 0; i < len && argc < 64;) {
        argv[argc++] = text + i;
        i += strlen(text + i) + 1;
        /* the NUL bytes of the input (and text[len]) end the words */
    }
    long lval = 7;
    int ival = 3, flag = 0, count = 0, choice = 0, n_rep = 0;
    double dval = 1.5;
    const char *sval = NULL, *rep[4];
    static const cli_choice words[] = {{"small", 0}, {"large", 1}, {NULL, 0}};
    cli_opt opts[] = {
        {.name = "--count", .type = CLI_INT, .meta = "N", .l = &lval, .rule = CLI_GE | CLI_LE, .lo = 1, .hi = 1e6,
         .help = "a count"},
        {.name = "--small", .type = CLI_INT, .meta = "N", .i = &ival, .help = "an int"},
        {.name = "--size", .type = CLI_REAL, .meta = "MM", .d = &dval, .rule = CLI_GT | CLI_FINITE, .lo = 0,
         .unit = "mm", .help = "a size"},
        {.name = "--frames", .type = CLI_STRING, .meta = "LIST", .s = &sval, .help = "frames"},
        {.name = "--only", .type = CLI_STRING, .meta = "NAME", .flags = CLI_REPEAT, .sv = rep, .count = &n_rep,
         .max = 4, .help = "repeatable"},
        {.name = "--kind", .type = CLI_CHOICE, .choices = words, .i = &choice, .help = "a choice"},
        {.name = "--flag", .alias = "-f", .type = CLI_FLAG, .i = &flag, .help = "a flag"},
        {.name = "-v", .type = CLI_COUNT, .ival = 1, .i = &count, .flags = CLI_NOUSAGE, .help = "louder"},
    };
    cli_command c = {.name = "fuzz", .usage = "[options]", .about = "fuzz\n",
                     .group = {{NULL, opts, sizeof opts / sizeof opts[0]}}};
    /* the parser's usage errors and help: not the harness's output (fd 1 and 2 to /dev/null
       for the call alone, so that libFuzzer's and the sanitizers' reports still show) */
    static int null_fd = -1;
    if (null_fd < 0) null_fd = open("/dev/null", O_WRONLY);
    fflush(stdout);
    fflush(stderr);
    int save1 = dup(1), save2 = dup(2);
    if (null_fd < 0 || save1 < 0 || save2 < 0) abort();
    dup2(null_fd, 1);
    dup2(null_fd, 2);
    int pr = cli_parse(&c, argc, argv);
    fflush(stdout);
    fflush(stderr);
    dup2(save1, 1);
    dup2(save2, 2);
    close(save1);
    close(save2);
    FUZZ_ASSERT(pr == 0 || pr == 2 || pr == CLI_HELP_DONE);
    if (pr == 0) {
        FUZZ_ASSERT(lval >= 1 && lval <= 1000000 && dval > 0 && n_rep <= 4 && (choice == 0 || choice == 1));
        if (sval) {
            unsigned char s12[12];
            (void)cli_parse_frames(sval, sizeof s12, s12);
        }
    }
    free(text);
    free(sel);
    free(ref);
    return 0;
}
