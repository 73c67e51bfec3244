/*
 * Every triangle quadrature rule of src/bem (thx_bem_quad_rules: the symmetric method's 3-, 7-
 * and 12-point rules, the collocation right-hand side's edge midpoints) integrates every monomial
 * x^p y^q with p + q <= its degree exactly on the reference triangle (0,0), (1,0), (0,1), against
 * the closed form  int x^p y^q = p! q! / (p + q + 2)!,  and misses some monomial of the next
 * degree (the degree it claims is its own, not less). src/fem has no quadrature rule: its P1
 * elements are assembled in closed form (src/fem/assemble.c), so there is no tetrahedron rule to
 * test.
 */
#include <math.h>
#include <stdio.h>

#include "bem/bem_impl.h"
#include "testlib.h"

static double factorial(int n)
{
    double f = 1;
    for (int k = 2; k <= n; k++) f *= k;
    return f;
}

/* The rule's integral of x^p y^q over the reference triangle (area 1/2): x = l1, y = l2. */
static double rule_integral(const thx_bem_quad_rule *q, int p, int e)
{
    double s = 0;
    for (int i = 0; i < q->n; i++) s += q->r[i][3] * pow(q->r[i][1], p) * pow(q->r[i][2], e);
    return 0.5 * s;
}

int main(void)
{
    int n_rules = 0;
    for (const thx_bem_quad_rule *q = thx_bem_quad_rules; q->name; q++, n_rules++) {
        double sum = 0;
        for (int i = 0; i < q->n; i++) {
            /* barycentric coordinates summing to 1, inside the triangle */
            CHECK_NEAR(q->r[i][0] + q->r[i][1] + q->r[i][2], 1.0, 1e-14);
            CHECK(q->r[i][0] >= 0 && q->r[i][1] >= 0 && q->r[i][2] >= 0);
            sum += q->r[i][3];
        }
        CHECK_NEAR(sum, 1.0, 1e-14);
        double worst = 0, next = 0;
        for (int d = 0; d <= q->degree + 1; d++)
            for (int p = 0; p <= d; p++) {
                double exact = factorial(p) * factorial(d - p) / factorial(d + 2);
                double err = fabs(rule_integral(q, p, d - p) - exact) / exact;
                if (d <= q->degree) {
                    if (err > 1e-13) printf("%s: x^%d y^%d: relative error %.3g\n", q->name, p, d - p, err);
                    CHECK(err <= 1e-13);
                    if (err > worst) worst = err;
                } else if (err > next) {
                    next = err;
                }
            }
        printf("%-36s degree %d: worst relative error %.2g up to degree %d, %.2g at degree %d\n", q->name, q->degree,
               worst, q->degree, next, q->degree + 1);
        CHECK(next > 1e-6); /* not exact one degree further: the degree given is the rule's */
    }
    CHECK(n_rules == 4);
    return tl_finish();
}
