/* dvec.h - double-precision vectors for tests that check the float kernel against an
 * independent computation. */
#ifndef TR_TEST_DVEC_H
#define TR_TEST_DVEC_H

#include <math.h>

#include "kernel/vec.h"

typedef struct dvec {
    double x, y, z;
} dvec;

static inline dvec dv(tr_vec3 a) {
    dvec r = {a.x, a.y, a.z};
    return r;
}
static inline dvec dsub(dvec a, dvec b) {
    dvec r = {a.x - b.x, a.y - b.y, a.z - b.z};
    return r;
}
static inline double ddot(dvec a, dvec b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline dvec dcross(dvec a, dvec b) {
    dvec r = {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
    return r;
}
static inline double dlen(dvec a) {
    return sqrt(ddot(a, a));
}
static inline dvec dnormalize(dvec a) {
    double l = dlen(a);
    dvec r = {a.x / l, a.y / l, a.z / l};
    return r;
}

#endif
