/* scene.h - a scene: materials, triangles grouped into shapes, and a camera.
 *
 * tr_scene is an opaque handle (as Embree's RTCScene): the scene owns flat arrays
 * indexed by integers, exactly as the kernels read them, and is read through the
 * accessors below. Shapes are generators of triangles (the thesis's Shape::make_*):
 * each call appends its triangles and the shape's bounding box. Edits take effect at
 * tr_scene_commit (or tr_scene_update after moving shapes): every edit that changes
 * what rays hit bumps the scene's generation, and rendering a scene whose generation is
 * not the committed one fails.
 *
 *     tr_error err;
 *     tr_scene *s = tr_scene_create(&err);
 *     uint32_t white;
 *     tr_scene_add_material(s, tr_material_diffuse(tr_vec3_make(0.7f, 0.7f, 0.7f)), &white,
 *                           &err);
 *     tr_shape_desc box = tr_shape_desc_default(TR_SHAPE_BOX);
 *     box.material = white;
 *     tr_scene_add_shape(s, &box, &err);
 *     ...
 *     tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err);
 *     tr_scene_destroy(s);
 */
#ifndef TRAC0R_SCENE_H
#define TRAC0R_SCENE_H

#include <stdint.h>

#include "trac0r/accel.h"
#include "trac0r/error.h"
#include "trac0r/types.h"

/* Icospheres are limited to this many subdivisions: 20 * 4^9 = 5 242 880 triangles. */
#define TR_ICOSPHERE_MAX_SUBDIVISIONS 9

typedef enum tr_shape_type {
    TR_SHAPE_PLANE = 1,            /* unit square in the xz plane, normal +y */
    TR_SHAPE_BOX = 2,              /* unit cube centred on the origin, normals outward */
    TR_SHAPE_ICOSPHERE = 3,        /* unit sphere from a subdivided icosahedron */
    TR_SHAPE_ICOSPHERE_SMOOTH = 4, /* the same, shaded with the sphere's normals at its vertices */
} tr_shape_type;

/* Where a shape's unit geometry goes: scaled, then rotated about x, then y, then z
 * (R = Rz * Ry * Rx, angles in radians, right-handed), then translated. */
typedef struct tr_transform {
    tr_vec3 position;
    tr_vec3 orientation; /* Euler angles, radians */
    tr_vec3 scale;       /* plane: (size x, 1, size z); box: size; icosphere: radius */
} tr_transform;

typedef struct tr_shape_desc {
    tr_shape_type type;
    tr_transform transform;
    uint32_t subdivisions; /* icosphere only: 20 * 4^n triangles */
    uint32_t material;     /* index returned by tr_scene_add_material */
} tr_shape_desc;

typedef struct tr_scene tr_scene;

/* A shape of the given type at the origin, unrotated, unit scale, material 0. */
tr_shape_desc tr_shape_desc_default(tr_shape_type type);

tr_material tr_material_emitter(tr_vec3 color, float emittance);
tr_material tr_material_diffuse(tr_vec3 color);
tr_material tr_material_glass(tr_vec3 color, float ior);
tr_material tr_material_glossy(tr_vec3 color, float roughness);

/* A new empty scene (generation 0, on the flat structure), or NULL when memory runs out. */
tr_scene *tr_scene_create(tr_error *err);
/* Releases the scene and everything it owns; NULL is ignored. */
void tr_scene_destroy(tr_scene *s);
/* Releases everything the scene owns and leaves it empty (the handle stays valid). */
void tr_scene_clear(tr_scene *s);
/* Appends a material and returns its index in *index. Rejects non-finite or negative
 * values and unknown types. */
int tr_scene_add_material(tr_scene *s, tr_material m, uint32_t *index, tr_error *err);
/* Appends a shape's triangles and its bounding box. */
int tr_scene_add_shape(tr_scene *s, const tr_shape_desc *desc, tr_error *err);
/* Appends an indexed triangle mesh as one shape: positions holds 3 floats per vertex,
 * indices 3 per triangle, normals (NULL for none) 3 floats per vertex; tf (NULL for
 * none) places it like a shape. Triangles of zero area after the transform are dropped
 * and counted in *dropped (may be NULL). Fails, adding nothing, on an index out of range,
 * a non-finite position, an unknown material or when nothing but degenerate triangles
 * is left. */
int tr_scene_add_mesh(tr_scene *s, const float *positions, uint32_t vertex_count,
                      const uint32_t *indices, uint32_t triangle_count, const float *normals,
                      uint32_t material, const tr_transform *tf, uint32_t *dropped, tr_error *err);
/* A shape transform applied to a point, and to a normal (inverse transpose, unit). */
tr_vec3 tr_transform_point(const tr_transform *tf, tr_vec3 p);
tr_vec3 tr_transform_normal(const tr_transform *tf, tr_vec3 n);

/* Number of triangles a shape description generates (0 for an invalid one). */
uint64_t tr_shape_triangle_count(const tr_shape_desc *desc);

/* Builds a built-in scene by name with its camera set up for a width x height image:
 * "cornell" is the thesis's listing 16; "cornell-mirror" the same with the glossy
 * objects' roughness 0 (perfect mirrors, on which the naive and pt integrators agree);
 * "cornell-diffuse" the same room with every object white diffuse; "cornell-ico-N" is
 * the scene of the thesis's complexity benchmark (figure 3.5): the same room with only
 * the glass icosphere, at N = 0..TR_ICOSPHERE_MAX_SUBDIVISIONS subdivisions (20 * 4^N
 * triangles). Whatever s held is released first; the scene is not committed. */
int tr_scene_builtin(tr_scene *s, const char *name, uint32_t width, uint32_t height, tr_error *err);

/* Builds the acceleration structure rays will be traced through (the thesis's flat
 * structure needs no build), releasing the one built before, and records the
 * generation it was built for. Call again after adding materials, shapes or meshes;
 * rendering a scene changed since fails. TR_ACCEL_TYPE_EMBREE fails with "this build of trac0r has
 * no Embree support" where tr_accel_available says so. On failure the scene is left on the flat
 * structure. */
int tr_scene_commit(tr_scene *s, tr_accel_type accel, tr_error *err);
/* Whether the scene is committed and unchanged since: its generation is the one the
 * last tr_scene_commit or tr_scene_update built for. */
int tr_scene_is_committed(const tr_scene *s);
/* The scene's generation: 0 when created, bumped by every edit of what rays hit
 * (materials, shapes, meshes, tr_scene_move_shape, loading a scene into it). A device
 * that uploaded the scene at one generation knows its copy is stale when this differs.
 * The camera is not part of it: it is no input to any acceleration structure, and
 * every backend takes the camera afresh with each frame. */
uint64_t tr_scene_generation(const tr_scene *s);
/* Dynamic scenes, as the thesis assumes (geometry may change every frame): moves shape
 * `shape` (its triangles and its box in the flat structure) by `delta`. Areas, normals and
 * the emitter table stay valid; the committed structure is stale until tr_scene_update. */
int tr_scene_move_shape(tr_scene *s, uint32_t shape, tr_vec3 delta, tr_error *err);
/* The demonstration animation of `trac0r view --animate` and the benchmarks: the scene's
 * last shape sways along x, a quarter of its width either way, one period per 60 frames.
 * Moves it from its place in frame f - 1 to its place in frame f (frame 0: where it was
 * built; nothing moves); tr_scene_update must follow. */
int tr_scene_animate_sway(tr_scene *s, uint32_t frame, tr_error *err);
/* Lights that change at run time. tr_scene_set_emittance sets emitter material
 * `material`'s emittance (0 switches it off; its colour stays): the emitter table (the
 * power CDF next-event estimation picks emitters from) and the light tree depend on it,
 * and tr_scene_update builds both anew, as tr_scene_commit does. Fails on an unknown
 * material, one that is not an emitter or a negative or non-finite value; setting the
 * value it has changes nothing (the scene stays committed). A light moves with its shape
 * (tr_scene_move_shape; the tree is rebuilt by tr_scene_update, the CDF, by area and
 * power, stays). tr_scene_set_sun_direction turns the sun to `dir` (towards it; any
 * length above 0), keeping its size and irradiance; it fails where the scene has no sun.
 * Each bumps the generation: tr_scene_update must follow before rendering. */
int tr_scene_set_emittance(tr_scene *s, uint32_t material, float emittance, tr_error *err);
int tr_scene_set_sun_direction(tr_scene *s, tr_vec3 dir, tr_error *err);
/* The light animations of `trac0r bench realtime --animate-light` and `view --animate`:
 * switch: every emitter material is on for TR_LIGHT_SWITCH_PERIOD / 2 frames and off
 * for as many (frames 0-7 on, 8-15 off, 16-23 on, ...), at the emittance it had at the
 * first call; move: every emitter's shape sways along x, a quarter of its width either
 * way, and the sun turns about y by 0.3 radians either way, one period per 60 frames
 * (frame 0: as built). tr_scene_animate_light brings the lights to their state in frame f
 * (moves go from frame f - 1 to f, as tr_scene_animate_sway's); tr_scene_update must
 * follow. none does nothing; an unknown mode fails. */
#define TR_LIGHT_ANIMATION_NONE 0
#define TR_LIGHT_ANIMATION_SWITCH 1
#define TR_LIGHT_ANIMATION_MOVE 2
#define TR_LIGHT_SWITCH_PERIOD 16u
int tr_scene_animate_light(tr_scene *s, uint32_t frame, int mode, tr_error *err);
/* Whether switch's lights are on in frame f. */
int tr_light_animation_on(uint32_t frame);
/* "none", "switch", "move" (NULL for anything else), and back (-1 for an unknown name). */
const char *tr_light_animation_name(int mode);
int tr_light_animation_from_name(const char *name);
/* Motion vectors for temporal reconstruction (tr_recon_frame_moving): how far each
 * primitive moved through tr_scene_move_shape since the last call, into motion[0, n) with
 * n = tr_scene_triangle_count(s) + 1, indexed as the id pass numbers primitives (triangle
 * + 1; entry 0, nothing hit, is zero); *moved is 1 when anything moved. The record starts
 * over. A table of another size fails with TR_STATUS_INVALID_ARGUMENT. */
int tr_scene_take_motion(tr_scene *s, tr_vec3 *motion, uint32_t n, int *moved, tr_error *err);
/* Brings the committed structure up to date after shapes moved and records the scene's
 * generation as committed: a BVH is refitted (boxes of the same trees, binary and wide),
 * Embree's scene rebuilt (with kept instances: its top scene, over the instances' new
 * matrices), the flat structure needs nothing. Fails when anything but moves
 * happened since the commit (shapes or meshes added, the scene reloaded): that needs
 * tr_scene_commit. *seconds (may be NULL) gets the time taken. */
int tr_scene_update(tr_scene *s, double *seconds, tr_error *err);
/* What tr_scene_update does for the scene's structure: "refit", "rebuild" or "none". */
const char *tr_scene_update_kind(const tr_scene *s);
/* Seconds tr_scene_commit took to build the BVH: the binary build plus, for
 * TR_ACCEL_TYPE_BVH, the wide collapse (0 for other structures). */
double tr_scene_bvh_build_seconds(const tr_scene *s);
/* Seconds tr_scene_commit took to build the Embree scene (0 unless the scene is
 * committed to TR_ACCEL_TYPE_EMBREE). */
double tr_scene_embree_build_seconds(const tr_scene *s);
/* Seconds tr_scene_commit took to build the scene's structure, whichever it is: the one
 * of the two above that applies (0 for the flat structure). */
double tr_scene_build_seconds(const tr_scene *s);

/* ---- Instances ------------------------------------------------------------------
 *
 * A prototype is geometry stored once (object space); an instance places it with a 3x4
 * affine matrix m (row-major, object to world: x' = m[0] x + m[1] y + m[2] z + m[3],
 * y' from m[4..7], z' from m[8..11]). Each instance is one shape of the scene whose
 * triangles are its prototype's, transformed: they count in tr_scene_triangle_count, have
 * ids (after the stored triangles, tr_scene_stored_triangle_count) and read as placed
 * (tr_scene_triangle), but are not stored: the instance keeps a matrix and a box, and
 * shading places a hit triangle through it. TR_ACCEL_TYPE_BVH on the CPU traces a
 * two-level structure: a top-level wide BVH over the instances whose leaves carry the ray
 * into each prototype's own bottom-level wide BVH, built once per prototype however many
 * instances it has. TR_ACCEL_TYPE_EMBREE traces them through Embree's own instancing (a
 * scene per prototype, an instance geometry per instance), with the same ids. The other
 * structures (flat, bvh2) and OpenCL devices trace
 * stored triangles only: committing to one of them, or uploading to such a device,
 * flattens the instances first (stores their transformed triangles in the order they were
 * added), and the scene stays flattened. A prototype with an emitting material is stored
 * transformed per instance from the start (the emitter table names stored triangles). */

/* The matrix of a transform (scale, then rotation, then translation). */
void tr_transform_matrix(const tr_transform *tf, float m[12]);
/* Turns shapes first_shape .. tr_scene_shape_count(s) - 1 (the last added, none of them an
 * instance) into prototype *proto: their triangles and vertex attributes leave the scene
 * and are kept, in the coordinates they were added in, as the prototype's. */
int tr_scene_make_prototype(tr_scene *s, uint32_t first_shape, uint32_t *proto, tr_error *err);
/* Places prototype `proto` with matrix m as a new shape (and instance *instance, may be
 * NULL). A matrix with a non-finite entry or a singular (or nearly singular) 3x3 part is
 * refused with TR_STATUS_INVALID_ARGUMENT. */
int tr_scene_add_instance(tr_scene *s, uint32_t proto, const float m[12], uint32_t *instance,
                          tr_error *err);
/* Appends prototype `proto` placed with m as a plain shape, not an instance (how scene
 * files nest prototypes in prototypes). */
int tr_scene_add_prototype_copy(tr_scene *s, uint32_t proto, const float m[12], tr_error *err);
/* Moves instance `instance` to matrix m (checked as above): its triangles and vertex
 * normals are placed anew (rewritten where stored); tr_scene_update then refits the top level along
 * the instance's path only (the bottom levels never change), or, committed to Embree, gives Embree
 * the new matrix and rebuilds its top scene (not the prototypes'). tr_scene_move_shape on an
 * instance's shape does the same with the translation added to its matrix. */
int tr_scene_set_instance_transform(tr_scene *s, uint32_t instance, const float m[12],
                                    tr_error *err);
/* Instance i's matrix into m (0 when there is no instance i). */
int tr_scene_instance_transform(const tr_scene *s, uint32_t instance, float m[12]);
uint32_t tr_scene_prototype_count(const tr_scene *s);
uint32_t tr_scene_instance_count(const tr_scene *s);
/* The prototype's triangle count (0 for no such prototype). */
uint32_t tr_scene_prototype_triangle_count(const tr_scene *s, uint32_t proto);
/* What scene triangle `triangle` (the id pass's primitive - 1) is: 1 with *instance and
 * *prim (its index in the prototype) when it belongs to an instance, 0 for a triangle of
 * the scene's own (or none). */
int tr_scene_triangle_instance(const tr_scene *s, uint32_t triangle, uint32_t *instance,
                               uint32_t *prim);

/* ---- Reading a scene ---------------------------------------------------------- */

/* Triangles the scene places: the ids rays can hit run from 0 to this count - 1. */
uint32_t tr_scene_triangle_count(const tr_scene *s);
/* Of those, the ones stored one by one (ids 0 ..): the rest are placed by instances kept
 * unflattened for the CPU's two-level `bvh` and Embree (tr_scene_add_instance), stored once per
 * prototype, none of them an emitter. Equal to tr_scene_triangle_count without them. */
uint32_t tr_scene_stored_triangle_count(const tr_scene *s);
uint32_t tr_scene_material_count(const tr_scene *s);
/* Shapes and meshes added: the boxes of the thesis's flat structure. */
uint32_t tr_scene_shape_count(const tr_scene *s);
/* Emissive triangles of positive area in the emitter table (built by tr_scene_commit;
 * 0 before). */
uint32_t tr_scene_light_count(const tr_scene *s);

/* How next-event estimation picks an emitter. auto: the light tree when the emitter table
 * has at least TR_LIGHT_TREE_MIN_EMITTERS entries, the power CDF otherwise. tree: a
 * light tree (Conty Estevez and Kulla 2018) that weighs each emitter's power by its
 * distance and orientation from the shading point. power: probability proportional to
 * emitted power, the same everywhere. */
#define TR_LIGHT_SAMPLING_AUTO 0
#define TR_LIGHT_SAMPLING_TREE 1
#define TR_LIGHT_SAMPLING_POWER 2
#define TR_LIGHT_TREE_MIN_EMITTERS 8
/* Sets the light sampling the next tr_scene_commit builds for (a fresh or freed scene
 * has auto); fails on an unknown mode. */
int tr_scene_set_light_sampling(tr_scene *s, int mode, tr_error *err);
/* What the committed scene uses: TR_LIGHT_SAMPLING_TREE or TR_LIGHT_SAMPLING_POWER. */
int tr_scene_light_sampling(const tr_scene *s);
/* "auto", "tree", "power" (NULL for anything else), and back (-1 for an unknown name). */
const char *tr_light_sampling_name(int mode);
int tr_light_sampling_from_name(const char *name);
/* Triangle i, material i, the box of shape i; all zero for an index out of range. */
tr_triangle tr_scene_triangle(const tr_scene *s, uint32_t i);
tr_material tr_scene_material(const tr_scene *s, uint32_t i);
tr_aabb tr_scene_shape_box(const tr_scene *s, uint32_t shape);
/* The vertex normals an imported mesh gave triangle i into out[0..2]; returns 1 when it
 * has them, 0 (and zeros) when it has none. */
int tr_scene_triangle_normals(const tr_scene *s, uint32_t i, tr_vec3 out[3]);
/* The maps material i has (textures from a scene file or a model's import
 * table), as TR_MAP_* bits; 0 for none or an index out of range. */
#define TR_MAP_BASE 1u
#define TR_MAP_EMISSION 2u
#define TR_MAP_METALLIC_ROUGHNESS 4u
#define TR_MAP_NORMAL 8u
#define TR_MAP_CUTOUT 16u               /* alpha cut-out of the base map */
#define TR_MAP_TRANSMISSION 32u         /* principled: the transmission's (its red channel) */
#define TR_MAP_CLEARCOAT 64u            /* principled: the clear coat's weight (its red channel) */
#define TR_MAP_CLEARCOAT_ROUGHNESS 128u /* principled: the coat's roughness (its green) */
#define TR_MAP_SHEEN_COLOR 256u         /* principled: the sheen's colour (sRGB) */
#define TR_MAP_SHEEN_ROUGHNESS 512u     /* principled: the sheen's roughness (its alpha) */
#define TR_MAP_CLEARCOAT_NORMAL 1024u   /* principled: the clear coat's own normal map */
uint32_t tr_scene_material_maps(const tr_scene *s, uint32_t i);
/* Triangles of shape i (a shape, or one part of an imported mesh); 0 out of range. */
uint32_t tr_scene_shape_triangle_count(const tr_scene *s, uint32_t shape);
/* The bounding box of every triangle (min = +inf, max = -inf for an empty scene). */
tr_aabb tr_scene_bounds(const tr_scene *s);

/* The sun ("sun" in scene files; a model's directional light): 1 with its direction
 * (unit, towards it), angular diameter in degrees and irradiance (W/m^2) where the scene
 * has one, else 0. Any pointer may be NULL. */
int tr_scene_sun(const tr_scene *s, tr_vec3 *dir, float *angle_deg, tr_vec3 *irradiance);

/* The camera rays start from; set by tr_scene_builtin and tr_scene_file_load. */
const tr_camera *tr_scene_camera(const tr_scene *s);
void tr_scene_set_camera(tr_scene *s, const tr_camera *cam);
/* The distance along cam's view direction to the first surface under the screen point
 * (x, y) (in pixels from the top-left corner, 0 <= x < width, 0 <= y < height): the
 * focus distance (tr_camera_set_lens) that makes that point sharp, as a viewer's "focus
 * on the point under the cursor" needs. Returns 1 and sets *dist, or 0 when the pinhole
 * ray through the point meets nothing, the point lies off the screen or the scene is not
 * committed. */
int tr_scene_focus_distance(const tr_scene *s, const tr_camera *cam, float x, float y, float *dist);

/* The committed acceleration structure (TR_ACCEL_TYPE_FLAT before any commit). */
tr_accel_type tr_scene_accel(const tr_scene *s);
/* Counts, depths and build times of the committed structure. */
void tr_scene_accel_info(const tr_scene *s, tr_accel_info *info);
/* The committed structure in one line for a summary: its name, and for bvh the wide
 * traversal's width and instruction set ("bvh (8-wide avx2)"; a TRAC0R_ISA the CPU or
 * build cannot honour is named as unavailable). With `detail` its size and build time too:
 * "bvh (8-wide avx2: N nodes, ...; built in T ms, ...)", "bvh2 (...)", "embree (built in T
 * ms)", "flat (N shape boxes)". Always NUL-terminates buf (truncating when it is short). */
void tr_scene_accel_describe(const tr_scene *s, int detail, char *buf, size_t n);
/* Node i of the committed binary BVH (bvh and bvh2; node 0 is the root, 0 nodes
 * otherwise): its box, and for an interior node the index of its first child (the
 * second follows it). Returns 1 for an interior node, 0 for a leaf, -1 for i out of
 * range. first_child may be NULL. */
int tr_scene_bvh_node(const tr_scene *s, uint32_t i, tr_aabb *box, uint32_t *first_child);
uint32_t tr_scene_bvh_node_count(const tr_scene *s);

#endif
