/*
 * The contour file (paper 3.1; docs/formats.md, "Contours"): reading (the structure checked,
 * nothing accepted in part) and writing.
 */
#include "thorax/io/contours_file.h"

#include <ctype.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "thorax/core/fileio.h"

/* ---- reading ----------------------------------------------------------- */

static char *next_token(char **s)
{
    char *p = *s;
    while (*p && isspace((unsigned char)*p)) p++;
    if (!*p) { *s = p; return NULL; }
    char *t = p;
    while (*p && !isspace((unsigned char)*p)) p++;
    if (*p) *p++ = '\0';
    *s = p;
    return t;
}

/* A decimal number and nothing else: [+-] digits [. digits] [e [+-] digits], at least one digit
 * before the exponent. No hex, inf or nan (strtod would take them), no trailing characters, and
 * finite (1e999 is refused, not read as infinity). */
static int parse_num(const char *t, double *v)
{
    const char *q = t;
    int digits = 0;
    if (*q == '+' || *q == '-') q++;
    while (isdigit((unsigned char)*q)) { q++; digits++; }
    if (*q == '.') {
        q++;
        while (isdigit((unsigned char)*q)) { q++; digits++; }
    }
    if (!digits) return 0;
    if (*q == 'e' || *q == 'E') {
        q++;
        if (*q == '+' || *q == '-') q++;
        if (!isdigit((unsigned char)*q)) return 0;
        while (isdigit((unsigned char)*q)) q++;
    }
    if (*q) return 0;
    char *end;
    *v = strtod(t, &end);
    return end == q && isfinite(*v);
}

static thx_status parse(thx_ctx *ctx, const char *name, const char *text, size_t len, thx_contours **out)
{
    thx_contours *c = NULL;
    thx_status st = THX_OK;
    *out = NULL;
    /* A NUL byte would end the text early and the rest would go unread: refused, with its line. */
    const char *nul = memchr(text, '\0', len);
    if (nul) {
        int nl = 1;
        for (const char *q = text; q < nul; q++) nl += *q == '\n';
        return thx_error(ctx, THX_EINPUT, "%s:%d: NUL byte (at byte offset %zu): not a text file", name, nl,
                         (size_t)(nul - text));
    }
    char *buf = thx_malloc(ctx, len + 1);
    if (!buf) return THX_ENOMEM;
    memcpy(buf, text, len);
    buf[len] = '\0';
    int line = 0, seen_header = 0, seen_end = 0, n_layers = 0, direction = 0, layer_loops = 0, frame_line = 0;
    int units_line = 0, spacing_line = 0, unterminated = 0;
    THX_TRY(thx_contours_create(ctx, &c));
    snprintf(c->path, sizeof c->path, "%s", name);

    double scale = 1.0, layer_z = NAN;
    int layer_line = 0;
    thx_loop *cur = NULL;
    const char *cur_surf = NULL;
    size_t cur_cap = 0, cur_loop_no = 0;
    int nonblank = 0;
    char *p = buf;
    while (*p) {
        char *eol = strchr(p, '\n');
        char *next = eol ? eol + 1 : p + strlen(p);
        if (eol) *eol = '\0';
        else unterminated = 1;
        if (line == INT_MAX) { st = thx_error(ctx, THX_EINPUT, "%s: more than %d lines", name, INT_MAX); goto done; }
        line++;
        char *hash = strchr(p, '#');
        if (hash) *hash = '\0';
        char *cursor = p;
        char *kw = next_token(&cursor);
        p = next;
        if (!kw) continue;
        nonblank++;
        if (seen_end) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: text after 'end'", name, line);
            goto done;
        }
        if (!seen_header) {
            char *ver = next_token(&cursor);
            if (strcmp(kw, "thorax-contours") != 0 || !ver || strcmp(ver, "1") != 0 || next_token(&cursor)) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: not a thorax contour file (expected 'thorax-contours 1' as the first line)", name, line);
                goto done;
            }
            seen_header = 1;
            continue;
        }
        double x, y;
        if (isdigit((unsigned char)kw[0]) || kw[0] == '-' || kw[0] == '+' || kw[0] == '.') {
            char *t2 = next_token(&cursor);
            char *t3 = next_token(&cursor);
            if (!cur) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: point outside a loop (a 'loop NAME' line must come first)", name, line);
                goto done;
            }
            if (!parse_num(kw, &x) || !t2 || t3 || !parse_num(t2, &y)) {
                st = thx_error(ctx, THX_EINPUT,
                               "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu point %zu: a point is two finite "
                               "decimal numbers 'x y'",
                               name, line, cur_surf, n_layers, layer_z, cur_loop_no, cur->n + 1);
                goto done;
            }
            if (!isfinite(x * scale) || !isfinite(y * scale)) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\" layer %d loop %zu point %zu: out of range in mm",
                               name, line, cur_surf, n_layers, cur_loop_no, cur->n + 1);
                goto done;
            }
            if (cur->n + 1 > cur_cap) {
                size_t ncap = cur_cap ? cur_cap * 2 : 8;
                thx_vec2 *np = thx_realloc(ctx, cur->p, ncap * sizeof *np);
                if (!np) { st = THX_ENOMEM; goto done; }
                cur->p = np;
                int *nl = thx_realloc(ctx, cur->lines, ncap * sizeof *nl);
                if (!nl) { st = THX_ENOMEM; goto done; }
                cur->lines = nl;
                cur_cap = ncap;
            }
            cur->p[cur->n].x = x * scale;
            cur->p[cur->n].y = y * scale;
            cur->lines[cur->n] = line;
            cur->n++;
            continue;
        }
        int was_in_loop = cur != NULL;
        cur = NULL;
        cur_cap = 0;
        if (strcmp(kw, "units") == 0) {
            char *u = next_token(&cursor);
            if (n_layers > 0) { st = thx_error(ctx, THX_EINPUT, "%s:%d: 'units' must come before the first layer", name, line); goto done; }
            if (units_line) { st = thx_error(ctx, THX_EINPUT, "%s:%d: 'units' given twice (first at line %d)", name, line, units_line); goto done; }
            if (spacing_line) { st = thx_error(ctx, THX_EINPUT, "%s:%d: 'units' must come before 'spacing' (line %d)", name, line, spacing_line); goto done; }
            units_line = line;
            if (u && strcmp(u, "mm") == 0) scale = 1.0;
            else if (u && strcmp(u, "cm") == 0) scale = 10.0;
            else if (u && strcmp(u, "m") == 0) scale = 1000.0;
            else { st = thx_error(ctx, THX_EINPUT, "%s:%d: unknown units '%s' (mm, cm or m)", name, line, u ? u : ""); goto done; }
            if (next_token(&cursor)) { st = thx_error(ctx, THX_EINPUT, "%s:%d: unexpected text after 'units %s'", name, line, u); goto done; }
        } else if (strcmp(kw, "spacing") == 0) {
            char *t = next_token(&cursor);
            double v;
            if (!t || !parse_num(t, &v) || !(v > 0) || !isfinite(v * scale) || next_token(&cursor)) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: expected 'spacing S' with S > 0 (node spacing, file units)", name, line);
                goto done;
            }
            if (spacing_line) { st = thx_error(ctx, THX_EINPUT, "%s:%d: 'spacing' given twice (first at line %d)", name, line, spacing_line); goto done; }
            spacing_line = line;
            c->spacing = v * scale;
        } else if (strcmp(kw, "frame") == 0) {
            char *up = next_token(&cursor), *front = next_token(&cursor);
            if (n_layers > 0) { st = thx_error(ctx, THX_EINPUT, "%s:%d: 'frame' must come before the first layer", name, line); goto done; }
            if (frame_line) { st = thx_error(ctx, THX_EINPUT, "%s:%d: 'frame' given twice (first at line %d)", name, line, frame_line); goto done; }
            if (!up || !front || next_token(&cursor)) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: expected 'frame UP FRONT' (the superior and anterior axes, e.g. 'frame +z +y')", name, line);
                goto done;
            }
            char what[600];
            snprintf(what, sizeof what, "%s:%d: frame", name, line);
            THX_TRY(thx_frame_from_names(ctx, up, front, what, &c->frame));
            frame_line = line;
        } else if (strcmp(kw, "image") == 0) {
            /* image sha256:HEX PATH: the image the contours were traced from (PATH: the rest of the
               line, '#', '%' and control characters as %XX) */
            char *h = next_token(&cursor);
            while (*cursor && isspace((unsigned char)*cursor)) cursor++;
            size_t pl = strlen(cursor);
            while (pl && isspace((unsigned char)cursor[pl - 1])) cursor[--pl] = '\0';
            int hex_ok = h && strlen(h) == 71 && strncmp(h, "sha256:", 7) == 0;
            for (int k = 7; hex_ok && k < 71; k++) hex_ok = isdigit((unsigned char)h[k]) || (h[k] >= 'a' && h[k] <= 'f');
            if (n_layers > 0) { st = thx_error(ctx, THX_EINPUT, "%s:%d: 'image' must come before the first layer", name, line); goto done; }
            if (c->image[0]) { st = thx_error(ctx, THX_EINPUT, "%s:%d: 'image' given twice", name, line); goto done; }
            if (!hex_ok || !pl || pl >= sizeof c->image) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: expected 'image sha256:HEX PATH' (the image's SHA-256, 64 lowercase hex digits, then its path)", name, line);
                goto done;
            }
            size_t o = 0;
            for (size_t k = 0; k < pl; k++) {
                unsigned v;
                if (cursor[k] == '%' && k + 2 < pl && isxdigit((unsigned char)cursor[k + 1]) &&
                    isxdigit((unsigned char)cursor[k + 2]) && sscanf(cursor + k + 1, "%2x", &v) == 1) {
                    c->image[o++] = (char)v;
                    k += 2;
                } else c->image[o++] = cursor[k];
            }
            c->image[o] = '\0';
            memcpy(c->image_sha256, h + 7, 65);
        } else if (strcmp(kw, "surface") == 0) {
            char *sname = next_token(&cursor), *srole = next_token(&cursor);
            thx_role role;
            if (!sname || !srole) { st = thx_error(ctx, THX_EINPUT, "%s:%d: expected 'surface NAME ROLE [cap polygon|grid [SPACING]]'", name, line); goto done; }
            if (n_layers > 0) { st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\" declared after the first layer", name, line, sname); goto done; }
            if (thx_role_parse(srole, &role) != 0) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": unknown role '%s' (outer, fat, muscle, lung, heart, other)", name, line, sname, srole);
                goto done;
            }
            thx_cap_method cap = THX_CAP_GRID;
            double grid = 0;
            char *t = next_token(&cursor);
            if (t) {
                char *m = next_token(&cursor);
                if (strcmp(t, "cap") != 0 || !m) { st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": expected 'cap polygon' or 'cap grid [SPACING]' after the role", name, line, sname); goto done; }
                if (strcmp(m, "polygon") == 0) cap = THX_CAP_POLYGON;
                else if (strcmp(m, "grid") == 0) cap = THX_CAP_GRID;
                else { st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": unknown cap method '%s' (polygon or grid)", name, line, sname, m); goto done; }
                char *g = next_token(&cursor);
                if (g && (cap != THX_CAP_GRID || !parse_num(g, &grid) || !(grid > 0) || !isfinite(grid * scale))) {
                    st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": bad grid spacing '%s'", name, line, sname, g);
                    goto done;
                }
                grid *= scale;
                if (next_token(&cursor)) { st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": unexpected text after the cap", name, line, sname); goto done; }
            }
            if (thx_contours_find_surface(c, sname) >= 0) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\" declared twice (first at line %d)", name, line, sname,
                               c->surf[thx_contours_find_surface(c, sname)].line);
                goto done;
            }
            size_t idx;
            st = thx_contours_add_surface(ctx, c, sname, role, cap, grid, &idx);
            if (st != THX_OK) {
                char m[600];
                snprintf(m, sizeof m, "%s", thx_ctx_message(ctx));
                st = thx_error(ctx, st, "%s:%d: %s", name, line, m);
                goto done;
            }
            c->surf[idx].line = line;
        } else if (strcmp(kw, "layer") == 0) {
            char *zt = next_token(&cursor);
            double z;
            if (!zt || !parse_num(zt, &z) || next_token(&cursor)) { st = thx_error(ctx, THX_EINPUT, "%s:%d: expected 'layer Z' with Z a finite number in the file's units", name, line); goto done; }
            if (!isfinite(z * scale)) { st = thx_error(ctx, THX_EINPUT, "%s:%d: layer z is out of range in mm", name, line); goto done; }
            if (c->n_surfaces == 0) { st = thx_error(ctx, THX_EINPUT, "%s:%d: layer before any 'surface' line", name, line); goto done; }
            z *= scale;
            if (n_layers > 0) {
                if (layer_loops == 0) { st = thx_error(ctx, THX_EINPUT, "%s:%d: layer %d (z=%g) has no loops", name, layer_line, n_layers, layer_z); goto done; }
                if (z == layer_z) { st = thx_error(ctx, THX_EINPUT, "%s:%d: layer z=%g duplicates the layer at line %d", name, line, z, layer_line); goto done; }
                int d = z > layer_z ? 1 : -1;
                if (direction == 0) direction = d;
                else if (d != direction) {
                    st = thx_error(ctx, THX_EINPUT, "%s:%d: layer z=%g is out of order (layers must run %s in z; previous z=%g)", name, line, z,
                                   direction > 0 ? "upward" : "downward", layer_z);
                    goto done;
                }
            }
            layer_z = z;
            layer_line = line;
            layer_loops = 0;
            n_layers++;
        } else if (strcmp(kw, "loop") == 0) {
            char *sname = next_token(&cursor);
            if (!sname || next_token(&cursor)) { st = thx_error(ctx, THX_EINPUT, "%s:%d: expected 'loop SURFACE'", name, line); goto done; }
            if (n_layers == 0) { st = thx_error(ctx, THX_EINPUT, "%s:%d: loop before the first 'layer' line", name, line); goto done; }
            int s = thx_contours_find_surface(c, sname);
            if (s < 0) { st = thx_error(ctx, THX_EINPUT, "%s:%d: loop of undeclared surface \"%s\"", name, line, sname); goto done; }
            thx_contour_layer *L;
            THX_TRY(thx_contours_layer(ctx, &c->surf[s], layer_z, n_layers - 1, layer_line, &L));
            THX_TRY(thx_contours_layer_add_loop(ctx, L, line, &cur));
            cur_surf = c->surf[s].name;
            cur_loop_no = L->n_loops;
            layer_loops++;
        } else if (strcmp(kw, "end") == 0) {
            if (next_token(&cursor)) { st = thx_error(ctx, THX_EINPUT, "%s:%d: unexpected text after 'end'", name, line); goto done; }
            if (n_layers > 0 && layer_loops == 0) { st = thx_error(ctx, THX_EINPUT, "%s:%d: layer %d (z=%g) has no loops", name, layer_line, n_layers, layer_z); goto done; }
            seen_end = 1;
        } else if (was_in_loop && (strncasecmp(kw, "nan", 3) == 0 || strncasecmp(kw, "inf", 3) == 0 ||
                                   strncasecmp(kw, "-nan", 4) == 0) && strlen(kw) < 40) {
            st = thx_error(ctx, THX_EINPUT,
                           "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: '%s' is neither a keyword nor a finite "
                           "decimal number (a point is two numbers 'x y')",
                           name, line, cur_surf, n_layers, layer_z, cur_loop_no, kw);
            goto done;
        } else {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: unknown keyword '%.40s'", name, line, kw);
            goto done;
        }
    }
    if (nonblank == 0) { st = thx_error(ctx, THX_EINPUT, "%s: empty file", name); goto done; }
    if (!seen_end) {
        if (cur)
            st = thx_error(ctx, THX_EINPUT, "%s:%d: truncated file: surface \"%s\" layer %d loop %zu is cut short (no 'end' line)",
                           name, line, cur_surf, n_layers, cur_loop_no);
        else
            st = thx_error(ctx, THX_EINPUT, "%s:%d: truncated file (no 'end' line)", name, line);
        unterminated = 0; /* said already */
        goto done;
    }
    c->n_layers = (size_t)n_layers;
    /* Layers were read in file order; store each surface's layers by increasing z. */
    if (direction < 0)
        for (size_t s = 0; s < c->n_surfaces; s++) {
            thx_contour_surface *cs = &c->surf[s];
            for (size_t i = 0, j = cs->n_layers ? cs->n_layers - 1 : 0; i < j; i++, j--) {
                thx_contour_layer t = cs->layers[i];
                cs->layers[i] = cs->layers[j];
                cs->layers[j] = t;
            }
            for (size_t i = 0; i < cs->n_layers; i++) cs->layers[i].index = n_layers - 1 - cs->layers[i].index;
        }
    THX_TRY(thx_contours_validate_structure(ctx, c));
done:
    free(buf);
    if (st == THX_EINPUT && unterminated && len > 0) { /* the error is on the last line, which has no newline */
        char m[1200];
        snprintf(m, sizeof m, "%s", thx_ctx_message(ctx));
        st = thx_error(ctx, st, "%s (the file ends in this line, without a newline: is it cut short?)", m);
    }
    if (st != THX_OK) thx_contours_destroy(&c);
    *out = c;
    return st;
}

thx_status thx_contours_parse_raw(thx_ctx *ctx, const char *name, const char *text, size_t len, thx_contours **out)
{
    return parse(ctx, name, text, len, out);
}

thx_status thx_contours_read_raw(thx_ctx *ctx, const char *path, thx_contours **out)
{
    char *text = NULL;
    size_t len = 0;
    *out = NULL;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    thx_status st = parse(ctx, path, text, len, out);
    free(text);
    return st;
}

/* ---- writing ----------------------------------------------------------- */

thx_status thx_contours_write(thx_ctx *ctx, const thx_contours *c, const char *path, const char *comment)
{
    double *zs = NULL;
    size_t nz = 0;
    THX_CHECK(thx_contours_layer_z(ctx, c, &zs, &nz));
    thx_atomic_file af;
    /* an existing file is replaced only when it is thorax's own contours (thorax/core/fileio.h) */
    thx_status st = thx_atomic_open_output(ctx, path, "thorax-contours", 15, NULL, 0, &af);
    if (st != THX_OK) { free(zs); return st; }
    FILE *f = af.f;
    fprintf(f, "thorax-contours 1\n");
    if (comment && comment[0]) {
        const char *p = comment;
        while (*p) {
            const char *e = strchr(p, '\n');
            int n = e ? (int)(e - p) : (int)strlen(p);
            fprintf(f, "# %.*s\n", n, p);
            p += n + (e ? 1 : 0);
        }
    }
    fprintf(f, "units mm\n");
    if (c->spacing > 0) fprintf(f, "spacing %.17g\n", c->spacing);
    if (c->frame.set) {
        char u[3], v[3];
        fprintf(f, "frame %s %s\n", thx_axis_name(c->frame.up, u), thx_axis_name(c->frame.front, v));
    }
    if (c->image[0] && strlen(c->image_sha256) == 64) {
        fprintf(f, "image sha256:%s ", c->image_sha256);
        for (const unsigned char *q = (const unsigned char *)c->image; *q; q++)
            if (*q == '#' || *q == '%' || *q < 0x20 || *q == 0x7f || (q[1] == '\0' && isspace(*q)) || (q == (const unsigned char *)c->image && isspace(*q)))
                fprintf(f, "%%%02X", *q);
            else fputc(*q, f);
        fprintf(f, "\n");
    }
    for (size_t s = 0; s < c->n_surfaces; s++) {
        const thx_contour_surface *cs = &c->surf[s];
        fprintf(f, "surface %s %s cap %s", cs->name, thx_role_name(cs->role), cs->cap == THX_CAP_POLYGON ? "polygon" : "grid");
        if (cs->cap == THX_CAP_GRID && cs->cap_grid > 0) fprintf(f, " %.17g", cs->cap_grid);
        fprintf(f, "\n");
    }
    size_t *pos = calloc(c->n_surfaces ? c->n_surfaces : 1, sizeof *pos);
    if (!pos) { thx_atomic_abort(&af); free(zs); return thx_error(ctx, THX_ENOMEM, "out of memory"); }
    for (size_t k = 0; k < nz; k++) {
        fprintf(f, "layer %.17g\n", zs[k]);
        for (size_t s = 0; s < c->n_surfaces; s++) {
            const thx_contour_surface *cs = &c->surf[s];
            if (pos[s] >= cs->n_layers || cs->layers[pos[s]].z != zs[k]) continue;
            const thx_contour_layer *L = &cs->layers[pos[s]++];
            for (size_t i = 0; i < L->n_loops; i++) {
                fprintf(f, "loop %s\n", cs->name);
                for (size_t j = 0; j < L->loops[i].n; j++) fprintf(f, "%.6f %.6f\n", L->loops[i].p[j].x, L->loops[i].p[j].y);
            }
        }
    }
    fprintf(f, "end\n");
    free(pos);
    free(zs);
    return thx_atomic_commit(ctx, &af);
}
