/* embree.c - Intel Embree 3 as a third acceleration structure (host only).
 *
 * The scene's triangles go to Embree as one triangle geometry, in the scene's order
 * and all of them (degenerate ones included: Embree leaves triangles with non-finite
 * vertices out of its build and never hits zero-area ones), so that Embree's primID
 * is the index into tr_scene.triangles. Kept instances go through Embree's own
 * instancing: each placed prototype is a scene of its own (its triangles in its own
 * space, the same way), built once, and each instance a geometry of the top scene
 * (RTC_GEOMETRY_TYPE_INSTANCE, the instance's 3x4 matrix) whose hits report the
 * instance's first id plus the prototype's primID: the ids the CPU's two-level bvh
 * reports. Queries follow the flat structure's rules
 * (src/kernel/intersect.h): two-sided triangles, hits in the open interval
 * (tmin, tmax), u and v the barycentrics of v1 and v2.
 *
 * Each tr_embree owns its own RTCDevice. Creating one measured 0.3 to 0.8 ms the first
 * time in a process and under 0.1 ms after that (Embree 3.13.5, the Debian package),
 * nothing next to a build, and it keeps the library free of global state: there is no
 * once-initialiser to get right, errors go to the scene that caused them, and
 * tr_scene_clear releases everything Embree allocated for the scene. */
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accel/accel_internal.h"
#include "trac0r/accel.h"
#include "trac0r/render.h"

#ifdef TRAC0R_HAVE_EMBREE

#include <embree3/rtcore.h>

#include "kernel/scene_view.h"

/* Which BVH Embree builds. Measured with 10^6 random incoherent closest-hit rays on
 * one thread (2-core AMD EPYC VM, best of 5):
 *   builtin:cornell (676 triangles): LOW 7.5 Mrays/s (0.12 ms build), MEDIUM 9.2
 *   (0.16 ms), HIGH 8.7 (0.96 ms);
 *   builtin:cornell-ico-6 (82k): LOW 7.5 (3.6 ms), MEDIUM 7.7 (11 ms), HIGH 8.2 (46 ms);
 *   builtin:cornell-ico-8 (1.3M): LOW 6.4 (82 ms), MEDIUM 6.9 (216 ms), HIGH 7.3 (443 ms).
 * MEDIUM is the fastest on the benchmark scene (bench frame renders the Cornell box,
 * where HIGH also lost 5-10% FPS) and costs at most ~7% on the big meshes for half the
 * build time or less. RTC_SCENE_FLAG_ROBUST was 10-15% slower on all three. */
#define TR_EMBREE_BUILD_QUALITY RTC_BUILD_QUALITY_MEDIUM

struct tr_embree_state {
    RTCDevice device;
    RTCScene scene;   /* the scene rays are traced through (the top one, with instances) */
    RTCScene *protos; /* per prototype: its own scene once an instance places it, or NULL */
    uint32_t proto_count;
    uint32_t *first;     /* per geometry of `scene`: the id of its primitive 0 (instances) */
    uint32_t geom_count; /* entries of `first`: 1 + the instances handed over */
    float *verts;        /* the stored triangles' vertex buffer (geometry 0; Embree's memory) */
    uint32_t tri_count;  /* its triangles */
    atomic_int error_claimed; /* the first error callback to claim it writes message */
    char message[256];
};

static const char *error_name(enum RTCError code) {
    switch (code) {
    case RTC_ERROR_NONE:
        return "no error";
    case RTC_ERROR_UNKNOWN:
        return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT:
        return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION:
        return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY:
        return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU:
        return "unsupported CPU";
    case RTC_ERROR_CANCELLED:
        return "cancelled";
    }
    return "unrecognised error";
}

/* Embree calls this on the thread whose API call failed; the library must not print,
 * so the first message is kept for tr_embree_build to return. Errors that can only
 * arise while tracing (none do for well-formed scenes) are kept but not reported. */
static void on_error(void *user, enum RTCError code, const char *str) {
    struct tr_embree_state *st = user;
    if (atomic_exchange(&st->error_claimed, 1) == 0) {
        snprintf(st->message, sizeof st->message, "%s%s%s", error_name(code), str ? ": " : "",
                 str ? str : "");
    }
}

/* TR_OK, or TR_ERR with Embree's message when the device has recorded an error. */
static int check_device(struct tr_embree_state *st, const char *what, tr_error *err) {
    enum RTCError code = rtcGetDeviceError(st->device);
    if (code == RTC_ERROR_NONE) {
        return TR_OK;
    }
    return tr_error_set(
        err, code == RTC_ERROR_OUT_OF_MEMORY ? TR_STATUS_OUT_OF_MEMORY : TR_STATUS_DEVICE,
        "embree: %s failed: %s", what,
        atomic_load(&st->error_claimed) ? st->message : error_name(code));
}

/* TR_ERR with Embree's message, or with `what` alone when Embree recorded none. */
static int device_failed(struct tr_embree_state *st, const char *what, tr_error *err) {
    if (check_device(st, what, err) == TR_OK) {
        tr_error_set(err, TR_STATUS_DEVICE, "embree: %s failed", what);
    }
    return TR_ERR;
}

void tr_embree_free(tr_embree *e) {
    if (e->state) {
        /* The top scene first: its instances refer to the prototypes' scenes. */
        if (e->state->scene) {
            rtcReleaseScene(e->state->scene);
        }
        for (uint32_t i = 0; e->state->protos && i < e->state->proto_count; ++i) {
            if (e->state->protos[i]) {
                rtcReleaseScene(e->state->protos[i]);
            }
        }
        if (e->state->device) {
            rtcReleaseDevice(e->state->device);
        }
        free(e->state->protos);
        free(e->state->first);
        free(e->state);
    }
    memset(e, 0, sizeof *e);
}

/* Writes n triangles into Embree's buffers: three vertices of their own per triangle
 * (idx may be NULL when only the positions change). */
static void write_triangles(float *v, uint32_t *idx, const tr_triangle *tris, uint32_t n) {
    for (uint32_t i = 0; i < n; ++i) {
        const tr_vec3 p[3] = {tris[i].v0, tris[i].v1, tris[i].v2};
        for (int k = 0; k < 3; ++k) {
            v[9 * (size_t)i + 3 * k] = p[k].x;
            v[9 * (size_t)i + 3 * k + 1] = p[k].y;
            v[9 * (size_t)i + 3 * k + 2] = p[k].z;
            if (idx) {
                idx[3 * (size_t)i + k] = 3 * i + (uint32_t)k;
            }
        }
    }
}

/* A new scene with Embree's flags and build quality for ours. */
static RTCScene new_scene(struct tr_embree_state *st, tr_error *err) {
    RTCScene sc = rtcNewScene(st->device);
    if (!sc) {
        device_failed(st, "rtcNewScene", err);
        return NULL;
    }
    /* No RTC_SCENE_FLAG_ROBUST: the default Moller-Trumbore style intersector is what
     * the flat structure uses too (and it is faster). */
    rtcSetSceneFlags(sc, RTC_SCENE_FLAG_NONE);
    rtcSetSceneBuildQuality(sc, TR_EMBREE_BUILD_QUALITY);
    return sc;
}

/* Attaches n triangles (n > 0) to scene `sc` as its geometry 0, in their order, so that
 * Embree's primID is the index into tris. *verts (may be NULL) gets the vertex buffer. */
static int add_triangles(struct tr_embree_state *st, RTCScene sc, const tr_triangle *tris,
                         uint32_t n, float **verts, tr_error *err) {
    RTCGeometry g = rtcNewGeometry(st->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!g) {
        return device_failed(st, "rtcNewGeometry", err);
    }
    rtcSetGeometryBuildQuality(g, TR_EMBREE_BUILD_QUALITY);
    /* Embree's buffers (it pads them for its vector loads): three vertices of their own
     * per triangle, and triangle i indexing vertices 3i, 3i+1, 3i+2. */
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                       3 * sizeof(float), 3 * (size_t)n);
    uint32_t *idx = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                            3 * sizeof(uint32_t), (size_t)n);
    if (!v || !idx) {
        rtcReleaseGeometry(g);
        return device_failed(st, "rtcSetNewGeometryBuffer", err);
    }
    write_triangles(v, idx, tris, n);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(sc, g, 0);
    rtcReleaseGeometry(g); /* the scene holds its own reference */
    if (verts) {
        *verts = v;
    }
    return check_device(st, "adding the triangles", err);
}

/* Prototype p's scene, built the first time an instance places it. */
static RTCScene proto_scene(struct tr_embree_state *st, const tr_embree_proto *p, uint32_t i,
                            tr_error *err) {
    if (st->protos[i]) {
        return st->protos[i];
    }
    if (p->count > UINT32_MAX / 3) {
        tr_error_set(err, TR_STATUS_LIMIT,
                     "embree: prototype %u: %u triangles are more than Embree can index", i,
                     p->count);
        return NULL;
    }
    RTCScene sc = new_scene(st, err);
    if (!sc) {
        return NULL;
    }
    st->protos[i] = sc; /* released with the state whatever happens next */
    if (p->count > 0 && add_triangles(st, sc, p->tris, p->count, NULL, err) != TR_OK) {
        return NULL;
    }
    rtcCommitScene(sc);
    return check_device(st, "rtcCommitScene (a prototype)", err) == TR_OK ? sc : NULL;
}

int tr_embree_build_instanced(tr_embree *e, const tr_triangle *tris, uint32_t n,
                              const tr_embree_proto *protos, uint32_t proto_count,
                              const tr_embree_instance *inst, uint32_t inst_count, tr_error *err) {
    memset(e, 0, sizeof *e);
    double t0 = tr_time_now();
    /* Embree indexes vertices with 32-bit unsigned integers: three per triangle; geometry
     * ids are 32-bit too, and one is the stored triangles'. */
    if (n > UINT32_MAX / 3) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "embree: %u triangles are more than Embree can index", n);
    }
    if (inst_count >= RTC_INVALID_GEOMETRY_ID - 1u) {
        return tr_error_set(err, TR_STATUS_LIMIT, "embree: %u instances are more than Embree names",
                            inst_count);
    }
    struct tr_embree_state *st = calloc(1, sizeof *st);
    if (!st) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory building the Embree scene");
    }
    atomic_init(&st->error_claimed, 0);
    e->state = st;
    if (inst_count > 0) {
        st->protos = calloc(proto_count ? proto_count : 1, sizeof *st->protos);
        st->first = malloc(((size_t)inst_count + 1) * sizeof *st->first);
        if (!st->protos || !st->first) {
            tr_embree_free(e);
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                                "out of memory building the Embree scene over %u instances",
                                inst_count);
        }
        st->proto_count = proto_count;
        st->geom_count = inst_count + 1;
        st->first[0] = 0; /* the stored triangles: primID is the id */
    }

    st->device = rtcNewDevice(NULL);
    if (!st->device) {
        tr_error_set(err, TR_STATUS_DEVICE, "embree: could not create a device: %s",
                     error_name(rtcGetDeviceError(NULL)));
        tr_embree_free(e);
        return TR_ERR;
    }
    rtcSetDeviceErrorFunction(st->device, on_error, st);

    st->scene = new_scene(st, err);
    if (!st->scene) {
        tr_embree_free(e);
        return TR_ERR;
    }
    if (n > 0 && add_triangles(st, st->scene, tris, n, &st->verts, err) != TR_OK) {
        tr_embree_free(e);
        return TR_ERR;
    }
    st->tri_count = n;
    /* Instance k is geometry k + 1 of the top scene: RTCHit.instID[0] names it, and its
     * hits' ids are its first id plus the prototype's primID. */
    for (uint32_t k = 0; k < inst_count; ++k) {
        st->first[k + 1] = inst[k].first;
        if (inst[k].proto >= proto_count) {
            continue; /* not traced as an instance (its triangles are stored) */
        }
        RTCScene ps = proto_scene(st, &protos[inst[k].proto], inst[k].proto, err);
        if (!ps) {
            tr_embree_free(e);
            return TR_ERR;
        }
        RTCGeometry g = rtcNewGeometry(st->device, RTC_GEOMETRY_TYPE_INSTANCE);
        if (!g) {
            device_failed(st, "rtcNewGeometry (an instance)", err);
            tr_embree_free(e);
            return TR_ERR;
        }
        rtcSetGeometryInstancedScene(g, ps);
        rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, inst[k].m);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(st->scene, g, k + 1);
        rtcReleaseGeometry(g);
    }
    if (check_device(st, "adding the instances", err) != TR_OK) {
        tr_embree_free(e);
        return TR_ERR;
    }
    rtcCommitScene(st->scene);
    if (check_device(st, "rtcCommitScene", err) != TR_OK) {
        tr_embree_free(e);
        return TR_ERR;
    }
    e->scene = st->scene;
    e->first = st->first;
    e->triangle_count = n;
    e->instance_count = inst_count;
    e->build_seconds = tr_time_now() - t0;
    return TR_OK;
}

int tr_embree_build(tr_embree *e, const tr_triangle *tris, uint32_t n, tr_error *err) {
    return tr_embree_build_instanced(e, tris, n, NULL, 0, NULL, 0, err);
}

int tr_embree_set_transform(tr_embree *e, uint32_t k, const float m[12], tr_error *err) {
    struct tr_embree_state *st = e->state;
    if (!st || k + 1u >= st->geom_count) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "embree: instance %u is not in the Embree scene", k);
    }
    RTCGeometry g = rtcGetGeometry(st->scene, k + 1);
    if (!g) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "embree: instance %u is not traced as an instance", k);
    }
    rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, m);
    rtcCommitGeometry(g);
    return check_device(st, "rtcSetGeometryTransform", err);
}

int tr_embree_set_triangles(tr_embree *e, const tr_triangle *tris, uint32_t n, tr_error *err) {
    struct tr_embree_state *st = e->state;
    if (!st || n != st->tri_count) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "embree: %u triangles where the scene was built with %u", n,
                            st ? st->tri_count : 0u);
    }
    if (n == 0) {
        return TR_OK;
    }
    RTCGeometry g = rtcGetGeometry(st->scene, 0);
    write_triangles(st->verts, NULL, tris, n);
    rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0);
    rtcCommitGeometry(g);
    return check_device(st, "rtcUpdateGeometryBuffer", err);
}

int tr_embree_commit(tr_embree *e, tr_error *err) {
    if (!e->state) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION, "embree: nothing is built");
    }
    rtcCommitScene(e->state->scene);
    return check_device(e->state, "rtcCommitScene", err);
}

/* Fills Embree's ray from ours; returns 0 when no hit is possible, as the flat
 * structure would find none either.
 *
 * The interval. We report hits with tmin < t < tmax. Embree documents no promise for
 * hits exactly at tnear or tfar; this Embree (3.13.5, scene without
 * RTC_SCENE_FLAG_ROBUST) rejects t == tnear and accepts t == tfar, which
 * tests/test_embree.c checks with exactly representable hit distances. So tnear is
 * tmin itself (also for tmin = 0: a ray starting on a triangle does not hit it at
 * t = 0, as in the flat structure), and tfar is the float below tmax (FLT_MAX for an
 * infinite tmax, which keeps every finite hit, as t < inf does). Embree only accepts
 * segments starting at or after the origin: a negative tmin is taken as 0 (the kernel
 * never makes such rays; the flat structure would also report hits behind the
 * origin for them). An empty or NaN interval, a non-finite origin or direction and a
 * zero direction can hit nothing in the flat structure and are answered here without
 * asking Embree, whose traversal is undefined for them. */
static int make_ray(const tr_ray *r, struct RTCRay *out) {
    if (!(r->tmin < r->tmax && r->tmax > 0.0f)) {
        return 0;
    }
    if (!(isfinite(r->origin.x) && isfinite(r->origin.y) && isfinite(r->origin.z) &&
          isfinite(r->dir.x) && isfinite(r->dir.y) && isfinite(r->dir.z))) {
        return 0;
    }
    if (r->dir.x == 0.0f && r->dir.y == 0.0f && r->dir.z == 0.0f) {
        return 0;
    }
    out->org_x = r->origin.x;
    out->org_y = r->origin.y;
    out->org_z = r->origin.z;
    out->tnear = r->tmin > 0.0f ? r->tmin : 0.0f;
    out->dir_x = r->dir.x;
    out->dir_y = r->dir.y;
    out->dir_z = r->dir.z;
    out->time = 0.0f;
    out->tfar = nextafterf(r->tmax, -INFINITY);
    out->mask = UINT32_MAX;
    out->id = 0;
    out->flags = 0;
    return 1;
}

int tr_embree_intersect(const void *scene, const uint32_t *first, const tr_ray *ray, tr_hit *hit) {
    struct RTCRayHit rh;
    if (!make_ray(ray, &rh.ray)) {
        return 0;
    }
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx); /* single incoherent rays, no filter */
    rtcIntersect1((RTCScene)scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
        return 0;
    }
    /* Embree's triangle barycentrics are those of Moller-Trumbore:
     * p = (1 - u - v) v0 + u v1 + v v2. */
    hit->t = rh.ray.tfar;
    /* A hit through an instance names its geometry in the top scene (instID[0]) and the
     * prototype's triangle (primID); t, u and v are the same in both spaces (the ray's
     * direction is transformed, not normalised). */
    const unsigned inst = rh.hit.instID[0];
    hit->triangle = inst == RTC_INVALID_GEOMETRY_ID ? rh.hit.primID : first[inst] + rh.hit.primID;
    hit->u = rh.hit.u;
    hit->v = rh.hit.v;
    return 1;
}

int tr_embree_occluded(const void *scene, const tr_ray *ray) {
    struct RTCRay r;
    if (!make_ray(ray, &r)) {
        return 0;
    }
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    rtcOccluded1((RTCScene)scene, &ctx, &r);
    return r.tfar == -INFINITY; /* Embree's mark for "something was hit" */
}

#else /* !TRAC0R_HAVE_EMBREE */

/* Builds without Embree keep the API whole: building fails with a message. */
int tr_embree_build(tr_embree *e, const tr_triangle *tris, uint32_t n, tr_error *err) {
    (void)tris;
    (void)n;
    memset(e, 0, sizeof *e);
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "this build of trac0r has no Embree support");
}

int tr_embree_build_instanced(tr_embree *e, const tr_triangle *tris, uint32_t n,
                              const tr_embree_proto *protos, uint32_t proto_count,
                              const tr_embree_instance *inst, uint32_t inst_count, tr_error *err) {
    (void)protos;
    (void)proto_count;
    (void)inst;
    (void)inst_count;
    return tr_embree_build(e, tris, n, err);
}

int tr_embree_set_transform(tr_embree *e, uint32_t k, const float m[12], tr_error *err) {
    (void)e;
    (void)k;
    (void)m;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "this build of trac0r has no Embree support");
}

int tr_embree_set_triangles(tr_embree *e, const tr_triangle *tris, uint32_t n, tr_error *err) {
    (void)e;
    (void)tris;
    (void)n;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "this build of trac0r has no Embree support");
}

int tr_embree_commit(tr_embree *e, tr_error *err) {
    (void)e;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "this build of trac0r has no Embree support");
}

void tr_embree_free(tr_embree *e) {
    memset(e, 0, sizeof *e);
}

#endif
