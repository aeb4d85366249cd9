/* check.h - the few assertion macros the C tests share.
 *
 * CHECK(cond, fmt, ...) records a failure with file:line and a message and goes on;
 * a test's main returns check_finish() so that every failure is reported.
 * CHECK_STATUS(rc, err, code, what) checks that a call failed with one tr_status. */
#ifndef TR_TEST_CHECK_H
#define TR_TEST_CHECK_H

#include <math.h>
#include <stdio.h>

#include "trac0r/error.h"

static int check_failures = 0;
static int check_count = 0;

#define CHECK(cond, ...)                                                                           \
    do {                                                                                           \
        ++check_count;                                                                             \
        if (!(cond)) {                                                                             \
            ++check_failures;                                                                      \
            fprintf(stderr, "%s:%d: check failed: %s: ", __FILE__, __LINE__, #cond);               \
            fprintf(stderr, __VA_ARGS__);                                                          \
            fputc('\n', stderr);                                                                   \
        }                                                                                          \
    } while (0)

/* |a - b| <= tol */
#define CHECK_NEAR(a, b, tol, what)                                                                \
    CHECK(fabs((double)(a) - (double)(b)) <= (double)(tol), "%s: %.9g vs %.9g (tol %.3g)", (what), \
          (double)(a), (double)(b), (double)(tol))

/* A call that must fail with the error code `want`: rc is what it returned, err the
 * tr_error it filled (read only when rc is TR_ERR: success leaves it unset). */
#define CHECK_STATUS(rc, err, want, what)                                                          \
    do {                                                                                           \
        const int check_rc_ = (rc);                                                                \
        const int check_set_ = check_rc_ == TR_ERR;                                                \
        CHECK(check_set_ && (err).code == (want), "%s: rc %d, %s (expected %s): %s", (what),       \
              check_rc_, check_set_ ? tr_status_name((err).code) : "no code",                      \
              tr_status_name(want), check_set_ ? (err).msg : "");                                  \
    } while (0)

/* Chi-square critical value for `dof` degrees of freedom at p = 1e-4 (Wilson-Hilferty:
 * (X/k)^(1/3) is nearly normal with mean 1 - 2/(9k) and variance 2/(9k)); for 15 to
 * 255 degrees of freedom the exact tail probability of the result is 0.89e-4 to 0.99e-4.
 * 3.719... is the upper-tail standard normal quantile for p = 1e-4. */
static inline double chi2_critical(int dof) {
    double k = (double)dof;
    double a = 2.0 / (9.0 * k);
    double c = 1.0 - a + 3.7190164854556804 * sqrt(a);
    return k * c * c * c;
}

static inline int check_finish(const char *name) {
    if (check_failures) {
        fprintf(stderr, "%s: %d of %d checks failed\n", name, check_failures, check_count);
        return 1;
    }
    printf("%s: all %d checks passed\n", name, check_count);
    return 0;
}

#endif
