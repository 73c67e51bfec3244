/*
 * Volume meshes made elsewhere: Gmsh MSH 4.1 ASCII (thorax/io/volume_read.h).
 */
#include "io/volume/import_volume_impl.h"

/* ---------------------------------------------------------- Gmsh .msh */

typedef struct {
    long long tag;
    long long phys; /* the physical tag when n_phys == 1 */
    int n_phys;
} msh_entity;

static int cmp_entity(const void *a, const void *b)
{
    long long x = ((const msh_entity *)a)->tag, y = ((const msh_entity *)b)->tag;
    return x < y ? -1 : x > y;
}

static const msh_entity *find_entity(const msh_entity *e, size_t n, long long tag)
{
    msh_entity key = {tag, 0, 0};
    return bsearch(&key, e, n, sizeof *e, cmp_entity);
}

typedef struct { long long tag; int32_t index; } node_key;

static int cmp_node_key(const void *a, const void *b)
{
    long long x = ((const node_key *)a)->tag, y = ((const node_key *)b)->tag;
    return x < y ? -1 : x > y;
}

static const char *msh_type_name(long long type)
{
    switch (type) {
    case 1: return "2-node line";
    case 2: return "3-node triangle";
    case 3: return "4-node quadrangle";
    case 4: return "4-node tetrahedron";
    case 5: return "8-node hexahedron";
    case 6: return "6-node prism";
    case 7: return "5-node pyramid";
    case 11: return "10-node second-order tetrahedron";
    case 12: return "27-node hexahedron";
    case 13: return "18-node prism";
    case 14: return "14-node pyramid";
    case 15: return "1-node point";
    case 17: return "20-node hexahedron";
    case 18: return "15-node prism";
    case 19: return "13-node pyramid";
    case 29: return "20-node third-order tetrahedron";
    default: return "not a 4-node tetrahedron";
    }
}

/* Skips lines to "$End<name>" (after the section's opening line). */
static thx_status msh_skip_section(raw *r, cursor *c, const char *name, int open_line)
{
    char want[80];
    snprintf(want, sizeof want, "$End%s", name);
    tok tk[1];
    int line;
    size_t k;
    while ((k = read_line(c, tk, 1, &line)) != 0)
        if (tok_is(tk[0].t, tk[0].n, want)) return THX_OK;
    return fail(r, at_line(open_line), "section $%s is not closed by %s (file truncated?)", name, want);
}

static thx_status msh_end(raw *r, cursor *c, const char *name)
{
    char want[80];
    snprintf(want, sizeof want, "$End%s", name);
    tok tk[2];
    int line;
    size_t k = read_line(c, tk, 2, &line);
    if (k != 1 || !tok_is(tk[0].t, tk[0].n, want))
        return fail(r, at_line(line), "expected %s, found %s", want, k ? tok_show(tk[0].t, tk[0].n) : "the end of the file");
    return THX_OK;
}

/* The counts on a section's header line: n integers >= 0. */
static thx_status msh_counts(raw *r, cursor *c, const char *what, int n, long long *v)
{
    tok tk[8];
    int line;
    size_t k = read_line(c, tk, 8, &line);
    if ((int)k != n) return fail(r, at_line(line), "%s: expected %d numbers on this line, found %zu", what, n, k);
    for (int i = 0; i < n; i++)
        if (tk_int(&tk[i], &v[i]) != 0 || v[i] < 0)
            return fail(r, at_line(line), "%s: \"%s\" is not a count", what, tok_show(tk[i].t, tk[i].n));
    return THX_OK;
}

static int cmp_ref(const void *a, const void *b)
{
    const long long *x = a, *y = b; /* (element tag, index) pairs */
    if (x[0] != y[0]) return x[0] < y[0] ? -1 : 1;
    return (x[1] > y[1]) - (x[1] < y[1]);
}

/* Tetrahedra in the order of their element tags (blocks come per entity;
 * thorax's own export numbers elements as volume.tet's lines). */
static thx_status sort_tets_by_tag(raw *r, int line)
{
    size_t n = r->n_tets;
    long long *key = thx_malloc(r->ctx, 2 * (n ? n : 1) * sizeof *key);
    int32_t *tet = thx_malloc(r->ctx, 4 * (n ? n : 1) * sizeof *tet);
    long long *tag = thx_malloc(r->ctx, (n ? n : 1) * sizeof *tag);
    thx_status st = THX_OK;
    if (!key || !tet || !tag) {
        st = THX_ENOMEM;
        goto done;
    }
    for (size_t t = 0; t < n; t++) key[2 * t] = r->ref[t], key[2 * t + 1] = (long long)t;
    qsort(key, n, 2 * sizeof *key, cmp_ref);
    for (size_t t = 0; t < n; t++) {
        if (t && key[2 * t] == key[2 * t - 2]) {
            st = fail(r, at_line(line), "$Elements: element tag %lld appears twice", key[2 * t]);
            goto done;
        }
        size_t o = (size_t)key[2 * t + 1];
        memcpy(tet + 4 * t, r->tet + 4 * o, 4 * sizeof *tet);
        tag[t] = r->tag[o];
    }
    if (n) { /* memcpy wants real pointers even for no bytes; an empty file has none */
        memcpy(r->tet, tet, 4 * n * sizeof *tet);
        memcpy(r->tag, tag, n * sizeof *tag);
    }
    for (size_t t = 0; t < n; t++) r->ref[t] = key[2 * t];
done:
    free(key);
    free(tet);
    free(tag);
    return st;
}

thx_status vol_read_msh(raw *r, const char *text, size_t len)
{
    thx_status st = THX_OK;
    cursor c = {text, len, 0, 1};
    tok tk[16];
    int line;
    size_t k;
    msh_entity *ents[4] = {NULL, NULL, NULL, NULL};
    size_t n_ents[4] = {0, 0, 0, 0};
    int have_entities = 0, have_nodes = 0, have_elements = 0, phys3 = 0;
    node_key *keys = NULL;
    int32_t *tri_nodes = NULL;
    if (nul_line(text, len)) { /* an ASCII file: a NUL byte means a binary or damaged one */
        st = fail(r, at_line(nul_line(text, len)), "NUL byte at byte %zu (binary MSH files are not supported)",
                  (size_t)((const char *)memchr(text, 0, len) - text));
        goto done;
    }
    int have_names = 0;
    k = read_line(&c, tk, 2, &line);
    if (k != 1 || !tok_is(tk[0].t, tk[0].n, "$MeshFormat")) {
        st = fail(r, at_line(line), "not a Gmsh .msh file (no $MeshFormat on the first line)");
        goto done;
    }
    k = read_line(&c, tk, 4, &line);
    if (k != 3) {
        st = fail(r, at_line(line), "$MeshFormat: expected \"version file-type data-size\"");
        goto done;
    }
    if (!tok_is(tk[0].t, tk[0].n, "4.1")) {
        st = fail(r, at_line(line), "MSH version %s is not supported: only 4.1 (gmsh -format msh41, or Mesh.MshFileVersion = 4.1)",
                  tok_show(tk[0].t, tk[0].n));
        goto done;
    }
    if (!tok_is(tk[1].t, tk[1].n, "0")) {
        st = fail(r, at_line(line), "binary MSH files are not supported: write ASCII (Mesh.Binary = 0)");
        goto done;
    }
    THX_TRY(msh_end(r, &c, "MeshFormat"));
    while ((k = read_line(&c, tk, 2, &line)) != 0) {
        if (tk[0].n < 2 || tk[0].t[0] != '$') {
            st = fail(r, at_line(line), "expected a section ($Nodes, $Elements, ...), found \"%s\"", tok_show(tk[0].t, tk[0].n));
            goto done;
        }
        char name[64];
        copy_tok(name, sizeof name, tk[0].t + 1, tk[0].n - 1);
        int open_line = line;
        if ((!strcmp(name, "PhysicalNames") && have_names) || (!strcmp(name, "Entities") && have_entities) ||
            (!strcmp(name, "Nodes") && have_nodes) || (!strcmp(name, "Elements") && have_elements) ||
            !strcmp(name, "MeshFormat")) {
            st = fail(r, at_line(line), "a second $%s section", name);
            goto done;
        }
        if (!strcmp(name, "PhysicalNames")) {
            have_names = 1;
            long long n;
            THX_TRY(msh_counts(r, &c, "$PhysicalNames", 1, &n));
            if ((size_t)n > len / 8) {
                st = fail(r, at_line(open_line), "$PhysicalNames: %lld names declared, but the file is too short for them", n);
                goto done;
            }
            for (long long i = 0; i < n; i++) {
                if (!to_filled_line(&c)) {
                    st = fail(r, at_line(c.line), "$PhysicalNames: file ends at name %lld of %lld", i + 1, n);
                    goto done;
                }
                line = c.line;
                cursor lc = c;
                k = line_tokens(&lc, tk, 2);
                long long dim, tag;
                if (k < 3 || tk_int(&tk[0], &dim) != 0 || tk_int(&tk[1], &tag) != 0) {
                    st = fail(r, at_line(line), "$PhysicalNames: expected 'dimension tag \"name\"'");
                    goto done;
                }
                /* the name is quoted and may hold spaces */
                const char *ls = c.buf + c.pos, *le = memchr(ls, '\n', c.len - c.pos);
                if (!le) le = c.buf + c.len;
                const char *q1 = memchr(ls, '"', (size_t)(le - ls));
                const char *q2 = q1 ? memchr(q1 + 1, '"', (size_t)(le - q1 - 1)) : NULL;
                if (!q2) {
                    st = fail(r, at_line(line), "$PhysicalNames: the name must be in double quotes");
                    goto done;
                }
                if (dim == 2 || dim == 3) THX_TRY(add_name(r, (int)dim, tag, q1 + 1, (size_t)(q2 - q1 - 1)));
                next_line(&c);
            }
            THX_TRY(msh_end(r, &c, name));
        } else if (!strcmp(name, "Entities")) {
            long long cnt[4];
            THX_TRY(msh_counts(r, &c, "$Entities", 4, cnt));
            for (int d = 0; d < 4; d++) {
                if ((size_t)cnt[d] > len / 8) {
                    st = fail(r, at_line(open_line), "$Entities: %lld entities of dimension %d declared, but the file is too "
                              "short for them", cnt[d], d);
                    goto done;
                }
                if (d >= 2) {
                    ents[d] = thx_calloc(r->ctx, (size_t)cnt[d] + 1, sizeof *ents[d]);
                    if (!ents[d]) {
                        st = THX_ENOMEM;
                        goto done;
                    }
                }
                for (long long i = 0; i < cnt[d]; i++) {
                    k = read_line(&c, tk, 16, &line);
                    int at = d == 0 ? 4 : 7; /* numPhysicalTags after the tag and the coordinates / bounding box */
                    long long tag, np = 0;
                    if (k == 0) {
                        st = fail(r, at_line(line), "$Entities: file ends at entity %lld of dimension %d", i + 1, d);
                        goto done;
                    }
                    if (k < (size_t)at + 1 || tk_int(&tk[0], &tag) != 0 || tk_int(&tk[at], &np) != 0 || np < 0 ||
                        k < (size_t)(at + 1 + np)) {
                        st = fail(r, at_line(line), "$Entities: malformed entity of dimension %d", d);
                        goto done;
                    }
                    if (d < 2) continue;
                    msh_entity *e = &ents[d][n_ents[d]++];
                    e->tag = tag;
                    e->n_phys = (int)(np > 2 ? 2 : np);
                    if (np >= 1) {
                        if ((size_t)at + 1 >= 16 || tk_int(&tk[at + 1], &e->phys) != 0) {
                            st = fail(r, at_line(line), "$Entities: malformed physical tag");
                            goto done;
                        }
                        if (d == 3) phys3 = 1;
                    }
                }
                if (d >= 2) qsort(ents[d], n_ents[d], sizeof *ents[d], cmp_entity);
            }
            have_entities = 1;
            THX_TRY(msh_end(r, &c, name));
        } else if (!strcmp(name, "PartitionedEntities")) {
            st = fail(r, at_line(line), "partitioned meshes are not supported (write the mesh unpartitioned)");
            goto done;
        } else if (!strcmp(name, "Nodes")) {
            long long h[4];
            THX_TRY(msh_counts(r, &c, "$Nodes", 4, h));
            if ((size_t)h[1] > len / 8) {
                st = fail(r, at_line(open_line), "$Nodes: %lld nodes declared, but the file is too short for them", h[1]);
                goto done;
            }
            for (long long b = 0; b < h[0]; b++) {
                long long bh[4];
                THX_TRY(msh_counts(r, &c, "$Nodes block", 4, bh));
                long long dim = bh[0], param = bh[2], n = bh[3];
                if (dim > 3 || param > 1 || (size_t)n > (len - c.pos) / 8) {
                    st = fail(r, at_line(c.line - 1), "$Nodes: malformed block header (or more nodes than the file holds)");
                    goto done;
                }
                size_t first = r->n_nodes;
                if (first + (size_t)n > r->cap_node_tag)
                    THX_TRY(thx_grow(r->ctx, (void **)&r->node_tag, &r->cap_node_tag, first + (size_t)n, sizeof *r->node_tag));
                for (long long i = 0; i < n; i++) {
                    long long tag;
                    k = read_line(&c, tk, 2, &line);
                    if (k != 1 || tk_int(&tk[0], &tag) != 0 || tag < 1) {
                        st = fail(r, at_line(line), "$Nodes: expected a node tag (a positive integer)%s", k ? "" : ": file ends");
                        goto done;
                    }
                    r->node_tag[first + (size_t)i] = tag;
                }
                size_t want = 3 + (size_t)(param ? dim : 0);
                for (long long i = 0; i < n; i++) {
                    k = read_line(&c, tk, 8, &line);
                    double v[3];
                    if (k != want) {
                        st = fail(r, at_line(line), "$Nodes: node %lld: expected %zu coordinates, found %zu",
                                  r->node_tag[first + (size_t)i], want, k);
                        goto done;
                    }
                    for (int j = 0; j < 3; j++)
                        if (parse_num(tk[j].t, tk[j].n, &v[j]) != 0) {
                            st = fail(r, at_line(line), "$Nodes: node %lld: coordinate \"%s\" is not a finite number",
                                      r->node_tag[first + (size_t)i], tok_show(tk[j].t, tk[j].n));
                            goto done;
                        }
                    THX_TRY(add_node(r, at_line(line), v[0], v[1], v[2]));
                }
            }
            if (r->n_nodes != (size_t)h[1]) {
                st = fail(r, at_line(open_line), "$Nodes: %lld nodes declared, %zu in the blocks", h[1], r->n_nodes);
                goto done;
            }
            THX_TRY(msh_end(r, &c, name));
            keys = thx_malloc(r->ctx, (r->n_nodes ? r->n_nodes : 1) * sizeof *keys);
            if (!keys) {
                st = THX_ENOMEM;
                goto done;
            }
            for (size_t i = 0; i < r->n_nodes; i++) keys[i].tag = r->node_tag[i], keys[i].index = (int32_t)i;
            qsort(keys, r->n_nodes, sizeof *keys, cmp_node_key);
            for (size_t i = 1; i < r->n_nodes; i++)
                if (keys[i].tag == keys[i - 1].tag) {
                    st = fail(r, at_line(open_line), "$Nodes: node tag %lld appears twice", keys[i].tag);
                    goto done;
                }
            /* nodes in the order of their tags (a tag is a node's identity; thorax's
             * own export uses the volume node numbers) */
            {
                double *xyz = thx_malloc(r->ctx, 3 * (r->n_nodes ? r->n_nodes : 1) * sizeof *xyz);
                if (!xyz) {
                    st = THX_ENOMEM;
                    goto done;
                }
                for (size_t i = 0; i < r->n_nodes; i++) {
                    memcpy(xyz + 3 * i, r->xyz + 3 * (size_t)keys[i].index, 3 * sizeof *xyz);
                    r->node_tag[i] = keys[i].tag;
                    keys[i].index = (int32_t)i;
                }
                free(r->xyz);
                r->xyz = xyz;
                r->cap_nodes = r->n_nodes;
            }
            have_nodes = 1;
        } else if (!strcmp(name, "Elements")) {
            if (!have_nodes) {
                st = fail(r, at_line(line), "$Elements before $Nodes");
                goto done;
            }
            long long h[4];
            THX_TRY(msh_counts(r, &c, "$Elements", 4, h));
            if ((size_t)h[1] > len / 4) {
                st = fail(r, at_line(open_line), "$Elements: %lld elements declared, but the file is too short for them", h[1]);
                goto done;
            }
            long long seen = 0;
            for (long long b = 0; b < h[0]; b++) {
                long long bh[4];
                THX_TRY(msh_counts(r, &c, "$Elements block", 4, bh));
                int hline = c.line - 1;
                long long dim = bh[0], etag = bh[1], type = bh[2], n = bh[3];
                if (dim > 3 || (size_t)n > (len - c.pos) / 4) {
                    st = fail(r, at_line(hline), "$Elements: malformed block header (or more elements than the file holds)");
                    goto done;
                }
                seen += n;
                if (dim == 3 && type != 4) {
                    st = fail(r, at_line(hline), "elements of type %lld (%s) in volume %lld: only 4-node tetrahedra (type 4) "
                              "can be imported", type, msh_type_name(type), etag);
                    goto done;
                }
                if (type == 4 && dim != 3) {
                    st = fail(r, at_line(hline), "tetrahedra in an entity of dimension %lld", dim);
                    goto done;
                }
                long long region = etag, sphys = -1;
                if (dim == 3 && phys3) {
                    const msh_entity *e = find_entity(ents[3], n_ents[3], etag);
                    if (!e) {
                        st = fail(r, at_line(hline), "volume %lld is not listed in $Entities", etag);
                        goto done;
                    }
                    if (e->n_phys == 0) {
                        st = fail(r, at_line(hline), "volume %lld belongs to no physical group while other volumes do: "
                                  "give every volume one physical group, or none", etag);
                        goto done;
                    }
                    if (e->n_phys > 1) {
                        st = fail(r, at_line(hline), "volume %lld belongs to several physical groups: its region is ambiguous",
                                  etag);
                        goto done;
                    }
                    region = e->phys;
                }
                if (dim == 2 && type == 2 && have_entities) {
                    const msh_entity *e = find_entity(ents[2], n_ents[2], etag);
                    if (e && e->n_phys == 1 && name_of(r, 2, e->phys)) sphys = e->phys;
                }
                for (long long i = 0; i < n; i++) {
                    k = read_line(&c, tk, 8, &line);
                    if (k == 0) {
                        st = fail(r, at_line(line), "$Elements: file ends in a block of %lld elements", n);
                        goto done;
                    }
                    if (type != 4 && !(type == 2 && sphys >= 0)) {
                        r->n_ignored++;
                        continue;
                    }
                    size_t want = type == 4 ? 5 : 4;
                    long long tag;
                    if (k != want || tk_int(&tk[0], &tag) != 0) {
                        st = fail(r, at_line(line), "$Elements: expected an element tag and %zu node tags, found %zu values",
                                  want - 1, k);
                        goto done;
                    }
                    int32_t v[4];
                    for (size_t j = 1; j < want; j++) {
                        node_key key = {0, 0};
                        if (tk_int(&tk[j], &key.tag) != 0) {
                            st = fail(r, at_line(line), "element %lld: node tag \"%s\" is not an integer", tag,
                                      tok_show(tk[j].t, tk[j].n));
                            goto done;
                        }
                        const node_key *f = bsearch(&key, keys, r->n_nodes, sizeof *keys, cmp_node_key);
                        if (!f) {
                            st = fail(r, at_line(line), "element %lld refers to node %lld, which $Nodes does not have", tag,
                                      key.tag);
                            goto done;
                        }
                        v[j - 1] = f->index;
                    }
                    if (type == 4) {
                        THX_TRY(add_tet(r, v, region, tag));
                    } else {
                        if (r->n_tris + 1 > r->cap_tri)
                            THX_TRY(thx_grow(r->ctx, (void **)&r->tri, &r->cap_tri, r->n_tris + 1, 3 * sizeof *r->tri));
                        if (r->n_tris + 1 > r->cap_tri_tag)
                            THX_TRY(thx_grow(r->ctx, (void **)&r->tri_tag, &r->cap_tri_tag, r->n_tris + 1, sizeof *r->tri_tag));
                        memcpy(r->tri + 3 * r->n_tris, v, 3 * sizeof *v);
                        r->tri_tag[r->n_tris++] = sphys;
                    }
                }
            }
            if (seen != h[1]) {
                st = fail(r, at_line(open_line), "$Elements: %lld elements declared, %lld in the blocks", h[1], seen);
                goto done;
            }
            THX_TRY(sort_tets_by_tag(r, open_line));
            THX_TRY(msh_end(r, &c, name));
            have_elements = 1;
        } else {
            /* $Periodic, $NodeData, $ElementData, $Comments, ...: no mesh in them */
            THX_TRY(msh_skip_section(r, &c, name, open_line));
        }
    }
    if (!have_nodes || !have_elements) {
        st = fail(r, at_file(), "no %s section", have_nodes ? "$Elements" : "$Nodes");
        goto done;
    }
    r->has_tags = 1;
    r->ref_kind = "element";
    r->index_base = 1;
    snprintf(r->detail, sizeof r->detail, "Gmsh MSH 4.1 ASCII");
    snprintf(r->region_source, sizeof r->region_source, "%s",
             phys3 ? "physical groups (dimension 3)" : "volume entities (no physical groups)");
done:
    for (int d = 0; d < 4; d++) free(ents[d]);
    free(keys);
    free(tri_nodes);
    return st;
}

