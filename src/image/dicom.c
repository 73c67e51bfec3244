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
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "image/image_impl.h"
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

/* ---- GDCM in a child process: Debian's GDCM keeps its assert()s, and a truncated or corrupt file
 * aborts inside it (measured on one slice cut at each length: most lengths abort). The child runs
 * the C++ calls and sends fixed-size records through a pipe; a child that dies mid-file is an error
 * naming that file. */

static int write_all(int fd, const void *buf, size_t n)
{
    const char *p = buf;
    while (n > 0) {
        ssize_t w = write(fd, p, n);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) return -1;
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

/* 1: all n bytes read; 0: the pipe ended first (the child is gone). */
static int read_all(int fd, void *buf, size_t n)
{
    char *p = buf;
    while (n > 0) {
        ssize_t r = read(fd, p, n);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) return 0;
        p += r;
        n -= (size_t)r;
    }
    return 1;
}

typedef struct {
    pid_t pid;
    int fd; /* read end */
} child;

/* Starts a child that runs fn(arg, write end) then exits; the parent reads c->fd. */
static thx_status spawn(thx_ctx *ctx, const char *what, void (*fn)(void *, int), void *arg, child *c)
{
    int p[2];
    if (pipe(p) != 0) return thx_error(ctx, THX_EIO, "%s: cannot make a pipe: %s", what, strerror(errno));
    fflush(NULL);
    pid_t pid = fork();
    if (pid < 0) {
        int e = errno;
        close(p[0]);
        close(p[1]);
        return thx_error(ctx, THX_EIO, "%s: cannot start a process to read DICOM: %s", what, strerror(e));
    }
    if (pid == 0) {
        close(p[0]);
        signal(SIGPIPE, SIG_DFL);
        /* GDCM's codecs and its assert()s print: not from the library */
        int dn = open("/dev/null", O_WRONLY);
        if (dn >= 0) {
            dup2(dn, 1);
            dup2(dn, 2);
            close(dn);
        }
        fn(arg, p[1]);
        close(p[1]);
        _exit(0);
    }
    close(p[1]);
    c->pid = pid;
    c->fd = p[0];
    return THX_OK;
}

/* Closes the pipe and collects the child; a description of how it ended into how[]. */
static void reap(child *c, char *how, size_t size)
{
    if (c->fd >= 0) close(c->fd);
    c->fd = -1;
    int st = 0;
    while (waitpid(c->pid, &st, 0) < 0 && errno == EINTR) {
    }
    if (WIFSIGNALED(st)) snprintf(how, size, "GDCM crashed on it (signal %d, %s)", WTERMSIG(st), strsignal(WTERMSIG(st)));
    else snprintf(how, size, "GDCM's process ended (status %d)", WIFEXITED(st) ? WEXITSTATUS(st) : -1);
}

typedef struct {
    int status; /* 1 DICOM, 0 not DICOM, -1 error */
    thx_dicom_entry e;
    char msg[1400];
} scan_record;

typedef struct {
    char **files;
    size_t n;
} scan_job;

static void scan_child(void *arg, int fd)
{
    const scan_job *job = arg;
    scan_record *r = malloc(sizeof *r);
    if (!r) return;
    for (size_t k = 0; k < job->n; k++) {
        memset(r, 0, sizeof *r);
        r->status = thx_dicom_scan_file(job->files[k], &r->e, r->msg, sizeof r->msg);
        if (write_all(fd, r, sizeof *r) != 0 || r->status < 0) break;
    }
    free(r);
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

/* Every file's tags, read in a child process: *entries the DICOM files (in name order). */
static thx_status scan_folder(thx_ctx *ctx, const char *dir, thx_dicom_entry **entries, size_t *count)
{
    *entries = NULL;
    *count = 0;
    char **files;
    size_t n;
    thx_status s = list_files(ctx, dir, &files, &n);
    if (s == THX_OK && n > 0) {
        *entries = malloc(n * sizeof **entries);
        scan_record *r = malloc(sizeof *r);
        child c;
        scan_job job = {files, n};
        if (!*entries || !r) s = thx_error(ctx, THX_ENOMEM, "%s: out of memory", dir);
        else s = spawn(ctx, dir, scan_child, &job, &c);
        for (size_t k = 0; s == THX_OK && k < n; k++) {
            if (!read_all(c.fd, r, sizeof *r)) {
                char how[200];
                reap(&c, how, sizeof how);
                s = thx_error(ctx, THX_EINPUT, "%s: its tags cannot be read: %s (a truncated or corrupt file?)", files[k], how);
                break;
            }
            if (r->status < 0) {
                r->msg[sizeof r->msg - 1] = '\0';
                s = thx_error(ctx, THX_EINPUT, "%s", r->msg);
            } else if (r->status == 1) {
                r->e.file[sizeof r->e.file - 1] = '\0';
                (*entries)[(*count)++] = r->e;
            }
            if (s != THX_OK || k + 1 == n) {
                char how[200];
                reap(&c, how, sizeof how);
            }
        }
        free(r);
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

typedef struct {
    int status; /* 0 or -1 */
    int integer;
    char type[16];
    char msg[1400];
} pixel_record;

typedef struct {
    const slice *sl;
    size_t ns;
} pixel_job;

static void pixel_child(void *arg, int fd)
{
    const pixel_job *job = arg;
    const thx_dicom_entry *e0 = job->sl[0].e;
    size_t plane = (size_t)e0->rows * e0->columns;
    double *buf = malloc(plane * sizeof *buf);
    pixel_record *r = malloc(sizeof *r);
    if (!buf || !r) goto out;
    for (size_t s = 0; s < job->ns; s++) {
        memset(r, 0, sizeof *r);
        const thx_dicom_entry *e = job->sl[s].e;
        r->status = thx_dicom_pixels(e->file, e->rows, e->columns, buf, r->type, &r->integer, r->msg, sizeof r->msg);
        if (write_all(fd, r, sizeof *r) != 0 || r->status != 0) break;
        if (write_all(fd, buf, plane * sizeof *buf) != 0) break;
    }
out:
    free(r);
    free(buf);
}

/* The series' slices checked, sorted and read into *img. */
static thx_status assemble(thx_ctx *ctx, const char *path, slice *sl, size_t ns, thx_image *img)
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

    /* the volume and the slice buffer are allocated once GDCM has decoded the first slice: a header
     * claiming a huge image in a small file costs nothing */
    size_t n[3] = {e0->columns, e0->rows, ns};
    size_t plane = n[0] * n[1];
    double *buf = NULL;
    thx_sha256_ctx hash;
    thx_sha256_init(&hash);
    int integral = 1;
    child ch = {0, -1};
    pixel_job job = {sl, ns};
    pixel_record *rec = malloc(sizeof *rec);
    thx_status st = rec ? spawn(ctx, path, pixel_child, &job, &ch) : thx_error(ctx, THX_ENOMEM, "%s: out of memory", path);
    for (size_t s = 0; st == THX_OK && s < ns; s++) {
        const thx_dicom_entry *e = sl[s].e;
        int got = read_all(ch.fd, rec, sizeof *rec);
        if (got && rec->status == 0 && !buf) {
            if ((st = thx_image_alloc(ctx, n, img)) != THX_OK) break;
            if (!(buf = malloc(plane * sizeof *buf))) {
                st = thx_error(ctx, THX_ENOMEM, "%s: out of memory for a slice of %u x %u", path, e0->rows, e0->columns);
                break;
            }
        }
        if (!got || (rec->status == 0 && !read_all(ch.fd, buf, plane * sizeof *buf))) {
            char how[200];
            reap(&ch, how, sizeof how);
            st = thx_error(ctx, THX_EINPUT, "%s: its pixels cannot be read: %s (a truncated or corrupt file?)", e->file, how);
            break;
        }
        if (rec->status != 0) {
            rec->msg[sizeof rec->msg - 1] = '\0';
            st = thx_error(ctx, THX_EINPUT, "%s", rec->msg);
        } else {
            rec->type[sizeof rec->type - 1] = '\0';
            if (s == 0) snprintf(img->stored_type, sizeof img->stored_type, "%s", rec->type);
            else if (strcmp(rec->type, img->stored_type) != 0) snprintf(img->stored_type, sizeof img->stored_type, "mixed");
            double slope = e->slope, inter = e->intercept;
            if (!rec->integer || slope != floor(slope) || inter != floor(inter)) integral = 0;
            float *dst = img->v + s * plane;
            for (size_t q = 0; q < plane; q++) dst[q] = (float)(slope * buf[q] + inter);
            char hex[65];
            st = thx_sha256_file(ctx, e->file, hex);
            if (st == THX_OK) thx_sha256_update(&hash, hex, 64);
        }
        if (st != THX_OK || s + 1 == ns) {
            char how[200];
            reap(&ch, how, sizeof how);
        }
    }
    if (ch.fd >= 0) {
        char how[200];
        reap(&ch, how, sizeof how);
    }
    free(rec);
    if (st != THX_OK) {
        free(buf);
        thx_image_free(img);
        return st;
    }
    free(buf);
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
    THX_CHECK(scan_folder(ctx, dir, &all, &count));

    thx_status s = THX_OK;
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
    s = assemble(ctx, path, sl, ns, img);
done:
    free(sl);
    free(list);
    free(all);
    return s;
}
