/* test_checkpoint.c - the checkpoint reader treats its file as untrusted input: a file
 * written with a valid checksum but lying about the render (a film of another size than
 * the identity names, a pass dropped, a sample count beyond what --spp allows, a tile
 * claimed rendered whose pixels hold no samples) is refused, as are a file of the wrong
 * magic and one whose header claims more than the file holds; a true file still reads.
 * The render's identity covers what decides the image beyond geometry and settings: the
 * texels of textures and environment maps (a file changed between --checkpoint and
 * --resume), the sun, and TRAC0R_VCM_RADIUS. */
#define _POSIX_C_SOURCE 200809L
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "scene_util.h"
#include "scene/scene_internal.h"
#include "session/checkpoint.h"
#include "trac0r/trac0r.h"

#define W 64u
#define H 64u
#define SIDE 32u
#define TILES 4u
#define PASSES (TR_PASS_ALBEDO | TR_PASS_DEPTH)

static char path[256];

/* A film of w x h keeping `passes` whose every pixel holds `n` samples of value 1. */
static void make_film(tr_film *f, uint32_t w, uint32_t h, uint32_t passes, uint32_t n) {
    tr_error err;
    CHECK(tr_film_init_passes(f, w, h, passes, &err) == TR_OK, "%s", err.msg);
    for (size_t i = 0; i < (size_t)w * h; ++i) {
        f->count[i] = n;
        f->sum[3 * i] = f->sum[3 * i + 1] = f->sum[3 * i + 2] = (float)n;
    }
}

/* Writes a checkpoint of `film` with the given header values (the checksum is right) and
 * reads it back for the render `id`; the status of the read, TR_OK or the error code. */
static int write_read(const tr_ck_id *id, const tr_film *film, uint32_t spp, uint32_t *samples) {
    tr_error err;
    tr_ck_tiles t = {SIDE, TILES, samples};
    CHECK(tr_ck_write(path, id, film, spp, &t, &err) == TR_OK, "%s", err.msg);
    uint32_t got[TILES] = {0};
    tr_ck_tiles plan = {SIDE, TILES, got};
    tr_film back;
    uint32_t back_spp = 0;
    const int rc = tr_ck_read(path, id, &plan, &back, &back_spp, &err);
    if (rc == TR_OK) {
        tr_film_free(&back);
        return TR_OK;
    }
    CHECK(back.sum == NULL && back.count == NULL, "a refused checkpoint left a film");
    return err.code;
}

static tr_scene *cornell(void) {
    return committed_builtin("cornell", W, H);
}

/* The scene hash of the cornell box with one 2x2 texture whose first texel is `t0`, an
 * environment map whose first texel is `e0` and a sun of angle `sun` (0: none). */
static uint64_t hash_with(uint32_t t0, float e0, float sun) {
    tr_error err;
    tr_scene *s = cornell();
    const uint32_t rgba[4] = {t0, 0xff00ff00u, 0xffff0000u, 0xff0000ffu};
    const float rgb[6] = {e0, 0.5f, 0.5f, 0.25f, 0.25f, 0.25f};
    uint32_t index = 0;
    CHECK(tr_scene_add_texture(s, rgba, 2, 2, 0, &index, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_set_environment(s, (tr_vec3){1, 1, 1}, 1.0f, 0.0f, rgb, 2, 1, &err) == TR_OK,
          "%s", err.msg);
    if (sun > 0.0f) {
        CHECK(tr_scene_set_sun(s, (tr_vec3){0, 1, 0}, sun, (tr_vec3){1, 1, 1}, &err) == TR_OK, "%s",
              err.msg);
    }
    tr_render_config cfg = tr_render_config_default();
    tr_ck_id id;
    CHECK(tr_ck_identity(&id, s, &cfg, NULL, &err) == TR_OK, "%s", err.msg);
    tr_scene_destroy(s);
    return id.scene_hash;
}

static void test_identity(void) {
    const uint64_t h = hash_with(0xffffffffu, 1.0f, 0.0f);
    CHECK(hash_with(0xffffffffu, 1.0f, 0.0f) == h, "the identity of one scene varies");
    CHECK(hash_with(0xfffffffeu, 1.0f, 0.0f) != h, "a texture's texel is not in the identity");
    CHECK(hash_with(0xffffffffu, 2.0f, 0.0f) != h, "an environment map is not in the identity");
    CHECK(hash_with(0xffffffffu, 1.0f, 0.5f) != hash_with(0xffffffffu, 1.0f, 1.0f),
          "the sun is not in the identity");

    /* TRAC0R_VCM_RADIUS changes vcm's image: a render under another radius is another. */
    tr_error err;
    tr_scene *s = cornell();
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = tr_integrator_from_name("vcm");
    tr_ck_id a, b;
    unsetenv("TRAC0R_VCM_RADIUS");
    CHECK(tr_ck_identity(&a, s, &cfg, NULL, &err) == TR_OK, "%s", err.msg);
    setenv("TRAC0R_VCM_RADIUS", "5", 1);
    CHECK(tr_ck_identity(&b, s, &cfg, NULL, &err) == TR_OK, "%s", err.msg);
    CHECK(strcmp(a.desc, b.desc) != 0 || a.scene_hash != b.scene_hash,
          "TRAC0R_VCM_RADIUS is not in the identity");
    setenv("TRAC0R_VCM_RADIUS", "nonsense", 1);
    CHECK_STATUS(tr_ck_identity(&b, s, &cfg, NULL, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "an unusable TRAC0R_VCM_RADIUS");
    unsetenv("TRAC0R_VCM_RADIUS");
    tr_scene_destroy(s);
}

int main(void) {
    test_identity();
    snprintf(path, sizeof path, "/tmp/trac0r-test-checkpoint-%ld.ck", (long)getpid());
    tr_error err;
    tr_scene *s = cornell();
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = PASSES;
    tr_ck_id id;
    CHECK(tr_ck_identity(&id, s, &cfg, NULL, &err) == TR_OK, "%s", err.msg);

    uint32_t full[TILES] = {4, 4, 4, 4};
    tr_film f;
    make_film(&f, W, H, PASSES, 4);
    CHECK(write_read(&id, &f, 4, full) == TR_OK, "a true checkpoint is refused");

    /* A tile claimed rendered whose pixels hold nothing: resuming would leave a hole. */
    for (uint32_t y = 32; y < 64; ++y) {
        for (uint32_t x = 0; x < 32; ++x) {
            f.count[(size_t)y * W + x] = 0;
        }
    }
    CHECK(write_read(&id, &f, 4, full) == TR_STATUS_PARSE, "a hollowed tile is accepted");
    tr_film_free(&f);

    /* A film smaller than the identity's image. */
    make_film(&f, 32, 32, PASSES, 4);
    CHECK(write_read(&id, &f, 4, full) == TR_STATUS_PARSE, "an 32x32 film of a 64x64 render");
    tr_film_free(&f);

    /* A film without a pass the render keeps. */
    make_film(&f, W, H, TR_PASS_ALBEDO, 4);
    CHECK(write_read(&id, &f, 4, full) == TR_STATUS_PARSE, "a film without the depth pass");
    tr_film_free(&f);

    /* A sample count beyond what a render may ask for. */
    uint32_t none[TILES] = {0, 0, 0, 0};
    make_film(&f, W, H, PASSES, 0);
    CHECK(write_read(&id, &f, 0xffffffffu, none) == TR_STATUS_LIMIT,
          "a checkpoint of 2^32-1 samples per pixel");
    CHECK(write_read(&id, &f, TR_SESSION_SPP_MAX + 1u, none) == TR_STATUS_LIMIT,
          "a checkpoint of more samples than --spp allows");
    CHECK(write_read(&id, &f, TR_SESSION_SPP_MAX, none) == TR_OK,
          "a checkpoint of the most samples --spp allows");
    tr_film_free(&f);

    /* The wrong magic in a file far larger than memory would hold (sparse): refused after
     * reading its first bytes, not after reading it whole. */
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    CHECK(fd >= 0 && write(fd, "NOTACKPT", 8) == 8 && ftruncate(fd, 8ll << 30) == 0,
          "cannot make a sparse file");
    if (fd >= 0) {
        close(fd);
    }
    uint32_t got[TILES];
    tr_ck_tiles plan = {SIDE, TILES, got};
    tr_film back;
    uint32_t spp = 0;
    CHECK_STATUS(tr_ck_read(path, &id, &plan, &back, &spp, &err), err, TR_STATUS_PARSE,
                 "a sparse file of the wrong magic");

    /* A small file whose header claims a film of 16384 x 4096. */
    unsigned char head[4096] = {0};
    memcpy(head, "TRAC0RCK", 8);
    const uint32_t words[9] = {3, 0x01020304u, 16384, 4096, 0, 1, SIDE, TILES, 0};
    memcpy(head + 8, words, sizeof words);
    FILE *fp = fopen(path, "wb");
    CHECK(fp && fwrite(head, 1, sizeof head, fp) == sizeof head && fclose(fp) == 0,
          "cannot write %s", path);
    CHECK_STATUS(tr_ck_read(path, &id, &plan, &back, &spp, &err), err, TR_STATUS_PARSE,
                 "a 4 KB checkpoint claiming 16384 x 4096");

    remove(path);
    tr_scene_destroy(s);
    return check_finish("test_checkpoint");
}
