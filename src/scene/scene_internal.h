/* scene_internal.h - the scene as the library holds it (tr_scene is opaque to clients:
 * include/trac0r/scene.h), and what the scene, accel and backend sources share. Tests
 * include it to build scenes on the stack and to read the arrays directly. */
#ifndef TR_SCENE_INTERNAL_H
#define TR_SCENE_INTERNAL_H

#include "accel/accel_internal.h"
#include "kernel/scene_view.h"
#include "kernel/types.h"
#include "trac0r/scene.h"
#include "trac0r/scene_file.h"

/* The most triangles a scene holds, stored or placed by kept instances together: ids
 * (and id + 1 in the primitive pass) stay far inside 32 bits. */
#define TR_SCENE_MAX_TRIANGLES (UINT32_MAX / 2)

/* Geometry stored once and placed by instances (src/scene/instance.c), in object space:
 * tris, and when it has vertex attributes idx (3 per triangle into verts, TR_NO_INDEX for
 * none). Its bottom-level BVH is built by the first commit that needs it. */
typedef struct tr_prototype {
    tr_triangle *tris;
    uint32_t tri_count;
    tr_vertex *verts;
    uint32_t vert_count;
    uint32_t *idx;
    /* Its distinct vertex positions: an instance's world box is theirs transformed, the
     * same box as its transformed triangles' (tr_triangles_bounds reads the vertices). */
    tr_vec3 *pts;
    uint32_t pt_count;
    int emissive; /* some triangle's material emits */
    int built;
    tr_bvh bvh;
    tr_wbvh wbvh;
} tr_prototype;

/* One placement of a prototype: its shape, and its matrix (object to world) and inverse,
 * 3x4 row-major. A flattened instance (flat set) holds its transformed triangles in the
 * scene's arrays at its shape's `first`, and vert_base is its first vertex there. A kept
 * one (flat 0) stores nothing per triangle: its shape's `first` is the first of its ids,
 * which lie past the stored triangles (tr_scene_instance_ids), and vert_base is the
 * stored vertex count when it was added (where flattening puts its vertices). */
typedef struct tr_instance {
    uint32_t proto;
    uint32_t shape;
    uint32_t vert_base;
    uint32_t at; /* the stored triangle count when it was added */
    float m[12], inv[12];
    int moved; /* set by tr_scene_set_instance_transform until tr_scene_update */
    int flat;
} tr_instance;

struct tr_scene {
    tr_material *materials;
    uint32_t material_count, material_capacity;
    tr_triangle *triangles;
    uint32_t triangle_count, triangle_capacity;
    tr_flat_node *shapes; /* one box + triangle run per shape: the thesis's flat structure */
    uint32_t shape_count, shape_capacity;
    /* Per shape, how far tr_scene_move_shape moved it since the last tr_scene_take_motion
     * (motion vectors for temporal reconstruction). */
    tr_vec3 *shape_moved;
    uint32_t shape_moved_capacity;
    tr_camera camera;
    /* Set by tr_scene_commit: the structure rays are traced through. */
    tr_accel_type accel;
    tr_bvh bvh;
    tr_wbvh wbvh;                 /* collapsed from bvh for TR_ACCEL_TYPE_BVH (host traversal) */
    tr_embree embree;             /* built for TR_ACCEL_TYPE_EMBREE only */
    uint32_t committed_triangles; /* triangle count at the last successful commit */
    /* Bumped by every edit of what rays hit (tr_scene_generation); committed_generation is
     * the generation the last tr_scene_commit or tr_scene_update built for, valid when
     * `committed` is set. */
    uint64_t generation;
    uint64_t committed_generation;
    int committed;
    /* Emitter table for next-event estimation, rebuilt by tr_scene_commit
     * (src/scene/lights.c): emissive triangle indices and their selection CDF. */
    uint32_t *lights;
    float *light_cdf;
    uint32_t light_count;
    float light_weight_total;
    uint32_t light_triangles; /* triangle count when the table was built */
    /* The triangles' bounding sphere (tr_scene_sky_bounds). */
    float sky_center[3], sky_radius;
    /* The light tree over the table (src/scene/light_tree.c; kernel/light_tree.h), built
     * by tr_scene_commit when light_sampling asks for it: 2 light_count - 1 nodes and
     * each emitter's leaf; light_node_count 0 for none. */
    tr_light_node *light_nodes;
    uint32_t *light_leaf;
    uint32_t light_node_count;
    /* The punctual slots of light_leaf, after the emitters': punctual_count when the tree
     * also holds the point and spot lights (tr_scene_light_tree_punctual), 0 otherwise. */
    uint32_t light_tree_punctual;
    int light_sampling; /* TR_LIGHT_SAMPLING_*, what the next commit builds */
    /* Vertex attributes (kernel/attrib.h): triangles 0..tri_verts_count-1 name three
     * entries of `vertices` each (v[0] == TR_NO_INDEX: none); triangles beyond have none. */
    tr_vertex *vertices;
    uint32_t vertex_count, vertex_capacity;
    tr_tri_verts *tri_verts;
    uint32_t tri_verts_count, tri_verts_capacity;
    /* Textures (src/scene/texture.c) and the per-material extras that refer to them:
     * material_ext_count is 0 or material_count. */
    tr_texture *textures;
    uint32_t texture_count, texture_capacity;
    uint32_t *texels;
    uint32_t texel_count, texel_capacity;
    /* The file each texture was decoded from (tr_scene_load_texture; NULL: given as
     * texels), so that a file named again is not decoded again: texture_file_count <=
     * texture_count entries. */
    char **texture_files;
    uint32_t texture_file_count;
    tr_material_ext *material_exts;
    uint32_t material_ext_count, material_ext_capacity;
    /* The environment light (src/scene/envmap.c): env_count 0 or 1. */
    tr_env env;
    uint32_t env_count;
    float *env_texels; /* 3 per texel */
    uint32_t env_texel_count;
    float *env_cdf;
    uint32_t env_cdf_count;
    /* The sun (src/scene/sun.c): sun_count 0 or 1. */
    tr_sun sun;
    uint32_t sun_count;
    /* Point, spot and directional lights (src/scene/punctual.c). */
    tr_punctual *punctual;
    uint32_t punctual_count, punctual_capacity;
    uint32_t punctual_built; /* the count the CDF was built for */
    /* Instancing (src/scene/instance.c). With instances, a TR_ACCEL_TYPE_BVH commit builds
     * the two-level structure instead of `bvh`/`wbvh`: `rest` over the scene's own
     * triangles (an identity instance, the top level's last entry) and `tlas` over
     * everything; two_level says it is the committed one. rest_moved: a shape of the
     * scene's own moved since. */
    tr_prototype *protos;
    uint32_t proto_count, proto_capacity;
    tr_instance *instances;
    uint32_t instance_count, instance_capacity;
    tr_tlas tlas;
    tr_bvh rest_bvh;
    tr_wbvh rest_wbvh;
    int two_level;
    int rest_moved;
    uint32_t *moved; /* instances moved since the last update, each once */
    uint32_t moved_count, moved_capacity;
    /* Kept instances (src/scene/instance.c): placed_count triangles placed but not stored,
     * and per instance the first of its ids (inst_first, instance_count entries, in
     * ascending order; a flattened instance repeats the next kept one's), which the kernel
     * searches to name a hit's instance (tr_inst_triangle). */
    uint64_t placed_count;
    uint32_t *inst_first;
    uint32_t inst_first_capacity;
    /* Lights changed at run time (src/scene/light_change.c): lights_dirty says an
     * emittance changed since the emitter table was built, so that tr_scene_update rebuilds
     * it; light_base holds each material's emittance as tr_scene_animate_light first saw
     * it (light_base_count entries, 0 before its first call). */
    int lights_dirty;
    float *light_base;
    uint32_t light_base_count;
};

/* An empty scene (no allocation), for a tr_scene the caller owns (tr_scene_create does
 * this on the heap). Callers may also zero-initialise one: tr_scene s = {0}. */
void tr_scene_init(tr_scene *s);

/* Appends n triangles as one shape (one box of the flat structure), growing the scene's
 * arrays; `normals` (3 per triangle) may be NULL. The caller keeps its arrays. */
int tr_scene_append_shape(tr_scene *s, const tr_triangle *tris, uint32_t n, const tr_vec3 *normals,
                          tr_error *err);
/* The same with indexed vertex attributes: nv vertices, and for triangle i the indices
 * idx[3i..3i+2] into them (verts and idx may be NULL together for none). */
int tr_scene_append_shape_attr(tr_scene *s, const tr_triangle *tris, uint32_t n,
                               const tr_vertex *verts, uint32_t nv, const uint32_t *idx,
                               tr_error *err);
/* tr_scene_add_mesh with texture coordinates: uvs (NULL for none) holds 2 floats per
 * vertex. */
int tr_scene_add_mesh_uv(tr_scene *s, const float *positions, uint32_t vertex_count,
                         const uint32_t *indices, uint32_t triangle_count, const float *normals,
                         const float *uvs, uint32_t material, const tr_transform *tf,
                         uint32_t *dropped, tr_error *err);
/* Sets the extras of material `index` (the scene's other materials get the defaults,
 * tr_material_ext_default, when this is the first). */
int tr_scene_set_material_ext(tr_scene *s, uint32_t index, const tr_material_ext *ext,
                              tr_error *err);
/* No textures, metallic 0, no cut-out, normal scale 1. */
tr_material_ext tr_material_ext_default(void);
/* KHR_materials_volume's absorption coefficient: -ln(color) / distance per channel, the
 * light that is left after `distance` being `color` (attrib.h). */
tr_vec3 tr_volume_absorption(tr_vec3 color, float distance);
/* xf (tr_texture) for KHR_texture_transform's offset, rotation (radians) and scale. */
void tr_texture_transform_glTF(float xf[6], float offset_u, float offset_v, float rotation,
                               float scale_u, float scale_v);
/* Texture `tex` seen through the coordinate transform xf: a new entry over the same texels
 * (TR_TEXTURE_TRANSFORM), or tex itself for the identity; its index in *index. */
int tr_scene_texture_transformed(tr_scene *s, uint32_t tex, const float xf[6], uint32_t *index,
                                 tr_error *err);
/* The most texels a scene's textures may hold together: TRAC0R_TEXEL_BUDGET from the
 * environment (1..2^32-1), else TR_TEXEL_BUDGET_DEFAULT (2^28: 1 GiB of RGBA8). Fails
 * with TR_STATUS_INVALID_ARGUMENT on a malformed value. */
#define TR_TEXEL_BUDGET_DEFAULT (1u << 28)
int tr_scene_texel_budget(uint32_t *budget, tr_error *err);
/* Appends a width x height RGBA8 image (row-major from the top, R in the low byte) as a
 * texture; its index in *index. */
int tr_scene_add_texture(tr_scene *s, const uint32_t *rgba, uint32_t width, uint32_t height,
                         uint32_t flags, uint32_t *index, tr_error *err);
/* tr_scene_import_mesh with warnings: warn(ctx, message) for every texture or material
 * property the import drops or approximates (names the material), may be NULL. */
typedef void (*tr_import_warn_fn)(void *ctx, const char *message);
/* A light of a model file, placed by its node and tf (model.c maps it onto trac0r's). */
#define TR_IMPORT_MAX_LIGHTS 16
typedef struct tr_import_light {
    int type; /* Assimp's aiLightSourceType */
    char name[64];
    tr_vec3 pos, dir;     /* dir: where the light shines (unit) */
    tr_vec3 color;        /* Assimp's mColorDiffuse (glTF: colour x intensity) */
    float outer_cone;     /* spot lights: half-angle, radians */
    float size_x, size_y; /* area lights */
    float inner_cone;     /* spot lights: Assimp's mAngleInnerCone, radians */
    int gltf;             /* from a glTF file: the cones are glTF's half-angles */
    float att[3];         /* Assimp's attenuation 1 / (att[0] + att[1] d + att[2] d^2) */
} tr_import_light;
/* What else a model file holds: the camera asked for (camera_want, before the import:
 * its index in the file, >= 0), placed by its node and tf; how many cameras and lights
 * it has; its lights (the first TR_IMPORT_MAX_LIGHTS). */
typedef struct tr_import_extras {
    int camera_want;
    /* Set by the caller (kept by the import); 0: off. When the meshes the file's node
     * graph places more than once make at least this many triangles placed, each becomes
     * one prototype with an instance per placement (mesh.c). */
    uint64_t instance_min;
    int has_camera;
    char cam_name[64];
    tr_vec3 cam_pos, cam_dir, cam_up;
    float cam_hfov;   /* Assimp's mHorizontalFOV, radians (model.c: the whole angle) */
    float cam_aspect; /* 0: not given */
    int cam_gltf;     /* a glTF file's camera: cam_hfov is Assimp 5.2's yfov x aspect */
    uint32_t cameras, lights;
    uint32_t light_count; /* placed in light[]: those whose node was found */
    tr_import_light light[TR_IMPORT_MAX_LIGHTS];
} tr_import_extras;
/* The index of the camera called `name` in model file `path`, or of camera number `name`
 * (digits); -1 (with err) when there is none such. */
int tr_model_find_camera(const char *path, const char *name, int *index, tr_error *err);
/* A model file's shared meshes are instanced from this many placed triangles on: below,
 * one flattened structure traces faster than two levels (on 2CylinderEngine.glb, 58 K
 * triangles in 100 placements of 19 meshes, 17 % fewer rays per second instanced), and
 * the memory instancing saves is small. */
#define TR_IMPORT_INSTANCE_MIN (1u << 20)
int tr_scene_import_mesh_ex(tr_scene *s, const char *path, const tr_transform *tf,
                            int64_t material_override, uint32_t max_triangles,
                            tr_mesh_import_stats *stats, tr_import_warn_fn warn, void *warn_ctx,
                            tr_import_extras *extras, tr_error *err);

/* Sets the environment light (replacing any): radiance color * strength, times the
 * width x height RGB map rgb (linear, top row first; NULL and 0 x 0 for a constant
 * colour), turned by rotation radians about +y. Builds the map's sampling CDFs. */
int tr_scene_set_environment(tr_scene *s, tr_vec3 color, float strength, float rotation,
                             const float *rgb, uint32_t width, uint32_t height, tr_error *err);
/* Loads an equirectangular map (Radiance .hdr, or a PNG, JPEG, TGA or BMP) and sets
 * it as the environment. */
int tr_scene_load_environment(tr_scene *s, const char *path, tr_vec3 color, float strength,
                              float rotation, tr_error *err);
#define TR_SUN_MIN_ANGLE 1e-3f /* degrees: the cone's pdf squared stays a float */
#define TR_SUN_MAX_ANGLE 90.0f
/* Sets the sun (replacing any): seen from the scene in direction `dir` (towards the sun,
 * any length > 0) as a disc of angular diameter angle_deg (1e-3..90 degrees), giving the
 * irradiance `irradiance` (W/m^2 per channel) on a surface facing it. */
int tr_scene_set_sun(tr_scene *s, tr_vec3 dir, float angle_deg, tr_vec3 irradiance, tr_error *err);
/* GGX's albedo table for multiple-scattering compensation (src/kernel/ggx_ms.h):
 * TR_GGX_MS_COUNT floats, computed on the first call (src/scene/ggx_ms.c). */
const float *tr_ggx_ms_table(void);
#define TR_MAX_PUNCTUAL 65536u
/* Adds a punctual light (attrib.h): type, pos (point, spot), dir (spot, directional; any
 * length > 0), intensity, and a spot's cos_outer <= cos_inner; the other fields are
 * ignored. */
int tr_scene_add_punctual(tr_scene *s, const tr_punctual *light, tr_error *err);
/* Their selection CDF by power (tr_scene_commit; a directional light's from the
 * triangles' bounds). */
void tr_scene_build_punctual(tr_scene *s);
/* Restores the counts a failed import started from (everything is appended). */
void tr_scene_truncate(tr_scene *s, uint32_t triangles, uint32_t shapes, uint32_t materials);

/* After moving triangles (same count) of a scene committed to a BVH: refits the binary
 * BVH's boxes (tr_bvh_refit), then the wide BVH in place (tr_wbvh_refit: same shape, new
 * boxes and leaf packets; collapsed anew if it was older than the binary tree). A view
 * taken after a bare tr_bvh_refit uses the binary BVH until this runs. */
int tr_scene_refit(tr_scene *s, tr_error *err);

/* Rebuilds the emitter table (tr_scene_commit calls it): every triangle of positive
 * area whose material has emittance > 0, weighted by tr_light_weight. */
int tr_scene_build_lights(tr_scene *s, tr_error *err);
/* The triangles' bounding sphere, which light subpaths from the environment and the sun
 * start outside of (kernel/integrator_bdpt.h); tr_scene_build_lights and tr_scene_update
 * call it. */
void tr_scene_sky_bounds(tr_scene *s);

/* Builds the light tree over the emitter table (after tr_scene_build_lights), replacing
 * any; tr_scene_free_light_tree drops it. */
int tr_scene_build_light_tree(tr_scene *s, tr_error *err);
/* Whether tr_scene_commit builds the tree: as light_sampling says, for auto with at least
 * TR_LIGHT_TREE_MIN_EMITTERS emitters in the (fresh) table. */
int tr_scene_light_tree_wanted(const tr_scene *s);
/* Whether that tree also holds the point and spot lights: unless light_sampling is power,
 * when there are more of them than TR_PUNCTUAL_ALL (fewer are each sampled at every
 * vertex, without selection noise). */
int tr_scene_light_tree_punctual(const tr_scene *s);
/* The emitter table and, where wanted, its light tree built anew for the materials'
 * emittances now (after tr_scene_set_emittance); clears lights_dirty. */
int tr_scene_rebuild_lights(tr_scene *s, tr_error *err);
void tr_scene_free_light_tree(tr_scene *s);

/* Fills a triangle's normal, centroid and area from its vertices (normal and area are
 * zero for degenerate ones). */
void tr_triangle_finish(tr_triangle *t);
/* The bounding box of n triangles. */
tr_aabb tr_triangles_bounds(const tr_triangle *t, uint32_t n);

/* TR_OK when the scene is committed at its current generation (tr_scene_is_committed),
 * otherwise TR_ERR with a message saying which call is missing: every backend checks
 * this before it traces or uploads a scene. */
int tr_scene_check_committed(const tr_scene *s, tr_error *err);

/* Instancing (src/scene/instance.c): builds the two-level structure for a
 * TR_ACCEL_TYPE_BVH commit of a scene with instances; brings it up to date after moves
 * (tr_scene_update); frees everything instancing holds (tr_scene_clear). The instance
 * owning shape `shape`, or UINT32_MAX. */
int tr_scene_build_two_level(tr_scene *s, tr_error *err);
int tr_scene_update_two_level(tr_scene *s, tr_error *err);
/* A TR_ACCEL_TYPE_EMBREE commit with kept instances: the stored triangles, a scene per
 * placed prototype and an instance geometry per kept instance (tr_embree_build_instanced);
 * the update after moves gives Embree the moved instances' matrices (and the stored
 * triangles when any of them moved) and commits the top scene again. */
int tr_scene_build_embree(tr_scene *s, tr_error *err);
int tr_scene_update_embree(tr_scene *s, tr_error *err);
void tr_scene_free_instances(tr_scene *s);
void tr_scene_free_two_level(tr_scene *s);
/* Kept instances: assigns their ids after the stored triangles (each commit does, as
 * shapes added after them move the stored count); writes them into the scene's arrays
 * exactly as flattening each at its addition would have (the same triangles, vertices,
 * order and ids), for the structures and devices that trace stored triangles only. */
void tr_scene_instance_ids(tr_scene *s);
int tr_scene_flatten(tr_scene *s, tr_error *err);
/* tr_scene_flatten, then the commit the scene had (same structure, same generation):
 * for a device that reads stored triangles only, given a scene committed with kept
 * instances. */
int tr_scene_flatten_committed(tr_scene *s, tr_error *err);
/* Whether the scene holds kept instances (placed triangles not stored). */
int tr_scene_has_kept_instances(const tr_scene *s);
/* How many of the kept instances' triangles have vertex normals (trac0r info's count,
 * a prototype's once per placement). */
uint32_t tr_scene_kept_normals(const tr_scene *s);
/* Whether a kept instance places a prototype with an emitting material. */
int tr_scene_kept_emit(const tr_scene *s);
/* The box of the stored triangles and of every kept instance. */
tr_aabb tr_scene_all_bounds(const tr_scene *s);
uint32_t tr_scene_shape_instance(const tr_scene *s, uint32_t shape);

/* The view the kernels trace against; valid while the scene is not modified. */
tr_scene_view tr_scene_view_of(const tr_scene *s);

#endif
