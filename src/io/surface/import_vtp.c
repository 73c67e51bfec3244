/*
 * Surfaces made elsewhere: VTK XML PolyData (.vtp) with ascii arrays (thorax/io/surface_read.h).
 */
#include "io/surface/import_surface.h"

/* Reads an ascii DataArray starting at tag into *out (count values). */
static thx_status vtp_array(build *b, const char *buf, const char *tag, const char *end, const char *what, size_t count,
                            int integer, double **out)
{
    const char *gt = memchr(tag, '>', (size_t)(end - tag));
    if (!gt) return fail(b, at_line(line_of(buf, tag)), "%s: unterminated <DataArray> tag", what);
    char fmt[32] = "ascii";
    if (xml_attr(tag, gt, "format", fmt, sizeof fmt) == 0 && strcmp(fmt, "ascii") != 0)
        return fail(b, at_line(line_of(buf, tag)),
                    "%s: DataArray format \"%s\" is not supported: only format=\"ascii\" (in ParaView, save as "
                    "ASCII; or use a legacy .vtk file)", what, fmt);
    const char *lt = memchr(gt, '<', (size_t)(end - gt));
    if (!lt) return fail(b, at_line(line_of(buf, gt)), "%s: DataArray without its closing tag", what);
    source s = {{gt + 1, (size_t)(lt - gt - 1), 0, line_of(buf, gt)}, 0, 0};
    if (count > s.c.len / 2 + 1) /* as in vtk_values: no allocation for a count the data cannot hold */
        return fail(b, at_line(s.c.line), "%s: %zu values declared, but the DataArray is too short for them", what, count);
    double *v = NULL;
    if (count) {
        v = thx_malloc(b->ctx, count * sizeof *v);
        if (!v) return THX_ENOMEM;
    }
    char w_what[96];
    for (size_t i = 0; i < count; i++) {
        where w;
        snprintf(w_what, sizeof w_what, "%s value %zu", what, i + 1);
        thx_status st = read_scalar(b, &s, integer ? T_I64 : T_F64, w_what, &v[i], &w);
        if (st) {
            free(v);
            return st;
        }
    }
    const char *t;
    int l;
    if (next_token(&s.c, &t, &l)) {
        free(v);
        return fail(b, at_line(l), "%s: more than the %zu values expected", what, count);
    }
    *out = v;
    return THX_OK;
}

thx_status import_read_vtp(build *b, const char *text, size_t len, thx_surface_read_info *info)
{
    thx_status st = THX_OK;
    const char *end = text + len;
    double *pts = NULL, *off = NULL, *conn = NULL;
    int32_t *poly = NULL;
    size_t pcap = 0;
    char val[64];
    const char *vf = xml_find(text, end, "VTKFile");
    if (!vf) {
        st = fail(b, at_line(1), "not a VTK XML file (no <VTKFile>)");
        goto done;
    }
    const char *vf_end = memchr(vf, '>', (size_t)(end - vf));
    if (!vf_end || xml_attr(vf, vf_end, "type", val, sizeof val) != 0 || strcmp(val, "PolyData") != 0) {
        st = fail(b, at_line(line_of(text, vf)), "VTK XML file is not of type \"PolyData\"");
        goto done;
    }
    if (xml_find(vf, end, "AppendedData")) {
        st = fail(b, at_line(line_of(text, vf)), "appended (binary) VTP data is not supported: only format=\"ascii\"");
        goto done;
    }
    const char *piece = xml_find(vf, end, "Piece");
    const char *piece_end = piece ? memchr(piece, '>', (size_t)(end - piece)) : NULL;
    if (!piece_end) {
        st = fail(b, at_line(line_of(text, vf)), "no <Piece>");
        goto done;
    }
    if (xml_find(piece_end, end, "Piece")) {
        st = fail(b, at_line(line_of(text, piece)), "more than one <Piece> is not supported");
        goto done;
    }
    long long np = 0, npoly = 0, nstrip = 0;
    if (xml_attr(piece, piece_end, "NumberOfPoints", val, sizeof val) != 0 || parse_int(val, strlen(val), &np) != 0 ||
        np < 0 || np > INT32_MAX) {
        st = fail(b, at_line(line_of(text, piece)), "<Piece> without a valid NumberOfPoints");
        goto done;
    }
    if (xml_attr(piece, piece_end, "NumberOfPolys", val, sizeof val) == 0 &&
        (parse_int(val, strlen(val), &npoly) != 0 || npoly < 0 || npoly > INT32_MAX)) {
        st = fail(b, at_line(line_of(text, piece)), "<Piece>: invalid NumberOfPolys");
        goto done;
    }
    if (xml_attr(piece, piece_end, "NumberOfStrips", val, sizeof val) == 0 && parse_int(val, strlen(val), &nstrip) == 0 &&
        nstrip > 0) {
        st = fail(b, at_line(line_of(text, piece)), "triangle strips in a VTP file are not supported");
        goto done;
    }
    const char *ptag = xml_find(piece_end, end, "Points");
    const char *da = ptag ? xml_find(ptag, end, "DataArray") : NULL;
    if (!da) {
        st = fail(b, at_line(line_of(text, piece)), "<Piece> without <Points><DataArray>");
        goto done;
    }
    THX_TRY(vtp_array(b, text, da, end, "Points", 3 * (size_t)np, 0, &pts));
    int pts_line = line_of(text, da); /* once: line_of scans from the start of the file */
    for (long long i = 0; i < np; i++) THX_TRY(add_node(b, at_line(pts_line), pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]));
    if (npoly > 0) {
        const char *polys = xml_find(piece_end, end, "Polys");
        const char *pend = polys ? strstr(polys, "</Polys>") : NULL;
        if (!pend) {
            st = fail(b, at_line(line_of(text, piece)), "NumberOfPolys=%lld but no complete <Polys> element", npoly);
            goto done;
        }
        const char *ca = NULL, *oa = NULL;
        for (const char *p = polys; (p = xml_find(p + 1, pend, "DataArray")) != NULL;) {
            const char *gt = memchr(p, '>', (size_t)(pend - p));
            if (!gt) break;
            if (xml_attr(p, gt, "Name", val, sizeof val) != 0) continue;
            if (!strcmp(val, "connectivity")) ca = p;
            if (!strcmp(val, "offsets")) oa = p;
        }
        if (!ca || !oa) {
            st = fail(b, at_line(line_of(text, polys)), "<Polys> needs DataArrays named \"connectivity\" and \"offsets\"");
            goto done;
        }
        THX_TRY(vtp_array(b, text, oa, pend, "Polys offsets", (size_t)npoly, 1, &off));
        double total = off[npoly - 1];
        if (!(total >= 0 && total <= 1e10)) {
            st = fail(b, at_line(line_of(text, oa)), "Polys offsets: last offset %g out of range", total);
            goto done;
        }
        THX_TRY(vtp_array(b, text, ca, pend, "Polys connectivity", (size_t)total, 1, &conn));
        /* XML offsets are the ends of the cells: prepend the start 0 */
        double *o2 = thx_malloc(b->ctx, ((size_t)npoly + 1) * sizeof *o2);
        if (!o2) {
            st = THX_ENOMEM;
            goto done;
        }
        o2[0] = 0;
        memcpy(o2 + 1, off, (size_t)npoly * sizeof *off);
        free(off);
        off = o2;
        THX_TRY(import_vtk_cells(b, 0, off, (size_t)npoly, conn, (size_t)total, 0, at_line(line_of(text, ca)), &poly, &pcap));
    }
    if (info) {
        snprintf(info->format_detail, sizeof info->format_detail, "VTK XML PolyData (ascii)");
        info->index_base = 0;
    }
done:
    free(pts);
    free(off);
    free(conn);
    free(poly);
    return st;
}

