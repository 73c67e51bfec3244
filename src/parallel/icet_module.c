/*
 * Sort-last compositing by IceT (thx_par_mpi.composite, src/parallel/mpi_module.h), in the solver
 * module. IceT is Sandia's compositing library, in Debian 12 inside ParaView 5.11's packages: its
 * headers (paraview-dev) are needed to build this file's IceT code (THORAX_HAVE_ICET, set by CMake
 * when it finds them), and its libraries (paraview) only when a picture is composited: they are
 * loaded then (dlopen), so that the solver module, which every solve loads, does not need ParaView
 * at run time. $THORAX_ICET_LIBRARY names another libvtkIceTMPI (or IceTMPI) to load.
 */
#include <dlfcn.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "parallel/mpi_module.h"

int thx_par_icet_composite(int mode, int w, int h, void *color, float *depth, const int *order, char *why, size_t why_size);
void thx_par_icet_end(void);

#ifndef THORAX_HAVE_ICET

int thx_par_icet_composite(int mode, int w, int h, void *color, float *depth, const int *order, char *why, size_t why_size)
{
    snprintf(why, why_size, "this thorax was built without IceT, which sort-last compositing needs: install Debian's "
             "paraview-dev (IceT's headers; paraview, its libraries, comes with it) and build thorax again");
    return -1;
}

void thx_par_icet_end(void) {}

#else

#include <IceT.h>
#include <IceTMPI.h>

/* IceT's calls, looked up in the library once it is loaded */
static struct {
    void *lib;
    IceTCommunicator (*create_comm)(MPI_Comm);
    void (*destroy_comm)(IceTCommunicator);
    IceTContext (*create_context)(IceTCommunicator);
    void (*destroy_context)(IceTContext);
    void (*reset_tiles)(void);
    int (*add_tile)(IceTInt, IceTInt, IceTSizeType, IceTSizeType, int);
    void (*strategy)(IceTEnum);
    void (*single_image_strategy)(IceTEnum);
    void (*color_format)(IceTEnum);
    void (*depth_format)(IceTEnum);
    void (*composite_mode)(IceTEnum);
    void (*composite_order)(const IceTInt *);
    void (*enable)(IceTEnum);
    void (*disable)(IceTEnum);
    void (*diagnostics)(IceTBitField);
    IceTEnum (*get_error)(void);
    IceTImage (*composite_image)(const IceTVoid *, const IceTFloat *, const IceTInt *, const IceTDouble *,
                                 const IceTDouble *, const IceTFloat *);
    const IceTUByte *(*color_ub)(const IceTImage);
    const IceTFloat *(*color_f)(const IceTImage);
    const IceTFloat *(*depth_f)(const IceTImage);
    IceTSizeType (*n_pixels)(const IceTImage);
    IceTCommunicator comm;
    IceTContext context;
    int ready;
} g;

static int load(char *why, size_t why_size)
{
    if (g.ready) return 0;
    const char *name = getenv("THORAX_ICET_LIBRARY");
    if (!name || !*name) name = THORAX_ICET_MPI_LIBRARY;
    g.lib = dlopen(name, RTLD_NOW | RTLD_LOCAL);
    if (!g.lib) {
        snprintf(why, why_size, "IceT's library %s cannot be loaded (%s): install Debian's paraview (IceT comes with it)", name,
                 dlerror());
        return -1;
    }
    struct { void **fn; const char *sym; } syms[] = {
        {(void **)&g.create_comm, "icetCreateMPICommunicator"}, {(void **)&g.destroy_comm, "icetDestroyMPICommunicator"},
        {(void **)&g.create_context, "icetCreateContext"},      {(void **)&g.destroy_context, "icetDestroyContext"},
        {(void **)&g.reset_tiles, "icetResetTiles"},            {(void **)&g.add_tile, "icetAddTile"},
        {(void **)&g.strategy, "icetStrategy"},                 {(void **)&g.single_image_strategy, "icetSingleImageStrategy"},
        {(void **)&g.color_format, "icetSetColorFormat"},       {(void **)&g.depth_format, "icetSetDepthFormat"},
        {(void **)&g.composite_mode, "icetCompositeMode"},      {(void **)&g.composite_order, "icetCompositeOrder"},
        {(void **)&g.enable, "icetEnable"},                     {(void **)&g.disable, "icetDisable"},
        {(void **)&g.diagnostics, "icetDiagnostics"},           {(void **)&g.get_error, "icetGetError"},
        {(void **)&g.composite_image, "icetCompositeImage"},    {(void **)&g.color_ub, "icetImageGetColorcub"},
        {(void **)&g.color_f, "icetImageGetColorcf"},           {(void **)&g.depth_f, "icetImageGetDepthcf"},
        {(void **)&g.n_pixels, "icetImageGetNumPixels"},
    };
    for (size_t k = 0; k < sizeof syms / sizeof syms[0]; k++) {
        *syms[k].fn = dlsym(g.lib, syms[k].sym);
        if (!*syms[k].fn) {
            snprintf(why, why_size, "IceT's library %s has no %s: not the IceT this thorax was built with", name, syms[k].sym);
            dlclose(g.lib);
            memset(&g, 0, sizeof g);
            return -1;
        }
    }
    g.comm = g.create_comm(MPI_COMM_WORLD);
    g.context = g.create_context(g.comm);
    g.diagnostics(ICET_DIAG_OFF); /* its errors are reported here, once, by rank */
    g.ready = 1;
    return 0;
}

int thx_par_icet_composite(int mode, int w, int h, void *color, float *depth, const int *order, char *why, size_t why_size)
{
    if (load(why, why_size)) return -1;
    if (!color) return 0; /* loaded: the ranks agree before any waits in IceT */
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    g.reset_tiles();
    g.add_tile(0, 0, w, h, 0); /* one tile, the whole picture, shown by rank 0 */
    g.strategy(ICET_STRATEGY_REDUCE);
    g.single_image_strategy(ICET_SINGLE_IMAGE_STRATEGY_AUTOMATIC);
    g.disable(ICET_FLOATING_VIEWPORT);
    g.disable(ICET_INTERLACE_IMAGES); /* every pixel's result is the same; interlacing only balances */
    if (mode == THX_PAR_COMPOSITE_DEPTH) {
        g.color_format(ICET_IMAGE_COLOR_RGBA_UBYTE);
        g.depth_format(ICET_IMAGE_DEPTH_FLOAT);
        g.composite_mode(ICET_COMPOSITE_MODE_Z_BUFFER);
        g.disable(ICET_ORDERED_COMPOSITE);
        g.disable(ICET_COMPOSITE_ONE_BUFFER); /* the depth kept in the result: the caller reads what no rank drew */
    } else {
        int size = 1;
        MPI_Comm_size(MPI_COMM_WORLD, &size);
        g.color_format(ICET_IMAGE_COLOR_RGBA_FLOAT);
        g.depth_format(ICET_IMAGE_DEPTH_NONE);
        g.composite_mode(ICET_COMPOSITE_MODE_BLEND);
        g.enable(ICET_ORDERED_COMPOSITE);
        IceTInt *o = malloc((size_t)size * sizeof *o);
        if (!o) {
            snprintf(why, why_size, "out of memory (the compositing order)");
            return -1;
        }
        for (int r = 0; r < size; r++) o[r] = order[r];
        g.composite_order(o);
        free(o);
    }
    static const IceTDouble eye[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    static const IceTFloat none[4] = {0, 0, 0, 0};
    const IceTInt vp[4] = {0, 0, w, h};
    IceTImage img = g.composite_image(color, mode == THX_PAR_COMPOSITE_DEPTH ? depth : NULL, vp, eye, eye, none);
    IceTEnum e = g.get_error();
    if (e != ICET_NO_ERROR) {
        snprintf(why, why_size, "IceT could not composite the %d x %d picture (its error 0x%x)", w, h, (unsigned)e);
        return -1;
    }
    if (rank != 0) return 0;
    size_t n = (size_t)w * (size_t)h;
    const void *c = mode == THX_PAR_COMPOSITE_DEPTH ? (const void *)g.color_ub(img) : (const void *)g.color_f(img);
    if ((size_t)g.n_pixels(img) != n || !c || (mode == THX_PAR_COMPOSITE_DEPTH && !g.depth_f(img))) {
        snprintf(why, why_size, "IceT returned a picture of %ld pixels%s, where %zu were composited", (long)g.n_pixels(img),
                 c ? "" : " without colours", n);
        return -1;
    }
    if (mode == THX_PAR_COMPOSITE_DEPTH) {
        memcpy(color, g.color_ub(img), 4 * n);
        memcpy(depth, g.depth_f(img), n * sizeof *depth);
    } else {
        memcpy(color, g.color_f(img), 4 * n * sizeof(float));
    }
    return 0;
}

void thx_par_icet_end(void)
{
    if (!g.ready) return;
    g.destroy_context(g.context);
    g.destroy_comm(g.comm);
    /* the library stays loaded: IceT may have handed MPI callbacks that outlive the context */
    g.ready = 0;
}

#endif
