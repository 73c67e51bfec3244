/*
 * Tests of the line tokenizer shared by the .channels/.leadlinks and electrode readers
 * (src/io/common/tokens.h: thx_io_split, thx_io_next_line, thx_io_line_at):
 *  - edge cases, each with the tokens spelled out: tabs and the other blanks, CR LF line ends,
 *    leading and trailing blanks, runs of blanks (no empty fields), a blank or empty line,
 *    more tokens than stored (counted, not stored, nothing written past max), max = 0;
 *  - overlong lines: a 1 MiB token, and 100000 tokens of which 4 are stored;
 *  - lines: '\n' cuts, a last line without '\n', CR LF, an empty line between lines, a comment
 *    cut at its character and not cut when the comment character is 0, the end (NULL);
 *  - the line of a byte (thx_io_line_at), as the readers name a NUL byte's line;
 *  - 20000 random lines over an alphabet of blanks, letters and '#' against an independent
 *    tokenizer: strtok_r on a copy with the same blanks as delimiters (count, every stored token,
 *    the slots past max untouched).
 */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "io/common/tokens.h"

/* Splits a copy of `text` with room for max tokens; checks the count and the first tokens
 * against want[] (NULL-terminated, the tokens that must be stored), and that the slot after
 * max is left as it was. */
static void check_split(const char *text, int max, int want_n, const char *const *want)
{
    char *copy = strdup(text);
    char *tok[16];
    char sentinel = 0;
    for (int i = 0; i < 16; i++) tok[i] = &sentinel;
    int n = thx_io_split(copy, tok, max);
    CHECK(n == want_n);
    if (n != want_n) fprintf(stderr, "  line \"%s\": %d tokens, expected %d\n", text, n, want_n);
    int stored = want_n < max ? want_n : max;
    for (int i = 0; i < stored; i++) {
        CHECK(tok[i] != &sentinel && want[i] && !strcmp(tok[i], want[i]));
        if (tok[i] == &sentinel || !want[i] || strcmp(tok[i], want[i]))
            fprintf(stderr, "  line \"%s\": token %d is \"%s\", expected \"%s\"\n", text, i,
                    tok[i] == &sentinel ? "(none)" : tok[i], want[i] ? want[i] : "(none)");
    }
    for (int i = stored; i < 16; i++) CHECK(tok[i] == &sentinel);
    free(copy);
}

static void test_edges(void)
{
    const char *ab[] = {"a", "b", NULL};
    const char *abc[] = {"a", "b", "c", NULL};
    check_split("a b", 4, 2, ab);
    check_split("a\tb", 4, 2, ab);                /* tab */
    check_split("\ta\t\tb\t", 4, 2, ab);          /* tabs around and between */
    check_split("a b\r", 4, 2, ab);               /* CR of a CR LF line: not part of b */
    check_split("a\r\rb\r\r", 4, 2, ab);          /* stray CRs are blanks too */
    check_split("a\vb\f", 4, 2, ab);              /* vertical tab, form feed */
    check_split("   a b   ", 4, 2, ab);           /* leading and trailing blanks */
    check_split("a     b", 4, 2, ab);             /* a run of blanks: no empty field */
    check_split("a \t \r b", 4, 2, ab);           /* a mixed run */
    check_split("", 4, 0, NULL);                  /* empty line */
    check_split(" \t\r\v\f ", 4, 0, NULL);        /* blank line */
    check_split("a b c", 2, 3, abc);              /* more than max: counted, two stored */
    check_split("a b c", 3, 3, abc);              /* exactly max */
    check_split("a b c", 0, 3, abc);              /* max 0: counts only */
    const char *one[] = {"x,y;z", NULL};
    check_split("x,y;z", 4, 1, one);              /* only blanks separate (no commas) */
    const char *hash[] = {"a#b", "#", NULL};
    check_split("a#b #", 4, 2, hash);             /* the tokenizer knows no comments */
    const char *nl[] = {"a\nb", NULL};
    check_split("a\nb", 4, 1, nl);                /* '\n' is the line reader's, not a blank */

    /* in place: the tokens point into the line, their ends are NULs */
    char line[] = "  pq\trs  ";
    char *t[2];
    CHECK(thx_io_split(line, t, 2) == 2);
    CHECK(t[0] == line + 2 && t[1] == line + 5);
    CHECK(line[4] == '\0' && line[7] == '\0' && line[8] == ' '); /* one NUL after each, the rest as it was */
}

static void test_overlong(void)
{
    /* one token of 1 MiB between blanks */
    size_t big = (size_t)1 << 20;
    char *line = malloc(big + 8);
    memcpy(line, " \t", 2);
    memset(line + 2, 'x', big);
    memcpy(line + 2 + big, " y\r", 4);
    char *tok[3] = {NULL, NULL, NULL};
    CHECK(thx_io_split(line, tok, 3) == 2);
    CHECK(tok[0] == line + 2 && strlen(tok[0]) == big && tok[1] && !strcmp(tok[1], "y") && tok[2] == NULL);
    free(line);

    /* 100000 tokens "k0 k1 ...": all counted, the first four stored */
    size_t cap = 100000 * 8 + 1, len = 0;
    line = malloc(cap);
    for (int i = 0; i < 100000; i++) len += (size_t)snprintf(line + len, cap - len, "k%d ", i);
    char *t4[5] = {NULL, NULL, NULL, NULL, NULL};
    CHECK(thx_io_split(line, t4, 4) == 100000);
    CHECK(t4[0] && !strcmp(t4[0], "k0") && t4[3] && !strcmp(t4[3], "k3") && t4[4] == NULL);
    free(line);
}

static void test_lines(void)
{
    char text[] = "a b\r\n\r\n  # c\nd e # f\n\ng";
    char *p = text;
    char *l;
    char *tok[4];
    l = thx_io_next_line(&p, '#');
    CHECK(l && !strcmp(l, "a b\r") && thx_io_split(l, tok, 4) == 2 && !strcmp(tok[1], "b"));
    l = thx_io_next_line(&p, '#');
    CHECK(l && !strcmp(l, "\r") && thx_io_split(l, tok, 4) == 0); /* an empty CR LF line */
    l = thx_io_next_line(&p, '#');
    CHECK(l && !strcmp(l, "  ") && thx_io_split(l, tok, 4) == 0); /* a comment line */
    l = thx_io_next_line(&p, '#');
    CHECK(l && !strcmp(l, "d e ") && thx_io_split(l, tok, 4) == 2); /* a comment after tokens */
    l = thx_io_next_line(&p, '#');
    CHECK(l && !strcmp(l, ""));                                  /* an empty line is a line */
    l = thx_io_next_line(&p, '#');
    CHECK(l && !strcmp(l, "g"));                                 /* the last, without '\n' */
    CHECK(thx_io_next_line(&p, '#') == NULL);
    CHECK(thx_io_next_line(&p, '#') == NULL);                   /* and stays at the end */

    char text2[] = "x # y\n";
    p = text2;
    l = thx_io_next_line(&p, 0);                                 /* no comment character */
    CHECK(l && !strcmp(l, "x # y"));
    CHECK(thx_io_next_line(&p, 0) == NULL);                     /* a final '\n' ends no extra line */

    char empty[] = "";
    p = empty;
    CHECK(thx_io_next_line(&p, '#') == NULL);

    /* the line of a byte */
    const char *t = "ab\ncd\r\n\nef";
    CHECK(thx_io_line_at(t, t) == 1);
    CHECK(thx_io_line_at(t, t + 2) == 1);                       /* the '\n' itself is on its line */
    CHECK(thx_io_line_at(t, t + 3) == 2);
    CHECK(thx_io_line_at(t, t + 7) == 3);
    CHECK(thx_io_line_at(t, t + 8) == 4);
}

/* xorshift64: a fixed sequence, so a failure repeats */
static uint64_t rnd_state = 0x9e3779b97f4a7c15ull;
static unsigned rnd(unsigned n)
{
    rnd_state ^= rnd_state << 13;
    rnd_state ^= rnd_state >> 7;
    rnd_state ^= rnd_state << 17;
    return (unsigned)(rnd_state % n);
}

static void test_random_against_strtok(void)
{
    static const char alphabet[] = " \t\r\v\f  ab1.-#xyz";
    int bad = 0;
    for (int iter = 0; iter < 20000; iter++) {
        char line[64], ref[64];
        unsigned len = rnd(sizeof line);
        for (unsigned i = 0; i < len; i++) line[i] = alphabet[rnd(sizeof alphabet - 1)];
        line[len] = '\0';
        memcpy(ref, line, len + 1);
        char *want[64];
        int want_n = 0;
        char *save = NULL;
        for (char *w = strtok_r(ref, " \t\r\v\f", &save); w; w = strtok_r(NULL, " \t\r\v\f", &save))
            want[want_n++] = w;
        int max = (int)rnd(6);
        char *tok[8];
        char sentinel = 0;
        for (int i = 0; i < 8; i++) tok[i] = &sentinel;
        int n = thx_io_split(line, tok, max);
        int ok = n == want_n;
        for (int i = 0; ok && i < 8; i++)
            ok = i < want_n && i < max ? tok[i] != &sentinel && !strcmp(tok[i], want[i]) : tok[i] == &sentinel;
        if (!ok && bad++ < 5) fprintf(stderr, "  random line %d (max %d): %d tokens, strtok_r %d\n", iter, max, n, want_n);
        CHECK(ok);
    }
}

int main(void)
{
    test_edges();
    test_overlong();
    test_lines();
    test_random_against_strtok();
    return tl_finish();
}
