/*
 * Contour files (paper 3.1): reading, validation, writing, in-memory builders.
 * Format: docs/formats.md, "Contours".
 */
#include "thorax/contours.h"

#include <ctype.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "thorax/fileio.h"
#include "thorax/predicates.h"

/* Grows an array of n elements by one: arrays grown only here have capacity n rounded up to a
 * power of two, so a file of many small loops costs O(total) copying, not O(n^2). */
static void *grow_one(thx_ctx *ctx, void *a, size_t n, size_t size)
{
    if (n && (n & (n - 1))) return a; /* not a power of two: room left */
    size_t cap = n ? 2 * n : 1;
    return thx_realloc(ctx, a, cap * size);
}

/* ---- builders ---------------------------------------------------------- */

thx_status thx_contours_create(thx_ctx *ctx, thx_contours **out)
{
    *out = thx_calloc(ctx, 1, sizeof **out);
    return *out ? THX_OK : THX_ENOMEM;
}

void thx_contours_destroy(thx_contours **c)
{
    if (!c || !*c) return;
    thx_contours *k = *c;
    for (size_t s = 0; s < k->n_surfaces; s++) {
        thx_contour_surface *cs = &k->surf[s];
        for (size_t l = 0; l < cs->n_layers; l++) {
            for (size_t i = 0; i < cs->layers[l].n_loops; i++) {
                free(cs->layers[l].loops[i].p);
                free(cs->layers[l].loops[i].lines);
            }
            free(cs->layers[l].loops);
        }
        free(cs->layers);
    }
    free(k->surf);
    free(k);
    *c = NULL;
}

static int find_surface(const thx_contours *c, const char *name)
{
    for (size_t s = 0; s < c->n_surfaces; s++)
        if (strcmp(c->surf[s].name, name) == 0) return (int)s;
    return -1;
}

thx_status thx_contours_add_surface(thx_ctx *ctx, thx_contours *c, const char *name, thx_role role,
                                    thx_cap_method cap, double cap_grid, size_t *idx)
{
    if (strlen(name) == 0 || strlen(name) >= sizeof c->surf[0].name)
        return thx_error(ctx, THX_EINPUT, "surface name '%s' is empty or longer than 63 characters", name);
    if (find_surface(c, name) >= 0) return thx_error(ctx, THX_EINPUT, "surface \"%s\" declared twice", name);
    thx_contour_surface *ns = grow_one(ctx, c->surf, c->n_surfaces, sizeof *ns);
    if (!ns) return THX_ENOMEM;
    c->surf = ns;
    thx_contour_surface *cs = &c->surf[c->n_surfaces];
    memset(cs, 0, sizeof *cs);
    snprintf(cs->name, sizeof cs->name, "%s", name);
    cs->role = role;
    cs->cap = cap;
    cs->cap_grid = cap_grid;
    if (idx) *idx = c->n_surfaces;
    c->n_surfaces++;
    return THX_OK;
}

/* Returns the layer of surface s at height z, appending it if z is new. */
static thx_status surface_layer(thx_ctx *ctx, thx_contour_surface *cs, double z, int index, int line,
                                thx_contour_layer **out)
{
    if (cs->n_layers && cs->layers[cs->n_layers - 1].z == z) {
        *out = &cs->layers[cs->n_layers - 1];
        return THX_OK;
    }
    thx_contour_layer *nl = grow_one(ctx, cs->layers, cs->n_layers, sizeof *nl);
    if (!nl) return THX_ENOMEM;
    cs->layers = nl;
    thx_contour_layer *L = &cs->layers[cs->n_layers++];
    memset(L, 0, sizeof *L);
    L->z = z;
    L->index = index;
    L->line = line;
    *out = L;
    return THX_OK;
}

static thx_status layer_add_loop(thx_ctx *ctx, thx_contour_layer *L, int line, thx_loop **out)
{
    thx_loop *nl = grow_one(ctx, L->loops, L->n_loops, sizeof *nl);
    if (!nl) return THX_ENOMEM;
    L->loops = nl;
    thx_loop *lp = &L->loops[L->n_loops++];
    memset(lp, 0, sizeof *lp);
    lp->line = line;
    *out = lp;
    return THX_OK;
}

thx_status thx_contours_add_loop(thx_ctx *ctx, thx_contours *c, size_t s, double z, const thx_vec2 *pts, size_t n)
{
    if (s >= c->n_surfaces) return thx_error(ctx, THX_EINPUT, "no surface %zu", s);
    thx_contour_surface *cs = &c->surf[s];
    if (cs->n_layers && z < cs->layers[cs->n_layers - 1].z)
        return thx_error(ctx, THX_EINPUT, "surface \"%s\": layer z=%g added after z=%g", cs->name, z,
                         cs->layers[cs->n_layers - 1].z);
    /* The file-wide layer index: count distinct z over all surfaces lazily at write time. */
    thx_contour_layer *L;
    THX_CHECK(surface_layer(ctx, cs, z, -1, 0, &L));
    thx_loop *lp;
    THX_CHECK(layer_add_loop(ctx, L, 0, &lp));
    lp->p = thx_malloc(ctx, (n ? n : 1) * sizeof *lp->p);
    if (!lp->p) return THX_ENOMEM;
    memcpy(lp->p, pts, n * sizeof *pts);
    lp->n = n;
    return THX_OK;
}

/* ---- validation -------------------------------------------------------- */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Sorted distinct z of all layers of all surfaces. */
static thx_status all_layer_z(thx_ctx *ctx, const thx_contours *c, double **zs, size_t *nz)
{
    size_t total = 0;
    for (size_t s = 0; s < c->n_surfaces; s++) total += c->surf[s].n_layers;
    double *z = thx_malloc(ctx, (total ? total : 1) * sizeof *z);
    if (!z) return THX_ENOMEM;
    size_t k = 0;
    for (size_t s = 0; s < c->n_surfaces; s++)
        for (size_t l = 0; l < c->surf[s].n_layers; l++) z[k++] = c->surf[s].layers[l].z;
    qsort(z, k, sizeof *z, cmp_double);
    size_t m = 0;
    for (size_t i = 0; i < k; i++)
        if (m == 0 || z[i] != z[m - 1]) z[m++] = z[i];
    *zs = z;
    *nz = m;
    return THX_OK;
}

static size_t z_index(const double *zs, size_t nz, double z)
{
    size_t lo = 0, hi = nz;
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (zs[mid] <= z) lo = mid; else hi = mid;
    }
    return lo;
}


/* Finds a pair of non-adjacent edges of a closed loop that touch (an O(n log n) sweep), or a spike. */
static int loop_self_intersection(thx_ctx *ctx, const thx_loop *lp, int *ei, int *ej)
{
    int n = (int)lp->n;
    size_t e1 = 0, e2 = 0;
    int found = thx_loop_touch(&lp->p[0].x, lp->n, &e1, &e2);
    if (found < 0) return -1;
    if (found) { *ei = (int)e1; *ej = (int)e2; }
    (void)ctx;
    /* Adjacent edges folding back onto each other (a spike) also make a loop invalid. */
    if (!found)
        for (int i = 0; i < n; i++) {
            thx_vec2 a = lp->p[(i + n - 1) % n], b = lp->p[i], c = lp->p[(i + 1) % n];
            if (thx_orient2d(&a.x, &b.x, &c.x) == 0 && (a.x - b.x) * (c.x - b.x) + (a.y - b.y) * (c.y - b.y) > 0) {
                *ei = (i + n - 1) % n;
                *ej = i;
                return 1;
            }
        }
    return found;
}

/* Layer number for messages: the file's, or the surface's own for contours built in memory. */
static int layer_no(const double *zs, size_t nz, const thx_contour_layer *L)
{
    return L->index >= 0 ? L->index + 1 : (int)z_index(zs, nz, L->z) + 1;
}

/* The structure (surfaces, layers, loop sizes, finite values) and, when `geometry`, the loops'
 * geometry (no repeated consecutive points, no self-intersection). */
static thx_status validate(thx_ctx *ctx, const thx_contours *c, int geometry)
{
    const char *path = c->path[0] ? c->path : "<contours>";
    if (c->n_surfaces == 0) return thx_error(ctx, THX_EINPUT, "%s: no surfaces declared", path);
    double *zs = NULL;
    size_t nz = 0;
    THX_CHECK(all_layer_z(ctx, c, &zs, &nz));
    thx_status st = THX_OK;
    for (size_t s = 0; s < c->n_surfaces && st == THX_OK; s++) {
        const thx_contour_surface *cs = &c->surf[s];
        if (cs->n_layers == 0) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\" has no loops", path, cs->line, cs->name);
            break;
        }
        for (size_t l = 0; l < cs->n_layers && st == THX_OK; l++) {
            const thx_contour_layer *L = &cs->layers[l];
            int lno = layer_no(zs, nz, L);
            if (!isfinite(L->z)) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\" layer %d: z is not finite", path, L->line,
                               cs->name, lno);
                break;
            }
            if (l > 0) {
                const thx_contour_layer *P = &cs->layers[l - 1];
                if (!(L->z > P->z)) {
                    st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\": layer z=%g is out of order after z=%g",
                                   path, L->line, cs->name, L->z, P->z);
                    break;
                }
                size_t ip = z_index(zs, nz, P->z), il = z_index(zs, nz, L->z);
                if (il != ip + 1) {
                    st = thx_error(ctx, THX_EINPUT,
                                   "%s:%d: surface \"%s\" vanishes at z=%g and reappears at z=%g "
                                   "(a surface must be digitized on consecutive layers)",
                                   path, L->line, cs->name, zs[ip + 1], L->z);
                    break;
                }
            }
            for (size_t i = 0; i < L->n_loops && st == THX_OK; i++) {
                const thx_loop *lp = &L->loops[i];
                int where = lp->line ? lp->line : L->line;
                if (lp->n < 3) {
                    st = thx_error(ctx, THX_EINPUT,
                                   "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: loop has %zu point%s (at least 3 needed)",
                                   path, where, cs->name, lno, L->z, i + 1, lp->n, lp->n == 1 ? "" : "s");
                    break;
                }
                for (size_t k = 0; k < lp->n; k++) {
                    thx_vec2 a = lp->p[k], b = lp->p[(k + 1) % lp->n];
                    int line = lp->lines ? lp->lines[k] : where;
                    if (!isfinite(a.x) || !isfinite(a.y)) {
                        st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: point %zu is not finite",
                                       path, line, cs->name, lno, L->z, i + 1, k + 1);
                        break;
                    }
                    if (geometry && a.x == b.x && a.y == b.y) {
                        int bl = lp->lines ? lp->lines[(k + 1) % lp->n] : where;
                        if (k + 1 == lp->n)
                            st = thx_error(ctx, THX_EINPUT,
                                           "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: the last point repeats the "
                                           "first point (%g, %g): a loop is closed without repeating its first point",
                                           path, line, cs->name, lno, L->z, i + 1, a.x, a.y);
                        else
                            st = thx_error(ctx, THX_EINPUT,
                                           "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: point %zu repeats point %zu (%g, %g)",
                                           path, bl, cs->name, lno, L->z, i + 1, k + 2, k + 1, a.x, a.y);
                        break;
                    }
                }
                if (st != THX_OK || !geometry) continue;
                int ei = 0, ej = 0;
                int r = loop_self_intersection(ctx, lp, &ei, &ej);
                if (r < 0) { st = thx_error(ctx, THX_ENOMEM, "out of memory"); break; }
                if (r > 0) {
                    int line = lp->lines ? lp->lines[ei] : where;
                    st = thx_error(ctx, THX_EINPUT,
                                   "%s:%d: surface \"%s\" layer %d (z=%g) loop %zu: loop intersects itself "
                                   "(edge %d-%d crosses edge %d-%d)",
                                   path, line, cs->name, lno, L->z, i + 1, ei + 1, (int)((ei + 1) % lp->n) + 1,
                                   ej + 1, (int)((ej + 1) % lp->n) + 1);
                    break;
                }
            }
        }
    }
    free(zs);
    return st;
}

thx_status thx_contours_validate(thx_ctx *ctx, const thx_contours *c) { return validate(ctx, c, 1); }

thx_status thx_contours_validate_structure(thx_ctx *ctx, const thx_contours *c) { return validate(ctx, c, 0); }

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

static thx_status parse(thx_ctx *ctx, const char *name, const char *text, size_t len, int geometry, thx_contours **out)
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
    THX_TRY(thx_contours_create(ctx, &c));
    snprintf(c->path, sizeof c->path, "%s", name);

    int line = 0, seen_header = 0, seen_end = 0, n_layers = 0, direction = 0, layer_loops = 0, frame_line = 0;
    int units_line = 0, spacing_line = 0, unterminated = 0;
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
            if (find_surface(c, sname) >= 0) {
                st = thx_error(ctx, THX_EINPUT, "%s:%d: surface \"%s\" declared twice (first at line %d)", name, line, sname,
                               c->surf[find_surface(c, sname)].line);
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
            int s = find_surface(c, sname);
            if (s < 0) { st = thx_error(ctx, THX_EINPUT, "%s:%d: loop of undeclared surface \"%s\"", name, line, sname); goto done; }
            thx_contour_layer *L;
            THX_TRY(surface_layer(ctx, &c->surf[s], layer_z, n_layers - 1, layer_line, &L));
            THX_TRY(layer_add_loop(ctx, L, line, &cur));
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
    THX_TRY(validate(ctx, c, geometry));
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

thx_status thx_contours_parse(thx_ctx *ctx, const char *name, const char *text, size_t len, thx_contours **out)
{
    return parse(ctx, name, text, len, 1, out);
}

thx_status thx_contours_parse_raw(thx_ctx *ctx, const char *name, const char *text, size_t len, thx_contours **out)
{
    return parse(ctx, name, text, len, 0, out);
}

static thx_status read_file(thx_ctx *ctx, const char *path, int geometry, thx_contours **out)
{
    char *text = NULL;
    size_t len = 0;
    *out = NULL;
    THX_CHECK(thx_read_file(ctx, path, &text, &len));
    thx_status st = parse(ctx, path, text, len, geometry, out);
    free(text);
    return st;
}

thx_status thx_contours_read(thx_ctx *ctx, const char *path, thx_contours **out) { return read_file(ctx, path, 1, out); }

thx_status thx_contours_read_raw(thx_ctx *ctx, const char *path, thx_contours **out) { return read_file(ctx, path, 0, out); }

/* ---- writing ----------------------------------------------------------- */

thx_status thx_contours_write(thx_ctx *ctx, const thx_contours *c, const char *path, const char *comment)
{
    double *zs = NULL;
    size_t nz = 0;
    THX_CHECK(all_layer_z(ctx, c, &zs, &nz));
    thx_atomic_file af;
    /* an existing file is replaced only when it is thorax's own contours (thorax/fileio.h) */
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
