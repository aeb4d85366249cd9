/* describe.c - the committed acceleration structure in one line (trac0r/scene.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "trac0r/scene.h"

void tr_scene_accel_describe(const tr_scene *s, char *buf, size_t n) {
    tr_accel_info info;
    tr_scene_accel_info(s, &info);
    if (info.type == TR_ACCEL_TYPE_BVH) {
        /* The traversal's ISA is chosen at run time; a TRAC0R_ISA the CPU (or build)
         * cannot honour is said here rather than silently replaced. */
        const char *asked = getenv("TRAC0R_ISA");
        char note[96] = "";
        if (asked && *asked && strcmp(asked, info.wide_isa) != 0) {
            snprintf(note, sizeof note, ", TRAC0R_ISA=%.40s unavailable", asked);
        }
        snprintf(buf, n,
                 "bvh (%u-wide %s%s: %u nodes, %u leaves, depth %u, from %u binary nodes; built "
                 "in %.1f ms, %.1f ms of it the collapse)",
                 info.wide_width, info.wide_isa, note, info.wide_nodes, info.wide_leaves,
                 info.wide_depth, info.bvh_nodes, tr_scene_bvh_build_seconds(s) * 1e3,
                 info.wide_seconds * 1e3);
    } else if (info.type == TR_ACCEL_TYPE_BVH2) {
        snprintf(buf, n, "bvh2 (%u nodes, %u leaves, depth %u, built in %.1f ms)", info.bvh_nodes,
                 info.bvh_leaves, info.bvh_depth, info.bvh_seconds * 1e3);
    } else if (info.type == TR_ACCEL_TYPE_EMBREE) {
        snprintf(buf, n, "embree (built in %.1f ms)", info.embree_seconds * 1e3);
    } else {
        snprintf(buf, n, "flat (%u shape boxes)", tr_scene_shape_count(s));
    }
}
