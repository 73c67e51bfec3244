/* Inputs of the boundary-element solver: OpenMEEG's .geom/.cond pair, dipole files, and the
 * conductivities of a meshed model's compartments (thorax/bem/bem.h). */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "thorax/bem/bem.h"
#include "thorax/io/surface_read.h"
#include "thorax/mesh/mesh.h"

#define MAX_IF 64

static char *trim(char *s)
{
    while (isspace((unsigned char)*s)) s++;
    size_t n = strlen(s);
    while (n && isspace((unsigned char)s[n - 1])) s[--n] = '\0';
    return s;
}

thx_status thx_bem_read_dipoles(thx_ctx *ctx, const char *path, double **pos, double **mom, size_t *n)
{
    *pos = *mom = NULL;
    *n = 0;
    FILE *f = fopen(path, "r");
    if (!f) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    thx_status st = THX_OK;
    size_t cap = 0;
    char line[4096];
    int ln = 0;
    while (fgets(line, sizeof line, f)) {
        ln++;
        char *h = strchr(line, '#');
        if (h) *h = '\0';
        char *s = trim(line);
        if (!*s) continue;
        double v[6];
        char *e = s;
        int k = 0;
        for (; k < 6; k++) {
            char *q;
            errno = 0;
            v[k] = strtod(e, &q);
            if (q == e) break;
            if (!isfinite(v[k])) { st = thx_error(ctx, THX_EINPUT, "%s:%d: value %d is not finite", path, ln, k + 1); goto done; }
            e = q;
        }
        if (k < 6 || *trim(e)) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: dipole %zu: expected 6 numbers 'px py pz qx qy qz'", path, ln, *n + 1);
            goto done;
        }
        if (*n + 1 > cap) {
            size_t c2 = cap;
            THX_TRY(thx_grow(ctx, (void **)pos, &c2, *n + 1, 3 * sizeof **pos));
            c2 = cap;
            THX_TRY(thx_grow(ctx, (void **)mom, &c2, *n + 1, 3 * sizeof **mom));
            cap = c2;
        }
        memcpy(*pos + 3 * *n, v, 3 * sizeof *v);
        memcpy(*mom + 3 * *n, v + 3, 3 * sizeof *v);
        (*n)++;
    }
    if (ferror(f)) st = thx_error(ctx, THX_EIO, "%s: read error", path);
    else if (*n == 0) st = thx_error(ctx, THX_EINPUT, "%s: no dipole", path);
done:
    fclose(f);
    if (st != THX_OK) {
        free(*pos);
        free(*mom);
        *pos = *mom = NULL;
        *n = 0;
    }
    return st;
}

thx_status thx_bem_read_openmeeg(thx_ctx *ctx, const char *geom, const char *cond, thx_model **mout, double **sig_out)
{
    *mout = NULL;
    *sig_out = NULL;
    char files[MAX_IF][512];
    char dname[MAX_IF][64];
    int dif[MAX_IF][MAX_IF], dn[MAX_IF];
    double dsig[MAX_IF];
    size_t nif = 0, ndom = 0, want_if = 0, want_dom = 0;
    thx_status st = THX_OK;
    thx_model *m = NULL;
    double *sig = NULL;
    char line[4096];
    int ln = 0;
    FILE *f = fopen(geom, "r");
    if (!f) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", geom, strerror(errno));
    while (fgets(line, sizeof line, f)) {
        ln++;
        char *s = trim(line);
        if (!*s) continue;
        if (*s == '#') {
            if (ln == 1 && !strstr(s, "Domain Description 1.1")) {
                st = thx_error(ctx, THX_EINPUT, "%s:1: not an OpenMEEG geometry 1.1 ('# Domain Description 1.1')", geom);
                break;
            }
            continue;
        }
        if (!strncmp(s, "Interfaces", 10)) {
            want_if = strtoul(s + 10, NULL, 10);
            if (want_if == 0 || want_if > MAX_IF) { st = thx_error(ctx, THX_EINPUT, "%s:%d: interface count 1..%d", geom, ln, MAX_IF); break; }
        } else if (!strncmp(s, "Interface:", 10)) {
            char *a = strchr(s, '"'), *b = a ? strchr(a + 1, '"') : NULL;
            if (!a || !b || nif >= want_if) { st = thx_error(ctx, THX_EINPUT, "%s:%d: expected Interface: \"FILE.tri\" (%zu declared)", geom, ln, want_if); break; }
            *b = '\0';
            const char *sl = strrchr(geom, '/');
            if (a[1] == '/' || !sl) snprintf(files[nif], sizeof files[nif], "%s", a + 1);
            else snprintf(files[nif], sizeof files[nif], "%.*s/%s", (int)(sl - geom), geom, a + 1);
            nif++;
        } else if (!strncmp(s, "Domains", 7)) {
            want_dom = strtoul(s + 7, NULL, 10);
            if (want_dom == 0 || want_dom > MAX_IF) { st = thx_error(ctx, THX_EINPUT, "%s:%d: domain count 1..%d", geom, ln, MAX_IF); break; }
        } else if (!strncmp(s, "Domain", 6)) {
            char *p = trim(s + 6), *c = strchr(p, ':');
            if (!c || ndom >= want_dom) { st = thx_error(ctx, THX_EINPUT, "%s:%d: expected 'Domain NAME: i -j' (%zu declared)", geom, ln, want_dom); break; }
            *c = '\0';
            snprintf(dname[ndom], sizeof dname[ndom], "%s", trim(p));
            dn[ndom] = 0;
            char *q = c + 1;
            for (;;) {
                char *e;
                long v = strtol(q, &e, 10);
                if (e == q) break;
                if (v == 0 || labs(v) > (long)want_if || dn[ndom] >= MAX_IF) { st = thx_error(ctx, THX_EINPUT, "%s:%d: domain '%s': interface %ld out of range", geom, ln, dname[ndom], v); break; }
                dif[ndom][dn[ndom]++] = (int)v;
                q = e;
            }
            if (st != THX_OK) break;
            if (*trim(q)) { st = thx_error(ctx, THX_EINPUT, "%s:%d: domain '%s': '%s' is not an interface number", geom, ln, dname[ndom], trim(q)); break; }
            dsig[ndom] = NAN;
            ndom++;
        } else {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: unknown line '%.40s' (MeshFile and named interfaces of geometry 1.1 are not supported)", geom, ln, s);
            break;
        }
    }
    fclose(f);
    if (st == THX_OK && (nif != want_if || ndom != want_dom || nif == 0))
        st = thx_error(ctx, THX_EINPUT, "%s: %zu of %zu interfaces and %zu of %zu domains given", geom, nif, want_if, ndom, want_dom);
    if (st != THX_OK) return st;
    /* conductivities by domain name */
    f = fopen(cond, "r");
    if (!f) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", cond, strerror(errno));
    ln = 0;
    while (fgets(line, sizeof line, f)) {
        ln++;
        char *s = trim(line);
        if (!*s || *s == '#') continue;
        char name[64];
        double v;
        char extra[8];
        if (sscanf(s, "%63s %lf %7s", name, &v, extra) != 2 || !isfinite(v) || v < 0) {
            st = thx_error(ctx, THX_EINPUT, "%s:%d: expected 'DOMAIN CONDUCTIVITY' (a number >= 0)", cond, ln);
            break;
        }
        if (v != 0 && !(v >= THX_SIGMA_MIN && v <= THX_SIGMA_MAX)) { /* thorax sigma's bounds (thorax/mesh/mesh.h) */
            st = thx_error(ctx, THX_EINPUT, "%s:%d: domain '%s': conductivity %g is outside %g..%g (or 0, an insulator)",
                           cond, ln, name, v, THX_SIGMA_MIN, THX_SIGMA_MAX);
            break;
        }
        size_t d = 0;
        while (d < ndom && strcmp(dname[d], name)) d++;
        if (d == ndom) { st = thx_error(ctx, THX_EINPUT, "%s:%d: domain '%s' is not in %s", cond, ln, name, geom); break; }
        dsig[d] = v;
    }
    fclose(f);
    if (st != THX_OK) return st;
    sig = thx_malloc(ctx, nif * sizeof *sig);
    if (!sig) return THX_ENOMEM;
    /* sigma inside interface i: the domain that lists -i */
    for (size_t i = 0; i < nif && st == THX_OK; i++) {
        int found = -1;
        for (size_t d = 0; d < ndom; d++)
            for (int k = 0; k < dn[d]; k++)
                if (dif[d][k] == -(int)(i + 1)) found = (int)d;
        if (found < 0) st = thx_error(ctx, THX_EINPUT, "%s: no domain is inside interface %zu ('%s')", geom, i + 1, files[i]);
        else if (isnan(dsig[found])) st = thx_error(ctx, THX_EINPUT, "%s: domain '%s' has no conductivity", cond, dname[found]);
        else sig[i] = dsig[found];
    }
    if (st == THX_OK) st = thx_model_create(ctx, &m);
    for (size_t i = 0; i < nif && st == THX_OK; i++) {
        thx_surface *s = NULL;
        const char *base = strrchr(files[i], '/');
        char name[64];
        snprintf(name, sizeof name, "%s", base ? base + 1 : files[i]);
        char *dot = strchr(name, '.');
        if (dot) *dot = '\0';
        st = thx_surface_read_file(ctx, files[i], NULL, THX_IMPORT_AUTO, name, THX_ROLE_OTHER, &s, NULL);
        if (st == THX_OK) st = thx_model_add_surface(ctx, m, &s);
    }
    /* the outermost surface: the one whose outside has conductivity 0 (listed +i by a domain of 0) */
    if (st == THX_OK) {
        double big = -1;
        size_t o = 0;
        for (size_t i = 0; i < nif; i++) {
            double v = fabs(thx_surface_volume(m->surf[i]));
            if (v > big) { big = v; o = i; }
        }
        m->surf[o]->role = THX_ROLE_OUTER;
    }
    if (st != THX_OK) {
        thx_model_destroy(&m);
        free(sig);
        return st;
    }
    *mout = m;
    *sig_out = sig;
    return THX_OK;
}

thx_status thx_bem_sigma_from_volume(thx_ctx *ctx, const thx_model *m, const char *where, double *sigma_in)
{
    const thx_volume *v = m->volume;
    if (!v) return thx_error(ctx, THX_EINPUT, "%s: the model has no volume mesh to take conductivities from", where);
    thx_status st = THX_OK;
    /* tetrahedra at each volume node: counts, then lists */
    size_t *start = thx_calloc(ctx, v->n_nodes + 1, sizeof *start);
    int32_t *list = thx_malloc(ctx, (v->n_tets ? 4 * v->n_tets : 1) * sizeof *list);
    size_t *votes = thx_calloc(ctx, v->n_regions ? v->n_regions : 1, sizeof *votes);
    double *nrm = NULL;
    if (!start || !list || !votes) { st = THX_ENOMEM; goto done; }
    for (size_t t = 0; t < 4 * v->n_tets; t++) start[v->tet[t] + 1]++;
    for (size_t i = 0; i < v->n_nodes; i++) start[i + 1] += start[i];
    {
        size_t *fill = thx_malloc(ctx, (v->n_nodes ? v->n_nodes : 1) * sizeof *fill);
        if (!fill) { st = THX_ENOMEM; goto done; }
        memcpy(fill, start, v->n_nodes * sizeof *fill);
        for (size_t t = 0; t < v->n_tets; t++)
            for (int k = 0; k < 4; k++) list[fill[v->tet[4 * t + (size_t)k]]++] = (int32_t)t;
        free(fill);
    }
    for (size_t s = 0; s < m->n_surfaces && st == THX_OK; s++) {
        const thx_surface *S = m->surf[s];
        memset(votes, 0, v->n_regions * sizeof *votes);
        nrm = thx_calloc(ctx, 3 * S->n_nodes, sizeof *nrm);
        if (!nrm) { st = THX_ENOMEM; goto done; }
        thx_surface_normal_sums(S, nrm); /* area-weighted node normals */
        for (size_t i = 0; i < S->n_nodes; i++) {
            int32_t vn = v->surf_node[s][i];
            const double *p = v->xyz + 3 * (size_t)vn;
            for (size_t k = start[vn]; k < start[vn + 1]; k++) {
                const int32_t *tt = v->tet + 4 * (size_t)list[k];
                double c[3] = {0, 0, 0};
                for (int q = 0; q < 4; q++)
                    for (int a = 0; a < 3; a++) c[a] += 0.25 * v->xyz[3 * (size_t)tt[q] + (size_t)a];
                double dd = (c[0] - p[0]) * nrm[3 * i] + (c[1] - p[1]) * nrm[3 * i + 1] + (c[2] - p[2]) * nrm[3 * i + 2];
                if (dd < 0) votes[v->region[list[k]]]++;
            }
        }
        free(nrm);
        nrm = NULL;
        size_t best = 0, total = 0;
        for (size_t r = 0; r < v->n_regions; r++) {
            total += votes[r];
            if (votes[r] > votes[best]) best = r;
        }
        if (total == 0) { sigma_in[s] = 0; continue; }
        if (v->regions[best].anisotropic) {
            st = thx_error(ctx, THX_EINPUT, "%s: region '%s' inside surface '%s' is anisotropic; the boundary elements need "
                           "one conductivity a compartment", where, v->regions[best].name, S->name);
            break;
        }
        sigma_in[s] = v->regions[best].sigma[0];
    }
done:
    free(start);
    free(list);
    free(votes);
    free(nrm);
    return st;
}
