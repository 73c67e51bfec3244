/* DICOM series -> thx_image: the series logic (ours, not GDCM's sorter) over the tags and pixels
 * that src/image/dicom_gdcm.cc reads. The rules and their tolerances are in docs/design/image.md,
 * "DICOM"; in short:
 *   - a folder's files (not its subfolders) are grouped by SeriesInstanceUID; several series need a
 *     choice (UID or 1-based number of the listing, ordered by SeriesNumber then UID);
 *   - the slices of the series are sorted by d = ImagePositionPatient . n, n = row x column
 *     direction (ImageOrientationPatient); the spacing between slices comes from the positions;
 *   - refused, naming the files: orientation, pixel spacing or size differing within the series,
 *     two slices at one position, a stack leaning more than 0.5 degrees off the normal (gantry
 *     tilt) or positions off one line by more than a tenth of a pixel, a gap more than 1% away from the median gap (uneven spacing, a missing slice),
 *     several frames in one file;
 *   - values = RescaleSlope * stored + RescaleIntercept, slice by slice;
 *   - DICOM's patient frame is LPS: origin and directions negate x and y into RAS. */
#include "image/dicom.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <signal.h>
#include <string.h>
#include <spawn.h>
#include <stdint.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <poll.h>

#include "image/image_impl.h"
#include "thorax/core/module.h"
#include "thorax/core/sha256.h"

/* Tolerances (docs/design/image.md, "DICOM"). */
#define ORIENT_TOL 1e-4      /* |difference| of any ImageOrientationPatient component */
#define SPACING_TOL 1e-4     /* relative difference of PixelSpacing */
#define DUPLICATE_MM 1e-3    /* two positions closer than this along the normal are one position */
#define TILT_DEG 0.5         /* largest angle between the stack (first -> last position) and the normal */
#define LINE_TOL 0.1         /* largest distance of a position from that line, in pixels (the smaller spacing) */
#define GAP_TOL 0.01         /* largest relative difference of a gap from the median gap */

int thx_image_is_dicom_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    char b[132];
    size_t n = fread(b, 1, sizeof b, f);
    fclose(f);
    return n == sizeof b && memcmp(b + 128, "DICM", 4) == 0;
}

typedef struct {
    const char *uid, *number, *description, *modality;
    size_t slices;
    unsigned rows, columns;
} series_info;

static int all_digits(const char *s)
{
    if (!*s) return 0;
    for (; *s; s++)
        if (!isdigit((unsigned char)*s)) return 0;
    return 1;
}

static int series_cmp(const void *pa, const void *pb)
{
    const series_info *a = pa, *b = pb;
    int ha = all_digits(a->number), hb = all_digits(b->number);
    if (ha != hb) return hb - ha; /* numbered series first */
    if (ha) {
        long na = strtol(a->number, NULL, 10), nb = strtol(b->number, NULL, 10);
        if (na != nb) return na < nb ? -1 : 1;
    }
    return strcmp(a->uid, b->uid);
}

/* The listing of the series, one per line, into buf. */
static void list_series(const series_info *s, size_t ns, char *buf, size_t size)
{
    size_t used = 0;
    buf[0] = '\0';
    for (size_t k = 0; k < ns; k++) {
        char line[400];
        snprintf(line, sizeof line, "\n  %zu: %s  \"%s\"  %s  %zu slice%s of %u x %u (rows x columns)%s%s", k + 1,
                 s[k].uid[0] ? s[k].uid : "(no SeriesInstanceUID)", s[k].description, s[k].modality[0] ? s[k].modality : "-",
                 s[k].slices, s[k].slices == 1 ? "" : "s", s[k].rows, s[k].columns, s[k].number[0] ? "  series number " : "",
                 s[k].number);
        size_t m = strlen(line);
        if (used + m + 40 >= size) {
            snprintf(buf + used, size - used, "\n  ... and %zu more", ns - k);
            return;
        }
        memcpy(buf + used, line, m + 1);
        used += m;
    }
}

typedef struct {
    const thx_dicom_entry *e;
    double d; /* position along the normal */
} slice;

static int slice_cmp(const void *pa, const void *pb)
{
    const slice *a = pa, *b = pb;
    if (a->d != b->d) return a->d < b->d ? -1 : 1;
    return strcmp(a->e->file, b->e->file);
}

static int dcmp(const void *pa, const void *pb)
{
    double a = *(const double *)pa, b = *(const double *)pb;
    return a < b ? -1 : a > b;
}

static void unit(double *v)
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0)
        for (int c = 0; c < 3; c++) v[c] /= l;
}

/* ---- GDCM in the helper program thorax-dicom (src/image/dicom_helper.c), started by posix_spawn:
 * Debian's GDCM keeps its assert()s, and a truncated or corrupt file aborts inside it (measured on
 * one slice cut at each length: most lengths abort). The helper is exec'd, so nothing of the
 * caller's process follows it (signal handlers, a fuzzer's or sanitizer's allocator hooks), and it
 * answers the requests of src/image/dicom.h's protocol on a socket. Its replies are not trusted:
 * every length is checked against its bound before anything is read or allocated for it, and a
 * helper that dies, answers late or answers garbage is an error naming the file. */

#ifndef THORAX_DICOM_HELPER_INSTALLED /* CMakeLists.txt sets these three from the install directories */
#define THORAX_DICOM_HELPER_INSTALLED "/usr/local/libexec/thorax/thorax-dicom"
#endif
#ifndef THORAX_DICOM_HELPER_FROM_BIN
#define THORAX_DICOM_HELPER_FROM_BIN "../libexec/thorax/thorax-dicom"
#endif
#ifndef THORAX_DICOM_HELPER_FROM_LIB
#define THORAX_DICOM_HELPER_FROM_LIB "../libexec/thorax/thorax-dicom"
#endif
#define HELPER_CHANNEL 3          /* the helper's end of the socket */
#define HELPER_SECONDS 30         /* default wall time for one reply (THORAX_DICOM_SECONDS) */
#define HELPER_MEMORY_MB 4096     /* default address space of the helper (THORAX_DICOM_MEMORY_MB) */

typedef struct {
    pid_t pid;     /* 0: not running (or reaped) */
    int fd;        /* the parent's end of the socket; -1 when closed */
    int seconds;   /* wall time allowed for each reply */
    char path[1100];
} helper;

/* The helper's path: $THORAX_DICOM_HELPER; else LIBEXECDIR/thorax/thorax-dicom relative to the object
 * holding this code (libthorax.so in LIBDIR) or to the running program (in BINDIR: the build tree's
 * bin/ and tests/ sit beside its libexec/ alike), so that a moved prefix keeps working; else the
 * absolute path the build was configured to install it at. */
static thx_status find_helper(thx_ctx *ctx, const char *what, char *out, size_t size)
{
    const char *env = getenv("THORAX_DICOM_HELPER");
    if (env && *env) {
        if (access(env, X_OK) != 0)
            return thx_error(ctx, THX_EIO, "%s: THORAX_DICOM_HELPER=%s: %s (DICOM is read through the helper program thorax-dicom)",
                             what, env, strerror(errno));
        snprintf(out, size, "%s", env);
        return THX_OK;
    }
    char cand[3][1100];
    const char *from_bin[] = {THORAX_DICOM_HELPER_FROM_BIN};
    int nc = thx_shipped_paths(THORAX_DICOM_HELPER_FROM_LIB, from_bin, 1, THORAX_DICOM_HELPER_INSTALLED, cand[0],
                               sizeof cand[0], 3);
    for (int k = 0; k < nc; k++)
        if (access(cand[k], X_OK) == 0) {
            snprintf(out, size, "%.1099s", cand[k]); /* (cand[k] is one row: gcc cannot see it) */
            return THX_OK;
        }
    return thx_error(ctx, THX_EIO,
                     "%s: the DICOM helper program thorax-dicom is missing (looked for %s%s%s%s%s): thorax reads DICOM through "
                     "it; install thorax (cmake --install) or set THORAX_DICOM_HELPER to its path",
                     what, cand[0], nc > 1 ? ", " : "", nc > 1 ? cand[1] : "", nc > 2 ? ", " : "", nc > 2 ? cand[2] : "");
}

/* A positive integer from the environment (at most max), or def; -1 when set but not one. */
static long env_limit(const char *name, long def, long max)
{
    const char *v = getenv(name);
    if (!v || !*v) return def;
    char *end;
    errno = 0;
    long x = strtol(v, &end, 10);
    return *end == '\0' && errno == 0 && x > 0 && x <= max ? x : -1;
}

/* Milliseconds left until deadline (0 when past). */
static int ms_left(const struct timespec *deadline)
{
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    double ms = (double)(deadline->tv_sec - now.tv_sec) * 1e3 + (double)(deadline->tv_nsec - now.tv_nsec) / 1e6;
    return ms <= 0 ? 0 : ms > 1e9 ? 1000000000 : (int)ceil(ms);
}

static void deadline_in(struct timespec *d, int seconds)
{
    clock_gettime(CLOCK_MONOTONIC, d);
    d->tv_sec += seconds;
}

enum { GOT = 0, GONE = 1, LATE = 2 };

/* Reads n bytes from the helper by the deadline: GOT; GONE (the socket ended or failed: the helper
 * closed it or died); LATE (the deadline passed). Reads as the helper writes (a slice larger than
 * the socket's buffer streams through), and a signal interrupting poll or read is not an error. */
static int recv_exact(helper *h, void *buf, size_t n, const struct timespec *deadline)
{
    char *p = buf;
    while (n > 0) {
        int ms = ms_left(deadline);
        if (ms == 0) return LATE;
        struct pollfd pf = {h->fd, POLLIN, 0};
        int r = poll(&pf, 1, ms);
        if (r < 0 && errno == EINTR) continue;
        if (r < 0) return GONE;
        if (r == 0) continue; /* the deadline is checked above */
        ssize_t got = read(h->fd, p, n);
        if (got < 0 && (errno == EINTR || errno == EAGAIN)) continue;
        if (got <= 0) return GONE;
        p += got;
        n -= (size_t)got;
    }
    return GOT;
}

/* 0, or -1 (the helper is gone). send(MSG_NOSIGNAL): a helper that died leaves EPIPE here, never a
 * SIGPIPE that would end the caller's process. */
static int send_all(int fd, const void *buf, size_t n)
{
    const char *p = buf;
    while (n > 0) {
        ssize_t w = send(fd, p, n, MSG_NOSIGNAL);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return -1;
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

/* Ends the helper and collects it (no zombie is left): the socket closed, then (kill_it) SIGKILL at
 * once, or up to 2 s for it to end by itself (it exits on the closed socket; one that died already
 * is collected with its status), then SIGKILL. How it ended into how[]. */
static void helper_stop(helper *h, int kill_it, char *how, size_t size)
{
    if (size) how[0] = '\0';
    if (h->fd >= 0) close(h->fd);
    h->fd = -1;
    if (h->pid <= 0) return;
    int st = 0;
    pid_t r = 0;
    if (!kill_it) {
        struct timespec d;
        deadline_in(&d, 2);
        while ((r = waitpid(h->pid, &st, WNOHANG)) == 0 && ms_left(&d) > 0) {
            struct timespec nap = {0, 2000000};
            nanosleep(&nap, NULL);
        }
        if (r < 0 && errno == EINTR) r = 0;
    }
    if (r == 0) {
        kill(h->pid, SIGKILL); /* not yet collected: the pid is still ours */
        while ((r = waitpid(h->pid, &st, 0)) < 0 && errno == EINTR) {
        }
    }
    h->pid = 0;
    if (r < 0) snprintf(how, size, "the DICOM helper ended, how is unknown (%s)", strerror(errno));
    else if (WIFSIGNALED(st) && WTERMSIG(st) == SIGXCPU)
        snprintf(how, size, "GDCM used more than %d s of processor time on it (signal %d, %s)", h->seconds, SIGXCPU,
                 strsignal(SIGXCPU));
    else if (WIFSIGNALED(st))
        snprintf(how, size, "GDCM crashed on it (signal %d, %s)", WTERMSIG(st), strsignal(WTERMSIG(st)));
    else
        snprintf(how, size, "the DICOM helper ended (status %d)", WIFEXITED(st) ? WEXITSTATUS(st) : -1);
}

/* Starts the helper and checks its greeting (the protocol's name and version). */
static thx_status helper_start(thx_ctx *ctx, const char *what, helper *h)
{
    h->pid = 0;
    h->fd = -1;
    THX_CHECK(find_helper(ctx, what, h->path, sizeof h->path));
    long seconds = env_limit("THORAX_DICOM_SECONDS", HELPER_SECONDS, 86400);
    long mb = env_limit("THORAX_DICOM_MEMORY_MB", HELPER_MEMORY_MB, 1L << 30);
    if (seconds < 0 || mb < 0)
        return thx_error(ctx, THX_EINPUT, "%s: %s=%s: a whole number of %s is needed", what,
                         seconds < 0 ? "THORAX_DICOM_SECONDS" : "THORAX_DICOM_MEMORY_MB",
                         getenv(seconds < 0 ? "THORAX_DICOM_SECONDS" : "THORAX_DICOM_MEMORY_MB"),
                         seconds < 0 ? "seconds (1 to 86400)" : "megabytes");
    h->seconds = (int)seconds;
    int sv[2];
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
        return thx_error(ctx, THX_EIO, "%s: cannot make a socket for the DICOM helper: %s", what, strerror(errno));
    if (sv[1] == HELPER_CHANNEL) { /* dup2 onto itself would keep close-on-exec */
        int d = fcntl(sv[1], F_DUPFD_CLOEXEC, HELPER_CHANNEL + 1);
        close(sv[1]);
        sv[1] = d;
        if (d < 0) {
            close(sv[0]);
            return thx_error(ctx, THX_EIO, "%s: cannot make a socket for the DICOM helper: %s", what, strerror(errno));
        }
    }
    posix_spawn_file_actions_t fa;
    posix_spawnattr_t at;
    posix_spawn_file_actions_init(&fa);
    posix_spawnattr_init(&at);
    posix_spawn_file_actions_adddup2(&fa, sv[1], HELPER_CHANNEL);
    /* GDCM's codecs and its assert()s print: not from the library */
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 34))
    posix_spawn_file_actions_addclosefrom_np(&fa, HELPER_CHANNEL + 1); /* none of the caller's descriptors */
#endif
    /* handlers are reset by exec anyway; ignored signals and the mask would carry over */
    sigset_t none, dfl;
    sigemptyset(&none);
    sigemptyset(&dfl);
    const int sigs[] = {SIGPIPE, SIGINT, SIGQUIT, SIGHUP, SIGTERM, SIGALRM, SIGCHLD, SIGXCPU, SIGXFSZ, SIGUSR1, SIGUSR2};
    for (size_t k = 0; k < sizeof sigs / sizeof *sigs; k++) sigaddset(&dfl, sigs[k]);
    posix_spawnattr_setsigmask(&at, &none);
    posix_spawnattr_setsigdefault(&at, &dfl);
    posix_spawnattr_setflags(&at, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
    char version[16], mbs[32], secs[32];
    snprintf(version, sizeof version, "%d", THX_DICOM_PROTOCOL);
    snprintf(mbs, sizeof mbs, "%ld", mb);
    snprintf(secs, sizeof secs, "%ld", seconds);
    char *argv[] = {h->path, "--protocol", version, "--memory-mb", mbs, "--seconds", secs, NULL};
    pid_t pid;
    int e = posix_spawn(&pid, h->path, &fa, &at, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    posix_spawnattr_destroy(&at);
    close(sv[1]);
    if (e != 0) {
        close(sv[0]);
        return thx_error(ctx, THX_EIO, "%s: cannot start the DICOM helper %s: %s", what, h->path, strerror(e));
    }
    h->pid = pid;
    h->fd = sv[0];
    unsigned char hello[12];
    struct timespec d;
    deadline_in(&d, h->seconds);
    int r = recv_exact(h, hello, sizeof hello, &d);
    uint32_t v = 0;
    if (r == GOT) memcpy(&v, hello + 8, 4);
    if (r != GOT || memcmp(hello, THX_DICOM_HELLO, 8) != 0 || v != THX_DICOM_PROTOCOL) {
        char how[200];
        helper_stop(h, r != GONE, how, sizeof how);
        if (r == GOT && memcmp(hello, THX_DICOM_HELLO, 8) != 0)
            return thx_error(ctx, THX_EIO, "%s: %s is not the DICOM helper (its greeting is not the protocol's)", what, h->path);
        if (r == GOT)
            return thx_error(ctx, THX_EIO, "%s: the DICOM helper %s speaks protocol version %u, this library version %d "
                             "(the helper and the library come from different builds: reinstall thorax)", what, h->path, v,
                             THX_DICOM_PROTOCOL);
        return thx_error(ctx, THX_EIO, "%s: the DICOM helper %s did not start: %s", what, h->path,
                         r == LATE ? "no greeting within the time limit" : how);
    }
    return THX_OK;
}

/* A reply's payload, read in full (small payloads: a message, a scan entry), taken field by field;
 * `bad` holds the first fault. */
typedef struct {
    const unsigned char *p;
    size_t left;
    const char *bad;
} cursor;

static void take(cursor *c, void *dst, size_t n)
{
    if (c->bad || n > c->left) {
        if (!c->bad) c->bad = "it ends inside a field";
        memset(dst, 0, n);
        return;
    }
    memcpy(dst, c->p, n);
    c->p += n;
    c->left -= n;
}
static uint32_t take_u32(cursor *c)
{
    uint32_t v;
    take(c, &v, 4);
    return v;
}
static double take_f64(cursor *c, int needed)
{
    double v;
    take(c, &v, 8);
    if (needed && !isfinite(v) && !c->bad) c->bad = "a number is not finite";
    return v;
}
static void take_str(cursor *c, char *dst, size_t cap)
{
    uint16_t n = 0;
    take(c, &n, 2);
    dst[0] = '\0';
    if (c->bad) return;
    if (n >= cap) {
        c->bad = "a text longer than its field";
        return;
    }
    take(c, dst, n);
    dst[c->bad ? 0 : n] = '\0';
    if (!c->bad && strlen(dst) != n) c->bad = "a text holds a NUL";
}
static int take_flag(cursor *c)
{
    uint32_t v = take_u32(c);
    if (v > 1 && !c->bad) c->bad = "a yes/no field is neither";
    return (int)v;
}

/* Sends one request about `file` and reads the reply's header: *status and *len, both checked
 * (op echoed; status one the op may answer; a length within its bound). On any failure the helper
 * is stopped and the error names the file: `doing` is what could not be done ("its tags cannot be
 * read"). */
static thx_status ask(thx_ctx *ctx, helper *h, uint32_t op, unsigned rows, unsigned columns, const char *file,
                      const char *doing, int32_t *status, uint64_t *len, struct timespec *deadline)
{
    size_t pl = strlen(file);
    if (pl == 0 || pl > THX_DICOM_MAX_PATH)
        return thx_error(ctx, THX_EINPUT, "%s: a path of %zu bytes (at most %d)", file, pl, THX_DICOM_MAX_PATH);
    unsigned char req[16 + THX_DICOM_MAX_PATH];
    uint32_t head[4] = {op, rows, columns, (uint32_t)pl};
    memcpy(req, head, 16);
    memcpy(req + 16, file, pl);
    char how[200];
    deadline_in(deadline, h->seconds);
    if (send_all(h->fd, req, 16 + pl) != 0) {
        helper_stop(h, 0, how, sizeof how);
        return thx_error(ctx, THX_EINPUT, "%s: %s: the DICOM helper was gone before the request: %s", file, doing, how);
    }
    unsigned char rh[16];
    int r = recv_exact(h, rh, sizeof rh, deadline);
    if (r != GOT) {
        helper_stop(h, r == LATE, how, sizeof how);
        if (r == LATE)
            return thx_error(ctx, THX_EINPUT, "%s: %s: no reply from GDCM within %d s (THORAX_DICOM_SECONDS; the helper was stopped)",
                             file, doing, h->seconds);
        return thx_error(ctx, THX_EINPUT, "%s: %s: %s (a truncated or corrupt file?)", file, doing, how);
    }
    uint32_t rop;
    memcpy(&rop, rh, 4);
    memcpy(status, rh + 4, 4);
    memcpy(len, rh + 8, 8);
    const char *bad = NULL;
    if (rop != op) bad = "an answer to another request";
    else if (*status != -1 && *status != 0 && !(op == THX_DICOM_OP_SCAN && *status == 1)) bad = "an unknown status";
    else if (*status == -1 && (*len == 0 || *len > THX_DICOM_MAX_MESSAGE)) bad = "a message of impossible length";
    else if (op == THX_DICOM_OP_SCAN && *status == 0 && *len != 0) bad = "a payload after \"not DICOM\"";
    else if (op == THX_DICOM_OP_SCAN && *status == 1 && *len > THX_DICOM_MAX_ENTRY) bad = "an entry of impossible length";
    else if (op == THX_DICOM_OP_PIXELS && *status == 0 && *len < 12) bad = "pixels without their header";
    if (bad) {
        helper_stop(h, 1, how, sizeof how);
        return thx_error(ctx, THX_EIO, "%s: %s: the DICOM helper's reply is garbled (%s: op %u, status %d, %llu bytes)", file,
                         doing, bad, rop, *status, (unsigned long long)*len);
    }
    return THX_OK;
}

/* Reads a reply's small payload (len checked by ask()) into buf[len + 1], NUL-terminated. */
static thx_status payload(thx_ctx *ctx, helper *h, unsigned char *buf, size_t len, const char *file, const char *doing,
                          const struct timespec *deadline)
{
    int r = recv_exact(h, buf, len, deadline);
    buf[len] = '\0';
    if (r == GOT) return THX_OK;
    char how[200];
    helper_stop(h, r == LATE, how, sizeof how);
    if (r == LATE)
        return thx_error(ctx, THX_EINPUT, "%s: %s: the reply did not arrive whole within %d s (THORAX_DICOM_SECONDS; the helper was stopped)",
                         file, doing, h->seconds);
    return thx_error(ctx, THX_EINPUT, "%s: %s: the DICOM helper's reply stops short of its %zu bytes: %s", file, doing, len,
                     how);
}

/* A message reply: its text (control characters shown as '?') as the error, prefixed with the
 * file's name unless the text names it. */
static thx_status helper_message(thx_ctx *ctx, unsigned char *buf, size_t len, const char *file)
{
    for (size_t k = 0; k < len; k++)
        if (buf[k] < 32 || buf[k] == 127) buf[k] = '?';
    if (strstr((const char *)buf, file)) return thx_error(ctx, THX_EINPUT, "%s", (const char *)buf);
    return thx_error(ctx, THX_EINPUT, "%s: %s", file, (const char *)buf);
}

static int name_cmp(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

/* The regular files of dir (not its subfolders), sorted by name. */
static thx_status list_files(thx_ctx *ctx, const char *dir, char ***files, size_t *n)
{
    *files = NULL;
    *n = 0;
    DIR *d = opendir(dir);
    if (!d) return thx_error(ctx, THX_EIO, "%s: cannot open the folder: %s", dir, strerror(errno));
    size_t cap = 0;
    thx_status s = THX_OK;
    struct dirent *de;
    while ((de = readdir(d)) != NULL) {
        if (de->d_name[0] == '.') continue; /* ., .. and hidden files */
        size_t len = strlen(dir) + strlen(de->d_name) + 2;
        char *f = malloc(len);
        if (!f) {
            s = thx_error(ctx, THX_ENOMEM, "%s: out of memory", dir);
            break;
        }
        snprintf(f, len, "%s/%s", dir, de->d_name);
        struct stat st;
        if (stat(f, &st) != 0 || !S_ISREG(st.st_mode)) {
            free(f);
            continue;
        }
        if (*n == cap) {
            cap = cap ? 2 * cap : 64;
            char **g = realloc(*files, cap * sizeof *g);
            if (!g) {
                free(f);
                s = thx_error(ctx, THX_ENOMEM, "%s: out of memory", dir);
                break;
            }
            *files = g;
        }
        (*files)[(*n)++] = f;
    }
    closedir(d);
    if (s == THX_OK && *n) qsort(*files, *n, sizeof **files, name_cmp);
    return s;
}

/* One SCAN reply's entry payload into *e (file set by the caller); NULL, or what is wrong with it. */
static const char *decode_entry(const unsigned char *buf, size_t len, thx_dicom_entry *e)
{
    cursor c = {buf, len, NULL};
    take_str(&c, e->series_uid, sizeof e->series_uid);
    take_str(&c, e->series_number, sizeof e->series_number);
    take_str(&c, e->description, sizeof e->description);
    take_str(&c, e->modality, sizeof e->modality);
    e->image = take_flag(&c);
    e->frames = (int)take_u32(&c);
    e->has_position = take_flag(&c);
    e->has_orientation = take_flag(&c);
    e->has_spacing = take_flag(&c);
    for (int q = 0; q < 3; q++) e->position[q] = take_f64(&c, e->has_position);
    for (int q = 0; q < 6; q++) e->orientation[q] = take_f64(&c, e->has_orientation);
    for (int q = 0; q < 2; q++) e->pixel_spacing[q] = take_f64(&c, e->has_spacing);
    e->thickness = take_f64(&c, 1);
    e->slope = take_f64(&c, 1);
    e->intercept = take_f64(&c, 1);
    e->rows = take_u32(&c);
    e->columns = take_u32(&c);
    if (c.bad) return c.bad;
    if (c.left) return "bytes left over after the entry";
    if (e->frames < 1) return "a number of frames below 1";
    if (e->rows > 65535 || e->columns > 65535) return "rows or columns above 65535";
    if (e->image && (e->rows == 0 || e->columns == 0)) return "an image without rows or columns";
    return NULL;
}

/* Every file's tags, read by the helper (started here): *entries the DICOM files (in name order). */
static thx_status scan_folder(thx_ctx *ctx, helper *h, const char *dir, thx_dicom_entry **entries, size_t *count)
{
    *entries = NULL;
    *count = 0;
    char **files;
    size_t n;
    thx_status s = list_files(ctx, dir, &files, &n);
    if (s == THX_OK && n > 0) {
        *entries = malloc(n * sizeof **entries);
        if (!*entries) s = thx_error(ctx, THX_ENOMEM, "%s: out of memory", dir);
        else s = helper_start(ctx, dir, h);
    }
    static const char doing[] = "its tags cannot be read";
    unsigned char buf[THX_DICOM_MAX_MESSAGE + THX_DICOM_MAX_ENTRY + 1];
    for (size_t k = 0; s == THX_OK && k < n; k++) {
        int32_t status;
        uint64_t len;
        struct timespec deadline;
        if ((s = ask(ctx, h, THX_DICOM_OP_SCAN, 0, 0, files[k], doing, &status, &len, &deadline)) != THX_OK) break;
        if ((s = payload(ctx, h, buf, (size_t)len, files[k], doing, &deadline)) != THX_OK) break;
        if (status < 0) {
            s = helper_message(ctx, buf, (size_t)len, files[k]);
        } else if (status == 1) {
            thx_dicom_entry *e = &(*entries)[*count];
            memset(e, 0, sizeof *e);
            snprintf(e->file, sizeof e->file, "%s", files[k]);
            const char *bad = decode_entry(buf, (size_t)len, e);
            if (bad) {
                char how[200];
                helper_stop(h, 1, how, sizeof how);
                s = thx_error(ctx, THX_EIO, "%s: %s: the DICOM helper's reply is garbled (%s)", files[k], doing, bad);
            } else {
                (*count)++;
            }
        }
    }
    for (size_t k = 0; k < n; k++) free(files[k]);
    free(files);
    if (s != THX_OK) {
        free(*entries);
        *entries = NULL;
        *count = 0;
    }
    return s;
}

static const char *const type_name[] = {"", "uint8", "int8", "uint16", "int16", "uint32", "int32", "float32", "float64"};
static const size_t type_size[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};

/* count stored values of `type` -> slope * v + inter, as float. */
static void convert(const unsigned char *b, size_t count, int type, double slope, double inter, float *dst)
{
#define CONVERT(T)                                                      \
    for (size_t q = 0; q < count; q++) {                                \
        T x;                                                            \
        memcpy(&x, b + q * sizeof x, sizeof x);                         \
        dst[q] = (float)(slope * (double)x + inter);                    \
    }                                                                   \
    break;
    switch (type) {
    case THX_DICOM_T_UINT8: CONVERT(uint8_t)
    case THX_DICOM_T_INT8: CONVERT(int8_t)
    case THX_DICOM_T_UINT16: CONVERT(uint16_t)
    case THX_DICOM_T_INT16: CONVERT(int16_t)
    case THX_DICOM_T_UINT32: CONVERT(uint32_t)
    case THX_DICOM_T_INT32: CONVERT(int32_t)
    case THX_DICOM_T_FLOAT32: CONVERT(float)
    default: CONVERT(double)
    }
#undef CONVERT
}

/* The series' slices checked, sorted and read into *img. */
static thx_status assemble(thx_ctx *ctx, helper *h, const char *path, slice *sl, size_t ns, thx_image *img)
{
    const thx_dicom_entry *e0 = sl[0].e;
    for (size_t s = 0; s < ns; s++) {
        const thx_dicom_entry *e = sl[s].e;
        if (e->frames > 1)
            return thx_error(ctx, THX_EINPUT,
                             "%s: %d frames in one file (a multi-frame image): thorax reads series of single-frame slices",
                             e->file, e->frames);
        if (!e->has_position || !e->has_orientation)
            return thx_error(ctx, THX_EINPUT,
                             "%s: no %s: the slice cannot be placed in the patient frame", e->file,
                             !e->has_position ? "ImagePositionPatient (0020,0032)" : "ImageOrientationPatient (0020,0037)");
        if (!e->has_spacing || !(e->pixel_spacing[0] > 0) || !(e->pixel_spacing[1] > 0))
            return thx_error(ctx, THX_EINPUT, "%s: %s: the pixel size is unknown", e->file,
                             e->has_spacing ? "PixelSpacing (0028,0030) is not positive" : "no PixelSpacing (0028,0030)");
        if (e->rows != e0->rows || e->columns != e0->columns)
            return thx_error(ctx, THX_EINPUT, "%s: %u x %u pixels (rows x columns) but %s has %u x %u: one series, one size",
                             e->file, e->rows, e->columns, e0->file, e0->rows, e0->columns);
        for (int c = 0; c < 6; c++)
            if (fabs(e->orientation[c] - e0->orientation[c]) > ORIENT_TOL)
                return thx_error(ctx, THX_EINPUT,
                                 "%s: ImageOrientationPatient %g\\%g\\%g\\%g\\%g\\%g differs from %s's %g\\%g\\%g\\%g\\%g\\%g "
                                 "(a series of one orientation is needed; a localizer mixed in?)",
                                 e->file, e->orientation[0], e->orientation[1], e->orientation[2], e->orientation[3],
                                 e->orientation[4], e->orientation[5], e0->file, e0->orientation[0], e0->orientation[1],
                                 e0->orientation[2], e0->orientation[3], e0->orientation[4], e0->orientation[5]);
        for (int c = 0; c < 2; c++)
            if (fabs(e->pixel_spacing[c] - e0->pixel_spacing[c]) > SPACING_TOL * e0->pixel_spacing[c])
                return thx_error(ctx, THX_EINPUT, "%s: PixelSpacing %g\\%g differs from %s's %g\\%g", e->file,
                                 e->pixel_spacing[0], e->pixel_spacing[1], e0->file, e0->pixel_spacing[0],
                                 e0->pixel_spacing[1]);
    }
    /* the frame: row direction (i), column direction (j), their cross product (k), LPS */
    double r[3] = {e0->orientation[0], e0->orientation[1], e0->orientation[2]};
    double c[3] = {e0->orientation[3], e0->orientation[4], e0->orientation[5]};
    unit(r);
    unit(c);
    double nrm[3] = {r[1] * c[2] - r[2] * c[1], r[2] * c[0] - r[0] * c[2], r[0] * c[1] - r[1] * c[0]};
    if (!(sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]) > 0.5))
        return thx_error(ctx, THX_EINPUT, "%s: ImageOrientationPatient %g\\%g\\%g\\%g\\%g\\%g: the row and column directions are not perpendicular unit vectors",
                         e0->file, e0->orientation[0], e0->orientation[1], e0->orientation[2], e0->orientation[3],
                         e0->orientation[4], e0->orientation[5]);
    unit(nrm);
    for (size_t s = 0; s < ns; s++) {
        const double *p = sl[s].e->position;
        sl[s].d = p[0] * nrm[0] + p[1] * nrm[1] + p[2] * nrm[2];
    }
    qsort(sl, ns, sizeof *sl, slice_cmp);
    double step = 0;
    if (ns > 1) {
        double *gaps = malloc((ns - 1) * sizeof *gaps);
        if (!gaps) return thx_error(ctx, THX_ENOMEM, "%s: out of memory", path);
        for (size_t s = 0; s + 1 < ns; s++) {
            const thx_dicom_entry *a = sl[s].e, *b = sl[s + 1].e;
            double g = sl[s + 1].d - sl[s].d;
            if (g < DUPLICATE_MM) {
                free(gaps);
                return thx_error(ctx, THX_EINPUT,
                                 "%s and %s: two slices at one position (%g, %g, %g) along the normal (two echoes, "
                                 "phases or acquisitions in one series?)",
                                 a->file, b->file, b->position[0], b->position[1], b->position[2]);
            }
            gaps[s] = g;
        }
        /* the line of positions: the stack's lean (first -> last against n), then each position's
         * distance from that line */
        {
            const thx_dicom_entry *a = sl[0].e, *b = sl[ns - 1].e;
            double span = sl[ns - 1].d - sl[0].d, off[3];
            for (int q = 0; q < 3; q++) off[q] = (b->position[q] - a->position[q]) - span * nrm[q];
            double lean = atan2(sqrt(off[0] * off[0] + off[1] * off[1] + off[2] * off[2]), span) * 180.0 / M_PI;
            if (lean > TILT_DEG) {
                free(gaps);
                return thx_error(ctx, THX_EINPUT,
                                 "%s (%g, %g, %g) -> %s (%g, %g, %g): the stack of slices leans %.2f degrees off their "
                                 "normal (a gantry tilt or a sheared stack; at most %g degrees): not a box of voxels",
                                 a->file, a->position[0], a->position[1], a->position[2], b->file, b->position[0],
                                 b->position[1], b->position[2], lean, TILT_DEG);
            }
            double tol = LINE_TOL * fmin(e0->pixel_spacing[0], e0->pixel_spacing[1]);
            for (size_t s = 1; s + 1 < ns; s++) {
                const double *p = sl[s].e->position;
                double f = (sl[s].d - sl[0].d) / span, dev = 0;
                for (int q = 0; q < 3; q++) {
                    double x = p[q] - (a->position[q] + f * (b->position[q] - a->position[q]));
                    dev += x * x;
                }
                dev = sqrt(dev);
                if (dev > tol) {
                    free(gaps);
                    return thx_error(ctx, THX_EINPUT,
                                     "%s (%g, %g, %g): %g mm off the line from %s to %s (at most %g mm, a tenth of a "
                                     "pixel): the slices are not one stack",
                                     sl[s].e->file, p[0], p[1], p[2], dev, a->file, b->file, tol);
                }
            }
        }
        double *sorted = malloc((ns - 1) * sizeof *sorted);
        if (!sorted) {
            free(gaps);
            return thx_error(ctx, THX_ENOMEM, "%s: out of memory", path);
        }
        memcpy(sorted, gaps, (ns - 1) * sizeof *sorted);
        qsort(sorted, ns - 1, sizeof *sorted, dcmp);
        double median = (ns - 1) % 2 ? sorted[(ns - 1) / 2] : 0.5 * (sorted[(ns - 1) / 2 - 1] + sorted[(ns - 1) / 2]);
        free(sorted);
        for (size_t s = 0; s + 1 < ns; s++)
            if (fabs(gaps[s] - median) > GAP_TOL * median) {
                const thx_dicom_entry *a = sl[s].e, *b = sl[s + 1].e;
                double g = gaps[s];
                free(gaps);
                double ratio = g / median;
                return thx_error(ctx, THX_EINPUT,
                                 "%s (%g, %g, %g) -> %s (%g, %g, %g): %g mm between the slices, the median gap is %g mm "
                                 "(more than %g%% apart: %s)",
                                 a->file, a->position[0], a->position[1], a->position[2], b->file, b->position[0],
                                 b->position[1], b->position[2], g, median, GAP_TOL * 100,
                                 fabs(ratio - round(ratio)) < 0.05 && ratio > 1.5 ? "a slice missing?" : "uneven spacing");
            }
        free(gaps);
        step = (sl[ns - 1].d - sl[0].d) / (double)(ns - 1);
    } else {
        /* one slice: no positions to measure, the header's thickness (or 1 mm) */
        step = e0->thickness > 0 ? e0->thickness : 1.0;
    }

    /* the volume is allocated once the helper has decoded the first slice: a header claiming a huge
     * image in a small file costs nothing; each slice streams from the socket through a small
     * buffer straight into its plane */
    size_t n[3] = {e0->columns, e0->rows, ns};
    size_t plane = n[0] * n[1];
    thx_sha256_ctx hash;
    thx_sha256_init(&hash);
    int integral = 1;
    static const char doing[] = "its pixels cannot be read";
    enum { CHUNK = 1 << 16 }; /* a multiple of every stored type's size */
    /* payload() NUL-terminates what it reads: room for a whole chunk of pixels or the longest message, and one */
    unsigned char *chunk = malloc((CHUNK > THX_DICOM_MAX_MESSAGE ? CHUNK : THX_DICOM_MAX_MESSAGE) + 1);
    thx_status st = chunk ? THX_OK : thx_error(ctx, THX_ENOMEM, "%s: out of memory", path);
    for (size_t s = 0; st == THX_OK && s < ns; s++) {
        const thx_dicom_entry *e = sl[s].e;
        int32_t status;
        uint64_t len;
        struct timespec deadline;
        if ((st = ask(ctx, h, THX_DICOM_OP_PIXELS, e->rows, e->columns, e->file, doing, &status, &len, &deadline)) != THX_OK)
            break;
        if (status != 0) {
            if ((st = payload(ctx, h, chunk, (size_t)len, e->file, doing, &deadline)) == THX_OK)
                st = helper_message(ctx, chunk, (size_t)len, e->file);
            break;
        }
        if ((st = payload(ctx, h, chunk, 12, e->file, doing, &deadline)) != THX_OK) break;
        uint32_t head[3];
        memcpy(head, chunk, 12);
        const char *bad = NULL;
        if (head[0] < THX_DICOM_T_UINT8 || head[0] > THX_DICOM_T_FLOAT64) bad = "an unknown stored type";
        else if (head[1] != e->rows || head[2] != e->columns) bad = "pixels of another size than asked for";
        else if (len - 12 != (uint64_t)plane * type_size[head[0]]) bad = "a pixel count that is not rows x columns";
        if (bad) {
            char how[200];
            helper_stop(h, 1, how, sizeof how);
            st = thx_error(ctx, THX_EIO, "%s: %s: the DICOM helper's reply is garbled (%s: type %u, %u x %u, %llu bytes)",
                           e->file, doing, bad, head[0], head[1], head[2], (unsigned long long)len);
            break;
        }
        if (!img->v && (st = thx_image_alloc(ctx, n, img)) != THX_OK) {
            char how[200];
            helper_stop(h, 1, how, sizeof how);
            break;
        }
        int type = (int)head[0];
        double slope = e->slope, inter = e->intercept;
        float *dst = img->v + s * plane;
        for (size_t done = 0; done < plane;) {
            size_t count = plane - done < CHUNK / type_size[type] ? plane - done : CHUNK / type_size[type];
            if ((st = payload(ctx, h, chunk, count * type_size[type], e->file, doing, &deadline)) != THX_OK) break;
            convert(chunk, count, type, slope, inter, dst + done);
            done += count;
        }
        if (st != THX_OK) break;
        if (s == 0) snprintf(img->stored_type, sizeof img->stored_type, "%s", type_name[type]);
        else if (strcmp(type_name[type], img->stored_type) != 0) snprintf(img->stored_type, sizeof img->stored_type, "mixed");
        if (type >= THX_DICOM_T_FLOAT32 || slope != floor(slope) || inter != floor(inter)) integral = 0;
        char hex[65];
        st = thx_sha256_file(ctx, e->file, hex);
        if (st == THX_OK) thx_sha256_update(&hash, hex, 64);
    }
    free(chunk);
    if (st != THX_OK) {
        thx_image_free(img);
        return st;
    }
    unsigned char digest[32];
    thx_sha256_final(&hash, digest);
    for (int b = 0; b < 32; b++) snprintf(img->sha256 + 2 * b, 3, "%02x", digest[b]);
    img->integral = integral;
    img->spacing[0] = e0->pixel_spacing[1]; /* PixelSpacing: between rows (along j), then between columns (along i) */
    img->spacing[1] = e0->pixel_spacing[0];
    img->spacing[2] = step;
    /* LPS -> RAS: negate x and y */
    const double flip[3] = {-1, -1, 1};
    const double *p0 = sl[0].e->position;
    for (int a = 0; a < 3; a++) {
        img->origin[a] = flip[a] * p0[a];
        img->dir[a * 3 + 0] = flip[a] * r[a];
        img->dir[a * 3 + 1] = flip[a] * c[a];
        img->dir[a * 3 + 2] = flip[a] * nrm[a];
    }
    snprintf(img->format, sizeof img->format, "dicom");
    snprintf(img->source_frame, sizeof img->source_frame, "LPS (DICOM patient)");
    return THX_OK;
}

thx_status thx_image_read_dicom(thx_ctx *ctx, const char *path, const char *series, thx_image *img)
{
    memset(img, 0, sizeof *img);
    struct stat st;
    if (stat(path, &st) != 0) return thx_error(ctx, THX_EIO, "%s: cannot open: %s", path, strerror(errno));
    int is_dir = S_ISDIR(st.st_mode);
    char dir[1024];
    if (is_dir) {
        snprintf(dir, sizeof dir, "%s", path);
    } else {
        const char *slash = strrchr(path, '/');
        if (!slash) snprintf(dir, sizeof dir, ".");
        else if (slash == path) snprintf(dir, sizeof dir, "/");
        else snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    }
    thx_dicom_entry *all = NULL;
    size_t count = 0;
    helper h = {0, -1, 0, ""};
    char how[200];
    thx_status s = scan_folder(ctx, &h, dir, &all, &count);
    if (s != THX_OK) {
        helper_stop(&h, 1, how, sizeof how);
        return s;
    }
    series_info *list = NULL;
    slice *sl = NULL;
    /* the images only; a file given names its series */
    size_t ni = 0;
    const char *want_uid = NULL;
    for (size_t k = 0; k < count; k++) {
        if (!all[k].image) continue;
        all[ni++] = all[k];
    }
    if (!is_dir) {
        for (size_t k = 0; k < ni && !want_uid; k++) {
            struct stat so;
            if (stat(all[k].file, &so) == 0 && so.st_dev == st.st_dev && so.st_ino == st.st_ino) want_uid = all[k].series_uid;
        }
        if (!want_uid) {
            s = thx_error(ctx, THX_EINPUT, "%s: not a DICOM image GDCM can parse (no Rows/Columns, or not DICOM)", path);
            goto done;
        }
    }
    if (ni == 0) {
        s = thx_error(ctx, THX_EINPUT, "%s: no DICOM image in the folder (%zu DICOM file%s without pixels; subfolders are not searched)",
                      dir, count, count == 1 ? "" : "s");
        goto done;
    }
    list = calloc(ni, sizeof *list);
    if (!list) {
        s = thx_error(ctx, THX_ENOMEM, "%s: out of memory", dir);
        goto done;
    }
    size_t nseries = 0;
    for (size_t k = 0; k < ni; k++) {
        size_t q = 0;
        while (q < nseries && strcmp(list[q].uid, all[k].series_uid) != 0) q++;
        if (q == nseries) {
            list[q].uid = all[k].series_uid;
            list[q].number = all[k].series_number;
            list[q].description = all[k].description;
            list[q].modality = all[k].modality;
            list[q].rows = all[k].rows;
            list[q].columns = all[k].columns;
            nseries++;
        }
        list[q].slices++;
    }
    qsort(list, nseries, sizeof *list, series_cmp);
    const char *uid = NULL;
    if (series && *series) {
        if (all_digits(series)) {
            long k = strtol(series, NULL, 10);
            if (k >= 1 && (size_t)k <= nseries) uid = list[k - 1].uid;
        } else {
            for (size_t q = 0; q < nseries && !uid; q++)
                if (strcmp(list[q].uid, series) == 0) uid = list[q].uid;
        }
        if (!uid) {
            char listing[1200];
            list_series(list, nseries, listing, sizeof listing);
            s = thx_error(ctx, THX_EINPUT, "%s: no series \"%s\" (a number from 1 to %zu or a SeriesInstanceUID):%s", dir,
                          series, nseries, listing);
            goto done;
        }
        if (want_uid && strcmp(uid, want_uid) != 0) {
            s = thx_error(ctx, THX_EINPUT, "%s: the file belongs to series %s, not to the series asked for (%s)", path,
                          want_uid, series);
            goto done;
        }
    } else if (want_uid) {
        uid = want_uid;
    } else if (nseries > 1) {
        char listing[1200];
        list_series(list, nseries, listing, sizeof listing);
        s = thx_error(ctx, THX_EINPUT, "%s: %zu DICOM series in the folder; choose one with --series NUMBER or UID:%s", dir,
                      nseries, listing);
        goto done;
    } else {
        uid = list[0].uid;
    }
    size_t ns = 0;
    sl = calloc(ni, sizeof *sl);
    if (!sl) {
        s = thx_error(ctx, THX_ENOMEM, "%s: out of memory", dir);
        goto done;
    }
    for (size_t k = 0; k < ni; k++)
        if (strcmp(all[k].series_uid, uid) == 0) sl[ns++].e = &all[k];
    s = assemble(ctx, &h, path, sl, ns, img);
done:
    helper_stop(&h, s != THX_OK, how, sizeof how); /* done: it exits on the closed socket */
    free(sl);
    free(list);
    free(all);
    return s;
}
