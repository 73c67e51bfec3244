/* OpenBLAS's kernels: on processors it does not know, and the ones thorax's own work runs fastest with
   (thorax/core/blas_kernels.h). */
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "thorax/core/blas_kernels.h"
#include "thorax/core/cache.h"
#include "thorax/core/fileio.h"
#include "thorax/core/sha256.h"

/* The processor (and the operating system) run SkylakeX's kernels: AVX-512 F, CD, BW, DQ and VL. */
static int runs_skylakex(void)
{
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") &&
           __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl");
#else
    return 0;
#endif
}

/* ... Haswell's: AVX2 and FMA. */
static int runs_haswell(void)
{
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
    return 0;
#endif
}

const char *thx_blas_better_core(const char *loaded)
{
    if (!loaded || strcmp(loaded, "Prescott") != 0) return NULL;
    if (runs_skylakex()) return "SkylakeX";
    if (runs_haswell()) return "Haswell";
    return NULL;
}

const char *thx_blas_loaded_core(void)
{
    char *(*corename)(void) = (char *(*)(void))dlsym(RTLD_DEFAULT, "openblas_get_corename");
    return corename ? corename() : NULL;
}

void dgemm_(const char *ta, const char *tb, const int *m, const int *n, const int *k, const double *alpha, const double *a,
            const int *lda, const double *b, const int *ldb, const double *beta, double *c, const int *ldc);
void dsyrk_(const char *uplo, const char *trans, const int *n, const int *k, const double *alpha, const double *a,
            const int *lda, const double *beta, double *c, const int *ldc);
void dtrsm_(const char *side, const char *uplo, const char *ta, const char *diag, const int *m, const int *n,
            const double *alpha, const double *a, const int *lda, double *b, const int *ldb);

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* One pass of the workload: the shapes of thorax's own calls (the sweeps' r ~ 150 columns of a thread
   against supernodes small and large, the fronts' triangle solves and rank updates), each repeated to
   about 4e8 flops. Returns its seconds. */
static double probe_pass(double *A, double *B, double *C)
{
    static const struct { char kind, ta, tb; int m, n, k; } w[] = {
        {'g', 'N', 'T', 150, 1500, 300}, /* forward sweep, a large supernode: X_s L21^T */
        {'g', 'N', 'N', 150, 300, 1500}, /* backward sweep, the same */
        {'g', 'N', 'T', 150, 165, 48},   /* the sweeps, a middling supernode */
        {'g', 'N', 'N', 150, 48, 165},
        {'t', 'T', 0, 150, 2000, 0},     /* the sweeps' diagonal block: X_s L11^-T */
        {'t', 'T', 0, 1000, 200, 0},     /* a front's L21 = F21 L11^-T */
        {'s', 0, 0, 1000, 200, 0},       /* a front's update matrix */
        {'g', 'N', 'T', 1500, 300, 300}, /* a front's larger products */
    };
    const double one = 1, minus = -1, zero = 0;
    double t0 = now();
    for (size_t q = 0; q < sizeof w / sizeof *w; q++) {
        const int m = w[q].m, n = w[q].n, k = w[q].k;
        double flops = w[q].kind == 'g' ? 2.0 * m * n * k : w[q].kind == 't' ? (double)m * n * n : (double)m * m * n;
        long reps = (long)(4e8 / flops) + 1;
        for (long r = 0; r < reps; r++) {
            if (w[q].kind == 'g') {
                const int lda = w[q].ta == 'N' ? m : k, ldb = w[q].tb == 'N' ? k : n;
                const char ta[2] = {w[q].ta, 0}, tb[2] = {w[q].tb, 0};
                dgemm_(ta, tb, &m, &n, &k, &one, A, &lda, B, &ldb, &zero, C, &m);
            } else if (w[q].kind == 't')
                dtrsm_("R", "L", "T", "N", &m, &n, &one, A, &n, C, &m);
            else
                dsyrk_("L", "N", &m, &n, &minus, B, &m, &one, C, &m);
        }
    }
    return now() - t0;
}

int thx_blas_probe_run(void)
{
    void (*threads)(int) = (void (*)(int))dlsym(RTLD_DEFAULT, "openblas_set_num_threads");
    if (threads) threads(1); /* thorax calls BLAS from threads of its own, each on one */
    const size_t n = (size_t)3000 * 3000;
    double *A = malloc(n * sizeof *A), *B = malloc(n * sizeof *B), *C = malloc(n * sizeof *C);
    if (!A || !B || !C) return 1;
    /* values of order 1 (no denormals, no overflow); A's diagonal large: a well-conditioned triangle */
    for (size_t i = 0; i < n; i++) {
        A[i] = 1e-3 * (double)(i % 1000);
        B[i] = 1e-3 * (double)(i % 777);
        C[i] = 1e-3 * (double)(i % 555);
    }
    for (size_t i = 0; i < 3000; i++) A[i * 3000 + i] += 1e3;
    double best = probe_pass(A, B, C);
    double again = probe_pass(A, B, C);
    best = again < best ? again : best;
    printf("%.6f\n", best);
    fflush(stdout);
    free(A);
    free(B);
    free(C);
    return 0;
}

/* The seconds of the workload with OpenBLAS's kernels `core`: this program run again as a probe
   (THORAX_BLAS_PROBE), its answer read from a pipe; a negative number when it could not be had. */
static double probe_core(char **argv, const char *core)
{
    int fd[2];
    if (pipe(fd) != 0) return -1;
    pid_t pid = fork();
    if (pid < 0) {
        close(fd[0]);
        close(fd[1]);
        return -1;
    }
    if (pid == 0) {
        close(fd[0]);
        if (dup2(fd[1], STDOUT_FILENO) < 0) _exit(127);
        setenv("OPENBLAS_CORETYPE", core, 1);
        setenv("THORAX_BLAS_PROBE", "1", 1);
        execv("/proc/self/exe", argv);
        _exit(127);
    }
    close(fd[1]);
    char buf[64];
    ssize_t got = thx_read_at(fd[0], buf, sizeof buf - 1, -1);
    buf[got > 0 ? got : 0] = '\0';
    close(fd[0]);
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
    char *end = NULL;
    double t = strtod(buf, &end);
    return WIFEXITED(status) && WEXITSTATUS(status) == 0 && end != buf && t > 0 ? t : -1;
}

/* The key of this machine's choice: OpenBLAS's build (its configuration, its version in it), the core it
   chose, and the processor's name and features as the system lists them. */
static void choice_key(const char *loaded, unsigned char key[32])
{
    thx_sha256_ctx h;
    thx_sha256_init(&h);
    static const char tag[] = "thorax OpenBLAS kernels chosen by their time on thorax's shapes, v1";
    thx_sha256_update(&h, tag, sizeof tag);
    char *(*config)(void) = (char *(*)(void))dlsym(RTLD_DEFAULT, "openblas_get_config");
    const char *cfg = config ? config() : "";
    thx_sha256_update(&h, cfg, strlen(cfg) + 1);
    thx_sha256_update(&h, loaded, strlen(loaded) + 1);
    FILE *f = fopen("/proc/cpuinfo", "r");
    char line[8192];
    int have_name = 0, have_flags = 0;
    while (f && fgets(line, sizeof line, f) && !(have_name && have_flags)) {
        if (!have_name && !strncmp(line, "model name", 10)) have_name = 1;
        else if (!have_flags && !strncmp(line, "flags", 5)) have_flags = 1;
        else continue;
        thx_sha256_update(&h, line, strlen(line));
    }
    if (f) fclose(f);
    thx_sha256_final(&h, key);
}

/* The choice kept: "core NAME" on the first line; 1 and name filled when there is one. */
static int choice_read(int fd, char *name, size_t n)
{
    char buf[512];
    ssize_t got = pread(fd, buf, sizeof buf - 1, 0);
    if (got <= 0) return 0;
    buf[got] = '\0';
    char *nl = strchr(buf, '\n');
    if (strncmp(buf, "core ", 5) || !nl || nl - (buf + 5) < 1 || (size_t)(nl - (buf + 5)) >= n) return 0;
    memcpy(name, buf + 5, (size_t)(nl - (buf + 5)));
    name[nl - (buf + 5)] = '\0';
    for (char *c = name; *c; c++)
        if (!((*c >= 'A' && *c <= 'Z') || (*c >= 'a' && *c <= 'z') || (*c >= '0' && *c <= '9'))) return 0;
    return 1;
}

const char *thx_blas_chosen_core(const char *loaded, char **argv)
{
    if (!loaded) return NULL;
    if (!strcmp(loaded, "Prescott")) return thx_blas_better_core(loaded);
    /* the candidates: the core OpenBLAS chose, and the wider and narrower vector kernels the processor runs */
    const char *cand[3] = {loaded, NULL, NULL};
    int nc = 1;
    if (runs_skylakex() && strcasecmp(loaded, "SkylakeX")) cand[nc++] = "SkylakeX";
    if (runs_haswell() && strcasecmp(loaded, "Haswell")) cand[nc++] = "Haswell";
    if (nc == 1) return NULL;
    char dir[4096], path[4200];
    if (!thx_cache_dir(dir, sizeof dir)) return NULL;
    unsigned char key[32];
    choice_key(loaded, key);
    thx_cache_path(path, sizeof path, dir, "blas", key);
    if (thx_make_dirs(dir) != 0) return NULL;
    int fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) return NULL;
    /* one process measures, the others (ranks, commands started together) wait for its answer */
    while (flock(fd, LOCK_EX) != 0 && errno == EINTR) {}
    static char name[64];
    const char *use = NULL;
    if (choice_read(fd, name, sizeof name))
        use = name;
    else {
        /* two rounds, the candidates in turn, each its shorter time: a slow moment of the machine does not
           land on one candidate alone */
        double t[3] = {-1, -1, -1};
        for (int round = 0; round < 2; round++)
            for (int i = 0; i < nc; i++) {
                double ti = probe_core(argv, cand[i]);
                if (ti > 0 && (t[i] <= 0 || ti < t[i])) t[i] = ti;
            }
        /* another core only when it is clearly faster (by 5 %): noise does not move the choice */
        int best = 0;
        for (int i = 1; i < nc; i++)
            if (t[i] > 0 && (t[0] <= 0 || t[i] < 0.95 * t[0]) && (best == 0 || t[i] < t[best])) best = i;
        if (t[best] > 0) {
            char text[512];
            int len = snprintf(text, sizeof text, "core %s\n", cand[best]);
            for (int i = 0; i < nc && len < (int)sizeof text; i++)
                len += snprintf(text + len, sizeof text - (size_t)len, "%s %.4f s\n", cand[i], t[i]);
            if (ftruncate(fd, 0) == 0 && pwrite(fd, text, strlen(text), 0) == (ssize_t)strlen(text)) {
                snprintf(name, sizeof name, "%s", cand[best]);
                use = name;
            }
        }
    }
    flock(fd, LOCK_UN);
    close(fd);
    return use && strcasecmp(use, loaded) ? use : NULL;
}
