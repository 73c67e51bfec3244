/* thx_cores_free and thx_cores_allowed (thorax/core/cores.h): the allowed count is the affinity's;
 * the free count lies between 1 and it; with as many busy child processes as allowed cores (each
 * runnable all the time) no core is free but the one the caller runs on: 1. */
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "testlib.h"
#include "thorax/core/cores.h"

int main(void)
{
    cpu_set_t set;
    CPU_ZERO(&set);
    CHECK(sched_getaffinity(0, sizeof set, &set) == 0);
    int allowed = thx_cores_allowed(), free_now = thx_cores_free();
    printf("allowed %d (affinity %d), free now %d\n", allowed, CPU_COUNT(&set), free_now);
    CHECK(allowed == CPU_COUNT(&set));
    CHECK(free_now >= 1 && free_now <= allowed);
    pid_t kids[256];
    int n = allowed < 256 ? allowed : 256;
    for (int k = 0; k < n; k++) {
        kids[k] = fork();
        if (kids[k] == 0) {
            volatile unsigned long x = 0;
            for (;;) x++; /* runnable until killed */
        }
        CHECK(kids[k] > 0);
    }
    nanosleep(&(struct timespec){0, 50000000}, NULL); /* the children running */
    int busy = thx_cores_free();
    printf("with %d busy processes beside: free %d\n", n, busy);
    CHECK(busy == 1);
    for (int k = 0; k < n; k++)
        if (kids[k] > 0) kill(kids[k], SIGKILL);
    for (int k = 0; k < n; k++)
        if (kids[k] > 0) waitpid(kids[k], NULL, 0);
    return tl_finish();
}
