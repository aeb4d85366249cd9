/* describe.c - a scene in words: the committed acceleration structure in one line
 * (trac0r/scene.h), and what a loaded scene holds (trac0r/scene_file.h). */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/scene_internal.h"
#include "trac0r/registry.h"
#include "trac0r/scene.h"
#include "trac0r/scene_file.h"

void tr_scene_accel_describe(const tr_scene *s, int detail, char *buf, size_t n) {
    tr_accel_info info;
    tr_scene_accel_info(s, &info);
    char more[160] = "";
    if (info.type == TR_ACCEL_TYPE_BVH) {
        /* The traversal's ISA is chosen at run time; a TRAC0R_ISA the CPU (or build)
         * cannot honour is said here rather than silently replaced. */
        const char *asked = getenv("TRAC0R_ISA");
        char note[96] = "";
        if (asked && *asked && strcmp(asked, info.wide_isa) != 0) {
            snprintf(note, sizeof note, ", TRAC0R_ISA=%.40s unavailable", asked);
        }
        if (detail) {
            snprintf(more, sizeof more,
                     ": %u nodes, %u leaves, depth %u, from %u binary nodes; built in %.1f ms, "
                     "%.1f ms of it the collapse",
                     info.wide_nodes, info.wide_leaves, info.wide_depth, info.bvh_nodes,
                     tr_scene_bvh_build_seconds(s) * 1e3, info.wide_seconds * 1e3);
        }
        snprintf(buf, n, "bvh (%u-wide %s%s%s)", info.wide_width, info.wide_isa, note, more);
    } else if (!detail) {
        snprintf(buf, n, "%s", tr_accel_name(info.type));
    } else if (info.type == TR_ACCEL_TYPE_BVH2) {
        snprintf(buf, n, "bvh2 (%u nodes, %u leaves, depth %u, built in %.1f ms)", info.bvh_nodes,
                 info.bvh_leaves, info.bvh_depth, info.bvh_seconds * 1e3);
    } else if (info.type == TR_ACCEL_TYPE_EMBREE) {
        snprintf(buf, n, "embree (built in %.1f ms)", info.embree_seconds * 1e3);
    } else {
        snprintf(buf, n, "flat (%u shape boxes)", tr_scene_shape_count(s));
    }
}

char *tr_scene_describe(const tr_scene *s, const char *name, const tr_scene_file *info,
                        uint32_t listed) {
    char *text = NULL;
    size_t size = 0;
    FILE *out = open_memstream(&text, &size);
    if (!out) {
        return NULL;
    }
    fprintf(out, "scene:      %s\n", name);
    fprintf(out,
            "triangles:  %u (%u from %u mesh file%s in %u part%s, %u degenerate faces dropped)\n",
            tr_scene_triangle_count(s), info->mesh_triangles, info->mesh_count,
            info->mesh_count == 1 ? "" : "s", info->mesh_parts, info->mesh_parts == 1 ? "" : "s",
            info->degenerate_dropped);
    fprintf(out, "shapes:     %u (%u boxes in the flat structure)\n", info->shape_count,
            tr_scene_shape_count(s));
    fprintf(out, "materials:  %u\n", tr_scene_material_count(s));
    fprintf(out, "emitters:   %u material%s, %u triangle%s\n", info->emitter_materials,
            info->emitter_materials == 1 ? "" : "s", info->emissive_triangles,
            info->emissive_triangles == 1 ? "" : "s");
    fprintf(out, "bounds:     (%g, %g, %g) .. (%g, %g, %g)\n", (double)info->bounds.min.x,
            (double)info->bounds.min.y, (double)info->bounds.min.z, (double)info->bounds.max.x,
            (double)info->bounds.max.y, (double)info->bounds.max.z);
    const tr_camera *cam = tr_scene_camera(s);
    fprintf(out,
            "camera:     at (%g, %g, %g), looking (%g, %g, %g), up (%g, %g, %g), vertical fov %g\n",
            (double)cam->pos.x, (double)cam->pos.y, (double)cam->pos.z, (double)cam->dir.x,
            (double)cam->dir.y, (double)cam->dir.z, (double)cam->up.x, (double)cam->up.y,
            (double)cam->up.z, (double)cam->vertical_fov);
    tr_vec3 sun_dir, sun_e;
    float sun_angle;
    if (tr_scene_sun(s, &sun_dir, &sun_angle, &sun_e)) {
        fprintf(out, "sun:        towards (%g, %g, %g), %g degrees, irradiance (%g, %g, %g)\n",
                (double)sun_dir.x, (double)sun_dir.y, (double)sun_dir.z, (double)sun_angle,
                (double)sun_e.x, (double)sun_e.y, (double)sun_e.z);
    }
    uint32_t with_normals = 0;
    for (uint32_t i = 0; i < tr_scene_stored_triangle_count(s); ++i) {
        tr_vec3 n[3];
        with_normals += (uint32_t)tr_scene_triangle_normals(s, i, n);
    }
    with_normals += tr_scene_kept_normals(s);
    fprintf(out, "normals:    %u triangles with vertex normals\n", with_normals);
    /* Per shape or mesh part: its triangles, its material and its bounds. */
    const uint32_t shown_max = listed, ns = tr_scene_shape_count(s);
    for (uint32_t i = 0; i < ns && i < shown_max; ++i) {
        tr_aabb b = tr_scene_shape_box(s, i);
        uint32_t first = 0;
        for (uint32_t k = 0; k < i; ++k) {
            first += tr_scene_shape_triangle_count(s, k);
        }
        fprintf(out, "part %-5u  %u triangles, material %u, bounds (%g, %g, %g) .. (%g, %g, %g)\n",
                i, tr_scene_shape_triangle_count(s, i), tr_scene_triangle(s, first).material,
                (double)b.min.x, (double)b.min.y, (double)b.min.z, (double)b.max.x, (double)b.max.y,
                (double)b.max.z);
    }
    if (ns > shown_max) {
        fprintf(out, "part ...    %u more\n", ns - shown_max);
    }
    for (uint32_t i = 0; i < tr_scene_material_count(s) && i < shown_max; ++i) {
        tr_material m = tr_scene_material(s, i);
        uint32_t maps = tr_scene_material_maps(s, i);
        fprintf(out, "material %-3u %s, colour (%.3g, %.3g, %.3g)%s%s%s%s%s%s%s%s%s%s%s%s\n", i,
                tr_material_type_name(m.type) ? tr_material_type_name(m.type) : "?",
                (double)m.color.x, (double)m.color.y, (double)m.color.z, maps ? ", maps:" : "",
                maps & TR_MAP_BASE ? " base" : "",
                maps & TR_MAP_METALLIC_ROUGHNESS ? " metallic-roughness" : "",
                maps & TR_MAP_NORMAL ? " normal" : "", maps & TR_MAP_EMISSION ? " emission" : "",
                maps & TR_MAP_CUTOUT ? " cut-out" : "",
                maps & TR_MAP_TRANSMISSION ? " transmission" : "",
                maps & TR_MAP_CLEARCOAT ? " clearcoat" : "",
                maps & TR_MAP_CLEARCOAT_ROUGHNESS ? " clearcoat-roughness" : "",
                maps & TR_MAP_CLEARCOAT_NORMAL ? " clearcoat-normal" : "",
                maps & TR_MAP_SHEEN_COLOR ? " sheen-colour" : "",
                maps & TR_MAP_SHEEN_ROUGHNESS ? " sheen-roughness" : "");
    }
    if (!tr_scene_name_is_builtin(name)) {
        fprintf(out, "render:     %ux%u%s, %u spp%s, max depth %d%s, integrator %s%s, accel %s%s\n",
                info->width, info->height, info->has_width || info->has_height ? "" : " (default)",
                info->spp, info->has_spp ? "" : " (default)",
                info->has_max_depth
                    ? info->max_depth
                    : tr_default_max_depth(info->has_integrator
                                               ? tr_integrator_from_name(info->integrator)
                                               : TR_INTEGRATOR_PT),
                info->has_max_depth ? "" : " (default)",
                info->has_integrator ? info->integrator : tr_integrator_name(TR_INTEGRATOR_PT),
                info->has_integrator ? "" : " (default)", tr_accel_name(info->accel),
                info->has_accel ? "" : " (default)");
    }
    fprintf(out, "warnings:   %u\n", info->warning_count);
    for (uint32_t i = 0; i < info->warning_count; ++i) {
        fprintf(out, "  warning: %s\n", info->warnings[i]);
    }
    if (ferror(out)) {
        fclose(out);
        free(text);
        return NULL;
    }
    return fclose(out) == 0 ? text : (free(text), NULL);
}
