/* Loading the solver module (thorax/core/module.h). */
#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "thorax/core/module.h"

#define MODULE_NAME "libthorax-petsc.so"
#ifndef THORAX_PETSC_MODULE_INSTALLED /* CMakeLists.txt sets these two from the install directories */
#define THORAX_PETSC_MODULE_INSTALLED "/usr/local/lib/thorax/" MODULE_NAME
#endif
#ifndef THORAX_PETSC_MODULE_FROM_BIN
#define THORAX_PETSC_MODULE_FROM_BIN "../lib/thorax/" MODULE_NAME
#endif

static pthread_once_t g_once = PTHREAD_ONCE_INIT;
static void *g_handle;
static char g_why[2048]; /* why it could not be loaded */

/* dirname(object)/rel into out; 0, or -1 (no slash, too long). */
static int beside(const char *object, const char *rel, char *out, size_t size)
{
    const char *slash = strrchr(object, '/');
    if (!slash) return -1;
    int n = snprintf(out, size, "%.*s/%s", (int)(slash - object), object, rel);
    return n > 0 && (size_t)n < size ? 0 : -1;
}

/* Appends "path: reason" to g_why. */
static void why(const char *path, const char *reason)
{
    size_t n = strlen(g_why);
    snprintf(g_why + n, sizeof g_why - n, "%s%s: %s", n ? "; " : "", path, reason);
}

/* Loads the module at path; 1 on success (g_handle set). */
static int try_load(const char *path)
{
    struct stat sb;
    if (stat(path, &sb) != 0) {
        why(path, "not found");
        return 0;
    }
    /* RTLD_GLOBAL: Open MPI loads its own plugins later, and they look for libmpi's symbols in the
     * global scope. The module itself exports only its tables' getters (a version script). */
    void *h = dlopen(path, RTLD_NOW | RTLD_GLOBAL);
    if (!h) {
        const char *e = dlerror();
        size_t n = strlen(path);
        if (e && strncmp(e, path, n) == 0 && strncmp(e + n, ": ", 2) == 0) e += n + 2; /* the path once */
        why(path, e ? e : "dlopen failed");
        return 0;
    }
    if (!dlsym(h, "thx_fem_petsc_get")) {
        why(path, "not thorax's solver module (no thx_fem_petsc_get)");
        dlclose(h);
        return 0;
    }
    g_handle = h; /* never closed: PETSc and MPI cannot be unloaded and loaded again */
    return 1;
}

int thx_shipped_paths(const char *from_lib, const char *const *from_bin, int n_bin, const char *installed, char *out,
                      size_t size, int max)
{
    int nc = 0;
    char exe[1024];
    ssize_t ne = readlink("/proc/self/exe", exe, sizeof exe - 1);
    exe[ne > 0 ? ne : 0] = '\0';
    Dl_info info;
    if (nc < max && from_lib && dladdr((void *)thx_shipped_paths, &info) && info.dli_fname &&
        strcmp(info.dli_fname, exe) != 0 && beside(info.dli_fname, from_lib, out + (size_t)nc * size, size) == 0)
        nc++;
    for (int i = 0; i < n_bin && ne > 0; i++)
        if (nc < max && beside(exe, from_bin[i], out + (size_t)nc * size, size) == 0) nc++;
    if (nc < max && installed) snprintf(out + (size_t)nc++ * size, size, "%s", installed);
    return nc;
}

/* $THORAX_PETSC_MODULE alone when set; else LIBDIR/thorax/ beside libthorax.so (the build tree puts
 * the module in thorax/ beside its libthorax.so), then from the program (installed: BINDIR's way to
 * LIBDIR/thorax/; the build tree's bin/ and tests/: ../thorax/), then the configured install path. */
static void load(void)
{
    const char *env = getenv("THORAX_PETSC_MODULE");
    if (env && *env) {
        try_load(env);
        return;
    }
    char cand[4][1100];
    const char *from_bin[] = {THORAX_PETSC_MODULE_FROM_BIN, "../thorax/" MODULE_NAME};
    int nc = thx_shipped_paths("thorax/" MODULE_NAME, from_bin, 2, THORAX_PETSC_MODULE_INSTALLED, cand[0], sizeof cand[0], 4);
    for (int k = 0; k < nc; k++) {
        int seen = 0;
        for (int j = 0; j < k; j++) seen |= strcmp(cand[j], cand[k]) == 0;
        if (!seen && try_load(cand[k])) return;
    }
}

void *thx_solver_module_symbol(thx_ctx *ctx, const char *name)
{
    pthread_once(&g_once, load);
    void *sym = g_handle ? dlsym(g_handle, name) : NULL;
    if (!sym && ctx) {
        if (g_handle)
            thx_error(ctx, THX_ESOLVER, "the solver module " MODULE_NAME " has no %s: it was built for another version of thorax", name);
        else
            thx_error(ctx, THX_ESOLVER,
                      "the solver module " MODULE_NAME " (PETSc and MPI) could not be loaded (%s): install thorax "
                      "(cmake --install) or set THORAX_PETSC_MODULE to the module's path",
                      g_why);
    }
    return sym;
}

const void *thx_solver_module_table(thx_ctx *ctx, const char *getter, int abi, const void *volatile *cache)
{
    static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
    pthread_mutex_lock(&lock);
    if (!*cache) {
        const void *(*get)(void) = (const void *(*)(void))thx_solver_module_symbol(ctx, getter);
        const int *t = get ? (const int *)get() : NULL; /* every table begins with `int abi` */
        if (t && *t == abi)
            *cache = t;
        else if (t && ctx)
            thx_error(ctx, THX_ESOLVER, "the solver module " MODULE_NAME " was built for another version of thorax");
    }
    const void *r = *cache;
    pthread_mutex_unlock(&lock);
    return r;
}
