/* thorax-dicom: the helper program in which GDCM reads DICOM files for the library (src/image/dicom.c
 * starts it; docs/design/image.md, "The DICOM helper program"). Not for people: it speaks the binary
 * protocol of src/image/dicom.h on file descriptor 3 and exits when the socket closes.
 *
 *   thorax-dicom --protocol 1 --memory-mb MB --seconds S
 *
 * Debian's GDCM aborts on some truncated files (its assert()s are on): here that ends this process
 * only, and the library names the file. Limits: the address space (setrlimit RLIMIT_AS, MB) and the
 * processor time of each request (RLIMIT_CPU: the time used so far + S + 1 s; the library also
 * bounds each reply's wall time and kills a late helper); the helper dies with its parent
 * (PR_SET_PDEATHSIG). Linked with GDCM (dicom_gdcm.cc) and the C library only: not with libthorax,
 * and never with the sanitizers or libFuzzer (CMakeLists.txt strips them: ASan's shadow memory
 * cannot live under an address-space limit). */
#include <errno.h>
#include <limits.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <unistd.h>

#include "image/dicom.h"

#define CHANNEL 3

static int write_all(const void *buf, size_t n)
{
    const char *p = buf;
    while (n > 0) {
        ssize_t w = write(CHANNEL, p, n);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return -1;
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

/* 1: n bytes read; 0: the socket ended before the first byte; -1: it ended within them, or an error. */
static int read_all(void *buf, size_t n)
{
    char *p = buf;
    size_t got = 0;
    while (got < n) {
        ssize_t r = read(CHANNEL, p + got, n - got);
        if (r < 0 && errno == EINTR) continue;
        if (r < 0) return -1;
        if (r == 0) return got == 0 ? 0 : -1;
        got += (size_t)r;
    }
    return 1;
}

/* A growing reply payload. */
typedef struct {
    unsigned char *b;
    size_t n, cap;
} out;

static void put(out *o, const void *p, size_t n)
{
    if (o->n + n > o->cap) {
        size_t cap = o->cap ? o->cap : 256;
        while (cap < o->n + n) cap *= 2;
        unsigned char *b = realloc(o->b, cap);
        if (!b) _exit(3);
        o->b = b;
        o->cap = cap;
    }
    memcpy(o->b + o->n, p, n);
    o->n += n;
}
static void put_u32(out *o, uint32_t v) { put(o, &v, 4); }
static void put_f64(out *o, double v) { put(o, &v, 8); }
static void put_str(out *o, const char *s)
{
    uint16_t n = (uint16_t)strnlen(s, 60000);
    put(o, &n, 2);
    put(o, s, n);
}

static int reply(uint32_t op, int32_t status, const void *a, size_t na, const void *b, size_t nb)
{
    unsigned char h[16];
    uint64_t len = (uint64_t)na + nb;
    memcpy(h, &op, 4);
    memcpy(h + 4, &status, 4);
    memcpy(h + 8, &len, 8);
    if (write_all(h, sizeof h) != 0) return -1;
    if (na && write_all(a, na) != 0) return -1;
    if (nb && write_all(b, nb) != 0) return -1;
    return 0;
}

static int reply_msg(uint32_t op, const char *msg)
{
    size_t n = strnlen(msg, THX_DICOM_MAX_MESSAGE);
    if (n == 0) msg = "GDCM failed without a message", n = strlen(msg);
    return reply(op, -1, msg, n, NULL, 0);
}

/* Allows this request S + 1 more seconds of processor time. */
static void cpu_budget(long seconds)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0) return;
    rlim_t used = (rlim_t)(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec + 1);
    struct rlimit rl = {used + (rlim_t)seconds + 1, used + (rlim_t)seconds + 2};
    setrlimit(RLIMIT_CPU, &rl);
}

static long arg_long(int argc, char **argv, const char *name)
{
    for (int k = 1; k + 1 < argc; k++)
        if (strcmp(argv[k], name) == 0) {
            char *end;
            long v = strtol(argv[k + 1], &end, 10);
            if (*end == '\0' && v > 0) return v;
        }
    return -1;
}

int main(int argc, char **argv)
{
    long version = arg_long(argc, argv, "--protocol"), mb = arg_long(argc, argv, "--memory-mb"),
         seconds = arg_long(argc, argv, "--seconds");
    if (version != THX_DICOM_PROTOCOL || mb <= 0 || seconds <= 0) {
        fprintf(stderr, "thorax-dicom: the library's DICOM helper (protocol %d on fd 3), not a command: "
                        "thorax-dicom --protocol %d --memory-mb MB --seconds S\n", THX_DICOM_PROTOCOL, THX_DICOM_PROTOCOL);
        return 2;
    }
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    signal(SIGPIPE, SIG_DFL); /* the parent gone: end here */
    if ((unsigned long)mb < ULONG_MAX / (1024ul * 1024ul)) {
        struct rlimit rl = {(rlim_t)mb * 1024 * 1024, (rlim_t)mb * 1024 * 1024};
        setrlimit(RLIMIT_AS, &rl);
    }
    unsigned char hello[12];
    uint32_t v = THX_DICOM_PROTOCOL;
    memcpy(hello, THX_DICOM_HELLO, 8);
    memcpy(hello + 8, &v, 4);
    if (write_all(hello, sizeof hello) != 0) _exit(1);

    static char path[THX_DICOM_MAX_PATH + 1];
    static char msg[THX_DICOM_MAX_MESSAGE + 1];
    for (;;) {
        uint32_t req[4];
        int r = read_all(req, sizeof req);
        if (r == 0) break; /* the parent is done */
        if (r < 0 || req[3] == 0 || req[3] > THX_DICOM_MAX_PATH) _exit(1);
        if (read_all(path, req[3]) != 1) _exit(1);
        path[req[3]] = '\0';
        if (strlen(path) != req[3]) _exit(1);
        cpu_budget(seconds);
        msg[0] = '\0';
        if (req[0] == THX_DICOM_OP_SCAN) {
            thx_dicom_entry e;
            memset(&e, 0, sizeof e);
            int st = thx_dicom_scan_file(path, &e, msg, sizeof msg);
            if (st < 0) {
                if (reply_msg(req[0], msg) != 0) _exit(1);
                continue;
            }
            out o = {0};
            if (st == 1) {
                put_str(&o, e.series_uid);
                put_str(&o, e.series_number);
                put_str(&o, e.description);
                put_str(&o, e.modality);
                put_u32(&o, (uint32_t)e.image);
                put_u32(&o, (uint32_t)e.frames);
                put_u32(&o, (uint32_t)e.has_position);
                put_u32(&o, (uint32_t)e.has_orientation);
                put_u32(&o, (uint32_t)e.has_spacing);
                for (int c = 0; c < 3; c++) put_f64(&o, e.position[c]);
                for (int c = 0; c < 6; c++) put_f64(&o, e.orientation[c]);
                for (int c = 0; c < 2; c++) put_f64(&o, e.pixel_spacing[c]);
                put_f64(&o, e.thickness);
                put_f64(&o, e.slope);
                put_f64(&o, e.intercept);
                put_u32(&o, e.rows);
                put_u32(&o, e.columns);
            }
            int w = reply(req[0], st, o.b, o.n, NULL, 0);
            free(o.b);
            if (w != 0) _exit(1);
        } else if (req[0] == THX_DICOM_OP_PIXELS) {
            void *data = NULL;
            size_t len = 0;
            int type = 0;
            if (thx_dicom_pixels(path, req[1], req[2], &data, &len, &type, msg, sizeof msg) != 0) {
                free(data);
                if (strstr(msg, "out of memory")) {
                    size_t m = strlen(msg);
                    snprintf(msg + m, sizeof msg - m, " (the helper's limit: %ld MB of address space, THORAX_DICOM_MEMORY_MB)", mb);
                }
                if (reply_msg(req[0], msg) != 0) _exit(1);
                continue;
            }
            uint32_t head[3] = {(uint32_t)type, req[1], req[2]};
            int w = reply(req[0], 0, head, sizeof head, data, len);
            free(data);
            if (w != 0) _exit(1);
        } else {
            _exit(1);
        }
    }
    return 0;
}
