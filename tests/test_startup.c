/* thx_startup_heavy (thorax/core/startup.h): a heavy command runs again once with GOMP_SPINCOUNT set to
 * THX_STARTUP_SPINCOUNT (the guard THORAX_BLAS_REEXEC set, so not a second time); a user's OMP_WAIT_POLICY or
 * GOMP_SPINCOUNT is kept, and then nothing is set. The test runs itself: the first stage checks what it was
 * given after the new execution, then starts itself again with the user's choice in its environment. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "testlib.h"
#include "thorax/core/startup.h"

int main(int argc, char **argv)
{
    thx_startup_heavy(argv); /* may execute this program again, once */
    const char *spin = getenv("GOMP_SPINCOUNT"), *guard = getenv("THORAX_BLAS_REEXEC");
    const char *preload = getenv("LD_PRELOAD");
    if (preload && strstr(preload, "vgpreload")) { /* under valgrind nothing is done: nothing to test */
        printf("under valgrind: nothing set, as documented\n");
        CHECK(!guard);
        return tl_finish();
    }
    if (argc > 1 && !strcmp(argv[1], "user")) {
        /* started with the user's own choice: kept, nothing of ours added */
        printf("user's OMP_WAIT_POLICY=%s: GOMP_SPINCOUNT %s\n", getenv("OMP_WAIT_POLICY") ? getenv("OMP_WAIT_POLICY") : "-",
               spin ? spin : "unset");
        CHECK(getenv("OMP_WAIT_POLICY") && !strcmp(getenv("OMP_WAIT_POLICY"), "active"));
        CHECK(!spin || strcmp(spin, THX_STARTUP_SPINCOUNT) != 0);
        return tl_finish();
    }
    printf("after the new execution: GOMP_SPINCOUNT %s, guard %s\n", spin ? spin : "unset", guard ? guard : "unset");
    CHECK(spin && !strcmp(spin, THX_STARTUP_SPINCOUNT) && guard);
    /* this program again, as a user who chose the wait policy would start it */
    pid_t pid = fork();
    if (pid == 0) {
        unsetenv("GOMP_SPINCOUNT");
        unsetenv("THORAX_BLAS_REEXEC");
        unsetenv("OPENBLAS_CORETYPE");
        setenv("OMP_WAIT_POLICY", "active", 1);
        char *args[] = {argv[0], "user", NULL};
        execv("/proc/self/exe", args);
        _exit(127);
    }
    int status = 0;
    CHECK(pid > 0 && waitpid(pid, &status, 0) == pid && WIFEXITED(status) && WEXITSTATUS(status) == 0);
    return tl_finish();
}
