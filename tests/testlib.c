#define _POSIX_C_SOURCE 200809L
#include "testlib.h"
#include "thorax/geom/surfaces.h"
#include "thorax/phantom/phantom.h"

#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "thorax/core/fileio.h"
int tl_pass, tl_fail;

void tl_report_fail(const char *file, int line, const char *what)
{
    fprintf(stderr, "%s:%d: check failed: %s\n", file, line, what);
}

int tl_finish(void)
{
    printf("%d passed, %d failed\n", tl_pass, tl_fail);
    return tl_fail ? 1 : (tl_pass ? 0 : 1); /* a test that checked nothing fails */
}

char tl_scratch[1024];

int tl_scratch_make(const char *name)
{
    snprintf(tl_scratch, sizeof tl_scratch, "%s.XXXXXX", name);
    if (!mkdtemp(tl_scratch)) {
        perror("mkdtemp");
        return -1;
    }
    return 0;
}

int tl_scratch_finish(const char *name)
{
    int rc = tl_finish();
    if (rc == 0) {
        char cmd[1200];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", tl_scratch);
        if (system(cmd) != 0) fprintf(stderr, "%s: could not remove %s\n", name, tl_scratch);
    } else {
        fprintf(stderr, "%s: files kept in %s\n", name, tl_scratch);
    }
    return rc;
}

const char *tl_path(const char *file)
{
    static char buf[8][2048];
    static int k;
    k = (k + 1) % 8;
    snprintf(buf[k], sizeof buf[k], "%s/%s", tl_scratch, file);
    return buf[k];
}

const char *tl_src_path(const char *here, const char *rel)
{
    static char buf[8][4096];
    static int k;
    k = (k + 1) % 8;
    const char *slash = strrchr(here, '/');
    if (slash) snprintf(buf[k], sizeof buf[k], "%.*s/%s", (int)(slash - here), here, rel);
    else snprintf(buf[k], sizeof buf[k], "./%s", rel);
    return buf[k];
}

void tl_write_bytes(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(data, 1, n, f) != n) {
        fprintf(stderr, "cannot write %s\n", path);
        exit(1);
    }
    fclose(f);
}

void tl_write_text(const char *path, const char *text) { tl_write_bytes(path, text, strlen(text)); }

char *tl_slurp(thx_ctx *ctx, const char *path, size_t *len)
{
    char *t = NULL;
    if (thx_read_file(ctx, path, &t, len) != THX_OK) return NULL;
    return t;
}

int tl_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

int tl_leftover_tmp(const char *prefix)
{
    DIR *d = opendir(tl_scratch);
    int found = 0;
    struct dirent *e;
    while (d && (e = readdir(d)))
        if (strncmp(e->d_name, prefix, strlen(prefix)) == 0 && (strstr(e->d_name, ".tmp") || strstr(e->d_name, ".old"))) {
            fprintf(stderr, "leftover temporary %s/%s\n", tl_scratch, e->d_name);
            found = 1;
        }
    if (d) closedir(d);
    return found;
}

int tl_msg_has(thx_ctx *ctx, const char *needle)
{
    const char *m = thx_ctx_message(ctx);
    if (strstr(m, needle)) return 1;
    fprintf(stderr, "  message \"%s\" lacks \"%s\"\n", m, needle);
    return 0;
}

struct thx_model *tl_phantom_surfaces(thx_ctx *ctx)
{
    thx_phantom_opts po;
    thx_phantom_opts_default(&po);
    thx_contours *c = NULL;
    CHECK_OK(ctx, thx_phantom_contours(ctx, &po, &c));
    thx_surfaces_opts so;
    thx_surfaces_opts_default(&so);
    thx_model *m = NULL;
    if (c) CHECK_OK(ctx, thx_surfaces_build(ctx, c, &so, &m, NULL, NULL));
    thx_contours_destroy(&c);
    return m;
}
