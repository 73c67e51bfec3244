/*
 * Current streamlines on a volume in parts (thorax/field/streamline.h, thx_streamlines_trace_parts;
 * docs/design/parallel.md, "Streamlines on the parts"): each rank traces the lines in its own
 * tetrahedra and hands them over where they enter another part's; rank 0 joins them into the one
 * process's lines. Every step below is a collective reached by every rank, the status carried.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/field/streamline.h"
#include "thorax/mesh/tet_locate.h"
#include "thorax/parallel/parallel.h"

/* Collective: every rank's n bytes of send on every rank, rank after rank (*all, *counts the
 * caller's to free), st agreed first as thx_par_gather does; a failure after it agreed again. */
static thx_status part_allgather(thx_ctx *ctx, thx_status st, const void *send, size_t n, unsigned char **all,
                                 size_t **counts)
{
    int size = thx_par_size();
    void *g = NULL;
    size_t *c = NULL;
    unsigned long long *cc = calloc((size_t)size, sizeof *cc);
    if (!cc && st == THX_OK) st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines' exchange)");
    static const char none = 0;
    st = thx_par_gather(ctx, st, n ? send : &none, n, &g, &c);
    *all = NULL;
    *counts = NULL;
    if (st != THX_OK) {
        free(cc);
        return st;
    }
    if (thx_par_rank() == 0)
        for (int r = 0; r < size; r++) cc[r] = c[r];
    free(c);
    st = thx_par_bcast(ctx, cc, (size_t)size * sizeof *cc, 0);
    size_t total = 0;
    for (int r = 0; r < size; r++) total += (size_t)cc[r];
    unsigned char *buf = thx_par_rank() == 0 ? g : malloc(total ? total : 1);
    size_t *cn = malloc((size_t)size * sizeof *cn);
    if (st == THX_OK && (!buf || !cn)) st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines' exchange)");
    st = thx_par_agree(ctx, st, NULL); /* every rank ready for the bytes, or none waits for them */
    if (st == THX_OK && total) st = thx_par_bcast(ctx, buf, total, 0);
    for (int r = 0; r < size && cn; r++) cn[r] = (size_t)cc[r];
    free(cc);
    if (st != THX_OK) {
        free(buf);
        free(cn);
        return st;
    }
    *all = buf;
    *counts = cn;
    return THX_OK;
}

static long find_id(const int32_t *ids, size_t n, int32_t id)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t m = lo + (hi - lo) / 2;
        if (ids[m] < id) lo = m + 1;
        else hi = m;
    }
    return lo < n && ids[lo] == id ? (long)lo : -1;
}

/* J at a node, from a part that owns a tetrahedron round it (and so holds them all). */
typedef struct {
    int32_t id, pad;
    double j[3];
} node_j;

/* A line's state on its way to the part owning the tetrahedron it entered (t its number in the whole). */
typedef struct {
    thx_stream_state s;
    int32_t seed, dir, piece, to;
} handover;

/* A piece of a line as this rank traced it (stop -1: handed over at its end). */
typedef struct {
    int32_t seed, dir, piece, stop;
    double length;
    size_t steps, evals;
    int64_t seed_tet; /* the seed's tetrahedron in the whole: a loop's last point */
    thx_stream_piece b;
} piece;

typedef struct {
    int32_t seed, dir, piece, stop;
    int64_t n, steps, evals;
    double length;
} piece_head;

typedef struct {
    piece *p;
    size_t n, cap;
    handover *out;
    size_t n_out, cap_out;
} trace_book;

/* Runs the state s of a line on this part, keeping the piece and, handed over, the state for its owner. */
static thx_status run_piece(thx_ctx *ctx, const thx_stream_field *f, const thx_stream_opts *so, const thx_stream_part *d,
                            thx_stream_state *s, int32_t seed, int32_t dir, int32_t pn, int started, thx_stream_piece *head,
                            trace_book *tb)
{
    if (tb->n == tb->cap) {
        size_t cap = tb->cap ? 2 * tb->cap : 64;
        piece *p = realloc(tb->p, cap * sizeof *p);
        if (!p) {
            if (head) thx_stream_piece_free(head);
            return thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
        }
        tb->p = p, tb->cap = cap;
    }
    piece *p = &tb->p[tb->n++];
    memset(p, 0, sizeof *p);
    p->seed = seed, p->dir = dir, p->piece = pn;
    if (head) p->b = *head; /* the seed's point, from thx_stream_start */
    p->seed_tet = pn == 0 ? d->tet_id[s->t0] : s->t0; /* (a line handed over carries it by its number in the whole) */
    size_t steps = 0, evals = 0;
    int nomem = 0, r = started;
    if (r == THX_STREAM_GOING) r = thx_stream_run(f, so, s, &p->b, &steps, &evals, &nomem);
    p->steps = steps, p->evals = evals;
    if (nomem) return thx_error(ctx, THX_ENOMEM, "out of memory tracing the streamline of seed %d", (int)seed);
    if (r == THX_STREAM_UNSURE)
        return thx_error(ctx, THX_EINPUT, "streamlines: a step of the line from seed %d near (%g, %g, %g) reaches beyond part "
                         "%d's tetrahedra and their ghosts: draw it with one process", (int)seed, s->x[0], s->x[1], s->x[2],
                         d->rank);
    p->stop = r >= 0 ? r : -1;
    p->length = p->b.length;
    if (r != THX_STREAM_HANDOVER) return THX_OK;
    if (tb->n_out == tb->cap_out) {
        size_t cap = tb->cap_out ? 2 * tb->cap_out : 64;
        handover *h = realloc(tb->out, cap * sizeof *h);
        if (!h) return thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
        tb->out = h, tb->cap_out = cap;
    }
    handover *h = &tb->out[tb->n_out++];
    memset(h, 0, sizeof *h);
    h->s = *s;
    h->s.t = d->tet_id[s->t];
    h->s.t0 = p->seed_tet;
    h->seed = seed, h->dir = dir, h->piece = pn + 1, h->to = d->owner[s->t];
    return THX_OK;
}

static int piece_order(const void *a, const void *b)
{
    const piece_head *p = *(const piece_head *const *)a, *q = *(const piece_head *const *)b;
    if (p->seed != q->seed) return p->seed < q->seed ? -1 : 1;
    if (p->dir != q->dir) return p->dir > q->dir ? -1 : 1; /* forward first */
    return p->piece < q->piece ? -1 : p->piece > q->piece;
}

/* Rank 0: the pieces of every rank (bytes, n of them) joined into the one process's lines. */
static thx_status join_lines(thx_ctx *ctx, const unsigned char *all, size_t bytes, thx_streamlines *l)
{
    size_t n = 0, np = 0;
    for (size_t o = 0; o < bytes; n++) {
        piece_head h;
        memcpy(&h, all + o, sizeof h);
        o += sizeof h + (size_t)h.n * 7 * sizeof(double);
    }
    const piece_head **ps = malloc((n + 1) * sizeof *ps);
    if (!ps) return thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
    size_t k = 0;
    for (size_t o = 0; o < bytes; k++) {
        ps[k] = (const piece_head *)(all + o); /* (the gather's buffer is malloc's: aligned, and every piece a multiple of 8) */
        o += sizeof(piece_head) + (size_t)ps[k]->n * 7 * sizeof(double);
        np += (size_t)ps[k]->n;

    }
    qsort(ps, n, sizeof *ps, piece_order);
    l->first = malloc((n + 1) * sizeof *l->first);
    l->xyz = malloc((3 * np + 1) * sizeof *l->xyz);
    l->current = malloc((np + 1) * sizeof *l->current);
    l->potential = malloc((np + 1) * sizeof *l->potential);
    l->arc = malloc((np + 1) * sizeof *l->arc);
    l->tet = calloc(np + 1, sizeof *l->tet);
    l->seed = malloc((n + 1) * sizeof *l->seed);
    l->direction = malloc(n + 1);
    l->stop = malloc(n + 1);
    l->length = malloc((n + 1) * sizeof *l->length);
    if (!l->first || !l->xyz || !l->current || !l->potential || !l->arc || !l->tet || !l->seed || !l->direction || !l->stop ||
        !l->length) {
        free(ps);
        return thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
    }
    size_t nl = 0, q = 0;
    int fwd_loop = 0;
    for (size_t i = 0; i < n;) {
        size_t j = i; /* the pieces of one line: i .. j-1 */
        while (j < n && ps[j]->seed == ps[i]->seed && ps[j]->dir == ps[i]->dir) j++;
        if (ps[i]->dir > 0) fwd_loop = 0;
        int keep = !(ps[i]->dir < 0 && fwd_loop && i > 0 && ps[i - 1]->seed == ps[i]->seed);
        if (ps[i]->dir > 0) fwd_loop = ps[j - 1]->stop == THX_STOP_LOOP;
        if (keep) {
            l->first[nl] = q;
            l->seed[nl] = ps[i]->seed;
            l->direction[nl] = (int8_t)ps[i]->dir;
            l->stop[nl] = (int8_t)ps[j - 1]->stop;
            l->length[nl] = ps[j - 1]->length;
            for (size_t m = i; m < j; m++) {
                l->n_steps += (size_t)ps[m]->steps; /* (a dropped backward line's not: one process traces none) */
                l->n_evals += (size_t)ps[m]->evals;
                const double *v = (const double *)(ps[m] + 1);
                size_t pn = (size_t)ps[m]->n;
                for (size_t a = 0; a < pn; a++, q++) {
                    memcpy(l->xyz + 3 * q, v + 7 * a, 3 * sizeof *v);
                    l->current[q] = v[7 * a + 3];
                    l->potential[q] = v[7 * a + 4];
                    l->arc[q] = v[7 * a + 5];
                    l->tet[q] = (int32_t)v[7 * a + 6];
                }
            }
            nl++;
        }
        i = j;
    }
    l->first[nl] = q;
    l->n_lines = nl;
    l->n_points = q;
    free(ps);
    return THX_OK;
}

thx_status thx_streamlines_trace_parts(thx_ctx *ctx, const thx_volume *v, const thx_stream_part *d, const unsigned char *use,
                                      const double *phi, const double *j_node, const thx_seed_spec *spec, int n_spec,
                                      const thx_stream_opts *opts, const char *what, thx_status st, thx_streamlines **out)
{
    *out = NULL;
    int rank = thx_par_rank();
    size_t nn = v->n_nodes, nt = v->n_tets;
    /* 1: J at the nodes. A node of an own tetrahedron has every tetrahedron round it in the part, summed
       in the whole's order (the part's are ascending): the whole's J to the bit. The others (the ghosts'
       far nodes) are asked of the parts that own a tetrahedron round them. */
    double *jn = malloc((3 * nn + 1) * sizeof *jn);
    unsigned char *full = calloc(nn + 1, 1);
    int32_t *need = malloc((nn + 1) * sizeof *need);
    size_t n_need = 0;
    if (st == THX_OK && (!jn || !full || !need)) st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
    if (st == THX_OK) {
        memcpy(jn, j_node, 3 * nn * sizeof *jn);
        for (size_t t = 0; t < nt; t++)
            if (d->own[t])
                for (int a = 0; a < 4; a++) full[v->tet[4 * t + (size_t)a]] = 1;
        for (size_t i = 0; i < nn; i++)
            if (!full[i]) need[n_need++] = d->node_id[i];
    }
    unsigned char *all = NULL;
    size_t *counts = NULL;
    st = part_allgather(ctx, st, need, n_need * sizeof *need, &all, &counts);
    node_j *reply = NULL;
    size_t n_reply = 0;
    if (st == THX_OK) {
        size_t total = 0;
        for (int r = 0; r < thx_par_size(); r++) total += counts[r];
        const int32_t *ids = (const int32_t *)all;
        reply = malloc((total / sizeof *ids + 1) * sizeof *reply);
        if (!reply) st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
        for (size_t k = 0; reply && k < total / sizeof *ids; k++) {
            long i = find_id(d->node_id, nn, ids[k]);
            if (i < 0 || !full[i]) continue;
            node_j *r = &reply[n_reply++];
            memset(r, 0, sizeof *r);
            r->id = ids[k];
            memcpy(r->j, jn + 3 * i, sizeof r->j);
        }
    }
    free(all);
    free(counts);
    st = part_allgather(ctx, st, reply, n_reply * sizeof *reply, &all, &counts);
    free(reply);
    if (st == THX_OK) {
        size_t total = 0;
        for (int r = 0; r < thx_par_size(); r++) total += counts[r];
        for (size_t k = 0; k < total / sizeof(node_j); k++) {
            node_j r;
            memcpy(&r, all + k * sizeof r, sizeof r);
            long i = find_id(d->node_id, nn, r.id);
            if (i >= 0 && !full[i]) memcpy(jn + 3 * i, r.j, sizeof r.j), full[i] = 2;
        }
        for (size_t i = 0; i < nn && st == THX_OK; i++)
            if (!full[i])
                st = thx_error(ctx, THX_EINPUT, "%s: node %d of part %d is in no part's own tetrahedra", what,
                               (int)d->node_id[i] + 1, rank);
    }
    free(all);
    free(counts);
    free(need);
    free(full);
    /* 2: the field on the part; the whole's largest nodal |J| and bounding box, agreed */
    thx_stream_field *f = NULL;
    if (st == THX_OK) st = thx_stream_field_create(ctx, v, jn, phi, use, &f);
    free(jn);
    double g[7] = {-INFINITY, -INFINITY, -INFINITY, -INFINITY, -INFINITY, -INFINITY, -INFINITY};
    if (st == THX_OK) {
        g[0] = thx_stream_field_max(f);
        for (size_t i = 0; i < nn; i++)
            for (int a = 0; a < 3; a++) {
                g[1 + a] = fmax(g[1 + a], -v->xyz[3 * i + (size_t)a]);
                g[4 + a] = fmax(g[4 + a], v->xyz[3 * i + (size_t)a]);
            }
    }
    st = thx_par_max(ctx, st, g, 7);
    /* the faces of the part's edge: a ghost's face with no neighbour in the part is asked of the ghost's
       owner, who holds every neighbour of its own tetrahedra: the whole's boundary, or another part */
    int32_t *ask = malloc((8 * nt + 2) * sizeof *ask);
    unsigned char *edge = calloc(4 * nt + 1, 1);
    size_t n_ask = 0;
    if (st == THX_OK && (!ask || !edge)) st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
    if (st == THX_OK) {
        const thx_tet_locator *loc = thx_stream_field_locator(f);
        for (size_t t = 0; t < nt; t++)
            for (int k = 0; k < 4 && !d->own[t]; k++)
                if (thx_tet_neighbour(loc, t, k) < 0) ask[2 * n_ask] = d->tet_id[t], ask[2 * n_ask++ + 1] = k;
    }
    st = part_allgather(ctx, st, ask, 2 * n_ask * sizeof *ask, &all, &counts);
    n_ask = 0;
    if (st == THX_OK) {
        size_t total = 0;
        for (int r = 0; r < thx_par_size(); r++) total += counts[r];
        const int32_t *q = (const int32_t *)all;
        int32_t *more = realloc(ask, (3 * (total / (2 * sizeof *q)) + 1) * sizeof *ask);
        if (more) ask = more;
        else st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
        const thx_tet_locator *loc = thx_stream_field_locator(f);
        for (size_t k = 0; more && k < total / (2 * sizeof *q); k++) {
            long t = find_id(d->tet_id, nt, q[2 * k]);
            if (t < 0 || !d->own[t]) continue;
            ask[3 * n_ask] = q[2 * k];
            ask[3 * n_ask + 1] = q[2 * k + 1];
            ask[3 * n_ask++ + 2] = thx_tet_neighbour(loc, (size_t)t, q[2 * k + 1]) >= 0;
        }
    }
    free(all);
    free(counts);
    st = part_allgather(ctx, st, ask, 3 * n_ask * sizeof *ask, &all, &counts);
    if (st == THX_OK) {
        size_t total = 0;
        for (int r = 0; r < thx_par_size(); r++) total += counts[r];
        const int32_t *q = (const int32_t *)all;
        for (size_t k = 0; k < total / (3 * sizeof *q); k++) {
            long t = find_id(d->tet_id, nt, q[3 * k]);
            if (t >= 0 && !d->own[t] && q[3 * k + 2]) edge[4 * (size_t)t + (size_t)q[3 * k + 1]] = 1;
        }
        double lo[3] = {-g[1], -g[2], -g[3]}, hi[3] = {g[4], g[5], g[6]};
        double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
        thx_stream_field_set_part(f, d->own, d->tet_id, edge, g[0], diag);
    }
    free(all);
    free(counts);
    free(ask);
    /* 3: the seeds, every rank all of them; each traced by the lowest rank owning its tetrahedron */
    double *xyz = NULL;
    long *tet = NULL;
    size_t n = 0, *first = calloc((size_t)n_spec + 1, sizeof *first);
    if (st == THX_OK && !first) st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
    for (int k = 0; k < n_spec && st == THX_OK; k++) {
        st = thx_stream_seeds(ctx, f, &spec[k], &xyz, &tet, &n);
        first[k + 1] = n;
    }
    unsigned char *mine = malloc(n + 1);
    if (st == THX_OK && !mine) st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
    for (size_t i = 0; mine && i < n; i++) mine[i] = tet[i] >= 0 && d->own[tet[i]];
    st = part_allgather(ctx, st, mine, n, &all, &counts);
    int *owner = malloc((n + 1) * sizeof *owner);
    if (st == THX_OK && !owner) st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
    for (size_t i = 0; st == THX_OK && i < n; i++) {
        owner[i] = -1;
        for (int r = thx_par_size() - 1; r >= 0; r--)
            if (all[(size_t)r * n + i]) owner[i] = r;
    }
    free(all);
    free(counts);
    free(mine);
    /* the seeds no part holds are outside the domain: dropped, or refused, as one process does */
    int32_t *index = malloc((n + 1) * sizeof *index);
    if (st == THX_OK && !index) st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
    int32_t kept_all = 0;
    for (int k = 0; k < n_spec && st == THX_OK; k++) {
        size_t m = first[k + 1] - first[k], kept = 0;
        for (size_t i = first[k]; i < first[k + 1]; i++) {
            index[i] = owner[i] >= 0 ? kept_all++ : -1;
            kept += owner[i] >= 0;
        }
        if (spec[k].kind == THX_SEED_POINT && !kept)
            st = thx_error(ctx, THX_EINPUT, "seed \"%s\": the point (%g, %g, %g) is outside the domain%s", spec[k].text,
                           spec[k].a[0], spec[k].a[1], spec[k].a[2], " (the mesh, or a region without current)");
        else if (!kept)
            st = thx_error(ctx, THX_EINPUT, "seed \"%s\": every one of its %zu points is outside the domain", spec[k].text, m);
        else if (kept < m && rank == 0)
            thx_log(ctx, THX_LOG_INFO, "seed \"%s\": %zu of its %zu points are outside the domain, left out", spec[k].text,
                    m - kept, m);
    }
    /* 4: the lines, in rounds: each rank runs the lines it holds until they stop or enter another part's
       tetrahedron, then the states handed over go to their owners, until no line is on its way */
    thx_stream_opts so = *opts;
    trace_book tb;
    memset(&tb, 0, sizeof tb);
    for (size_t i = 0; i < n && st == THX_OK; i++) {
        if (owner[i] != rank) continue;
        for (int dir = 1; dir >= -1 && st == THX_OK; dir -= 2) {
            if (!(so.direction & (dir > 0 ? THX_STREAM_FORWARD : THX_STREAM_BACKWARD))) continue;
            /* (a backward line whose forward one closed a loop is traced too, and left out by the join) */
            thx_stream_state s;
            thx_stream_piece b;
            memset(&b, 0, sizeof b);
            int nomem = 0, r = thx_stream_start(f, &so, xyz + 3 * i, tet[i], dir, &s, &b, &nomem);
            if (nomem) {
                thx_stream_piece_free(&b);
                st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
            } else st = run_piece(ctx, f, &so, d, &s, index[i], dir, 0, r, &b, &tb);
        }
    }
    size_t handed = 0;
    int rounds = 0;
    for (;;) {
        st = part_allgather(ctx, st, tb.out, tb.n_out * sizeof *tb.out, &all, &counts);
        tb.n_out = 0;
        if (st != THX_OK) break;
        size_t total = 0;
        for (int r = 0; r < thx_par_size(); r++) total += counts[r];
        handed += total / sizeof(handover);
        rounds++;
        for (size_t k = 0; k < total / sizeof(handover) && st == THX_OK; k++) {
            handover h;
            memcpy(&h, all + k * sizeof h, sizeof h);
            if (h.to != rank) continue;
            long t = find_id(d->tet_id, nt, (int32_t)h.s.t);
            if (t < 0 || !d->own[t]) {
                st = thx_error(ctx, THX_EINTERNAL, "streamlines: a line handed to part %d in tetrahedron %lld, not its own", rank,
                               (long long)h.s.t + 1);
                break;
            }
            h.s.t = t; /* (t0 stays the whole's number: only a loop's last point takes it, see run_piece) */
            st = run_piece(ctx, f, &so, d, &h.s, h.seed, h.dir, h.piece, THX_STREAM_GOING, NULL, &tb);
        }
        free(all);
        free(counts);
        if (!total) break;
    }
    free(xyz);
    free(tet);
    free(owner);
    free(index);
    free(first);
    thx_stream_field_destroy(&f);
    free(edge);
    /* 5: the pieces to rank 0, joined in the one process's order */
    size_t bytes = 0;
    for (size_t k = 0; k < tb.n; k++) bytes += sizeof(piece_head) + tb.p[k].b.n * 7 * sizeof(double);
    unsigned char *buf = malloc(bytes + 1);
    if (st == THX_OK && !buf) st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
    if (st == THX_OK) {
        size_t q = 0;
        for (size_t k = 0; k < tb.n; k++) {
            const piece *p = &tb.p[k];
            piece_head h = {p->seed, p->dir, p->piece, p->stop, (int64_t)p->b.n, (int64_t)p->steps, (int64_t)p->evals, p->length};
            memcpy(buf + q, &h, sizeof h);
            q += sizeof h;
            for (size_t a = 0; a < p->b.n; a++) { /* the point's tetrahedron by its number in the whole */
                int loop_end = p->stop == THX_STOP_LOOP && a + 1 == p->b.n;
                double w[7] = {p->b.xyz[3 * a], p->b.xyz[3 * a + 1], p->b.xyz[3 * a + 2], p->b.cur[a], p->b.phi[a], p->b.arc[a],
                               loop_end ? (double)p->seed_tet : (double)d->tet_id[p->b.tet[a]]};
                memcpy(buf + q, w, sizeof w);
                q += sizeof w;
            }
        }
    }
    for (size_t k = 0; k < tb.n; k++) thx_stream_piece_free(&tb.p[k].b);
    free(tb.p);
    free(tb.out);
    void *g0 = NULL;
    size_t *c0 = NULL;
    st = thx_par_gather(ctx, st, bytes ? (const void *)buf : (const void *)"", bytes, &g0, &c0);
    free(buf);
    thx_streamlines *l = NULL;
    if (st == THX_OK && !(l = calloc(1, sizeof *l))) st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
    if (st == THX_OK && rank == 0) {
        size_t total = 0;
        for (int r = 0; r < thx_par_size(); r++) total += c0[r];
        st = join_lines(ctx, g0, total, l);
        if (st == THX_OK)
            thx_log(ctx, THX_LOG_INFO, "streamlines on %d parts: %zu lines from %d seeds, handed from part to part %zu times in %d "
                    "rounds", thx_par_size(), l->n_lines, (int)kept_all, handed, rounds);
    } else if (st == THX_OK && !(l->first = calloc(1, sizeof *l->first)))
        st = thx_error(ctx, THX_ENOMEM, "out of memory (streamlines)");
    free(g0);
    free(c0);
    if (st != THX_OK) {
        thx_streamlines_destroy(&l);
        return st;
    }
    *out = l;
    return THX_OK;
}
