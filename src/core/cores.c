/* How many of this process's cores are free now (thorax/core/cores.h). */
#include <dirent.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "thorax/core/cores.h"

int thx_cores_allowed(void)
{
    cpu_set_t set;
    CPU_ZERO(&set);
    if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0) return CPU_COUNT(&set);
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)n : 1;
}

/* The tasks runnable now on the machine (/proc/loadavg's "R/T"), or -1. */
static int runnable_all(void)
{
    FILE *f = fopen("/proc/loadavg", "r");
    if (!f) return -1;
    double a, b, c;
    int r = -1, t;
    if (fscanf(f, "%lf %lf %lf %d/%d", &a, &b, &c, &r, &t) != 5) r = -1;
    fclose(f);
    return r;
}

/* This process's threads that are running or runnable now (state R in /proc/self/task/N/stat). */
static int runnable_own(void)
{
    DIR *d = opendir("/proc/self/task");
    if (!d) return 1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        char path[64], line[512];
        snprintf(path, sizeof path, "/proc/self/task/%.20s/stat", e->d_name);
        FILE *f = fopen(path, "r");
        if (!f) continue;
        size_t len = fread(line, 1, sizeof line - 1, f);
        fclose(f);
        line[len] = '\0';
        const char *p = strrchr(line, ')'); /* the command may hold spaces and parentheses: the state follows the last ')' */
        n += p && p[1] == ' ' && p[2] == 'R';
    }
    closedir(d);
    return n > 0 ? n : 1;
}

static int cmp_int(const void *a, const void *b) { return *(const int *)a - *(const int *)b; }

int thx_cores_free(void)
{
    int cores = thx_cores_allowed(), others[5];
    for (int k = 0; k < 5; k++) {
        int all = runnable_all();
        if (all < 0) return cores;
        int o = all - runnable_own();
        others[k] = o > 0 ? o : 0;
        if (k < 4) nanosleep(&(struct timespec){0, 2000000}, NULL);
    }
    qsort(others, 5, sizeof *others, cmp_int);
    int free_cores = cores - others[2];
    return free_cores > 0 ? free_cores : 1;
}
