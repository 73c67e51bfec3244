/* DICOM series read through GDCM (src/image/dicom.c, dicom_gdcm.cc), on series written by GDCM's own
 * tools, not by thorax: each slice's pixels are raw int16 bytes that `gdcmimg` wraps as a CT image,
 * `gdcmanon --dumb --replace` sets its geometry and rescale tags, `gdcmconv --jpeg` recompresses
 * (lossless JPEG). The volume and its RAS geometry are known here, so the read-back is compared voxel
 * for voxel, with the origin, directions and spacing the construction implies (an oblique grid, the
 * two in-plane spacings different, shuffled file names, slope/intercept differing per slice).
 * Then: two series in one folder (listed; picked by number and by UID; a file picks its own), and
 * the refusals: gantry tilt, positions off one line, uneven spacing, a missing slice, two slices at one position, an
 * orientation differing within the series, a truncated slice (pixel data and header), naming files;
 * one slice cut at every eleventh length, each refused naming the file (none accepted, the test process
 * never dies); a 2048 x 2048 slice (8 MB of pixels through the socket, larger than its buffer), read
 * whole under the default memory limit of the helper and refused under 40 MB; reads interrupted by
 * a 1 ms interval timer (EINTR); no child left unreaped.
 * The helper program's replies are not trusted (src/image/dicom.c): this program is also a fake
 * helper (run with --protocol, THORAX_DICOM_HELPER pointing at it, the fault chosen by THX_FAKE)
 * that speaks the protocol of src/image/dicom.h and breaks it one way at a time: each break is a
 * refusal naming the file and what was wrong, a hung helper is stopped after THORAX_DICOM_SECONDS,
 * and one that has shut its socket leaves EPIPE, not a SIGPIPE that would end this process. */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "image/dicom.h"
#include "testlib.h"
#include "thorax/core/sha256.h"
#include "thorax/image/image.h"

#define MAXS 16

typedef struct {
    const char *folder;         /* folder under the scratch folder */
    const char *uid;            /* SeriesInstanceUID */
    int number;                 /* SeriesNumber */
    const char *desc;           /* SeriesDescription */
    size_t n[3];                /* columns, rows, slices */
    double origin[3];           /* RAS of voxel (0,0,0) */
    double dir[9];              /* RAS directions, row-major, columns i, j, k (right-handed) */
    double spacing[3];          /* along i (between columns), along j (between rows), between slices */
    double gap[MAXS];           /* per step gap (0: spacing[2]) */
    double tilt_deg;            /* each step shifted along the row direction by gap * tan(tilt) */
    int skip;                   /* slice left out (-1: none) */
    int duplicate;              /* slice 2 placed at slice 1's position */
    int odd_orientation;        /* slice 1 rotated by 2 degrees in its plane */
    double zig;                 /* slice 2 shifted by this many mm along the row direction */
    double slope_base;          /* slope of slice k: slope_base + (k % 2) (0: 1 + k % 2) */
    double inter_base;          /* intercept of slice k: inter_base + 3k */
    char files[MAXS][64];       /* file name of slice k (position order) */
} spec;

static int16_t stored_value(size_t i, size_t j, size_t k) { return (int16_t)((i * 37 + j * 101 + k * 211) % 1500) - 700; }
static double slope_of(const spec *s, size_t k) { return (s->slope_base != 0 ? s->slope_base : 1) + (double)(k % 2); }
static double inter_of(const spec *s, size_t k) { return s->inter_base + 3.0 * (double)k; }

static int run(const char *cmd)
{
    int rc = system(cmd);
    if (rc != 0) fprintf(stderr, "command failed (%d): %s\n", rc, cmd);
    return rc;
}

/* The slice files of *s, by GDCM's tools; 0 or -1. */
static int write_series(spec *s)
{
    char d[1200];
    snprintf(d, sizeof d, "%s", tl_path(s->folder));
    mkdir(d, 0755);
    const double flip[3] = {-1, -1, 1};
    double pos[3] = {s->origin[0], s->origin[1], s->origin[2]};
    for (size_t k = 0; k < s->n[2]; k++) {
        if (k > 0) {
            double g = s->gap[k - 1] > 0 ? s->gap[k - 1] : s->spacing[2];
            double shift = g * tan(s->tilt_deg * M_PI / 180);
            for (int a = 0; a < 3; a++) pos[a] += g * s->dir[a * 3 + 2] + shift * s->dir[a * 3 + 0];
        }
        /* shuffled names: not the position order */
        snprintf(s->files[k], sizeof s->files[k], "%08x.dcm", (unsigned)((k + 1) * 2654435761u ^ (unsigned)s->number * 0x9e3779b9u));
        if ((int)k == s->skip) continue;
        size_t plane = s->n[0] * s->n[1];
        int16_t *px = malloc(plane * sizeof *px);
        for (size_t j = 0; j < s->n[1]; j++)
            for (size_t i = 0; i < s->n[0]; i++) px[i + s->n[0] * j] = stored_value(i, j, k);
        const char *raw = tl_path("slice.raw");
        tl_write_bytes(raw, px, plane * sizeof *px);
        free(px);
        double row[3], col[3], p[3];
        double a = s->odd_orientation && k == 1 ? 2 * M_PI / 180 : 0;
        for (int c = 0; c < 3; c++) {
            double ri = s->dir[c * 3 + 0], cj = s->dir[c * 3 + 1];
            row[c] = flip[c] * (cos(a) * ri + sin(a) * cj);
            col[c] = flip[c] * (-sin(a) * ri + cos(a) * cj);
            p[c] = flip[c] * (s->duplicate && k == 2 ? pos[c] - s->spacing[2] * s->dir[c * 3 + 2] : pos[c]);
            if (k == 2) p[c] += flip[c] * s->zig * s->dir[c * 3 + 0];
        }
        char cmd[4096];
        snprintf(cmd, sizeof cmd,
                 "gdcmimg --size %zu,%zu --depth 16 --sign 1 -C 1.2.840.10008.5.1.4.1.1.2 -S %s -T 1.2.826.0.1.3680043.9.7.1 "
                 "-i '%s' -o '%s' && "
                 "gdcmanon --dumb --replace '0020,0032=%.10g\\%.10g\\%.10g' --replace '0020,0037=%.10g\\%.10g\\%.10g\\%.10g\\%.10g\\%.10g' "
                 "--replace '0028,0030=%.10g\\%.10g' --replace '0028,1053=%.10g' --replace '0028,1052=%.10g' "
                 "--replace '0008,0060=CT' --replace '0020,0011=%d' --replace '0008,103e=%s' --replace '0018,0050=9' "
                 "-i '%s' -o '%s/%s'",
                 s->n[0], s->n[1], s->uid, raw, tl_path("slice0.dcm"), p[0], p[1], p[2], row[0], row[1], row[2], col[0],
                 col[1], col[2], s->spacing[1], s->spacing[0], slope_of(s, k), inter_of(s, k), s->number, s->desc,
                 tl_path("slice0.dcm"), d, s->files[k]);
        if (run(cmd) != 0) return -1;
    }
    return 0;
}

static void base_spec(spec *s, const char *dir, const char *uid, int number, const char *desc)
{
    memset(s, 0, sizeof *s);
    s->folder = dir, s->uid = uid, s->number = number, s->desc = desc;
    s->n[0] = 6, s->n[1] = 5, s->n[2] = 7;
    /* an oblique grid: rotation by 20 degrees about RAS x, then 10 about z; spacings 0.6, 0.8, 2.5 */
    double a = 20 * M_PI / 180, b = 10 * M_PI / 180;
    double rx[9] = {1, 0, 0, 0, cos(a), -sin(a), 0, sin(a), cos(a)};
    double rz[9] = {cos(b), -sin(b), 0, sin(b), cos(b), 0, 0, 0, 1};
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            double v = 0;
            for (int q = 0; q < 3; q++) v += rz[r * 3 + q] * rx[q * 3 + c];
            s->dir[r * 3 + c] = v;
        }
    s->spacing[0] = 0.6, s->spacing[1] = 0.8, s->spacing[2] = 2.5;
    s->origin[0] = -40.25, s->origin[1] = 12.5, s->origin[2] = 101.75;
    s->skip = -1;
    s->inter_base = -1000;
}

/* The image read against the spec: values, geometry in RAS, the SHA-256 rule. */
static void check_image(const spec *s, const thx_image *img, int integral)
{
    CHECK(img->n[0] == s->n[0] && img->n[1] == s->n[1] && img->n[2] == s->n[2]);
    if (img->n[0] != s->n[0] || img->n[1] != s->n[1] || img->n[2] != s->n[2]) return;
    size_t bad = 0;
    for (size_t k = 0; k < s->n[2]; k++)
        for (size_t j = 0; j < s->n[1]; j++)
            for (size_t i = 0; i < s->n[0]; i++) {
                float want = (float)(slope_of(s, k) * stored_value(i, j, k) + inter_of(s, k));
                if (img->v[thx_image_at(img, i, j, k)] != want && bad++ < 3)
                    fprintf(stderr, "voxel (%zu, %zu, %zu): %g, want %g\n", i, j, k, img->v[thx_image_at(img, i, j, k)],
                            want);
            }
    CHECK(bad == 0);
    for (int c = 0; c < 3; c++) {
        CHECK_NEAR(img->spacing[c], s->spacing[c], 1e-6);
        CHECK_NEAR(img->origin[c], s->origin[c], 1e-6);
    }
    for (int q = 0; q < 9; q++) CHECK_NEAR(img->dir[q], s->dir[q], 1e-6);
    /* the far corner voxel where the construction put it */
    double ijk[3] = {(double)s->n[0] - 1, (double)s->n[1] - 1, (double)s->n[2] - 1}, ras[3];
    thx_image_index_to_ras(img, ijk, ras);
    for (int r = 0; r < 3; r++) {
        double want = s->origin[r];
        for (int c = 0; c < 3; c++) want += s->dir[r * 3 + c] * s->spacing[c] * ijk[c];
        CHECK_NEAR(ras[r], want, 1e-6);
    }
    CHECK(strcmp(img->format, "dicom") == 0);
    CHECK(strcmp(img->source_frame, "LPS (DICOM patient)") == 0);
    CHECK(strcmp(img->stored_type, "int16") == 0);
    CHECK(img->integral == integral);
    /* sha256: of the slice files' hex digests in position order */
    char *cat = malloc(64 * s->n[2] + 1);
    thx_ctx *c2 = NULL;
    thx_ctx_create(&c2);
    for (size_t k = 0; k < s->n[2]; k++) {
        char f[1200], hex[65] = "";
        snprintf(f, sizeof f, "%s/%s", tl_path(s->folder), s->files[k]);
        CHECK_OK(c2, thx_sha256_file(c2, f, hex));
        memcpy(cat + 64 * k, hex, 64);
    }
    char want[65];
    thx_sha256_hex(cat, 64 * s->n[2], want);
    CHECK(strcmp(img->sha256, want) == 0);
    free(cat);
    thx_ctx_destroy(&c2);
}

/* ---- the fake helper (this program run with --protocol): THX_FAKE names the fault ---- */

static void fake_write(const void *b, size_t n)
{
    const char *p = b;
    while (n > 0) {
        ssize_t w = write(3, p, n);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) _exit(1);
        p += w;
        n -= (size_t)w;
    }
}
static int fake_read(void *b, size_t n)
{
    char *p = b;
    while (n > 0) {
        ssize_t r = read(3, p, n);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) return 0;
        p += r;
        n -= (size_t)r;
    }
    return 1;
}
static void fake_put(unsigned char *b, size_t *n, const void *v, size_t len)
{
    memcpy(b + *n, v, len);
    *n += len;
}
static void fake_u32(unsigned char *b, size_t *n, uint32_t v) { fake_put(b, n, &v, 4); }
static void fake_f64(unsigned char *b, size_t *n, double v) { fake_put(b, n, &v, 8); }
static void fake_str(unsigned char *b, size_t *n, const char *s)
{
    uint16_t len = (uint16_t)strlen(s);
    fake_put(b, n, &len, 2);
    fake_put(b, n, s, len);
}
static void fake_head(uint32_t op, int32_t status, uint64_t len)
{
    unsigned char h[16];
    memcpy(h, &op, 4);
    memcpy(h + 4, &status, 4);
    memcpy(h + 8, &len, 8);
    fake_write(h, 16);
}

/* Two slices, s1.dcm and s2.dcm (k = 0, 1): 3 x 2 pixels 10k + q (int16), at z = 2k mm, intercept
 * 100k; everything else as a real helper would say it, but for the fault. */
static int fake_helper(void)
{
    const char *mode = getenv("THX_FAKE");
    if (!mode) mode = "ok";
#define IS(m) (strcmp(mode, m) == 0)
    if (IS("epipe")) shutdown(3, SHUT_RD); /* the parent's next send meets a closed socket */
    unsigned char hello[12];
    uint32_t v = IS("version") ? THX_DICOM_PROTOCOL + 1 : THX_DICOM_PROTOCOL;
    memcpy(hello, IS("greeting") ? "NOTDICOM" : THX_DICOM_HELLO, 8);
    memcpy(hello + 8, &v, 4);
    fake_write(hello, 12);
    if (IS("epipe")) {
        struct timespec nap = {0, 200000000};
        nanosleep(&nap, NULL);
        _exit(0);
    }
    for (;;) {
        uint32_t req[4];
        char path[THX_DICOM_MAX_PATH + 1];
        if (!fake_read(req, 16) || req[3] > THX_DICOM_MAX_PATH || !fake_read(path, req[3])) _exit(0);
        path[req[3]] = '\0';
        int k = strstr(path, "s2.dcm") != NULL;
        if (req[0] == THX_DICOM_OP_SCAN) {
            if (IS("abort_scan")) abort();
            unsigned char b[2048];
            size_t n = 0;
            char longer[200];
            memset(longer, '7', sizeof longer - 1);
            longer[sizeof longer - 1] = '\0';
            fake_str(b, &n, IS("long_string") ? longer : "1.2.826.0.1.3680043.9.7.77");
            fake_str(b, &n, "1");
            fake_str(b, &n, "fake");
            fake_str(b, &n, "CT");
            fake_u32(b, &n, IS("flag") ? 2 : 1); /* image */
            fake_u32(b, &n, 1);                  /* frames */
            for (int q = 0; q < 3; q++) fake_u32(b, &n, 1);
            fake_f64(b, &n, 0);
            fake_f64(b, &n, 0);
            fake_f64(b, &n, IS("nan") ? NAN : 2.0 * k);
            const double o[6] = {1, 0, 0, 0, 1, 0};
            for (int q = 0; q < 6; q++) fake_f64(b, &n, o[q]);
            fake_f64(b, &n, 0.5);
            fake_f64(b, &n, 0.5);
            fake_f64(b, &n, 2);       /* thickness */
            fake_f64(b, &n, 1);       /* slope */
            fake_f64(b, &n, 100.0 * k); /* intercept */
            fake_u32(b, &n, 2);       /* rows */
            fake_u32(b, &n, 3);       /* columns */
            if (IS("leftover")) fake_u32(b, &n, 0);
            fake_head(IS("wrong_op") ? THX_DICOM_OP_PIXELS : req[0], IS("bad_status") ? 7 : 1,
                      IS("scan_len_huge") ? (uint64_t)1 << 40 : n);
            if (IS("short_reply")) {
                fake_write(b, n / 2);
                _exit(0);
            }
            fake_write(b, n);
        } else {
            if (IS("hang")) sleep(30);
            if (IS("message")) {
                const char m[] = "fake: no pixels\x01\x1b[31m here";
                fake_head(req[0], -1, sizeof m - 1);
                fake_write(m, sizeof m - 1);
                continue;
            }
            uint32_t ph[3] = {IS("bad_type") ? 9 : THX_DICOM_T_INT16, IS("wrong_size") ? req[2] : req[1],
                              IS("wrong_size") ? req[1] : req[2]};
            int16_t px[6];
            for (int q = 0; q < 6; q++) px[q] = (int16_t)(10 * k + q);
            fake_head(req[0], 0, IS("pixel_len_huge") ? 12 + ((uint64_t)1 << 40) : 12 + sizeof px);
            fake_write(ph, 12);
            fake_write(px, sizeof px);
        }
    }
#undef IS
}

/* Reads path expecting `code` and a message holding each of the needles. */
static void refused_as(thx_ctx *ctx, const char *path, thx_status code, const char *const *needles)
{
    thx_image img;
    thx_status s = thx_image_read(ctx, path, NULL, &img);
    CHECK(s == code);
    if (s != code) fprintf(stderr, "status %d, expected %d: %s\n", s, code, thx_ctx_message(ctx));
    CHECK(img.v == NULL);
    for (; *needles; needles++) CHECK(tl_msg_has(ctx, *needles));
}

static volatile sig_atomic_t ticks;
static void tick(int sig)
{
    (void)sig;
    ticks++;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Reads path expecting THX_EINPUT and a message holding each of the needles (NULL-terminated). */
static void refused(thx_ctx *ctx, const char *path, const char *series, const char *const *needles)
{
    thx_image img;
    thx_image_read_opts o = {.series = series};
    CHECK(thx_image_read(ctx, path, &o, &img) == THX_EINPUT);
    CHECK(img.v == NULL);
    for (; *needles; needles++) CHECK(tl_msg_has(ctx, *needles));
}

int main(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "--protocol") == 0) return fake_helper();
    if (tl_scratch_make("test_image_dicom") != 0) return 1;
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);
    thx_image img;

    /* series A: oblique, shuffled names, slope 1 or 2 and intercept -1000 + 3k per slice */
    spec a;
    base_spec(&a, "a", "1.2.826.0.1.3680043.9.7.11", 3, "alpha");
    if (write_series(&a) != 0) return tl_scratch_finish("test_image_dicom");
    tl_write_text(tl_path("a/notes.txt"), "not DICOM: skipped\n");
    CHECK_OK(ctx, thx_image_read(ctx, tl_path("a"), NULL, &img));
    check_image(&a, &img, 1);
    char sha_a[65];
    snprintf(sha_a, sizeof sha_a, "%s", img.sha256);
    thx_image_free(&img);
    /* one file of the series reads the whole series */
    char one[1200];
    snprintf(one, sizeof one, "%s/%s", tl_path("a"), a.files[4]);
    CHECK_OK(ctx, thx_image_read(ctx, one, NULL, &img));
    check_image(&a, &img, 1);
    CHECK(strcmp(img.sha256, sha_a) == 0);
    thx_image_free(&img);

    /* the same series recompressed by GDCM (lossless JPEG): the same voxels */
    mkdir(tl_path("jpeg"), 0755);
    for (size_t k = 0; k < a.n[2]; k++) {
        char cmd[3000];
        snprintf(cmd, sizeof cmd, "gdcmconv --jpeg '%s/%s' '%s/%s'", tl_path("a"), a.files[k], tl_path("jpeg"), a.files[k]);
        CHECK(run(cmd) == 0);
    }
    char cmd[3000];
    snprintf(cmd, sizeof cmd, "gdcmdump '%s/%s' | grep -q 1.2.840.10008.1.2.4.70", tl_path("jpeg"), a.files[0]);
    CHECK(run(cmd) == 0); /* JPEG Lossless, first-order prediction */
    CHECK_OK(ctx, thx_image_read(ctx, tl_path("jpeg"), NULL, &img));
    spec aj = a;
    aj.folder = "jpeg";
    check_image(&aj, &img, 1);
    thx_image_free(&img);

    /* fractional rescale: not integral */
    spec f;
    base_spec(&f, "frac", "1.2.826.0.1.3680043.9.7.12", 1, "fraction");
    f.n[2] = 3, f.slope_base = 0.5, f.inter_base = 0.25;
    CHECK(write_series(&f) == 0);
    CHECK_OK(ctx, thx_image_read(ctx, tl_path("frac"), NULL, &img));
    check_image(&f, &img, 0);
    thx_image_free(&img);

    /* two series in one folder: A (number 3) and B (number 2: listed first) */
    spec b;
    base_spec(&b, "two", "1.2.826.0.1.3680043.9.7.13", 2, "beta");
    b.n[0] = 4, b.n[1] = 3, b.n[2] = 3;
    memset(b.dir, 0, sizeof b.dir);
    b.dir[0] = b.dir[4] = b.dir[8] = 1;
    CHECK(write_series(&b) == 0);
    spec a2 = a;
    a2.folder = "two";
    CHECK(write_series(&a2) == 0);
    refused(ctx, tl_path("two"), NULL,
            (const char *const[]){"2 DICOM series", "--series", "1: 1.2.826.0.1.3680043.9.7.13", "\"beta\"", "3 slices of 3 x 4",
                                  "2: 1.2.826.0.1.3680043.9.7.11", "\"alpha\"", "7 slices of 5 x 6", "CT", NULL});
    thx_image_read_opts o = {.series = "1"};
    CHECK_OK(ctx, thx_image_read(ctx, tl_path("two"), &o, &img));
    check_image(&b, &img, 1);
    thx_image_free(&img);
    o.series = "2";
    CHECK_OK(ctx, thx_image_read(ctx, tl_path("two"), &o, &img));
    check_image(&a2, &img, 1);
    thx_image_free(&img);
    o.series = "1.2.826.0.1.3680043.9.7.11";
    CHECK_OK(ctx, thx_image_read(ctx, tl_path("two"), &o, &img));
    check_image(&a2, &img, 1);
    thx_image_free(&img);
    o.series = "1.2.826.0.1.3680043.9.7.13";
    CHECK_OK(ctx, thx_image_read(ctx, tl_path("two"), &o, &img));
    check_image(&b, &img, 1);
    thx_image_free(&img);
    snprintf(one, sizeof one, "%s/%s", tl_path("two"), b.files[1]);
    CHECK_OK(ctx, thx_image_read(ctx, one, NULL, &img)); /* a file: its own series, no choice needed */
    check_image(&b, &img, 1);
    thx_image_free(&img);
    refused(ctx, tl_path("two"), "3", (const char *const[]){"no series \"3\"", "\"alpha\"", NULL});
    refused(ctx, tl_path("two"), "1.2.3", (const char *const[]){"no series \"1.2.3\"", NULL});

    /* gantry tilt: 0.3 degrees is within the tolerance, 2 degrees is refused */
    spec t;
    base_spec(&t, "tilt03", "1.2.826.0.1.3680043.9.7.14", 1, "tilt");
    t.n[2] = 4, t.tilt_deg = 0.3;
    CHECK(write_series(&t) == 0);
    CHECK_OK(ctx, thx_image_read(ctx, tl_path("tilt03"), NULL, &img));
    thx_image_free(&img);
    base_spec(&t, "tilt2", "1.2.826.0.1.3680043.9.7.15", 1, "tilt");
    t.n[2] = 4, t.tilt_deg = 2;
    CHECK(write_series(&t) == 0);
    refused(ctx, tl_path("tilt2"), NULL, (const char *const[]){"leans 2.00 degrees off", "gantry tilt", t.files[0], t.files[3], NULL});

    /* positions off one line: the middle slice shifted by half a pixel in its plane */
    spec z;
    base_spec(&z, "zig", "1.2.826.0.1.3680043.9.7.20", 1, "zig");
    z.n[2] = 5, z.zig = 0.3;
    CHECK(write_series(&z) == 0);
    refused(ctx, tl_path("zig"), NULL, (const char *const[]){"0.3 mm off the line", "not one stack", z.files[2], z.files[0], z.files[4], NULL});

    /* uneven spacing: one gap 2.8 mm among 2.5 */
    spec u;
    base_spec(&u, "uneven", "1.2.826.0.1.3680043.9.7.16", 1, "uneven");
    u.n[2] = 6, u.gap[2] = 2.8;
    CHECK(write_series(&u) == 0);
    refused(ctx, tl_path("uneven"), NULL,
            (const char *const[]){"2.8 mm between the slices", "median gap is 2.5 mm", "uneven spacing", u.files[2],
                                  u.files[3], NULL});

    /* a missing middle slice */
    spec m;
    base_spec(&m, "missing", "1.2.826.0.1.3680043.9.7.17", 1, "missing");
    m.n[2] = 6, m.skip = 3;
    CHECK(write_series(&m) == 0);
    refused(ctx, tl_path("missing"), NULL,
            (const char *const[]){"5 mm between the slices", "a slice missing?", m.files[2], m.files[4], NULL});

    /* two slices at one position */
    spec dup;
    base_spec(&dup, "dup", "1.2.826.0.1.3680043.9.7.18", 1, "dup");
    dup.n[2] = 4, dup.duplicate = 1;
    CHECK(write_series(&dup) == 0);
    refused(ctx, tl_path("dup"), NULL, (const char *const[]){"two slices at one position", dup.files[1], dup.files[2], NULL});

    /* an orientation differing within the series */
    spec odd;
    base_spec(&odd, "odd", "1.2.826.0.1.3680043.9.7.19", 1, "odd");
    odd.n[2] = 4, odd.odd_orientation = 1;
    CHECK(write_series(&odd) == 0);
    refused(ctx, tl_path("odd"), NULL, (const char *const[]){"ImageOrientationPatient", "differs from", odd.files[1], NULL});

    /* a truncated slice: pixel data cut short, then a header cut short; each named */
    snprintf(cmd, sizeof cmd, "cp -r '%s' '%s' && cp -r '%s' '%s'", tl_path("a"), tl_path("cut"), tl_path("a"), tl_path("cuthead"));
    CHECK(run(cmd) == 0);
    char victim[1200];
    snprintf(victim, sizeof victim, "%s/%s", tl_path("cut"), a.files[3]);
    struct stat st;
    CHECK(stat(victim, &st) == 0);
    CHECK(truncate(victim, st.st_size - 7) == 0);
    refused(ctx, tl_path("cut"), NULL, (const char *const[]){victim, "truncated", NULL});
    snprintf(victim, sizeof victim, "%s/%s", tl_path("cuthead"), a.files[5]);
    CHECK(truncate(victim, 200) == 0);
    refused(ctx, tl_path("cuthead"), NULL, (const char *const[]){victim, "truncated or corrupt", NULL});

    /* one slice cut at every eleventh length (and each of the last ten), alone in its folder: every
     * length refused with the file's name, the test process alive throughout */
    {
        char src[1200];
        snprintf(src, sizeof src, "%s/%s", tl_path("a"), a.files[0]);
        size_t len = 0;
        char *bytes = tl_slurp(ctx, src, &len);
        CHECK(bytes != NULL && len > 100);
        mkdir(tl_path("sweep"), 0755);
        char cut[1200];
        snprintf(cut, sizeof cut, "%s/s.dcm", tl_path("sweep"));
        size_t tried = 0, named = 0;
        double t_sweep = now_s();
        for (size_t l = 0; bytes && l < len; l += (l + 10 >= len ? 1 : 11)) {
            tl_write_bytes(cut, bytes, l);
            thx_status rs = thx_image_read(ctx, cut, NULL, &img);
            tried++;
            if (rs != THX_OK && img.v == NULL && strstr(thx_ctx_message(ctx), cut)) named++;
            else fprintf(stderr, "cut at %zu of %zu bytes: status %d: %s\n", l, len, rs, thx_ctx_message(ctx));
            if (rs == THX_OK) thx_image_free(&img);
        }
        fprintf(stderr, "truncation sweep: %zu of %zu lengths refused naming the file (%.2f s)\n", named, tried, now_s() - t_sweep);
        CHECK(tried > 80 && named == tried);
        free(bytes);
    }

    /* a 2048 x 2048 slice of zeros, RLE-compressed (small file, 8 MB of int16 pixels through the
     * socket): read whole with the default memory limit, refused under a 40 MB address space */
    mkdir(tl_path("big"), 0755);
    {
        int16_t *zeros = calloc((size_t)2048 * 2048, sizeof *zeros);
        tl_write_bytes(tl_path("big.raw"), zeros, (size_t)2048 * 2048 * sizeof *zeros);
        free(zeros);
    }
    snprintf(cmd, sizeof cmd,
             "gdcmimg --size 2048,2048 --depth 16 --sign 1 -C 1.2.840.10008.5.1.4.1.1.2 -i '%s' -o '%s' && "
             "gdcmanon --dumb --replace '0020,0032=0\\0\\0' --replace '0020,0037=1\\0\\0\\0\\1\\0' --replace '0028,0030=0.5\\0.5' "
             "-i '%s' -o '%s' && gdcmconv --rle '%s' '%s/big.dcm'",
             tl_path("big.raw"), tl_path("big0.dcm"), tl_path("big0.dcm"), tl_path("big1.dcm"), tl_path("big1.dcm"), tl_path("big"));
    CHECK(run(cmd) == 0);
    CHECK_OK(ctx, thx_image_read(ctx, tl_path("big"), NULL, &img));
    if (img.v) {
        size_t nonzero = 0;
        for (size_t q = 0; q < thx_image_count(&img); q++) nonzero += img.v[q] != 0;
        CHECK(img.n[0] == 2048 && img.n[1] == 2048 && img.n[2] == 1 && nonzero == 0);
    }
    thx_image_free(&img);
    setenv("THORAX_DICOM_MEMORY_MB", "40", 1);
    {
        thx_image im2;
        CHECK(thx_image_read(ctx, tl_path("big"), NULL, &im2) == THX_EINPUT);
        CHECK(im2.v == NULL);
        CHECK(tl_msg_has(ctx, "big.dcm")); /* GDCM out of memory, or its assert on a failed allocation */
    }
    unsetenv("THORAX_DICOM_MEMORY_MB");

    /* reads under a 1 ms interval timer whose handler interrupts system calls (no SA_RESTART) */
    {
        struct sigaction sa, old;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = tick;
        sigemptyset(&sa.sa_mask);
        sigaction(SIGALRM, &sa, &old);
        struct itimerval it = {{0, 1000}, {0, 1000}}, off = {{0, 0}, {0, 0}};
        setitimer(ITIMER_REAL, &it, NULL);
        CHECK_OK(ctx, thx_image_read(ctx, tl_path("a"), NULL, &img));
        check_image(&a, &img, 1);
        thx_image_free(&img);
        CHECK_OK(ctx, thx_image_read(ctx, tl_path("big"), NULL, &img));
        CHECK(img.n[0] == 2048);
        thx_image_free(&img);
        setitimer(ITIMER_REAL, &off, NULL);
        sigaction(SIGALRM, &old, NULL);
        fprintf(stderr, "interval timer: %d signals during the reads\n", (int)ticks);
        CHECK(ticks > 10);
    }

    /* the fake helper: each break of the protocol refused by name */
    {
        char self[1024];
        ssize_t ns = readlink("/proc/self/exe", self, sizeof self - 1);
        CHECK(ns > 0);
        self[ns > 0 ? ns : 0] = '\0';
        mkdir(tl_path("fake"), 0755);
        tl_write_text(tl_path("fake/s1.dcm"), "the fake helper answers for this file\n");
        tl_write_text(tl_path("fake/s2.dcm"), "and for this one\n");
        char s1[1200];
        snprintf(s1, sizeof s1, "%s/s1.dcm", tl_path("fake"));
        setenv("THORAX_DICOM_HELPER", self, 1);
        setenv("THX_FAKE", "ok", 1);
        CHECK_OK(ctx, thx_image_read(ctx, tl_path("fake"), NULL, &img));
        if (img.v) {
            CHECK(img.n[0] == 3 && img.n[1] == 2 && img.n[2] == 2);
            for (size_t k = 0; k < 2; k++)
                for (size_t q = 0; q < 6; q++) CHECK(img.v[k * 6 + q] == (float)(10 * k + q + 100 * k));
            CHECK_NEAR(img.spacing[2], 2, 1e-12);
            CHECK(strcmp(img.stored_type, "int16") == 0);
        }
        thx_image_free(&img);
        static const struct {
            const char *mode;
            thx_status code;
            const char *needle;
        } faults[] = {
            {"version", THX_EIO, "speaks protocol version 2, this library version 1"},
            {"greeting", THX_EIO, "is not the DICOM helper"},
            {"abort_scan", THX_EINPUT, "its tags cannot be read: GDCM crashed on it (signal 6"},
            {"short_reply", THX_EINPUT, "reply stops short of its"},
            {"long_string", THX_EIO, "garbled (a text longer than its field)"},
            {"scan_len_huge", THX_EIO, "garbled (an entry of impossible length"},
            {"pixel_len_huge", THX_EIO, "garbled (a pixel count that is not rows x columns"},
            {"wrong_size", THX_EIO, "garbled (pixels of another size than asked for"},
            {"bad_type", THX_EIO, "garbled (an unknown stored type"},
            {"nan", THX_EIO, "garbled (a number is not finite)"},
            {"leftover", THX_EIO, "garbled (bytes left over after the entry)"},
            {"bad_status", THX_EIO, "garbled (an unknown status"},
            {"wrong_op", THX_EIO, "garbled (an answer to another request"},
            {"flag", THX_EIO, "garbled (a yes/no field is neither)"},
            {"message", THX_EINPUT, "fake: no pixels??[31m here"},
            {"epipe", THX_EINPUT, "the DICOM helper was gone before the request"},
        };
        for (size_t q = 0; q < sizeof faults / sizeof *faults; q++) {
            setenv("THX_FAKE", faults[q].mode, 1);
            int names_file = strcmp(faults[q].mode, "version") != 0 && strcmp(faults[q].mode, "greeting") != 0;
            refused_as(ctx, tl_path("fake"), faults[q].code,
                       (const char *const[]){faults[q].needle, names_file ? "s1.dcm" : self, NULL});
        }
        /* a helper that hangs: stopped after THORAX_DICOM_SECONDS */
        setenv("THX_FAKE", "hang", 1);
        setenv("THORAX_DICOM_SECONDS", "1", 1);
        double t0 = now_s();
        refused_as(ctx, tl_path("fake"), THX_EINPUT, (const char *const[]){"s1.dcm", "no reply from GDCM within 1 s", NULL});
        double dt = now_s() - t0;
        CHECK(dt >= 0.9 && dt < 10);
        setenv("THORAX_DICOM_SECONDS", "soon", 1);
        refused_as(ctx, tl_path("fake"), THX_EINPUT, (const char *const[]){"THORAX_DICOM_SECONDS=soon", NULL});
        unsetenv("THORAX_DICOM_SECONDS");
        unsetenv("THX_FAKE");
        /* a missing helper */
        setenv("THORAX_DICOM_HELPER", "/nonexistent/thorax-dicom", 1);
        refused_as(ctx, tl_path("a"), THX_EIO, (const char *const[]){"THORAX_DICOM_HELPER=/nonexistent/thorax-dicom", "thorax-dicom", NULL});
        unsetenv("THORAX_DICOM_HELPER");
        /* every helper collected: no child of this process is left, not even a zombie */
        errno = 0;
        CHECK(waitpid(-1, NULL, WNOHANG) == -1 && errno == ECHILD);
    }

    /* a folder with no DICOM image */
    mkdir(tl_path("empty"), 0755);
    tl_write_text(tl_path("empty/readme.txt"), "nothing\n");
    refused(ctx, tl_path("empty"), NULL, (const char *const[]){"no DICOM image", NULL});

    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("test_image_dicom");
}
