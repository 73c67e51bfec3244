/* Atomic file and directory output (see thorax/fileio.h). */
#include "thorax/fileio.h"

#include <dirent.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

thx_status thx_atomic_open(thx_ctx *ctx, const char *path, thx_atomic_file *af)
{
    memset(af, 0, sizeof *af);
    if (strlen(path) >= sizeof af->path) return thx_error(ctx, THX_EIO, "%s: path too long", path);
    snprintf(af->path, sizeof af->path, "%s", path);
    snprintf(af->tmp, sizeof af->tmp, "%s.tmpXXXXXX", path);
    int fd = mkstemp(af->tmp);
    if (fd < 0) {
        af->tmp[0] = '\0';
        return thx_error(ctx, THX_EIO, "%s: cannot create: %s", path, strerror(errno));
    }
    fchmod(fd, 0644);
    af->f = fdopen(fd, "w");
    if (!af->f) {
        close(fd);
        unlink(af->tmp);
        af->tmp[0] = '\0';
        return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    }
    return THX_OK;
}

thx_status thx_atomic_commit(thx_ctx *ctx, thx_atomic_file *af)
{
    int bad = ferror(af->f);
    if (fclose(af->f) != 0) bad = 1;
    af->f = NULL;
    if (bad) {
        thx_atomic_abort(af);
        return thx_error(ctx, THX_EIO, "%s: write failed: %s", af->path, strerror(errno));
    }
    if (rename(af->tmp, af->path) != 0) {
        int e = errno;
        thx_atomic_abort(af);
        return thx_error(ctx, THX_EIO, "%s: cannot rename into place: %s", af->path, strerror(e));
    }
    af->tmp[0] = '\0';
    return THX_OK;
}

void thx_atomic_abort(thx_atomic_file *af)
{
    if (af->f) fclose(af->f);
    af->f = NULL;
    if (af->tmp[0]) unlink(af->tmp);
    af->tmp[0] = '\0';
}

thx_status thx_tmpdir_create(thx_ctx *ctx, const char *final_dir, char *tmp, size_t tmp_size)
{
    size_t n = strlen(final_dir);
    while (n > 1 && final_dir[n - 1] == '/') n--;
    if ((size_t)snprintf(tmp, tmp_size, "%.*s.tmpXXXXXX", (int)n, final_dir) >= tmp_size)
        return thx_error(ctx, THX_EIO, "%s: path too long", final_dir);
    if (!mkdtemp(tmp)) return thx_error(ctx, THX_EIO, "%s: cannot create a temporary directory: %s", final_dir, strerror(errno));
    chmod(tmp, 0755);
    return THX_OK;
}

static void remove_tree(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return;
    struct dirent *e;
    char p[4096];
    while ((e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        struct stat st;
        if (lstat(p, &st) == 0 && S_ISDIR(st.st_mode)) remove_tree(p);
        else unlink(p);
    }
    closedir(d);
    rmdir(dir);
}

thx_status thx_tmpdir_commit(thx_ctx *ctx, const char *tmp, const char *final_dir)
{
    struct stat st;
    if (stat(final_dir, &st) == 0) {
        if (!S_ISDIR(st.st_mode)) {
            remove_tree(tmp);
            return thx_error(ctx, THX_EIO, "%s: exists and is not a directory", final_dir);
        }
        /* Move the old directory aside first so the swap leaves no mixture. */
        char old[4200];
        snprintf(old, sizeof old, "%s.oldXXXXXX", tmp);
        if (!mkdtemp(old) || rmdir(old) != 0 || rename(final_dir, old) != 0) {
            remove_tree(tmp);
            return thx_error(ctx, THX_EIO, "%s: cannot replace: %s", final_dir, strerror(errno));
        }
        if (rename(tmp, final_dir) != 0) {
            int e = errno;
            rename(old, final_dir);
            remove_tree(tmp);
            return thx_error(ctx, THX_EIO, "%s: cannot rename into place: %s", final_dir, strerror(e));
        }
        remove_tree(old);
        return THX_OK;
    }
    if (rename(tmp, final_dir) != 0) {
        int e = errno;
        remove_tree(tmp);
        return thx_error(ctx, THX_EIO, "%s: cannot rename into place: %s", final_dir, strerror(e));
    }
    return THX_OK;
}

void thx_tmpdir_abort(const char *tmp) { remove_tree(tmp); }

thx_status thx_read_file(thx_ctx *ctx, const char *path, char **text, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap);
    if (!buf) { fclose(f); return thx_error(ctx, THX_ENOMEM, "%s: out of memory", path); }
    for (;;) {
        if (n + 1 >= cap) {
            char *q = realloc(buf, cap * 2);
            if (!q) { free(buf); fclose(f); return thx_error(ctx, THX_ENOMEM, "%s: out of memory", path); }
            buf = q;
            cap *= 2;
        }
        size_t got = fread(buf + n, 1, cap - n - 1, f);
        n += got;
        if (got == 0) break;
    }
    int bad = ferror(f);
    fclose(f);
    if (bad) { free(buf); return thx_error(ctx, THX_EIO, "%s: read error", path); }
    buf[n] = '\0';
    *text = buf;
    if (len) *len = n;
    return THX_OK;
}
