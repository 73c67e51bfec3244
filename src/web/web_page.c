/*
 * The page's file (thorax/web/page.h): the blobs kept compressed and written as base64 script
 * elements between the description and the viewer.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "thorax/core/fileio.h"
#include "thorax/web/page.h"

#define PAGE_MARKER "thorax-page" /* in the page's first bytes: a file thorax may replace */
#define PAGE_WAITING                                                                                  \
    "This page is a thorax viewer. Its data and its viewer come after this text; if this text stays, " \
    "the viewer did not start: the file is cut short (an interrupted copy or download), or this "    \
    "browser runs no scripts on it."

typedef struct {
    char type[16];
    size_t count, raw, stored;
    int deflated;
    unsigned char *bytes;
} blob;

struct thx_web_page {
    blob *b;
    size_t n, cap;
};

thx_status thx_web_page_create(thx_ctx *ctx, thx_web_page **p)
{
    *p = calloc(1, sizeof **p);
    return *p ? THX_OK : thx_error(ctx, THX_ENOMEM, "web: out of memory");
}

void thx_web_page_free(thx_web_page **p)
{
    if (!p || !*p) return;
    for (size_t k = 0; k < (*p)->n; k++) free((*p)->b[k].bytes);
    free((*p)->b);
    free(*p);
    *p = NULL;
}

thx_status thx_web_page_blob(thx_ctx *ctx, thx_web_page *p, const char *type, const void *data, size_t count,
                             size_t elem_size, int compress, int *index)
{
    if (p->n == p->cap) {
        size_t cap = p->cap ? 2 * p->cap : 16;
        blob *b = realloc(p->b, cap * sizeof *b);
        if (!b) return thx_error(ctx, THX_ENOMEM, "web: out of memory");
        p->b = b;
        p->cap = cap;
    }
    blob *b = &p->b[p->n];
    memset(b, 0, sizeof *b);
    snprintf(b->type, sizeof b->type, "%s", type);
    b->count = count;
    b->raw = count * elem_size;
    if (compress) {
        THX_CHECK(thx_web_deflate(ctx, data, b->raw, &b->bytes, &b->stored));
        b->deflated = 1;
    } else {
        b->bytes = malloc(b->raw ? b->raw : 1);
        if (!b->bytes) return thx_error(ctx, THX_ENOMEM, "web: out of memory");
        if (b->raw) memcpy(b->bytes, data, b->raw);
        b->stored = b->raw;
    }
    *index = (int)p->n++;
    return THX_OK;
}

size_t thx_web_page_blobs(const thx_web_page *p) { return p->n; }

const char *thx_web_page_blob_type(const thx_web_page *p, size_t k, size_t *count, size_t *stored)
{
    if (k >= p->n) return NULL;
    if (count) *count = p->b[k].count;
    if (stored) *stored = p->b[k].stored;
    return p->b[k].type;
}

/* s with every "</" written "<\/" and "<!--" as "<\!--" (a JSON string may hold either; neither may
   appear inside a script element) */
static void put_script_text(FILE *f, const char *s)
{
    for (; *s; s++) {
        fputc(*s, f);
        if (s[0] == '<' && (s[1] == '/' || s[1] == '!')) fputc('\\', f);
    }
}

static void put_html_text(FILE *f, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '&': fputs("&amp;", f); break;
        case '"': fputs("&quot;", f); break;
        default: fputc(*s, f);
        }
    }
}

thx_status thx_web_page_write(thx_ctx *ctx, const thx_web_page *p, const char *path, const char *title,
                              const char *meta_json, const char *viewer, size_t viewer_len,
                              const char *const *inputs, size_t n_inputs, size_t *bytes)
{
    if (!viewer || !viewer_len)
        return thx_error(ctx, THX_EINPUT, "%s: this thorax was built without the page's viewer (THORAX_WEB off, or node "
                         "and npm missing at build time: run scripts/deps.sh, then build again)", path);
    /* the viewer must not close its own script element */
    for (size_t k = 0; k + 8 < viewer_len; k++)
        if (viewer[k] == '<' && viewer[k + 1] == '/' && !strncasecmp(viewer + k + 2, "script", 6))
            return thx_error(ctx, THX_EINTERNAL, "web: the bundled viewer holds \"</script\" (at byte %zu): it cannot be "
                             "inlined", k);
    thx_atomic_file af;
    THX_CHECK(thx_atomic_open_output(ctx, path, PAGE_MARKER, strlen(PAGE_MARKER), inputs, n_inputs, &af));
    FILE *f = af.f;
    fputs("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
          "<meta name=\"generator\" content=\"" PAGE_MARKER "\">\n"
          "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>", f);
    put_html_text(f, title ? title : "thorax");
    /* what shows until the viewer starts (it removes it): all a page cut short, or one opened with
       scripts off, can say, for the viewer comes last */
    fputs("</title>\n</head>\n<body>\n<div id=\"thorax\"><p id=\"thorax-waiting\">" PAGE_WAITING "</p></div>\n"
          "<script type=\"application/json\" id=\"thorax-page\">", f);
    put_script_text(f, meta_json);
    fputs("</script>\n", f);
    char *b64 = NULL;
    size_t b64_cap = 0;
    thx_status st = THX_OK;
    for (size_t k = 0; k < p->n && st == THX_OK; k++) {
        const blob *b = &p->b[k];
        size_t need = 4 * ((b->stored + 2) / 3) + 1;
        if (need > b64_cap) {
            char *nb = realloc(b64, need);
            if (!nb) { st = thx_error(ctx, THX_ENOMEM, "web: out of memory"); break; }
            b64 = nb;
            b64_cap = need;
        }
        size_t len = thx_web_base64(b->bytes, b->stored, b64);
        fprintf(f, "<script type=\"application/octet-stream\" id=\"thorax-blob-%zu\" data-compression=\"%s\" "
                "data-bytes=\"%zu\">", k, b->deflated ? "deflate-raw" : "none", b->raw);
        fwrite(b64, 1, len, f);
        fputs("</script>\n", f);
    }
    free(b64);
    if (st != THX_OK) {
        thx_atomic_abort(&af);
        return st;
    }
    fputs("<script>\n", f);
    fwrite(viewer, 1, viewer_len, f);
    fputs("\n</script>\n</body>\n</html>\n", f);
    long size = ftell(f);
    st = thx_atomic_commit(ctx, &af);
    if (st != THX_OK) thx_atomic_abort(&af);
    if (st == THX_OK && bytes) *bytes = size > 0 ? (size_t)size : 0;
    return st;
}
