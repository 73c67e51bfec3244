/*
 * Numbered map3d .pot files read as one series, one frame per file
 * (series.c dispatches here; docs/formats.md, "Numbered .pot files").
 *
 * The set is named by a pattern with one printf-style number, "dipole2_%03d.pot"
 * ("%d", "%Nd" or "%0Nd"), or by a directory holding the files. Every file of
 * the directory that the pattern matches is a frame, in the order of its
 * number; the numbers must follow each other (a gap, or two files with the
 * same number, is an error naming them). With "%0Nd" a match has exactly N
 * digits. A directory's .pot files must all be NAME + digits + ".pot" with one
 * NAME. Every file must have the same number of values.
 */
#include "thorax/io/series_file.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "io/series/series_impl.h"

typedef struct {
    unsigned long long num;
    char name[256];
} pot_entry;

static int by_num(const void *a, const void *b)
{
    const pot_entry *x = a, *y = b;
    return x->num < y->num ? -1 : x->num > y->num;
}

/* Splits a base name with one %d / %Nd / %0Nd into prefix, suffix and the exact width (0: any). */
static int parse_pattern(const char *base, char *pre, char *suf, size_t cap, int *width)
{
    const char *pc = strchr(base, '%');
    if (!pc || strchr(pc + 1, '%')) return -1;
    const char *q = pc + 1;
    int zero = *q == '0';
    int w = 0;
    while (isdigit((unsigned char)*q)) w = w * 10 + (*q++ - '0');
    if (*q != 'd' || w > 20) return -1;
    size_t np = (size_t)(pc - base);
    if (np >= cap || strlen(q + 1) >= cap) return -1;
    memcpy(pre, base, np);
    pre[np] = '\0';
    snprintf(suf, cap, "%s", q + 1);
    *width = zero ? w : 0;
    return 0;
}

/* The number in name = pre + digits + suf, or -1. */
static int match(const char *name, const char *pre, const char *suf, int width, unsigned long long *num)
{
    size_t n = strlen(name), np = strlen(pre), ns = strlen(suf);
    if (n <= np + ns || strncmp(name, pre, np) || strcmp(name + n - ns, suf)) return -1;
    size_t nd = n - np - ns;
    if (nd > 18 || (width && nd != (size_t)width)) return -1;
    unsigned long long v = 0;
    for (size_t i = 0; i < nd; i++) {
        if (!isdigit((unsigned char)name[np + i])) return -1;
        v = v * 10 + (unsigned long long)(name[np + i] - '0');
    }
    *num = v;
    return 0;
}

thx_status series_read_pot_set(thx_ctx *ctx, const char *path, thx_series **out)
{
    *out = NULL;
    char dir[4096], pre[256], suf[256];
    int width = 0;
    struct stat sb;
    int is_dir = stat(path, &sb) == 0 && S_ISDIR(sb.st_mode);
    if (strlen(path) >= sizeof dir) return thx_error(ctx, THX_EIO, "%s: path too long", path);
    snprintf(dir, sizeof dir, "%s", path);
    if (!is_dir) {
        char *slash = strrchr(dir, '/');
        const char *base = slash ? slash + 1 : dir;
        if (parse_pattern(base, pre, suf, sizeof pre, &width) != 0)
            return thx_error(ctx, THX_EINPUT, "%s: a set of .pot files is named by one number pattern (%%d, %%3d or "
                                              "%%03d: 'dipole2_%%03d.pot') or a directory", path);
        if (slash) *slash = '\0';
        else snprintf(dir, sizeof dir, ".");
    }
    DIR *d = opendir(dir);
    if (!d) return thx_error(ctx, THX_EIO, "%s: cannot open the directory %s: %s", path, dir, strerror(errno));
    pot_entry *e = NULL;
    size_t n = 0, cap = 0;
    thx_status st = THX_OK;
    struct dirent *de;
    while (st == THX_OK && (de = readdir(d))) {
        const char *nm = de->d_name;
        size_t L = strlen(nm);
        if (L >= sizeof e->name) continue;
        unsigned long long num;
        if (is_dir) {
            if (L < 5 || strcasecmp(nm + L - 4, ".pot")) continue;
            size_t k = L - 4;
            while (k && isdigit((unsigned char)nm[k - 1])) k--;
            if (k == L - 4 || L - 4 - k > 18) {
                st = thx_error(ctx, THX_EINPUT, "%s: %s is not NAME + number + .pot", path, nm);
                break;
            }
            if (n == 0) {
                memcpy(pre, nm, k);
                pre[k] = '\0';
                snprintf(suf, sizeof suf, "%s", nm + L - 4);
            } else if (strncmp(nm, pre, k) || strlen(pre) != k || strcmp(nm + L - 4, suf)) {
                st = thx_error(ctx, THX_EINPUT, "%s: the directory holds .pot files of several names (%s..., %s): name "
                                                "the set by a pattern", path, pre, nm);
                break;
            }
            num = 0;
            for (size_t i = k; i < L - 4; i++) num = num * 10 + (unsigned long long)(nm[i] - '0');
        } else if (match(nm, pre, suf, width, &num) != 0) {
            continue;
        }
        if (n == cap) {
            size_t nc = cap ? 2 * cap : 64;
            pot_entry *w = thx_realloc(ctx, e, nc * sizeof *e);
            if (!w) { st = THX_ENOMEM; break; }
            e = w, cap = nc;
        }
        e[n].num = num;
        snprintf(e[n].name, sizeof e[n].name, "%s", nm);
        n++;
    }
    closedir(d);
    if (st == THX_OK && n == 0) st = thx_error(ctx, THX_EINPUT, "%s: no file matches (in %s)", path, dir);
    if (st == THX_OK) qsort(e, n, sizeof *e, by_num);
    for (size_t k = 1; st == THX_OK && k < n; k++) {
        if (e[k].num == e[k - 1].num)
            st = thx_error(ctx, THX_EINPUT, "%s: %s and %s have the same number %llu", path, e[k - 1].name, e[k].name, e[k].num);
        else if (e[k].num != e[k - 1].num + 1)
            st = thx_error(ctx, THX_EINPUT, "%s: the numbers jump from %llu (%s) to %llu (%s): frame%s missing", path,
                           e[k - 1].num, e[k - 1].name, e[k].num, e[k].name, e[k].num - e[k - 1].num > 2 ? "s" : "");
    }
    thx_series *s = NULL;
    for (size_t k = 0; st == THX_OK && k < n; k++) {
        char fp[8192];
        snprintf(fp, sizeof fp, "%s/%s", dir, e[k].name);
        thx_series *one = NULL;
        st = series_read_pot(ctx, fp, &one);
        if (st == THX_OK && !s) {
            st = thx_series_create(ctx, one->n_rows, n, &s);
            if (st == THX_OK) {
                snprintf(s->label, sizeof s->label, "map3d .pot set %.60s%s..%s", pre, e[0].name + strlen(pre), e[n - 1].name + strlen(pre));
                snprintf(s->time_unit, sizeof s->time_unit, "frame");
            }
        }
        if (st == THX_OK && one->n_rows != s->n_rows)
            st = thx_error(ctx, THX_EINPUT, "%s: %zu values, but %s has %zu (every frame needs one value per node)", fp,
                           one->n_rows, e[0].name, s->n_rows);
        if (st == THX_OK) memcpy(s->v + k * s->n_rows, one->v, s->n_rows * sizeof *s->v);
        thx_series_destroy(&one);
    }
    free(e);
    if (st != THX_OK) {
        thx_series_destroy(&s);
        return st;
    }
    *out = s;
    return THX_OK;
}
