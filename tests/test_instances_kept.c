/* test_instances_kept.c - instances kept unflattened for the CPU's two-level `bvh`.
 *
 * A prototype with vertex normals, texture coordinates, a base colour map and a normal
 * map (a smooth icosphere and a textured quad) is placed by non-identity matrices (a
 * rotation with a non-uniform scale, a mirror, a shear) between shapes of the scene's own
 * (a floor, a box, a mesh with normals and UVs added after the instances); a box without
 * vertex attributes is placed twice (its triangles fall where the flattened scene pads
 * vertex indices with "none" for the later mesh), and a lamp prototype is placed once (an
 * emitting prototype: flattened when placed). Checked:
 * 1. The kept instances store no triangle: the scene stores its own shapes and the lamp
 *    instance's triangles only, and the kept ids read the triangles and vertex normals
 *    the flattened scene stores, bit for bit.
 * 2. Flattening (tr_scene_flatten, what a commit to another structure or an OpenCL upload
 *    does) leaves the very arrays that placing every instance as plain copies when it
 *    was added leaves: triangles, vertices, their indices and the shapes.
 * 3. The kept scene renders (pt and bdpt, with the primitive pass) to the bits the same
 *    scene renders to once flattened and traced by the same two levels: tolerance zero.
 *    The two-level traversal intersects the same object-space triangles with the same
 *    transformed ray either way, and the shading reads every placed triangle, normal and
 *    texture coordinate through one function (place_one, xform_normal in
 *    src/scene/instance.c) that is also what flattening stores; the library is built
 *    with -ffp-contract=off, so no call site fuses the arithmetic differently. Against
 *    the same scene traced by a one-level structure over world-space triangles the hits
 *    differ in the last bits (test_instances.c: 0.1 % in the mean).
 * 4. Ids: a kept id names its instance and primitive (tr_scene_triangle_instance), and
 *    the flattened scene's triangle for that instance and primitive is the one the id
 *    reads.
 * 5. Moving a kept instance and tr_scene_update trace what a new commit traces.
 * 6. A kept prototype whose emitter material is switched on (tr_scene_set_emittance,
 *    then tr_scene_update) is flattened so that the emitter table names its triangles.
 * 7. A scene file's triangle budget counts stored triangles: kept placements beyond it
 *    load, placements of an emitting prototype beyond it are refused (TR_STATUS_LIMIT),
 *    and a kept placement with a vertex beyond the coordinate bound is refused as a
 *    copy's is.
 * 8. Where Embree is built in, a commit to it keeps the instances too (Embree's own
 *    instancing; the stored triangle count is unchanged), and its hits on random rays,
 *    its occlusion answers and its pt render agree with the two-level bvh's within the
 *    tolerances stated at EMB_T_TOL and EMB_MEAN_TOL below, also after a kept instance,
 *    the flattened lamp and a shape of the scene's own moved (tr_scene_update). */
#define _POSIX_C_SOURCE 200809L /* mkstemp */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "kernel/kernel.h"
#include "render_film.h"
#include "scene/scene_internal.h"
#include "scene_util.h"
#include "trac0r/trac0r.h"

#define W 48u
#define H 36u

static const uint32_t checker[16] = {
    0xff2040c0u, 0xffe0e0e0u, 0xff2040c0u, 0xffe0e0e0u, 0xffe0e0e0u, 0xff20a040u,
    0xffe0e0e0u, 0xff20a040u, 0xff2040c0u, 0xffe0e0e0u, 0xff2040c0u, 0xffe0e0e0u,
    0xffe0e0e0u, 0xff20a040u, 0xffe0e0e0u, 0xff20a040u,
};
/* A tangent-space normal map tilting the shading normal two ways. */
static const uint32_t bumps[4] = {0xffff8060u, 0xffff60a0u, 0xffffa080u, 0xffff8080u};

static void placement(int k, float m[12]) {
    tr_transform tf;
    memset(&tf, 0, sizeof tf);
    switch (k % 3) {
    case 0:
        tf.position = v3(0.9f, 0.3f, -0.4f);
        tf.orientation = v3(0.3f, 0.9f, -0.2f);
        tf.scale = v3(0.5f, 0.8f, 0.6f);
        tr_transform_matrix(&tf, m);
        break;
    case 1:
        tf.position = v3(-1.0f, 0.2f, 0.5f);
        tf.orientation = v3(0.0f, -0.5f, 0.0f);
        tf.scale = v3(0.6f, 0.6f, 0.6f);
        tr_transform_matrix(&tf, m);
        m[0] = -m[0]; /* mirror x */
        m[4] = -m[4];
        m[8] = -m[8];
        break;
    default: {
        const float sh[12] = {0.4f, 0.2f,  0.0f, 0.1f, 0.0f,  0.5f,
                              0.1f, -0.2f, 0.1f, 0.0f, 0.45f, 1.0f};
        memcpy(m, sh, sizeof sh);
        break;
    }
    }
    m[3] += 0.25f * (float)(k / 3);
}

/* The scene; copies set: every placement of the tree prototype added as plain triangles
 * (tr_scene_add_prototype_copy, the flattening at addition). */
static void build(tr_scene *s, int copies) {
    tr_error err;
    tr_scene_init(s);
    uint32_t checker_tex = 0, bump_tex = 0;
    CHECK(tr_scene_add_texture(s, checker, 4, 4, 0u, &checker_tex, &err) == TR_OK &&
              tr_scene_add_texture(s, bumps, 2, 2, 0u, &bump_tex, &err) == TR_OK,
          "textures: %s", err.msg);
    uint32_t white = add_mat(s, tr_material_diffuse(v3(0.8f, 0.8f, 0.8f)));
    uint32_t red = add_mat(s, tr_material_glossy(v3(0.8f, 0.3f, 0.2f), 0.3f));
    uint32_t lamp = add_mat(s, tr_material_emitter(v3(1.0f, 1.0f, 1.0f), 8.0f));
    uint32_t painted = add_mat(s, tr_material_diffuse(v3(1.0f, 1.0f, 1.0f)));
    tr_material_ext ext = tr_material_ext_default();
    ext.base_tex = checker_tex;
    ext.normal_tex = bump_tex;
    CHECK(tr_scene_set_material_ext(s, painted, &ext, &err) == TR_OK, "ext: %s", err.msg);
    /* Prototype 0: a smooth sphere and a textured quad with vertex normals. */
    add_shape(s, TR_SHAPE_ICOSPHERE_SMOOTH, red, v3(0.0f, 0.5f, 0.0f), v3s(0.0f), v3s(0.45f));
    const float pos[12] = {-0.5f, 0.0f, 0.6f, 0.5f,  0.0f, 0.6f,
                           0.5f,  1.0f, 0.7f, -0.5f, 1.0f, 0.7f};
    const float nrm[12] = {0.0f, 0.1f,  1.0f, 0.2f,  0.0f, 1.0f,
                           0.0f, -0.1f, 1.0f, -0.2f, 0.0f, 1.0f};
    const float uv[8] = {0, 0, 2, 0, 2, 2, 0, 2};
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    CHECK(tr_scene_add_mesh_uv(s, pos, 4, idx, 2, nrm, uv, painted, NULL, NULL, &err) == TR_OK,
          "quad: %s", err.msg);
    uint32_t tree = 9, bulb = 9;
    CHECK(tr_scene_make_prototype(s, 0, &tree, &err) == TR_OK, "prototype: %s", err.msg);
    /* Prototype 1: an emitting square (placed flattened either way). */
    add_shape(s, TR_SHAPE_PLANE, lamp, v3s(0.0f), v3(3.14159265f, 0.0f, 0.0f), v3s(0.6f));
    CHECK(tr_scene_make_prototype(s, 0, &bulb, &err) == TR_OK, "lamp prototype: %s", err.msg);
    /* Prototype 2: a box without vertex attributes (flattened, its triangles fall in the
     * range that a later shape with attributes pads with "none"). */
    uint32_t crate = 9;
    add_shape(s, TR_SHAPE_BOX, white, v3(0.0f, 0.2f, 0.0f), v3s(0.0f), v3s(0.4f));
    CHECK(tr_scene_make_prototype(s, 0, &crate, &err) == TR_OK, "box prototype: %s", err.msg);
    add_shape(s, TR_SHAPE_PLANE, white, v3s(0.0f), v3s(0.0f), v3(8.0f, 1.0f, 8.0f));
    for (int k = 0; k < 6; ++k) {
        float m[12];
        placement(k, m);
        const int rc = copies ? tr_scene_add_prototype_copy(s, tree, m, &err)
                              : tr_scene_add_instance(s, tree, m, NULL, &err);
        CHECK(rc == TR_OK, "placement %d: %s", k, err.msg);
        if (k == 1 || k == 4) {
            float mb[12];
            placement(k + 1, mb);
            mb[3] -= 1.3f;
            mb[11] += 0.6f;
            const int rb = copies ? tr_scene_add_prototype_copy(s, crate, mb, &err)
                                  : tr_scene_add_instance(s, crate, mb, NULL, &err);
            CHECK(rb == TR_OK, "box: %s", err.msg);
        }
        if (k == 2) {
            const float up[12] = {1, 0, 0, 0.2f, 0, 1, 0, 3.0f, 0, 0, 1, 0.1f};
            CHECK(tr_scene_add_instance(s, bulb, up, NULL, &err) == TR_OK, "lamp: %s", err.msg);
            add_shape(s, TR_SHAPE_BOX, red, v3(1.8f, 0.3f, -1.2f), v3(0.0f, 0.4f, 0.0f), v3s(0.3f));
        }
    }
    /* A shape of the scene's own with attributes after the instances. */
    const float pos2[12] = {-2.5f, 0.0f, -1.5f, -1.5f, 0.0f, -1.5f,
                            -1.5f, 1.2f, -1.6f, -2.5f, 1.2f, -1.6f};
    CHECK(tr_scene_add_mesh_uv(s, pos2, 4, idx, 2, nrm, uv, painted, NULL, NULL, &err) == TR_OK,
          "own quad: %s", err.msg);
    tr_scene_set_environment(s, v3(0.2f, 0.25f, 0.3f), 1.0f, 0.0f, NULL, 0, 0, &err);
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3(0.0f, 1.6f, 4.0f), v3(0.0f, -0.3f, -1.0f), v3(0.0f, 1.0f, 0.0f),
                         50.0f, 0.0f, 1e30f, W, H, &err) == TR_OK,
          "camera: %s", err.msg);
    tr_scene_set_camera(s, &cam);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
}

static void storage_and_flattening(void) {
    tr_scene k, c;
    tr_error err;
    build(&k, 0);
    build(&c, 1);
    const uint32_t proto_tris = tr_scene_prototype_triangle_count(&k, 0);
    const uint32_t box_tris = tr_scene_prototype_triangle_count(&k, 2);
    CHECK(k.two_level && tr_scene_has_kept_instances(&k) &&
              k.placed_count == 6ull * proto_tris + 2ull * box_tris,
          "six kept instances (%llu placed triangles)", (unsigned long long)k.placed_count);
    CHECK(tr_scene_triangle_count(&k) == c.triangle_count &&
              tr_scene_stored_triangle_count(&k) ==
                  c.triangle_count - 6u * proto_tris - 2u * box_tris,
          "%u placed, %u stored vs %u flattened", tr_scene_triangle_count(&k), k.triangle_count,
          c.triangle_count);
    /* A kept id's triangle and normals are those of the same (instance, primitive) in the
     * flattened scene. */
    uint32_t named = 0, bad = 0;
    for (uint32_t id = k.triangle_count; id < tr_scene_triangle_count(&k); ++id) {
        uint32_t inst = 0, prim = 0;
        if (!tr_scene_triangle_instance(&k, id, &inst, &prim)) {
            bad++;
            continue;
        }
        named++;
        const uint32_t flat_id = c.shapes[k.instances[inst].shape].first + prim;
        const tr_triangle t = tr_scene_triangle(&k, id);
        tr_vec3 nk[3], nc[3];
        const int hk = tr_scene_triangle_normals(&k, id, nk);
        const int hc = tr_scene_triangle_normals(&c, flat_id, nc);
        bad += memcmp(&t, &c.triangles[flat_id], sizeof t) != 0 || hk != hc ||
               memcmp(nk, nc, sizeof nk) != 0 || k.instances[inst].flat;
    }
    CHECK(named == 6u * proto_tris + 2u * box_tris && bad == 0,
          "%u kept ids named, %u differ from the flattened triangles", named, bad);
    /* The kept scene's shapes are the flattened one's but for where their ids start. */
    CHECK(k.shape_count == c.shape_count, "%u vs %u shapes", k.shape_count, c.shape_count);
    /* Flattening writes the arrays the copies left. */
    CHECK(tr_scene_flatten(&k, &err) == TR_OK && !tr_scene_has_kept_instances(&k), "flatten: %s",
          err.msg);
    CHECK(k.triangle_count == c.triangle_count &&
              memcmp(k.triangles, c.triangles, (size_t)c.triangle_count * sizeof *c.triangles) == 0,
          "flattened triangles: %u vs %u", k.triangle_count, c.triangle_count);
    CHECK(k.vertex_count == c.vertex_count &&
              memcmp(k.vertices, c.vertices, (size_t)c.vertex_count * sizeof *c.vertices) == 0,
          "flattened vertices: %u vs %u", k.vertex_count, c.vertex_count);
    CHECK(k.tri_verts_count == c.tri_verts_count &&
              memcmp(k.tri_verts, c.tri_verts, (size_t)c.tri_verts_count * sizeof *c.tri_verts) ==
                  0,
          "flattened vertex indices: %u vs %u", k.tri_verts_count, c.tri_verts_count);
    uint32_t shape_diff = 0;
    for (uint32_t i = 0; i < c.shape_count; ++i) {
        shape_diff += memcmp(&k.shapes[i], &c.shapes[i], sizeof c.shapes[i]) != 0;
    }
    CHECK(shape_diff == 0, "%u shapes differ once flattened", shape_diff);
    uint32_t inst = 0, prim = 0;
    const uint32_t lamp_first = k.shapes[k.instances[4].shape].first;
    CHECK(tr_scene_triangle_instance(&k, lamp_first + 1, &inst, &prim) && inst == 4 && prim == 1,
          "a flattened instance's id names it (%u, %u)", inst, prim);
    tr_scene_clear(&k);
    tr_scene_clear(&c);
}

/* The kept scene against itself flattened (bvh2 commit, then bvh: the same two levels
 * over stored triangles), integrator `integ`: the same bits. */
static void same_bits(int integ, const char *name) {
    tr_scene k, f;
    tr_error err;
    build(&k, 0);
    build(&f, 0);
    CHECK(tr_scene_commit(&f, TR_ACCEL_TYPE_BVH2, &err) == TR_OK &&
              !tr_scene_has_kept_instances(&f) &&
              tr_scene_commit(&f, TR_ACCEL_TYPE_BVH, &err) == TR_OK && f.two_level,
          "%s: flattened twin: %s", name, err.msg);
    CHECK(tr_scene_has_kept_instances(&k) && k.two_level, "%s: kept", name);
    tr_film fk, ff;
    memset(&fk, 0, sizeof fk);
    memset(&ff, 0, sizeof ff);
    render_film(&k, W, H, integ, 5, TR_PASS_PRIM, 11, 0, 3, &fk);
    render_film(&f, W, H, integ, 5, TR_PASS_PRIM, 11, 0, 3, &ff);
    CHECK(fk.sum && ff.sum && memcmp(fk.sum, ff.sum, (size_t)W * H * 3 * sizeof(float)) == 0,
          "%s: radiance bit for bit", name);
    /* Ids differ (kept ones follow the stored ones; flattened ones sit where each
     * instance was added) but name the same instance and primitive, or the same own
     * triangle. */
    uint32_t kept_seen = 0, id_bad = 0, hit = 0;
    for (uint32_t i = 0; fk.prim && ff.prim && i < W * H; ++i) {
        hit += fk.prim[i] != 0;
        if ((fk.prim[i] == 0) != (ff.prim[i] == 0)) {
            id_bad++;
            continue;
        }
        if (fk.prim[i] == 0) {
            continue;
        }
        const uint32_t a = fk.prim[i] - 1, b = ff.prim[i] - 1;
        uint32_t ia, pa, ib, pb;
        const int na = tr_scene_triangle_instance(&k, a, &ia, &pa);
        const int nb = tr_scene_triangle_instance(&f, b, &ib, &pb);
        kept_seen += a >= k.triangle_count;
        const tr_triangle ta = tr_scene_triangle(&k, a), tb = tr_scene_triangle(&f, b);
        id_bad += na != nb || (na && (ia != ib || pa != pb)) || memcmp(&ta, &tb, sizeof ta) != 0;
    }
    CHECK(hit > W * H / 2 && kept_seen > W * H / 20, "%s: %u pixels hit, %u on kept instances",
          name, hit, kept_seen);
    CHECK(id_bad == 0, "%s: %u pixels name another primitive", name, id_bad);
    tr_film_free(&fk);
    tr_film_free(&ff);
    tr_scene_clear(&k);
    tr_scene_clear(&f);
}

static void refit(void) {
    tr_scene s;
    tr_error err;
    build(&s, 0);
    float m[12];
    placement(4, m);
    m[3] -= 0.6f;
    m[7] += 0.2f;
    CHECK(tr_scene_set_instance_transform(&s, 1, m, &err) == TR_OK &&
              tr_scene_update(&s, NULL, &err) == TR_OK && tr_scene_has_kept_instances(&s),
          "move and update: %s", err.msg);
    enum { N = 3000 };
    tr_hit *h1 = calloc(N, sizeof *h1), *h2 = calloc(N, sizeof *h2);
    int f1[N], f2[N];
    tr_rng r;
    for (int pass = 0; pass < 2 && h1 && h2; ++pass) {
        if (pass == 1) {
            CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
        }
        const tr_scene_view v = tr_scene_view_of(&s);
        tr_rng_init(&r, 3, 0, 0);
        for (int i = 0; i < N; ++i) {
            const tr_vec3 o = v3(tr_rng_range(&r, -3.0f, 3.0f), tr_rng_range(&r, 0.2f, 3.0f), 3.5f);
            const tr_vec3 t = v3(tr_rng_range(&r, -1.5f, 1.5f), tr_rng_range(&r, 0.0f, 1.2f),
                                 tr_rng_range(&r, -1.0f, 1.0f));
            const tr_ray ray = tr_ray_make(o, v3_normalize(v3_sub(t, o)), 0.0f, TR_INFINITY);
            if (pass == 0) {
                f1[i] = tr_intersect_scene(&v, &ray, &h1[i]);
            } else {
                f2[i] = tr_intersect_scene(&v, &ray, &h2[i]);
            }
        }
    }
    uint32_t diff = 0, hits = 0;
    for (int i = 0; h1 && h2 && i < N; ++i) {
        hits += f1[i];
        diff += f1[i] != f2[i] || (f1[i] && memcmp(&h1[i], &h2[i], sizeof h1[i]) != 0);
    }
    CHECK(hits > N / 2 && diff == 0, "refit vs rebuild: %u of %d rays differ (%u hit)", diff, N,
          hits);
    free(h1);
    free(h2);
    tr_scene_clear(&s);
}

/* Loads JSON text `text` (written to a temporary file) with a budget of `budget`
 * triangles; returns the status (TR_OK or the error's), the placed triangle count and in
 * *info (may be NULL) what the file said. */
static int load_json_info(const char *text, uint32_t budget, uint32_t *placed,
                          tr_scene_file *info) {
    const char *tmp = getenv("TMPDIR");
    char path[512];
    snprintf(path, sizeof path, "%s/trac0r-kept-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    const int fd = mkstemp(path);
    CHECK(fd >= 0, "temporary file");
    if (fd < 0) {
        return -1;
    }
    const size_t n = strlen(text);
    CHECK(write(fd, text, n) == (ssize_t)n, "write the scene");
    close(fd);
    tr_scene s;
    tr_scene_init(&s);
    tr_error err;
    tr_scene_file_options opt = {1, budget};
    const int rc = tr_scene_file_load(&s, path, &opt, info, &err);
    const int status = rc == TR_OK ? TR_OK : (int)err.code;
    *placed = tr_scene_triangle_count(&s);
    tr_scene_clear(&s);
    unlink(path);
    return status;
}

static int load_json(const char *text, uint32_t budget, uint32_t *placed) {
    return load_json_info(text, budget, placed, NULL);
}

/* A scene of kept instances alone: it loads (its placed triangles count as the scene's),
 * its material counts as used, and its bounds are the placements'. Placements are checked
 * as a whole where their prototype's box and the transform show every placed triangle
 * within the bound and of non-zero area; those that may not be are still refused. */
static void instances_only(void) {
    char text[65536];
    int len = snprintf(text, sizeof text,
                       "{\"camera\": {\"position\": [0, 2, -5], \"look_at\": [0, 0, 0], "
                       "\"fov\": 40}, \"environment\": {\"color\": [1, 1, 1]},"
                       " \"materials\": {\"w\": {\"type\": \"diffuse\", \"color\": [0.5, 0.5, "
                       "0.5]}}, \"prototypes\": {\"b\": {\"shapes\": [{\"type\": \"box\", "
                       "\"material\": \"w\"}]}}, \"instances\": [");
    for (int i = 0; i < 40; ++i) {
        /* Rotated, stretched and sheared placements, all valid. */
        len += snprintf(text + len, sizeof text - (size_t)len,
                        "%s{\"prototype\": \"b\", \"matrix\": [%g, %g, 0, %d, 0, %g, 0, 0, %g, "
                        "0, %g, 0]}",
                        i ? ", " : "", 1.0 + 0.1 * i, 0.05 * i, i, 0.5 + 0.01 * i, -0.02 * i,
                        2.0 - 0.03 * i);
    }
    char *tail = text + len;
    snprintf(tail, sizeof text - (size_t)len, "]}");
    tr_scene_file info;
    uint32_t placed = 0;
    CHECK(load_json_info(text, 0, &placed, &info) == TR_OK && placed == 40 * 12,
          "instances alone load (%u placed)", placed);
    CHECK(info.warning_count == 0, "%u warnings", info.warning_count);
    CHECK(info.bounds.min.x < 0.0f && info.bounds.max.x > 39.0f && info.bounds.max.y > 0.0f,
          "bounds x %g..%g", (double)info.bounds.min.x, (double)info.bounds.max.x);
    /* A placement so small that its triangles' areas are below what a float holds. */
    snprintf(tail, sizeof text - (size_t)len,
             ", {\"prototype\": \"b\", \"position\": [1, 0, 0], \"scale\": 1e-22}]}");
    CHECK(load_json(text, 0, &placed) == TR_STATUS_PARSE, "a vanishing placement is refused");
    /* Past the bound by a corner only: the whole-box test cannot show it, each triangle is
     * read, and the one beyond is found. */
    snprintf(tail, sizeof text - (size_t)len,
             ", {\"prototype\": \"b\", \"position\": [%.9g, 0, 0]}]}",
             TR_SCENE_FILE_MAX_COORD - 0.25);
    CHECK(load_json(text, 0, &placed) == TR_STATUS_PARSE, "a corner past the bound is refused");
}

static void budget(void) {
    /* A 12-triangle box placed 40 times: 480 placed triangles, 12 + 2 stored. */
    char text[8192];
    int len =
        snprintf(text, sizeof text,
                 "{\"camera\": {\"position\": [0, 2, -5], \"look_at\": [0, 0, 0], \"fov\": 40},"
                 " \"materials\": {\"w\": {\"type\": \"diffuse\", \"color\": [0.5, 0.5, 0.5]},"
                 " \"l\": {\"type\": \"emitter\", \"color\": [1, 1, 1], \"emittance\": 4}},"
                 " \"shapes\": [{\"type\": \"plane\", \"material\": \"w\"}],"
                 " \"prototypes\": {\"b\": {\"shapes\": [{\"type\": \"box\", \"material\": "
                 "\"%s\"}]}}, \"instances\": [",
                 "w");
    for (int i = 0; i < 40; ++i) {
        len += snprintf(text + len, sizeof text - (size_t)len,
                        "%s{\"prototype\": \"b\", \"position\": [%d, 0, 0]}", i ? ", " : "", i);
    }
    snprintf(text + len, sizeof text - (size_t)len, "]}");
    uint32_t placed = 0;
    CHECK(load_json(text, 100, &placed) == TR_OK && placed == 2 + 40 * 12,
          "kept placements beyond the budget load (%u placed)", placed);
    /* The same with an emitting box: each placement is stored, and the budget stops it. */
    char *l = strstr(text, "\"material\": \"w\"}]}}");
    CHECK(l != NULL, "the prototype's material");
    if (l) {
        l[13] = 'l';
    }
    CHECK(load_json(text, 100, &placed) == TR_STATUS_LIMIT, "emitting placements count");
    if (l) {
        l[13] = 'w';
    }
    /* A placement stretching the box past the coordinate bound: refused as a copy is (a
     * fault of the file's content: TR_STATUS_PARSE). */
    char *q = strstr(text, "{\"prototype\": \"b\", \"position\": [39, 0, 0]}");
    CHECK(q != NULL, "the last placement");
    if (q) {
        snprintf(q, sizeof text - (size_t)(q - text),
                 "{\"prototype\": \"b\", \"matrix\": [1e7, 0, 0, 1e7, 0, 1, 0, 0, 0, 0, 1, 0]}]}");
    }
    CHECK(load_json(text, 0, &placed) == TR_STATUS_PARSE,
          "a kept placement beyond the coordinate bound is refused");
}

static void switched_on(void) {
    tr_scene s;
    tr_error err;
    build(&s, 0);
    const uint32_t lights = tr_scene_light_count(&s);
    /* A dark lamp prototype (emittance 0: kept), switched on after the commit. */
    const uint32_t dark = add_mat(&s, tr_material_emitter(v3(1.0f, 0.9f, 0.8f), 0.0f));
    add_shape(&s, TR_SHAPE_PLANE, dark, v3s(0.0f), v3(3.14159265f, 0.0f, 0.0f), v3s(0.3f));
    uint32_t proto = 0;
    const float up[12] = {1, 0, 0, -1.0f, 0, 1, 0, 2.5f, 0, 0, 1, 0.0f};
    CHECK(tr_scene_make_prototype(&s, tr_scene_shape_count(&s) - 1, &proto, &err) == TR_OK &&
              tr_scene_add_instance(&s, proto, up, NULL, &err) == TR_OK &&
              tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK,
          "dark lamp: %s", err.msg);
    const uint32_t stored = tr_scene_stored_triangle_count(&s);
    CHECK(tr_scene_light_count(&s) == lights && tr_scene_has_kept_instances(&s),
          "the dark lamp is kept (%u emitters)", tr_scene_light_count(&s));
    CHECK(tr_scene_set_emittance(&s, dark, 6.0f, &err) == TR_OK &&
              tr_scene_update(&s, NULL, &err) == TR_OK && tr_scene_is_committed(&s),
          "switch on: %s", err.msg);
    CHECK(!tr_scene_has_kept_instances(&s) && tr_scene_stored_triangle_count(&s) > stored &&
              tr_scene_light_count(&s) == lights + 2 && s.two_level,
          "switched on: flattened, %u emitters (%u before)", tr_scene_light_count(&s), lights);
    tr_scene_clear(&s);
}

#ifdef TRAC0R_HAVE_EMBREE
/* ---- Embree's own instancing ---------------------------------------------------------
 *
 * A commit to TR_ACCEL_TYPE_EMBREE keeps the instances (a scene per prototype, an
 * instance geometry each) and reports the ids the two-level bvh reports. Embree's
 * ray-triangle test and its inverse of each matrix (float, from the matrix) are its own,
 * so a hit's distance agrees with the bvh's within EMB_T_TOL (relative, against
 * max(1, t)); a ray through an edge or a silhouette may be decided the other way by one
 * of the two (EMB_EDGE_FRACTION of the rays at most). */
#define EMB_RAYS 20000u
#define EMB_T_TOL 1e-4f
#define EMB_EDGE_FRACTION 0.001
/* Renders: the image means agree within EMB_MEAN_TOL (relative), and at most
 * EMB_PIXEL_FRACTION of the pixels differ by more than EMB_PIXEL_TOL (relative, any
 * channel) or name another primitive (a path that took the other side of an edge). */
#define EMB_MEAN_TOL 0.005
#define EMB_PIXEL_TOL 1e-3
#define EMB_PIXEL_FRACTION 0.02

/* Random rays: from in front of the scene at points of `aim` (the placements' region when
 * NULL), a quarter of them in a random direction, a fifth with a finite end (for the
 * occlusion query). Compares embree (scene e) with the two-level bvh (scene b); returns
 * the rays that hit ids [lo, hi) in both. */
static uint32_t embree_rays(const char *what, const tr_scene *b, const tr_scene *e,
                            const tr_aabb *aim, uint32_t lo, uint32_t hi, uint64_t seed) {
    const tr_scene_view vb = tr_scene_view_of(b), ve = tr_scene_view_of(e);
    CHECK(vb.accel == TR_ACCEL_BVH && ve.accel == TR_ACCEL_EMBREE && ve.kept == e &&
              ve.embree_first != NULL,
          "%s: the views trace the two levels and Embree's instances", what);
    const tr_aabb region = {v3(-1.5f, 0.0f, -1.0f), v3(1.5f, 1.2f, 1.0f)};
    const tr_aabb box = aim ? *aim : region;
    const uint32_t stored = tr_scene_stored_triangle_count(e), total = tr_scene_triangle_count(e);
    tr_rng r;
    tr_rng_init(&r, seed, 0, 0);
    uint32_t hits = 0, kept = 0, watched = 0, edge = 0, far = 0, occ = 0, occ_bad = 0, range = 0;
    for (uint32_t i = 0; i < EMB_RAYS; ++i) {
        const tr_vec3 o = v3(tr_rng_range(&r, -3.0f, 3.0f), tr_rng_range(&r, 0.2f, 3.0f), 3.5f);
        const tr_vec3 t =
            v3(tr_rng_range(&r, box.min.x, box.max.x), tr_rng_range(&r, box.min.y, box.max.y),
               tr_rng_range(&r, box.min.z, box.max.z));
        tr_vec3 d = v3_normalize(v3_sub(t, o));
        if (i % 4 == 3) {
            d = v3_normalize(v3(tr_rng_range(&r, -1.0f, 1.0f), tr_rng_range(&r, -1.0f, 0.3f),
                                tr_rng_range(&r, -1.0f, 0.2f)));
        }
        const float tmax = i % 5 == 4 ? tr_rng_range(&r, 1.0f, 6.0f) : TR_INFINITY;
        const tr_ray ray = tr_ray_make(o, d, 0.0f, tmax);
        tr_hit hb, he;
        memset(&hb, 0, sizeof hb);
        memset(&he, 0, sizeof he);
        const int fb = tr_intersect_scene(&vb, &ray, &hb);
        const int fe = tr_intersect_scene(&ve, &ray, &he);
        const int ob = tr_occluded_scene(&vb, &ray), oe = tr_occluded_scene(&ve, &ray);
        occ += ob;
        occ_bad += ob != oe;
        hits += fb;
        if (fb != fe) {
            edge++;
            continue;
        }
        if (!fb) {
            continue;
        }
        range += he.triangle >= total;
        kept += hb.triangle >= stored;
        /* A different triangle at the same distance is a ray through a shared edge. */
        if (he.triangle != hb.triangle) {
            edge++;
        }
        far += fabsf(he.t - hb.t) > EMB_T_TOL * fmaxf(1.0f, hb.t);
        watched += he.triangle == hb.triangle && hb.triangle >= lo && hb.triangle < hi;
    }
    printf("%s: %u of %u rays hit (%u on kept instances), %u decided otherwise at an edge, "
           "%u occluded (%u answered otherwise)\n",
           what, hits, EMB_RAYS, kept, edge, occ, occ_bad);
    CHECK(hits > EMB_RAYS / 2 && kept > EMB_RAYS / 10, "%s: %u rays hit, %u on kept instances",
          what, hits, kept);
    CHECK(range == 0 && far == 0, "%s: %u ids past the placed triangles, %u distances differ", what,
          range, far);
    CHECK(edge <= EMB_EDGE_FRACTION * EMB_RAYS && occ_bad <= EMB_EDGE_FRACTION * EMB_RAYS,
          "%s: %u hits and %u occlusion answers differ from the bvh's", what, edge, occ_bad);
    return watched;
}

/* The scene of build() committed to Embree: kept, not flattened. */
static void build_embree(tr_scene *e) {
    tr_error err;
    build(e, 0);
    const uint32_t stored = tr_scene_stored_triangle_count(e);
    const uint32_t placed = tr_scene_triangle_count(e);
    CHECK(tr_scene_commit(e, TR_ACCEL_TYPE_EMBREE, &err) == TR_OK, "embree commit: %s", err.msg);
    CHECK(tr_scene_is_committed(e) && tr_scene_accel(e) == TR_ACCEL_TYPE_EMBREE &&
              tr_scene_has_kept_instances(e) && tr_scene_stored_triangle_count(e) == stored &&
              tr_scene_triangle_count(e) == placed && e->embree.instance_count == e->instance_count,
          "embree keeps the instances (%u stored, was %u)", tr_scene_stored_triangle_count(e),
          stored);
}

static void embree_hits(void) {
    tr_scene b, e;
    build(&b, 0);
    build_embree(&e);
    embree_rays("embree rays", &b, &e, NULL, 0, 0, 5);
    tr_scene_clear(&b);
    tr_scene_clear(&e);
}

static void embree_render(int integ, const char *name) {
    tr_scene b, e;
    build(&b, 0);
    build_embree(&e);
    tr_film fb, fe;
    memset(&fb, 0, sizeof fb);
    memset(&fe, 0, sizeof fe);
    render_film(&b, W, H, integ, 5, TR_PASS_PRIM, 11, 0, 4, &fb);
    render_film(&e, W, H, integ, 5, TR_PASS_PRIM, 11, 0, 4, &fe);
    double sb = 0.0, se = 0.0;
    uint32_t differ = 0, id_diff = 0, kept_seen = 0;
    for (uint32_t i = 0; fb.sum && fe.sum && fb.prim && fe.prim && i < W * H; ++i) {
        int beyond = 0;
        for (int c = 0; c < 3; ++c) {
            const double x = fb.sum[3 * i + c], y = fe.sum[3 * i + c];
            sb += x;
            se += y;
            beyond |= fabs(x - y) > EMB_PIXEL_TOL * fmax(fmax(fabs(x), fabs(y)), 1e-6);
        }
        differ += (uint32_t)beyond;
        id_diff += fb.prim[i] != fe.prim[i];
        kept_seen += fe.prim[i] > e.triangle_count;
    }
    printf("embree %s: mean %.6g vs bvh %.6g, %u pixels differ beyond %.0e, %u name another "
           "primitive, %u on kept instances\n",
           name, se / (W * H * 3.0), sb / (W * H * 3.0), differ, EMB_PIXEL_TOL, id_diff, kept_seen);
    CHECK(kept_seen > W * H / 20, "embree %s: %u pixels on kept instances", name, kept_seen);
    CHECK(fabs(se - sb) <= EMB_MEAN_TOL * sb, "embree %s: mean %.6g vs %.6g", name, se, sb);
    CHECK(differ <= EMB_PIXEL_FRACTION * W * H && id_diff <= EMB_PIXEL_FRACTION * W * H,
          "embree %s: %u pixels differ, %u name another primitive", name, differ, id_diff);
    tr_film_free(&fb);
    tr_film_free(&fe);
    tr_scene_clear(&b);
    tr_scene_clear(&e);
}

/* Moves a kept instance, the flattened lamp instance and a shape of the scene's own in
 * both scenes; tr_scene_update keeps Embree's instances and traces what the bvh traces. */
static void embree_moves(void) {
    tr_scene b, e;
    tr_error err;
    build(&b, 0);
    build_embree(&e);
    const uint32_t stored = tr_scene_stored_triangle_count(&e);
    tr_scene *both[2] = {&b, &e};
    for (int k = 0; k < 2; ++k) {
        tr_scene *s = both[k];
        float m[12];
        placement(4, m);
        m[3] -= 0.6f;
        m[7] += 0.2f;
        const float up[12] = {1, 0, 0, -0.4f, 0, 1, 0, 2.8f, 0, 0, 1, 0.3f};
        const uint32_t box_shape = s->instances[4].shape + 1; /* added after the lamp */
        CHECK(tr_scene_set_instance_transform(s, 1, m, &err) == TR_OK &&
                  tr_scene_set_instance_transform(s, 4, up, &err) == TR_OK &&
                  tr_scene_move_shape(s, box_shape, v3(-0.3f, 0.0f, 0.4f), &err) == TR_OK &&
                  tr_scene_update(s, NULL, &err) == TR_OK,
              "moves: %s", err.msg);
    }
    CHECK(tr_scene_is_committed(&e) && tr_scene_accel(&e) == TR_ACCEL_TYPE_EMBREE &&
              tr_scene_has_kept_instances(&e) && tr_scene_stored_triangle_count(&e) == stored,
          "embree's update keeps the instances");
    const tr_aabb moved = e.shapes[e.instances[1].shape].box;
    const uint32_t first = e.inst_first[1];
    const uint32_t seen = embree_rays("embree rays after moves", &b, &e, &moved, first,
                                      first + tr_scene_prototype_triangle_count(&e, 0), 9);
    CHECK(seen > EMB_RAYS / 10, "the moved instance is hit where the bvh hits it (%u rays)", seen);
    embree_rays("embree rays after moves, the whole scene", &b, &e, NULL, 0, 0, 10);
    tr_scene_clear(&b);
    tr_scene_clear(&e);
}
#endif

int main(void) {
    storage_and_flattening();
    same_bits(TR_INTEGRATOR_PT, "pt");
    same_bits(TR_INTEGRATOR_BDPT, "bdpt");
    refit();
    switched_on();
    budget();
    instances_only();
#ifdef TRAC0R_HAVE_EMBREE
    if (tr_accel_available(TR_ACCEL_TYPE_EMBREE)) {
        embree_hits();
        embree_render(TR_INTEGRATOR_PT, "pt");
        embree_moves();
    }
#endif
    return check_finish("test_instances_kept");
}
