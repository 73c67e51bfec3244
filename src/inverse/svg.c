/* The L-curve as an SVG picture (thx_inverse_write_svg): log-log axes, the curve, its corner and
 * the λ used marked. */
#include <math.h>
#include <stdio.h>

#include "inverse/inverse_impl.h"
#include "thorax/core/fileio.h"

/* the curve's point nearest λ in log λ */
static size_t nearest(const thx_inverse_report *r, double lam)
{
    size_t b = 0;
    for (size_t i = 1; i < r->n_curve; i++)
        if (fabs(log(r->curve_lambda[i] / lam)) < fabs(log(r->curve_lambda[b] / lam))) b = i;
    return b;
}

thx_status thx_inverse_write_svg(thx_ctx *ctx, const thx_inverse_report *r, const char *title, const char *path)
{
    if (!r->n_curve) return thx_error(ctx, THX_EINPUT, "%s: no L-curve to draw", path);
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (size_t i = 0; i < r->n_curve; i++) {
        double x = log10(r->curve_residual[i]), y = log10(r->curve_seminorm[i]);
        if (!isfinite(x) || !isfinite(y)) continue;
        x0 = fmin(x0, x);
        x1 = fmax(x1, x);
        y0 = fmin(y0, y);
        y1 = fmax(y1, y);
    }
    if (!(x1 >= x0)) return thx_error(ctx, THX_EINPUT, "%s: the L-curve has no finite point", path);
    if (x1 - x0 < 1e-6) x1 = x0 + 1, x0 -= 1;
    if (y1 - y0 < 1e-6) y1 = y0 + 1, y0 -= 1;
    x0 = floor(x0), x1 = ceil(x1), y0 = floor(y0), y1 = ceil(y1);
    const double W = 640, H = 480, L = 80, R = 20, T = 40, B = 60;
#define PX(x) (L + ((x) - x0) / (x1 - x0) * (W - L - R))
#define PY(y) (H - B - ((y) - y0) / (y1 - y0) * (H - T - B))
    thx_atomic_file af;
    THX_CHECK(thx_atomic_open(ctx, path, &af));
    FILE *f = af.f;
    fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
               "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%g\" height=\"%g\" viewBox=\"0 0 %g %g\">\n"
               "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n", W, H, W, H);
    fprintf(f, "<text x=\"%g\" y=\"24\" font-family=\"sans-serif\" font-size=\"15\" text-anchor=\"middle\">", W / 2);
    for (const char *c = title; *c; c++) {
        if (*c == '<') fputs("&lt;", f);
        else if (*c == '&') fputs("&amp;", f);
        else fputc(*c, f);
    }
    fprintf(f, "</text>\n<g stroke=\"#ccc\" stroke-width=\"1\">\n");
    for (double x = x0; x <= x1 + 1e-9; x += 1)
        fprintf(f, "<line x1=\"%.2f\" y1=\"%g\" x2=\"%.2f\" y2=\"%g\"/>\n", PX(x), T, PX(x), H - B);
    for (double y = y0; y <= y1 + 1e-9; y += 1)
        fprintf(f, "<line x1=\"%g\" y1=\"%.2f\" x2=\"%g\" y2=\"%.2f\"/>\n", L, PY(y), W - R, PY(y));
    fprintf(f, "</g>\n<g font-family=\"sans-serif\" font-size=\"12\">\n");
    for (double x = x0; x <= x1 + 1e-9; x += 1)
        fprintf(f, "<text x=\"%.2f\" y=\"%g\" text-anchor=\"middle\">1e%d</text>\n", PX(x), H - B + 18, (int)x);
    for (double y = y0; y <= y1 + 1e-9; y += 1)
        fprintf(f, "<text x=\"%g\" y=\"%.2f\" text-anchor=\"end\">1e%d</text>\n", L - 6, PY(y) + 4, (int)y);
    fprintf(f, "<text x=\"%g\" y=\"%g\" text-anchor=\"middle\">residual norm ||A x - b||</text>\n", (L + W - R) / 2, H - 16);
    fprintf(f, "<text x=\"18\" y=\"%g\" text-anchor=\"middle\" transform=\"rotate(-90 18 %g)\">solution (semi)norm "
               "||L x||</text>\n</g>\n", (T + H - B) / 2, (T + H - B) / 2);
    fprintf(f, "<polyline fill=\"none\" stroke=\"#1f4e9c\" stroke-width=\"2\" points=\"");
    for (size_t i = 0; i < r->n_curve; i++) {
        double x = log10(r->curve_residual[i]), y = log10(r->curve_seminorm[i]);
        if (isfinite(x) && isfinite(y)) fprintf(f, "%.2f,%.2f ", PX(x), PY(y));
    }
    fprintf(f, "\"/>\n");
    if (isfinite(r->corner_lambda) && r->corner_lambda > 0) {
        size_t c = nearest(r, r->corner_lambda);
        double x = PX(log10(r->curve_residual[c])), y = PY(log10(r->curve_seminorm[c]));
        fprintf(f, "<circle id=\"corner\" cx=\"%.2f\" cy=\"%.2f\" r=\"7\" fill=\"none\" stroke=\"#d62728\" stroke-width=\"2.5\"/>\n"
                   "<text x=\"%.2f\" y=\"%.2f\" font-family=\"sans-serif\" font-size=\"12\" fill=\"#d62728\">corner "
                   "&#955; = %.3g</text>\n", x, y, x + 10, y - 10, r->corner_lambda);
    }
    if (isfinite(r->chosen_lambda) && r->chosen_lambda > 0) {
        size_t c = nearest(r, r->chosen_lambda);
        double x = PX(log10(r->curve_residual[c])), y = PY(log10(r->curve_seminorm[c]));
        fprintf(f, "<rect id=\"chosen\" x=\"%.2f\" y=\"%.2f\" width=\"10\" height=\"10\" fill=\"#2ca02c\"/>\n"
                   "<text x=\"%.2f\" y=\"%.2f\" font-family=\"sans-serif\" font-size=\"12\" fill=\"#2ca02c\">used "
                   "&#955; = %.3g</text>\n", x - 5, y - 5, x + 10, y + 18, r->chosen_lambda);
    }
    fprintf(f, "</svg>\n");
#undef PX
#undef PY
    return thx_atomic_commit(ctx, &af);
}
