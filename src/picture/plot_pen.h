/* The plots' pen (private to src/picture): one set of drawing calls that writes either SVG
 * elements (text; one user unit = one layout unit) or pixels of an image (a layout unit = s
 * pixels). The 12-lead ECG (ecg_plot.c) and the L-curve (lcurve_plot.c) draw through it, so both
 * pictures share one line, text and mark drawing. */
#ifndef THORAX_PICTURE_PLOT_PEN_H
#define THORAX_PICTURE_PLOT_PEN_H
#include <stdio.h>

#include "thorax/render/image.h"

typedef struct {
    FILE *svg;          /* SVG: write here */
    thx_raster *img;     /* PNG: draw here */
    thx_font *fbig, *fsmall;
    double s;           /* pixels per layout unit */
} plot_pen;

typedef struct {
    unsigned char r, g, b;
} plot_rgb;

/* A line from (x0, y0) to (x1, y1), w layout units wide (at least one pixel in an image). */
void plot_line(plot_pen *p, double x0, double y0, double x1, double y1, double w, plot_rgb c);
/* Text with its baseline at y; anchor 0 start, 1 middle, 2 end; the big (bold in SVG) or the
 * small font (SVG font sizes: the layout's big and small, in layout units). */
void plot_text(plot_pen *p, double x, double y, int big, int anchor, const char *t, plot_rgb c, double svg_big,
               double svg_small);
/* A filled disc of radius rad centred on (x, y) (an image: the pixels whose centres lie within
 * rad s of the centre, so the disc's centroid is the point to a fraction of a pixel). */
void plot_disc(plot_pen *p, double x, double y, double rad, plot_rgb c);
/* A circle's outline. */
void plot_ring(plot_pen *p, double x, double y, double rad, double w, plot_rgb c);
/* t with & < > " escaped and control characters dropped. */
void plot_svg_escaped(FILE *f, const char *t);
#endif
