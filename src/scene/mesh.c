/* mesh.c - triangle meshes from model files through Assimp's C API. */
#define _POSIX_C_SOURCE 200809L
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_internal.h"
#include "trac0r/scene_file.h"

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
} import_ctx;

static float clamp01(float x) {
    return isfinite(x) ? (x < 0.0f ? 0.0f : x > 1.0f ? 1.0f : x) : 0.0f;
}

static float max3(float a, float b, float c) {
    float m = a > b ? a : b;
    return m > c ? m : c;
}

/* Wavefront MTL (and whatever Assimp maps onto the same keys) to our four materials:
 * Ke > 0 -> emitter (colour Ke / max(Ke), emittance max(Ke)); dissolve d < 1 or illum
 * 4, 6, 7, 9 -> glass (colour Kd, ior Ni, 1.5 where Ni is missing or below 1); illum 3,
 * 5, 8 -> glossy (colour Ks, or Kd where Ks is black, roughness sqrt(2 / (Ns + 2)));
 * otherwise diffuse with colour Kd. Colours other than Ke are clamped to [0, 1]. */
static tr_material map_material(const struct aiMaterial *m) {
    struct aiColor4D kd = {0.6f, 0.6f, 0.6f, 1.0f}, ks = {0, 0, 0, 1}, ke = {0, 0, 0, 1};
    aiGetMaterialColor(m, AI_MATKEY_COLOR_DIFFUSE, &kd);
    aiGetMaterialColor(m, AI_MATKEY_COLOR_SPECULAR, &ks);
    aiGetMaterialColor(m, AI_MATKEY_COLOR_EMISSIVE, &ke);
    ai_real ni = 0.0f, d = 1.0f, ns = 0.0f;
    unsigned int one = 1;
    aiGetMaterialFloatArray(m, AI_MATKEY_REFRACTI, &ni, &one);
    one = 1;
    aiGetMaterialFloatArray(m, AI_MATKEY_OPACITY, &d, &one);
    one = 1;
    aiGetMaterialFloatArray(m, AI_MATKEY_SHININESS, &ns, &one);
    int illum = -1;
    one = 1;
    aiGetMaterialIntegerArray(m, "$mat.illum", 0, 0, &illum, &one);

    tr_vec3 diffuse = v3(clamp01(kd.r), clamp01(kd.g), clamp01(kd.b));
    float e[3] = {ke.r, ke.g, ke.b};
    for (int i = 0; i < 3; ++i) {
        e[i] = isfinite(e[i]) && e[i] > 0.0f ? (e[i] > 1e7f ? 1e7f : e[i]) : 0.0f;
    }
    float emax = max3(e[0], e[1], e[2]);
    if (emax > 0.0f) {
        return tr_material_emitter(v3(e[0] / emax, e[1] / emax, e[2] / emax), emax);
    }
    if ((isfinite(d) && d < 1.0f) || illum == 4 || illum == 6 || illum == 7 || illum == 9) {
        float ior = isfinite(ni) && ni >= 1.0f && ni <= 10.0f ? ni : 1.5f;
        return tr_material_glass(diffuse, ior);
    }
    if (illum == 3 || illum == 5 || illum == 8) {
        tr_vec3 spec = v3(clamp01(ks.r), clamp01(ks.g), clamp01(ks.b));
        if (!(max3(spec.x, spec.y, spec.z) > 0.0f)) {
            spec = diffuse;
        }
        float rough = isfinite(ns) && ns >= 0.0f ? sqrtf(2.0f / (ns + 2.0f)) : 1.0f;
        return tr_material_glossy(spec, rough > 1.0f ? 1.0f : rough);
    }
    return tr_material_diffuse(diffuse);
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
        if (tr_scene_add_material(c->s, map_material(c->ai->mMaterials[index]), &m, c->err) !=
            TR_OK) {
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
    uint32_t *idx = malloc((size_t)tris * 3 * sizeof *idx);
    if (!pos || !idx || (mesh->mNormals && !nrm)) {
        free(pos);
        free(nrm);
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
    rc = tr_scene_add_mesh(c->s, pos, nv, idx, tris, nrm, material, c->tf, &dropped, c->err);
    c->st->degenerate += dropped;
    if (rc == TR_OK) {
        c->st->parts++;
        c->st->triangles += tris - dropped;
    } else if (dropped == tris) {
        rc = TR_OK; /* nothing but degenerate faces: dropped and counted */
    }
    free(pos);
    free(nrm);
    free(idx);
    return rc;
}

static int walk(import_ctx *c, const struct aiNode *node, const struct aiMatrix4x4 *parent,
                int depth) {
    if (depth > NODE_DEPTH_LIMIT) {
        return tr_error_set(c->err, TR_STATUS_LIMIT, "node hierarchy deeper than %d",
                            NODE_DEPTH_LIMIT);
    }
    struct aiMatrix4x4 m = mat_mul(parent, &node->mTransformation);
    for (unsigned int i = 0; i < node->mNumMeshes; ++i) {
        if (node->mMeshes[i] >= c->ai->mNumMeshes) {
            return tr_error_set(c->err, TR_STATUS_PARSE, "a node refers to mesh %u of %u",
                                node->mMeshes[i], c->ai->mNumMeshes);
        }
        if (add_ai_mesh(c, c->ai->mMeshes[node->mMeshes[i]], &m) != TR_OK) {
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

/* Assimp's message on one line. */
static void one_line(char *out, size_t n, const char *msg) {
    size_t j = 0;
    for (size_t i = 0; msg && msg[i] && j + 1 < n; ++i) {
        unsigned char ch = (unsigned char)msg[i];
        out[j++] = (ch == '\n' || ch == '\r' || ch == '\t') ? ' ' : (ch < 32 ? '?' : (char)ch);
    }
    while (j > 0 && out[j - 1] == ' ') {
        j--;
    }
    out[j] = '\0';
}

int tr_scene_import_mesh(tr_scene *s, const char *path, const tr_transform *tf,
                         int64_t material_override, uint32_t max_triangles,
                         tr_mesh_import_stats *stats, tr_error *err) {
    tr_mesh_import_stats local;
    tr_mesh_import_stats *st = stats ? stats : &local;
    memset(st, 0, sizeof *st);
    if (material_override >= (int64_t)s->material_count) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND, "material %lld does not exist",
                            (long long)material_override);
    }
    FILE *fp = fopen(path, "rb");
    if (!fp) {
        return tr_error_set(err, tr_status_from_errno(errno), "cannot open '%.200s': %s", path,
                            strerror(errno));
    }
    char probe;
    errno = 0;
    size_t got = fread(&probe, 1, 1, fp);
    int read_error = ferror(fp) ? (errno ? errno : EIO) : 0;
    fclose(fp);
    if (read_error) {
        return tr_error_set(err, tr_status_from_errno(read_error), "cannot read '%.200s': %s", path,
                            strerror(read_error));
    }
    if (got == 0) {
        return tr_error_set(err, TR_STATUS_PARSE, "'%.200s' is empty", path);
    }
    const struct aiScene *ai =
        aiImportFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                               aiProcess_SortByPType | aiProcess_ValidateDataStructure);
    if (!ai || !ai->mRootNode || (ai->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
        char msg[300];
        one_line(msg, sizeof msg, aiGetErrorString());
        if (ai) {
            aiReleaseImport(ai);
        }
        return tr_error_set(err, TR_STATUS_PARSE, "Assimp cannot read '%.200s': %s", path,
                            msg[0] ? msg : "no meshes");
    }
    const uint32_t t0 = s->triangle_count, s0 = s->shape_count, m0 = s->material_count;
    import_ctx c = {s,  ai, tf, material_override, NULL, max_triangles ? max_triangles : UINT32_MAX,
                    t0, st, err};
    c.material_map = malloc((ai->mNumMaterials ? ai->mNumMaterials : 1) * sizeof *c.material_map);
    int rc = TR_OK;
    if (!c.material_map) {
        rc = tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
    } else {
        for (unsigned int i = 0; i < ai->mNumMaterials; ++i) {
            c.material_map[i] = -1;
        }
        struct aiMatrix4x4 id = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        rc = walk(&c, ai->mRootNode, &id, 0);
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
    aiReleaseImport(ai);
    return rc;
}
