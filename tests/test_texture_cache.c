/* test_texture_cache.c - a scene decodes each texture file once: sixteen materials naming
 * one file hold its texels once (another wrap mode shares them too), and the texel budget
 * (TRAC0R_TEXEL_BUDGET) bounds what one scene may hold, however its files are named. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>

#include "check.h"
#include "scene/scene_internal.h"
#include "scene/texture.h"

#ifndef TR_SOURCE_DIR
#error "TR_SOURCE_DIR must name the source tree"
#endif
#define PNG TR_SOURCE_DIR "/tests/data/texture/checker.png"

int main(void) {
    tr_error err;
    unsetenv("TRAC0R_TEXEL_BUDGET");
    tr_scene *s = tr_scene_create(&err);
    uint32_t first = 0, index = 0;
    CHECK(tr_scene_load_texture(s, PNG, 0, &first, &err) == TR_OK, "%s", err.msg);
    const uint32_t texels = s->texel_count;
    CHECK(texels > 0, "no texels");
    for (int k = 0; k < 15; ++k) {
        CHECK(tr_scene_load_texture(s, PNG, 0, &index, &err) == TR_OK && index == first,
              "the file named again is another texture (%u, %u)", index, first);
    }
    CHECK(s->texel_count == texels, "one file named 16 times holds %u texels, not %u",
          s->texel_count, texels);
    CHECK(tr_scene_load_texture(s, PNG, TR_TEXTURE_CLAMP, &index, &err) == TR_OK &&
              index != first && s->textures[index].flags == TR_TEXTURE_CLAMP &&
              s->textures[index].offset == s->textures[first].offset,
          "another wrap mode of one file");
    CHECK(s->texel_count == texels, "another wrap mode copied the texels");
    tr_scene_destroy(s);

    /* The budget: one texel fewer than the file has is refused, what it has is accepted. */
    char budget[32];
    snprintf(budget, sizeof budget, "%u", texels - 1);
    setenv("TRAC0R_TEXEL_BUDGET", budget, 1);
    s = tr_scene_create(&err);
    CHECK_STATUS(tr_scene_load_texture(s, PNG, 0, &index, &err), err, TR_STATUS_LIMIT,
                 "a texture over the budget");
    tr_scene_destroy(s);
    snprintf(budget, sizeof budget, "%u", texels);
    setenv("TRAC0R_TEXEL_BUDGET", budget, 1);
    s = tr_scene_create(&err);
    CHECK(tr_scene_load_texture(s, PNG, 0, &index, &err) == TR_OK, "%s", err.msg);
    tr_scene_destroy(s);
    setenv("TRAC0R_TEXEL_BUDGET", " 5", 1);
    s = tr_scene_create(&err);
    CHECK_STATUS(tr_scene_load_texture(s, PNG, 0, &index, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "an unusable TRAC0R_TEXEL_BUDGET");
    tr_scene_destroy(s);
    unsetenv("TRAC0R_TEXEL_BUDGET");
    return check_finish("test_texture_cache");
}
