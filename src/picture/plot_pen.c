/* The plots' pen: SVG elements or image pixels from the same calls (plot_pen.h). */
#include "picture/plot_pen.h"

#include <math.h>

void plot_line(plot_pen *p, double x0, double y0, double x1, double y1, double w, plot_rgb c)
{
    if (p->svg)
        fprintf(p->svg, "<line x1=\"%.3f\" y1=\"%.3f\" x2=\"%.3f\" y2=\"%.3f\" stroke=\"#%02x%02x%02x\" "
                        "stroke-width=\"%.2f\"/>\n",
                x0, y0, x1, y1, c.r, c.g, c.b, w);
    else {
        unsigned char k[4] = {c.r, c.g, c.b, 255};
        thx_draw_line(p->img, x0 * p->s, y0 * p->s, x1 * p->s, y1 * p->s, fmax(1.0, w * p->s), k);
    }
}

void plot_svg_escaped(FILE *f, const char *t)
{
    for (; *t; t++) {
        if (*t == '&') fputs("&amp;", f);
        else if (*t == '<') fputs("&lt;", f);
        else if (*t == '>') fputs("&gt;", f);
        else if (*t == '"') fputs("&quot;", f);
        else if ((unsigned char)*t >= 0x20 || *t == '\t') fputc(*t, f);
    }
}

void plot_text(plot_pen *p, double x, double y, int big, int anchor, const char *t, plot_rgb c, double svg_big,
               double svg_small)
{
    if (p->svg) {
        static const char *const a[3] = {"start", "middle", "end"};
        fprintf(p->svg, "<text x=\"%.3f\" y=\"%.3f\" font-size=\"%g\"%s text-anchor=\"%s\"", x, y,
                big ? svg_big : svg_small, big ? " font-weight=\"bold\"" : "", a[anchor]);
        if (c.r || c.g || c.b) fprintf(p->svg, " fill=\"#%02x%02x%02x\"", c.r, c.g, c.b);
        fputc('>', p->svg);
        plot_svg_escaped(p->svg, t);
        fputs("</text>\n", p->svg);
    } else {
        thx_font *f = big ? p->fbig : p->fsmall;
        if (!f) return;
        unsigned char k[4] = {c.r, c.g, c.b, 255};
        int w = thx_text_width(f, t);
        int px = (int)lround(x * p->s) - (anchor == 1 ? w / 2 : anchor == 2 ? w : 0);
        thx_draw_text(p->img, f, px, (int)lround(y * p->s), t, k);
    }
}

void plot_disc(plot_pen *p, double x, double y, double rad, plot_rgb c)
{
    if (p->svg) {
        fprintf(p->svg, "<circle cx=\"%.3f\" cy=\"%.3f\" r=\"%.3f\" fill=\"#%02x%02x%02x\"/>\n", x, y, rad, c.r, c.g,
                c.b);
        return;
    }
    /* pixel (i, j) covers [i, i + 1) x [j, j + 1): its centre is (i + 0.5, j + 0.5) */
    double cx = x * p->s, cy = y * p->s, R = rad * p->s;
    int i0 = (int)floor(cx - R - 1), i1 = (int)ceil(cx + R + 1), j0 = (int)floor(cy - R - 1), j1 = (int)ceil(cy + R + 1);
    for (int j = j0; j <= j1; j++)
        for (int i = i0; i <= i1; i++) {
            if (i < 0 || j < 0 || i >= p->img->w || j >= p->img->h) continue;
            double dx = i + 0.5 - cx, dy = j + 0.5 - cy;
            if (dx * dx + dy * dy > R * R) continue;
            unsigned char *q = p->img->rgba + 4 * ((size_t)j * (size_t)p->img->w + (size_t)i);
            q[0] = c.r;
            q[1] = c.g;
            q[2] = c.b;
            q[3] = 255;
        }
}

void plot_ring(plot_pen *p, double x, double y, double rad, double w, plot_rgb c)
{
    if (p->svg) {
        fprintf(p->svg, "<circle cx=\"%.3f\" cy=\"%.3f\" r=\"%.3f\" fill=\"none\" stroke=\"#%02x%02x%02x\" "
                        "stroke-width=\"%.2f\"/>\n",
                x, y, rad, c.r, c.g, c.b, w);
        return;
    }
    const int n = 48;
    for (int k = 0; k < n; k++) {
        double a0 = 2 * M_PI * k / n, a1 = 2 * M_PI * (k + 1) / n;
        plot_line(p, x + rad * cos(a0), y + rad * sin(a0), x + rad * cos(a1), y + rad * sin(a1), w, c);
    }
}
