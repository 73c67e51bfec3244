/*
 * The one line tokenizer of the line-oriented text readers (map3d's .channels and .leadlinks in
 * src/io/map3d/channels.c, the electrode files in src/io/model/electrodes.c and electrodes_any.c),
 * which each carried a copy of it before (docs/design/io.md, "One tokenizer"). Not installed, not
 * public; tested on its own by tests/test_io_tokens.c.
 *
 * A text is read whole and NUL-terminated (thx_read_file); the readers refuse a text with a NUL byte
 * before they scan it, naming its line (thx_io_line_at). Lines end at '\n'; a '\r' before it (CR LF)
 * is a blank like ' ', '\t', '\v' and '\f'. Tokens are the runs of non-blanks: blanks fold (there are
 * no empty fields), leading and trailing blanks are nothing, and a line has no length limit (tokens
 * are cut in place, never copied).
 */
#ifndef THORAX_IO_COMMON_TOKENS_H
#define THORAX_IO_COMMON_TOKENS_H

#include <stddef.h>
#include <string.h>

/* A blank between tokens: space, tab, CR, vertical tab, form feed (not '\n', which ends a line). */
static inline int thx_io_is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/* Splits the NUL-terminated line p into blank-separated tokens, NUL-terminated in place; the first
 * `max` are stored in tok[0..max-1] (nothing past them is written). Returns how many tokens the
 * line has, which may exceed max: the extra ones are counted, not stored. */
static inline int thx_io_split(char *p, char **tok, int max)
{
    int n = 0;
    for (;;) {
        while (thx_io_is_blank(*p)) p++;
        if (!*p) return n;
        if (n < max) tok[n] = p;
        n++;
        while (*p && !thx_io_is_blank(*p)) p++;
        if (*p) *p++ = '\0';
    }
}

/* The next line of the NUL-terminated text at *p: cut at its '\n' (replaced by a NUL) and, when
 * comment is not 0, at its first `comment` character; *p moves to the start of the following line.
 * NULL once *p is at the end of the text (a last line without '\n' is still a line). */
static inline char *thx_io_next_line(char **p, char comment)
{
    char *line = *p;
    if (!*line) return NULL;
    char *nl = strchr(line, '\n');
    if (nl) *nl = '\0';
    *p = nl ? nl + 1 : line + strlen(line);
    if (comment) {
        char *c = strchr(line, comment);
        if (c) *c = '\0';
    }
    return line;
}

/* The 1-based line of the byte at `at` in text (the lines before it counted by their '\n'). */
static inline size_t thx_io_line_at(const char *text, const char *at)
{
    size_t line = 1;
    for (const char *c = text; c < at; c++) line += *c == '\n';
    return line;
}

#endif
