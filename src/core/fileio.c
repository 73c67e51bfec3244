/* Atomic file and directory output (see thorax/core/fileio.h). */
#include "thorax/core/fileio.h"
#include "thorax/core/pages.h"
#include <cjson/cJSON.h>

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
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

/* Puts the finished file tmp at af->path: a plain rename, or under a claim (see fileio.h). */
static thx_status place(thx_ctx *ctx, thx_atomic_file *af, const char *tmp)
{
    if (!af->claimed) {
        if (rename(tmp, af->path) != 0) {
            int e = errno;
            unlink(tmp);
            return thx_error(ctx, THX_EIO, "%s: cannot rename into place: %s", af->path, strerror(e));
        }
        return THX_OK;
    }
    if (!af->existed) {
        if (link(tmp, af->path) != 0) {
            int e = errno;
            unlink(tmp);
            if (e == EEXIST)
                return thx_error(ctx, THX_EIO,
                                 "%s: another command wrote this file while this one ran; it was not replaced (nothing "
                                 "was written)",
                                 af->path);
            return thx_error(ctx, THX_EIO, "%s: cannot put the file in place: %s", af->path, strerror(e));
        }
        unlink(tmp);
        return THX_OK;
    }
    struct stat st;
    if (lstat(af->path, &st) != 0 || (unsigned long long)st.st_dev != af->dev ||
        (unsigned long long)st.st_ino != af->ino) {
        unlink(tmp);
        return thx_error(ctx, THX_EIO,
                         "%s: another command replaced or removed this file while this one ran; it was not replaced "
                         "(nothing was written)",
                         af->path);
    }
    if (rename(tmp, af->path) != 0) {
        int e = errno;
        unlink(tmp);
        return thx_error(ctx, THX_EIO, "%s: cannot rename into place: %s", af->path, strerror(e));
    }
    return THX_OK;
}

thx_status thx_atomic_commit(thx_ctx *ctx, thx_atomic_file *af)
{
    int bad = ferror(af->f);
    if (fclose(af->f) != 0) bad = 1;
    af->f = NULL;
    if (bad) {
        int e = errno;
        thx_atomic_abort(af);
        return thx_error(ctx, THX_EIO, "%s: write failed: %s", af->path, strerror(e));
    }
    thx_status st = place(ctx, af, af->tmp);
    af->tmp[0] = '\0';
    return st;
}

/* 1 if path names the same file as one of inputs (by device and inode). */
static int is_input(const struct stat *st, const char *const *inputs, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        struct stat si;
        if (inputs[i] && stat(inputs[i], &si) == 0 && si.st_dev == st->st_dev && si.st_ino == st->st_ino) return 1;
    }
    return 0;
}

thx_status thx_output_claim(thx_ctx *ctx, const char *path, const void *marker, size_t marker_len,
                            const char *const *inputs, size_t n_inputs, thx_atomic_file *af)
{
    return thx_output_claim_in(ctx, path, marker, marker_len, 4096, inputs, n_inputs, af);
}

thx_status thx_output_claim_in(thx_ctx *ctx, const char *path, const void *marker, size_t marker_len, size_t window,
                               const char *const *inputs, size_t n_inputs, thx_atomic_file *af)
{
    memset(af, 0, sizeof *af);
    if (!path[0] || strlen(path) >= sizeof af->path) return thx_error(ctx, THX_EIO, "%s: path empty or too long", path);
    snprintf(af->path, sizeof af->path, "%s", path);
    af->claimed = 1;
    struct stat st;
    if (lstat(path, &st) != 0) {
        if (errno != ENOENT) return thx_error(ctx, THX_EIO, "%s: %s", path, strerror(errno));
        return THX_OK;
    }
    if (S_ISLNK(st.st_mode))
        return thx_error(ctx, THX_EIO,
                         "%s is a symbolic link; thorax does not write through links (give the file itself): nothing was "
                         "written",
                         path);
    if (S_ISDIR(st.st_mode)) return thx_error(ctx, THX_EIO, "%s is a directory, not a file: nothing was written", path);
    if (!S_ISREG(st.st_mode)) return thx_error(ctx, THX_EIO, "%s exists and is not a regular file: nothing was written", path);
    size_t n_ctx = 0;
    const char *const *ctx_inputs = thx_ctx_inputs(ctx, &n_ctx);
    if (is_input(&st, inputs, n_inputs) || is_input(&st, ctx_inputs, n_ctx))
        return thx_error(ctx, THX_EIO,
                         "%s is an input of this command; thorax does not replace its own input: nothing was written "
                         "(give another -o)",
                         path);
    size_t got = 0;
    unsigned char *head = malloc(window ? window : 1);
    if (!head) return thx_error(ctx, THX_ENOMEM, "out of memory");
    FILE *f = fopen(path, "rb");
    if (f) {
        got = fread(head, 1, window, f);
        fclose(f);
    }
    int found = f && memmem(head, got, marker, marker_len) != NULL;
    free(head);
    /* an empty file holds nothing to lose (and is what mkstemp makes for a command to write into) */
    if (!f || (st.st_size > 0 && !found)) {
        char shown[64];
        size_t k = 0;
        for (size_t i = 0; i < marker_len && k + 1 < sizeof shown; i++) {
            unsigned char c = ((const unsigned char *)marker)[i];
            shown[k++] = (c >= 32 && c < 127) ? (char)c : '.';
        }
        shown[k] = '\0';
        return thx_error(ctx, THX_EIO,
                         "%s exists and is not thorax's own output of this kind (no \"%s\" in its first %zu bytes); "
                         "thorax replaces only what it wrote: nothing was written (remove it or give another -o)",
                         path, shown, window);
    }
    af->existed = 1;
    af->dev = (unsigned long long)st.st_dev;
    af->ino = (unsigned long long)st.st_ino;
    return THX_OK;
}

thx_status thx_output_place(thx_ctx *ctx, thx_atomic_file *af, const char *tmp) { return place(ctx, af, tmp); }

thx_status thx_atomic_open_output(thx_ctx *ctx, const char *path, const void *marker, size_t marker_len,
                                  const char *const *inputs, size_t n_inputs, thx_atomic_file *af)
{
    THX_CHECK(thx_output_claim(ctx, path, marker, marker_len, inputs, n_inputs, af));
    thx_atomic_file claim = *af;
    THX_CHECK(thx_atomic_open(ctx, path, af));
    af->claimed = claim.claimed;
    af->existed = claim.existed;
    af->dev = claim.dev;
    af->ino = claim.ino;
    return THX_OK;
}

void thx_atomic_abort(thx_atomic_file *af)
{
    if (af->f) fclose(af->f);
    af->f = NULL;
    if (af->tmp[0]) unlink(af->tmp);
    af->tmp[0] = '\0';
}

static void remove_tree(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return;
    struct dirent *e;
    char p[4400];
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

/* The file names a manifest gives: the values of "pts", "fac", "vmap", "tet", "steiner" and
 * "edit_log" (a model's edits.txt, named in its provenance) at any depth (a model) and every string
 * in a "files" object (a solution). */
static size_t manifest_files(const cJSON *j, int in_files, const char **out, size_t n, size_t cap)
{
    static const char *keys[] = {"pts", "fac", "vmap", "tet", "steiner", "edit_log"};
    for (const cJSON *c = j ? j->child : NULL; c; c = c->next) {
        if (cJSON_IsString(c) && c->valuestring) {
            int take = in_files;
            for (size_t k = 0; k < sizeof keys / sizeof *keys && !take && c->string; k++) take = !strcmp(c->string, keys[k]);
            if (take && n < cap) out[n++] = c->valuestring;
        } else if (cJSON_IsObject(c) || cJSON_IsArray(c)) {
            n = manifest_files(c, in_files || (c->string && !strcmp(c->string, "files")), out, n, cap);
        }
    }
    return n;
}

/* Is dir thorax's own output of this kind? (dir exists; lstat'ed by the caller as a directory) */
static int empty_dir(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return 0;
    struct dirent *e;
    int n = 0;
    while (!n && (e = readdir(d))) n = strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
    closedir(d);
    return !n;
}

static thx_status owned(thx_ctx *ctx, const char *dir, const char *manifest, const char *format);

/* Outputs that thorax writes inside another one, by their manifests. */
static const struct { const char *manifest, *format; } sub_outputs[] = {{"electrodes.json", "thorax-electrodes"},
                                                                        {"parts.json", "thorax-parts"}};

static thx_status owned_sub(thx_ctx *ctx, const char *dir)
{
    for (size_t k = 0; k < sizeof sub_outputs / sizeof *sub_outputs; k++) {
        char path[4500];
        struct stat st;
        if ((size_t)snprintf(path, sizeof path, "%s/%s", dir, sub_outputs[k].manifest) >= sizeof path) return THX_EIO;
        if (lstat(path, &st) == 0 && S_ISREG(st.st_mode)) return owned(ctx, dir, sub_outputs[k].manifest, sub_outputs[k].format);
    }
    return THX_EIO;
}

static thx_status owned(thx_ctx *ctx, const char *dir, const char *manifest, const char *format)
{
    if (empty_dir(dir)) return THX_OK; /* nothing to lose */
    char path[4400];
    snprintf(path, sizeof path, "%s/%s", dir, manifest);
    struct stat st;
    if (lstat(path, &st) != 0 || !S_ISREG(st.st_mode))
        return thx_error(ctx, THX_EIO,
                         "%s exists and is not a thorax output of this kind (it has no %s); thorax replaces only its "
                         "own outputs: nothing was written (give another -o, or empty it yourself)",
                         dir, manifest);
    if (st.st_size > (64 << 20))
        return thx_error(ctx, THX_EIO, "%s: %s is larger than any manifest thorax writes; nothing was written", dir, manifest);
    char *text = NULL;
    THX_CHECK(thx_read_file(ctx, path, &text, NULL));
    cJSON *root = cJSON_Parse(text);
    free(text);
    const cJSON *fmt = root ? cJSON_GetObjectItemCaseSensitive(root, "format") : NULL;
    if (!cJSON_IsString(fmt) || strcmp(fmt->valuestring, format) != 0) {
        thx_status st2 = thx_error(ctx, THX_EIO,
                                   "%s holds a %s that is not a thorax output of this kind (%s%s%s; this command writes "
                                   "\"format\": \"%s\"): nothing was written",
                                   dir, manifest, !root ? "not JSON" : cJSON_IsString(fmt) ? "\"format\": \"" : "no \"format\"",
                                   cJSON_IsString(fmt) ? fmt->valuestring : "", cJSON_IsString(fmt) ? "\"" : "", format);
        cJSON_Delete(root);
        return st2;
    }
    size_t cap = 4096;
    const char **names = malloc(cap * sizeof *names);
    if (!names) { cJSON_Delete(root); return thx_error(ctx, THX_ENOMEM, "%s: out of memory", path); }
    size_t nn = manifest_files(root, 0, names, 0, cap);
    DIR *d = opendir(dir);
    if (!d) {
        free(names);
        cJSON_Delete(root);
        return thx_error(ctx, THX_EIO, "%s: cannot read: %s", dir, strerror(errno));
    }
    thx_status rs = THX_OK;
    struct dirent *e;
    while (rs == THX_OK && (e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..") || !strcmp(e->d_name, manifest)) continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        const char *what = NULL;
        if (lstat(path, &st) != 0) what = "an entry it cannot examine";
        else if (S_ISLNK(st.st_mode)) what = "a symbolic link";
        else if (S_ISDIR(st.st_mode)) {
            /* a folder thorax wrote into the output, with its own manifest (the electrodes thorax
               electrodes puts into a model by default): thorax's own too */
            thx_status sub = owned_sub(ctx, path);
            if (sub != THX_OK) thx_ctx_clear(ctx);
            what = sub == THX_OK ? NULL : "a folder";
        }
        else if (!S_ISREG(st.st_mode)) what = "a special file";
        else {
            int listed = 0;
            for (size_t i = 0; i < nn && !listed; i++) listed = strcmp(names[i], e->d_name) == 0;
            if (!listed) what = "a file its manifest does not name";
        }
        if (what)
            rs = thx_error(ctx, THX_EIO,
                           "%s is a thorax output but also holds \"%s\", %s; thorax does not replace what it did not "
                           "write: nothing was written",
                           dir, e->d_name, what);
    }
    closedir(d);
    free(names);
    cJSON_Delete(root);
    return rs;
}

/* Is `path` (a file or directory that exists) dir itself or inside it? Both resolved. */
static int inside_dir(const char *path, const char *dir_real)
{
    char r[PATH_MAX];
    if (!realpath(path, r)) return 0;
    size_t n = strlen(dir_real);
    return strncmp(r, dir_real, n) == 0 && (r[n] == '\0' || r[n] == '/');
}

thx_status thx_outdir_claim(thx_ctx *ctx, thx_outdir *od, const char *dir, const char *manifest, const char *format,
                            const char *const *inputs, size_t n_inputs)
{
    memset(od, 0, sizeof *od);
    size_t n = strlen(dir);
    while (n > 1 && dir[n - 1] == '/') n--;
    if (n == 0 || n >= sizeof od->dir - 16) return thx_error(ctx, THX_EIO, "%s: path empty or too long", dir);
    memcpy(od->dir, dir, n);
    od->dir[n] = '\0';
    od->manifest = manifest;
    od->format = format;
    struct stat st;
    if (lstat(od->dir, &st) != 0) {
        if (errno != ENOENT) return thx_error(ctx, THX_EIO, "%s: %s", od->dir, strerror(errno));
        return THX_OK; /* absent: created at commit */
    }
    if (S_ISLNK(st.st_mode))
        return thx_error(ctx, THX_EIO,
                         "%s is a symbolic link; thorax does not write through links (give the directory itself): nothing "
                         "was written",
                         od->dir);
    if (!S_ISDIR(st.st_mode)) return thx_error(ctx, THX_EIO, "%s exists and is not a directory: nothing was written", od->dir);
    char real[PATH_MAX];
    if (!realpath(od->dir, real)) return thx_error(ctx, THX_EIO, "%s: %s", od->dir, strerror(errno));
    for (size_t i = 0; i < n_inputs; i++)
        if (inputs[i] && inside_dir(inputs[i], real))
            return thx_error(ctx, THX_EIO,
                             "%s holds %s, an input of this command; thorax does not replace its own input: nothing was "
                             "written (give another -o)",
                             od->dir, inputs[i]);
    THX_CHECK(owned(ctx, od->dir, manifest, format));
    od->existed = 1;
    od->dev = (unsigned long long)st.st_dev;
    od->ino = (unsigned long long)st.st_ino;
    return THX_OK;
}

thx_status thx_outdir_begin(thx_ctx *ctx, thx_outdir *od)
{
    if ((size_t)snprintf(od->tmp, sizeof od->tmp, "%s.tmpXXXXXX", od->dir) >= sizeof od->tmp) {
        od->tmp[0] = '\0';
        return thx_error(ctx, THX_EIO, "%s: path too long", od->dir);
    }
    if (!mkdtemp(od->tmp)) {
        od->tmp[0] = '\0';
        return thx_error(ctx, THX_EIO, "%s: cannot create a temporary directory: %s", od->dir, strerror(errno));
    }
    chmod(od->tmp, 0755);
    return THX_OK;
}

void thx_outdir_abort(thx_outdir *od)
{
    if (od->tmp[0]) remove_tree(od->tmp);
    od->tmp[0] = '\0';
}

static thx_status raced(thx_ctx *ctx, thx_outdir *od)
{
    thx_outdir_abort(od);
    return thx_error(ctx, THX_EIO,
                     "%s was changed by another command while this one ran; this command's output was discarded and "
                     "the other's left whole",
                     od->dir);
}

thx_status thx_outdir_commit(thx_ctx *ctx, thx_outdir *od)
{
    struct stat st;
    if (!od->existed) {
        /* created, unless another command made it meanwhile (a non-empty directory is never renamed over) */
        if (lstat(od->dir, &st) == 0) return raced(ctx, od);
        if (rename(od->tmp, od->dir) != 0) {
            if (errno == EEXIST || errno == ENOTEMPTY || errno == EISDIR || errno == ENOTDIR) return raced(ctx, od);
            int e = errno;
            thx_outdir_abort(od);
            return thx_error(ctx, THX_EIO, "%s: cannot rename into place: %s", od->dir, strerror(e));
        }
        od->tmp[0] = '\0';
        return THX_OK;
    }
    if (lstat(od->dir, &st) != 0 || !S_ISDIR(st.st_mode) || (unsigned long long)st.st_dev != od->dev ||
        (unsigned long long)st.st_ino != od->ino)
        return raced(ctx, od);
    /* still thorax's own (nothing added while the command ran) */
    thx_status ow = owned(ctx, od->dir, od->manifest, od->format);
    if (ow != THX_OK) { thx_outdir_abort(od); return ow; }
    /* the old directory aside, then the new one in its place: no mixture is ever visible */
    char old[4300];
    snprintf(old, sizeof old, "%s.oldXXXXXX", od->tmp);
    if (!mkdtemp(old) || rmdir(old) != 0 || rename(od->dir, old) != 0) {
        int e = errno;
        if (e == ENOENT) return raced(ctx, od);
        thx_outdir_abort(od);
        return thx_error(ctx, THX_EIO, "%s: cannot replace: %s", od->dir, strerror(e));
    }
    /* what was moved must be what was claimed (another command may have swapped it in between) */
    if (lstat(old, &st) != 0 || (unsigned long long)st.st_ino != od->ino || (unsigned long long)st.st_dev != od->dev) {
        if (rename(old, od->dir) != 0) {
            thx_outdir_abort(od);
            return thx_error(ctx, THX_EIO, "%s was changed by another command meanwhile; its output is now at %s", od->dir,
                             old);
        }
        return raced(ctx, od);
    }
    if (rename(od->tmp, od->dir) != 0) {
        int e = errno;
        if (rename(old, od->dir) != 0) {
            thx_outdir_abort(od);
            return thx_error(ctx, THX_EIO, "%s: cannot rename into place (%s); the previous output is at %s", od->dir,
                             strerror(e), old);
        }
        if (e == EEXIST || e == ENOTEMPTY) return raced(ctx, od);
        thx_outdir_abort(od);
        return thx_error(ctx, THX_EIO, "%s: cannot rename into place: %s", od->dir, strerror(e));
    }
    od->tmp[0] = '\0';
    remove_tree(old);
    return THX_OK;
}

ssize_t thx_read_at(int fd, void *p, size_t count, off_t off)
{
    size_t done = 0;
    while (done < count) {
        ssize_t got = off < 0 ? read(fd, (char *)p + done, count - done)
                              : pread(fd, (char *)p + done, count - done, off + (off_t)done);
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) return -1;
        if (got == 0) break;
        done += (size_t)got;
    }
    return (ssize_t)done;
}

int thx_read_exact(int fd, void *p, size_t count, off_t off)
{
    (void)thx_pages_present(p, count); /* (where it cannot, the copy faults them in) */
    return thx_read_at(fd, p, count, off) == (ssize_t)count;
}

thx_status thx_read_file(thx_ctx *ctx, const char *path, char **text, size_t *len)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    struct stat sb;
    const int sized = fstat(fd, &sb) == 0 && S_ISREG(sb.st_mode) && sb.st_size > 0;
    const size_t size = sized ? (size_t)sb.st_size : 0;
    /* room for the size the file has, its NUL, and one byte more: a file that grew is seen growing */
    size_t cap = sized ? size + 2 : (size_t)1 << 16, n = 0;
    char *buf = cap > size ? malloc(cap) : NULL;
    if (!buf) {
        close(fd);
        return thx_error(ctx, THX_ENOMEM, "%s: out of memory", path);
    }
    int bad = 0;
    if (size >= THX_READ_SPLIT) {
        /* a large file's halves read side by side, each into pages asked for at once (thorax/core/pages.h):
           the copy and the pages' cost are most of the reading, and one thread alone held the rest waiting */
        const size_t half = size / 2;
        ssize_t got[2] = {0, 0};
#pragma omp parallel for num_threads(2) schedule(static, 1)
        for (int k = 0; k < 2; k++) {
            size_t at = k ? half : 0, count = k ? size - half : half;
            (void)thx_pages_present(buf + at, count); /* (where it cannot, the copy faults them in) */
            got[k] = thx_read_at(fd, buf + at, count, (off_t)at);
        }
        bad = got[0] < 0 || got[1] < 0;
        /* what came whole from the start; the rest (a file that shrank meanwhile) is read on below */
        n = bad ? 0 : (size_t)got[0] < half ? (size_t)got[0] : half + (size_t)got[1];
    }
    while (!bad) {
        if (n + 1 >= cap) {
            char *q = realloc(buf, cap * 2);
            if (!q) {
                free(buf);
                close(fd);
                return thx_error(ctx, THX_ENOMEM, "%s: out of memory", path);
            }
            buf = q;
            cap *= 2;
        }
        ssize_t got = thx_read_at(fd, buf + n, cap - n - 1, sized ? (off_t)n : -1);
        if (got < 0) bad = 1;
        else n += (size_t)got;
        if (got <= 0 || n + 1 < cap) break; /* the end of the file (a read short of the room left) */
    }
    int e = errno;
    close(fd);
    if (bad) {
        free(buf);
        return thx_error(ctx, THX_EIO, "%s: read error: %s", path, strerror(e));
    }
    buf[n] = '\0';
    *text = buf;
    if (len) *len = n;
    return THX_OK;
}

int thx_make_dirs(const char *dir)
{
    char p[4096];
    if (snprintf(p, sizeof p, "%s", dir) >= (int)sizeof p) {
        errno = ENAMETOOLONG;
        return -1;
    }
    for (char *c = p + 1; *c; c++)
        if (*c == '/') {
            *c = '\0';
            if (mkdir(p, 0755) != 0 && errno != EEXIST) return -1;
            *c = '/';
        }
    return mkdir(p, 0755) != 0 && errno != EEXIST ? -1 : 0;
}
