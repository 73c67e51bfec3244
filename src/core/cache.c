/*
 * The user's cache directory (thorax/core/cache.h): its name, its files' names, and its size kept
 * under THORAX_CACHE_MAX by removing the least recently used of thorax's own files.
 */
#include <ctype.h>
#include <errno.h>
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

#include "thorax/core/cache.h"
#include "thorax/core/fileio.h"

const char *thx_cache_dir(char *buf, size_t n)
{
    const char *d = getenv("THORAX_CACHE_DIR");
    if (d && *d) return snprintf(buf, n, "%s", d) < (int)n ? buf : NULL;
    d = getenv("XDG_CACHE_HOME");
    if (d && *d == '/') return snprintf(buf, n, "%s/thorax", d) < (int)n ? buf : NULL;
    d = getenv("HOME");
    if (d && *d == '/') return snprintf(buf, n, "%s/.cache/thorax", d) < (int)n ? buf : NULL;
    return NULL;
}

void thx_cache_path(char *buf, size_t n, const char *dir, const char *what, const unsigned char key[32])
{
    char hex[65];
    for (int i = 0; i < 32; i++) snprintf(hex + 2 * i, 3, "%02x", key[i]);
    snprintf(buf, n, "%s/%s-%s.bin", dir, what, hex);
}

int thx_cache_create(thx_cache_file *cf, const char *dir, const char *path, uint64_t bytes, const char *what, char *note,
                     size_t note_n)
{
    cf->f = NULL;
    if (bytes > thx_cache_max_bytes()) {
        snprintf(note, note_n, "%s (%.0f MB) is larger than the cache's limit (THORAX_CACHE_MAX), not kept", what,
                 (double)bytes / 1e6);
        return 0;
    }
    if (thx_make_dirs(dir)) {
        snprintf(note, note_n, "cannot create the cache directory %s", dir);
        return 0;
    }
    snprintf(cf->tmp, sizeof cf->tmp, "%s.%ld.tmp", path, (long)getpid());
    if (!(cf->f = fopen(cf->tmp, "wb"))) {
        snprintf(note, note_n, "cannot write in the cache directory %s", dir);
        return 0;
    }
    return 1;
}

void thx_cache_commit(thx_cache_file *cf, int ok, const char *dir, const char *path, const char *what, char *note,
                      size_t note_n)
{
    ok = (fclose(cf->f) == 0) && ok;
    cf->f = NULL;
    if (!ok || rename(cf->tmp, path)) {
        unlink(cf->tmp);
        snprintf(note, note_n, "cannot write %s into the cache directory %s", what, dir);
        return;
    }
    thx_cache_trim(dir, thx_cache_max_bytes(), path);
}

void thx_cache_used(const char *path)
{
    (void)utimes(path, NULL); /* a file we may not touch is simply trimmed by its older time */
}

uint64_t thx_cache_max_bytes(void)
{
    const uint64_t dflt = (uint64_t)4 << 30;
    const char *s = getenv("THORAX_CACHE_MAX");
    if (!s || !isdigit((unsigned char)*s)) return dflt; /* (strtoull would take "-1" as 2^64 - 1) */
    char *end = NULL;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (end == s || errno == ERANGE) return dflt;
    uint64_t mul = 1;
    switch (toupper((unsigned char)*end)) {
    case 'K': mul = (uint64_t)1 << 10; end++; break;
    case 'M': mul = (uint64_t)1 << 20; end++; break;
    case 'G': mul = (uint64_t)1 << 30; end++; break;
    default: break;
    }
    if (*end) return dflt;
    return v > UINT64_MAX / mul ? UINT64_MAX : (uint64_t)v * mul;
}

/* One of thorax's cache files: WHAT-<64 hex>.bin */
static int ours(const char *name)
{
    static const char *const what[] = {"ordering-", "symbolic-", "stiffness-"};
    for (size_t w = 0; w < sizeof what / sizeof *what; w++) {
        size_t k = strlen(what[w]);
        if (strncmp(name, what[w], k)) continue;
        const char *h = name + k;
        for (int i = 0; i < 64; i++)
            if (!isxdigit((unsigned char)h[i]) || isupper((unsigned char)h[i])) return 0;
        return !strcmp(h + 64, ".bin");
    }
    return 0;
}

typedef struct {
    char *path;
    uint64_t bytes;
    struct timespec used;
} entry;

static int older_first(const void *a, const void *b)
{
    const entry *x = a, *y = b;
    if (x->used.tv_sec != y->used.tv_sec) return x->used.tv_sec < y->used.tv_sec ? -1 : 1;
    if (x->used.tv_nsec != y->used.tv_nsec) return x->used.tv_nsec < y->used.tv_nsec ? -1 : 1;
    return strcmp(x->path, y->path);
}

int thx_cache_trim(const char *dir, uint64_t max_bytes, const char *keep)
{
    DIR *d = opendir(dir);
    if (!d) return 0;
    entry *e = NULL;
    size_t n = 0, cap = 0;
    uint64_t total = 0;
    struct dirent *de;
    while ((de = readdir(d))) {
        if (!ours(de->d_name)) continue;
        size_t len = strlen(dir) + strlen(de->d_name) + 2;
        char *p = malloc(len);
        if (!p) break;
        snprintf(p, len, "%s/%s", dir, de->d_name);
        struct stat st;
        if (lstat(p, &st) || !S_ISREG(st.st_mode)) { free(p); continue; }
        if (n == cap) {
            size_t c2 = cap ? 2 * cap : 32;
            entry *e2 = realloc(e, c2 * sizeof *e);
            if (!e2) { free(p); break; }
            e = e2;
            cap = c2;
        }
        e[n].path = p;
        e[n].bytes = (uint64_t)st.st_size;
        e[n].used = st.st_mtim;
        total += e[n].bytes;
        n++;
    }
    closedir(d);
    int removed = 0;
    if (total > max_bytes) {
        qsort(e, n, sizeof *e, older_first);
        for (size_t i = 0; i < n && total > max_bytes; i++) {
            if (keep && !strcmp(e[i].path, keep)) continue;
            if (!unlink(e[i].path)) {
                total -= e[i].bytes;
                removed++;
            }
        }
    }
    for (size_t i = 0; i < n; i++) free(e[i].path);
    free(e);
    return removed;
}
