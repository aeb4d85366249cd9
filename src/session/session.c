/* session.c - an offline render as one job (include/trac0r/session.h). */
#include "trac0r/session.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "device/vcm.h"
#include "kernel/integrator_vcm.h"
#include "scene/scene_internal.h"
#include "session/checkpoint.h"
#include "trac0r/post.h"
#include "trac0r/registry.h"

struct tr_session {
    tr_device *dev;
    const tr_scene *scene;
    tr_render_config cfg;
    tr_session_desc desc; /* its strings point into `strings` */
    char *strings;
    uint32_t width, height, spp;
    double interval; /* seconds between checkpoints; < 0: every pass */

    /* The tile plan and what the film holds of each tile. */
    tr_ck_tiles tiles;
    unsigned char *pending; /* per tile: rendered on the device, not yet in `film` */
    uint32_t npending;
    tr_film film;    /* the image as far as read back or put */
    tr_film scratch; /* a read-back when only some tiles are wanted */

    int have_id;
    tr_ck_id id;
    double last_checkpoint;

    atomic_int cancel;
    tr_session_progress st;
};

double tr_session_pixel_error(const float full[3], const float half[3]) {
    double diff = fabs((double)full[0] - half[0]) + fabs((double)full[1] - half[1]) +
                  fabs((double)full[2] - half[2]);
    double sum = fmax(0.0, (double)full[0] + full[1] + full[2]);
    return diff / (1e-4 + sqrt(sum));
}

/* ---- the render's identity ------------------------------------------------------- */

static uint64_t fnv_floats(uint64_t h, const float *v, size_t n) {
    return tr_ck_fnv(h, v, n * sizeof *v);
}

static uint64_t fnv_u32(uint64_t h, uint32_t v) {
    return tr_ck_fnv(h, &v, sizeof v);
}

/* The scene file's bytes: its meshes are in the geometry hashed below, but settings the
 * geometry does not show (a light's sampling, a future field) are in the file. */
static int hash_file(uint64_t *h, const char *path, tr_error *err) {
    FILE *fp = fopen(path, "rb");
    if (!fp) {
        return tr_error_set(err, tr_status_from_errno(errno), "%s: cannot read: %s", path,
                            strerror(errno));
    }
    unsigned char buf[65536];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, fp)) > 0) {
        *h = tr_ck_fnv(*h, buf, n);
    }
    const int bad = ferror(fp);
    fclose(fp);
    if (bad) {
        return tr_error_set(err, TR_STATUS_IO, "%s: read error", path);
    }
    return TR_OK;
}

static const char *sampler_name(int sampler) {
    return sampler == TR_SAMPLER_RANDOM   ? "random"
           : sampler == TR_SAMPLER_ZSOBOL ? "zsobol"
                                          : "sobol";
}

int tr_ck_identity(tr_ck_id *id, const tr_scene *scene, const tr_render_config *cfg,
                   const char *scene_file, tr_error *err) {
    memset(id, 0, sizeof *id);
    const tr_camera *cam = tr_scene_camera(scene);
    /* The sampler and the light selection decide the samples too: a film resumed with
     * other ones would mix two sequences of points. */
    snprintf(id->desc, sizeof id->desc,
             "size=%ux%u seed=%llu max-depth=%d integrator=%s accel=%s stride=%d passes=0x%x "
             "sampler=%s light-sampling=%s",
             cam->screen_width, cam->screen_height, (unsigned long long)cfg->seed, cfg->max_depth,
             tr_integrator_name(cfg->integrator), tr_accel_name(tr_scene_accel(scene)),
             cfg->stride > 0 ? cfg->stride : 1, cfg->passes, sampler_name(cfg->sampler),
             tr_light_sampling_name(tr_scene_light_sampling(scene)));
    /* pt's roulette start decides the paths as well. */
    const int rr = cfg->roulette_start ? cfg->roulette_start : TR_ROULETTE_START_PT;
    if (rr != TR_ROULETTE_START_PT) {
        const size_t used = strlen(id->desc);
        snprintf(id->desc + used, sizeof id->desc - used, " roulette-start=%d", rr);
    }
    /* So does the firefly control (named only when on: older checkpoints stay valid). */
    if (cfg->clamp_indirect > 0.0f || cfg->regularize || cfg->no_primary_direct) {
        const size_t used = strlen(id->desc);
        snprintf(id->desc + used, sizeof id->desc - used,
                 " clamp-indirect=%.9g regularize=%d no-primary-direct=%d",
                 (double)cfg->clamp_indirect, cfg->regularize, cfg->no_primary_direct);
    }
    /* vcm's merge radius comes from the environment (TRAC0R_VCM_RADIUS): named when it is
     * not the default. */
    if (cfg->integrator == TR_INTEGRATOR_VCM) {
        float radius = 0.0f;
        if (tr_vcm_radius_pixels(&radius, err) != TR_OK) {
            return TR_ERR;
        }
        if (radius != TR_VCM_RADIUS_DEFAULT) {
            const size_t used = strlen(id->desc);
            snprintf(id->desc + used, sizeof id->desc - used, " vcm-radius=%.9g", (double)radius);
        }
    }
    uint64_t h = TR_CK_FNV_OFFSET;
    const uint32_t nt = tr_scene_triangle_count(scene);
    const uint32_t stored = tr_scene_stored_triangle_count(scene);
    h = fnv_u32(h, nt);
    for (uint32_t i = 0; i < stored; ++i) {
        const tr_triangle t = tr_scene_triangle(scene, i);
        const float v[9] = {t.v0.x, t.v0.y, t.v0.z, t.v1.x, t.v1.y, t.v1.z, t.v2.x, t.v2.y, t.v2.z};
        h = fnv_u32(fnv_floats(h, v, 9), t.material);
    }
    if (stored < nt) {
        /* Kept instances: their prototypes' triangles once, and every placement. */
        for (uint32_t k = 0; k < tr_scene_prototype_count(scene); ++k) {
            h = fnv_u32(h, tr_scene_prototype_triangle_count(scene, k));
        }
        for (uint32_t i = 0; i < tr_scene_instance_count(scene); ++i) {
            float m[12];
            tr_scene_instance_transform(scene, i, m);
            h = fnv_floats(h, m, 12);
        }
    }
    const uint32_t nm = tr_scene_material_count(scene);
    h = fnv_u32(h, nm);
    for (uint32_t i = 0; i < nm; ++i) {
        const tr_material m = tr_scene_material(scene, i);
        const float v[6] = {m.color.x, m.color.y, m.color.z, m.roughness, m.ior, m.emittance};
        h = fnv_u32(fnv_u32(fnv_floats(h, v, 6), m.type), m.flags);
    }
    const float c[10] = {cam->pos.x,      cam->pos.y,       cam->pos.z,      cam->dir.x,
                         cam->dir.y,      cam->dir.z,       cam->world_up.x, cam->world_up.y,
                         cam->world_up.z, cam->vertical_fov};
    h = fnv_floats(h, c, 10);
    /* What the files a scene names decode to - textures, the environment map - and the
     * sun: a texture or map changed on disk between --checkpoint and --resume would mix two
     * scenes in one image. Hashed only where the scene has them, so that the identity of a
     * scene without them stays what it was. Fields one by one, leaving out the padding. */
    if (scene->texture_count > 0) {
        h = fnv_u32(h, scene->texture_count);
        for (uint32_t i = 0; i < scene->texture_count; ++i) {
            const tr_texture *t = &scene->textures[i];
            h = fnv_u32(fnv_u32(fnv_u32(fnv_u32(h, t->offset), t->width), t->height), t->flags);
            if ((t->flags & TR_TEXTURE_TRANSFORM) != 0u) {
                h = fnv_floats(h, t->xf, 6);
            }
        }
        h = fnv_u32(h, scene->texel_count);
        h = tr_ck_fnv(h, scene->texels, (size_t)scene->texel_count * sizeof *scene->texels);
        h = fnv_u32(h, scene->material_ext_count);
        for (uint32_t i = 0; i < scene->material_ext_count; ++i) {
            const tr_material_ext *e = &scene->material_exts[i];
            const uint32_t u[5] = {e->base_tex, e->emission_tex, e->mr_tex, e->normal_tex,
                                   e->flags};
            const float f[6] = {e->emission.x, e->emission.y,   e->emission.z,
                                e->metallic,   e->alpha_cutoff, e->normal_scale};
            h = fnv_floats(tr_ck_fnv(h, u, sizeof u), f, 6);
            if (e->clearcoat > 0.0f) {
                /* Only where set: checkpoints of scenes without a coat keep their identity. */
                const float cc[2] = {e->clearcoat, e->clearcoat_roughness};
                h = fnv_floats(h, cc, 2);
            }
            if (e->clearcoat_tex != TR_NO_INDEX || e->clearcoat_rough_tex != TR_NO_INDEX) {
                /* The coat's maps, likewise only where there are any. */
                const uint32_t cm[2] = {e->clearcoat_tex, e->clearcoat_rough_tex};
                h = tr_ck_fnv(h, cm, sizeof cm);
            }
            if (e->sheen_color_tex != TR_NO_INDEX || e->sheen_rough_tex != TR_NO_INDEX ||
                e->clearcoat_normal_tex != TR_NO_INDEX) {
                /* The sheen's maps and the coat's normal map, likewise. */
                const uint32_t sm[3] = {e->sheen_color_tex, e->sheen_rough_tex,
                                        e->clearcoat_normal_tex};
                h = fnv_floats(tr_ck_fnv(h, sm, sizeof sm), &e->clearcoat_normal_scale, 1);
            }
            if ((e->flags & TR_MATEXT_SPECULAR) != 0u) {
                const float sp[4] = {e->specular, e->specular_color.x, e->specular_color.y,
                                     e->specular_color.z};
                h = fnv_floats(h, sp, 4);
            }
            if (e->sheen_color.x > 0.0f || e->sheen_color.y > 0.0f || e->sheen_color.z > 0.0f) {
                const float sh[4] = {e->sheen_color.x, e->sheen_color.y, e->sheen_color.z,
                                     e->sheen_roughness};
                h = fnv_floats(h, sh, 4);
            }
            if (e->transmission > 0.0f || e->absorption.x > 0.0f || e->absorption.y > 0.0f ||
                e->absorption.z > 0.0f) {
                const float tv[4] = {e->transmission, e->absorption.x, e->absorption.y,
                                     e->absorption.z};
                h = fnv_floats(h, tv, 4);
            }
        }
    }
    if (scene->env_count > 0) {
        const tr_env *e = &scene->env;
        const float f[6] = {e->color.x,  e->color.y, e->color.z,
                            e->strength, e->rot_cos, e->rot_sin};
        h = fnv_u32(fnv_u32(fnv_floats(h, f, 6), e->width), e->height);
        h = fnv_floats(h, scene->env_texels, scene->env_texel_count); /* floats, 3 a texel */
    }
    if (scene->sun_count > 0) {
        const tr_sun *u = &scene->sun;
        const float f[7] = {u->dir.x,      u->dir.y,      u->dir.z,     u->one_minus_cos,
                            u->radiance.x, u->radiance.y, u->radiance.z};
        h = fnv_floats(h, f, 7);
    }
    if (scene_file && hash_file(&h, scene_file, err) != TR_OK) {
        return TR_ERR;
    }
    id->scene_hash = h;
    id->width = cam->screen_width;
    id->height = cam->screen_height;
    id->passes = cfg->passes;
    id->spp_max = TR_SESSION_SPP_MAX;
    return TR_OK;
}

/* ---- creating ------------------------------------------------------------------ */

/* Copies the desc's strings into one block the session owns. */
static int keep_strings(tr_session *s, tr_error *err) {
    const char *src[3] = {s->desc.checkpoint, s->desc.resume, s->desc.scene_file};
    size_t total = 0;
    for (int i = 0; i < 3; ++i) {
        total += src[i] ? strlen(src[i]) + 1 : 0;
    }
    s->strings = malloc(total ? total : 1);
    if (!s->strings) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
    }
    char *p = s->strings;
    const char **dst[3] = {&s->desc.checkpoint, &s->desc.resume, &s->desc.scene_file};
    for (int i = 0; i < 3; ++i) {
        if (src[i]) {
            const size_t n = strlen(src[i]) + 1;
            memcpy(p, src[i], n);
            *dst[i] = p;
            p += n;
        }
    }
    return TR_OK;
}

static int check_desc(const tr_session_desc *d, int stride, tr_error *err) {
    if (d->spp > TR_SESSION_SPP_MAX) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "spp %u must be in 1..%u", d->spp,
                            TR_SESSION_SPP_MAX);
    }
    if (!(d->noise_threshold >= 0.0f && d->noise_threshold <= 1.0f)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "noise threshold %g must be in 0..1 (0: off)", d->noise_threshold);
    }
    if (!(d->time_limit >= 0.0 && d->time_limit <= 1e9)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "time limit %g must be in 0..1e9 seconds (0: none)", d->time_limit);
    }
    if (!(d->checkpoint_interval <= 1e9)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "checkpoint interval %g is too long",
                            d->checkpoint_interval);
    }
    if (d->noise_threshold > 0.0f && stride > 1) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "the noise threshold is not for a stride of %d (a preview traces too "
                            "few pixels to estimate their noise)",
                            stride);
    }
    if (d->noise_threshold > 0.0f && (d->checkpoint || d->resume)) {
        /* Adaptive tiles stop at different sample counts on tests of half-films that a
         * checkpoint does not keep. */
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "the noise threshold is not for a render with checkpoints");
    }
    return TR_OK;
}

static int make_plan(tr_session *s, tr_error *err) {
    const uint32_t stride = s->cfg.stride > 0 ? (uint32_t)s->cfg.stride : 1u;
    s->tiles.side = TR_SESSION_TILE * stride;
    const uint32_t nx = (s->width + s->tiles.side - 1) / s->tiles.side;
    const uint32_t ny = (s->height + s->tiles.side - 1) / s->tiles.side;
    s->tiles.count = nx * ny;
    s->tiles.samples = calloc(s->tiles.count, sizeof *s->tiles.samples);
    s->pending = calloc(s->tiles.count, 1);
    if (!s->tiles.samples || !s->pending) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
    }
    return TR_OK;
}

static int ensure_id(tr_session *s, tr_error *err) {
    if (!s->have_id) {
        if (tr_ck_identity(&s->id, s->scene, &s->cfg, s->desc.scene_file, err) != TR_OK) {
            return TR_ERR;
        }
        s->have_id = 1;
    }
    return TR_OK;
}

/* Reads desc.resume into the film and the tile samples, and hands the film to the device,
 * so the samples still missing are added to those very floats. */
static int resume(tr_session *s, tr_error *err) {
    uint32_t ck_spp = 0;
    tr_film_free(&s->film);
    if (ensure_id(s, err) != TR_OK ||
        tr_ck_read(s->desc.resume, &s->id, &s->tiles, &s->film, &ck_spp, err) != TR_OK) {
        return TR_ERR;
    }
    s->spp = s->desc.spp ? s->desc.spp : ck_spp;
    uint32_t most = 0;
    for (uint32_t k = 0; k < s->tiles.count; ++k) {
        most = s->tiles.samples[k] > most ? s->tiles.samples[k] : most;
    }
    if (s->spp < most) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "%u is fewer than the %u samples per pixel %s holds", s->spp, most,
                            s->desc.resume);
    }
    return tr_device_write_film(s->dev, &s->film, err);
}

tr_session *tr_session_create(tr_device *dev, const tr_scene *scene, const tr_render_config *cfg,
                              const tr_session_desc *desc, tr_error *err) {
    if (!dev || !scene) {
        tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "a session needs a device and a scene");
        return NULL;
    }
    tr_session *s = calloc(1, sizeof *s);
    if (!s) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
        return NULL;
    }
    s->dev = dev;
    s->scene = scene;
    s->cfg = cfg ? *cfg : tr_render_config_default();
    if (desc) {
        s->desc = *desc;
    }
    if (s->desc.denoise) {
        /* The denoiser's guides, the sample statistics it judges fireflies by and the
         * emission it keeps out of the filter. */
        s->cfg.passes |=
            TR_PASS_ALBEDO | TR_PASS_NORMAL | TR_PASS_DEPTH | TR_PASS_VARIANCE | TR_PASS_EMISSION;
    }
    const tr_camera *cam = tr_scene_camera(scene);
    s->width = cam->screen_width;
    s->height = cam->screen_height;
    s->spp = s->desc.spp ? s->desc.spp : TR_SESSION_SPP_DEFAULT;
    s->interval = s->desc.checkpoint_interval == 0.0 ? TR_SESSION_CHECKPOINT_INTERVAL
                                                     : s->desc.checkpoint_interval;
    atomic_init(&s->cancel, 0);
    int rc = keep_strings(s, err);
    rc = rc == TR_OK ? check_desc(&s->desc, s->cfg.stride, err) : rc;
    rc = rc == TR_OK ? tr_render_config_check(&s->cfg, err) : rc;
    /* An integrator that cannot render the scene (bdpt and vcm with a sun or an
     * environment) is refused before any work, not on the first pass. */
    rc = rc == TR_OK ? tr_integrator_supports(scene, s->cfg.integrator, err) : rc;
    rc = rc == TR_OK ? tr_film_init_passes(&s->film, s->width, s->height, s->cfg.passes, err) : rc;
    rc = rc == TR_OK ? make_plan(s, err) : rc;
    if (rc == TR_OK && tr_device_scene(dev) != scene) {
        rc = tr_device_upload(dev, scene, err);
    }
    if (rc == TR_OK && s->desc.resume) {
        rc = resume(s, err);
    } else if (rc == TR_OK) {
        rc = tr_device_clear(dev, err); /* a film of an earlier render would add up */
    }
    if (rc != TR_OK) {
        tr_session_destroy(s);
        return NULL;
    }
    s->st.spp = s->spp;
    s->st.first = s->tiles.samples[0];
    s->st.samples = s->st.first;
    return s;
}

void tr_session_destroy(tr_session *s) {
    if (!s) {
        return;
    }
    tr_film_free(&s->film);
    tr_film_free(&s->scratch);
    free(s->tiles.samples);
    free(s->pending);
    free(s->strings);
    free(s);
}

void tr_session_cancel(tr_session *s) {
    atomic_store(&s->cancel, 1);
}

void tr_session_progress_get(const tr_session *s, tr_session_progress *out) {
    *out = s->st;
}

/* ---- the film ------------------------------------------------------------------ */

static tr_rect tile_rect(const tr_session *s, uint32_t k) {
    const uint32_t side = s->tiles.side, nx = (s->width + side - 1) / side;
    tr_rect r;
    r.x = (k % nx) * side;
    r.y = (k / nx) * side;
    r.width = r.x + side < s->width ? side : s->width - r.x;
    r.height = r.y + side < s->height ? side : s->height - r.y;
    return r;
}

static void mark_all_pending(tr_session *s) {
    memset(s->pending, 1, s->tiles.count);
    s->npending = s->tiles.count;
}

/* Copies the pending tiles from the device's film into `film`: the whole film when every
 * tile is pending (reading a device's film costs as much as the whole image). */
static int read_back(tr_session *s, tr_error *err) {
    if (s->npending == 0) {
        return TR_OK;
    }
    if (s->npending == s->tiles.count) {
        if (tr_device_read_film(s->dev, &s->film, err) != TR_OK) {
            return TR_ERR;
        }
    } else {
        if (!s->scratch.sum &&
            tr_film_init_passes(&s->scratch, s->width, s->height, s->film.passes, err) != TR_OK) {
            return TR_ERR;
        }
        if (tr_device_read_film(s->dev, &s->scratch, err) != TR_OK) {
            return TR_ERR;
        }
        const size_t bytes =
            (size_t)s->tiles.side * s->tiles.side * tr_film_pixel_bytes(s->film.passes);
        unsigned char *buf = malloc(bytes);
        if (!buf) {
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
        }
        for (uint32_t k = 0; k < s->tiles.count; ++k) {
            const tr_rect r = tile_rect(s, k);
            if (s->pending[k] && (tr_film_pack_rect(&s->scratch, &r, buf, bytes, err) != TR_OK ||
                                  tr_film_unpack_rect(&s->film, &r, buf, bytes, err) != TR_OK)) {
                free(buf);
                return TR_ERR;
            }
        }
        free(buf);
    }
    memset(s->pending, 0, s->tiles.count);
    s->npending = 0;
    return TR_OK;
}

const tr_film *tr_session_film(tr_session *s, tr_error *err) {
    return read_back(s, err) == TR_OK ? &s->film : NULL;
}

int tr_session_denoise(tr_session *s, tr_film *out, tr_error *err) {
    memset(out, 0, sizeof *out);
    const tr_film *film = tr_session_film(s, err);
    if (!film) {
        return TR_ERR;
    }
    const uint32_t guides = TR_PASS_ALBEDO | TR_PASS_NORMAL | TR_PASS_DEPTH;
    if ((film->passes & guides) != guides) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION,
                            "denoising needs the albedo, normal and depth passes "
                            "(tr_session_desc.denoise)");
    }
    int rc = tr_film_init(out, film->width, film->height, err);
    rc = rc == TR_OK ? tr_denoise_film(film, NULL, 0, out->sum, err) : rc;
    for (size_t i = 0; rc == TR_OK && i < (size_t)film->width * film->height; ++i) {
        out->count[i] = film->count[i] ? 1u : 0u;
    }
    if (rc != TR_OK) {
        tr_film_free(out);
    }
    return rc;
}

const char *tr_session_identity(tr_session *s, uint64_t *scene_hash, tr_error *err) {
    if (ensure_id(s, err) != TR_OK) {
        return NULL;
    }
    if (scene_hash) {
        *scene_hash = s->id.scene_hash;
    }
    return s->id.desc;
}

int tr_session_checkpoint(tr_session *s, const char *path, tr_error *err) {
    if (!path && !s->desc.checkpoint) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "no checkpoint file named");
    }
    if (read_back(s, err) != TR_OK || ensure_id(s, err) != TR_OK) {
        return TR_ERR;
    }
    s->last_checkpoint = tr_time_now();
    return tr_ck_write(path ? path : s->desc.checkpoint, &s->id, &s->film, s->spp, &s->tiles, err);
}

/* ---- tiles --------------------------------------------------------------------- */

uint32_t tr_session_tile_count(const tr_session *s) {
    return s->tiles.count;
}

static int check_tile(const tr_session *s, uint32_t k, tr_error *err) {
    if (k >= s->tiles.count) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tile %u is not one of the %u", k,
                            s->tiles.count);
    }
    return TR_OK;
}

int tr_session_tile(const tr_session *s, uint32_t k, tr_rect *rect, uint32_t *samples,
                    tr_error *err) {
    if (check_tile(s, k, err) != TR_OK) {
        return TR_ERR;
    }
    if (rect) {
        *rect = tile_rect(s, k);
    }
    if (samples) {
        *samples = s->tiles.samples[k];
    }
    return TR_OK;
}

int tr_session_render_tile(tr_session *s, uint32_t k, int (*cancel)(void *user), void *user,
                           tr_render_stats *stats, tr_error *err) {
    if (check_tile(s, k, err) != TR_OK) {
        return TR_ERR;
    }
    tr_render_stats st = {0, 0.0};
    const uint32_t have = s->tiles.samples[k];
    if (have < s->spp) {
        const tr_rect r = tile_rect(s, k);
        tr_render_config cfg = s->cfg;
        cfg.cancel = cancel;
        cfg.cancel_user = user;
        if (tr_device_render(s->dev, tr_scene_camera(s->scene), &cfg, have, s->spp - have, &r, &st,
                             err) != TR_OK) {
            return TR_ERR;
        }
        s->tiles.samples[k] = s->spp;
        s->npending += !s->pending[k];
        s->pending[k] = 1;
        s->st.rays += st.rays;
        s->st.pixel_samples += (uint64_t)r.width * r.height * (s->spp - have);
    }
    if (stats) {
        *stats = st;
    }
    return TR_OK;
}

int tr_session_put_tile(tr_session *s, uint32_t k, const void *pixels, size_t size, tr_error *err) {
    if (check_tile(s, k, err) != TR_OK) {
        return TR_ERR;
    }
    const tr_rect r = tile_rect(s, k);
    if (tr_film_unpack_rect(&s->film, &r, pixels, size, err) != TR_OK) {
        return TR_ERR;
    }
    s->tiles.samples[k] = s->spp;
    s->npending -= s->pending[k];
    s->pending[k] = 0;
    return TR_OK;
}

/* ---- running ------------------------------------------------------------------- */

/* The state of adaptive sampling while passes run. */
typedef struct adapt {
    uint32_t tx, ty;
    unsigned char *active; /* per 8x8 tile */
    tr_film films[2];      /* the film at the last two powers of two */
    int half, have_half;
} adapt;

static void adapt_free(adapt *a) {
    free(a->active);
    tr_film_free(&a->films[0]);
    tr_film_free(&a->films[1]);
}

static int adapt_init(adapt *a, const tr_session *s, tr_error *err) {
    memset(a, 0, sizeof *a);
    a->tx = (s->width + TR_SESSION_ADAPT_TILE - 1) / TR_SESSION_ADAPT_TILE;
    a->ty = (s->height + TR_SESSION_ADAPT_TILE - 1) / TR_SESSION_ADAPT_TILE;
    a->active = malloc((size_t)a->tx * a->ty);
    if (!a->active) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
    }
    memset(a->active, 1, (size_t)a->tx * a->ty);
    if (tr_film_init(&a->films[0], s->width, s->height, err) != TR_OK ||
        tr_film_init(&a->films[1], s->width, s->height, err) != TR_OK) {
        adapt_free(a);
        return TR_ERR;
    }
    return TR_OK;
}

/* The film's mean of pixel i into out (0 for a pixel without samples). */
static void pixel_mean(const tr_film *f, size_t i, float out[3]) {
    float inv = f->count[i] ? 1.0f / (float)f->count[i] : 0.0f;
    for (int c = 0; c < 3; ++c) {
        out[c] = f->sum[3 * i + c] * inv;
    }
}

/* Stops the tiles whose pixels' mean error estimate is below the threshold: one pixel's
 * estimate, from two halves, is too noisy to decide on (its spread is about its size), the
 * mean of a tile's 64 is good to about 10 %. */
static void converge_tiles(adapt *a, const tr_film *full, const tr_film *half, float threshold,
                           uint32_t *converged) {
    const uint32_t side = TR_SESSION_ADAPT_TILE;
    for (uint32_t t = 0; t < a->tx * a->ty; ++t) {
        if (!a->active[t]) {
            continue;
        }
        const uint32_t x0 = (t % a->tx) * side, y0 = (t / a->tx) * side;
        const uint32_t x1 = x0 + side < full->width ? x0 + side : full->width;
        const uint32_t y1 = y0 + side < full->height ? y0 + side : full->height;
        double sum = 0.0;
        for (uint32_t y = y0; y < y1; ++y) {
            for (uint32_t x = x0; x < x1; ++x) {
                const size_t i = (size_t)y * full->width + x;
                float m[3], h[3];
                pixel_mean(full, i, m);
                pixel_mean(half, i, h);
                sum += tr_session_pixel_error(m, h);
            }
        }
        if (sum < threshold * (double)((x1 - x0) * (y1 - y0))) {
            a->active[t] = 0;
            ++*converged;
        }
    }
}

static int render_rect(tr_session *s, uint32_t sample, const tr_rect *r, tr_error *err) {
    tr_render_stats st;
    if (tr_device_render(s->dev, tr_scene_camera(s->scene), &s->cfg, sample, 1, r, &st, err) !=
        TR_OK) {
        return TR_ERR;
    }
    s->st.rays += st.rays;
    s->st.pixel_samples += r ? (uint64_t)r->width * r->height : (uint64_t)s->width * s->height;
    return TR_OK;
}

/* One sample of every active adaptive tile: each maximal run of active tiles in a row of
 * tiles is one rectangle, and rows wholly active merge into one. */
static int render_active(tr_session *s, const adapt *a, uint32_t sample, tr_error *err) {
    const uint32_t side = TR_SESSION_ADAPT_TILE, w = s->width, h = s->height;
    uint32_t row = 0;
    while (row < a->ty) {
        uint32_t full = 0;
        while (row + full < a->ty && memchr(a->active + (row + full) * a->tx, 0, a->tx) == NULL) {
            ++full;
        }
        if (full > 0) {
            const uint32_t y1 = (row + full) * side < h ? (row + full) * side : h;
            const tr_rect r = {0, row * side, w, y1 - row * side};
            if (render_rect(s, sample, &r, err) != TR_OK) {
                return TR_ERR;
            }
            row += full;
            continue;
        }
        for (uint32_t k = 0; k < a->tx;) {
            if (!a->active[row * a->tx + k]) {
                ++k;
                continue;
            }
            uint32_t k1 = k;
            while (k1 < a->tx && a->active[row * a->tx + k1]) {
                ++k1;
            }
            const uint32_t x1 = k1 * side < w ? k1 * side : w;
            const uint32_t y0 = row * side, y1 = y0 + side < h ? y0 + side : h;
            const tr_rect r = {k * side, y0, x1 - k * side, y1 - y0};
            if (render_rect(s, sample, &r, err) != TR_OK) {
                return TR_ERR;
            }
            k = k1;
        }
        ++row;
    }
    return TR_OK;
}

/* After pass n (samples 0..n-1): at every power of two from 8 on, the film is kept, and
 * from 16 on the tiles are tested against the film at half as many samples. */
static int adapt_after_pass(tr_session *s, adapt *a, uint32_t n, tr_error *err) {
    if (n < TR_SESSION_ADAPT_FIRST_CHECK / 2 || (n & (n - 1)) != 0 || n >= s->spp) {
        return TR_OK;
    }
    tr_film *cur = &a->films[1 - a->half];
    if (tr_device_read_film(s->dev, cur, err) != TR_OK) {
        return TR_ERR;
    }
    if (a->have_half) {
        converge_tiles(a, cur, &a->films[a->half], s->desc.noise_threshold, &s->st.tiles_done);
    }
    a->half = 1 - a->half;
    a->have_half = 1;
    return TR_OK;
}

/* Whether a checkpoint is due after `done` samples. */
static int checkpoint_due(const tr_session *s, uint32_t done) {
    return s->desc.checkpoint && done < s->spp &&
           (s->interval < 0.0 || tr_time_now() - s->last_checkpoint >= s->interval);
}

/* Tells the progress callback; its nonzero answer cancels. */
static void report(tr_session *s, double t0) {
    s->st.seconds = tr_time_now() - t0;
    if (s->desc.progress && s->desc.progress(s->desc.progress_user, &s->st) != 0) {
        tr_session_cancel(s);
    }
}

/* Whether the next step should not start: cancelled, or it would end after the limit. */
static int stop_before(tr_session *s, double t0, double last_step, int first_step) {
    if (atomic_load(&s->cancel)) {
        s->st.end = TR_SESSION_CANCELLED;
        return 1;
    }
    if (s->desc.time_limit > 0.0 && !first_step &&
        tr_time_now() - t0 + last_step > s->desc.time_limit) {
        s->st.end = TR_SESSION_TIME_LIMIT;
        return 1;
    }
    return 0;
}

/* Whole passes over the image, sample by sample (every tile holds the same samples). */
static int run_passes(tr_session *s, double t0, tr_error *err) {
    adapt a;
    const int adaptive = s->desc.noise_threshold > 0.0f;
    if (adaptive && adapt_init(&a, s, err) != TR_OK) {
        return TR_ERR;
    }
    if (adaptive) {
        s->st.tiles = a.tx * a.ty;
    }
    const uint32_t first = s->tiles.samples[0];
    double last_pass = 0.0;
    int rc = TR_OK;
    for (uint32_t n = first; n < s->spp; ++n) {
        if (adaptive && s->st.tiles_done == s->st.tiles) {
            s->st.end = TR_SESSION_CONVERGED;
            break;
        }
        if (stop_before(s, t0, last_pass, n == first)) {
            break;
        }
        const double start = tr_time_now();
        rc = adaptive ? render_active(s, &a, n, err) : render_rect(s, n, NULL, err);
        if (rc != TR_OK) {
            break;
        }
        last_pass = tr_time_now() - start;
        for (uint32_t k = 0; k < s->tiles.count; ++k) {
            s->tiles.samples[k] = n + 1;
        }
        mark_all_pending(s);
        s->st.samples = n + 1;
        if (adaptive && (rc = adapt_after_pass(s, &a, n + 1, err)) != TR_OK) {
            break;
        }
        report(s, t0);
        if (checkpoint_due(s, n + 1) && (rc = tr_session_checkpoint(s, NULL, err)) != TR_OK) {
            break;
        }
    }
    if (adaptive) {
        adapt_free(&a);
    }
    return rc;
}

/* Tile by tile, each to the session's spp (a resumed tile checkpoint whose tiles hold
 * different sample counts). */
static int run_tiles(tr_session *s, double t0, tr_error *err) {
    s->st.tiles = s->tiles.count;
    s->st.tiles_done = 0;
    for (uint32_t k = 0; k < s->tiles.count; ++k) {
        s->st.tiles_done += s->tiles.samples[k] >= s->spp;
    }
    double last_tile = 0.0;
    int first = 1;
    for (uint32_t k = 0; k < s->tiles.count; ++k) {
        if (s->tiles.samples[k] >= s->spp) {
            continue;
        }
        if (stop_before(s, t0, last_tile, first)) {
            return TR_OK;
        }
        first = 0;
        const double start = tr_time_now();
        if (tr_session_render_tile(s, k, NULL, NULL, NULL, err) != TR_OK) {
            return TR_ERR;
        }
        last_tile = tr_time_now() - start;
        ++s->st.tiles_done;
        report(s, t0);
        if (checkpoint_due(s, 0) && tr_session_checkpoint(s, NULL, err) != TR_OK) {
            return TR_ERR;
        }
    }
    s->st.samples = s->spp;
    return TR_OK;
}

int tr_session_run(tr_session *s, tr_error *err) {
    const double t0 = tr_time_now();
    s->last_checkpoint = t0;
    s->st.end = TR_SESSION_NOT_RUN;
    int uniform = 1;
    for (uint32_t k = 1; k < s->tiles.count; ++k) {
        uniform &= s->tiles.samples[k] == s->tiles.samples[0];
    }
    int rc = uniform ? run_passes(s, t0, err) : run_tiles(s, t0, err);
    if (rc == TR_OK && s->st.end == TR_SESSION_NOT_RUN) {
        s->st.end = TR_SESSION_DONE;
    }
    if (s->st.end == TR_SESSION_CANCELLED) {
        atomic_store(&s->cancel, 0); /* taken: a later run goes on */
    }
    s->st.seconds = tr_time_now() - t0;
    int any = 0;
    for (uint32_t k = 0; k < s->tiles.count && !any; ++k) {
        any = s->tiles.samples[k] > 0;
    }
    if (rc == TR_OK && s->desc.checkpoint && any) {
        rc = tr_session_checkpoint(s, NULL, err);
    }
    return rc;
}
