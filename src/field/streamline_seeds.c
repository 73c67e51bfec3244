/* Seeds of current streamlines (thorax/field/streamline.h): a point, a line rake, a sphere, a tissue
 * region, or drawn by |J| density. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "field/streamline_impl.h"

/* "X,Y,Z" ending at end (exclusive): 3 finite numbers. */
static int read_xyz(const char *s, const char *end, double p[3])
{
    for (int c = 0; c < 3; c++) {
        char *e;
        errno = 0;
        p[c] = strtod(s, &e);
        if (e == s || errno || !isfinite(p[c])) return 0;
        s = e;
        if (c < 2) {
            if (*s != ',') return 0;
            s++;
        }
    }
    return s == end;
}

static int read_count(const char *s, size_t *n)
{
    char *e;
    errno = 0;
    if (*s < '0' || *s > '9') return 0;
    unsigned long long v = strtoull(s, &e, 10);
    if (*e || errno || v < 1 || v > 100000000ull) return 0;
    *n = (size_t)v;
    return 1;
}

thx_status thx_seed_spec_parse(thx_ctx *ctx, const char *text, thx_seed_spec *s)
{
    memset(s, 0, sizeof *s);
    s->rng_seed = 1;
    s->n = 1;
    if (strlen(text) >= sizeof s->text)
        return thx_error(ctx, THX_EINPUT, "seed \"%.40s...\": too long", text);
    strcpy(s->text, text);
    const char *colon = strchr(text, ':');
    if (!colon)
        return thx_error(ctx, THX_EINPUT, "seed \"%s\": expected point:X,Y,Z, line:X,Y,Z:X,Y,Z:N, sphere:X,Y,Z:R:N, "
                                          "region:NAME:N or density:N", text);
    size_t kl = (size_t)(colon - text);
    const char *rest = colon + 1;
    char parts[4][128];
    int np = 0;
    for (const char *p = rest;; np++) {
        const char *q = strchr(p, ':');
        size_t l = q ? (size_t)(q - p) : strlen(p);
        if (np == 4 || l >= sizeof parts[0]) return thx_error(ctx, THX_EINPUT, "seed \"%s\": too many parts", text);
        memcpy(parts[np], p, l);
        parts[np][l] = '\0';
        if (!q) {
            np++;
            break;
        }
        p = q + 1;
    }
#define PART_XYZ(i, dst, what)                                                                                   \
    if (!read_xyz(parts[i], parts[i] + strlen(parts[i]), dst))                                                   \
        return thx_error(ctx, THX_EINPUT, "seed \"%s\": %s \"%s\" is not X,Y,Z (three numbers, mm)", text, what, \
                         parts[i]);
#define PART_N(i)                                                                                                      \
    if (!read_count(parts[i], &s->n))                                                                                  \
        return thx_error(ctx, THX_EINPUT, "seed \"%s\": the count \"%s\" is not a whole number from 1 to 100000000", text, \
                         parts[i]);
    if (kl == 5 && !strncmp(text, "point", 5)) {
        if (np != 1) return thx_error(ctx, THX_EINPUT, "seed \"%s\": expected point:X,Y,Z", text);
        s->kind = THX_SEED_POINT;
        PART_XYZ(0, s->a, "the point");
    } else if (kl == 4 && !strncmp(text, "line", 4)) {
        if (np != 3) return thx_error(ctx, THX_EINPUT, "seed \"%s\": expected line:X,Y,Z:X,Y,Z:N", text);
        s->kind = THX_SEED_LINE;
        PART_XYZ(0, s->a, "the start");
        PART_XYZ(1, s->b, "the end");
        PART_N(2);
    } else if (kl == 6 && !strncmp(text, "sphere", 6)) {
        if (np != 3) return thx_error(ctx, THX_EINPUT, "seed \"%s\": expected sphere:X,Y,Z:R:N", text);
        s->kind = THX_SEED_SPHERE;
        PART_XYZ(0, s->a, "the centre");
        char *e;
        errno = 0;
        s->radius = strtod(parts[1], &e);
        if (e == parts[1] || *e || errno || !(s->radius > 0) || !isfinite(s->radius))
            return thx_error(ctx, THX_EINPUT, "seed \"%s\": the radius \"%s\" is not a positive number (mm)", text,
                             parts[1]);
        PART_N(2);
    } else if (kl == 6 && !strncmp(text, "region", 6)) {
        if (np != 2) return thx_error(ctx, THX_EINPUT, "seed \"%s\": expected region:NAME:N", text);
        s->kind = THX_SEED_REGION;
        if (!parts[0][0] || strlen(parts[0]) >= sizeof s->region)
            return thx_error(ctx, THX_EINPUT, "seed \"%s\": no region name, or one too long", text);
        strcpy(s->region, parts[0]);
        PART_N(1);
    } else if (kl == 7 && !strncmp(text, "density", 7)) {
        if (np != 1) return thx_error(ctx, THX_EINPUT, "seed \"%s\": expected density:N", text);
        s->kind = THX_SEED_DENSITY;
        PART_N(0);
    } else {
        return thx_error(ctx, THX_EINPUT, "seed \"%s\": unknown kind \"%.*s\" (point, line, sphere, region or density)",
                         text, (int)kl, text);
    }
#undef PART_XYZ
#undef PART_N
    return THX_OK;
}

static thx_status grow(thx_ctx *ctx, double **xyz, long **tet, size_t n)
{
    double *x = thx_realloc(ctx, *xyz, 3 * (n + 1) * sizeof *x);
    if (!x) return THX_ENOMEM;
    *xyz = x;
    long *t = thx_realloc(ctx, *tet, (n + 1) * sizeof *t);
    if (!t) return THX_ENOMEM;
    *tet = t;
    return THX_OK;
}

/* A point uniformly distributed in tetrahedron t (the folding of the unit cube onto the simplex of
 * Rocchini and Cignoni). */
static void point_in_tet(const thx_volume *v, size_t t, uint64_t *rng, double p[3])
{
    double s = thx_stream_rand(rng), u = thx_stream_rand(rng), w = thx_stream_rand(rng);
    if (s + u > 1) s = 1 - s, u = 1 - u;
    if (u + w > 1) {
        double tmp = w;
        w = 1 - s - u;
        u = 1 - tmp;
    } else if (s + u + w > 1) {
        double tmp = w;
        w = s + u + w - 1;
        s = 1 - u - tmp;
    }
    double lam[4] = {1 - s - u - w, s, u, w};
    const int32_t *q = v->tet + 4 * t;
    for (int c = 0; c < 3; c++) {
        p[c] = 0;
        for (int k = 0; k < 4; k++) p[c] += lam[k] * v->xyz[3 * (size_t)q[k] + (size_t)c];
    }
}

/* n indices drawn from the cumulative weights cum[0..m-1] (cum[m-1] > 0), by bisection. */
static size_t draw(const double *cum, size_t m, uint64_t *rng)
{
    double r = thx_stream_rand(rng) * cum[m - 1];
    size_t lo = 0, hi = m - 1;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (cum[mid] > r) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

/* Seeds on the faces between region r (outside the domain) and the domain, uniform by area, each
 * moved a millionth of the tetrahedron's size into the domain's tetrahedron. */
static thx_status region_faces(thx_ctx *ctx, const thx_stream_field *f, int32_t r, const thx_seed_spec *s,
                               double **xyz, long **tet, size_t *n)
{
    const thx_volume *v = f->v;
    size_t m = 0, cap = 0;
    double *cum = NULL;
    long *ft = NULL; /* 2 per face: the domain's tetrahedron, the face (its opposite corner) */
    thx_status st = THX_OK;
    for (size_t t = 0; t < v->n_tets; t++) {
        if (!f->active[t]) continue;
        for (int k = 0; k < 4; k++) {
            long w = thx_tet_neighbour(f->loc, t, k);
            if (w < 0 || v->region[w] != r) continue;
            if (m == cap) {
                cap = cap ? 2 * cap : 256;
                double *c = thx_realloc(ctx, cum, cap * sizeof *c);
                if (!c) {
                    st = THX_ENOMEM;
                    goto done;
                }
                cum = c;
                long *g = thx_realloc(ctx, ft, 2 * cap * sizeof *g);
                if (!g) {
                    st = THX_ENOMEM;
                    goto done;
                }
                ft = g;
            }
            const int32_t *q = v->tet + 4 * t;
            const double *A = v->xyz + 3 * (size_t)q[(k + 1) & 3], *B = v->xyz + 3 * (size_t)q[(k + 2) & 3],
                         *C = v->xyz + 3 * (size_t)q[(k + 3) & 3];
            double ab[3] = {B[0] - A[0], B[1] - A[1], B[2] - A[2]}, ac[3] = {C[0] - A[0], C[1] - A[1], C[2] - A[2]};
            double cr[3] = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0]};
            cum[m] = (m ? cum[m - 1] : 0) + 0.5 * sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
            ft[2 * m] = (long)t;
            ft[2 * m + 1] = k;
            m++;
        }
    }
    if (!m || !(cum[m - 1] > 0)) {
        st = thx_error(ctx, THX_EINPUT, "seed \"%s\": region \"%s\" carries no current and has no face to the domain",
                       s->text, s->region);
        goto done;
    }
    uint64_t rng = s->rng_seed;
    for (size_t i = 0; i < s->n; i++) {
        size_t j = draw(cum, m, &rng);
        size_t t = (size_t)ft[2 * j];
        int k = (int)ft[2 * j + 1];
        double a = thx_stream_rand(&rng), b = thx_stream_rand(&rng);
        if (a + b > 1) a = 1 - a, b = 1 - b;
        const int32_t *q = v->tet + 4 * t;
        const double *A = v->xyz + 3 * (size_t)q[(k + 1) & 3], *B = v->xyz + 3 * (size_t)q[(k + 2) & 3],
                     *C = v->xyz + 3 * (size_t)q[(k + 3) & 3], *O = v->xyz + 3 * (size_t)q[k];
        THX_TRY(grow(ctx, xyz, tet, *n));
        double *p = *xyz + 3 * *n;
        for (int c = 0; c < 3; c++) {
            p[c] = (1 - a - b) * A[c] + a * B[c] + b * C[c];
            p[c] += 1e-6 * (O[c] - p[c]);
        }
        (*tet)[*n] = (long)t;
        (*n)++;
    }
done:
    free(cum);
    free(ft);
    return st;
}

thx_status thx_stream_seeds(thx_ctx *ctx, const thx_stream_field *f, const thx_seed_spec *s, double **xyz, long **tet,
                            size_t *n)
{
    const thx_volume *v = f->v;
    thx_status st = THX_OK;
    if (s->kind == THX_SEED_POINT || s->kind == THX_SEED_LINE || s->kind == THX_SEED_SPHERE) {
        size_t m = s->kind == THX_SEED_POINT ? 1 : s->n, kept = 0;
        for (size_t i = 0; i < m; i++) {
            double p[3];
            if (s->kind == THX_SEED_POINT) memcpy(p, s->a, sizeof p);
            else if (s->kind == THX_SEED_LINE) {
                double u = m == 1 ? 0.5 : (double)i / (double)(m - 1);
                for (int c = 0; c < 3; c++) p[c] = s->a[c] + u * (s->b[c] - s->a[c]);
            } else {
                /* the Fibonacci lattice: z evenly spaced, the longitude turned by the golden angle */
                double z = 1 - (2.0 * (double)i + 1) / (double)m, rr = sqrt(fmax(0, 1 - z * z));
                double lon = (double)i * 2.39996322972865332; /* pi (3 - sqrt 5) */
                p[0] = s->a[0] + s->radius * rr * cos(lon);
                p[1] = s->a[1] + s->radius * rr * sin(lon);
                p[2] = s->a[2] + s->radius * z;
            }
            long t = thx_stream_field_eval(f, p, -1, NULL, NULL);
            if (t >= 0) t = thx_stream_field_lowest(f, p, t);
            if (t < 0 && f->own) { /* on a part: kept, the caller agrees which part holds it, if any */
                THX_CHECK(grow(ctx, xyz, tet, *n));
                memcpy(*xyz + 3 * *n, p, sizeof p);
                (*tet)[(*n)++] = -1;
                kept++;
                continue;
            }
            if (t < 0) {
                if (s->kind == THX_SEED_POINT)
                    return thx_error(ctx, THX_EINPUT, "seed \"%s\": the point (%g, %g, %g) is outside the domain%s",
                                     s->text, p[0], p[1], p[2], " (the mesh, or a region without current)");
                continue;
            }
            THX_CHECK(grow(ctx, xyz, tet, *n));
            memcpy(*xyz + 3 * *n, p, sizeof p);
            (*tet)[*n] = t;
            (*n)++;
            kept++;
        }
        if (!kept)
            return thx_error(ctx, THX_EINPUT, "seed \"%s\": every one of its %zu points is outside the domain", s->text, m);
        if (kept < m)
            thx_log(ctx, THX_LOG_INFO, "seed \"%s\": %zu of its %zu points are outside the domain, left out", s->text,
                    m - kept, m);
        return THX_OK;
    }
    int32_t r = -1;
    if (s->kind == THX_SEED_REGION) {
        for (size_t i = 0; i < v->n_regions && r < 0; i++)
            if (!strcmp(v->regions[i].name, s->region)) r = (int32_t)i;
        if (r < 0) {
            char list[1024] = "";
            size_t off = 0;
            for (size_t i = 0; i < v->n_regions && off < sizeof list; i++)
                off += (size_t)snprintf(list + off, sizeof list - off, "%s%s", i ? ", " : "", v->regions[i].name);
            return thx_error(ctx, THX_EINPUT, "seed \"%s\": no region \"%s\"; the volume has: %s", s->text, s->region,
                             list);
        }
        int active = 0;
        for (size_t t = 0; t < v->n_tets && !active; t++) active = v->region[t] == r && f->active[t];
        if (!active) return region_faces(ctx, f, r, s, xyz, tet, n);
    } else if (s->kind != THX_SEED_DENSITY) {
        return thx_error(ctx, THX_EINPUT, "seed \"%s\": unknown kind", s->text);
    }
    /* region: weights the volumes of its tetrahedra; density: |J| at the centroid x volume */
    double *cum = thx_malloc(ctx, (v->n_tets + 1) * sizeof *cum);
    if (!cum) return THX_ENOMEM;
    double acc = 0;
    for (size_t t = 0; t < v->n_tets; t++) {
        double w = 0;
        if (f->active[t] && (r < 0 || v->region[t] == r)) {
            w = fabs(thx_volume_tet_volume(v, t));
            if (r < 0) {
                const int32_t *q = v->tet + 4 * t;
                double J[3] = {0, 0, 0};
                for (int k = 0; k < 4; k++)
                    for (int c = 0; c < 3; c++) J[c] += 0.25 * f->j[3 * (size_t)q[k] + (size_t)c];
                w *= sqrt(J[0] * J[0] + J[1] * J[1] + J[2] * J[2]);
            }
        }
        acc += w;
        cum[t] = acc;
    }
    if (!(acc > 0)) {
        free(cum);
        return thx_error(ctx, THX_EINPUT, "seed \"%s\": %s", s->text,
                         r < 0 ? "no current anywhere in the domain" : "the region has no volume");
    }
    uint64_t rng = s->rng_seed;
    for (size_t i = 0; i < s->n; i++) {
        size_t t = draw(cum, v->n_tets, &rng);
        THX_TRY(grow(ctx, xyz, tet, *n));
        point_in_tet(v, t, &rng, *xyz + 3 * *n);
        (*tet)[*n] = (long)t;
        (*n)++;
    }
done:
    free(cum);
    return st;
}
