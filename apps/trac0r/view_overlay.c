/* view_overlay.c - debug overlay text and wireframes. */
#define _POSIX_C_SOURCE 200809L
#include "view_overlay.h"

#include <errno.h>
#include <fontconfig/fontconfig.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "view_wire.h"

#define FONT_FAMILY "DejaVu Sans Mono"

int view_font_find(const char *override, char *path, size_t n, tr_error *err) {
    if (override) {
        /* stat, not fopen: opening a FIFO named as the font would block. */
        struct stat st;
        if (stat(override, &st) != 0) {
            return tr_error_set(err, tr_status_from_errno(errno), "--font: cannot open '%s'",
                                override);
        }
        if (!S_ISREG(st.st_mode)) {
            return tr_error_set(err, TR_STATUS_IO, "--font: cannot open '%s': not a regular file",
                                override);
        }
        snprintf(path, n, "%s", override);
        return TR_OK;
    }
    int found = 0;
    FcConfig *cfg = FcInitLoadConfigAndFonts();
    FcPattern *pat = cfg ? FcNameParse((const FcChar8 *)FONT_FAMILY ":style=Book") : NULL;
    if (pat) {
        FcConfigSubstitute(cfg, pat, FcMatchPattern);
        FcDefaultSubstitute(pat);
        FcResult res = FcResultNoMatch;
        FcPattern *match = FcFontMatch(cfg, pat, &res);
        FcChar8 *family = NULL, *file = NULL;
        /* fontconfig always offers some font: accept only the family asked for. */
        if (match && FcPatternGetString(match, FC_FAMILY, 0, &family) == FcResultMatch &&
            FcPatternGetString(match, FC_FILE, 0, &file) == FcResultMatch &&
            strcasecmp((const char *)family, FONT_FAMILY) == 0) {
            snprintf(path, n, "%s", (const char *)file);
            found = 1;
        }
        if (match) {
            FcPatternDestroy(match);
        }
        FcPatternDestroy(pat);
    }
    if (cfg) {
        FcConfigDestroy(cfg);
    }
    if (!found) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND,
                            "fontconfig finds no '" FONT_FAMILY
                            "' font for the debug view (install fonts-dejavu-core "
                            "or pass --font FILE.ttf)");
    }
    return TR_OK;
}

SDL_Rect view_draw_text(SDL_Renderer *ren, TTF_Font *font, int x, int y, const char *text) {
    enum { MAX_LINES = 48 };
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", text);
    char *lines[MAX_LINES];
    int count = 0, width = 0;
    for (char *s = buf, *save = NULL; count < MAX_LINES; s = NULL) {
        char *line = strtok_r(s, "\n", &save);
        if (!line) {
            break;
        }
        int w = 0, h = 0;
        TTF_SizeUTF8(font, line, &w, &h);
        width = w > width ? w : width;
        lines[count++] = line;
    }
    const int skip = TTF_FontLineSkip(font);
    SDL_Rect panel = {x, y, width + 12, count * skip + 8};
    int ww = 0, wh = 0;
    if ((x < 0 || y < 0) && SDL_GetRendererOutputSize(ren, &ww, &wh) == 0) {
        panel.x = x < 0 ? (ww > panel.w ? ww - panel.w : 0) : x;
        panel.y = y < 0 ? (wh > panel.h ? wh - panel.h : 0) : y;
    }
    x = panel.x;
    y = panel.y;
    SDL_SetRenderDrawBlendMode(ren, SDL_BLENDMODE_BLEND);
    SDL_SetRenderDrawColor(ren, 0, 0, 0, 170);
    SDL_RenderFillRect(ren, &panel);
    const SDL_Color white = {255, 255, 255, 255};
    for (int i = 0; i < count; ++i) {
        SDL_Surface *surf = TTF_RenderUTF8_Blended(font, lines[i], white);
        if (!surf) {
            continue;
        }
        SDL_Texture *tex = SDL_CreateTextureFromSurface(ren, surf);
        if (tex) {
            SDL_Rect dst = {x + 6, y + 4 + i * skip, surf->w, surf->h};
            SDL_RenderCopy(ren, tex, NULL, &dst);
            SDL_DestroyTexture(tex);
        }
        SDL_FreeSurface(surf);
    }
    return panel;
}

static void draw_box(SDL_Renderer *ren, const tr_camera *cam, const tr_aabb *box) {
    tr_vec3 corners[8];
    view_box_corners(box, corners);
    for (int e = 0; e < 12; ++e) {
        float seg[4];
        if (view_project_segment(cam, corners[view_box_edges[e][0]], corners[view_box_edges[e][1]],
                                 seg) &&
            view_clip_segment_2d(seg, (float)cam->screen_width, (float)cam->screen_height, 2.0f)) {
            SDL_RenderDrawLineF(ren, seg[0], seg[1], seg[2], seg[3]);
        }
    }
}

void view_draw_boxes(SDL_Renderer *ren, const tr_camera *cam, const tr_aabb *boxes, size_t n,
                     SDL_Color color) {
    SDL_SetRenderDrawBlendMode(ren, SDL_BLENDMODE_NONE);
    SDL_SetRenderDrawColor(ren, color.r, color.g, color.b, color.a);
    for (size_t i = 0; i < n; ++i) {
        draw_box(ren, cam, &boxes[i]);
    }
}

uint32_t view_bvh_depth(const tr_scene *scene) {
    tr_accel_info info;
    tr_scene_accel_info(scene, &info);
    return info.bvh_depth;
}

size_t view_draw_bvh(SDL_Renderer *ren, const tr_camera *cam, const tr_scene *scene,
                     uint32_t max_depth) {
    const uint32_t node_count = tr_scene_bvh_node_count(scene);
    if (node_count == 0) {
        return 0;
    }
    /* Two children pushed per level: room for any depth the BVH builder makes (it stops
     * at 64 levels), and the push below checks anyway. */
    enum { STACK = 2 * 64 + 2 };
    uint32_t stack[STACK], depth[STACK];
    int top = 0;
    size_t drawn = 0;
    stack[top] = 0;
    depth[top++] = 0;
    SDL_SetRenderDrawBlendMode(ren, SDL_BLENDMODE_NONE);
    while (top > 0) {
        --top;
        const uint32_t i = stack[top], d = depth[top];
        tr_aabb box;
        uint32_t first = 0;
        const int interior = tr_scene_bvh_node(scene, i, &box, &first);
        if (interior < 0) {
            continue;
        }
        /* Shallow boxes light, deep ones red: g falls from 255 to 0 over the depths. */
        const Uint8 g = (Uint8)(max_depth ? 255u - 255u * d / max_depth : 255u);
        SDL_SetRenderDrawColor(ren, 255, g, (Uint8)(g / 2), 255);
        draw_box(ren, cam, &box);
        ++drawn;
        if (interior && d < max_depth && top + 2 <= STACK && first + 1 < node_count) {
            stack[top] = first;
            depth[top++] = d + 1;
            stack[top] = first + 1;
            depth[top++] = d + 1;
        }
    }
    return drawn;
}
