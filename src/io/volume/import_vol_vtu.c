/*
 * Volume meshes made elsewhere: VTK XML UnstructuredGrid (.vtu), ascii,
 * base64 and appended data, raw or zlib-compressed (thorax/io/volume_read.h).
 */
#include <zlib.h>

#include "io/volume/import_volume_impl.h"

/* ---------------------------------------------------------- VTK XML (.vtu) */

/* Binary data: raw bytes or base64 text (concatenated encodings allowed:
 * VTK encodes a header and its data separately). */
typedef struct {
    const unsigned char *p, *end;
    int b64;
    unsigned char q[3];
    int nq, iq;
} bstream;

static int b64_value(unsigned char ch)
{
    if (ch >= 'A' && ch <= 'Z') return ch - 'A';
    if (ch >= 'a' && ch <= 'z') return ch - 'a' + 26;
    if (ch >= '0' && ch <= '9') return ch - '0' + 52;
    if (ch == '+') return 62;
    if (ch == '/') return 63;
    return -1;
}

/* Reads n bytes; 0, or -1 (end of data, or not base64). */
static int bs_read(bstream *s, unsigned char *out, size_t n)
{
    if (!s->b64) {
        if ((size_t)(s->end - s->p) < n) return -1;
        if (out) memcpy(out, s->p, n);
        s->p += n;
        return 0;
    }
    for (size_t i = 0; i < n;) {
        if (s->iq < s->nq) {
            unsigned char b = s->q[s->iq++];
            if (out) out[i] = b;
            i++;
            continue;
        }
        int v[4], k = 0;
        while (k < 4) {
            if (s->p >= s->end || *s->p == '<') return -1;
            unsigned char ch = *s->p++;
            if (isspace(ch)) continue;
            v[k] = ch == '=' ? -2 : b64_value(ch);
            if (v[k] == -1) return -1;
            k++;
        }
        if (v[0] < 0 || v[1] < 0 || (v[2] == -2 && v[3] != -2)) return -1;
        s->q[0] = (unsigned char)(v[0] << 2 | v[1] >> 4);
        s->nq = 1;
        if (v[2] >= 0) {
            s->q[1] = (unsigned char)((v[1] & 15) << 4 | v[2] >> 2);
            s->nq = 2;
            if (v[3] >= 0) {
                s->q[2] = (unsigned char)((v[2] & 3) << 6 | v[3]);
                s->nq = 3;
            }
        }
        s->iq = 0;
    }
    return 0;
}

/* An upper bound of the bytes left. */
static size_t bs_left(const bstream *s)
{
    size_t n = (size_t)(s->end - s->p);
    return s->b64 ? n / 4 * 3 + 3 + (size_t)(s->nq - s->iq) : n;
}

typedef struct {
    const char *text;      /* the whole file */
    size_t len;
    const char *xml_end;   /* where XML parsing stops: <AppendedData, else the end */
    int big;               /* byte_order="BigEndian" */
    int header64;          /* header_type="UInt64" */
    int zlib;              /* compressor="vtkZLibDataCompressor" */
    const char *app;       /* the first byte after the appended data's '_' (NULL: none) */
    int app_b64;           /* appended encoding="base64" */
    size_t inflate_left;   /* bytes zlib may still give (INFLATE_BUDGET) */
} vtu_file;

/* What compressed arrays may expand to, in all: 64 times the file's size and
 * 16 MB. zlib itself allows 1032 bytes out per byte in, so that a small file
 * of compressed zeros could otherwise claim gigabytes; real meshes expand
 * less than 10 times (their connectivity compresses about 4:1). */
#define INFLATE_BUDGET(len) ((len) < SIZE_MAX / 128 ? 64 * (len) + ((size_t)16 << 20) : SIZE_MAX)

static scalar_type vtu_type(const char *s)
{
    static const struct { const char *name; scalar_type ty; } tab[] = {
        {"Int8", T_I8}, {"UInt8", T_U8}, {"Int16", T_I16}, {"UInt16", T_U16}, {"Int32", T_I32}, {"UInt32", T_U32},
        {"Int64", T_I64}, {"UInt64", T_U64}, {"Float32", T_F32}, {"Float64", T_F64},
        /* VTK 0.1-era names */
        {"Char", T_I8}, {"UChar", T_U8}, {"Short", T_I16}, {"UShort", T_U16}, {"Int", T_I32}, {"UInt", T_U32},
        {"Float", T_F32}, {"Double", T_F64},
    };
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
        if (!strcmp(s, tab[i].name)) return tab[i].ty;
    return T_NONE;
}

static int read_uint(bstream *b, const vtu_file *f, uint64_t *out)
{
    unsigned char q[8];
    size_t k = f->header64 ? 8 : 4;
    if (bs_read(b, q, k) != 0) return -1;
    uint64_t u = 0; /* exactly, not through a double (2^64 - 1 would not convert back) */
    for (size_t i = 0; i < k; i++) u |= (uint64_t)q[f->big ? k - 1 - i : i] << (8 * i);
    *out = u;
    return 0;
}

/* The bytes of one binary DataArray (header + data, compressed or not),
 * nbytes expected, into a new buffer. */
static thx_status vtu_block(raw *r, vtu_file *f, bstream *b, where w, const char *what, size_t nbytes,
                            unsigned char **out)
{
    thx_status st = THX_OK;
    unsigned char *data = NULL, *cbuf = NULL;
    uint64_t *csize = NULL;
    *out = NULL;
    if (!f->zlib) {
        uint64_t nb;
        if (read_uint(b, f, &nb) != 0) return fail(r, w, "%s: the binary data end before their header", what);
        if (nb != (uint64_t)nbytes)
            return fail(r, w, "%s: the data hold %llu bytes, %zu expected", what, (unsigned long long)nb, nbytes);
        if (nbytes > bs_left(b)) return fail(r, w, "%s: %zu bytes declared, but the data are shorter", what, nbytes);
        data = thx_malloc(r->ctx, nbytes ? nbytes : 1);
        if (!data) return THX_ENOMEM;
        if (bs_read(b, data, nbytes) != 0) {
            free(data);
            return fail(r, w, "%s: the data end before their %zu bytes (or are not valid base64)", what, nbytes);
        }
        *out = data;
        return THX_OK;
    }
    uint64_t nblk, bsz, last;
    if (read_uint(b, f, &nblk) != 0 || read_uint(b, f, &bsz) != 0 || read_uint(b, f, &last) != 0)
        return fail(r, w, "%s: the compressed data end before their header", what);
    if (nblk > bs_left(b) / (f->header64 ? 8 : 4))
        return fail(r, w, "%s: %llu compressed blocks declared, but the data are too short", what, (unsigned long long)nblk);
    /* every block but the last holds bsz bytes, the last one `last` (0: bsz; VTK writes one
     * block of a smaller array with bsz its default 32768); the sizes must add up to the
     * array's bytes without overflow */
    if (nblk > 0 && (bsz == 0 || last > bsz || (nblk > 1 && (bsz > (uint64_t)nbytes || (nblk - 1) > (uint64_t)nbytes / bsz))))
        return fail(r, w, "%s: compressed header (%llu blocks of %llu bytes, the last %llu) inconsistent with the %zu "
                    "bytes expected", what, (unsigned long long)nblk, (unsigned long long)bsz, (unsigned long long)last,
                    nbytes);
    uint64_t total = nblk == 0 ? 0 : (nblk - 1) * bsz + (last ? last : bsz);
    if (total != (uint64_t)nbytes)
        return fail(r, w, "%s: the compressed data hold %llu bytes, %zu expected", what, (unsigned long long)total, nbytes);
    csize = thx_malloc(r->ctx, (nblk ? nblk : 1) * sizeof *csize);
    if (!csize) return THX_ENOMEM;
    uint64_t csum = 0, cmax = 0;
    for (uint64_t i = 0; i < nblk; i++) {
        if (read_uint(b, f, &csize[i]) != 0) {
            st = fail(r, w, "%s: the compressed data end in their header", what);
            goto done;
        }
        if (csize[i] > bs_left(b)) {
            st = fail(r, w, "%s: compressed block %llu of %llu bytes, but the data are shorter", what,
                      (unsigned long long)i + 1, (unsigned long long)csize[i]);
            goto done;
        }
        csum += csize[i];
        if (csize[i] > cmax) cmax = csize[i];
    }
    if (csum > bs_left(b) || (uint64_t)nbytes > 1032 * csum + 64) {
        st = fail(r, w, "%s: compressed sizes (%llu bytes) inconsistent with the data", what, (unsigned long long)csum);
        goto done;
    }
    if (nbytes > f->inflate_left) {
        st = fail(r, w, "%s: the compressed arrays expand to more than 64 times the file's size (%zu bytes here): "
                  "refused as a damaged or hostile file", what, nbytes);
        goto done;
    }
    f->inflate_left -= nbytes;
    data = thx_malloc(r->ctx, nbytes ? nbytes : 1);
    cbuf = thx_malloc(r->ctx, cmax ? cmax : 1);
    if (!data || !cbuf) {
        st = THX_ENOMEM;
        goto done;
    }
    size_t at = 0;
    for (uint64_t i = 0; i < nblk; i++) {
        if (bs_read(b, cbuf, csize[i]) != 0) {
            st = fail(r, w, "%s: compressed block %llu ends early", what, (unsigned long long)i + 1);
            goto done;
        }
        uLongf dl = (uLongf)((i + 1 == nblk && last) ? last : bsz);
        uLongf want = dl;
        if (dl > nbytes - at) { /* cannot happen after the header checks; never write past data */
            st = fail(r, w, "%s: compressed block %llu larger than the array", what, (unsigned long long)i + 1);
            goto done;
        }
        int zr = uncompress(data + at, &dl, cbuf, (uLong)csize[i]);
        if (zr != Z_OK || dl != want) {
            st = fail(r, w, "%s: compressed block %llu is not valid zlib data of %lu bytes", what, (unsigned long long)i + 1,
                      (unsigned long)want);
            goto done;
        }
        at += dl;
    }
    *out = data;
    data = NULL;
done:
    free(data);
    free(cbuf);
    free(csize);
    return st;
}

/* Reads the DataArray whose tag starts at tag: count values (components
 * included) into a new array. what names it in messages. */
static thx_status vtu_array(raw *r, vtu_file *f, const char *tag, const char *what, size_t count, double **out)
{
    const char *end = f->xml_end;
    where w = at_line(line_of(f->text, tag));
    const char *gt = memchr(tag, '>', (size_t)(end - tag));
    if (!gt) return fail(r, w, "%s: unterminated <DataArray> tag", what);
    char val[64] = "";
    if (xml_attr(tag, gt, "type", val, sizeof val) != 0) return fail(r, w, "%s: DataArray without a type", what);
    scalar_type ty = vtu_type(val);
    if (!ty) return fail(r, w, "%s: DataArray type \"%s\" is not supported", what, val);
    char fmt[32] = "ascii";
    xml_attr(tag, gt, "format", fmt, sizeof fmt);
    int self_closing = gt > tag && gt[-1] == '/';
    double *v = NULL;
    if (!strcmp(fmt, "ascii")) {
        if (self_closing) return fail(r, w, "%s: ascii DataArray without data", what);
        const char *lt = memchr(gt, '<', (size_t)(end - gt));
        if (!lt) return fail(r, w, "%s: DataArray without its closing tag", what);
        cursor c = {gt + 1, (size_t)(lt - gt - 1), 0, line_of(f->text, gt)};
        if (count > c.len / 2 + 1) return fail(r, w, "%s: %zu values declared, but the DataArray is too short for them", what, count);
        v = thx_malloc(r->ctx, (count ? count : 1) * sizeof *v);
        if (!v) return THX_ENOMEM;
        for (size_t i = 0; i < count; i++) {
            const char *t;
            int line;
            size_t n = next_token(&c, &t, &line);
            int bad = !n;
            if (n && ty >= T_F32) bad = parse_num(t, n, &v[i]) != 0;
            else if (n) {
                long long x = 0, lo, hi;
                type_range(ty, &lo, &hi);
                int pr = parse_i64(t, n, lo, hi, &x);
                if (pr == -2) {
                    free(v);
                    return fail(r, at_line(line), "%s: value %zu \"%s\" is out of range %lld..%lld", what, i + 1,
                                tok_show(t, n), lo, hi);
                }
                bad = pr != 0;
                v[i] = (double)x;
            }
            if (bad) {
                free(v);
                if (!n) return fail(r, at_line(line), "%s: the DataArray ends at value %zu of %zu", what, i + 1, count);
                return fail(r, at_line(line), "%s: value %zu \"%s\" is not %s", what, i + 1, tok_show(t, n),
                            ty >= T_F32 ? "a finite number" : "an integer");
            }
        }
        const char *t;
        int line;
        if (next_token(&c, &t, &line)) {
            free(v);
            return fail(r, at_line(line), "%s: more than the %zu values expected", what, count);
        }
        *out = v;
        return THX_OK;
    }
    bstream b;
    memset(&b, 0, sizeof b);
    if (!strcmp(fmt, "binary")) {
        if (self_closing) return fail(r, w, "%s: binary DataArray without data", what);
        const char *lt = memchr(gt, '<', (size_t)(end - gt));
        if (!lt) return fail(r, w, "%s: DataArray without its closing tag", what);
        b.p = (const unsigned char *)gt + 1, b.end = (const unsigned char *)lt, b.b64 = 1;
    } else if (!strcmp(fmt, "appended")) {
        if (!f->app) return fail(r, w, "%s: format=\"appended\" but the file has no <AppendedData> section", what);
        long long offs;
        if (xml_attr(tag, gt, "offset", val, sizeof val) != 0 || parse_int(val, strlen(val), &offs) != 0 || offs < 0 ||
            (size_t)offs > (size_t)(f->text + f->len - f->app))
            return fail(r, w, "%s: appended DataArray without a valid offset", what);
        b.p = (const unsigned char *)f->app + offs, b.end = (const unsigned char *)f->text + f->len, b.b64 = f->app_b64;
        w = at_byte((size_t)(f->app - f->text) + (size_t)offs);
    } else {
        return fail(r, w, "%s: DataArray format \"%s\" is not supported (ascii, binary, appended)", what, fmt);
    }
    if (count > SIZE_MAX / 16) return fail(r, w, "%s: too many values", what);
    size_t nbytes = count * type_size[ty];
    unsigned char *bytes = NULL;
    THX_CHECK(vtu_block(r, f, &b, w, what, nbytes, &bytes));
    v = thx_malloc(r->ctx, (count ? count : 1) * sizeof *v);
    if (!v) {
        free(bytes);
        return THX_ENOMEM;
    }
    for (size_t i = 0; i < count; i++) {
        char big[32];
        if (int64_beyond(bytes + i * type_size[ty], ty, f->big, big, sizeof big)) {
            free(bytes);
            free(v);
            return fail(r, w, "%s: value %zu: integer %s is beyond +-2^53 (too large for any index, count or region)",
                        what, i + 1, big);
        }
        v[i] = get_scalar(bytes + i * type_size[ty], ty, f->big);
        if (ty >= T_F32 && !isfinite(v[i])) {
            free(bytes);
            free(v);
            return fail(r, w, "%s: value %zu is not a finite number", what, i + 1);
        }
    }
    free(bytes);
    *out = v;
    return THX_OK;
}

/* The NumberOfComponents of a DataArray tag (1 when absent); -1 if invalid. */
static long long vtu_components(const char *tag, const char *end)
{
    const char *gt = memchr(tag, '>', (size_t)(end - tag));
    char val[32];
    long long nc = 1;
    if (gt && xml_attr(tag, gt, "NumberOfComponents", val, sizeof val) == 0 &&
        (parse_int(val, strlen(val), &nc) != 0 || nc < 1 || nc > 64))
        return -1;
    return nc;
}

/* The element `name` directly after from and before limit, with its closing tag. */
static const char *vtu_section(const char *from, const char *limit, const char *name, const char **close)
{
    const char *p = xml_find(from, limit, name);
    if (!p) return NULL;
    char ct[48];
    snprintf(ct, sizeof ct, "</%s>", name);
    size_t cl = strlen(ct);
    const char *q = p;
    *close = NULL;
    for (; q + cl <= limit; q++)
        if (!memcmp(q, ct, cl)) {
            *close = q;
            break;
        }
    return p;
}

thx_status vol_read_vtu(raw *r, const char *text, size_t len, const char *region_array)
{
    thx_status st = THX_OK;
    vtu_file f;
    memset(&f, 0, sizeof f);
    f.text = text, f.len = len;
    f.inflate_left = INFLATE_BUDGET(len);
    const char *end = text + len;
    double *pts = NULL, *conn = NULL, *off = NULL, *types = NULL;
    cell_array *arr = NULL;
    size_t n_arr = 0, cap_arr = 0;
    char val[96];
    /* the appended data may hold any bytes: XML is parsed only before it */
    const char *ad = xml_find(text, end, "AppendedData");
    f.xml_end = ad ? ad : end;
    if (nul_line(text, (size_t)(f.xml_end - text))) {
        st = fail(r, at_line(nul_line(text, (size_t)(f.xml_end - text))), "NUL byte in the XML (at byte %zu)",
                  (size_t)((const char *)memchr(text, 0, (size_t)(f.xml_end - text)) - text));
        goto done;
    }
    const char *vf = xml_find(text, f.xml_end, "VTKFile");
    const char *vf_end = vf ? memchr(vf, '>', (size_t)(f.xml_end - vf)) : NULL;
    if (!vf_end) {
        st = fail(r, at_line(1), "not a VTK XML file (no <VTKFile>)");
        goto done;
    }
    int vline = line_of(text, vf);
    if (xml_attr(vf, vf_end, "type", val, sizeof val) != 0 || strcmp(val, "UnstructuredGrid") != 0) {
        st = fail(r, at_line(vline), "VTK XML file of type \"%s\": only \"UnstructuredGrid\" is a volume mesh%s", val,
                  !strcmp(val, "PolyData") ? " (a PolyData file is a surface)" : "");
        goto done;
    }
    if (xml_attr(vf, vf_end, "byte_order", val, sizeof val) == 0) {
        if (!strcmp(val, "BigEndian")) f.big = 1;
        else if (strcmp(val, "LittleEndian") != 0) {
            st = fail(r, at_line(vline), "unknown byte_order \"%s\"", val);
            goto done;
        }
    }
    if (xml_attr(vf, vf_end, "header_type", val, sizeof val) == 0) {
        if (!strcmp(val, "UInt64")) f.header64 = 1;
        else if (strcmp(val, "UInt32") != 0) {
            st = fail(r, at_line(vline), "unknown header_type \"%s\" (UInt32 or UInt64)", val);
            goto done;
        }
    }
    if (xml_attr(vf, vf_end, "compressor", val, sizeof val) == 0 && val[0]) {
        if (!strcmp(val, "vtkZLibDataCompressor")) f.zlib = 1;
        else {
            st = fail(r, at_line(vline), "compressor \"%s\" is not supported (only vtkZLibDataCompressor, or none)", val);
            goto done;
        }
    }
    if (ad) {
        const char *ad_end = memchr(ad, '>', (size_t)(end - ad));
        if (!ad_end) {
            st = fail(r, at_line(line_of(text, ad)), "unterminated <AppendedData> tag");
            goto done;
        }
        f.app_b64 = 1;
        if (xml_attr(ad, ad_end, "encoding", val, sizeof val) == 0) {
            if (!strcmp(val, "raw")) f.app_b64 = 0;
            else if (strcmp(val, "base64") != 0) {
                st = fail(r, at_line(line_of(text, ad)), "unknown AppendedData encoding \"%s\" (raw or base64)", val);
                goto done;
            }
        }
        const char *u = memchr(ad_end, '_', (size_t)(end - ad_end));
        if (!u) {
            st = fail(r, at_line(line_of(text, ad)), "<AppendedData> without its '_' marker");
            goto done;
        }
        f.app = u + 1;
    }
    const char *piece = xml_find(vf_end, f.xml_end, "Piece");
    const char *piece_end = piece ? memchr(piece, '>', (size_t)(f.xml_end - piece)) : NULL;
    if (!piece_end) {
        st = fail(r, at_line(vline), "no <Piece>");
        goto done;
    }
    int pline = line_of(text, piece);
    if (xml_find(piece_end, f.xml_end, "Piece")) {
        st = fail(r, at_line(pline), "more than one <Piece> is not supported");
        goto done;
    }
    long long np, nc;
    if (xml_attr(piece, piece_end, "NumberOfPoints", val, sizeof val) != 0 || parse_int(val, strlen(val), &np) != 0 || np < 0 ||
        np > INT32_MAX || xml_attr(piece, piece_end, "NumberOfCells", val, sizeof val) != 0 ||
        parse_int(val, strlen(val), &nc) != 0 || nc < 0 || nc > INT32_MAX) {
        st = fail(r, at_line(pline), "<Piece> needs valid NumberOfPoints and NumberOfCells");
        goto done;
    }
    const char *close;
    const char *ptag = vtu_section(piece_end, f.xml_end, "Points", &close);
    const char *da = ptag && close ? xml_find(ptag, close, "DataArray") : NULL;
    if (!da) {
        st = fail(r, at_line(pline), "<Piece> without <Points><DataArray>");
        goto done;
    }
    if (vtu_components(da, f.xml_end) != 3) {
        st = fail(r, at_line(line_of(text, da)), "Points: NumberOfComponents must be 3");
        goto done;
    }
    THX_TRY(vtu_array(r, &f, da, "Points", 3 * (size_t)np, &pts));
    {
        int pl = line_of(text, da);
        for (long long i = 0; i < np; i++) THX_TRY(add_node(r, at_line(pl), pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]));
    }
    const char *cells = vtu_section(piece_end, f.xml_end, "Cells", &close);
    if (!cells || !close) {
        st = fail(r, at_line(pline), "<Piece> without a complete <Cells> element");
        goto done;
    }
    const char *ca = NULL, *oa = NULL, *ta = NULL;
    for (const char *p = cells; (p = xml_find(p + 1, close, "DataArray")) != NULL;) {
        const char *gt = memchr(p, '>', (size_t)(close - p));
        if (!gt || xml_attr(p, gt, "Name", val, sizeof val) != 0) continue;
        if (!strcmp(val, "connectivity")) ca = p;
        if (!strcmp(val, "offsets")) oa = p;
        if (!strcmp(val, "types")) ta = p;
    }
    if (!ca || !oa || !ta) {
        st = fail(r, at_line(line_of(text, cells)), "<Cells> needs DataArrays named \"connectivity\", \"offsets\" and \"types\"");
        goto done;
    }
    int cline = line_of(text, ca);
    THX_TRY(vtu_array(r, &f, oa, "Cells offsets", (size_t)nc, &off));
    THX_TRY(vtu_array(r, &f, ta, "Cells types", (size_t)nc, &types));
    double total = nc ? off[nc - 1] : 0;
    if (!(total >= 0 && total <= 64.0 * (double)(nc + 1))) {
        st = fail(r, at_line(line_of(text, oa)), "Cells offsets: last offset %g out of range", total);
        goto done;
    }
    THX_TRY(vtu_array(r, &f, ca, "Cells connectivity", (size_t)total, &conn));
    /* XML offsets are the ends of the cells: prepend the start 0 */
    double *o2 = thx_malloc(r->ctx, ((size_t)nc + 1) * sizeof *o2);
    if (!o2) {
        st = THX_ENOMEM;
        goto done;
    }
    o2[0] = 0;
    if (nc) memcpy(o2 + 1, off, (size_t)nc * sizeof *off);
    free(off);
    off = o2;
    const char *cd = vtu_section(piece_end, f.xml_end, "CellData", &close);
    if (cd && close) {
        for (const char *p = cd; (p = xml_find(p + 1, close, "DataArray")) != NULL;) {
            const char *gt = memchr(p, '>', (size_t)(close - p));
            char nm[128] = "";
            if (!gt || xml_attr(p, gt, "Name", nm, sizeof nm) != 0 || vtu_components(p, f.xml_end) != 1) continue;
            char what[160];
            snprintf(what, sizeof what, "CellData \"%s\"", nm);
            char tyv[32] = "";
            if (xml_attr(p, gt, "type", tyv, sizeof tyv) == 0 && !vtu_type(tyv)) continue; /* strings etc. */
            double *v = NULL;
            THX_TRY(vtu_array(r, &f, p, what, (size_t)nc, &v));
            if (n_arr + 1 > cap_arr) {
                st = thx_grow(r->ctx, (void **)&arr, &cap_arr, n_arr + 1, sizeof *arr);
                if (st) {
                    free(v);
                    goto done;
                }
            }
            snprintf(arr[n_arr].name, sizeof arr[n_arr].name, "%s", nm);
            arr[n_arr].v = v, arr[n_arr].n = (size_t)nc;
            n_arr++;
        }
    }
    int ri;
    THX_TRY(vol_choose_region_array(r, arr, n_arr, region_array, &ri));
    THX_TRY(vol_vtk_tets(r, at_line(cline), types, off, (size_t)nc, conn, (size_t)total, ri >= 0 ? arr[ri].v : NULL,
                     ri >= 0 ? arr[ri].name : NULL));
    if (ri >= 0) snprintf(r->region_source, sizeof r->region_source, "cell array \"%s\"", arr[ri].name);
    else snprintf(r->region_source, sizeof r->region_source, "none (one region%s)",
                  n_arr ? ": no cell array is named as a region array; give --region-array" : "");
    {
        int any_app = 0, any_bin = 0, any_ascii = 0;
        for (const char *p = piece; (p = xml_find(p + 1, f.xml_end, "DataArray")) != NULL;) {
            const char *gt = memchr(p, '>', (size_t)(f.xml_end - p));
            char fm[32] = "ascii";
            if (gt) xml_attr(p, gt, "format", fm, sizeof fm);
            any_app |= !strcmp(fm, "appended"), any_bin |= !strcmp(fm, "binary"), any_ascii |= !strcmp(fm, "ascii");
        }
        snprintf(r->detail, sizeof r->detail, "VTK XML UnstructuredGrid (%s%s%s%s%s)",
                 any_ascii ? "ascii" : "", any_ascii && (any_bin || any_app) ? ", " : "", any_bin ? "binary" : "",
                 any_bin && any_app ? ", " : "",
                 any_app ? (f.app_b64 ? "appended base64" : "appended raw") : "");
        if (f.zlib) snprintf(r->detail + strlen(r->detail) - 1, sizeof r->detail - strlen(r->detail) + 1, ", zlib)");
    }
    r->index_base = 0;
done:
    free(pts);
    free(conn);
    free(off);
    free(types);
    for (size_t i = 0; i < n_arr; i++) free(arr[i].v);
    free(arr);
    return st;
}

