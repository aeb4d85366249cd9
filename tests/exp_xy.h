/* exp_xy.h - the smooth test integrand of the sampler tests (test_sampler, test_sampler_z):
 * f(x, y) = exp(c x y) over the unit square, whose integral has a series. */
#ifndef TRAC0R_TESTS_EXP_XY_H
#define TRAC0R_TESTS_EXP_XY_H

/* The integral over [0,1]^2 of exp(c x y) = sum_{n>=0} c^n / (n! (n+1)^2); with c = 2 it is
 * the mean of f^2 for c = 1, so the variance of f follows too. */
static double series_exp_xy(double c) {
    double sum = 0.0, term = 1.0;
    for (int n = 0; n < 40; ++n) {
        sum += term / ((n + 1.0) * (n + 1.0));
        term *= c / (n + 1.0);
    }
    return sum;
}

#endif
