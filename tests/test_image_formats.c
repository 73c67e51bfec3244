/* The NRRD and MetaImage readers and writers and the dispatcher (src/image/nrrd.c, metaimage.c, image.c):
 *  - round trips through every format thorax writes (.nrrd, .mha, .nii, .nii.gz) and every voxel type,
 *    on an oblique right-handed grid and a left-handed one: voxels identical, geometry to 1e-14 (NRRD,
 *    MetaImage: decimal text) or float precision (NIfTI);
 *  - hand-written files (zlib here, independent of the writers' code) with known answers: LPS -> RAS
 *    (x and y negated), LAS, scanner-xyz, RAS; spacings without a space; a 2-D plane; every NRRD type
 *    alias; big-endian data; ascii; gzip; a detached .nhdr and .mhd (with byte skip / HeaderSize);
 *    MetaIO's TransformMatrix convention (row c = the direction of index axis c, LPS); ElementSize
 *    as the spacing's fallback; CompressedData with CompressedDataSize;
 *  - bad files refused naming the file (and line): truncated raw, gzip and text data, data longer than
 *    claimed, NaN voxels, zero or negative spacing, a skewed grid, a 4-D or vector image, an unknown
 *    encoding, a misnamed file (NRRD content named .nii), a header line that is not a field;
 *  - the writers: .nhdr / .mhd refused, a file thorax did not write is not replaced, no temporary left. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "testlib.h"
#include "thorax/image/image.h"

/* Geometry to tol (relative for spacing, mm for the origin) and voxels identical. */
static int same_image(const thx_image *a, const thx_image *b, double tol)
{
    int ok = 1;
    for (int c = 0; c < 3; c++) {
        ok &= a->n[c] == b->n[c];
        ok &= fabs(a->spacing[c] - b->spacing[c]) <= tol * a->spacing[c];
        ok &= fabs(a->origin[c] - b->origin[c]) <= tol * 100;
    }
    for (int k = 0; k < 9; k++) ok &= fabs(a->dir[k] - b->dir[k]) <= tol;
    if (!ok) {
        fprintf(stderr, "geometry differs: spacing %g %g %g vs %g %g %g, origin %g %g %g vs %g %g %g\n", a->spacing[0],
                a->spacing[1], a->spacing[2], b->spacing[0], b->spacing[1], b->spacing[2], a->origin[0], a->origin[1],
                a->origin[2], b->origin[0], b->origin[1], b->origin[2]);
        return 0;
    }
    size_t count = thx_image_count(a);
    for (size_t q = 0; q < count; q++)
        if (a->v[q] != b->v[q]) {
            fprintf(stderr, "voxel %zu: %g vs %g\n", q, a->v[q], b->v[q]);
            return 0;
        }
    return 1;
}

/* header text + data bytes into a file */
static void write_file(const char *path, const char *head, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f) exit(1);
    fwrite(head, 1, strlen(head), f);
    if (n) fwrite(data, 1, n, f);
    fclose(f);
}

/* 24 int16 values 0..23 * 100 - 1000 (a 4 x 3 x 2 grid), little or big endian */
static void int16_bytes(unsigned char *b, int big)
{
    for (int q = 0; q < 24; q++) {
        int16_t v = (int16_t)(q * 100 - 1000);
        uint16_t u = (uint16_t)v;
        b[2 * q + (big ? 1 : 0)] = (unsigned char)(u & 0xff);
        b[2 * q + (big ? 0 : 1)] = (unsigned char)(u >> 8);
    }
}

static int int16_voxels_ok(const thx_image *img)
{
    if (thx_image_count(img) != 24) return 0;
    for (int q = 0; q < 24; q++)
        if (img->v[q] != (float)(q * 100 - 1000)) return 0;
    return 1;
}

/* Reads `path` and expects a refusal whose message holds `needle`. */
static int refused(thx_ctx *ctx, const char *path, const char *needle)
{
    thx_image img;
    thx_status s = thx_image_read(ctx, path, NULL, &img);
    if (s == THX_OK) {
        fprintf(stderr, "%s: accepted, expected a refusal with \"%s\"\n", path, needle);
        thx_image_free(&img);
        return 0;
    }
    return img.v == NULL && tl_msg_has(ctx, needle);
}

/* ---- the round trips' table: every format thorax writes x every voxel type x grid orientation */
typedef struct {
    const char *suffix, *format;
    double tol; /* NRRD and MetaImage: geometry as decimal text of 17 digits; NIfTI: as float32 */
} rt_format;
static const rt_format FORMATS[] = {
    {".nrrd", "nrrd", 1e-14}, {".mha", "metaimage", 1e-14}, {".nii", "nifti1", 2e-7}, {".nii.gz", "nifti1", 2e-7}};

typedef struct {
    const char *type;
    int integral;
    double lo, hi; /* the values filled in include both (integers: the type's whole range, int32 as far as
                      a float holds every integer) */
} rt_dtype;
static const rt_dtype DTYPES[] = {{"uint8", 1, 0, 255},
                                  {"int16", 1, -32768, 32767},
                                  {"uint16", 1, 0, 65535},
                                  {"int32", 1, -16777216, 16777216},
                                  {"float32", 0, -3.0e38, 3.0e38}};

typedef struct {
    const char *name;
    double about_z, about_x; /* degrees: the rotation about z, then about x */
    int negate;              /* an index axis whose direction is negated (a left-handed grid), or -1 */
} rt_orient;
static const rt_orient ORIENTS[] = {{"axis-aligned", 0, 0, -1},
                                    {"oblique right-handed", 20, 35, -1},
                                    {"oblique left-handed (j negated)", 20, 35, 1},
                                    {"oblique left-handed (k negated)", -50, 110, 2},
                                    {"axis-aligned left-handed (i negated)", 0, 0, 0}};

/* The values of a type: the first two voxels its lo and hi, then integers spread over the range
 * (integral types) or fractions, signs and magnitudes a float holds exactly (float32). */
static void fill(thx_image *img, const rt_dtype *t)
{
    size_t count = thx_image_count(img);
    for (size_t q = 0; q < count; q++) {
        double v;
        if (q < 2) v = q ? t->hi : t->lo;
        else if (t->integral) v = t->lo + floor((double)((q * 37) % 251) / 250 * (t->hi - t->lo));
        else v = (0.125 * (double)q - 3.5) * (q % 3 == 0 ? 1e-20 : q % 3 == 1 ? 1.0 : 1e20);
        img->v[q] = (float)v;
    }
    img->integral = t->integral;
}

/* The grid of an orientation: 11 x 6 x 5 voxels of 0.7 x 1.3 x 2.9 mm, an origin off the axes. */
static thx_status oriented_grid(thx_ctx *ctx, const rt_orient *o, thx_image *img)
{
    size_t n[3] = {11, 6, 5};
    thx_status st = thx_image_alloc(ctx, n, img);
    if (st) return st;
    double a = o->about_z * M_PI / 180, b = o->about_x * M_PI / 180;
    double Rz[9] = {cos(a), -sin(a), 0, sin(a), cos(a), 0, 0, 0, 1};
    double Rx[9] = {1, 0, 0, 0, cos(b), -sin(b), 0, sin(b), cos(b)};
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            double s = 0;
            for (int k = 0; k < 3; k++) s += Rx[r * 3 + k] * Rz[k * 3 + c];
            img->dir[r * 3 + c] = c == o->negate ? -s : s;
        }
    img->spacing[0] = 0.7, img->spacing[1] = 1.3, img->spacing[2] = 2.9;
    img->origin[0] = -101.5, img->origin[1] = 37.25, img->origin[2] = -0.125;
    return THX_OK;
}

/* The determinant of a direction matrix (row-major, columns the index axes). */
static double det3(const double *m)
{
    return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
}

/* One round trip: written as `t`, read back the same (geometry to the format's tolerance, voxels
 * identical, the stored type, integral, a checksum, the format); written again over itself (thorax's
 * own file: the marker) and read back the same again. */
static void round_trip(thx_ctx *ctx, const thx_image *img, const rt_orient *o, const rt_dtype *t, const rt_format *f)
{
    char name[96];
    snprintf(name, sizeof name, "rt_%d_%s%s", (int)(o - ORIENTS), t->type, f->suffix);
    const char *p = tl_path(name);
    for (int pass = 0; pass < 2; pass++) {
        thx_image in;
        thx_status st = thx_image_write(ctx, img, p, t->type);
        CHECK_OK(ctx, st);
        if (st) {
            fprintf(stderr, "  writing %s (%s)\n", name, o->name);
            return;
        }
        CHECK_OK(ctx, thx_image_read(ctx, p, NULL, &in));
        if (!in.v) return;
        int same = same_image(img, &in, f->tol);
        CHECK(same);
        if (!same) fprintf(stderr, "  in %s (%s, pass %d)\n", name, o->name, pass + 1);
        CHECK((det3(in.dir) < 0) == (o->negate >= 0)); /* the handedness kept */
        CHECK(strcmp(in.stored_type, t->type) == 0);
        CHECK(in.integral == t->integral);
        CHECK(strlen(in.sha256) == 64);
        CHECK(strcmp(in.format, f->format) == 0);
        /* the second pass writes what was read: over thorax's own file */
        if (pass == 0) {
            CHECK_OK(ctx, thx_image_write(ctx, &in, p, t->type));
            thx_image again;
            CHECK_OK(ctx, thx_image_read(ctx, p, NULL, &again));
            if (again.v) CHECK(same_image(&in, &again, f->tol));
            thx_image_free(&again);
        }
        thx_image_free(&in);
    }
}

/* ---- the stored types of the hand-written files: a name (a NRRD type alias, a MetaIO ElementType),
 * its size in bytes, 'i' an integer or 'f' an IEEE float of that size */
typedef struct {
    const char *name;
    int size;
    char kind;
} stored_type;

/* For each type of the table: a 2 x 2 plane of the values 1 2 3 4 stored little-endian as it, after the
 * header head_fmt (its %s the type's name), written to `file` and read back: 2 x 2 x 1, the values,
 * spacings 0.5 0.25 1, the normal +z, the given origin, integral for the integers alone. Returns
 * whether every type did (each one that did not is named). */
static int decodes_1234(thx_ctx *ctx, const char *file, const char *head_fmt, const stored_type *types, size_t n,
                        const double *origin)
{
    int all = 1;
    for (size_t k = 0; k < n; k++) {
        const stored_type *t = &types[k];
        unsigned char d[32];
        memset(d, 0, sizeof d);
        for (int q = 0; q < 4; q++) {
            if (t->kind == 'f' && t->size == 4) {
                float f = (float)(q + 1);
                memcpy(d + 4 * q, &f, 4);
            } else if (t->kind == 'f') {
                double f = q + 1;
                memcpy(d + 8 * q, &f, 8);
            } else {
                d[t->size * q] = (unsigned char)(q + 1);
            }
        }
        char head[512];
        snprintf(head, sizeof head, head_fmt, t->name);
        write_file(tl_path(file), head, d, (size_t)(4 * t->size));
        thx_image a;
        if (thx_image_read(ctx, tl_path(file), NULL, &a) != THX_OK) {
            fprintf(stderr, "%s, type %s: %s\n", file, t->name, thx_ctx_message(ctx));
            all = 0;
            continue;
        }
        int ok = a.n[0] == 2 && a.n[1] == 2 && a.n[2] == 1;
        for (int q = 0; q < 4; q++) ok &= a.v[q] == (float)(q + 1);
        ok &= a.spacing[0] == 0.5 && a.spacing[1] == 0.25 && a.spacing[2] == 1 && a.dir[8] == 1;
        ok &= a.origin[0] == origin[0] && a.origin[1] == origin[1] && a.origin[2] == origin[2];
        ok &= (t->kind == 'i') == (a.integral != 0);
        if (!ok) fprintf(stderr, "%s, type %s: not the 2 x 2 plane 1 2 3 4 it holds\n", file, t->name);
        all &= ok;
        thx_image_free(&a);
    }
    return all;
}

static const char *NRRD_HEAD_LPS = "NRRD0004\n# a comment\nkey:=value\ntype: short\ndimension: 3\nspace: left-posterior-superior\n"
                                   "sizes: 4 3 2\nspace directions: (0,0.5,0) (-2,0,0) (0,0,3)\nkinds: domain domain domain\n"
                                   "endian: %s\nencoding: %s\nspace origin: (10,-20,30)\n";

int main(void)
{
    if (tl_scratch_make("test_image_formats") != 0) return 1;
    thx_ctx *ctx = NULL;
    thx_ctx_create(&ctx);

    /* ---- round trips: every written format x every type x every orientation (the tables above) */
    for (size_t o = 0; o < sizeof ORIENTS / sizeof ORIENTS[0]; o++) {
        thx_image img;
        CHECK_OK(ctx, oriented_grid(ctx, &ORIENTS[o], &img));
        if (!img.v) continue;
        for (size_t t = 0; t < sizeof DTYPES / sizeof DTYPES[0]; t++) {
            fill(&img, &DTYPES[t]);
            for (size_t f = 0; f < sizeof FORMATS / sizeof FORMATS[0]; f++)
                round_trip(ctx, &img, &ORIENTS[o], &DTYPES[t], &FORMATS[f]);
        }
        /* the default type for integers 0..250 is uint8, for -100..150 int16, for 0..70000 int32 */
        static const struct {
            double lo, hi;
            const char *type;
        } defaults[] = {{0, 250, "uint8"}, {-100, 150, "int16"}, {0, 70000, "int32"}};
        for (int d = 0; d < 3; d++) {
            rt_dtype range = {NULL, 1, defaults[d].lo, defaults[d].hi};
            fill(&img, &range);
            CHECK_OK(ctx, thx_image_write(ctx, &img, tl_path("default.nrrd"), NULL));
            thx_image in;
            CHECK_OK(ctx, thx_image_read(ctx, tl_path("default.nrrd"), NULL, &in));
            CHECK(in.v && strcmp(in.stored_type, defaults[d].type) == 0);
            if (in.v && strcmp(in.stored_type, defaults[d].type)) fprintf(stderr, "  default type %s, expected %s\n", in.stored_type, defaults[d].type);
            if (in.v) CHECK(same_image(&img, &in, 1e-14));
            thx_image_free(&in);
        }
        thx_image_free(&img);
    }

    /* ---- hand-written NRRD: LPS, little and big endian, raw, gzip, ascii */
    unsigned char le[48], be[48];
    int16_bytes(le, 0);
    int16_bytes(be, 1);
    char head[2048];
    snprintf(head, sizeof head, NRRD_HEAD_LPS, "little", "raw");
    strcat(head, "\n");
    write_file(tl_path("lps.nrrd"), head, le, 48);
    thx_image img;
    CHECK_OK(ctx, thx_image_read(ctx, tl_path("lps.nrrd"), NULL, &img));
    if (img.v) {
        CHECK(int16_voxels_ok(&img));
        CHECK(strcmp(img.stored_type, "int16") == 0 && img.integral);
        CHECK(strcmp(img.source_frame, "LPS") == 0);
        /* LPS (0,0.5,0) -> RAS (0,-0.5,0): axis i points posterior... negated: anterior -y; LPS (-2,0,0) -> RAS (2,0,0) */
        CHECK_NEAR(img.spacing[0], 0.5, 1e-15);
        CHECK_NEAR(img.spacing[1], 2, 1e-15);
        CHECK_NEAR(img.spacing[2], 3, 1e-15);
        CHECK(img.dir[0] == 0 && img.dir[3] == -1 && img.dir[6] == 0); /* column i = (0,-1,0) */
        CHECK(img.dir[1] == 1 && img.dir[4] == 0 && img.dir[7] == 0);  /* column j = (1,0,0) */
        CHECK(img.dir[2] == 0 && img.dir[5] == 0 && img.dir[8] == 1);
        CHECK(img.origin[0] == -10 && img.origin[1] == 20 && img.origin[2] == 30);
        thx_image_free(&img);
    }
    snprintf(head, sizeof head, NRRD_HEAD_LPS, "big", "raw");
    strcat(head, "\n");
    write_file(tl_path("big.nrrd"), head, be, 48);
    CHECK_OK(ctx, thx_image_read(ctx, tl_path("big.nrrd"), NULL, &img));
    CHECK(img.v && int16_voxels_ok(&img));
    thx_image_free(&img);
    /* gzip (zlib's gzip framing) and a zlib stream */
    for (int wrap = 0; wrap < 2; wrap++) {
        unsigned char z[256];
        z_stream zs;
        memset(&zs, 0, sizeof zs);
        deflateInit2(&zs, 9, Z_DEFLATED, wrap ? 15 : 15 + 16, 8, Z_DEFAULT_STRATEGY);
        zs.next_in = le;
        zs.avail_in = 48;
        zs.next_out = z;
        zs.avail_out = sizeof z;
        deflate(&zs, Z_FINISH);
        size_t nz = sizeof z - zs.avail_out;
        deflateEnd(&zs);
        snprintf(head, sizeof head, NRRD_HEAD_LPS, "little", wrap ? "gz" : "gzip");
        strcat(head, "\n");
        write_file(tl_path("gz.nrrd"), head, z, nz);
        CHECK_OK(ctx, thx_image_read(ctx, tl_path("gz.nrrd"), NULL, &img));
        CHECK(img.v && int16_voxels_ok(&img));
        thx_image_free(&img);
        /* the stream cut short, and with bytes after it */
        write_file(tl_path("gzcut.nrrd"), head, z, nz - 6);
        CHECK(refused(ctx, tl_path("gzcut.nrrd"), "truncated"));
        unsigned char zz[300];
        memcpy(zz, z, nz);
        memcpy(zz + nz, "junk", 4);
        write_file(tl_path("gzmore.nrrd"), head, zz, nz + 4);
        CHECK(refused(ctx, tl_path("gzmore.nrrd"), "follow the compressed"));
        /* a stream of more voxels than claimed: 49 bytes */
        unsigned char l49[49];
        memcpy(l49, le, 48);
        l49[48] = 7;
        uLongf nz2 = sizeof z;
        compress2(z, &nz2, l49, 49, 9);
        write_file(tl_path("gzlong.nrrd"), head, z, nz2);
        CHECK(refused(ctx, tl_path("gzlong.nrrd"), "more than the header"));
    }
    /* ascii, with the type alias "signed short int" */
    {
        char text[2048] = "NRRD0005\ntype: signed short int\ndimension: 3\nspace: RAS\nsizes: 4 3 2\n"
                          "space directions: (1,0,0) (0,1,0) (0,0,1)\nencoding: ascii\n\n";
        for (int q = 0; q < 24; q++) {
            char w[16];
            snprintf(w, sizeof w, "%d%s", q * 100 - 1000, q % 4 == 3 ? "\n" : " ");
            strcat(text, w);
        }
        write_file(tl_path("ascii.nrrd"), text, NULL, 0);
        CHECK_OK(ctx, thx_image_read(ctx, tl_path("ascii.nrrd"), NULL, &img));
        CHECK(img.v && int16_voxels_ok(&img) && strcmp(img.source_frame, "RAS") == 0);
        thx_image_free(&img);
        text[strlen(text) - 6] = '\0'; /* the last value gone */
        write_file(tl_path("asciicut.nrrd"), text, NULL, 0);
        CHECK(refused(ctx, tl_path("asciicut.nrrd"), "truncated"));
        write_file(tl_path("ascii300.nrrd"), "NRRD0004\ntype: uchar\ndimension: 2\nsizes: 2 1\nencoding: ascii\n\n7 300\n",
                   NULL, 0);
        CHECK(refused(ctx, tl_path("ascii300.nrrd"), "text value 2 (at byte 2) 300 is outside the range of uint8"));
    }
    /* every type alias decodes 1 2 3 4 as 1 2 3 4 (little endian; 2-D: one plane) */
    {
        static const stored_type aliases[] = {
            {"signed char", 1, 'i'}, {"int8", 1, 'i'}, {"int8_t", 1, 'i'}, {"uchar", 1, 'i'}, {"unsigned char", 1, 'i'},
            {"uint8", 1, 'i'}, {"uint8_t", 1, 'i'}, {"short", 2, 'i'}, {"short int", 2, 'i'}, {"signed short", 2, 'i'},
            {"int16", 2, 'i'}, {"int16_t", 2, 'i'}, {"ushort", 2, 'i'}, {"unsigned short", 2, 'i'},
            {"unsigned short int", 2, 'i'}, {"uint16", 2, 'i'}, {"uint16_t", 2, 'i'}, {"int", 4, 'i'},
            {"signed int", 4, 'i'}, {"int32", 4, 'i'}, {"int32_t", 4, 'i'}, {"uint", 4, 'i'}, {"unsigned int", 4, 'i'},
            {"uint32", 4, 'i'}, {"uint32_t", 4, 'i'}, {"longlong", 8, 'i'}, {"long long", 8, 'i'},
            {"long long int", 8, 'i'}, {"signed long long", 8, 'i'}, {"signed long long int", 8, 'i'}, {"int64", 8, 'i'},
            {"int64_t", 8, 'i'}, {"ulonglong", 8, 'i'}, {"unsigned long long", 8, 'i'}, {"unsigned long long int", 8, 'i'},
            {"uint64", 8, 'i'}, {"uint64_t", 8, 'i'}, {"float", 4, 'f'}, {"double", 8, 'f'}};
        static const double origin[3] = {0, 0, 0};
        CHECK(decodes_1234(ctx, "alias.nrrd",
                           "NRRD0004\ntype: %s\ndimension: 2\nsizes: 2 2\nspacings: 0.5 0.25\nendian: little\n"
                           "encoding: raw\n\n",
                           aliases, sizeof aliases / sizeof aliases[0], origin));
    }
    /* a 2-D plane in LPS: its third axis the right-handed normal u x w, spacing 1 */
    {
        unsigned char d4[4] = {1, 2, 3, 4};
        write_file(tl_path("plane.nrrd"),
                   "NRRD0004\ntype: uchar\ndimension: 2\nspace: LPS\nsizes: 2 2\nspace directions: (0,2,0) (0.5,0,0)\n"
                   "encoding: raw\nspace origin: (1,2,3)\n\n",
                   d4, 4);
        CHECK_OK(ctx, thx_image_read(ctx, tl_path("plane.nrrd"), NULL, &img));
        if (img.v) {
            /* RAS u = (0,-1,0), w = (-1,0,0): u x w = (0,0,-1) */
            CHECK(img.dir[3] == -1 && img.dir[1] == -1 && img.dir[8] == -1 && img.dir[2] == 0 && img.dir[5] == 0);
            CHECK(img.spacing[0] == 2 && img.spacing[1] == 0.5 && img.spacing[2] == 1 && img.n[2] == 1);
            CHECK(img.origin[0] == -1 && img.origin[1] == -2 && img.origin[2] == 3 && img.v[3] == 4);
            thx_image_free(&img);
        }
    }
    /* LAS and scanner-xyz: x negated; x and y negated */
    {
        const char *spaces[] = {"left-anterior-superior", "scanner-xyz", "right-anterior-superior"};
        const double sx[] = {-1, -1, 1}, sy[] = {1, -1, 1};
        for (int k = 0; k < 3; k++) {
            snprintf(head, sizeof head,
                     "NRRD0004\ntype: short\ndimension: 3\nspace: %s\nsizes: 4 3 2\n"
                     "space directions: (1,2,0) (-2,1,0) (0,0,1.5)\nendian: little\nencoding: raw\nspace origin: (1,2,3)\n\n",
                     spaces[k]);
            write_file(tl_path("space.nrrd"), head, le, 48);
            CHECK_OK(ctx, thx_image_read(ctx, tl_path("space.nrrd"), NULL, &img));
            if (!img.v) continue;
            double l = sqrt(5.0);
            CHECK_NEAR(img.dir[0], sx[k] * 1 / l, 1e-15);
            CHECK_NEAR(img.dir[3], sy[k] * 2 / l, 1e-15);
            CHECK_NEAR(img.dir[1], sx[k] * -2 / l, 1e-15);
            CHECK_NEAR(img.spacing[0], l, 1e-14);
            CHECK(img.origin[0] == sx[k] * 1 && img.origin[1] == sy[k] * 2 && img.origin[2] == 3);
            thx_image_free(&img);
        }
    }
    /* detached header: data file beside it, with byte skip; space units cm */
    {
        unsigned char d[58];
        memcpy(d, "0123456789", 10);
        memcpy(d + 10, le, 48);
        write_file(tl_path("det.raw"), "", d, 58);
        write_file(tl_path("det.nhdr"),
                   "NRRD0004\ntype: int16\ndimension: 3\nspace: RAS\nsizes: 4 3 2\nspace directions: (0.1,0,0) (0,0.1,0) "
                   "(0,0,0.2)\nspace units: \"cm\" \"cm\" \"cm\"\nendian: little\nencoding: raw\nbyte skip: 10\n"
                   "data file: det.raw\n",
                   NULL, 0);
        CHECK_OK(ctx, thx_image_read(ctx, tl_path("det.nhdr"), NULL, &img));
        CHECK(img.v && int16_voxels_ok(&img));
        if (img.v) CHECK(fabs(img.spacing[0] - 1) < 1e-12 && fabs(img.spacing[2] - 2) < 1e-12);
        thx_image_free(&img);
        /* byte skip -1: the data are the file's last bytes */
        write_file(tl_path("det2.nhdr"),
                   "NRRD0004\ntype: int16\ndimension: 3\nsizes: 4 3 2\nendian: little\nencoding: raw\nbyte skip: -1\n"
                   "data file: det.raw\n",
                   NULL, 0);
        CHECK_OK(ctx, thx_image_read(ctx, tl_path("det2.nhdr"), NULL, &img));
        CHECK(img.v && int16_voxels_ok(&img));
        thx_image_free(&img);
        /* the data file missing, and the data file shorter than claimed */
        write_file(tl_path("det3.nhdr"),
                   "NRRD0004\ntype: int16\ndimension: 3\nsizes: 4 3 3\nendian: little\nencoding: raw\ndata file: det.raw\n",
                   NULL, 0);
        CHECK(refused(ctx, tl_path("det3.nhdr"), "truncated"));
        write_file(tl_path("det4.nhdr"),
                   "NRRD0004\ntype: int16\ndimension: 3\nsizes: 4 3 2\nendian: little\nencoding: raw\ndata file: none.raw\n",
                   NULL, 0);
        CHECK(refused(ctx, tl_path("det4.nhdr"), "none.raw"));
    }
    /* ---- bad NRRD */
    snprintf(head, sizeof head, NRRD_HEAD_LPS, "little", "raw");
    strcat(head, "\n");
    write_file(tl_path("short.nrrd"), head, le, 47);
    CHECK(refused(ctx, tl_path("short.nrrd"), "truncated"));
    CHECK(tl_msg_has(ctx, "47 bytes"));
    unsigned char le50[50];
    memcpy(le50, le, 48);
    write_file(tl_path("long.nrrd"), head, le50, 50);
    CHECK(refused(ctx, tl_path("long.nrrd"), "2 bytes more"));
    snprintf(head, sizeof head, NRRD_HEAD_LPS, "little", "bzip2");
    strcat(head, "\n");
    write_file(tl_path("bz.nrrd"), head, le, 48);
    CHECK(refused(ctx, tl_path("bz.nrrd"), "bz.nrrd:11: encoding \"bzip2\""));
    write_file(tl_path("line.nrrd"), "NRRD0004\ntype: short\nthis is not a field\n\n", NULL, 0);
    CHECK(refused(ctx, tl_path("line.nrrd"), "line.nrrd:3:"));
    write_file(tl_path("4d.nrrd"), "NRRD0004\ntype: short\ndimension: 4\n\n", NULL, 0);
    CHECK(refused(ctx, tl_path("4d.nrrd"), "4d.nrrd:3: dimension 4"));
    write_file(tl_path("vec.nrrd"), "NRRD0004\ntype: short\ndimension: 3\nkinds: vector domain domain\n\n", NULL, 0);
    CHECK(refused(ctx, tl_path("vec.nrrd"), "kind \"vector\""));
    write_file(tl_path("none.nrrd"),
               "NRRD0004\ntype: short\ndimension: 3\nspace: RAS\nsizes: 3 4 2\nspace directions: none (1,0,0) (0,1,0)\n\n",
               NULL, 0);
    CHECK(refused(ctx, tl_path("none.nrrd"), "none.nrrd:6: axis 1 has no space direction"));
    write_file(tl_path("hand.nrrd"), "NRRD0004\ntype: short\ndimension: 3\nspace: 3D-right-handed\n\n", NULL, 0);
    CHECK(refused(ctx, tl_path("hand.nrrd"), "3D-right-handed"));
    /* NaN voxel, zero spacing, negative spacing, skewed directions */
    {
        float fv[24];
        for (int q = 0; q < 24; q++) fv[q] = (float)q;
        fv[13] = NAN;
        write_file(tl_path("nan.nrrd"), "NRRD0004\ntype: float\ndimension: 3\nsizes: 4 3 2\nendian: little\nencoding: raw\n\n",
                   fv, sizeof fv);
        CHECK(refused(ctx, tl_path("nan.nrrd"), "voxel (1, 0, 1) is NaN"));
        write_file(tl_path("zero.nrrd"),
                   "NRRD0004\ntype: short\ndimension: 3\nspace: RAS\nsizes: 4 3 2\nspace directions: (1,0,0) (0,0,0) "
                   "(0,0,1)\nendian: little\nencoding: raw\n\n",
                   le, 48);
        CHECK(refused(ctx, tl_path("zero.nrrd"), "spacing along axis 2 is 0"));
        write_file(tl_path("neg.nrrd"), "NRRD0004\ntype: short\ndimension: 3\nsizes: 4 3 2\nspacings: 1 -2 1\nendian: little\n"
                   "encoding: raw\n\n", le, 48);
        CHECK(refused(ctx, tl_path("neg.nrrd"), "spacing along axis 2 is -2"));
        write_file(tl_path("skew.nrrd"),
                   "NRRD0004\ntype: short\ndimension: 3\nspace: RAS\nsizes: 4 3 2\nspace directions: (1,0,0) (1,1,0) "
                   "(0,0,1)\nendian: little\nencoding: raw\n\n",
                   le, 48);
        CHECK(refused(ctx, tl_path("skew.nrrd"), "not orthonormal"));
    }
    /* a misnamed file: NRRD content named .nii, and .mha */
    snprintf(head, sizeof head, NRRD_HEAD_LPS, "little", "raw");
    strcat(head, "\n");
    write_file(tl_path("really_nrrd.nii"), head, le, 48);
    CHECK(refused(ctx, tl_path("really_nrrd.nii"), "named as NIfTI but the file is a NRRD file"));
    write_file(tl_path("really_nrrd.mha"), head, le, 48);
    CHECK(refused(ctx, tl_path("really_nrrd.mha"), "rename it .nrrd"));

    /* ---- hand-written MetaImage: LOCAL, MSB, TransformMatrix rows = index axes in LPS */
    const char *mha = "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = %s\n"
                      "TransformMatrix = 0 1 0 -1 0 0 0 0 1\nOffset = 10 -20 30\nAnatomicalOrientation = ???\n"
                      "ElementSpacing = 0.5 2 3\nDimSize = 4 3 2\nElementType = MET_SHORT\nElementDataFile = LOCAL\n";
    snprintf(head, sizeof head, mha, "True");
    write_file(tl_path("msb.mha"), head, be, 48);
    CHECK_OK(ctx, thx_image_read(ctx, tl_path("msb.mha"), NULL, &img));
    if (img.v) {
        CHECK(int16_voxels_ok(&img));
        /* axis i = LPS (0,1,0) = posterior -> RAS (0,-1,0); axis j = LPS (-1,0,0) -> RAS (1,0,0) */
        CHECK(img.dir[0] == 0 && img.dir[3] == -1 && img.dir[6] == 0);
        CHECK(img.dir[1] == 1 && img.dir[4] == 0 && img.dir[7] == 0);
        CHECK(img.origin[0] == -10 && img.origin[1] == 20 && img.origin[2] == 30);
        CHECK(img.spacing[0] == 0.5 && img.spacing[1] == 2 && img.spacing[2] == 3);
        CHECK(strcmp(img.format, "metaimage") == 0);
        thx_image_free(&img);
    }
    snprintf(head, sizeof head, mha, "False");
    write_file(tl_path("lsb.mha"), head, le, 48);
    CHECK_OK(ctx, thx_image_read(ctx, tl_path("lsb.mha"), NULL, &img));
    CHECK(img.v && int16_voxels_ok(&img));
    thx_image_free(&img);
    write_file(tl_path("lsbcut.mha"), head, le, 40);
    CHECK(refused(ctx, tl_path("lsbcut.mha"), "truncated"));
    write_file(tl_path("lsblong.mha"), head, le50, 50);
    CHECK(refused(ctx, tl_path("lsblong.mha"), "2 bytes more"));
    /* compressed, with and without CompressedDataSize; ElementSize as the spacing */
    {
        unsigned char z[256];
        uLongf nz = sizeof z;
        compress2(z, &nz, le, 48, 9);
        snprintf(head, sizeof head,
                 "ObjectType = Image\nNDims = 3\nCompressedData = True\nCompressedDataSize = %lu\nDimSize = 4 3 2\n"
                 "ElementSize = 1.5 1.5 4\nElementType = MET_SHORT\nElementDataFile = LOCAL\n",
                 (unsigned long)nz);
        write_file(tl_path("z.mha"), head, z, nz);
        CHECK_OK(ctx, thx_image_read(ctx, tl_path("z.mha"), NULL, &img));
        CHECK(img.v && int16_voxels_ok(&img));
        if (img.v) CHECK(img.spacing[0] == 1.5 && img.spacing[2] == 4);
        thx_image_free(&img);
        write_file(tl_path("zcut.mha"), head, z, nz - 3);
        CHECK(refused(ctx, tl_path("zcut.mha"), "truncated"));
        write_file(tl_path("z2.mha"),
                   "ObjectType = Image\nNDims = 3\nCompressedData = True\nDimSize = 4 3 3\nElementType = MET_SHORT\n"
                   "ElementDataFile = LOCAL\n",
                   z, nz);
        CHECK(refused(ctx, tl_path("z2.mha"), "truncated"));
    }
    /* detached .mhd with HeaderSize; 2-D; every ElementType */
    {
        unsigned char d[58];
        memcpy(d, "0123456789", 10);
        memcpy(d + 10, le, 48);
        write_file(tl_path("m.raw"), "", d, 58);
        write_file(tl_path("m.mhd"),
                   "ObjectType = Image\nNDims = 3\nDimSize = 4 3 2\nHeaderSize = 10\nElementType = MET_SHORT\n"
                   "ElementDataFile = m.raw\n",
                   NULL, 0);
        CHECK_OK(ctx, thx_image_read(ctx, tl_path("m.mhd"), NULL, &img));
        CHECK(img.v && int16_voxels_ok(&img));
        thx_image_free(&img);
        write_file(tl_path("m2.mhd"),
                   "ObjectType = Image\nNDims = 3\nDimSize = 4 3 2\nHeaderSize = -1\nElementType = MET_SHORT\n"
                   "ElementDataFile = m.raw\n",
                   NULL, 0);
        CHECK_OK(ctx, thx_image_read(ctx, tl_path("m2.mhd"), NULL, &img));
        CHECK(img.v && int16_voxels_ok(&img));
        thx_image_free(&img);
        static const stored_type met[] = {{"MET_CHAR", 1, 'i'},      {"MET_UCHAR", 1, 'i'},      {"MET_SHORT", 2, 'i'},
                                          {"MET_USHORT", 2, 'i'},    {"MET_INT", 4, 'i'},        {"MET_UINT", 4, 'i'},
                                          {"MET_LONG", 4, 'i'},      {"MET_ULONG", 4, 'i'},      {"MET_LONG_LONG", 8, 'i'},
                                          {"MET_ULONG_LONG", 8, 'i'}, {"MET_FLOAT", 4, 'f'},     {"MET_DOUBLE", 8, 'f'}};
        static const double origin[3] = {-1, -2, 0}; /* Offset 1 2 in LPS */
        CHECK(decodes_1234(ctx, "t.mha",
                           "ObjectType = Image\nNDims = 2\nDimSize = 2 2\nElementSpacing = 0.5 0.25\nOffset = 1 2\n"
                           "ElementType = %s\nElementDataFile = LOCAL\n",
                           met, sizeof met / sizeof met[0], origin));
    }
    /* bad MetaImage */
    write_file(tl_path("ch.mha"), "ObjectType = Image\nNDims = 3\nElementNumberOfChannels = 3\n", NULL, 0);
    CHECK(refused(ctx, tl_path("ch.mha"), "ch.mha:3: ElementNumberOfChannels 3"));
    write_file(tl_path("nd.mha"), "ObjectType = Image\nNDims = 4\n", NULL, 0);
    CHECK(refused(ctx, tl_path("nd.mha"), "nd.mha:2: NDims 4"));
    write_file(tl_path("kv.mha"), "ObjectType = Image\nNDims = 3\nno equals sign here\n", NULL, 0);
    CHECK(refused(ctx, tl_path("kv.mha"), "kv.mha:3:"));
    write_file(tl_path("sp.mha"),
               "ObjectType = Image\nNDims = 3\nDimSize = 4 3 2\nElementSpacing = 1 0 1\nElementType = MET_SHORT\n"
               "ElementDataFile = LOCAL\n",
               le, 48);
    CHECK(refused(ctx, tl_path("sp.mha"), "spacing along axis 2 is 0"));
    write_file(tl_path("sk.mha"),
               "ObjectType = Image\nNDims = 3\nDimSize = 4 3 2\nTransformMatrix = 1 0 0 0.5 1 0 0 0 1\n"
               "ElementType = MET_SHORT\nElementDataFile = LOCAL\n",
               le, 48);
    CHECK(refused(ctx, tl_path("sk.mha"), "not orthonormal"));
    write_file(tl_path("list.mhd"), "ObjectType = Image\nNDims = 3\nElementDataFile = LIST 2\n", NULL, 0);
    CHECK(refused(ctx, tl_path("list.mhd"), "list.mhd:3: ElementDataFile \"LIST 2\""));

    /* ---- the writers: detached forms refused, another program's file never replaced, nothing left over */
    {
        size_t n[3] = {3, 3, 3};
        thx_image w;
        CHECK_OK(ctx, thx_image_alloc(ctx, n, &w));
        CHECK(thx_image_write(ctx, &w, tl_path("w.nhdr"), NULL) != THX_OK && tl_msg_has(ctx, ".nrrd"));
        CHECK(thx_image_write(ctx, &w, tl_path("w.mhd"), NULL) != THX_OK && tl_msg_has(ctx, ".mha"));
        CHECK(!tl_exists(tl_path("w.nhdr")) && !tl_exists(tl_path("w.mhd")));
        CHECK(thx_image_write(ctx, &w, tl_path("lps.nrrd"), NULL) != THX_OK); /* hand-written: not thorax's */
        CHECK(thx_image_write(ctx, &w, tl_path("msb.mha"), NULL) != THX_OK);
        thx_image back;
        CHECK_OK(ctx, thx_image_read(ctx, tl_path("lps.nrrd"), NULL, &back)); /* still the original */
        CHECK(back.v && int16_voxels_ok(&back));
        thx_image_free(&back);
        thx_image_free(&w);
        CHECK(!tl_leftover_tmp(""));
    }

    thx_ctx_destroy(&ctx);
    return tl_scratch_finish("test_image_formats");
}
