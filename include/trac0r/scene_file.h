/* scene_file.h - scenes from JSON files (docs/scene-format.md) and meshes from any
 * format Assimp reads.
 *
 *     tr_error err;
 *     tr_scene *s = tr_scene_create(&err);
 *     tr_scene_file info;
 *     if (s && tr_scene_file_load(s, "scenes/cornell-classic.json", NULL, &info, &err) != TR_OK)
 *         fprintf(stderr, "%s\n", err.msg); // "FILE: camera.fov: expected ..." or FILE:LINE:COL
 *
 * Every error is one line that starts with the file's name and then either the line and
 * column of a JSON syntax error ("scene.json:3:14: ...") or the JSON path of the value at
 * fault ("scene.json: materials.glass.ior: ..."). On failure the scene is left empty. */
#ifndef TRAC0R_SCENE_FILE_H
#define TRAC0R_SCENE_FILE_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/error.h"
#include "trac0r/render.h"
#include "trac0r/scene.h"

/* The most triangles a scene file may generate (shapes and meshes together). */
#define TR_SCENE_FILE_MAX_TRIANGLES (1u << 24)
/* Every vertex, after its transform, and the camera position lie within |x| <= this. */
#define TR_SCENE_FILE_MAX_COORD 1e7
/* Scene files larger than this are refused before parsing. */
#define TR_SCENE_FILE_MAX_BYTES (64u * 1024u * 1024u)
/* ... and so are files with more JSON values (numbers, strings, arrays, objects) than
 * this: each costs memory while the file is parsed. */
#define TR_SCENE_FILE_MAX_VALUES (1u << 21)
#define TR_SCENE_FILE_MAX_WARNINGS 16

typedef struct tr_scene_file_options {
    /* 0: meshes are validated as JSON but their files are not opened (the fuzzer). */
    int load_meshes;
    /* Triangle budget; 0 means TR_SCENE_FILE_MAX_TRIANGLES. */
    uint32_t max_triangles;
} tr_scene_file_options;

/* What a scene file says besides its geometry, and what loading it found. */
typedef struct tr_scene_file {
    /* Render defaults; has_* is 1 where the file gave the value. */
    uint32_t width, height, spp;
    int max_depth;
    char integrator[32];
    tr_accel_type accel;
    int has_width, has_height, has_spp, has_max_depth, has_integrator, has_accel;
    int allow_no_emitter; /* "render": {"allow_no_emitter": true} */
    /* Counts. */
    uint32_t shape_count;        /* shapes[] entries */
    uint32_t mesh_count;         /* meshes[] entries */
    uint32_t mesh_parts;         /* Assimp meshes imported from them */
    uint32_t mesh_triangles;     /* triangles imported from them */
    uint32_t degenerate_dropped; /* mesh faces dropped: not triangles, zero area */
    uint32_t emissive_triangles; /* triangles whose material is an emitter */
    uint32_t emitter_materials;  /* emitter materials used by some triangle */
    tr_aabb bounds;              /* of all triangles */
    uint32_t warning_count;
    char warnings[TR_SCENE_FILE_MAX_WARNINGS][256];
    uint32_t open_stage; /* tr_scene_open: the stage that failed (TR_SCENE_OPEN_*), 0 if none */
} tr_scene_file;

/* What a program asks of a render of a scene file (tr_scene_file_apply). Zero-initialised,
 * every field means "the file's render block, else the default": a program passes on what
 * its user gave and leaves the rest 0 or NULL. */
typedef struct tr_render_request {
    uint32_t width, height;     /* the image; 0: render.width / render.height, else 800 / 600;
                                   one side alone: the other keeps that size's aspect */
    uint32_t spp;               /* samples per pixel; 0: render.spp, else 16 (tr_session's) */
    int max_depth;              /* 1..TR_MAX_DEPTH_LIMIT; 0: render.max_depth (at most
                                   TR_MAX_DEPTH_BDPT for bdpt and vcm), else the integrator's
                                   default */
    const char *integrator;     /* a name ("pt", "bdpt"); NULL: render.integrator, else pt */
    const char *accel;          /* a name ("bvh", "flat"); NULL: render.accel, else bvh */
    const char *light_sampling; /* "auto", "tree", "power"; NULL: render.light_sampling */
    int allow_dark;             /* nonzero: render a scene without an emitter even where the
                                   file does not set render.allow_no_emitter */
} tr_render_request;

/* The settings a render of the file uses, every default resolved. */
typedef struct tr_render_settings {
    uint32_t width, height; /* the image, and now the scene camera's screen */
    uint32_t spp;           /* for tr_session_desc.spp */
    tr_accel_type accel;    /* for tr_scene_commit: available in this build */
    /* tr_render_config_default() with the integrator and max_depth resolved (max_depth 0:
     * the integrator's default, tr_default_max_depth). */
    tr_render_config config;
} tr_render_settings;

/* Applies the render block of a scene file (or model file) that tr_scene_file_load,
 * tr_scene_file_parse or tr_scene_model_load just read into s and `file`: resolves the
 * request (NULL: a zero one) against the file's values and the defaults into *out,
 * resizes the scene's camera to the image size and sets the requested light sampling.
 * The scene is not committed: tr_scene_commit(s, out->accel, err) is next. `path` names
 * the file in messages. Fails, with a message naming the JSON path or request field at
 * fault, on:
 *   - an unknown integrator name in `file` (the JSON parser refuses those itself; a
 *     tr_scene_file filled another way): TR_STATUS_PARSE ("FILE: render.integrator:
 *     unknown integrator 'x' (available: pt, ...)");
 *   - an unknown integrator, accel or light sampling name in the request:
 *     TR_STATUS_INVALID_ARGUMENT;
 *   - an acceleration structure this build lacks (embree without Embree), the file's
 *     ("FILE: render.accel: ...") or the request's: TR_STATUS_UNSUPPORTED;
 *   - a scene without an emitter, an environment, a sun or a punctual light, unless
 *     render.allow_no_emitter or req->allow_dark: TR_STATUS_NOT_FOUND (the image would
 *     be black);
 *   - an image of more than TR_FILM_MAX_PIXELS pixels: TR_STATUS_LIMIT;
 *   - a camera that cannot take the size: tr_camera_resize's status.
 * On failure out still holds the image size and spp, resolved first (the size a
 * TR_STATUS_LIMIT names); the camera is resized only on success. */
int tr_scene_file_apply(tr_scene *s, const char *path, const tr_scene_file *file,
                        const tr_render_request *req, tr_render_settings *out, tr_error *err);

/* Reads and builds a scene file into s (a scene from tr_scene_create: whatever it held
 * is released first); the camera is set up for the file's image size
 * (render.width/height, default 800x600) - tr_camera_resize and tr_scene_set_camera for
 * another. The scene is not committed. opt may be NULL (meshes loaded, default budget);
 * info may be NULL. */
int tr_scene_file_load(tr_scene *s, const char *path, const tr_scene_file_options *opt,
                       tr_scene_file *info, tr_error *err);

/* The same from text in memory (need not be NUL-terminated). `path` names the file in
 * messages and mesh paths are relative to its directory. */
int tr_scene_file_parse(tr_scene *s, const char *path, const char *text, size_t len,
                        const tr_scene_file_options *opt, tr_scene_file *info, tr_error *err);

/* What importing one mesh file did. */
typedef struct tr_mesh_import_stats {
    uint32_t parts;      /* Assimp meshes with triangles */
    uint32_t triangles;  /* triangles added */
    uint32_t degenerate; /* faces dropped: points, lines or zero area */
    uint32_t materials;  /* materials added from the file (0 with an override) */
} tr_mesh_import_stats;

/* Imports every mesh of a model file through Assimp: node transforms applied, then `tf`
 * (NULL for none); each Assimp mesh becomes one shape. With material_override >= 0 every
 * triangle gets that material, otherwise the file's materials are mapped as
 * docs/scene-format.md describes. Fails, adding nothing, on an unreadable file, a file
 * Assimp cannot parse, one without triangles or more than max_triangles (0: no limit). */
int tr_scene_import_mesh(tr_scene *s, const char *path, const tr_transform *tf,
                         int64_t material_override, uint32_t max_triangles,
                         tr_mesh_import_stats *stats, tr_error *err);

/* A scene built around one model file (`trac0r render model.glb`): the model, turned so
 * that up_z models stand up (+z becomes +y) and scaled by `scale`; the file's camera (the
 * first, or the one `camera` names) if it has one, else one framing the model's bounding
 * sphere (40 degree vertical field of view, right-handed); the file's lights mapped onto
 * trac0r's (docs/scene-format.md, "Model files"; a warning names each approximated one),
 * and with them (unless one is ambient) a constant environment of radiance TR_MODEL_WORLD
 * (Blender's default world), or without any (or where every one is a point or spot light
 * inside the model's closed geometry, lighting nothing outside it) a constant grey
 * environment light of radiance TR_MODEL_SKY. info (may be NULL)
 * gets the counts, bounds, warnings (the import table's, naming materials and lights) and
 * render defaults (the file camera's aspect ratio when height is 0). */
#define TR_MODEL_SKY 0.5f
#define TR_MODEL_WORLD 0.05f
typedef struct tr_model_options {
    int up_z;
    float scale;            /* > 0 */
    uint32_t width, height; /* the camera's image size; 0 for 800 and 600 (or the aspect's) */
    const char *camera;     /* NULL: the first; "frame": the framing one; a name or index */
} tr_model_options;
int tr_scene_model_load(tr_scene *s, const char *path, const tr_model_options *opt,
                        tr_scene_file *info, tr_error *err);
/* Whether a scene name is a model file for tr_scene_model_load: a path (with a '/' or a
 * '.') that is not builtin:NAME and does not end in .json. */
int tr_scene_path_is_model(const char *path);
/* Whether a scene name is a built-in scene: "builtin:NAME", or a bare name without a '/'
 * or '.' (a file without an extension is written ./scene). */
int tr_scene_name_is_builtin(const char *name);

/* What a user adds to any scene or model before it is committed (the command's --env,
 * --sun and --ground): a zero struct adds nothing. */
typedef struct tr_scene_extras {
    const char *env;      /* "R,G,B" (a constant radiance) or an equirectangular image file
                             (.hdr, .png, ...): replaces the scene's environment; NULL: none */
    const char *sun;      /* "X,Y,Z": a sun towards that direction (0.53 degrees across),
                             replacing the scene's; NULL: none */
    float sun_irradiance; /* its irradiance per channel; 0: TR_SCENE_EXTRAS_SUN */
    int ground;           /* nonzero: a 0.5 grey diffuse floor just under the scene's bounds,
                             ten times their size */
} tr_scene_extras;
#define TR_SCENE_EXTRAS_SUN 3.0f
/* Adds x's extras to s (before tr_scene_commit). Fails with TR_STATUS_INVALID_ARGUMENT
 * naming "env", "sun" or "ground" and the value at fault, or the image reader's status. */
int tr_scene_add_extras(tr_scene *s, const tr_scene_extras *x, tr_error *err);

/* How a program opens a scene for rendering (tr_scene_open). A zero desc opens it as its
 * file says, with the library's defaults for the rest. */
typedef struct tr_scene_open_desc {
    tr_model_options model;     /* a model file's up axis, scale and camera (its width and
                                   height are ignored: the request's are used) */
    tr_render_request request;  /* what the user asked for: wins over the file */
    tr_render_request defaults; /* the program's own defaults, where neither the request nor
                                   the file gives a value (0/NULL: the library's); their
                                   allow_dark is ignored */
    tr_scene_extras extras;     /* added before the commit; an environment or a sun lets a
                                   scene without emitters render */
} tr_scene_open_desc;

/* tr_scene_file.open_stage: where tr_scene_open failed, so that a program can tell its
 * user which input was at fault (the file, an extra such as --env, a setting asked for, or
 * the acceleration structure) without reading the message. */
#define TR_SCENE_OPEN_LOAD 1u     /* tr_scene_load: the scene or model file */
#define TR_SCENE_OPEN_EXTRAS 2u   /* tr_scene_add_extras: "env", "sun" or "ground" */
#define TR_SCENE_OPEN_SETTINGS 3u /* tr_scene_file_apply: the request against the file */
#define TR_SCENE_OPEN_COMMIT 4u   /* tr_scene_commit: the acceleration structure */
/* Loads what `name` names (tr_scene_load: a built-in scene, a model or a scene file),
 * adds the extras, resolves the render settings (tr_scene_file_apply) into *out and
 * commits the scene with out->accel: the one call between a scene's name and
 * tr_session_create. `file` (may be NULL) gets what the file said and its warnings. On
 * failure the scene is left empty; the status is tr_scene_load's, tr_scene_add_extras's
 * (messages begin with "env", "sun" or "ground"), tr_scene_file_apply's or
 * tr_scene_commit's, and file->open_stage says which. */
int tr_scene_open(tr_scene *s, const char *name, const tr_scene_open_desc *d, tr_scene_file *file,
                  tr_render_settings *out, tr_error *err);

/* An image size with the sides left 0 filled in: both 0, dw x dh; one 0, from the other
 * with dw x dh's shape (rounded, 1..TR_FILM_MAX_SIDE), as resizing a picture keeps it. */
void tr_size_fill(uint32_t *width, uint32_t *height, uint32_t dw, uint32_t dh);

/* Loads any scene a name can give: a built-in scene (at opt's size, filled in from
 * 800x600 by tr_size_fill where a side is 0), a
 * model file (tr_scene_model_load with opt) or a scene file (tr_scene_file_load). `info`
 * (may be NULL) gets what the file says; for a built-in scene its size, shape count,
 * bounds and emitter counts. What `trac0r`'s SCENE argument accepts. */
int tr_scene_load(tr_scene *s, const char *name, const tr_model_options *opt, tr_scene_file *info,
                  tr_error *err);

/* What a loaded scene holds, as text (what `trac0r info` prints): its triangles, shapes,
 * materials, emitters, bounds, camera and sun, the first `listed` parts and materials one
 * line each, a file's render defaults (not for a built-in scene) and the warnings. `info`
 * is what tr_scene_load gave for `name`. Returns a string to free(), NULL when out of
 * memory. */
char *tr_scene_describe(const tr_scene *s, const char *name, const tr_scene_file *info,
                        uint32_t listed);

#endif
