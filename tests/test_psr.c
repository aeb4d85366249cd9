/* test_psr.c - primary surface replacement (src/kernel/psr.h, tr_render_config.psr): a flat
 * mirror stands behind a floor, and the camera, which sees both, moves sideways by a known
 * step between two frames.
 *
 * 1. Where the camera ray meets the mirror, the passes describe the floor seen in it: the
 *    floor's primitive, depth the length of the reflected path (the virtual point, camera +
 *    view direction x depth, mirrored back through the mirror's plane lies on the floor) and
 *    the floor's normal mirrored through the mirror.
 * 2. Reprojected into the previous frame through that virtual point, every such pixel finds
 *    its history on the same primitive: every tap that survives the consistency test is the
 *    pixel's own triangle, and all but the pixels at the image's edge keep history. (Without
 *    the replacement the passes hold the floor's own normal, facing up, which part 1 would
 *    reject.)
 * 3. Pixels that see the floor directly have the same passes either way.
 * 4. The albedo: a mirror's pixels take the floor's own; through a glass slab seen head-on
 *    (two faces, each refracting with probability 1 - F, F = 0.04 at index 1.5) the wall's
 *    albedo a is taken at the share of the light that passed both faces, k a + 1 - k with
 *    k = 0.96^2 (the reflected share is not the wall's light). With only the sky behind the
 *    slab the chain finds no surface: the passes are the slab's front face's, albedo 1. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "trac0r/scene_file.h"
#include "post/filter.h"
#include "post/recon_params.h"
#include "trac0r/trac0r.h"

#define W 64
#define H 48
#define MIRROR_Z 3.0f
#define MIRROR_Y 1.4f
/* The mirror's tilt from the vertical, towards the floor: the floor's image in it is a
 * sloping plane, whose normal is not the floor's. */
#define TILT 0.35f

static tr_scene *mirror_scene(uint32_t *floor_lo, uint32_t *floor_hi) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    CHECK(s != NULL, "%s", err.msg);
    uint32_t grey, mirror;
    CHECK(tr_scene_add_material(s, tr_material_diffuse(tr_vec3_make(0.6f, 0.5f, 0.4f)), &grey,
                                &err) == TR_OK,
          "%s", err.msg);
    CHECK(tr_scene_add_material(s, tr_material_glossy(tr_vec3_make(0.9f, 0.9f, 0.9f), 0.0f),
                                &mirror, &err) == TR_OK,
          "%s", err.msg);
    tr_shape_desc floor = tr_shape_desc_default(TR_SHAPE_PLANE);
    floor.transform.scale = tr_vec3_make(20.0f, 1.0f, 20.0f);
    floor.material = grey;
    CHECK(tr_scene_add_shape(s, &floor, &err) == TR_OK, "%s", err.msg);
    *floor_lo = 1u;
    *floor_hi = 1u + tr_scene_shape_triangle_count(s, 0);
    tr_shape_desc m = tr_shape_desc_default(TR_SHAPE_PLANE);
    m.transform.position = tr_vec3_make(0.0f, MIRROR_Y, MIRROR_Z);
    /* A plane's normal +y turned about x by -(pi/2 + TILT): (0, -sin TILT, -cos TILT). */
    m.transform.orientation = tr_vec3_make(-1.57079633f - TILT, 0.0f, 0.0f);
    /* Its lower edge below the floor: no floor behind its plane is seen past it. */
    m.transform.scale = tr_vec3_make(20.0f, 1.0f, 3.4f);
    m.material = mirror;
    CHECK(tr_scene_add_shape(s, &m, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    return s;
}

/* The mirror's unit normal and the reflection of point p through its plane. */
static tr_vec3 mirror_normal(void) {
    return tr_vec3_make(0.0f, -sinf(TILT), -cosf(TILT));
}

static tr_vec3 unmirror(tr_vec3 p) {
    const tr_vec3 m = mirror_normal();
    const float d = (p.x - 0.0f) * m.x + (p.y - MIRROR_Y) * m.y + (p.z - MIRROR_Z) * m.z;
    return tr_vec3_make(p.x - 2.0f * d * m.x, p.y - 2.0f * d * m.y, p.z - 2.0f * d * m.z);
}

/* The signed distance of point v from the mirror's plane (negative: behind it). */
static float mirror_side(tr_vec3 v) {
    const tr_vec3 m = mirror_normal();
    return v.x * m.x + (v.y - MIRROR_Y) * m.y + (v.z - MIRROR_Z) * m.z;
}

/* Whether the virtual point v (pixel ray at the depth pass) lies behind the mirror: more than
 * the jitter inside a pixel can move a point seen directly near where mirror and floor meet. */
static int behind_mirror(tr_vec3 v) {
    return mirror_side(v) < -0.05f;
}

static void camera_at(tr_camera *cam, float x) {
    tr_error err;
    CHECK(tr_camera_make(cam, tr_vec3_make(x, 1.2f, -1.0f), tr_vec3_make(0.0f, -0.12f, 1.0f),
                         tr_vec3_make(0.0f, 1.0f, 0.0f), 60.0f, 1e-3f, 1e3f, W, H, &err) == TR_OK,
          "%s", err.msg);
}

static void frame(const tr_scene *s, const tr_camera *cam, int psr, tr_gbuffer *g) {
    tr_error err;
    tr_film f;
    CHECK(tr_film_init_passes(&f, W, H, TR_PASS_ALL, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = TR_PASS_ALL;
    cfg.threads = 2;
    cfg.psr = psr;
    CHECK(tr_render_frame(s, cam, &cfg, &f, 0, NULL, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_gbuffer_init(g, W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_gbuffer_from_film(g, &f, &err) == TR_OK, "%s", err.msg);
    tr_film_free(&f);
}

/* Over the pixels of `cur` that see the floor in the mirror: how many there are, how many
 * keep history in `prev` (reprojection weight above 0.05), and how many taps that survive
 * lie on another primitive than the pixel's own (another of the floor's two triangles). */
static void reproject_mirror(const tr_camera *cam, const tr_camera *pcam, const tr_gbuffer *cur,
                             const tr_gbuffer *prev, uint32_t lo, uint32_t hi, int *seen, int *kept,
                             int *wrong) {
    *seen = *kept = *wrong = 0;
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            const size_t i = (size_t)y * W + x;
            const tr_vec3 v = tr_camera_point_at(cam, (float)x, (float)y, cur->depth[i]);
            if (!(cur->prim[i] >= lo && cur->prim[i] < hi) || !behind_mirror(v)) {
                continue;
            }
            ++*seen;
            const tr_vec3 n =
                v3(cur->normal[3 * i], cur->normal[3 * i + 1], cur->normal[3 * i + 2]);
            float w[4];
            int x0, y0;
            const float total =
                tr_post_reproject(cam, pcam, x, y, cur->depth[i], n, cur->prim[i], prev->depth,
                                  prev->normal, prev->prim, &x0, &y0, w);
            *kept += total > 0.05f;
            for (int k = 0; k < 4; ++k) {
                if (w[k] > 0.0f) {
                    const uint32_t pp = prev->prim[(y0 + (k >> 1)) * W + x0 + (k & 1)];
                    *wrong += pp != cur->prim[i];
                }
            }
        }
    }
}

/* Part 4's glass: a wall of albedo (0.2, 0.5, 0.8) at z = 3 (with `wall`; the sky
 * otherwise) behind a glass slab (faces at z = 1 and 1.1), seen head-on from z = -1 through a
 * 10-degree field of view: every ray meets both faces within 4 degrees of the normal, where F
 * is 0.04 to 1e-4. Behind the wall every pixel takes k a + 1 - k; with the sky behind, the
 * chain finds no surface, and every pixel takes the slab's front face: its primitive marked
 * curved, albedo 1, its distance along the pixel's ray, its normal towards the camera. */
static void test_glass_albedo(int wall) {
    tr_error err;
    char text[1200];
    snprintf(
        text, sizeof text,
        "{\"render\": {\"width\": 64, \"height\": 48},\n"
        " \"camera\": {\"position\": [0, 0, -1], \"direction\": [0, 0, 1], \"fov\": 10},\n"
        " \"materials\": {\"wall\": {\"type\": \"diffuse\", \"color\": [0.2, 0.5, 0.8]},\n"
        "   \"glass\": {\"type\": \"glass\", \"color\": [1, 1, 1], \"ior\": 1.5}},\n"
        " \"shapes\": [\n%s"
        "  {\"type\": \"quad\", \"vertices\": [[-2, -2, 1], [-2, 2, 1], [2, 2, 1], [2, -2, 1]],"
        " \"material\": \"glass\"},\n"
        "  {\"type\": \"quad\", \"vertices\": [[-2, -2, 1.1], [2, -2, 1.1], [2, 2, 1.1], "
        "[-2, 2, 1.1]], \"material\": \"glass\"}],\n"
        " \"environment\": {\"color\": [1, 1, 1]}}",
        wall ? "  {\"type\": \"quad\", \"vertices\": [[-5, -5, 3], [-5, 5, 3], [5, 5, 3], "
               "[5, -5, 3]], \"material\": \"wall\"},\n"
             : "");
    tr_scene *s = tr_scene_create(&err);
    CHECK(s && tr_scene_file_parse(s, "slab.json", text, strlen(text), NULL, NULL, &err) == TR_OK &&
              tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK,
          "the slab scene: %s", err.msg);
    if (!s) {
        return;
    }
    const tr_camera *cam = tr_scene_camera(s);
    tr_gbuffer g;
    frame(s, cam, 1, &g);
    const float k = wall ? 0.96f * 0.96f : 0.0f;
    const float a[3] = {0.2f, 0.5f, 0.8f};
    int through = 0, bad = 0, front = 0;
    for (size_t i = 0; i < (size_t)W * H; ++i) {
        if ((g.prim[i] & TR_PRIM_PSR_CURVED) == 0u) {
            continue;
        }
        ++through;
        for (int c = 0; c < 3; ++c) {
            bad += fabsf(g.albedo[3 * i + c] - (k * a[c] + 1.0f - k)) > 1e-3f;
        }
        if (!wall) {
            /* The point at the pass's depth along the pixel centre's ray lies on the front
             * face, to the difference between the sample's jittered ray and the centre's
             * (under 5e-4 here). */
            const uint32_t x = (uint32_t)(i % W), y = (uint32_t)(i / W);
            const tr_vec3 p = tr_camera_point_at(cam, (float)x, (float)y, g.depth[i]);
            front += fabsf(p.z - 1.0f) < 1e-3f && g.normal[3 * i + 2] < -0.999f;
        }
    }
    CHECK(through == W * H, "%d of %d pixels seen through the slab", through, W * H);
    CHECK(bad == 0, "%d albedo channels through the slab are not k a + 1 - k (k %g)", bad,
          (double)k);
    CHECK(wall || front == W * H, "%d of %d pixels on the slab's front face", front, W * H);
    tr_gbuffer_free(&g);
    tr_scene_destroy(s);
}

int main(void) {
    uint32_t lo, hi;
    tr_scene *s = mirror_scene(&lo, &hi);
    tr_camera c0, c1;
    camera_at(&c0, 0.0f);
    camera_at(&c1, 0.06f);
    tr_gbuffer g0, g1, o0, o1;
    frame(s, &c0, 1, &g0);
    frame(s, &c1, 1, &g1);
    frame(s, &c0, 0, &o0);
    frame(s, &c1, 0, &o1);

    /* 1: the virtual point behind the mirror, mirrored back through its plane, lies on the
     * floor (y = 0), and the normal is the floor's (0, 1, 0) mirrored: (I - 2 m m^T) e_y. */
    const tr_vec3 mn = mirror_normal();
    const tr_vec3 want =
        tr_vec3_make(-2.0f * mn.y * mn.x, 1.0f - 2.0f * mn.y * mn.y, -2.0f * mn.y * mn.z);
    int mirrored = 0;
    for (size_t i = 0; i < (size_t)W * H; ++i) {
        const uint32_t x = (uint32_t)(i % W), y = (uint32_t)(i / W);
        const tr_vec3 v = tr_camera_point_at(&c1, (float)x, (float)y, g1.depth[i]);
        if (!(g1.prim[i] >= lo && g1.prim[i] < hi) || !behind_mirror(v)) {
            continue;
        }
        ++mirrored;
        CHECK(g1.albedo[3 * i] == 0.6f && g1.albedo[3 * i + 1] == 0.5f &&
                  g1.albedo[3 * i + 2] == 0.4f,
              "pixel %zu: a mirror's albedo (%g, %g, %g) is not the floor's", i,
              (double)g1.albedo[3 * i], (double)g1.albedo[3 * i + 1], (double)g1.albedo[3 * i + 2]);
        const tr_vec3 real = unmirror(v);
        CHECK(fabsf(real.y) < 0.02f * g1.depth[i], "pixel %zu: the mirrored point's height %g", i,
              (double)real.y);
        CHECK(fabsf(g1.normal[3 * i] - want.x) < 1e-3f &&
                  fabsf(g1.normal[3 * i + 1] - want.y) < 1e-3f &&
                  fabsf(g1.normal[3 * i + 2] - want.z) < 1e-3f,
              "pixel %zu: normal (%g, %g, %g)", i, (double)g1.normal[3 * i],
              (double)g1.normal[3 * i + 1], (double)g1.normal[3 * i + 2]);
    }
    CHECK(mirrored > W * H / 8, "only %d pixels see the floor in the mirror", mirrored);

    /* 2: under the camera's move, every such pixel's history is on the floor. */
    int seen, kept, wrong;
    reproject_mirror(&c1, &c0, &g1, &g0, lo, hi, &seen, &kept, &wrong);
    CHECK(seen == mirrored, "%d of %d pixels", seen, mirrored);
    CHECK(wrong == 0, "%d taps on another primitive", wrong);
    /* The pixels at the mirror's edges lose their history to the move (their taps see past
     * the mirror): at most a column's worth. */
    CHECK(kept >= seen - H, "history kept by %d of %d pixels", kept, seen);

    /* Without the replacement the passes hold the floor's own normal, which faces up: not
     * the normal of the sloping plane its image lies on. */
    int seen_off, kept_off, wrong_off, unmirrored = 0;
    reproject_mirror(&c1, &c0, &o1, &o0, lo, hi, &seen_off, &kept_off, &wrong_off);
    for (size_t i = 0; i < (size_t)W * H; ++i) {
        const uint32_t x = (uint32_t)(i % W), y = (uint32_t)(i / W);
        const tr_vec3 v = tr_camera_point_at(&c1, (float)x, (float)y, o1.depth[i]);
        if (o1.prim[i] >= lo && o1.prim[i] < hi && behind_mirror(v)) {
            unmirrored += fabsf(o1.normal[3 * i + 1] - 1.0f) < 1e-3f;
        }
    }
    CHECK(seen_off == seen && unmirrored == seen, "without psr: %d pixels, %d facing up of %d",
          seen_off, unmirrored, seen);

    /* 3: what the camera sees directly is the same either way. */
    for (size_t i = 0; i < (size_t)W * H; ++i) {
        const uint32_t x = (uint32_t)(i % W), y = (uint32_t)(i / W);
        const tr_vec3 v = tr_camera_point_at(&c1, (float)x, (float)y, g1.depth[i]);
        if (!(mirror_side(v) > 0.05f) || g1.prim[i] == 0u) {
            continue;
        }
        CHECK(g1.prim[i] == o1.prim[i] && g1.depth[i] == o1.depth[i] &&
                  g1.normal[3 * i + 1] == o1.normal[3 * i + 1] &&
                  memcmp(&g1.color[3 * i], &o1.color[3 * i], 3 * sizeof(float)) == 0,
              "pixel %zu differs with psr", i);
    }
    /* The radiance of the mirror's pixels too: the replacement changes the passes only. */
    CHECK(memcmp(g1.color, o1.color, 3 * sizeof(float) * W * H) == 0, "radiance changed");
    printf("psr: %d pixels see the floor in the mirror, %d keep history (%d without psr)\n", seen,
           kept, kept_off);
    tr_gbuffer_free(&g0);
    tr_gbuffer_free(&g1);
    tr_gbuffer_free(&o0);
    tr_gbuffer_free(&o1);
    tr_scene_destroy(s);
    test_glass_albedo(1);
    test_glass_albedo(0);
    return check_finish("test_psr");
}
