/*
 * The web page's data (thorax/web/page.h): quantization within half a step (NaN kept, a constant
 * series exact), frame deltas undone exactly, raw deflate and base64 against their references (RFC
 * 4648's vectors; inflate), and a page written, read back blob by blob, its description escaped, a
 * foreign file left alone and a viewer that would close its script refused.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testlib.h"
#include "thorax/web/page.h"

static void quantize(thx_ctx *ctx)
{
    size_t n = 257, m = 40;
    double *v = malloc(n * m * sizeof *v);
    for (size_t f = 0; f < m; f++)
        for (size_t i = 0; i < n; i++) v[f * n + i] = 3.7 * sin(0.1 * (double)i + 0.3 * (double)f) - 1.25;
    v[5] = NAN;
    v[n * m - 1] = INFINITY; /* not a number either: kept apart */
    thx_web_quant q;
    CHECK_OK(ctx, thx_web_quantize(ctx, v, n, m, &q));
    CHECK(q.n_nan == 2);
    CHECK(q.codes[5] == THX_WEB_NAN_CODE && q.codes[n * m - 1] == THX_WEB_NAN_CODE);
    CHECK(isnan(thx_web_dequantize(&q, q.codes[5])));
    double err = thx_web_quant_error(&q, v);
    CHECK(err <= q.step / 2 * (1 + 1e-12));
    CHECK(err > q.step / 8); /* the bound is not loose by much (a sine lands everywhere in a step) */
    CHECK_NEAR(q.origin, q.min, 0);
    CHECK_NEAR(q.origin + 65534 * q.step, q.max, 1e-12 * fabs(q.max));
    /* the extremes are exact codes */
    int lo = 0, hi = 0;
    for (size_t k = 0; k < n * m; k++) {
        lo |= q.codes[k] == 0;
        hi |= q.codes[k] == 65534;
    }
    CHECK(lo && hi);
    /* deltas and back */
    uint16_t *keep = malloc(n * m * sizeof *keep);
    memcpy(keep, q.codes, n * m * sizeof *keep);
    thx_web_delta_encode(q.codes, n, m);
    CHECK(memcmp(q.codes, keep, n * sizeof *keep) == 0); /* frame 0 as it is */
    CHECK(memcmp(q.codes, keep, n * m * sizeof *keep) != 0);
    thx_web_delta_decode(q.codes, n, m);
    CHECK(memcmp(q.codes, keep, n * m * sizeof *keep) == 0);
    thx_web_quant_free(&q);
    /* a constant series: step 0, every value exact */
    for (size_t k = 0; k < n * m; k++) v[k] = 2.5;
    CHECK_OK(ctx, thx_web_quantize(ctx, v, n, m, &q));
    CHECK(q.step == 0 && thx_web_quant_error(&q, v) == 0 && thx_web_dequantize(&q, q.codes[17]) == 2.5);
    thx_web_quant_free(&q);
    /* nothing finite: every code NaN */
    for (size_t k = 0; k < n; k++) v[k] = NAN;
    CHECK_OK(ctx, thx_web_quantize(ctx, v, n, 1, &q));
    CHECK(q.n_nan == n && q.codes[0] == THX_WEB_NAN_CODE && q.min > q.max);
    thx_web_quant_free(&q);
    free(keep);
    free(v);
}

static void codecs(thx_ctx *ctx)
{
    static const char *const in[7] = {"", "f", "fo", "foo", "foob", "fooba", "foobar"};
    static const char *const out[7] = {"", "Zg==", "Zm8=", "Zm9v", "Zm9vYg==", "Zm9vYmE=", "Zm9vYmFy"};
    char b[16];
    for (int k = 0; k < 7; k++) {
        size_t len = thx_web_base64((const unsigned char *)in[k], strlen(in[k]), b);
        CHECK(len == strlen(out[k]) && memcmp(b, out[k], len) == 0);
    }
    size_t n = 1 << 20;
    unsigned char *r = malloc(n), *z = NULL, *back = NULL;
    srand(3);
    for (size_t i = 0; i < n; i++) r[i] = (unsigned char)(i % 251 < 200 ? (int)(i % 7) : rand());
    size_t zn = 0;
    CHECK_OK(ctx, thx_web_deflate(ctx, r, n, &z, &zn));
    CHECK(zn > 0 && zn < n / 2);
    CHECK_OK(ctx, thx_web_inflate(ctx, z, zn, n, &back));
    CHECK(back && memcmp(back, r, n) == 0);
    free(back);
    back = NULL;
    CHECK(thx_web_inflate(ctx, z, zn, n + 1, &back) == THX_EINPUT && !back); /* a wrong size is refused */
    free(z);
    CHECK_OK(ctx, thx_web_deflate(ctx, r, 0, &z, &zn)); /* empty */
    CHECK_OK(ctx, thx_web_inflate(ctx, z, zn, 0, &back));
    free(back);
    free(z);
    free(r);
}

static int b64v(char c)
{
    return c >= 'A' && c <= 'Z' ? c - 'A' : c >= 'a' && c <= 'z' ? c - 'a' + 26 : c >= '0' && c <= '9' ? c - '0' + 52
           : c == '+' ? 62 : c == '/' ? 63 : -1;
}

/* base64 text [s, e) to bytes (the test's own decoder) */
static unsigned char *unbase64(const char *s, const char *e, size_t *n)
{
    unsigned char *o = malloc((size_t)(e - s) / 4 * 3 + 3);
    size_t k = 0;
    uint32_t w = 0;
    int bits = 0;
    for (; s < e && *s != '='; s++) {
        w = w << 6 | (uint32_t)b64v(*s);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            o[k++] = (unsigned char)(w >> bits);
        }
    }
    *n = k;
    return o;
}

static void page(thx_ctx *ctx)
{
    thx_web_page *p = NULL;
    CHECK_OK(ctx, thx_web_page_create(ctx, &p));
    float xyz[300];
    for (int i = 0; i < 300; i++) xyz[i] = (float)i * 0.5f;
    uint16_t codes[1000];
    for (int i = 0; i < 1000; i++) codes[i] = (uint16_t)(i * 37);
    int k0 = -1, k1 = -1;
    CHECK_OK(ctx, thx_web_page_blob(ctx, p, "float32", xyz, 300, sizeof *xyz, 1, &k0));
    CHECK_OK(ctx, thx_web_page_blob(ctx, p, "uint16", codes, 1000, sizeof *codes, 0, &k1));
    CHECK(k0 == 0 && k1 == 1 && thx_web_page_blobs(p) == 2);
    size_t count = 0, stored = 0;
    CHECK(!strcmp(thx_web_page_blob_type(p, 1, &count, &stored), "uint16") && count == 1000 && stored == 2000);
    const char *viewer = "console.log('a</b>');";
    const char *path = tl_path("page.html");
    size_t bytes = 0;
    CHECK_OK(ctx, thx_web_page_write(ctx, p, path, "A & B <test>", "{\"title\":\"</script><!--x\"}", viewer,
                                     strlen(viewer), NULL, 0, &bytes));
    FILE *f = fopen(path, "rb");
    CHECK(f != NULL);
    char *text = malloc(bytes + 1);
    CHECK(fread(text, 1, bytes, f) == bytes);
    fclose(f);
    text[bytes] = '\0';
    CHECK(strstr(text, "<title>A &amp; B &lt;test&gt;</title>") != NULL);
    CHECK(strstr(text, "{\"title\":\"<\\/script><\\!--x\"}") != NULL); /* the description cannot close its element */
    CHECK(strstr(text, "console.log('a</b>');") != NULL);
    /* each blob back */
    const void *want[2] = {xyz, codes};
    size_t want_n[2] = {sizeof xyz, sizeof codes};
    for (int k = 0; k < 2; k++) {
        char id[160];
        snprintf(id, sizeof id, "id=\"thorax-blob-%d\" data-compression=\"%s\" data-bytes=\"%zu\">", k,
                 k == 0 ? "deflate-raw" : "none", want_n[k]);
        const char *s = strstr(text, id);
        CHECK(s != NULL);
        if (!s) continue;
        s += strlen(id);
        const char *e = strstr(s, "</script>");
        size_t n = 0;
        unsigned char *raw = unbase64(s, e, &n), *back = NULL;
        if (k == 0) {
            CHECK_OK(ctx, thx_web_inflate(ctx, raw, n, want_n[k], &back));
            CHECK(back && memcmp(back, want[k], want_n[k]) == 0);
        } else
            CHECK(n == want_n[k] && memcmp(raw, want[k], n) == 0);
        free(back);
        free(raw);
    }
    free(text);
    /* the page again over itself: thorax's own, replaced */
    CHECK_OK(ctx, thx_web_page_write(ctx, p, path, "t", "{}", viewer, strlen(viewer), NULL, 0, NULL));
    /* a file thorax did not write is left alone, and nothing is half-written beside it */
    const char *foreign = tl_path("notes.html");
    tl_write_text(foreign, "<html>my notes</html>\n");
    CHECK(thx_web_page_write(ctx, p, foreign, "t", "{}", viewer, strlen(viewer), NULL, 0, NULL) != THX_OK);
    f = fopen(foreign, "rb");
    char buf[64] = "";
    CHECK(f && fgets(buf, sizeof buf, f) && !strcmp(buf, "<html>my notes</html>\n"));
    if (f) fclose(f);
    CHECK(!tl_leftover_tmp("notes"));
    /* a viewer that would end its own script element, and none at all */
    const char *bad = "var s = '</SCRIPT>';";
    CHECK(thx_web_page_write(ctx, p, tl_path("bad.html"), "t", "{}", bad, strlen(bad), NULL, 0, NULL) == THX_EINTERNAL);
    CHECK(thx_web_page_write(ctx, p, tl_path("none.html"), "t", "{}", NULL, 0, NULL, 0, NULL) == THX_EINPUT &&
          tl_msg_has(ctx, "without the page's viewer"));
    CHECK(!tl_exists(tl_path("bad.html")) && !tl_exists(tl_path("none.html")));
    thx_web_page_free(&p);
    CHECK(p == NULL);
}

int main(void)
{
    thx_ctx *ctx = NULL;
    if (thx_ctx_create(&ctx) != THX_OK || tl_scratch_make("test_web")) return 1;
    quantize(ctx);
    codecs(ctx);
    page(ctx);
    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("test_web");
}
