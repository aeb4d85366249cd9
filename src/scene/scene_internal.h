/* scene_internal.h - what the scene sources share inside the library. */
#ifndef TR_SCENE_INTERNAL_H
#define TR_SCENE_INTERNAL_H

#include "trac0r/scene.h"

/* Appends n triangles as one shape (one box of the flat structure), growing the scene's
 * arrays; `normals` (3 per triangle) may be NULL. The caller keeps its arrays. */
int tr_scene_append_shape(tr_scene *s, const tr_triangle *tris, uint32_t n, const tr_vec3 *normals,
                          tr_error *err);

#endif
