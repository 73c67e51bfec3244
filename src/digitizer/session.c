/*
 * src/digitizer/session.c — a tracing session (thorax/digitizer/session.h): loops per surface and
 * image plane, the language that changes them, undo and redo, and the contours they make.
 *
 * Undo. Each line that changes loops records, before it changes a layer (a surface's loops on one
 * plane), a copy of that layer as it was, and the current surface, plane and tool. Undo puts the
 * copies back; redo applies the line again from the state it was first applied in (the tools are
 * deterministic: the same line on the same loops and image gives the same loops). A failing line is
 * undone the same way before its error is returned, so a line either happens whole or not at all.
 */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "digitizer/dig_impl.h"
#include "thorax/digitizer/interp.h"
#include "thorax/digitizer/livewire.h"
#include "thorax/digitizer/region.h"
#include "thorax/digitizer/session.h"
#include "thorax/digitizer/snap.h"
#include "thorax/digitizer/valid.h"

typedef struct {
    long k;
    thx_dig_loop *loops;
    size_t n, cap;
} sess_layer;

typedef struct {
    char name[64];
    thx_role role;
    sess_layer *layers; /* ascending k, none empty */
    size_t n, cap;
    unsigned long gen;
} sess_surface;

typedef struct {
    size_t surf;
    long k;
    int existed;
    sess_layer layer; /* the layer as it was (deep copy) */
} sess_saved;

typedef struct {
    char *line;
    int cur;
    long k;
    thx_dig_tool tool;
    size_t n_surf;      /* surfaces before the line */
    sess_saved *sv;
    size_t n_sv, cap_sv;
} sess_record;

typedef struct {
    sess_record *r;
    size_t n, cap;
} sess_stack;

struct thx_dig_session {
    const thx_image *img;
    double lo, step;
    long n_planes;
    sess_surface *surf;
    size_t n_surf, cap_surf;
    int cur;
    long k;
    thx_dig_tool tool;
    /* the current plane, sampled when first needed, and its livewire */
    int have_slice;
    thx_image_slice slice;
    thx_livewire *lw;
    double lw_seed[2];
    int lw_seeded;
    /* undo, redo, the line being applied */
    sess_stack undo, redo;
    sess_record *rec;
    unsigned long gen_counter;
    char **log;
    size_t n_log, cap_log;
};

/* ---- small helpers ---- */

static void loop_free(thx_dig_loop *l)
{
    free(l->p);
    memset(l, 0, sizeof *l);
}

static void layer_free(sess_layer *L)
{
    for (size_t i = 0; i < L->n; i++) loop_free(&L->loops[i]);
    free(L->loops);
    memset(L, 0, sizeof *L);
}

static thx_status loop_push(thx_ctx *ctx, thx_dig_loop *l, double x, double y)
{
    if (l->n && l->p[l->n - 1].x == x && l->p[l->n - 1].y == y) return THX_OK; /* no repeated point */
    if (l->n == l->cap) {
        size_t cap = l->cap ? 2 * l->cap : 16;
        thx_vec2 *p = thx_realloc(ctx, l->p, cap * sizeof *p);
        if (!p) return THX_ENOMEM;
        l->p = p;
        l->cap = cap;
    }
    l->p[l->n].x = x;
    l->p[l->n].y = y;
    l->n++;
    return THX_OK;
}

static thx_status loop_copy(thx_ctx *ctx, const thx_dig_loop *from, thx_dig_loop *to)
{
    memset(to, 0, sizeof *to);
    to->closed = from->closed;
    if (!from->n) return THX_OK;
    to->p = thx_malloc(ctx, from->n * sizeof *to->p);
    if (!to->p) return THX_ENOMEM;
    memcpy(to->p, from->p, from->n * sizeof *to->p);
    to->n = to->cap = from->n;
    return THX_OK;
}

static thx_status layer_copy(thx_ctx *ctx, const sess_layer *from, sess_layer *to)
{
    memset(to, 0, sizeof *to);
    to->k = from->k;
    if (!from->n) return THX_OK;
    to->loops = thx_calloc(ctx, from->n, sizeof *to->loops);
    if (!to->loops) return THX_ENOMEM;
    to->cap = from->n;
    for (size_t i = 0; i < from->n; i++) {
        thx_status st = loop_copy(ctx, &from->loops[i], &to->loops[i]);
        to->n = i + 1;
        if (st != THX_OK) { layer_free(to); return st; }
    }
    return THX_OK;
}

static long layer_index(const sess_surface *S, long k)
{
    for (size_t i = 0; i < S->n; i++)
        if (S->layers[i].k == k) return (long)i;
    return -1;
}

static sess_layer *find_layer(const thx_dig_session *s, size_t surf, long k)
{
    long i = layer_index(&s->surf[surf], k);
    return i < 0 ? NULL : &s->surf[surf].layers[i];
}

static void bump(thx_dig_session *s, size_t surf)
{
    if (surf < s->n_surf) s->surf[surf].gen = ++s->gen_counter;
}

/* Records the layer (surf, k) as it is, once per line, before it changes. */
static thx_status touch(thx_ctx *ctx, thx_dig_session *s, size_t surf, long k)
{
    sess_record *r = s->rec;
    bump(s, surf);
    if (!r) return THX_OK;
    for (size_t i = 0; i < r->n_sv; i++)
        if (r->sv[i].surf == surf && r->sv[i].k == k) return THX_OK;
    if (r->n_sv == r->cap_sv) {
        size_t cap = r->cap_sv ? 2 * r->cap_sv : 4;
        sess_saved *n = thx_realloc(ctx, r->sv, cap * sizeof *n);
        if (!n) return THX_ENOMEM;
        r->sv = n;
        r->cap_sv = cap;
    }
    sess_saved *v = &r->sv[r->n_sv];
    memset(v, 0, sizeof *v);
    v->surf = surf;
    v->k = k;
    const sess_layer *L = find_layer(s, surf, k);
    v->existed = L != NULL;
    if (L) THX_CHECK(layer_copy(ctx, L, &v->layer));
    r->n_sv++;
    return THX_OK;
}

/* The layer (surf, k), made (empty, in order) when absent; touch() first. */
static thx_status get_layer(thx_ctx *ctx, thx_dig_session *s, size_t surf, long k, sess_layer **out)
{
    THX_CHECK(touch(ctx, s, surf, k));
    sess_surface *S = &s->surf[surf];
    long i = layer_index(S, k);
    if (i >= 0) { *out = &S->layers[i]; return THX_OK; }
    if (S->n == S->cap) {
        size_t cap = S->cap ? 2 * S->cap : 8;
        sess_layer *n = thx_realloc(ctx, S->layers, cap * sizeof *n);
        if (!n) return THX_ENOMEM;
        S->layers = n;
        S->cap = cap;
    }
    size_t at = 0;
    while (at < S->n && S->layers[at].k < k) at++;
    memmove(&S->layers[at + 1], &S->layers[at], (S->n - at) * sizeof *S->layers);
    memset(&S->layers[at], 0, sizeof *S->layers);
    S->layers[at].k = k;
    S->n++;
    *out = &S->layers[at];
    return THX_OK;
}

/* Removes the layers left without loops. */
static void prune(thx_dig_session *s, size_t surf)
{
    sess_surface *S = &s->surf[surf];
    size_t w = 0;
    for (size_t i = 0; i < S->n; i++) {
        if (!S->layers[i].n) { layer_free(&S->layers[i]); continue; }
        S->layers[w++] = S->layers[i];
    }
    S->n = w;
}

static thx_status layer_add_loop(thx_ctx *ctx, sess_layer *L, thx_dig_loop **out)
{
    if (L->n == L->cap) {
        size_t cap = L->cap ? 2 * L->cap : 4;
        thx_dig_loop *n = thx_realloc(ctx, L->loops, cap * sizeof *n);
        if (!n) return THX_ENOMEM;
        L->loops = n;
        L->cap = cap;
    }
    memset(&L->loops[L->n], 0, sizeof *L->loops);
    *out = &L->loops[L->n++];
    return THX_OK;
}

static void record_free(sess_record *r)
{
    free(r->line);
    for (size_t i = 0; i < r->n_sv; i++) layer_free(&r->sv[i].layer);
    free(r->sv);
    memset(r, 0, sizeof *r);
}

static void stack_clear(sess_stack *st)
{
    for (size_t i = 0; i < st->n; i++) record_free(&st->r[i]);
    st->n = 0;
}

static thx_status stack_push(thx_ctx *ctx, sess_stack *st, sess_record *r)
{
    if (st->n == st->cap) {
        size_t cap = st->cap ? 2 * st->cap : 32;
        sess_record *n = thx_realloc(ctx, st->r, cap * sizeof *n);
        if (!n) return THX_ENOMEM;
        st->r = n;
        st->cap = cap;
    }
    st->r[st->n++] = *r;
    memset(r, 0, sizeof *r);
    return THX_OK;
}

static void drop_plane(thx_dig_session *s)
{
    thx_livewire_destroy(&s->lw);
    s->lw_seeded = 0;
    if (s->have_slice) thx_image_slice_free(&s->slice);
    s->have_slice = 0;
}

static void set_plane(thx_dig_session *s, long k)
{
    if (k != s->k) drop_plane(s);
    s->k = k;
}

/* Puts back what record r saved (in reverse order) and its surface, plane and tool. */
static void restore(thx_dig_session *s, sess_record *r)
{
    for (size_t i = r->n_sv; i-- > 0;) {
        sess_saved *v = &r->sv[i];
        if (v->surf >= s->n_surf) continue; /* a surface the line made: dropped below */
        sess_surface *S = &s->surf[v->surf];
        long at = layer_index(S, v->k);
        if (at >= 0) {
            layer_free(&S->layers[at]);
            if (v->existed) {
                S->layers[at] = v->layer;
            } else {
                memmove(&S->layers[at], &S->layers[at + 1], (S->n - (size_t)at - 1) * sizeof *S->layers);
                S->n--;
            }
        } else if (v->existed) {
            /* the line emptied and pruned it: insert it again, in order */
            size_t pos = 0;
            while (pos < S->n && S->layers[pos].k < v->k) pos++;
            if (S->n == S->cap) {
                size_t cap = S->cap ? 2 * S->cap : 8;
                sess_layer *g = realloc(S->layers, cap * sizeof *g);
                if (!g) { layer_free(&v->layer); continue; } /* out of memory: the layer is lost, not the session */
                S->layers = g;
                S->cap = cap;
            }
            memmove(&S->layers[pos + 1], &S->layers[pos], (S->n - pos) * sizeof *S->layers);
            S->layers[pos] = v->layer;
            S->n++;
        }
        memset(&v->layer, 0, sizeof v->layer);
        v->existed = 0;
        bump(s, v->surf);
    }
    while (s->n_surf > r->n_surf) {
        sess_surface *S = &s->surf[--s->n_surf];
        for (size_t i = 0; i < S->n; i++) layer_free(&S->layers[i]);
        free(S->layers);
        memset(S, 0, sizeof *S);
    }
    s->cur = r->cur;
    set_plane(s, r->k);
    s->tool = r->tool;
}

/* ---- the session ---- */

thx_status thx_dig_session_create(thx_ctx *ctx, const thx_image *img, thx_dig_session **out)
{
    *out = NULL;
    double lo, hi, step;
    thx_image_plane_range(img, 'z', &lo, &hi, &step);
    long n = isfinite(lo) && isfinite(hi) && step > 0 ? (long)floor((hi - lo) / step + 0.5) : 0;
    if (n < 2)
        return thx_error(ctx, THX_EINPUT, "%s: %ld plane%s along RAS z: tracing needs at least 2",
                         img->path[0] ? img->path : "the image", n, n == 1 ? "" : "s");
    thx_dig_session *s = thx_calloc(ctx, 1, sizeof *s);
    if (!s) return THX_ENOMEM;
    s->img = img;
    s->lo = lo;
    s->step = step;
    s->n_planes = n;
    s->cur = -1;
    s->k = n / 2;
    *out = s;
    return THX_OK;
}

void thx_dig_session_destroy(thx_dig_session **sp)
{
    thx_dig_session *s = sp ? *sp : NULL;
    if (!s) return;
    drop_plane(s);
    for (size_t i = 0; i < s->n_surf; i++) {
        for (size_t j = 0; j < s->surf[i].n; j++) layer_free(&s->surf[i].layers[j]);
        free(s->surf[i].layers);
    }
    free(s->surf);
    stack_clear(&s->undo);
    stack_clear(&s->redo);
    free(s->undo.r);
    free(s->redo.r);
    for (size_t i = 0; i < s->n_log; i++) free(s->log[i]);
    free(s->log);
    free(s);
    *sp = NULL;
}

size_t thx_dig_log(const thx_dig_session *s, const char *const **lines)
{
    *lines = (const char *const *)s->log;
    return s->n_log;
}

size_t thx_dig_n_surfaces(const thx_dig_session *s) { return s->n_surf; }
const char *thx_dig_surface_name(const thx_dig_session *s, size_t i) { return i < s->n_surf ? s->surf[i].name : ""; }
thx_role thx_dig_surface_role(const thx_dig_session *s, size_t i) { return i < s->n_surf ? s->surf[i].role : THX_ROLE_OTHER; }
unsigned long thx_dig_surface_gen(const thx_dig_session *s, size_t i) { return i < s->n_surf ? s->surf[i].gen : 0; }
int thx_dig_current_surface(const thx_dig_session *s) { return s->cur; }
long thx_dig_current_plane(const thx_dig_session *s) { return s->k; }
thx_dig_tool thx_dig_current_tool(const thx_dig_session *s) { return s->tool; }
long thx_dig_n_planes(const thx_dig_session *s) { return s->n_planes; }
size_t thx_dig_n_undo(const thx_dig_session *s) { return s->undo.n; }
size_t thx_dig_n_redo(const thx_dig_session *s) { return s->redo.n; }

double thx_dig_plane_z(const thx_dig_session *s, long k)
{
    return s->lo + ((double)k + 0.5) * s->step;
}

size_t thx_dig_loops(const thx_dig_session *s, size_t i, long k, const thx_dig_loop **loops)
{
    const sess_layer *L = i < s->n_surf ? find_layer(s, i, k) : NULL;
    *loops = L ? L->loops : NULL;
    return L ? L->n : 0;
}

size_t thx_dig_planes_traced(const thx_dig_session *s, size_t i, long *k, size_t max)
{
    if (i >= s->n_surf) return 0;
    const sess_surface *S = &s->surf[i];
    for (size_t j = 0; j < S->n && k && j < max; j++) k[j] = S->layers[j].k;
    return S->n;
}

const thx_image_slice *thx_dig_slice(thx_ctx *ctx, thx_dig_session *s)
{
    if (!s->have_slice) {
        thx_image_plane_spec spec = {'z', thx_dig_plane_z(s, s->k)};
        if (thx_image_sample_plane(ctx, s->img, &spec, 0, &s->slice) != THX_OK) return NULL;
        s->have_slice = 1;
    }
    return &s->slice;
}

/* The livewire of the current plane, seeded at (x, y) (kept seeded when it is there already: the
 * search goes on). */
static thx_status livewire_from(thx_ctx *ctx, thx_dig_session *s, double x, double y)
{
    if (!s->lw) {
        const thx_image_slice *sl = thx_dig_slice(ctx, s);
        if (!sl) return THX_EINPUT;
        thx_livewire_opts o;
        thx_livewire_opts_default(&o);
        THX_CHECK(thx_livewire_create(ctx, sl, &o, &s->lw));
        s->lw_seeded = 0;
    }
    if (!s->lw_seeded || s->lw_seed[0] != x || s->lw_seed[1] != y) {
        double ras[3] = {x, y, thx_dig_plane_z(s, s->k)};
        THX_CHECK(thx_livewire_seed(ctx, s->lw, ras));
        s->lw_seed[0] = x;
        s->lw_seed[1] = y;
        s->lw_seeded = 1;
    }
    return THX_OK;
}

/* The livewire's path from (x0, y0) to (x1, y1) on the current plane (RAS, *n points). */
static thx_status livewire_path(thx_ctx *ctx, thx_dig_session *s, double x0, double y0, double x1, double y1,
                                double **xyz, size_t *n)
{
    THX_CHECK(livewire_from(ctx, s, x0, y0));
    double to[3] = {x1, y1, thx_dig_plane_z(s, s->k)};
    return thx_livewire_path(ctx, s->lw, to, xyz, n);
}

static thx_dig_loop *open_loop(const thx_dig_session *s, size_t *index)
{
    if (s->cur < 0) return NULL;
    sess_layer *L = find_layer(s, (size_t)s->cur, s->k);
    for (size_t i = 0; L && i < L->n; i++)
        if (!L->loops[i].closed) {
            if (index) *index = i;
            return &L->loops[i];
        }
    return NULL;
}

thx_status thx_dig_preview(thx_ctx *ctx, thx_dig_session *s, double x, double y, double **xyz, size_t *n)
{
    *xyz = NULL;
    *n = 0;
    const thx_dig_loop *l = open_loop(s, NULL);
    if (!l || !l->n) return THX_OK;
    return livewire_path(ctx, s, l->p[l->n - 1].x, l->p[l->n - 1].y, x, y, xyz, n);
}

/* ---- the lines ---- */

#define MAX_WORDS 8

typedef struct {
    char buf[1024];
    char *w[MAX_WORDS];
    int n;
    const char *line;
} words;

static thx_status bad(thx_ctx *ctx, const words *wd, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static thx_status bad(thx_ctx *ctx, const words *wd, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return thx_error(ctx, THX_EINPUT, "trace '%s': %s", wd->line, msg);
}

static int number(const char *w, double *v)
{
    char *end;
    if (!w) return -1;
    *v = strtod(w, &end);
    return *w && !*end && isfinite(*v) ? 0 : -1;
}

static int index1(const char *w, size_t *v)
{
    char *end;
    if (!w || !isdigit((unsigned char)*w)) return -1;
    unsigned long u = strtoul(w, &end, 10);
    if (*end || u < 1) return -1;
    *v = (size_t)u - 1;
    return 0;
}

static const char *surf_name(const thx_dig_session *s) { return s->cur >= 0 ? s->surf[s->cur].name : "-"; }

static thx_status need_surface(thx_ctx *ctx, const thx_dig_session *s, const words *wd)
{
    if (s->cur < 0) return bad(ctx, wd, "no surface yet (a 'surface NAME' line first)");
    return THX_OK;
}

/* Loop L (0-based) of the current surface on the current plane. */
static thx_status the_loop(thx_ctx *ctx, thx_dig_session *s, const words *wd, const char *w, thx_dig_loop **out,
                           size_t *li)
{
    THX_CHECK(need_surface(ctx, s, wd));
    size_t l;
    if (index1(w, &l)) return bad(ctx, wd, "'%s' is not a loop number (1, 2, ...)", w ? w : "");
    sess_layer *L = find_layer(s, (size_t)s->cur, s->k);
    size_t have = L ? L->n : 0;
    if (l >= have)
        return bad(ctx, wd, "%s has %zu loop%s on plane z=%.4f", surf_name(s), have, have == 1 ? "" : "s",
                   thx_dig_plane_z(s, s->k));
    THX_CHECK(touch(ctx, s, (size_t)s->cur, s->k));
    *out = &L->loops[l];
    if (li) *li = l;
    return THX_OK;
}

static thx_role default_role(const char *name)
{
    if (!strcmp(name, "torso")) return THX_ROLE_OUTER;
    if (!strcmp(name, "fat")) return THX_ROLE_FAT;
    if (!strcmp(name, "muscle")) return THX_ROLE_MUSCLE;
    if (!strncmp(name, "lung", 4)) return THX_ROLE_LUNG;
    if (!strcmp(name, "heart")) return THX_ROLE_HEART;
    return THX_ROLE_OTHER;
}

static thx_status do_surface(thx_ctx *ctx, thx_dig_session *s, const words *wd)
{
    if (wd->n != 2) return bad(ctx, wd, "give surface NAME[:ROLE]");
    char name[64];
    const char *colon = strchr(wd->w[1], ':');
    size_t len = colon ? (size_t)(colon - wd->w[1]) : strlen(wd->w[1]);
    if (!len || len >= sizeof name) return bad(ctx, wd, "a surface name of 1 to 63 characters");
    memcpy(name, wd->w[1], len);
    name[len] = '\0';
    for (size_t i = 0; i < len; i++)
        if (!isalnum((unsigned char)name[i]) && name[i] != '_' && name[i] != '-' && name[i] != '.')
            return bad(ctx, wd, "'%s': a surface name of letters, digits, '_', '-' and '.'", name);
    thx_role role = default_role(name);
    if (colon && thx_role_parse(colon + 1, &role))
        return bad(ctx, wd, "'%s' is not a role (outer, fat, muscle, lung, heart, other)", colon + 1);
    for (size_t i = 0; i < s->n_surf; i++)
        if (!strcmp(s->surf[i].name, name)) {
            if (colon && s->surf[i].role != role)
                return bad(ctx, wd, "%s is traced already as %s", name, thx_role_name(s->surf[i].role));
            s->cur = (int)i;
            return THX_OK;
        }
    if (s->n_surf == s->cap_surf) {
        size_t cap = s->cap_surf ? 2 * s->cap_surf : 8;
        sess_surface *n = thx_realloc(ctx, s->surf, cap * sizeof *n);
        if (!n) return THX_ENOMEM;
        s->surf = n;
        s->cap_surf = cap;
    }
    sess_surface *S = &s->surf[s->n_surf];
    memset(S, 0, sizeof *S);
    snprintf(S->name, sizeof S->name, "%s", name);
    S->role = role;
    s->cur = (int)s->n_surf++;
    bump(s, (size_t)s->cur);
    return THX_OK;
}

static thx_status do_plane(thx_ctx *ctx, thx_dig_session *s, const words *wd)
{
    if (wd->n != 2) return bad(ctx, wd, "give plane z=MM, +N or -N");
    const char *w = wd->w[1];
    long k;
    if (*w == '+' || *w == '-') {
        char *end;
        long d = strtol(w, &end, 10);
        if (*end || end == w + 1) return bad(ctx, wd, "'%s' is not a number of planes", w);
        k = s->k + d;
    } else if (!strncmp(w, "z=", 2)) {
        double z;
        if (number(w + 2, &z)) return bad(ctx, wd, "'%s' is not a position in mm", w + 2);
        k = (long)floor((z - s->lo) / s->step);
        if (z < s->lo || k > s->n_planes) k = -1;
        if (k == s->n_planes) k--;
    } else {
        return bad(ctx, wd, "'%s': give z=MM, +N or -N", w);
    }
    if (k < 0 || k >= s->n_planes)
        return bad(ctx, wd, "outside the image's planes (z from %.4f to %.4f mm)", thx_dig_plane_z(s, 0),
                   thx_dig_plane_z(s, s->n_planes - 1));
    set_plane(s, k);
    return THX_OK;
}

static thx_status do_tool(thx_ctx *ctx, thx_dig_session *s, const words *wd)
{
    if (wd->n == 2 && !strcmp(wd->w[1], "points")) s->tool = THX_DIG_POINTS;
    else if (wd->n == 2 && !strcmp(wd->w[1], "livewire")) s->tool = THX_DIG_LIVEWIRE;
    else return bad(ctx, wd, "give tool points or tool livewire");
    return THX_OK;
}

/* Whether segments pq and rs cross at a point inside both (not at their ends); *u: the place on pq. */
static int segments_cross(thx_vec2 p, thx_vec2 q, thx_vec2 r, thx_vec2 t, double *u)
{
    double dx = q.x - p.x, dy = q.y - p.y, ex = t.x - r.x, ey = t.y - r.y;
    double den = dx * ey - dy * ex;
    if (den == 0) return 0;
    double a = ((r.x - p.x) * ey - (r.y - p.y) * ex) / den, b = ((r.x - p.x) * dy - (r.y - p.y) * dx) / den;
    if (!(a > 0 && a < 1 && b > 0 && b < 1)) return 0;
    *u = a;
    return 1;
}

/* Removes the twists where two livewire paths meet at a click (a path may leave the click on the
 * side the last one came in by): where an edge added from point `from` on crosses another edge of
 * the loop, the smaller of the two loops the crossing makes (for an open loop, the one between the
 * two edges) is cut off and the crossing point put in its place; until no new edge crosses. */
static void untwist(thx_dig_loop *l, size_t from)
{
    for (int again = 1; again;) {
        again = 0;
        size_t n = l->n, edges = l->closed ? n : n - 1;
        if (n < 4) return;
        for (size_t j = from ? from - 1 : 0; j < edges && !again; j++)
            for (size_t i = 0; i < edges && !again; i++) {
                size_t lo = i < j ? i : j, hi = i < j ? j : i;
                if (hi - lo < 2 || (l->closed && lo == 0 && hi == n - 1)) continue; /* neighbours */
                double u;
                thx_vec2 c;
                if (l->p[lo + 1].x == l->p[hi].x && l->p[lo + 1].y == l->p[hi].y && hi - lo >= 2) {
                    c = l->p[hi]; /* the loop comes back through one of its points: a spur closed on itself */
                } else {
                    if (!segments_cross(l->p[lo], l->p[lo + 1], l->p[hi], l->p[(hi + 1) % n], &u)) continue;
                    c.x = l->p[lo].x + u * (l->p[lo + 1].x - l->p[lo].x);
                    c.y = l->p[lo].y + u * (l->p[lo + 1].y - l->p[lo].y);
                }
                size_t inner = hi - lo; /* points lo+1 .. hi */
                if (!l->closed || inner <= n - inner) {
                    l->p[lo + 1] = c;
                    memmove(&l->p[lo + 2], &l->p[hi + 1], (n - hi - 1) * sizeof *l->p);
                    l->n = n - inner + 1;
                } else { /* the outer part is the twist: keep lo+1 .. hi, then c */
                    memmove(&l->p[0], &l->p[lo + 1], inner * sizeof *l->p);
                    l->p[inner] = c;
                    l->n = inner + 1;
                }
                from = 0;
                again = 1;
            }
    }
}

/* Removes the spurs where a livewire path goes back the way the last one came (to a click beside
 * the edge and back): a point where the loop turns back on itself (the edges before and after it at
 * more than 160 degrees), or that repeats the point before it, goes; until none is left from point
 * `from` - 1 on (the whole loop when closed: the join with the first point). */
static void despike(thx_dig_loop *l, size_t from)
{
    for (int again = 1; again;) {
        again = 0;
        size_t n = l->n;
        if (n < 3) return;
        size_t first = l->closed ? 0 : (from > 1 ? from - 1 : 1), last = l->closed ? n : n - 1;
        for (size_t i = first; i < last; i++) {
            thx_vec2 a = l->p[(i + n - 1) % n], b = l->p[i], c = l->p[(i + 1) % n];
            double ux = b.x - a.x, uy = b.y - a.y, vx = c.x - b.x, vy = c.y - b.y;
            double nu = hypot(ux, uy), nv = hypot(vx, vy);
            if (nu > 0 && nv > 0 && ux * vx + uy * vy > -0.94 * nu * nv) continue;
            memmove(&l->p[i], &l->p[i + 1], (n - i - 1) * sizeof *l->p);
            l->n--;
            again = l->n >= 3;
            break;
        }
    }
}

/* Appends the livewire's path from the loop's last point to (x, y), without its two ends. */
static thx_status append_path(thx_ctx *ctx, thx_dig_session *s, thx_dig_loop *l, double x, double y)
{
    if (!l->n) return THX_OK;
    double x0 = l->p[l->n - 1].x, y0 = l->p[l->n - 1].y;
    double *xyz = NULL;
    size_t n = 0;
    THX_CHECK(livewire_path(ctx, s, x0, y0, x, y, &xyz, &n));
    /* the path's ends within a pixel of the clicks give way to the clicks: they are the seed's and the
       target's pixels and their neighbours, placed by the pixel grid, where the click is the user's */
    const thx_image_slice *sl = thx_dig_slice(ctx, s);
    double pix = sl ? fmax(dig_len3(sl->du), dig_len3(sl->dv)) : 0;
    size_t i0 = 1, i1 = n ? n - 1 : 0;
    while (i0 < i1 && hypot(xyz[3 * i0] - x0, xyz[3 * i0 + 1] - y0) < pix) i0++;
    while (i1 > i0 && hypot(xyz[3 * (i1 - 1)] - x, xyz[3 * (i1 - 1) + 1] - y) < pix) i1--;
    thx_status st = THX_OK;
    for (size_t i = i0; i < i1 && st == THX_OK; i++) st = loop_push(ctx, l, xyz[3 * i], xyz[3 * i + 1]);
    free(xyz);
    return st;
}

static thx_status do_point(thx_ctx *ctx, thx_dig_session *s, const words *wd)
{
    double x, y;
    if (wd->n != 3 || number(wd->w[1], &x) || number(wd->w[2], &y)) return bad(ctx, wd, "give point X Y (mm)");
    THX_CHECK(need_surface(ctx, s, wd));
    const thx_image_slice *sl = thx_dig_slice(ctx, s);
    if (!sl) return THX_EINPUT;
    double ras[3] = {x, y, thx_dig_plane_z(s, s->k)}, a, b;
    dig_ras_to_px(sl, ras, &a, &b);
    if (!(a >= -0.5 && b >= -0.5 && a <= (double)sl->w - 0.5 && b <= (double)sl->h - 0.5))
        return bad(ctx, wd, "(%g, %g) mm lies outside the image on plane z=%.4f", x, y, ras[2]);
    sess_layer *L;
    THX_CHECK(get_layer(ctx, s, (size_t)s->cur, s->k, &L));
    thx_dig_loop *l = open_loop(s, NULL);
    if (!l) THX_CHECK(layer_add_loop(ctx, L, &l));
    size_t before = l->n;
    if (s->tool == THX_DIG_LIVEWIRE) THX_CHECK(append_path(ctx, s, l, x, y));
    THX_CHECK(loop_push(ctx, l, x, y));
    if (s->tool == THX_DIG_LIVEWIRE) {
        despike(l, before);
        untwist(l, before);
    }
    return THX_OK;
}

static thx_status do_close(thx_ctx *ctx, thx_dig_session *s, const words *wd)
{
    if (wd->n != 1) return bad(ctx, wd, "close takes nothing");
    THX_CHECK(need_surface(ctx, s, wd));
    thx_dig_loop *l = open_loop(s, NULL);
    if (!l) return bad(ctx, wd, "%s has no open loop on plane z=%.4f", surf_name(s), thx_dig_plane_z(s, s->k));
    THX_CHECK(touch(ctx, s, (size_t)s->cur, s->k));
    size_t before = l->n;
    if (s->tool == THX_DIG_LIVEWIRE && l->n >= 2) THX_CHECK(append_path(ctx, s, l, l->p[0].x, l->p[0].y));
    while (l->n > 1 && l->p[l->n - 1].x == l->p[0].x && l->p[l->n - 1].y == l->p[0].y) l->n--;
    if (l->n < 3) return bad(ctx, wd, "a loop needs 3 points (it has %zu)", l->n);
    l->closed = 1;
    if (s->tool == THX_DIG_LIVEWIRE) {
        despike(l, before);
        untwist(l, before);
        if (l->n < 3) return bad(ctx, wd, "a loop needs 3 points (it has %zu)", l->n);
    }
    return THX_OK;
}

static thx_status do_reopen(thx_ctx *ctx, thx_dig_session *s, const words *wd)
{
    if (wd->n != 2) return bad(ctx, wd, "give reopen L");
    if (open_loop(s, NULL)) return bad(ctx, wd, "%s has an open loop on this plane already (close it first)", surf_name(s));
    thx_dig_loop *l;
    THX_CHECK(the_loop(ctx, s, wd, wd->w[1], &l, NULL));
    l->closed = 0;
    return THX_OK;
}

static thx_status do_points(thx_ctx *ctx, thx_dig_session *s, const words *wd, int kind)
{
    /* kind 0 move L I X Y, 1 insert L I X Y, 2 delete L I */
    int want = kind == 2 ? 3 : 5;
    double x = 0, y = 0;
    size_t i;
    if (wd->n != want || (kind != 2 && (number(wd->w[3], &x) || number(wd->w[4], &y))))
        return bad(ctx, wd, kind == 2 ? "give delete L I" : "give %s L I X Y (mm)", wd->w[0]);
    thx_dig_loop *l;
    size_t li;
    THX_CHECK(the_loop(ctx, s, wd, wd->w[1], &l, &li));
    if (index1(wd->w[2], &i) || i >= l->n)
        return bad(ctx, wd, "loop %zu of %s has %zu points on this plane", li + 1, surf_name(s), l->n);
    if (kind == 0) {
        l->p[i].x = x;
        l->p[i].y = y;
    } else if (kind == 1) {
        THX_CHECK(loop_push(ctx, l, NAN, NAN)); /* room (NaN never equals the last point) */
        memmove(&l->p[i + 2], &l->p[i + 1], (l->n - i - 2) * sizeof *l->p);
        l->p[i + 1].x = x;
        l->p[i + 1].y = y;
    } else {
        if (l->closed && l->n <= 3) return bad(ctx, wd, "a closed loop keeps 3 points (delete-loop %zu removes it)", li + 1);
        memmove(&l->p[i], &l->p[i + 1], (l->n - i - 1) * sizeof *l->p);
        l->n--;
        if (!l->n) {
            sess_layer *L = find_layer(s, (size_t)s->cur, s->k);
            loop_free(l);
            memmove(&L->loops[li], &L->loops[li + 1], (L->n - li - 1) * sizeof *L->loops);
            L->n--;
        }
    }
    return THX_OK;
}

static thx_status do_delete_loop(thx_ctx *ctx, thx_dig_session *s, const words *wd)
{
    if (wd->n != 2) return bad(ctx, wd, "give delete-loop L");
    thx_dig_loop *l;
    size_t li;
    THX_CHECK(the_loop(ctx, s, wd, wd->w[1], &l, &li));
    sess_layer *L = find_layer(s, (size_t)s->cur, s->k);
    loop_free(l);
    memmove(&L->loops[li], &L->loops[li + 1], (L->n - li - 1) * sizeof *L->loops);
    L->n--;
    return THX_OK;
}

/* A new closed loop of the current surface on the current plane from RAS points. */
static thx_status add_closed(thx_ctx *ctx, thx_dig_session *s, long k, const double *xyz, size_t n)
{
    sess_layer *L;
    THX_CHECK(get_layer(ctx, s, (size_t)s->cur, k, &L));
    thx_dig_loop *l;
    THX_CHECK(layer_add_loop(ctx, L, &l));
    for (size_t i = 0; i < n; i++) THX_CHECK(loop_push(ctx, l, xyz[3 * i], xyz[3 * i + 1]));
    while (l->n > 1 && l->p[l->n - 1].x == l->p[0].x && l->p[l->n - 1].y == l->p[0].y) l->n--;
    l->closed = 1;
    if (l->n < 3) return thx_error(ctx, THX_EGEOM, "a loop of %zu points", l->n);
    return THX_OK;
}

static thx_status do_region(thx_ctx *ctx, thx_dig_session *s, const words *wd)
{
    double lo, hi, x, y;
    if (wd->n != 5 || number(wd->w[1], &lo) || number(wd->w[2], &hi) || number(wd->w[3], &x) || number(wd->w[4], &y))
        return bad(ctx, wd, "give region LO HI X Y");
    THX_CHECK(need_surface(ctx, s, wd));
    const thx_image_slice *sl = thx_dig_slice(ctx, s);
    if (!sl) return THX_EINPUT;
    double seed[3] = {x, y, thx_dig_plane_z(s, s->k)}, *xyz = NULL;
    size_t n = 0;
    thx_region_info info;
    thx_status st = thx_region_loop(ctx, sl, lo, hi, seed, 1, &xyz, &n, &info);
    if (st != THX_OK) return bad(ctx, wd, "%s", thx_ctx_message(ctx));
    st = add_closed(ctx, s, s->k, xyz, n);
    free(xyz);
    return st;
}

static thx_status do_copy(thx_ctx *ctx, thx_dig_session *s, const words *wd)
{
    char *end;
    long d = wd->n >= 2 ? strtol(wd->w[1], &end, 10) : 0;
    int raw = wd->n == 3 && !strcmp(wd->w[2], "raw");
    if (wd->n < 2 || wd->n > 3 || *end || !d || (wd->n == 3 && !raw)) return bad(ctx, wd, "give copy N [raw] (N planes on, not 0)");
    THX_CHECK(need_surface(ctx, s, wd));
    long k0 = s->k, k1 = k0 + d;
    if (k1 < 0 || k1 >= s->n_planes) return bad(ctx, wd, "plane %+ld lies outside the image", d);
    const sess_layer *from = find_layer(s, (size_t)s->cur, k0);
    size_t nc = 0;
    for (size_t i = 0; from && i < from->n; i++) nc += from->loops[i].closed;
    if (!nc) return bad(ctx, wd, "%s has no closed loop on plane z=%.4f", surf_name(s), thx_dig_plane_z(s, k0));
    if (find_layer(s, (size_t)s->cur, k1))
        return bad(ctx, wd, "%s has loops on plane z=%.4f already (delete them first)", surf_name(s), thx_dig_plane_z(s, k1));
    /* the loops to copy, before the layer array may move */
    sess_layer src;
    THX_CHECK(layer_copy(ctx, from, &src));
    set_plane(s, k1);
    double z1 = thx_dig_plane_z(s, k1);
    const thx_image_slice *sl = raw ? NULL : thx_dig_slice(ctx, s);
    thx_status st = raw || sl ? THX_OK : THX_EINPUT;
    thx_snap_opts so;
    thx_snap_opts_default(&so);
    for (size_t i = 0; i < src.n && st == THX_OK; i++) {
        const thx_dig_loop *l = &src.loops[i];
        if (!l->closed) continue;
        double *in = thx_malloc(ctx, 6 * l->n * sizeof *in);
        if (!in) { st = THX_ENOMEM; break; }
        double *out = in + 3 * l->n;
        for (size_t j = 0; j < l->n; j++) {
            in[3 * j] = l->p[j].x;
            in[3 * j + 1] = l->p[j].y;
            in[3 * j + 2] = z1;
        }
        if (raw) memcpy(out, in, 3 * l->n * sizeof *out);
        else st = thx_snap_loop(ctx, sl, &so, in, l->n, out);
        if (st != THX_OK) st = bad(ctx, wd, "loop %zu: %s", i + 1, thx_ctx_message(ctx));
        else st = add_closed(ctx, s, k1, out, l->n);
        free(in);
    }
    layer_free(&src);
    return st;
}

/* The centroid of a loop (of its points). */
static void centroid(const thx_dig_loop *l, double *cx, double *cy)
{
    double x = 0, y = 0;
    for (size_t i = 0; i < l->n; i++) { x += l->p[i].x; y += l->p[i].y; }
    *cx = l->n ? x / (double)l->n : 0;
    *cy = l->n ? y / (double)l->n : 0;
}

static double grid_step(const thx_dig_session *s)
{
    const double *sp = s->img->spacing;
    return 0.5 * fmin(sp[0], fmin(sp[1], sp[2]));
}

/* Interpolates between layers A (plane ka) and B (kb) of the current surface. */
static thx_status interp_gap(thx_ctx *ctx, thx_dig_session *s, const words *wd, long ka, long kb)
{
    const sess_layer *A = find_layer(s, (size_t)s->cur, ka), *B = find_layer(s, (size_t)s->cur, kb);
    size_t na = A->n, nb = B->n;
    for (size_t i = 0; i < na; i++)
        if (!A->loops[i].closed) return bad(ctx, wd, "plane z=%.4f has an open loop", thx_dig_plane_z(s, ka));
    for (size_t i = 0; i < nb; i++)
        if (!B->loops[i].closed) return bad(ctx, wd, "plane z=%.4f has an open loop", thx_dig_plane_z(s, kb));
    if (na != nb)
        return bad(ctx, wd, "%s has %zu loop%s on plane z=%.4f and %zu on z=%.4f: trace a plane between", surf_name(s), na,
                   na == 1 ? "" : "s", thx_dig_plane_z(s, ka), nb, thx_dig_plane_z(s, kb));
    /* pairs: each loop of A with the nearest free loop of B (by centroid), in A's order */
    size_t pair[64];
    unsigned char used[64] = {0};
    if (na > 64) return bad(ctx, wd, "more than 64 loops on a plane");
    for (size_t i = 0; i < na; i++) {
        double ax, ay, best = INFINITY;
        centroid(&A->loops[i], &ax, &ay);
        pair[i] = 0;
        for (size_t j = 0; j < nb; j++) {
            double bx, by;
            centroid(&B->loops[j], &bx, &by);
            double d = hypot(bx - ax, by - ay);
            if (!used[j] && d < best) { best = d; pair[i] = j; }
        }
        used[pair[i]] = 1;
    }
    /* copies: the layers' arrays move as layers are made */
    sess_layer ca, cb;
    THX_CHECK(layer_copy(ctx, A, &ca));
    thx_status st = layer_copy(ctx, B, &cb);
    if (st != THX_OK) { layer_free(&ca); return st; }
    double step = grid_step(s);
    for (long k = ka + 1; k < kb && st == THX_OK; k++) {
        double t = (double)(k - ka) / (double)(kb - ka);
        for (size_t i = 0; i < na && st == THX_OK; i++) {
            const thx_dig_loop *a = &ca.loops[i], *b = &cb.loops[pair[i]];
            thx_vec2 *out = NULL;
            size_t n = 0;
            st = thx_loop_interpolate(ctx, a->p, a->n, b->p, b->n, t, step, &out, &n);
            if (st != THX_OK) { st = bad(ctx, wd, "plane z=%.4f: %s", thx_dig_plane_z(s, k), thx_ctx_message(ctx)); break; }
            double *xyz = thx_malloc(ctx, 3 * (n ? n : 1) * sizeof *xyz);
            if (!xyz) st = THX_ENOMEM;
            for (size_t j = 0; xyz && j < n; j++) {
                xyz[3 * j] = out[j].x;
                xyz[3 * j + 1] = out[j].y;
                xyz[3 * j + 2] = 0;
            }
            if (st == THX_OK) st = add_closed(ctx, s, k, xyz, n);
            free(xyz);
            free(out);
        }
    }
    layer_free(&ca);
    layer_free(&cb);
    return st;
}

static thx_status do_interpolate(thx_ctx *ctx, thx_dig_session *s, const words *wd)
{
    if (wd->n != 1) return bad(ctx, wd, "interpolate takes nothing");
    THX_CHECK(need_surface(ctx, s, wd));
    sess_surface *S = &s->surf[s->cur];
    size_t nk = S->n, gaps = 0;
    long *ks = thx_malloc(ctx, (nk ? nk : 1) * sizeof *ks);
    if (!ks) return THX_ENOMEM;
    for (size_t i = 0; i < nk; i++) ks[i] = S->layers[i].k;
    thx_status st = THX_OK;
    for (size_t i = 0; i + 1 < nk && st == THX_OK; i++)
        if (ks[i + 1] - ks[i] > 1) {
            gaps++;
            st = interp_gap(ctx, s, wd, ks[i], ks[i + 1]);
        }
    free(ks);
    if (st == THX_OK && !gaps) return bad(ctx, wd, "%s has no gap between traced planes", surf_name(s));
    return st;
}

static thx_status log_line(thx_ctx *ctx, thx_dig_session *s, const char *line)
{
    if (s->n_log == s->cap_log) {
        size_t cap = s->cap_log ? 2 * s->cap_log : 64;
        char **n = thx_realloc(ctx, s->log, cap * sizeof *n);
        if (!n) return THX_ENOMEM;
        s->log = n;
        s->cap_log = cap;
    }
    char *c = strdup(line);
    if (!c) return thx_error(ctx, THX_ENOMEM, "out of memory (trace log)");
    s->log[s->n_log++] = c;
    return THX_OK;
}

static thx_status dispatch(thx_ctx *ctx, thx_dig_session *s, const words *wd)
{
    const char *c = wd->w[0];
    if (!strcmp(c, "surface")) return do_surface(ctx, s, wd);
    if (!strcmp(c, "plane")) return do_plane(ctx, s, wd);
    if (!strcmp(c, "tool")) return do_tool(ctx, s, wd);
    if (!strcmp(c, "point")) return do_point(ctx, s, wd);
    if (!strcmp(c, "close")) return do_close(ctx, s, wd);
    if (!strcmp(c, "reopen")) return do_reopen(ctx, s, wd);
    if (!strcmp(c, "move")) return do_points(ctx, s, wd, 0);
    if (!strcmp(c, "insert")) return do_points(ctx, s, wd, 1);
    if (!strcmp(c, "delete")) return do_points(ctx, s, wd, 2);
    if (!strcmp(c, "delete-loop")) return do_delete_loop(ctx, s, wd);
    if (!strcmp(c, "region")) return do_region(ctx, s, wd);
    if (!strcmp(c, "copy")) return do_copy(ctx, s, wd);
    if (!strcmp(c, "interpolate")) return do_interpolate(ctx, s, wd);
    return bad(ctx, wd, "no such line (surface, plane, tool, point, close, reopen, move, insert, delete, delete-loop, "
                        "region, copy, interpolate, undo, redo)");
}

/* Applies a parsed line that may change loops, as one step of undo. */
static thx_status apply_step(thx_ctx *ctx, thx_dig_session *s, const words *wd, int redoing)
{
    sess_record r = {0};
    r.cur = s->cur;
    r.k = s->k;
    r.tool = s->tool;
    r.n_surf = s->n_surf;
    s->rec = &r;
    thx_status st = dispatch(ctx, s, wd);
    s->rec = NULL;
    if (s->cur >= 0) prune(s, (size_t)s->cur);
    for (size_t i = 0; i < r.n_sv; i++)
        if (r.sv[i].surf < s->n_surf) prune(s, r.sv[i].surf);
    if (st != THX_OK) {
        restore(s, &r);
        record_free(&r);
        return st;
    }
    if (!r.n_sv && r.n_surf == s->n_surf) { record_free(&r); return THX_OK; } /* nothing changed: not a step */
    r.line = strdup(wd->line);
    if (!r.line) { restore(s, &r); record_free(&r); return thx_error(ctx, THX_ENOMEM, "out of memory (undo)"); }
    st = stack_push(ctx, &s->undo, &r);
    if (st != THX_OK) { restore(s, &r); record_free(&r); return st; }
    if (!redoing) stack_clear(&s->redo);
    return THX_OK;
}

static thx_status split(thx_ctx *ctx, const char *line, words *wd)
{
    memset(wd, 0, sizeof *wd);
    wd->line = line;
    if (strlen(line) >= sizeof wd->buf) return thx_error(ctx, THX_EINPUT, "trace: a line of %zu characters (at most %zu)", strlen(line), sizeof wd->buf - 1);
    strcpy(wd->buf, line);
    for (char *p = strtok(wd->buf, " \t\r\n"); p; p = strtok(NULL, " \t\r\n")) {
        if (wd->n == MAX_WORDS) return bad(ctx, wd, "more than %d words", MAX_WORDS);
        wd->w[wd->n++] = p;
    }
    if (!wd->n) return thx_error(ctx, THX_EINPUT, "trace: an empty line");
    return THX_OK;
}

thx_status thx_dig_apply(thx_ctx *ctx, thx_dig_session *s, const char *line)
{
    words wd;
    THX_CHECK(split(ctx, line, &wd));
    thx_status st;
    if (!strcmp(wd.w[0], "undo") || !strcmp(wd.w[0], "redo")) {
        int undo = wd.w[0][0] == 'u';
        if (wd.n != 1) return bad(ctx, &wd, "%s takes nothing", wd.w[0]);
        sess_stack *from = undo ? &s->undo : &s->redo;
        if (!from->n) return bad(ctx, &wd, "nothing to %s", wd.w[0]);
        sess_record r = from->r[--from->n];
        if (undo) {
            restore(s, &r);
            /* redo applies the line again from the state it was applied in (restore put it back) */
            for (size_t i = 0; i < r.n_sv; i++) layer_free(&r.sv[i].layer);
            free(r.sv);
            r.sv = NULL;
            r.n_sv = r.cap_sv = 0;
            st = stack_push(ctx, &s->redo, &r);
            if (st != THX_OK) { record_free(&r); return st; }
        } else {
            s->cur = r.cur;
            set_plane(s, r.k);
            s->tool = r.tool;
            words again;
            st = split(ctx, r.line, &again);
            if (st == THX_OK) st = apply_step(ctx, s, &again, 1);
            record_free(&r);
            if (st != THX_OK) return st;
        }
    } else {
        st = apply_step(ctx, s, &wd, 0);
        if (st != THX_OK) return st;
    }
    return log_line(ctx, s, line);
}

/* ---- checks ---- */

thx_status thx_dig_crossings(thx_ctx *ctx, const thx_dig_session *s, long k, thx_dig_crossing **out, size_t *n_out)
{
    *out = NULL;
    *n_out = 0;
    size_t n = 0;
    for (size_t i = 0; i < s->n_surf; i++) {
        const sess_layer *L = find_layer(s, i, k);
        for (size_t j = 0; L && j < L->n; j++) n += L->loops[j].closed && L->loops[j].n >= 3;
    }
    if (n == 0) return THX_OK;
    const thx_vec2 **loops = thx_malloc(ctx, n * sizeof *loops);
    size_t *cnt = thx_malloc(ctx, n * sizeof *cnt), *sid = thx_malloc(ctx, 2 * n * sizeof *sid);
    thx_status st = loops && cnt && sid ? THX_OK : THX_ENOMEM;
    size_t m = 0;
    for (size_t i = 0; st == THX_OK && i < s->n_surf; i++) {
        const sess_layer *L = find_layer(s, i, k);
        for (size_t j = 0; L && j < L->n; j++)
            if (L->loops[j].closed && L->loops[j].n >= 3) {
                loops[m] = L->loops[j].p;
                cnt[m] = L->loops[j].n;
                sid[2 * m] = i;
                sid[2 * m + 1] = j;
                m++;
            }
    }
    thx_loop_crossing *c = NULL;
    size_t nc = 0;
    if (st == THX_OK) st = thx_loops_crossings(ctx, loops, cnt, m, &c, &nc);
    if (st == THX_OK && nc) {
        *out = thx_malloc(ctx, nc * sizeof **out);
        if (!*out) st = THX_ENOMEM;
        for (size_t i = 0; *out && i < nc; i++) {
            thx_dig_crossing *x = &(*out)[i];
            x->sa = sid[2 * c[i].a];
            x->la = sid[2 * c[i].a + 1];
            x->sb = sid[2 * c[i].b];
            x->lb = sid[2 * c[i].b + 1];
            /* where: the two edges' intersection (their midpoints' mean when parallel) */
            const thx_vec2 *A = loops[c[i].a], *B = loops[c[i].b];
            thx_vec2 p = A[c[i].ea], q = A[(c[i].ea + 1) % cnt[c[i].a]];
            thx_vec2 r = B[c[i].eb], t = B[(c[i].eb + 1) % cnt[c[i].b]];
            double dx = q.x - p.x, dy = q.y - p.y, ex = t.x - r.x, ey = t.y - r.y;
            double den = dx * ey - dy * ex;
            double u = fabs(den) > 1e-300 ? ((r.x - p.x) * ey - (r.y - p.y) * ex) / den : 0.5;
            if (!(u >= 0 && u <= 1) || fabs(den) <= 1e-300) {
                x->x = 0.25 * (p.x + q.x + r.x + t.x);
                x->y = 0.25 * (p.y + q.y + r.y + t.y);
            } else {
                x->x = p.x + u * dx;
                x->y = p.y + u * dy;
            }
        }
        if (*out) *n_out = nc;
    }
    free(c);
    free(loops);
    free(cnt);
    free(sid);
    return st;
}

/* ---- outputs ---- */

thx_status thx_dig_contours(thx_ctx *ctx, const thx_dig_session *s, int only, thx_contours **out, size_t *n_skipped)
{
    *out = NULL;
    size_t skipped = 0;
    thx_contours *c = NULL;
    THX_CHECK(thx_contours_create(ctx, &c));
    thx_status st = THX_OK;
    thx_vec2 *tmp = NULL;
    size_t tmp_cap = 0;
    for (size_t i = 0; i < s->n_surf && st == THX_OK; i++) {
        if (only >= 0 && (size_t)only != i) continue;
        const sess_surface *S = &s->surf[i];
        size_t idx = (size_t)-1;
        for (size_t j = 0; j < S->n && st == THX_OK; j++) {
            const sess_layer *L = &S->layers[j];
            for (size_t l = 0; l < L->n && st == THX_OK; l++) {
                const thx_dig_loop *lp = &L->loops[l];
                if (!lp->closed) { skipped++; continue; }
                if (lp->n > tmp_cap) {
                    thx_vec2 *n = thx_realloc(ctx, tmp, lp->n * sizeof *n);
                    if (!n) { st = THX_ENOMEM; break; }
                    tmp = n;
                    tmp_cap = lp->n;
                }
                size_t m = 0;
                for (size_t q = 0; q < lp->n; q++)
                    if (!m || tmp[m - 1].x != lp->p[q].x || tmp[m - 1].y != lp->p[q].y) tmp[m++] = lp->p[q];
                while (m > 1 && tmp[m - 1].x == tmp[0].x && tmp[m - 1].y == tmp[0].y) m--;
                if (m < 3) { skipped++; continue; }
                if (idx == (size_t)-1) st = thx_contours_add_surface(ctx, c, S->name, S->role, THX_CAP_GRID, 0, &idx);
                if (st == THX_OK) st = thx_contours_add_loop(ctx, c, idx, thx_dig_plane_z(s, L->k), tmp, m);
            }
        }
    }
    free(tmp);
    if (st == THX_OK && !c->n_surfaces) st = thx_error(ctx, THX_EINPUT, "nothing traced yet: no closed loop%s%s",
                                                        only >= 0 ? " of " : "", only >= 0 ? thx_dig_surface_name(s, (size_t)only) : "");
    if (st != THX_OK) { thx_contours_destroy(&c); return st; }
    c->frame = thx_frame_ras();
    snprintf(c->image, sizeof c->image, "%s", s->img->path);
    snprintf(c->image_sha256, sizeof c->image_sha256, "%s", s->img->sha256);
    *out = c;
    if (n_skipped) *n_skipped = skipped;
    return THX_OK;
}

thx_status thx_dig_load(thx_ctx *ctx, thx_dig_session *s, const thx_contours *c)
{
    if (s->n_log || s->undo.n) return thx_error(ctx, THX_EINPUT, "trace: contours load only into a new session");
    const char *path = c->path[0] ? c->path : "the contours";
    for (size_t i = 0; i < c->n_surfaces; i++) {
        const thx_contour_surface *cs = &c->surf[i];
        char line[128];
        snprintf(line, sizeof line, "surface %s:%s", cs->name, thx_role_name(cs->role));
        words wd;
        THX_CHECK(split(ctx, line, &wd));
        THX_CHECK(do_surface(ctx, s, &wd));
        size_t si = (size_t)s->cur;
        long last = -1;
        for (size_t j = 0; j < cs->n_layers; j++) {
            const thx_contour_layer *L = &cs->layers[j];
            double f = (L->z - s->lo) / s->step - 0.5;
            long k = (long)floor(f + 0.5);
            if (k < 0 || k >= s->n_planes || fabs(f - (double)k) > 0.25)
                return thx_error(ctx, THX_EINPUT, "%s:%d: %s's layer at z=%g mm is not on one of %s's planes (z = %.4f + %g k mm)",
                                 path, L->line, cs->name, L->z, s->img->path[0] ? s->img->path : "the image",
                                 thx_dig_plane_z(s, 0), s->step);
            if (k == last)
                return thx_error(ctx, THX_EINPUT, "%s:%d: %s has two layers on the image plane z=%.4f", path, L->line,
                                 cs->name, thx_dig_plane_z(s, k));
            last = k;
            for (size_t l = 0; l < L->n_loops; l++) {
                const thx_loop *lp = &L->loops[l];
                double *xyz = thx_malloc(ctx, 3 * (lp->n ? lp->n : 1) * sizeof *xyz);
                if (!xyz) return THX_ENOMEM;
                for (size_t q = 0; q < lp->n; q++) {
                    xyz[3 * q] = lp->p[q].x;
                    xyz[3 * q + 1] = lp->p[q].y;
                    xyz[3 * q + 2] = 0;
                }
                thx_status st = add_closed(ctx, s, k, xyz, lp->n);
                free(xyz);
                if (st != THX_OK) return st;
            }
        }
        bump(s, si);
    }
    s->cur = c->n_surfaces ? 0 : -1;
    return THX_OK;
}
