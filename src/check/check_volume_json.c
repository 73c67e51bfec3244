/*
 * The volume check's report as JSON (thx_volume_report_json; see check_volume.c). Node and
 * tetrahedron numbers are 1-based; non-finite numbers become null.
 */
#include "check_volume_impl.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

static cJSON *num(double x) { return isfinite(x) ? cJSON_CreateNumber(x) : cJSON_CreateNull(); }

static void add_num(cJSON *o, const char *k, double x) { cJSON_AddItemToObject(o, k, num(x)); }

static void add_count(cJSON *o, const char *k, size_t n) { cJSON_AddNumberToObject(o, k, (double)n); }

static void add_nodes1(cJSON *o, const char *k, const int32_t *x, int n)
{
    cJSON *arr = cJSON_CreateArray();
    for (int i = 0; i < n; i++) cJSON_AddItemToArray(arr, cJSON_CreateNumber((double)x[i] + 1));
    cJSON_AddItemToObject(o, k, arr);
}

static void add_names(cJSON *o, const char *k, const char *list)
{
    cJSON *arr = cJSON_AddArrayToObject(o, k);
    char buf[160];
    snprintf(buf, sizeof buf, "%s", list);
    for (char *save = NULL, *tok = strtok_r(buf, ", ", &save); tok; tok = strtok_r(NULL, ", ", &save))
        cJSON_AddItemToArray(arr, cJSON_CreateString(tok));
}

static void add_hist(cJSON *o, const double *edges, const size_t *counts, int nb)
{
    cJSON *h = cJSON_AddObjectToObject(o, "histogram");
    cJSON *he = cJSON_AddArrayToObject(h, "edges");
    for (int b = 0; b <= nb; b++) cJSON_AddItemToArray(he, num(edges[b]));
    cJSON *hc = cJSON_AddArrayToObject(h, "counts");
    for (int b = 0; b < nb; b++) cJSON_AddItemToArray(hc, cJSON_CreateNumber((double)counts[b]));
}

static void add_worst(cJSON *o, const thx_volume_worst *l, size_t n)
{
    cJSON *arr = cJSON_AddArrayToObject(o, "worst");
    for (size_t k = 0; k < n; k++) {
        cJSON *pr = cJSON_CreateArray();
        cJSON_AddItemToArray(pr, cJSON_CreateNumber((double)l[k].tet + 1));
        cJSON_AddItemToArray(pr, num(l[k].value));
        cJSON_AddItemToArray(arr, pr);
    }
}

cJSON *thx_volume_report_json(thx_ctx *ctx, const thx_volume_report *r)
{
    cJSON *o = cJSON_CreateObject();
    if (!o) goto nomem;
    int indexed = !(r->failures & (THX_VCHECKF_EMPTY | THX_VCHECKF_BAD_INDEX));
    cJSON_AddBoolToObject(o, "ok", r->ok);
    cJSON_AddNumberToObject(o, "index_base", 1);
    cJSON *fl = cJSON_AddArrayToObject(o, "failures");
    for (unsigned b = 0; b < THX_VCHECK_N_FAILURES; b++)
        if (r->failures & (1u << b))
            cJSON_AddItemToArray(fl, cJSON_CreateString(thx_volume_check_failure_name((thx_volume_check_failure)(1u << b))));
    cJSON *rs = cJSON_AddArrayToObject(o, "reasons");
    for (size_t i = 0; i < r->n_reasons; i++) cJSON_AddItemToArray(rs, cJSON_CreateString(r->reasons[i]));
    add_count(o, "nodes", r->n_nodes);
    add_count(o, "tetrahedra", r->n_tets);
    add_count(o, "region_table_size", r->n_table_regions);
    cJSON_AddBoolToObject(o, "conforming", indexed && !r->n_nonconforming_faces && !r->n_overlapping_faces &&
                                               !r->n_duplicate_tets);
    cJSON_AddBoolToObject(o, "boundary_closed", indexed && r->boundary_checked && !r->boundary.n_boundary_edges &&
                                                    !r->boundary.n_nonmanifold_edges);
    cJSON_AddBoolToObject(o, "positive", indexed && !r->n_inverted_tets && !r->n_flat_tets && !r->n_repeated_node_tets);

    cJSON *va = cJSON_AddObjectToObject(o, "validity");
    add_count(va, "bad_index_tetrahedra", r->n_bad_index_tets);
    add_count(va, "bad_region_tetrahedra", r->n_bad_region_tets);
    add_count(va, "repeated_node_tetrahedra", r->n_repeated_node_tets);
    add_count(va, "inverted_tetrahedra", r->n_inverted_tets);
    add_count(va, "flat_tetrahedra", r->n_flat_tets);
    add_count(va, "unused_nodes", r->n_unused_nodes);
    add_count(va, "duplicate_nodes", r->n_duplicate_nodes);
    add_count(va, "duplicate_tetrahedra", r->n_duplicate_tets);
    cJSON *vf = cJSON_AddObjectToObject(va, "first");
    if (r->n_bad_index_tets) add_count(vf, "bad_index_tetrahedron", r->ex_bad_index_tet + 1);
    if (r->n_bad_region_tets) add_count(vf, "bad_region_tetrahedron", r->ex_bad_region_tet + 1);
    if (r->n_repeated_node_tets) add_count(vf, "repeated_node_tetrahedron", r->ex_repeated_node_tet + 1);
    if (r->n_inverted_tets) add_count(vf, "inverted_tetrahedron", r->ex_inverted_tet + 1);
    if (r->n_flat_tets) add_count(vf, "flat_tetrahedron", r->ex_flat_tet + 1);
    if (r->n_unused_nodes) add_count(vf, "unused_node", (size_t)r->ex_unused_node + 1);
    if (r->n_duplicate_nodes) add_nodes1(vf, "duplicate_nodes", r->ex_duplicate_node, 2);
    if (r->n_duplicate_tets) {
        int32_t d[2] = {(int32_t)r->ex_duplicate_tet[0], (int32_t)r->ex_duplicate_tet[1]};
        add_nodes1(vf, "duplicate_tetrahedra", d, 2);
    }

    cJSON *co = cJSON_AddObjectToObject(o, "conformity");
    add_count(co, "faces", r->n_faces);
    add_count(co, "interior_faces", r->n_interior_faces);
    add_count(co, "boundary_faces", r->n_boundary_faces);
    add_count(co, "faces_in_3_or_more", r->n_nonconforming_faces);
    add_count(co, "overlapping_faces", r->n_overlapping_faces);
    add_count(co, "boundary_components", r->n_boundary_components);
    add_count(co, "shells", r->n_shells);
    add_count(co, "cavities", r->n_cavities);
    add_count(co, "expected_shells", r->expected_shells);
    add_count(co, "expected_cavities", r->expected_cavities);
    add_count(co, "voids", r->n_voids);
    add_count(co, "boundary_nodes_off_surfaces", r->n_boundary_nodes_off_surfaces);
    cJSON *cf = cJSON_AddObjectToObject(co, "first");
    if (r->n_nonconforming_faces) add_nodes1(cf, "face_in_3_or_more", r->ex_nonconforming_face, 3);
    if (r->n_overlapping_faces) add_nodes1(cf, "overlapping_face", r->ex_overlapping_face, 3);
    if (r->boundary_checked) {
        cJSON *bj = thx_surface_report_json(ctx, &r->boundary, NULL);
        if (!bj) {
            cJSON_Delete(o);
            return NULL;
        }
        cJSON_AddItemToObject(co, "boundary", bj);
    } else {
        cJSON_AddNullToObject(co, "boundary");
    }

    cJSON *ct = cJSON_AddObjectToObject(o, "containment");
    cJSON_AddBoolToObject(ct, "checked", r->containment_checked);
    add_names(ct, "outer_surfaces", r->outer_names);
    add_names(ct, "excluded_surfaces", r->excluded_names);
    add_count(ct, "outside", r->n_outside_tets);
    add_count(ct, "in_excluded", r->n_in_cavity_tets);
    add_count(ct, "undecided", r->n_undecided_tets);
    cJSON *tf = cJSON_AddObjectToObject(ct, "first");
    if (r->n_outside_tets) add_count(tf, "outside_tetrahedron", r->ex_outside_tet + 1);
    if (r->n_in_cavity_tets) add_count(tf, "in_excluded_tetrahedron", r->ex_in_cavity_tet + 1);

    cJSON *cv = cJSON_AddObjectToObject(o, "coverage");
    cJSON_AddBoolToObject(cv, "checked", r->coverage_checked);
    add_count(cv, "interface_faces", r->n_interface_faces);
    add_count(cv, "uncovered_triangles", r->n_uncovered_tris);
    add_count(cv, "faces_off_surfaces", r->n_faces_off_surfaces);
    add_num(cv, "tolerance", r->coverage_tol);
    cJSON *csf = cJSON_AddArrayToObject(cv, "surfaces");
    for (size_t s = 0; s < r->n_surface_reports && csf; s++) {
        const thx_volume_surface_report *sr = &r->surfaces[s];
        cJSON *so = cJSON_CreateObject();
        cJSON_AddStringToObject(so, "name", sr->name);
        add_count(so, "triangles", sr->n_tris);
        add_count(so, "covered", sr->n_covered);
        add_num(so, "share", sr->share);
        add_num(so, "area", sr->area);
        add_num(so, "covered_area", sr->covered_area);
        add_count(so, "steiner_nodes", sr->n_steiner);
        if (sr->parent >= 0 && (size_t)sr->parent < r->n_surface_reports)
            cJSON_AddStringToObject(so, "inside", r->surfaces[sr->parent].name);
        else
            cJSON_AddNullToObject(so, "inside");
        if (sr->n_covered < sr->n_tris) {
            cJSON *fu = cJSON_AddObjectToObject(so, "first_uncovered");
            add_count(fu, "triangle", sr->ex_uncovered + 1);
            cJSON *ce = cJSON_AddArrayToObject(fu, "centroid");
            for (int k = 0; k < 3; k++) cJSON_AddItemToArray(ce, num(sr->ex_centroid[k]));
            add_num(fu, "covered_share", sr->ex_covered_share);
        }
        cJSON_AddItemToArray(csf, so);
    }
    if (r->n_faces_off_surfaces) {
        cJSON *fo = cJSON_AddObjectToObject(cv, "first_off_surface");
        add_nodes1(fo, "nodes", r->ex_off_face, 3);
        cJSON *ce = cJSON_AddArrayToObject(fo, "centroid");
        for (int k = 0; k < 3; k++) cJSON_AddItemToArray(ce, num(r->ex_off_centroid[k]));
    }

    cJSON *rcl = cJSON_AddObjectToObject(o, "region_cells");
    cJSON_AddBoolToObject(rcl, "checked", r->cells_checked);
    add_count(rcl, "outside_region", r->n_outside_region_tets);
    if (r->n_outside_region_tets) add_count(rcl, "first_tetrahedron", r->ex_outside_region_tet + 1);

    cJSON *vo = cJSON_AddObjectToObject(o, "volume");
    add_num(vo, "tetrahedra", r->tet_volume);
    add_num(vo, "enclosed", r->enclosed_volume);
    cJSON_AddStringToObject(vo, "definition", r->volume_definition);
    add_num(vo, "rel_diff", r->volume_rel_diff);
    add_num(vo, "tolerance", r->volume_tol);
    add_num(vo, "min_tet", r->min_tet_volume);
    add_num(vo, "max_tet", r->max_tet_volume);
    cJSON_AddBoolToObject(vo, "ok", !(r->failures & THX_VCHECKF_VOLUME));

    cJSON *rg = cJSON_AddArrayToObject(o, "regions");
    for (size_t k = 0; k < r->n_regions; k++) {
        const thx_volume_region_report *g = &r->regions[k];
        cJSON *go = cJSON_CreateObject();
        cJSON_AddStringToObject(go, "name", g->name);
        add_count(go, "tetrahedra", g->n_tets);
        add_num(go, "volume", g->volume);
        add_num(go, "expected", g->expected);
        cJSON_AddStringToObject(go, "definition", g->definition);
        add_num(go, "rel_diff", g->rel_diff);
        cJSON_AddBoolToObject(go, "ok", g->ok);
        if (g->cell >= -1) {
            char cn[96];
            if (g->cell >= 0 && (size_t)g->cell < r->n_surface_reports)
                snprintf(cn, sizeof cn, "inside %s", r->surfaces[g->cell].name);
            else
                snprintf(cn, sizeof cn, "outside every surface");
            cJSON_AddStringToObject(go, "cell", cn);
        } else {
            cJSON_AddNullToObject(go, "cell");
        }
        add_count(go, "outside_region", g->n_outside);
        if (g->n_outside) add_count(go, "first_outside_tetrahedron", g->ex_outside + 1);
        cJSON_AddItemToArray(rg, go);
    }
    add_num(o, "region_tolerance", r->region_volume_tol);

    cJSON *nt = cJSON_AddObjectToObject(o, "node_tables");
    cJSON_AddBoolToObject(nt, "checked", r->node_tables_checked);
    add_count(nt, "surfaces", r->n_table_surfaces);
    add_count(nt, "size_errors", r->n_table_size_errors);
    add_count(nt, "bad_entries", r->n_table_bad_entries);
    add_count(nt, "coordinate_mismatches", r->n_table_mismatches);
    add_count(nt, "backlink_errors", r->n_table_backlink_errors);
    add_num(nt, "max_distance", r->table_max_distance);
    add_num(nt, "tolerance", r->node_tol);
    cJSON *nf = cJSON_AddObjectToObject(nt, "first");
    if (r->n_table_bad_entries || r->n_table_mismatches) {
        add_count(nf, "surface", r->ex_table_surface + 1);
        add_count(nf, "surface_node", r->ex_table_node + 1);
    }
    if (r->n_table_backlink_errors) add_count(nf, "backlink_volume_node", (size_t)r->ex_backlink_node + 1);
    add_count(nt, "steiner_nodes", r->n_steiner);
    add_count(nt, "steiner_bad", r->n_steiner_bad);
    add_count(nt, "steiner_mismatches", r->n_steiner_mismatches);
    add_num(nt, "steiner_max_distance", r->steiner_max_distance);
    if (r->n_steiner_bad || r->n_steiner_mismatches) add_count(nf, "steiner_record", r->ex_steiner + 1);

    cJSON *q = cJSON_AddObjectToObject(o, "quality");
    add_num(q, "min_dihedral_deg", r->min_dihedral);
    if (isfinite(r->min_dihedral)) add_count(q, "min_dihedral_tetrahedron", r->min_dihedral_tet + 1);
    add_num(q, "max_dihedral_deg", r->max_dihedral);
    if (isfinite(r->max_dihedral)) add_count(q, "max_dihedral_tetrahedron", r->max_dihedral_tet + 1);
    add_num(q, "min_edge", r->min_edge);
    add_num(q, "max_edge", r->max_edge);
    cJSON *dj = cJSON_AddObjectToObject(q, "dihedral");
    cJSON_AddStringToObject(dj, "definition",
                            "smallest dihedral angle of each tetrahedron, degrees; regular 70.53; flat 0");
    add_hist(dj, thx_vcheck_dihedral_edges, r->dihedral_hist, THX_VCHECK_DIHEDRAL_BINS);
    add_worst(dj, r->worst_dihedral, r->n_worst_dihedral);
    cJSON *rj = cJSON_AddObjectToObject(q, "radius_edge");
    cJSON_AddStringToObject(rj, "definition",
                            "circumradius / shortest edge; regular sqrt(6)/4 = 0.612; null = infinite (flat)");
    add_num(rj, "max", r->max_radius_edge);
    if (r->max_radius_edge == r->max_radius_edge) add_count(rj, "max_tetrahedron", r->max_radius_edge_tet + 1);
    add_num(rj, "mean", r->mean_radius_edge);
    add_hist(rj, thx_vcheck_radius_edge_edges, r->radius_edge_hist, THX_VCHECK_RADIUS_EDGE_BINS);
    add_worst(rj, r->worst_radius_edge, r->n_worst_radius_edge);
    cJSON *rr = cJSON_AddObjectToObject(q, "radius_ratio");
    cJSON_AddStringToObject(rr, "definition", "3 inradius / circumradius; regular 1; flat 0");
    add_num(rr, "min", r->min_radius_ratio);
    if (r->min_radius_ratio == r->min_radius_ratio) add_count(rr, "min_tetrahedron", r->min_radius_ratio_tet + 1);
    add_num(rr, "mean", r->mean_radius_ratio);
    add_num(q, "min_dihedral_limit", r->min_dihedral_opt);
    add_num(q, "max_radius_edge_limit", r->max_radius_edge_opt);

    if (!fl || !rs || !va || !vf || !co || !cf || !ct || !tf || !cv || !csf || !rcl || !vo || !rg || !nt || !nf || !q ||
        !dj || !rj || !rr) {
        cJSON_Delete(o);
        goto nomem;
    }
    return o;
nomem:
    thx_error(ctx, THX_ENOMEM, "out of memory building the volume check report");
    return NULL;
}
