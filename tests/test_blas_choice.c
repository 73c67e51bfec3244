/* thx_blas_chosen_core (thorax/core/blas_kernels.h): where OpenBLAS knows the processor, the kernels thorax's
 * shapes run fastest with, measured once and kept. In a cache directory of its own: the first call measures
 * (this program run again as a probe for each candidate) and writes blas-KEY.bin ("core NAME", then each
 * candidate's seconds, every one positive); the core it returns is one of the candidates the file names,
 * and the fastest of them unless OpenBLAS's own was within 5 %; a second call reads the file and gives the
 * same answer without measuring again (quickly); a damaged file is measured again and rewritten; a core
 * name that is not a name is not taken from the file. "Prescott" still gets thx_blas_better_core's answer;
 * a NULL core, none. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>

#include "testlib.h"
#include "thorax/core/blas_kernels.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* the path of the one blas-*.bin in dir, or "" */
static const char *choice_file(const char *dir)
{
    static char path[4200];
    path[0] = '\0';
    DIR *d = opendir(dir);
    struct dirent *e;
    while (d && (e = readdir(d)))
        if (!strncmp(e->d_name, "blas-", 5)) snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
    if (d) closedir(d);
    return path;
}

int main(int argc, char **argv)
{
    (void)argc;
    if (getenv("THORAX_BLAS_PROBE")) return thx_blas_probe_run(); /* a probe: this program run again */
    if (tl_scratch_make("test_blas_choice")) return 1;
    setenv("THORAX_CACHE_DIR", tl_path("cache"), 1);
    const char *loaded = thx_blas_loaded_core();
    CHECK(thx_blas_chosen_core(NULL, argv) == NULL);
    if (!loaded) {
        printf("the BLAS is not OpenBLAS: nothing to choose\n");
        return tl_scratch_finish("test_blas_choice");
    }
    if (!strcmp(loaded, "Prescott")) { /* OpenBLAS did not know the processor: the old rule */
        const char *c = thx_blas_chosen_core(loaded, argv), *b = thx_blas_better_core(loaded);
        CHECK((c == NULL) == (b == NULL) && (!c || !strcmp(c, b)));
        return tl_scratch_finish("test_blas_choice");
    }
    double t0 = now();
    const char *first = thx_blas_chosen_core(loaded, argv);
    double t_first = now() - t0;
    char first_name[64];
    snprintf(first_name, sizeof first_name, "%s", first ? first : loaded);
    const char *path = choice_file(tl_path("cache"));
    printf("OpenBLAS chose %s; thorax takes %s (measured in %.2f s)\n", loaded, first_name, t_first);
    if (!path[0]) { /* a processor with no other kernels to try: nothing measured, nothing kept */
        CHECK(first == NULL);
        return tl_scratch_finish("test_blas_choice");
    }
    /* the file: "core NAME", then the candidates' seconds; NAME one of them, the fastest unless OpenBLAS's own
       was within 5 % */
    FILE *f = fopen(path, "r");
    CHECK(f != NULL);
    char line[256], core[64] = "", names[3][64];
    double secs[3];
    int n = 0;
    if (f && fgets(line, sizeof line, f)) sscanf(line, "core %63s", core);
    while (f && n < 3 && fgets(line, sizeof line, f))
        if (sscanf(line, "%63s %lf s", names[n], &secs[n]) == 2) n++;
    if (f) fclose(f);
    CHECK(!strcasecmp(core, first_name) && n >= 2 && !strcasecmp(names[0], loaded));
    int best = 0, own_close = 0;
    for (int i = 0; i < n; i++) {
        printf("  %s: %.4f s\n", names[i], secs[i]);
        CHECK(secs[i] > 0);
        if (secs[i] < secs[best]) best = i;
    }
    own_close = secs[0] <= secs[best] / 0.95;
    CHECK(own_close ? !strcasecmp(core, loaded) : !strcasecmp(core, names[best]));
    /* a second call: the file's answer, no measure (a measure runs the probes: tenths of a second) */
    t0 = now();
    const char *second = thx_blas_chosen_core(loaded, argv);
    double t_second = now() - t0;
    printf("the second call: %s in %.4f s\n", second ? second : loaded, t_second);
    CHECK(!strcasecmp(second ? second : loaded, first_name) && t_second < t_first / 4);
    /* damaged: a name that is not one, then a file cut short: measured again, rewritten whole */
    tl_write_text(path, "core ../../evil\n");
    const char *third = thx_blas_chosen_core(loaded, argv);
    f = fopen(path, "r");
    CHECK(f && fgets(line, sizeof line, f) && !strncmp(line, "core ", 5) && !strstr(line, "evil"));
    if (f) fclose(f);
    CHECK(!third || strcasecmp(third, "../../evil"));
    tl_write_text(path, "core Has");
    const char *fourth = thx_blas_chosen_core(loaded, argv);
    f = fopen(path, "r");
    CHECK(f && fgets(line, sizeof line, f) && strchr(line, '\n'));
    if (f) fclose(f);
    printf("damaged files measured again: %s, %s\n", third ? third : loaded, fourth ? fourth : loaded);
    return tl_scratch_finish("test_blas_choice");
}
