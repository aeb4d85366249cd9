/* mesh.c - triangle meshes from model files through Assimp's C API. */
#define _POSIX_C_SOURCE 200809L
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <errno.h>
#include <stdarg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <dirent.h>
#include <sys/stat.h>

#include <assimp/GltfMaterial.h>
#include <cJSON.h>
#include <assimp/texture.h>

#include "scene/scene_internal.h"
#include "scene/texture.h"
#include "trac0r/scene_file.h"
#include "util/infile.h"
#include "scene/material_registry.h"
#include "scene/mesh_guard.h"

/* Node hierarchies deeper than this are refused (a hostile file could recurse forever). */
#define NODE_DEPTH_LIMIT 256

typedef struct import_ctx {
    tr_scene *s;
    const struct aiScene *ai;
    const tr_transform *tf;
    int64_t override;
    int64_t *material_map; /* Assimp material -> scene material, -1 until used */
    uint32_t max_triangles, start_triangles;
    tr_mesh_import_stats *st;
    tr_error *err;
    /* Where texture paths are relative to, warnings, textures already loaded
     * (keyed by their path as the file gives it; -1: failed, not tried again). */
    char dir[4096];
    tr_import_warn_fn warn;
    void *warn_ctx;
    struct {
        char path[256];
        uint32_t flags;
        int64_t index;
    } tex_cache[64];
    uint32_t tex_cached;
    tr_import_extras *extras; /* the file's first camera, when asked for */
    int gltf;                 /* a .gltf or .glb file (their cameras' conventions) */
    /* A Silo .sib file. Assimp's reader of them (5.2, and its source since) drops the
     * last character of every string the file holds (it overwrites it with the end of
     * string it expects there: 'This Way Up.pn' for 'This Way Up.png') and passes each
     * light's target point on as its direction (heffalump.sib: the spot light's "direction"
     * has its position's z to the last digit, and taken as a direction it points away from
     * the model, taken as a target at it). */
    int sib;
    /* With extras->instance_shared: how many times the node graph places each of the
     * file's meshes, and the prototype each shared one became (+1; 0: not yet; UINT32_MAX:
     * none, nothing but degenerate faces). */
    uint32_t *placements, *proto;
    /* A glTF file's own JSON (NULL for other formats, or where it cannot be read): the
     * extensions Assimp 5.2 does not pass on are read from it (gltf_material_json). */
    cJSON *gltf_root;
} import_ctx;

static void import_warn(const import_ctx *c, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
static void import_warn(const import_ctx *c, const char *fmt, ...) {
    if (!c->warn) {
        return;
    }
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    c->warn(c->warn_ctx, msg);
}

static float clamp01(float x) {
    return isfinite(x) ? (x < 0.0f ? 0.0f : x > 1.0f ? 1.0f : x) : 0.0f;
}

static float max3(float a, float b, float c) {
    float m = a > b ? a : b;
    return m > c ? m : c;
}

/* A file named `name` (any case) in dir, else in its subdirectories down to `depth` more
 * levels (hidden ones and links to directories skipped, at most *budget entries read),
 * into out. Returns 1 when found. How a model made on another machine finds its textures:
 * "D:/work/tex/wood.jpg" or "IMAGE1.JPG" for a file shipped as tex/wood.jpg or
 * IMAGE1.jpg, as Blender's importers do. */
static int find_by_name(const char *dir, const char *name, int depth, int *budget, char *out,
                        size_t n) {
    DIR *d = opendir(dir[0] ? dir : ".");
    if (!d) {
        return 0;
    }
    char subdirs[8][256];
    int nsub = 0, found = 0;
    for (struct dirent *e; !found && *budget > 0 && (e = readdir(d)) != NULL; --*budget) {
        if (e->d_name[0] == '.') {
            continue;
        }
        if (strcasecmp(e->d_name, name) == 0) {
            found = snprintf(out, n, "%s%s%s", dir, dir[0] ? "/" : "", e->d_name) < (int)n;
        } else if (depth > 0 && nsub < 8 && strlen(e->d_name) < sizeof subdirs[0]) {
            char sub[4096];
            struct stat st;
            if (snprintf(sub, sizeof sub, "%s%s%s", dir, dir[0] ? "/" : "", e->d_name) <
                    (int)sizeof sub &&
                lstat(sub, &st) == 0 && S_ISDIR(st.st_mode)) {
                snprintf(subdirs[nsub++], sizeof subdirs[0], "%s", e->d_name);
            }
        }
    }
    closedir(d);
    for (int i = 0; !found && depth > 0 && i < nsub; ++i) {
        char sub[4096];
        if (snprintf(sub, sizeof sub, "%s%s%s", dir, dir[0] ? "/" : "", subdirs[i]) <
            (int)sizeof sub) {
            found = find_by_name(sub, name, depth - 1, budget, out, n);
        }
    }
    return found;
}

/* The one file in dir whose name is `name` (any case) and one more character, into out
 * (at most *budget entries read, as find_by_name). Returns 1 when there is exactly one. */
static int find_one_longer(const char *dir, const char *name, int *budget, char *out, size_t n) {
    DIR *d = opendir(dir[0] ? dir : ".");
    if (!d) {
        return 0;
    }
    const size_t len = strlen(name);
    int found = 0;
    for (struct dirent *e; *budget > 0 && (e = readdir(d)) != NULL; --*budget) {
        if (e->d_name[0] != '.' && strlen(e->d_name) == len + 1 &&
            strncasecmp(e->d_name, name, len) == 0) {
            found += snprintf(out, n, "%s%s%s", dir, dir[0] ? "/" : "", e->d_name) < (int)n;
        }
    }
    closedir(d);
    return found == 1;
}

/* A texture file that is not where the model says: the same name in any case beside
 * where it was looked for, else its file name anywhere in the model's directory tree;
 * for a .sib file, whose names lose their last character on the way (import_ctx.sib),
 * the one file beside it whose name has one more. Returns 1 with the path in out. */
static int texture_fallback(const import_ctx *c, const char *full, char *out, size_t n) {
    struct stat st;
    if (stat(full, &st) == 0) {
        return 0; /* there, but unreadable: not a naming problem */
    }
    const char *slash = strrchr(full, '/');
    const char *name = slash ? slash + 1 : full;
    char here[4096];
    snprintf(here, sizeof here, "%.*s", slash ? (int)(slash - full) : 0, full);
    int budget = 20000;
    return name[0] && (find_by_name(here, name, 0, &budget, out, n) ||
                       find_by_name(c->dir, name, 4, &budget, out, n) ||
                       (c->sib && find_one_longer(here, name, &budget, out, n)));
}

/* Texture `type`, index `slot`, of material m as a scene texture: embedded ("*N", or a
 * name Assimp matches to an embedded texture) or a file beside the model. A texture that
 * cannot be read is a warning naming the material, and the material goes without it. */
static uint32_t load_texture(import_ctx *c, const struct aiMaterial *m, const char *mname,
                             enum aiTextureType type, unsigned int slot, const char *what) {
    struct aiString path;
    enum aiTextureMapMode mode[2] = {aiTextureMapMode_Wrap, aiTextureMapMode_Wrap};
    if (aiGetMaterialTexture(m, type, slot, &path, NULL, NULL, NULL, NULL, mode, NULL) !=
            AI_SUCCESS ||
        path.length == 0) {
        return TR_NO_INDEX;
    }
    const char *p = path.data;
    uint32_t flags = mode[0] == aiTextureMapMode_Clamp || mode[0] == aiTextureMapMode_Decal
                         ? TR_TEXTURE_CLAMP
                         : 0u;
    if (mode[0] == aiTextureMapMode_Mirror || mode[1] == aiTextureMapMode_Mirror) {
        import_warn(c, "material '%.60s': %s map '%.80s' mirrors; repeated instead", mname, what,
                    p);
    }
    for (uint32_t i = 0; i < c->tex_cached; ++i) {
        if (c->tex_cache[i].flags == flags && strcmp(c->tex_cache[i].path, p) == 0) {
            return c->tex_cache[i].index < 0 ? TR_NO_INDEX : (uint32_t)c->tex_cache[i].index;
        }
    }
    uint32_t index = TR_NO_INDEX;
    tr_error e;
    int rc = TR_ERR;
    /* Embedded: "*N", or the file name of one of the scene's embedded textures. */
    const struct aiTexture *emb = NULL;
    if (p[0] == '*') {
        char *end;
        unsigned long k = strtoul(p + 1, &end, 10);
        if (*end == '\0' && k < c->ai->mNumTextures) {
            emb = c->ai->mTextures[k];
        }
    }
    for (unsigned int k = 0; !emb && k < c->ai->mNumTextures; ++k) {
        const struct aiTexture *t = c->ai->mTextures[k];
        if (t && t->mFilename.length && strcmp(t->mFilename.data, p) == 0) {
            emb = t;
        }
    }
    if (emb && emb->pcData) {
        if (emb->mHeight == 0) {
            rc = tr_scene_load_texture_memory(c->s, (const unsigned char *)emb->pcData, emb->mWidth,
                                              p, flags, &index, &e);
        } else if ((uint64_t)emb->mWidth * emb->mHeight <= TR_TEXTURE_MAX_TEXELS) {
            size_t n = (size_t)emb->mWidth * emb->mHeight;
            uint32_t *rgba = malloc(n * sizeof *rgba);
            if (rgba) {
                for (size_t i = 0; i < n; ++i) {
                    const struct aiTexel *t = &emb->pcData[i]; /* BGRA */
                    rgba[i] = (uint32_t)t->r | ((uint32_t)t->g << 8) | ((uint32_t)t->b << 16) |
                              ((uint32_t)t->a << 24);
                }
                rc = tr_scene_add_texture(c->s, rgba, emb->mWidth, emb->mHeight, flags, &index, &e);
                free(rgba);
            } else {
                rc = tr_error_set(&e, TR_STATUS_OUT_OF_MEMORY, "out of memory");
            }
        } else {
            rc = tr_error_set(&e, TR_STATUS_LIMIT, "%ux%u texels", emb->mWidth, emb->mHeight);
        }
    } else if (p[0] == '*') {
        rc = tr_error_set(&e, TR_STATUS_NOT_FOUND, "no embedded texture %s", p);
    } else {
        char rel[1024], full[8192];
        snprintf(rel, sizeof rel, "%s", p);
        for (char *q = rel; *q; ++q) {
            *q = *q == '\\' ? '/' : *q; /* Windows separators, as Assimp hands them on */
        }
        if (rel[0] == '/' || !c->dir[0]) {
            snprintf(full, sizeof full, "%s", rel);
        } else {
            snprintf(full, sizeof full, "%s/%s", c->dir, rel);
        }
        rc = tr_mesh_check_confined(c->dir, full, &e);
        if (rc == TR_OK) {
            rc = tr_scene_load_texture(c->s, full, flags, &index, &e);
        }
        char found[4096];
        if (rc != TR_OK && texture_fallback(c, full, found, sizeof found) &&
            tr_mesh_check_confined(c->dir, found, &e) == TR_OK &&
            (rc = tr_scene_load_texture(c->s, found, flags, &index, &e)) == TR_OK) {
            import_warn(c, "material '%.60s': %s map '%.80s' not found as named; using '%.120s'",
                        mname, what, p, found);
        }
    }
    if (rc != TR_OK) {
        import_warn(c, "material '%.60s': %s map dropped: %.150s", mname, what, e.msg);
        index = TR_NO_INDEX;
    }
    if (c->tex_cached < sizeof c->tex_cache / sizeof c->tex_cache[0] &&
        strlen(p) < sizeof c->tex_cache[0].path) {
        snprintf(c->tex_cache[c->tex_cached].path, sizeof c->tex_cache[0].path, "%s", p);
        c->tex_cache[c->tex_cached].flags = flags;
        c->tex_cache[c->tex_cached].index = index == TR_NO_INDEX ? -1 : (int64_t)index;
        c->tex_cached++;
    }
    return index;
}

/* load_texture, seen through glTF's KHR_texture_transform where the material gives one
 * for that map. Assimp 5.2's glTF importer turns the extension's offset o, rotation r and
 * scale s into its own aiUVTransform (rotation -r about the image centre in its flipped
 * coordinates, with a translation that absorbs the change of origin); this undoes that
 * to get o, r and s back. Other formats' transforms are not read. */
static uint32_t load_texture_xf_at(import_ctx *c, const struct aiMaterial *m, const char *mname,
                                   enum aiTextureType type, unsigned int slot, const char *what) {
    uint32_t index = load_texture(c, m, mname, type, slot, what);
    struct aiUVTransform t;
    if (index == TR_NO_INDEX || !c->gltf ||
        aiGetMaterialUVTransform(m, AI_MATKEY_UVTRANSFORM(type, slot), &t) != AI_SUCCESS) {
        return index;
    }
    const double r = -(double)t.mRotation, sx = t.mScaling.x, sy = t.mScaling.y;
    const double co = cos(r), sn = sin(r);
    const double ou = t.mTranslation.x - 0.5 * sx * (1.0 - co + sn);
    const double ov = -(t.mTranslation.y - 0.5 * sy * (sn + co - 1.0) - 1.0 + sy);
    float xf[6];
    tr_texture_transform_glTF(xf, (float)ou, (float)ov, (float)r, (float)sx, (float)sy);
    tr_error e;
    uint32_t out = index;
    if (tr_scene_texture_transformed(c->s, index, xf, &out, &e) != TR_OK) {
        import_warn(c, "material '%.60s': %s map's transform dropped: %s", mname, what, e.msg);
        return index;
    }
    return out;
}

/* load_texture_xf_at for the first texture of that type. */
static uint32_t load_texture_xf(import_ctx *c, const struct aiMaterial *m, const char *mname,
                                enum aiTextureType type, const char *what) {
    return load_texture_xf_at(c, m, mname, type, 0, what);
}

/* The import table: a file's material (Wavefront MTL keys, glTF's metallic-roughness, and
 * whatever Assimp maps onto the same keys for other formats) onto ours, with its extras
 * (textures, emission, cut-out) in *ext (*has_ext set when there are any):
 *
 *   glTF metallic-roughness (metallicFactor or roughnessFactor present) -> principled:
 *     base colour factor (Kd where missing) x base colour map, metallic and roughness
 *     factors x the metallic-roughness map, normal map, emissive factor x emissive map;
 *     clear coat factor and roughness x their maps, and the coat's normal map
 *     (KHR_materials_clearcoat);
 *     transmission factor x its map (KHR_materials_transmission) and index
 *     (KHR_materials_ior, Assimp's refracti);
 *     the volume's attenuation (KHR_materials_volume); the emission x its strength
 *     (KHR_materials_emissive_strength); the sheen's colour and roughness x their
 *     maps (KHR_materials_sheen); the dielectric layer's specular factor and colour
 *     (KHR_materials_specular, from the file's JSON: gltf_material_json). A transmission factor
 * without a metallic- roughness material -> glass (colour: Kd, ior Ni or 1.5). otherwise Ke > 0
 * without an emissive map -> emitter (colour Ke / max(Ke), emittance max(Ke)); illum 4, 6, 7 or 9
 * (refraction) -> glass (colour Kd, ior Ni, 1.5 where missing or outside [1, 10]); illum 3, 5 or 8
 * -> glossy (colour Ks, or Kd where Ks is black, roughness sqrt(2 / (Ns + 2))); otherwise diffuse,
 * colour Kd x diffuse map. Opacity below 1 alone is not glass: glTF's alphaMode MASK cuts out below
 * its alphaCutoff, BLEND and MTL's d < 1 cut out below 0.5 where the base map has alpha and are
 * otherwise opaque (a warning says so). Maps we do not use (specular, bump/height, opacity,
 * ambient, shininess, displacement, light, reflection) are dropped with a warning naming the
 * material. Colours other than Ke and the emission are clamped to [0, 1]. */
/* The number at `key` of object o, or `fallback` where there is none (or not a finite
 * number). */
static double json_number(const cJSON *o, const char *key, double fallback) {
    const cJSON *v = o ? cJSON_GetObjectItemCaseSensitive(o, key) : NULL;
    return cJSON_IsNumber(v) && isfinite(v->valuedouble) ? v->valuedouble : fallback;
}

/* glTF material `index`'s extension `name` (an object), or NULL. Assimp 5.2 keeps the
 * file's materials in their order (and appends its default one after them), so an Assimp
 * material index below the file's count is the file's. */
static const cJSON *gltf_material_ext(const import_ctx *c, unsigned int index, const char *name) {
    const cJSON *mats =
        c->gltf_root ? cJSON_GetObjectItemCaseSensitive(c->gltf_root, "materials") : NULL;
    const cJSON *m = cJSON_IsArray(mats) ? cJSON_GetArrayItem(mats, (int)index) : NULL;
    const cJSON *exts = m ? cJSON_GetObjectItemCaseSensitive(m, "extensions") : NULL;
    const cJSON *e = exts ? cJSON_GetObjectItemCaseSensitive(exts, name) : NULL;
    return cJSON_IsObject(e) ? e : NULL;
}

/* The glTF extensions Assimp 5.2 does not pass on, read from the file's own JSON:
 * KHR_materials_emissive_strength (the emission's multiplier) and KHR_materials_specular
 * (the dielectric layer's F0 scale and tint; its two maps are not read, a warning says
 * so). Values out of the extension's range are clamped to it as the others are. */
static void gltf_material_json(import_ctx *c, unsigned int index, const char *mname,
                               int assimp_strength, tr_material_ext *ext) {
    const cJSON *es = gltf_material_ext(c, index, "KHR_materials_emissive_strength");
    const double strength = json_number(es, "emissiveStrength", 1.0);
    if (es && !assimp_strength && strength >= 0.0 && strength != 1.0) {
        const tr_vec3 em = v3_scale(ext->emission, (float)strength);
        ext->emission =
            v3(em.x < 1e7f ? em.x : 1e7f, em.y < 1e7f ? em.y : 1e7f, em.z < 1e7f ? em.z : 1e7f);
    }
    const cJSON *sp = gltf_material_ext(c, index, "KHR_materials_specular");
    if (!sp) {
        return;
    }
    const double f = json_number(sp, "specularFactor", 1.0);
    tr_vec3 col = v3s(1.0f);
    const cJSON *cf = cJSON_GetObjectItemCaseSensitive(sp, "specularColorFactor");
    if (cJSON_IsArray(cf) && cJSON_GetArraySize(cf) == 3) {
        float k[3];
        for (int i = 0; i < 3; ++i) {
            const cJSON *x = cJSON_GetArrayItem(cf, i);
            const double v = cJSON_IsNumber(x) && isfinite(x->valuedouble) ? x->valuedouble : 1.0;
            k[i] = (float)(v < 0.0 ? 0.0 : v > 10.0 ? 10.0 : v);
        }
        col = v3(k[0], k[1], k[2]);
    }
    ext->flags |= TR_MATEXT_SPECULAR;
    ext->specular = (float)(f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f);
    ext->specular_color = col;
    if (cJSON_GetObjectItemCaseSensitive(sp, "specularTexture") ||
        cJSON_GetObjectItemCaseSensitive(sp, "specularColorTexture")) {
        import_warn(c,
                    "material '%.60s': KHR_materials_specular's specularTexture and "
                    "specularColorTexture are not read (its factors are used)",
                    mname);
    }
}

static tr_material map_material(import_ctx *c, unsigned int index, const struct aiMaterial *m,
                                tr_material_ext *ext, int *has_ext) {
    struct aiColor4D kd = {0.6f, 0.6f, 0.6f, 1.0f}, ks = {0, 0, 0, 1}, ke = {0, 0, 0, 1};
    struct aiColor4D base = {0, 0, 0, 0};
    aiGetMaterialColor(m, AI_MATKEY_COLOR_DIFFUSE, &kd);
    aiGetMaterialColor(m, AI_MATKEY_COLOR_SPECULAR, &ks);
    aiGetMaterialColor(m, AI_MATKEY_COLOR_EMISSIVE, &ke);
    int has_base = aiGetMaterialColor(m, AI_MATKEY_BASE_COLOR, &base) == AI_SUCCESS;
    ai_real ni = 0.0f, d = 1.0f, ns = 0.0f, metal = 0.0f, rough = 1.0f, transmission = 0.0f;
    ai_real cutoff = 0.5f;
    unsigned int one = 1;
    aiGetMaterialFloatArray(m, AI_MATKEY_REFRACTI, &ni, &one);
    one = 1;
    aiGetMaterialFloatArray(m, AI_MATKEY_OPACITY, &d, &one);
    one = 1;
    aiGetMaterialFloatArray(m, AI_MATKEY_SHININESS, &ns, &one);
    one = 1;
    int pbr = aiGetMaterialFloatArray(m, AI_MATKEY_METALLIC_FACTOR, &metal, &one) == AI_SUCCESS;
    one = 1;
    pbr |= aiGetMaterialFloatArray(m, AI_MATKEY_ROUGHNESS_FACTOR, &rough, &one) == AI_SUCCESS;
    one = 1;
    aiGetMaterialFloatArray(m, AI_MATKEY_TRANSMISSION_FACTOR, &transmission, &one);
    one = 1;
    aiGetMaterialFloatArray(m, AI_MATKEY_GLTF_ALPHACUTOFF, &cutoff, &one);
    int illum = -1;
    one = 1;
    aiGetMaterialIntegerArray(m, "$mat.illum", 0, 0, &illum, &one);
    struct aiString name, alpha_mode;
    char mname[64] = "(unnamed)";
    if (aiGetMaterialString(m, AI_MATKEY_NAME, &name) == AI_SUCCESS && name.length) {
        snprintf(mname, sizeof mname, "%.63s", name.data);
    }
    int mask = 0, blend = 0;
    if (aiGetMaterialString(m, AI_MATKEY_GLTF_ALPHAMODE, &alpha_mode) == AI_SUCCESS) {
        mask = strcmp(alpha_mode.data, "MASK") == 0;
        blend = strcmp(alpha_mode.data, "BLEND") == 0;
    }

    *ext = tr_material_ext_default();
    *has_ext = 0;
    tr_vec3 diffuse = v3(clamp01(kd.r), clamp01(kd.g), clamp01(kd.b));
    if (has_base) {
        diffuse = v3(clamp01(base.r), clamp01(base.g), clamp01(base.b));
    }
    /* A file without materials gets a stand-in from Assimp: STL's is named
     * AI_DEFAULT_MATERIAL_NAME, PLY's is unnamed with a white Kd. Their white would glow
     * under the white sky a bare model is rendered in: the documented 0.6 grey instead
     * (docs/scene-format.md). */
    const int stand_in = strcmp(mname, AI_DEFAULT_MATERIAL_NAME) == 0 ||
                         (strcmp(mname, "(unnamed)") == 0 && !has_base && kd.r == 1.0f &&
                          kd.g == 1.0f && kd.b == 1.0f);
    if (stand_in && aiGetMaterialTextureCount(m, aiTextureType_DIFFUSE) == 0 &&
        aiGetMaterialTextureCount(m, aiTextureType_BASE_COLOR) == 0) {
        diffuse = v3(0.6f, 0.6f, 0.6f);
    }
    float e[3] = {ke.r, ke.g, ke.b};
    for (int i = 0; i < 3; ++i) {
        e[i] = isfinite(e[i]) && e[i] > 0.0f ? (e[i] > 1e7f ? 1e7f : e[i]) : 0.0f;
    }
    float emax = max3(e[0], e[1], e[2]);
    const int refract = illum == 4 || illum == 6 || illum == 7 || illum == 9;
    const int transmit = isfinite(transmission) && transmission > 0.0f;
    if ((transmit && !pbr) || (refract && !pbr)) {
        float ior = isfinite(ni) && ni >= 1.0f && ni <= 10.0f ? ni : 1.5f;
        if (transmit && transmission < 1.0f) {
            import_warn(c, "material '%.60s': transmission %.2f taken as fully transmissive glass",
                        mname, (double)transmission);
        }
        return tr_material_glass(diffuse, ior);
    }
    uint32_t emission_tex = load_texture_xf(c, m, mname, aiTextureType_EMISSIVE, "emissive");
    if (emax > 0.0f && emission_tex == TR_NO_INDEX && !pbr) {
        return tr_material_emitter(v3(e[0] / emax, e[1] / emax, e[2] / emax), emax);
    }
    ext->base_tex = load_texture_xf(
        c, m, mname, has_base ? aiTextureType_BASE_COLOR : aiTextureType_DIFFUSE, "base colour");
    if (ext->base_tex == TR_NO_INDEX) {
        ext->base_tex = load_texture_xf(c, m, mname, aiTextureType_DIFFUSE, "diffuse");
    }
    ext->normal_tex = load_texture_xf(c, m, mname, aiTextureType_NORMALS, "normal");
    ext->emission_tex = emission_tex;
    ext->emission = v3(e[0], e[1], e[2]);
    if (emission_tex != TR_NO_INDEX && emax <= 0.0f) {
        ext->emission = v3s(1.0f);
    }
    /* Cut-outs: glTF MASK at its cutoff; BLEND and d < 1 at 0.5 where the base map can
     * say where (its alpha), else opaque. */
    if (mask || ((blend || (isfinite(d) && d < 1.0f)) && ext->base_tex != TR_NO_INDEX)) {
        ext->flags |= TR_MATEXT_ALPHA_MASK;
        ext->alpha_cutoff = mask && isfinite(cutoff) ? clamp01(cutoff) : 0.5f;
        if (!mask) {
            import_warn(c, "material '%.60s': %s approximated by a cut-out at alpha 0.5", mname,
                        blend ? "alpha blending" : "opacity below 1");
        }
    } else if (blend || (isfinite(d) && d < 1.0f)) {
        import_warn(c, "material '%.60s': opacity %.2f without a map taken as opaque", mname,
                    (double)d);
    }
    static const struct {
        enum aiTextureType type;
        const char *what;
    } unused[] = {
        {aiTextureType_SPECULAR, "specular"},   {aiTextureType_HEIGHT, "bump"},
        {aiTextureType_OPACITY, "opacity"},     {aiTextureType_AMBIENT, "ambient"},
        {aiTextureType_SHININESS, "shininess"}, {aiTextureType_DISPLACEMENT, "displacement"},
        {aiTextureType_LIGHTMAP, "light"},      {aiTextureType_REFLECTION, "reflection"}};
    for (size_t i = 0; i < sizeof unused / sizeof unused[0]; ++i) {
        if (aiGetMaterialTextureCount(m, unused[i].type) > 0) {
            import_warn(c, "material '%.60s': %s map dropped (not supported)", mname,
                        unused[i].what);
        }
    }
    tr_material out;
    if (pbr) {
        ext->mr_tex = load_texture_xf(c, m, mname, aiTextureType_UNKNOWN, "metallic-roughness");
        if (ext->mr_tex == TR_NO_INDEX) {
            ext->mr_tex =
                load_texture_xf(c, m, mname, aiTextureType_DIFFUSE_ROUGHNESS, "metallic-roughness");
        }
        ext->metallic = clamp01(metal);
        /* KHR_materials_clearcoat: the coat's weight and roughness, each times its map
         * (Assimp 5.1 on: aiTextureType_CLEARCOAT, index 0 the weight in red, index 1 the
         * roughness in green), and the coat's own normal map (index 2) with its scale. */
        ai_real coat = 0.0f, coat_rough = 0.0f;
        one = 1;
        aiGetMaterialFloatArray(m, AI_MATKEY_CLEARCOAT_FACTOR, &coat, &one);
        one = 1;
        aiGetMaterialFloatArray(m, AI_MATKEY_CLEARCOAT_ROUGHNESS_FACTOR, &coat_rough, &one);
        if (isfinite(coat) && coat > 0.0f) {
            ext->clearcoat = clamp01(coat);
            ext->clearcoat_roughness = isfinite(coat_rough) ? clamp01(coat_rough) : 0.0f;
            ext->clearcoat_tex =
                load_texture_xf_at(c, m, mname, aiTextureType_CLEARCOAT, 0, "clear coat");
            ext->clearcoat_rough_tex =
                load_texture_xf_at(c, m, mname, aiTextureType_CLEARCOAT, 1, "clear coat roughness");
            ext->clearcoat_normal_tex =
                load_texture_xf_at(c, m, mname, aiTextureType_CLEARCOAT, 2, "clear coat normal");
            ai_real nscale = 1.0f;
            one = 1;
            if (ext->clearcoat_normal_tex != TR_NO_INDEX &&
                aiGetMaterialFloatArray(m, AI_MATKEY_GLTF_TEXTURE_SCALE(aiTextureType_CLEARCOAT, 2),
                                        &nscale, &one) == AI_SUCCESS &&
                isfinite(nscale)) {
                ext->clearcoat_normal_scale = nscale;
            }
        }
        /* KHR_materials_sheen: the sheen's colour and roughness, times their maps (Assimp
         * 5.1 on: aiTextureType_SHEEN, index 0 the colour (sRGB), index 1 the roughness in
         * its alpha; Assimp passes them only with a colour factor that is not black). */
        ai_real sheen_rough = 0.0f, strength = 0.0f;
        struct aiColor4D sheen = {0, 0, 0, 1};
        one = 1;
        if (aiGetMaterialColor(m, AI_MATKEY_SHEEN_COLOR_FACTOR, &sheen) == AI_SUCCESS &&
            isfinite(sheen.r) && isfinite(sheen.g) && isfinite(sheen.b)) {
            ext->sheen_color = v3(clamp01(sheen.r), clamp01(sheen.g), clamp01(sheen.b));
            if (aiGetMaterialFloatArray(m, AI_MATKEY_SHEEN_ROUGHNESS_FACTOR, &sheen_rough, &one) ==
                    AI_SUCCESS &&
                isfinite(sheen_rough)) {
                ext->sheen_roughness = clamp01(sheen_rough);
            }
        }
        if (max3(ext->sheen_color.x, ext->sheen_color.y, ext->sheen_color.z) > 0.0f) {
            ext->sheen_color_tex =
                load_texture_xf_at(c, m, mname, aiTextureType_SHEEN, 0, "sheen colour");
            ext->sheen_rough_tex =
                load_texture_xf_at(c, m, mname, aiTextureType_SHEEN, 1, "sheen roughness");
        }
        one = 1;
        const int assimp_strength =
            aiGetMaterialFloatArray(m, AI_MATKEY_EMISSIVE_INTENSITY, &strength, &one) == AI_SUCCESS;
        if (assimp_strength && isfinite(strength) && strength >= 0.0f && strength != 1.0f) {
            /* KHR_materials_emissive_strength scales the emissive factor. */
            tr_vec3 em = v3_scale(ext->emission, strength);
            ext->emission =
                v3(em.x < 1e7f ? em.x : 1e7f, em.y < 1e7f ? em.y : 1e7f, em.z < 1e7f ? em.z : 1e7f);
        }
        gltf_material_json(c, index, mname, assimp_strength, ext);
        /* KHR_materials_transmission with its map (Assimp 5.1 on: aiTextureType_TRANSMISSION,
         * index 0; the red channel times the factor) and KHR_materials_ior, and
         * KHR_materials_volume's attenuation. Its thickness, factor and map (the same type,
         * index 1), is a rasteriser's stand-in for the distance a path tracer measures, and
         * is not needed. */
        if (transmit) {
            ext->transmission = clamp01(transmission);
            ext->transmission_tex =
                load_texture_xf(c, m, mname, aiTextureType_TRANSMISSION, "transmission");
        }
        ai_real att_dist = 0.0f;
        struct aiColor4D att = {1, 1, 1, 1};
        one = 1;
        if (aiGetMaterialFloatArray(m, AI_MATKEY_VOLUME_ATTENUATION_DISTANCE, &att_dist, &one) ==
                AI_SUCCESS &&
            isfinite(att_dist) && att_dist > 0.0f &&
            aiGetMaterialColor(m, AI_MATKEY_VOLUME_ATTENUATION_COLOR, &att) == AI_SUCCESS) {
            ext->absorption =
                tr_volume_absorption(v3(clamp01(att.r), clamp01(att.g), clamp01(att.b)), att_dist);
        }
        tr_material pm = tr_material_default(TR_MATERIAL_PRINCIPLED);
        pm.color = diffuse;
        pm.roughness = clamp01(rough);
        pm.ior = isfinite(ni) && ni >= 1.0f && ni <= 10.0f ? ni : 1.5f;
        out = pm;
    } else if (illum == 3 || illum == 5 || illum == 8) {
        tr_vec3 spec = v3(clamp01(ks.r), clamp01(ks.g), clamp01(ks.b));
        if (!(max3(spec.x, spec.y, spec.z) > 0.0f)) {
            spec = diffuse;
        }
        float r = isfinite(ns) && ns >= 0.0f ? sqrtf(2.0f / (ns + 2.0f)) : 1.0f;
        out = tr_material_glossy(spec, r > 1.0f ? 1.0f : r);
    } else {
        out = tr_material_diffuse(diffuse);
    }
    *has_ext = ext->base_tex != TR_NO_INDEX || ext->normal_tex != TR_NO_INDEX ||
               ext->emission_tex != TR_NO_INDEX || ext->mr_tex != TR_NO_INDEX ||
               ext->transmission_tex != TR_NO_INDEX || (ext->flags & TR_MATEXT_ALPHA_MASK) ||
               ext->metallic > 0.0f || ext->clearcoat > 0.0f || ext->emission.x > 0.0f ||
               ext->emission.y > 0.0f || ext->emission.z > 0.0f || ext->transmission > 0.0f ||
               ext->absorption.x > 0.0f || ext->absorption.y > 0.0f || ext->absorption.z > 0.0f ||
               ext->sheen_color.x > 0.0f || ext->sheen_color.y > 0.0f ||
               ext->sheen_color.z > 0.0f || (ext->flags & TR_MATEXT_SPECULAR);
    return out;
}

static int material_of(import_ctx *c, unsigned int index, uint32_t *out) {
    if (c->override >= 0) {
        *out = (uint32_t)c->override;
        return TR_OK;
    }
    if (index >= c->ai->mNumMaterials) {
        return tr_error_set(c->err, TR_STATUS_PARSE, "a mesh refers to material %u of %u", index,
                            c->ai->mNumMaterials);
    }
    if (c->material_map[index] < 0) {
        uint32_t m;
        tr_material_ext ext;
        int has_ext;
        tr_material mat = map_material(c, index, c->ai->mMaterials[index], &ext, &has_ext);
        if (tr_scene_add_material(c->s, mat, &m, c->err) != TR_OK ||
            (has_ext && tr_scene_set_material_ext(c->s, m, &ext, c->err) != TR_OK)) {
            return TR_ERR;
        }
        c->material_map[index] = m;
        c->st->materials++;
    }
    *out = (uint32_t)c->material_map[index];
    return TR_OK;
}

static struct aiMatrix4x4 mat_mul(const struct aiMatrix4x4 *a, const struct aiMatrix4x4 *b) {
    const ai_real *x = &a->a1, *y = &b->a1;
    struct aiMatrix4x4 r;
    ai_real *o = &r.a1;
    for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) {
            ai_real sum = 0;
            for (int k = 0; k < 4; ++k) {
                sum += x[4 * i + k] * y[4 * k + j];
            }
            o[4 * i + j] = sum;
        }
    }
    return r;
}

static int add_ai_mesh(import_ctx *c, const struct aiMesh *mesh, const struct aiMatrix4x4 *m) {
    uint32_t tris = 0;
    for (unsigned int f = 0; f < mesh->mNumFaces; ++f) {
        if (mesh->mFaces[f].mNumIndices == 3) {
            tris++;
        } else {
            c->st->degenerate++;
        }
    }
    if (tris == 0 || !mesh->mVertices) {
        return TR_OK;
    }
    if ((uint64_t)c->s->triangle_count - c->start_triangles + tris > c->max_triangles) {
        return tr_error_set(c->err, TR_STATUS_LIMIT,
                            "more than %u triangles (the scene's triangle budget)",
                            c->max_triangles);
    }
    uint32_t material = 0;
    if (material_of(c, mesh->mMaterialIndex, &material) != TR_OK) {
        return TR_ERR;
    }
    const uint32_t nv = mesh->mNumVertices;
    float *pos = malloc((size_t)nv * 3 * sizeof *pos);
    float *nrm = mesh->mNormals ? malloc((size_t)nv * 3 * sizeof *nrm) : NULL;
    const struct aiVector3D *tc = mesh->mTextureCoords[0];
    float *uv = tc ? malloc((size_t)nv * 2 * sizeof *uv) : NULL;
    uint32_t *idx = malloc((size_t)tris * 3 * sizeof *idx);
    if (!pos || !idx || (mesh->mNormals && !nrm) || (tc && !uv)) {
        free(pos);
        free(nrm);
        free(uv);
        free(idx);
        return tr_error_set(c->err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory importing a mesh of %u triangles", tris);
    }
    /* Normals go through the cofactor matrix of the upper 3x3 (its inverse transpose
     * times the determinant), with the determinant's sign. */
    const float a = m->a1, b = m->a2, cc = m->a3, d = m->b1, e = m->b2, f = m->b3, g = m->c1,
                h = m->c2, k = m->c3;
    const float cof[9] = {e * k - f * h,  f * g - d * k,  d * h - e * g,
                          cc * h - b * k, a * k - cc * g, b * g - a * h,
                          b * f - cc * e, cc * d - a * f, a * e - b * d};
    const float det = a * cof[0] + b * cof[1] + cc * cof[2];
    const float sgn = det < 0.0f ? -1.0f : 1.0f;
    for (uint32_t v = 0; v < nv; ++v) {
        const struct aiVector3D p = mesh->mVertices[v];
        pos[3 * v + 0] = m->a1 * p.x + m->a2 * p.y + m->a3 * p.z + m->a4;
        pos[3 * v + 1] = m->b1 * p.x + m->b2 * p.y + m->b3 * p.z + m->b4;
        pos[3 * v + 2] = m->c1 * p.x + m->c2 * p.y + m->c3 * p.z + m->c4;
        if (nrm) {
            const struct aiVector3D n = mesh->mNormals[v];
            nrm[3 * v + 0] = sgn * (cof[0] * n.x + cof[1] * n.y + cof[2] * n.z);
            nrm[3 * v + 1] = sgn * (cof[3] * n.x + cof[4] * n.y + cof[5] * n.z);
            nrm[3 * v + 2] = sgn * (cof[6] * n.x + cof[7] * n.y + cof[8] * n.z);
        }
        if (uv) {
            /* Assimp's v grows upwards (OpenGL); ours downwards, as image rows. */
            uv[2 * v + 0] = tc[v].x;
            uv[2 * v + 1] = 1.0f - tc[v].y;
        }
    }
    uint32_t t = 0;
    int rc = TR_OK;
    for (unsigned int fi = 0; fi < mesh->mNumFaces; ++fi) {
        const struct aiFace *face = &mesh->mFaces[fi];
        if (face->mNumIndices != 3) {
            continue;
        }
        for (int j = 0; j < 3; ++j) {
            idx[3 * t + j] = face->mIndices[j];
        }
        t++;
    }
    uint32_t dropped = 0;
    rc = tr_scene_add_mesh_uv(c->s, pos, nv, idx, tris, nrm, uv, material, c->tf, &dropped, c->err);
    c->st->degenerate += dropped;
    if (rc == TR_OK) {
        c->st->parts++;
        c->st->triangles += tris - dropped;
    } else if (dropped == tris) {
        rc = TR_OK; /* nothing but degenerate faces: dropped and counted */
    }
    free(pos);
    free(nrm);
    free(uv);
    free(idx);
    return rc;
}

/* Point p (w = 1) or direction p (w = 0) through m, then through the import's tf. */
static tr_vec3 place(const import_ctx *c, const struct aiMatrix4x4 *m, struct aiVector3D p,
                     float w) {
    tr_vec3 q = v3(m->a1 * p.x + m->a2 * p.y + m->a3 * p.z + w * m->a4,
                   m->b1 * p.x + m->b2 * p.y + m->b3 * p.z + w * m->b4,
                   m->c1 * p.x + m->c2 * p.y + m->c3 * p.z + w * m->c4);
    tr_transform identity = {v3s(0.0f), v3s(0.0f), v3s(1.0f)};
    const tr_transform *tf = c->tf ? c->tf : &identity;
    if (w != 0.0f) {
        return tr_transform_point(tf, q);
    }
    /* Directions turn with the transform (its scale is uniform or irrelevant). */
    return v3_normalize(v3_sub(tr_transform_point(tf, q), tr_transform_point(tf, v3s(0.0f))));
}

/* The camera asked for and every light whose name is this node's, placed by m. */
static void place_extras(import_ctx *c, const struct aiNode *node, const struct aiMatrix4x4 *m) {
    tr_import_extras *x = c->extras;
    const unsigned int want = (unsigned int)x->camera_want;
    if (!x->has_camera && want < c->ai->mNumCameras && c->ai->mCameras[want] &&
        strcmp(c->ai->mCameras[want]->mName.data, node->mName.data) == 0) {
        const struct aiCamera *cam = c->ai->mCameras[want];
        /* Assimp 5.2's glTF importer copies the node's translation into mPosition and
         * keeps it in the node's transform too: a glTF camera sits at its node's origin. */
        const struct aiVector3D origin = {0.0f, 0.0f, 0.0f};
        x->cam_gltf = c->gltf;
        x->cam_pos = place(c, m, c->gltf ? origin : cam->mPosition, 1.0f);
        x->cam_dir = place(c, m, cam->mLookAt, 0.0f);
        x->cam_up = place(c, m, cam->mUp, 0.0f);
        x->cam_hfov = cam->mHorizontalFOV;
        x->cam_aspect = cam->mAspect;
        snprintf(x->cam_name, sizeof x->cam_name, "%.63s", cam->mName.data);
        x->has_camera = v3_is_finite(x->cam_pos) && v3_is_finite(x->cam_dir) &&
                        v3_is_finite(x->cam_up) && isfinite(cam->mHorizontalFOV);
    }
    for (unsigned int i = 0; i < c->ai->mNumLights && x->light_count < TR_IMPORT_MAX_LIGHTS; ++i) {
        const struct aiLight *l = c->ai->mLights[i];
        if (!l || strcmp(l->mName.data, node->mName.data) != 0) {
            continue;
        }
        tr_import_light *o = &x->light[x->light_count++];
        memset(o, 0, sizeof *o);
        o->type = (int)l->mType;
        snprintf(o->name, sizeof o->name, "%.63s", l->mName.data);
        o->pos = place(c, m, l->mPosition, 1.0f);
        struct aiVector3D dir = l->mDirection;
        if (c->sib) { /* the light's target (import_ctx.sib) */
            dir.x -= l->mPosition.x;
            dir.y -= l->mPosition.y;
            dir.z -= l->mPosition.z;
        }
        o->dir = place(c, m, dir, 0.0f);
        o->color = v3(l->mColorDiffuse.r, l->mColorDiffuse.g, l->mColorDiffuse.b);
        o->outer_cone = l->mAngleOuterCone;
        o->inner_cone = l->mAngleInnerCone;
        o->gltf = c->gltf;
        o->size_x = l->mSize.x;
        o->size_y = l->mSize.y;
        o->att[0] = l->mAttenuationConstant;
        o->att[1] = l->mAttenuationLinear;
        o->att[2] = l->mAttenuationQuadratic;
    }
}

int tr_model_find_camera(const char *path, const char *name, int *index, tr_error *err) {
    const struct aiScene *ai = tr_mesh_guarded_import(path, aiProcess_ValidateDataStructure, err);
    if (!ai) {
        return TR_ERR;
    }
    int rc = TR_ERR;
    char *end = NULL;
    long k = strtol(name, &end, 10);
    for (unsigned int i = 0; i < ai->mNumCameras; ++i) {
        if ((end != name && *end == '\0' && k == (long)i) ||
            (ai->mCameras[i] && strcmp(ai->mCameras[i]->mName.data, name) == 0)) {
            *index = (int)i;
            rc = TR_OK;
            break;
        }
    }
    if (rc != TR_OK) {
        tr_error_set(err, TR_STATUS_NOT_FOUND, "'%.200s' has no camera '%.64s' (it has %u%s%.64s)",
                     path, name, ai->mNumCameras, ai->mNumCameras ? ": 0 is " : "",
                     ai->mNumCameras && ai->mCameras[0] ? ai->mCameras[0]->mName.data : "");
    }
    aiReleaseImport(ai);
    return rc;
}

/* Counts how many times the node graph under `node` places each mesh (bounded depth, as
 * walk). */
static void count_placements(import_ctx *c, const struct aiNode *node, int depth) {
    if (depth > NODE_DEPTH_LIMIT) {
        return;
    }
    for (unsigned int i = 0; i < node->mNumMeshes; ++i) {
        if (node->mMeshes[i] < c->ai->mNumMeshes && c->placements[node->mMeshes[i]] < UINT32_MAX) {
            c->placements[node->mMeshes[i]]++;
        }
    }
    for (unsigned int i = 0; i < node->mNumChildren; ++i) {
        count_placements(c, node->mChildren[i], depth + 1);
    }
}

/* Places shared mesh `mi` with node matrix m as an instance of its prototype (made at its
 * first placement from the mesh in its own coordinates): the matrix is the import's
 * transform after m, and the image is the flattened one's up to float rounding (the
 * matrices are composed once instead of applied one after the other). A placement the
 * instance refuses (a singular node matrix) is added flattened, as without instancing,
 * which drops its degenerate faces. */
static int place_shared(import_ctx *c, unsigned int mi, const struct aiMatrix4x4 *m) {
    const struct aiMesh *mesh = c->ai->mMeshes[mi];
    tr_mesh_import_stats *st = c->st;
    if (c->proto[mi] == 0u) {
        const uint32_t first = c->s->shape_count, parts = st->parts, tris = st->triangles;
        const tr_transform *tf = c->tf;
        const struct aiMatrix4x4 id = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        c->tf = NULL;
        const int rc = add_ai_mesh(c, mesh, &id);
        c->tf = tf;
        if (rc != TR_OK) {
            return TR_ERR;
        }
        /* Counted below, once per placement. */
        st->parts = parts;
        st->triangles = tris;
        uint32_t p = UINT32_MAX;
        if (c->s->shape_count > first &&
            tr_scene_make_prototype(c->s, first, &p, c->err) != TR_OK) {
            return TR_ERR;
        }
        c->proto[mi] = p == UINT32_MAX ? UINT32_MAX : p + 1u;
    }
    if (c->proto[mi] == UINT32_MAX) {
        return add_ai_mesh(c, mesh, m); /* degenerate faces only: dropped and counted */
    }
    const uint32_t proto = c->proto[mi] - 1u;
    const uint32_t n = tr_scene_prototype_triangle_count(c->s, proto);
    if ((uint64_t)c->s->triangle_count - c->start_triangles + n > c->max_triangles) {
        return tr_error_set(c->err, TR_STATUS_LIMIT,
                            "more than %u triangles (the scene's triangle budget)",
                            c->max_triangles);
    }
    float t[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    if (c->tf) {
        tr_transform_matrix(c->tf, t);
    }
    const float a[12] = {m->a1, m->a2, m->a3, m->a4, m->b1, m->b2,
                         m->b3, m->b4, m->c1, m->c2, m->c3, m->c4};
    float w[12];
    for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 4; ++k) {
            w[4 * r + k] = t[4 * r] * a[k] + t[4 * r + 1] * a[4 + k] + t[4 * r + 2] * a[8 + k] +
                           (k == 3 ? t[4 * r + 3] : 0.0f);
        }
    }
    tr_error e;
    if (tr_scene_add_instance(c->s, proto, w, NULL, &e) != TR_OK) {
        if (e.code != TR_STATUS_INVALID_ARGUMENT) {
            if (c->err) {
                *c->err = e;
            }
            return TR_ERR;
        }
        return add_ai_mesh(c, mesh, m);
    }
    st->parts++;
    st->triangles += n;
    return TR_OK;
}

static int walk(import_ctx *c, const struct aiNode *node, const struct aiMatrix4x4 *parent,
                int depth) {
    if (depth > NODE_DEPTH_LIMIT) {
        return tr_error_set(c->err, TR_STATUS_LIMIT, "node hierarchy deeper than %d",
                            NODE_DEPTH_LIMIT);
    }
    struct aiMatrix4x4 m = mat_mul(parent, &node->mTransformation);
    /* A model's cameras and lights sit at the nodes of their names. */
    if (c->extras) {
        place_extras(c, node, &m);
    }
    for (unsigned int i = 0; i < node->mNumMeshes; ++i) {
        if (node->mMeshes[i] >= c->ai->mNumMeshes) {
            return tr_error_set(c->err, TR_STATUS_PARSE, "a node refers to mesh %u of %u",
                                node->mMeshes[i], c->ai->mNumMeshes);
        }
        const unsigned int mi = node->mMeshes[i];
        if (c->placements && c->placements[mi] >= 2u
                ? place_shared(c, mi, &m) != TR_OK
                : add_ai_mesh(c, c->ai->mMeshes[mi], &m) != TR_OK) {
            return TR_ERR;
        }
    }
    for (unsigned int i = 0; i < node->mNumChildren; ++i) {
        if (walk(c, node->mChildren[i], &m, depth + 1) != TR_OK) {
            return TR_ERR;
        }
    }
    return TR_OK;
}

/* glTF's JSON text of `path` (a .gltf file, or a .glb file's first chunk), or NULL where
 * it cannot be had; free() it. At most GLTF_JSON_MAX bytes are read. */
#define GLTF_JSON_MAX (64u << 20)
static char *gltf_json(const char *path, int glb) {
    uint64_t bytes = 0;
    tr_error e;
    FILE *fp = tr_infile_open(path, &bytes, &e);
    if (!fp) {
        return NULL;
    }
    uint32_t len = bytes > GLTF_JSON_MAX ? 0u : (uint32_t)bytes;
    if (glb) {
        /* Header: magic, version, length; then the JSON chunk's length and type. */
        unsigned char h[20];
        len = 0;
        if (fread(h, 1, sizeof h, fp) == sizeof h && memcmp(h, "glTF", 4) == 0 &&
            memcmp(h + 16, "JSON", 4) == 0) {
            uint32_t n = (uint32_t)h[12] | (uint32_t)h[13] << 8 | (uint32_t)h[14] << 16 |
                         (uint32_t)h[15] << 24;
            len = n <= GLTF_JSON_MAX && (uint64_t)n + 20 <= bytes ? n : 0u;
        }
    }
    char *text = len ? malloc((size_t)len + 1) : NULL;
    if (text && fread(text, 1, len, fp) != len) {
        free(text);
        text = NULL;
    }
    if (text) {
        text[len] = '\0';
    }
    fclose(fp);
    return text;
}

/* Names in a warning each extension the glTF file lists in extensionsUsed that trac0r does
 * not render. Assimp passes some on (their materials are warned about where they are
 * mapped); most it drops without a word. Those rendered, or approximated with their own
 * warning: */
static void gltf_extension_warnings(const import_ctx *c, const char *path) {
    static const char *const handled[] = {
        "KHR_materials_clearcoat",         /* the clear coat and its three maps */
        "KHR_lights_punctual",             /* point, spot and directional lights */
        "KHR_materials_transmission",      /* principled's transmission and its map */
        "KHR_materials_ior",               /* the principled material's index */
        "KHR_materials_volume",            /* the attenuation (thickness is not needed) */
        "KHR_texture_transform",           /* the maps' offset, rotation and scale */
        "KHR_materials_sheen",             /* principled's sheen and its two maps */
        "KHR_materials_emissive_strength", /* from the file's JSON (gltf_material_json) */
        "KHR_materials_specular",          /* from the file's JSON, its maps warned */
    };
    const cJSON *root = c->gltf_root;
    if (!root) {
        import_warn(c, "'%.200s': cannot read its glTF extensions to check them", path);
        return;
    }
    const cJSON *used = cJSON_GetObjectItemCaseSensitive(root, "extensionsUsed");
    const cJSON *x;
    cJSON_ArrayForEach(x, used) {
        if (!cJSON_IsString(x) || !x->valuestring) {
            continue;
        }
        int known = 0;
        for (size_t i = 0; i < sizeof handled / sizeof handled[0]; ++i) {
            known |= strcmp(x->valuestring, handled[i]) == 0;
        }
        if (!known) {
            import_warn(c, "glTF extension %.80s not rendered", x->valuestring);
        }
    }
}

int tr_scene_import_mesh(tr_scene *s, const char *path, const tr_transform *tf,
                         int64_t material_override, uint32_t max_triangles,
                         tr_mesh_import_stats *stats, tr_error *err) {
    return tr_scene_import_mesh_ex(s, path, tf, material_override, max_triangles, stats, NULL, NULL,
                                   NULL, err);
}

int tr_scene_import_mesh_ex(tr_scene *s, const char *path, const tr_transform *tf,
                            int64_t material_override, uint32_t max_triangles,
                            tr_mesh_import_stats *stats, tr_import_warn_fn warn, void *warn_ctx,
                            tr_import_extras *extras, tr_error *err) {
    tr_mesh_import_stats local;
    tr_mesh_import_stats *st = stats ? stats : &local;
    memset(st, 0, sizeof *st);
    if (material_override >= (int64_t)s->material_count) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND, "material %lld does not exist",
                            (long long)material_override);
    }
    /* Regular files only (a FIFO would block), and an empty one is refused before Assimp
     * guesses at it. */
    uint64_t bytes = 0;
    tr_error open_err;
    FILE *fp = tr_infile_open(path, &bytes, &open_err);
    if (!fp) {
        const size_t skip = strnlen(path, 200) + strlen(": cannot open: ");
        /* The shipped scenes reach Debian's Assimp test models through a link beside them
         * (scenes/assimp-models, not in the repository): say which link is missing. */
        const char *link = strstr(path, "assimp-models/");
        return tr_error_set(
            err, open_err.code, "cannot open '%.200s': %s%s%.*s%s", path,
            strlen(open_err.msg) > skip ? open_err.msg + skip : open_err.msg,
            link && open_err.code == TR_STATUS_NOT_FOUND
                ? " (the scene reads Debian's assimp-testmodels through a link: ln -s "
                  "/usr/share/assimp/models "
                : "",
            link && open_err.code == TR_STATUS_NOT_FOUND ? (int)(link - path) : 0, path,
            link && open_err.code == TR_STATUS_NOT_FOUND ? "assimp-models)" : "");
    }
    fclose(fp);
    if (bytes == 0) {
        return tr_error_set(err, TR_STATUS_PARSE, "'%.200s' is empty", path);
    }
    /* Through mesh_guard.h: the files the model names confined to its directory tree,
     * declared sizes checked against real ones, reads within a budget. */
    const struct aiScene *ai =
        tr_mesh_guarded_import(path,
                               aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                   aiProcess_SortByPType | aiProcess_ValidateDataStructure,
                               err);
    if (!ai) {
        return TR_ERR;
    }
    const uint32_t t0 = s->triangle_count, s0 = s->shape_count, m0 = s->material_count;
    import_ctx c;
    memset(&c, 0, sizeof c);
    c.s = s;
    c.ai = ai;
    c.tf = tf;
    c.override = material_override;
    c.max_triangles = max_triangles ? max_triangles : UINT32_MAX;
    c.start_triangles = t0;
    c.st = st;
    c.err = err;
    c.warn = warn;
    c.warn_ctx = warn_ctx;
    c.extras = extras;
    const size_t plen = strlen(path);
    c.gltf = (plen > 5 && strcasecmp(path + plen - 5, ".gltf") == 0) ||
             (plen > 4 && strcasecmp(path + plen - 4, ".glb") == 0);
    c.sib = plen > 4 && strcasecmp(path + plen - 4, ".sib") == 0;
    if (extras) {
        const int want = extras->camera_want;
        const uint64_t instance_min = extras->instance_min;
        memset(extras, 0, sizeof *extras);
        extras->camera_want = want;
        extras->instance_min = instance_min;
        extras->lights = ai->mNumLights;
        extras->cameras = ai->mNumCameras;
    }
    const char *slash = strrchr(path, '/');
    if (slash && (size_t)(slash - path) < sizeof c.dir) {
        memcpy(c.dir, path, (size_t)(slash - path));
        c.dir[slash - path] = '\0';
        if (slash == path) {
            snprintf(c.dir, sizeof c.dir, "/");
        }
    }
    if (c.gltf) {
        char *text = gltf_json(path, plen > 4 && strcasecmp(path + plen - 4, ".glb") == 0);
        c.gltf_root = text ? cJSON_Parse(text) : NULL;
        free(text);
        if (c.warn) {
            gltf_extension_warnings(&c, path);
        }
    }
    c.material_map = malloc((ai->mNumMaterials ? ai->mNumMaterials : 1) * sizeof *c.material_map);
    int rc = TR_OK;
    if (!c.material_map) {
        rc = tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
    } else {
        for (unsigned int i = 0; i < ai->mNumMaterials; ++i) {
            c.material_map[i] = -1;
        }
        if (extras && extras->instance_min > 0u && ai->mNumMeshes > 0) {
            c.placements = calloc(ai->mNumMeshes, sizeof *c.placements);
            c.proto = calloc(ai->mNumMeshes, sizeof *c.proto);
            uint64_t shared = 0;
            if (c.placements && c.proto) {
                count_placements(&c, ai->mRootNode, 0);
                for (unsigned int i = 0; i < ai->mNumMeshes; ++i) {
                    shared += c.placements[i] >= 2u
                                  ? (uint64_t)c.placements[i] * ai->mMeshes[i]->mNumFaces
                                  : 0u;
                }
            }
            if (shared < extras->instance_min) {
                free(c.placements);
                free(c.proto);
                c.placements = c.proto = NULL; /* flattened */
            }
        }
        struct aiMatrix4x4 id = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        rc = walk(&c, ai->mRootNode, &id, 0);
        free(c.placements);
        free(c.proto);
    }
    if (rc != TR_OK && err && !strstr(err->msg, path)) {
        char msg[sizeof err->msg];
        memcpy(msg, err->msg, sizeof msg);
        tr_error_set(err, err->code, "'%.200s': %.300s", path, msg);
    }
    if (rc == TR_OK && st->triangles == 0) {
        rc = tr_error_set(err, TR_STATUS_PARSE,
                          "'%.200s' has no triangles of non-zero area (%u faces dropped)", path,
                          st->degenerate);
    }
    if (rc != TR_OK) {
        /* Roll back: everything was appended. */
        tr_scene_truncate(s, t0, s0, m0);
    }
    free(c.material_map);
    cJSON_Delete(c.gltf_root);
    aiReleaseImport(ai);
    return rc;
}
