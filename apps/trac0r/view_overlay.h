/* view_overlay.h - the viewer's debug overlay: text (SDL2_ttf, a font found through
 * fontconfig) and wireframe boxes projected through the camera. */
#ifndef TRAC0R_VIEW_OVERLAY_H
#define TRAC0R_VIEW_OVERLAY_H

#include <SDL.h>
#include <SDL_ttf.h>
#include <stddef.h>

#include "trac0r/trac0r.h"

/* The font file to use: `override` when given (it must be readable), else DejaVu Sans
 * Mono as fontconfig finds it. Fails with a message saying what to install or pass. */
int view_font_find(const char *override, char *path, size_t n, tr_error *err);

/* Draws newline-separated text at (x, y) on a translucent dark panel and returns the
 * panel; a negative x or y puts it against the right or bottom edge (never past the left
 * or top one). */
SDL_Rect view_draw_text(SDL_Renderer *ren, TTF_Font *font, int x, int y, const char *text);

/* Draws the 12 edges of each box, projected through cam and clipped. */
void view_draw_boxes(SDL_Renderer *ren, const tr_camera *cam, const tr_aabb *boxes, size_t n,
                     SDL_Color color);

/* Draws the committed binary BVH's node boxes (none for a scene without one) from the
 * root down to depth max_depth (root = 0), the colour going from yellow-white at the
 * root to red at max_depth. Returns how many. */
size_t view_draw_bvh(SDL_Renderer *ren, const tr_camera *cam, const tr_scene *scene,
                     uint32_t max_depth);
/* The depth of the scene's committed binary BVH (0 without one). */
uint32_t view_bvh_depth(const tr_scene *scene);

#endif
