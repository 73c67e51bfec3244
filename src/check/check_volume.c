/*
 * Invariant checks of tetrahedral volume meshes (see thorax/check_volume.h; paper 3.3): the
 * options, the failures' names and reasons, the regions' expected volumes, and thx_volume_check,
 * which runs the checks of the other check_volume*.c files in order (check_volume_impl.h lists
 * them) and gives the verdict.
 */
#include "check_volume_impl.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void thx_volume_check_opts_default(thx_volume_check_opts *o)
{
    o->volume_tol = 0.01;
    o->region_volume_tol = 0.005;
    o->node_tol = 1e-5;
    o->coverage_tol = 1e-6;
    o->expected_cavities = -1;
    o->check_intersections = 1;
    o->min_dihedral_deg = 1.0;
    o->max_radius_edge = 0.0;
}

const char *thx_volume_check_failure_name(thx_volume_check_failure f)
{
    switch (f) {
    case THX_VCHECKF_EMPTY: return "empty";
    case THX_VCHECKF_BAD_INDEX: return "bad_index";
    case THX_VCHECKF_BAD_REGION: return "bad_region";
    case THX_VCHECKF_REPEATED_NODE: return "repeated_node";
    case THX_VCHECKF_INVERTED: return "inverted";
    case THX_VCHECKF_FLAT: return "flat";
    case THX_VCHECKF_UNUSED: return "unused_nodes";
    case THX_VCHECKF_DUPLICATE_NODE: return "duplicate_nodes";
    case THX_VCHECKF_DUPLICATE_TET: return "duplicate_tetrahedra";
    case THX_VCHECKF_NONCONFORMING: return "nonconforming";
    case THX_VCHECKF_BOUNDARY: return "boundary";
    case THX_VCHECKF_COMPONENTS: return "components";
    case THX_VCHECKF_CONTAINMENT: return "containment";
    case THX_VCHECKF_VOLUME: return "volume";
    case THX_VCHECKF_REGION_VOLUME: return "region_volume";
    case THX_VCHECKF_NODE_TABLE: return "node_table";
    case THX_VCHECKF_QUALITY: return "quality";
    case THX_VCHECKF_COVERAGE: return "coverage";
    case THX_VCHECKF_REGION_CELLS: return "region_cells";
    }
    return "?";
}

static void add_reason(thx_volume_report *r, thx_volume_check_failure f, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void add_reason(thx_volume_report *r, thx_volume_check_failure f, const char *fmt, ...)
{
    r->failures |= (unsigned)f;
    if (r->n_reasons >= THX_VCHECK_MAX_REASONS) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->reasons[r->n_reasons++], sizeof r->reasons[0], fmt, ap);
    va_end(ap);
}

static void append_name(char *buf, size_t size, const char *sep, const char *name)
{
    size_t n = strlen(buf);
    if (n + 1 < size) snprintf(buf + n, size - n, "%s%s", n ? sep : "", name);
}

/* ------------------------------------------------------------------ */
/* Region expectations (mapping by name, documented in the header). */

/* The surfaces region `name` belongs to (the inside of each, less the
 * surfaces nested directly in it): flags in base[]; 0 if the name maps to none. */
static int region_base(const thx_model *m, const char *name, unsigned char *base)
{
    size_t ns = m->n_surfaces;
    memset(base, 0, ns);
    for (size_t s = 0; s < ns; s++) {
        thx_role ro = m->surf[s]->role;
        if ((ro == THX_ROLE_LUNG || ro == THX_ROLE_HEART || ro == THX_ROLE_OTHER) && !strcmp(m->surf[s]->name, name)) {
            base[s] = 1;
            return 1;
        }
    }
    size_t has[THX_ROLE_COUNT] = {0};
    for (size_t s = 0; s < ns; s++)
        if ((int)m->surf[s]->role >= 0 && m->surf[s]->role < THX_ROLE_COUNT) has[m->surf[s]->role]++;
    thx_role want;
    if (!strcmp(name, "heart")) want = THX_ROLE_HEART;
    else if (!strcmp(name, "lung") || !strcmp(name, "lungs")) want = THX_ROLE_LUNG;
    else if (!strcmp(name, "fat")) {
        if (!has[THX_ROLE_FAT]) return 0;
        want = THX_ROLE_OUTER;
    } else if (!strcmp(name, "muscle")) {
        if (!has[THX_ROLE_MUSCLE]) return 0;
        want = has[THX_ROLE_FAT] ? THX_ROLE_FAT : THX_ROLE_OUTER;
    } else if (!strcmp(name, "mean_thorax") || !strcmp(name, "thorax") || !strcmp(name, "torso")) {
        want = has[THX_ROLE_MUSCLE] ? THX_ROLE_MUSCLE : has[THX_ROLE_FAT] ? THX_ROLE_FAT : THX_ROLE_OUTER;
    } else {
        return 0;
    }
    if (!has[want]) return 0;
    for (size_t s = 0; s < ns; s++) base[s] = m->surf[s]->role == want;
    return 1;
}

/* Expected volume of region `name`: over its base surfaces S, V(S) minus the
 * volumes of the surfaces whose parent is S; NaN if the name maps to none.
 * def gets e.g. "muscle - lung_r - lung_l - heart". base: scratch, n_surfaces. */
static double region_expectation(const thx_model *m, const thx_volume_surface_report *sr, const char *name,
                                 unsigned char *base, char *def, size_t size)
{
    def[0] = '\0';
    if (!region_base(m, name, base)) return NAN;
    double v = 0.0;
    for (size_t s = 0; s < m->n_surfaces; s++) {
        if (!base[s]) continue;
        append_name(def, size, " + ", m->surf[s]->name);
        v += sr[s].volume;
        for (size_t c = 0; c < m->n_surfaces; c++)
            if (sr[c].parent == (int)s) {
                v -= sr[c].volume;
                size_t n = strlen(def);
                if (n + 1 < size) snprintf(def + n, size - n, " - %s", m->surf[c]->name);
            }
    }
    return v;
}

/* ------------------------------------------------------------------ */
/* The reasons. */

/* "inside NAME" / "outside every surface" for a cell. */
static void cell_name(const thx_model *m, int cell, char *buf, size_t size)
{
    if (cell >= 0) snprintf(buf, size, "inside %s", m->surf[cell]->name);
    else snprintf(buf, size, "outside every surface");
}

/* The reasons for the failures found, in a fixed order (numbers 1-based, as in volume.tet). */
static void list_reasons(const thx_volume *v, const thx_model *m, const thx_volume_check_opts *o, const tet_fig *fig,
                         const int32_t *cell_region, thx_volume_report *r)
{
    if (r->n_bad_region_tets) {
        if (!v->region)
            add_reason(r, THX_VCHECKF_BAD_REGION, "bad region: the volume has no region per tetrahedron");
        else
            add_reason(r, THX_VCHECKF_BAD_REGION,
                       "bad region: %zu tetrahedra have a region outside 1..%zu (first: tetrahedron %zu)",
                       r->n_bad_region_tets, v->n_regions, r->ex_bad_region_tet + 1);
    }
    if (r->n_repeated_node_tets)
        add_reason(r, THX_VCHECKF_REPEATED_NODE, "repeated node: %zu tetrahedra use a node twice (first: tetrahedron %zu)",
                   r->n_repeated_node_tets, r->ex_repeated_node_tet + 1);
    if (r->n_inverted_tets)
        add_reason(r, THX_VCHECKF_INVERTED,
                   "inverted: %zu tetrahedra have negative volume (left-handed; first: tetrahedron %zu, %.6g mm^3)",
                   r->n_inverted_tets, r->ex_inverted_tet + 1, fig[r->ex_inverted_tet].vol);
    if (r->n_flat_tets)
        add_reason(r, THX_VCHECKF_FLAT, "flat: %zu tetrahedra have zero volume (first: tetrahedron %zu)", r->n_flat_tets,
                   r->ex_flat_tet + 1);
    if (r->n_unused_nodes)
        add_reason(r, THX_VCHECKF_UNUSED, "unused nodes: %zu nodes in no tetrahedron (first: node %ld)",
                   r->n_unused_nodes, (long)r->ex_unused_node + 1);
    if (r->n_duplicate_nodes)
        add_reason(r, THX_VCHECKF_DUPLICATE_NODE,
                   "duplicate nodes: %zu nodes coincide with another (first: nodes %ld and %ld)", r->n_duplicate_nodes,
                   (long)r->ex_duplicate_node[0] + 1, (long)r->ex_duplicate_node[1] + 1);
    if (r->n_duplicate_tets)
        add_reason(r, THX_VCHECKF_DUPLICATE_TET,
                   "duplicate tetrahedra: %zu repeat the nodes of another (first: tetrahedra %zu and %zu)",
                   r->n_duplicate_tets, r->ex_duplicate_tet[0] + 1, r->ex_duplicate_tet[1] + 1);
    if (r->n_nonconforming_faces)
        add_reason(r, THX_VCHECKF_NONCONFORMING,
                   "nonconforming: %zu faces in three or more tetrahedra (first: nodes %ld %ld %ld)",
                   r->n_nonconforming_faces, (long)r->ex_nonconforming_face[0] + 1,
                   (long)r->ex_nonconforming_face[1] + 1, (long)r->ex_nonconforming_face[2] + 1);
    if (r->n_overlapping_faces)
        add_reason(r, THX_VCHECKF_NONCONFORMING,
                   "nonconforming: %zu faces have both tetrahedra on the same side (overlap; first: nodes %ld %ld %ld)",
                   r->n_overlapping_faces, (long)r->ex_overlapping_face[0] + 1, (long)r->ex_overlapping_face[1] + 1,
                   (long)r->ex_overlapping_face[2] + 1);
    if (r->boundary_checked && !r->boundary.ok)
        add_reason(r, THX_VCHECKF_BOUNDARY, "boundary surface (%zu faces): %s%s", r->n_boundary_faces,
                   r->boundary.reasons[0], r->boundary.n_reasons > 1 ? " (and more)" : "");
    else if (!r->n_boundary_faces)
        add_reason(r, THX_VCHECKF_BOUNDARY, "boundary: no face lies in exactly one tetrahedron");
    if (r->n_boundary_faces && (r->n_shells != r->expected_shells || r->n_cavities != r->expected_cavities)) {
        char voids[96] = "";
        if (r->n_voids)
            snprintf(voids, sizeof voids, "; %zu void%s: tetrahedra missing inside the mesh", r->n_voids,
                     r->n_voids == 1 ? "" : "s");
        add_reason(r, THX_VCHECKF_COMPONENTS,
                   "components: the boundary has %zu shell%s and %zu cavit%s, expected %zu and %zu%s", r->n_shells,
                   r->n_shells == 1 ? "" : "s", r->n_cavities, r->n_cavities == 1 ? "y" : "ies", r->expected_shells,
                   r->expected_cavities, voids);
    }
    if (r->n_outside_tets)
        add_reason(r, THX_VCHECKF_CONTAINMENT,
                   "containment: %zu tetrahedra have their centroid outside %s (first: tetrahedron %zu)",
                   r->n_outside_tets, r->outer_names, r->ex_outside_tet + 1);
    if (r->n_in_cavity_tets)
        add_reason(r, THX_VCHECKF_CONTAINMENT,
                   "containment: %zu tetrahedra have their centroid inside the excluded %s (first: tetrahedron %zu)",
                   r->n_in_cavity_tets, r->excluded_names, r->ex_in_cavity_tet + 1);
    if (r->coverage_checked) {
        for (size_t s = 0; s < r->n_surface_reports; s++) {
            const thx_volume_surface_report *sr = &r->surfaces[s];
            if (sr->n_covered == sr->n_tris) continue;
            add_reason(r, THX_VCHECKF_COVERAGE,
                       "coverage: surface \"%s\": %zu of %zu triangles not covered by mesh faces (first: triangle %zu, "
                       "centroid (%.6g, %.6g, %.6g), %.4g%% of its area covered)",
                       sr->name, sr->n_tris - sr->n_covered, sr->n_tris, sr->ex_uncovered + 1, sr->ex_centroid[0],
                       sr->ex_centroid[1], sr->ex_centroid[2], 100.0 * sr->ex_covered_share);
        }
        if (r->n_faces_off_surfaces)
            add_reason(r, THX_VCHECKF_COVERAGE,
                       "coverage: %zu faces between regions or on the boundary lie on no surface triangle (region "
                       "boundary off the surfaces; first: nodes %ld %ld %ld, centroid (%.6g, %.6g, %.6g))",
                       r->n_faces_off_surfaces, (long)r->ex_off_face[0] + 1, (long)r->ex_off_face[1] + 1,
                       (long)r->ex_off_face[2] + 1, r->ex_off_centroid[0], r->ex_off_centroid[1], r->ex_off_centroid[2]);
    }
    if (r->n_outside_region_tets)
        for (size_t k = 0; k < r->n_regions; k++) {
            const thx_volume_region_report *rg = &r->regions[k];
            if (!rg->n_outside) continue;
            char where[96];
            cell_name(m, rg->ex_outside_cell, where, sizeof where);
            int32_t holder = cell_region[rg->ex_outside_cell + 1];
            add_reason(r, THX_VCHECKF_REGION_CELLS,
                       "tetrahedra outside their region: region \"%s\": %zu of %zu tetrahedra lie %s, which holds "
                       "region \"%s\" (first: tetrahedron %zu)",
                       rg->name, rg->n_outside, rg->n_tets, where, holder >= 0 ? r->regions[holder].name : "?",
                       rg->ex_outside + 1);
        }
    if (o->volume_tol > 0.0 && r->volume_rel_diff == r->volume_rel_diff && !(fabs(r->volume_rel_diff) <= o->volume_tol))
        add_reason(r, THX_VCHECKF_VOLUME,
                   "volume: tetrahedra %.6g mm^3, enclosed by the surfaces (%s) %.6g mm^3: relative difference %+.3g%% "
                   "(tolerance %.3g%%)",
                   r->tet_volume, r->volume_definition, r->enclosed_volume, 100.0 * r->volume_rel_diff,
                   100.0 * o->volume_tol);
    for (size_t k = 0; k < r->n_regions; k++)
        if (!r->regions[k].ok)
            add_reason(r, THX_VCHECKF_REGION_VOLUME,
                       "region \"%s\": tetrahedra %.6g mm^3, surfaces (%s) %.6g mm^3: relative difference %+.3g%% "
                       "(tolerance %.3g%%)",
                       r->regions[k].name, r->regions[k].volume, r->regions[k].definition, r->regions[k].expected,
                       100.0 * r->regions[k].rel_diff, 100.0 * o->region_volume_tol);
    if (r->node_tables_checked) {
        if (r->n_table_size_errors)
            add_reason(r, THX_VCHECKF_NODE_TABLE,
                       "node tables: %zu missing or of the wrong size (volume tables for %zu surfaces, model has %zu)",
                       r->n_table_size_errors, v->n_surfaces, m ? m->n_surfaces : v->n_surfaces);
        if (r->n_table_bad_entries || r->n_table_mismatches)
            add_reason(r, THX_VCHECKF_NODE_TABLE,
                       "node tables: %zu surface nodes map to no volume node, %zu to a volume node elsewhere (> %.3g mm; "
                       "first: surface %zu node %zu)",
                       r->n_table_bad_entries, r->n_table_mismatches, o->node_tol, r->ex_table_surface + 1,
                       r->ex_table_node + 1);
        if (r->n_table_backlink_errors)
            add_reason(r, THX_VCHECKF_NODE_TABLE,
                       "node tables: %zu volume/surface entries do not point back to each other (first: volume node %ld)",
                       r->n_table_backlink_errors, (long)r->ex_backlink_node + 1);
    }
    if (r->n_steiner_bad || r->n_steiner_mismatches) {
        const thx_steiner *sr = v->steiner ? &v->steiner[r->ex_steiner] : NULL;
        add_reason(r, THX_VCHECKF_NODE_TABLE,
                   "Steiner nodes: %zu records out of range or on a surface node, %zu nodes farther than %.3g mm from "
                   "the point of their barycentric coordinates (first: record %zu, volume node %ld)",
                   r->n_steiner_bad, r->n_steiner_mismatches, o->node_tol, r->ex_steiner + 1,
                   sr ? (long)sr->node + 1 : 0L);
    }
    if (o->min_dihedral_deg > 0.0 && !(r->min_dihedral >= o->min_dihedral_deg))
        add_reason(r, THX_VCHECKF_QUALITY, "quality: smallest dihedral angle %.3g deg < %.3g deg (tetrahedron %zu)",
                   r->min_dihedral, o->min_dihedral_deg, r->min_dihedral_tet + 1);
    if (o->max_radius_edge > 0.0 && !(r->max_radius_edge <= o->max_radius_edge))
        add_reason(r, THX_VCHECKF_QUALITY, "quality: radius-edge ratio %.4g > %.4g (tetrahedron %zu)",
                   r->max_radius_edge, o->max_radius_edge, r->max_radius_edge_tet + 1);
}

/* ------------------------------------------------------------------ */

thx_status thx_volume_check(thx_ctx *ctx, const thx_volume *v, const thx_model *m, const thx_volume_check_opts *opts_in,
                            thx_volume_report *r)
{
    thx_volume_check_opts o;
    if (opts_in) o = *opts_in;
    else thx_volume_check_opts_default(&o);
    memset(r, 0, sizeof *r);
    r->n_nodes = v->n_nodes;
    r->n_tets = v->n_tets;
    r->n_table_regions = v->n_regions;
    r->volume_tol = o.volume_tol;
    r->region_volume_tol = o.region_volume_tol;
    r->node_tol = o.node_tol;
    r->coverage_tol = o.coverage_tol;
    r->min_dihedral_opt = o.min_dihedral_deg;
    r->max_radius_edge_opt = o.max_radius_edge;
    r->tet_volume = r->enclosed_volume = r->volume_rel_diff = NAN;
    r->min_tet_volume = r->max_tet_volume = NAN;
    r->table_max_distance = r->steiner_max_distance = NAN;
    r->min_dihedral = r->max_dihedral = r->max_radius_edge = r->mean_radius_edge = NAN;
    r->min_radius_ratio = r->mean_radius_ratio = r->min_edge = r->max_edge = NAN;

    thx_status st = THX_OK;
    size_t nt = v->n_tets, nv = v->n_nodes;
    tet_fig *fig = NULL;
    unsigned char *bmask = NULL, *used = NULL, *cls = NULL, *excluded = NULL, *usable = NULL, *base = NULL;
    int32_t *bnodes = NULL, *cell = NULL, *cell_region = NULL, *steiner_surf = NULL;
    size_t n_bnodes = 0, *iface = NULL, n_iface = 0, *order = NULL, *cell_count = NULL;
    inside_surface *isf = NULL;
    size_t n_isf = 0;

    /* regions table first: reported even when the mesh is unusable */
    if (v->n_regions) {
        r->regions = thx_calloc(ctx, v->n_regions, sizeof *r->regions);
        if (!r->regions) return THX_ENOMEM;
        r->n_regions = v->n_regions;
        for (size_t k = 0; k < v->n_regions; k++) {
            snprintf(r->regions[k].name, sizeof r->regions[k].name, "%s", v->regions[k].name);
            r->regions[k].expected = r->regions[k].rel_diff = NAN;
            r->regions[k].ok = 1;
            r->regions[k].cell = -2;
        }
    }
    if (nt == 0) {
        add_reason(r, THX_VCHECKF_EMPTY, "empty: the volume has no tetrahedra");
        goto verdict;
    }
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 4; k++) {
            int32_t g = v->tet[4 * t + k];
            if (g < 0 || (size_t)g >= nv) {
                if (!r->n_bad_index_tets) r->ex_bad_index_tet = t;
                r->n_bad_index_tets++;
                break;
            }
        }
    if (r->n_bad_index_tets) {
        add_reason(r, THX_VCHECKF_BAD_INDEX,
                   "bad index: %zu tetrahedra refer to nodes outside 1..%zu (first: tetrahedron %zu); nothing else "
                   "checked",
                   r->n_bad_index_tets, nv, r->ex_bad_index_tet + 1);
        goto verdict;
    }

    /* phase times for -v (THX_LOG_DEBUG) */
    double tp = thx_wtime(), t_tets = 0, t_faces = 0, t_bound = 0, t_surf = 0, t_cover = 0, t_cells = 0;
    fig = thx_malloc(ctx, nt * sizeof *fig);
    bmask = thx_calloc(ctx, nt, 1);
    used = thx_calloc(ctx, nv + 1, 1);
    if (!fig || !bmask || !used) {
        st = THX_ENOMEM;
        goto done;
    }
    long long nt_ll = (long long)nt;
    cv_tets(v, fig, used, r); /* orientation, volume and quality of each tetrahedron; their sums */

    t_tets = thx_wtime() - tp;
    tp = thx_wtime();
    THX_TRY(cv_duplicates(ctx, v, fig, r));
    THX_TRY(cv_faces_and_boundary(ctx, v, fig, bmask, r, m ? &iface : NULL, &n_iface));
    t_faces = thx_wtime() - tp;

    /* surfaces of the model that bound the mesh: outer ones and excluded hearts */
    size_t n_outer = 0, n_excl = 0;
    if (m) {
        excluded = thx_calloc(ctx, m->n_surfaces + 1, 1);
        if (!excluded) {
            st = THX_ENOMEM;
            goto done;
        }
        for (size_t s = 0; s < m->n_surfaces; s++) {
            const thx_surface *ms = m->surf[s];
            if (ms->role == THX_ROLE_OUTER) {
                n_outer++;
                append_name(r->outer_names, sizeof r->outer_names, ", ", ms->name);
            } else if (ms->role == THX_ROLE_HEART) {
                int mapped = 0;
                for (size_t k = 0; k < v->n_regions && !mapped; k++)
                    mapped = !strcmp(v->regions[k].name, ms->name) || !strcmp(v->regions[k].name, "heart");
                if (!mapped) {
                    excluded[s] = 1;
                    n_excl++;
                    append_name(r->excluded_names, sizeof r->excluded_names, ", ", ms->name);
                }
            }
        }
    }
    r->n_outer_surfaces = n_outer;
    r->n_excluded_hearts = n_excl;
    r->expected_shells = (m && n_outer) ? n_outer : 1;
    r->expected_cavities = o.expected_cavities >= 0 ? (size_t)o.expected_cavities : n_excl;

    tp = thx_wtime();
    if (r->n_boundary_faces) THX_TRY(cv_boundary(ctx, v, bmask, &o, r, &bnodes, &n_bnodes));
    t_bound = thx_wtime() - tp;
    tp = thx_wtime();
    if (r->n_cavities > r->expected_cavities) r->n_voids = r->n_cavities - r->expected_cavities;

    /* the model's surfaces: coverage, containment, cells, nesting, volumes */
    if (m && m->n_surfaces) {
        size_t ns = m->n_surfaces;
        isf = thx_calloc(ctx, ns, sizeof *isf);
        usable = thx_calloc(ctx, ns, 1);
        base = thx_calloc(ctx, ns, 1);
        order = thx_malloc(ctx, ns * sizeof *order);
        r->surfaces = thx_calloc(ctx, ns, sizeof *r->surfaces);
        cls = thx_calloc(ctx, nt, 1);
        cell = thx_malloc(ctx, nt * sizeof *cell);
        if (!isf || !usable || !base || !order || !r->surfaces || !cls || !cell) {
            st = THX_ENOMEM;
            goto done;
        }
        r->n_surface_reports = ns;
        n_isf = ns;
        int all_usable = 1, bound_usable = 1;
        for (size_t s = 0; s < ns; s++) {
            thx_volume_surface_report *sr = &r->surfaces[s];
            snprintf(sr->name, sizeof sr->name, "%s", m->surf[s]->name);
            sr->n_tris = m->surf[s]->n_tris;
            sr->parent = -1;
            sr->ex_covered_share = NAN;
            sr->volume = NAN; /* unusable surfaces: no volume, no nesting */
            thx_status s2 = cv_inside_surface_init(ctx, m->surf[s], &isf[s]);
            if (s2 == THX_EINPUT) {
                all_usable = 0;
                if (m->surf[s]->role == THX_ROLE_OUTER || excluded[s]) bound_usable = 0;
            } else if (s2 != THX_OK) {
                st = s2;
                goto done;
            } else {
                usable[s] = 1;
                sr->volume = thx_surface_volume(m->surf[s]);
            }
        }
        for (size_t k = 0; k < v->n_steiner && v->steiner; k++)
            if (v->steiner[k].surf >= 0 && (size_t)v->steiner[k].surf < ns) r->surfaces[v->steiner[k].surf].n_steiner++;
        /* increasing |volume|, ties by index: the first surface holding a point is its innermost */
        for (size_t s = 0; s < ns; s++) {
            size_t j = s;
            while (j > 0 && fabs(r->surfaces[order[j - 1]].volume) > fabs(r->surfaces[s].volume)) {
                order[j] = order[j - 1];
                j--;
            }
            order[j] = s;
        }
        cv_nesting(m, isf, usable, order, r->surfaces);
        t_surf = thx_wtime() - tp;
        tp = thx_wtime();
        THX_TRY(cv_coverage(ctx, v, m, iface, n_iface, &o, r));
        t_cover = thx_wtime() - tp;
        tp = thx_wtime();

        int do_cont = bound_usable && (n_outer || n_excl);
        if (do_cont || all_usable) {
            /* cls bits: 1 outside every outer surface, 2 inside an excluded heart, 4 fallback used */
THX_OMP(omp parallel for schedule(dynamic, 1024))
            for (long long t = 0; t < nt_ll; t++) {
                const int32_t *q = v->tet + 4 * t;
                thx_vec3 c = thx_v3(0, 0, 0);
                for (int k = 0; k < 4; k++) c = thx_v3_add(c, node3(v->xyz, q[k]));
                c = thx_v3_scale(c, 0.25);
                unsigned char bits = 0;
                int in_outer = 0;
                int32_t ce = -1;
                for (size_t k = 0; k < ns; k++) {
                    size_t s = order[k];
                    if (!usable[s]) continue;
                    int is_outer = m->surf[s]->role == THX_ROLE_OUTER, is_excl = excluded[s];
                    /* past the innermost surface only the outer and excluded ones matter */
                    int need = (all_usable && ce < 0) || (is_outer && !in_outer) || is_excl;
                    if (!need) continue;
                    int inside = 0;
                    if (cv_classify_point(&isf[s], c, &inside) == 2) bits |= 4;
                    if (inside && ce < 0) ce = (int32_t)s;
                    if (is_outer) in_outer |= inside;
                    else if (is_excl && inside) bits |= 2;
                }
                if (n_outer && !in_outer) bits |= 1;
                cls[t] = bits;
                cell[t] = ce;
            }
        }
        t_cells = thx_wtime() - tp;
        if (do_cont) {
            r->containment_checked = 1;
            for (size_t t = 0; t < nt; t++) {
                if (cls[t] & 1) {
                    if (!r->n_outside_tets) r->ex_outside_tet = t;
                    r->n_outside_tets++;
                }
                if (cls[t] & 2) {
                    if (!r->n_in_cavity_tets) r->ex_in_cavity_tet = t;
                    r->n_in_cavity_tets++;
                }
            }
        }
        if (do_cont || all_usable)
            for (size_t t = 0; t < nt; t++) r->n_undecided_tets += (cls[t] & 4) != 0;
        /* each cell holds one region: the one most of its tetrahedra have */
        size_t nreg = v->n_regions, nc = ns + 1;
        if (all_usable && v->region && nreg) {
            r->cells_checked = 1;
            cell_count = thx_calloc(ctx, nc * nreg, sizeof *cell_count);
            cell_region = thx_malloc(ctx, nc * sizeof *cell_region);
            if (!cell_count || !cell_region) {
                st = THX_ENOMEM;
                goto done;
            }
            for (size_t t = 0; t < nt; t++) {
                int32_t g = v->region[t];
                if (g >= 0 && (size_t)g < nreg) cell_count[(size_t)(cell[t] + 1) * nreg + (size_t)g]++;
            }
            for (size_t c = 0; c < nc; c++) {
                size_t best = 0;
                cell_region[c] = -1;
                for (size_t g = 0; g < nreg; g++)
                    if (cell_count[c * nreg + g] > best) {
                        best = cell_count[c * nreg + g];
                        cell_region[c] = (int32_t)g;
                    }
            }
            for (size_t g = 0; g < nreg; g++) {
                size_t best = 0;
                for (size_t c = 0; c < nc; c++)
                    if (cell_count[c * nreg + g] > best) {
                        best = cell_count[c * nreg + g];
                        r->regions[g].cell = (int)c - 1;
                    }
            }
            for (size_t t = 0; t < nt; t++) {
                int32_t g = v->region[t];
                if (g < 0 || (size_t)g >= nreg || cell_region[cell[t] + 1] == g) continue;
                thx_volume_region_report *rg = &r->regions[g];
                if (!rg->n_outside) {
                    rg->ex_outside = t;
                    rg->ex_outside_cell = cell[t];
                }
                rg->n_outside++;
                if (!r->n_outside_region_tets) r->ex_outside_region_tet = t;
                r->n_outside_region_tets++;
            }
        }
    }
    if (m && n_outer) {
        double ve = 0.0;
        for (size_t s = 0; s < m->n_surfaces; s++)
            if (m->surf[s]->role == THX_ROLE_OUTER) {
                ve += thx_surface_volume(m->surf[s]);
                append_name(r->volume_definition, sizeof r->volume_definition, " + ", m->surf[s]->name);
            }
        for (size_t s = 0; s < m->n_surfaces; s++)
            if (excluded[s]) {
                ve -= thx_surface_volume(m->surf[s]);
                append_name(r->volume_definition, sizeof r->volume_definition, " - ", m->surf[s]->name);
            }
        r->enclosed_volume = ve;
        r->volume_rel_diff = (r->tet_volume - ve) / ve;
    }
    if (m && r->surfaces)
        for (size_t k = 0; k < r->n_regions; k++) {
            thx_volume_region_report *rg = &r->regions[k];
            rg->expected = region_expectation(m, r->surfaces, rg->name, base, rg->definition, sizeof rg->definition);
            if (rg->expected == rg->expected) rg->rel_diff = (rg->volume - rg->expected) / rg->expected;
            if (o.region_volume_tol > 0.0 && rg->expected == rg->expected && !(fabs(rg->rel_diff) <= o.region_volume_tol))
                rg->ok = 0;
        }

    thx_log(ctx, THX_LOG_DEBUG,
            "volume check: tetrahedra %.3f s, faces %.3f s, boundary %.3f s, surfaces %.3f s, coverage %.3f s "
            "(%zu interface faces), cells %.3f s",
            t_tets, t_faces, t_bound, t_surf, t_cover, n_iface, t_cells);
    cv_node_tables(v, m, &o, r);
    cv_steiner_table(v, m, &o, r);
    if (m && r->node_tables_checked && v->node_surf && bnodes) {
        steiner_surf = thx_malloc(ctx, (nv + 1) * sizeof *steiner_surf);
        if (!steiner_surf) {
            st = THX_ENOMEM;
            goto done;
        }
        for (size_t g = 0; g < nv; g++) steiner_surf[g] = -1;
        for (size_t k = 0; k < v->n_steiner && v->steiner; k++) {
            const thx_steiner *sr = &v->steiner[k];
            if (sr->node >= 0 && (size_t)sr->node < nv && sr->surf >= 0 && (size_t)sr->surf < m->n_surfaces)
                steiner_surf[sr->node] = sr->surf;
        }
        for (size_t i = 0; i < n_bnodes; i++) {
            int32_t s = v->node_surf[bnodes[i]], s2 = steiner_surf[bnodes[i]];
            int on = (s >= 0 && (size_t)s < m->n_surfaces && (m->surf[s]->role == THX_ROLE_OUTER || excluded[s])) ||
                     (s2 >= 0 && (m->surf[s2]->role == THX_ROLE_OUTER || excluded[s2]));
            r->n_boundary_nodes_off_surfaces += !on;
        }
    }

    list_reasons(v, m, &o, fig, cell_region, r);

verdict:
    r->ok = r->failures == 0;
    if (!r->ok) st = thx_error(ctx, THX_ECHECK, "volume: %s", r->reasons[0]);
done:
    if (st != THX_OK && st != THX_ECHECK) {
        /* an allocation failed: the report is incomplete */
        r->ok = 0;
    }
    for (size_t k = 0; k < n_isf; k++) cv_inside_surface_free(&isf[k]);
    free(isf);
    free(usable);
    free(base);
    free(order);
    free(cell);
    free(cell_region);
    free(cell_count);
    free(steiner_surf);
    free(iface);
    free(fig);
    free(bmask);
    free(used);
    free(cls);
    free(excluded);
    free(bnodes);
    return st;
}

void thx_volume_report_free(thx_volume_report *r)
{
    if (!r) return;
    free(r->regions);
    free(r->surfaces);
    memset(r, 0, sizeof *r);
}
