/* info.c - `trac0r info SCENE`: what a scene holds, without rendering it. */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "devices.h"
#include "trac0r/registry.h"
#include "trac0r/scene_file.h"

static void info_help(void) {
    printf("Usage: trac0r info SCENE [options]\n"
           "       trac0r info --devices\n"
           "\n"
           "Describes a scene (counts, bounds, camera, materials, render defaults, warnings)\n"
           "without rendering it, or lists the OpenCL devices as --device opencl:N numbers\n"
           "them. Exit status 2 when the scene does not load or no OpenCL platform is found.\n"
           "\n"
           "Options:\n"
           "  --devices            list the OpenCL devices instead of describing a scene\n"
           "  --up y|z             a model file's up axis (default y)\n"
           "  --scale S            a model file's scale (default 1)\n"
           "  --camera N|NAME|frame  a model file's camera (default its first)\n"
           "  -h, --help           show this help\n");
}

int cmd_info(int argc, char **argv) {
    cli_args a = {.cmd = "info", .argc = argc, .argv = argv, .i = 0};
    const char *path = NULL;
    int devices = 0;
    cli_common mc; /* --up, --scale for model files */
    cli_common_default(&mc);
    while (cli_next(&a)) {
        if (cli_is(&a, "-h") || cli_is(&a, "--help")) {
            info_help();
            return CLI_OK;
        } else if (cli_is(&a, "--devices")) {
            devices = 1;
        } else if (cli_is(&a, "--up") || cli_is(&a, "--scale") || cli_is(&a, "--camera")) {
            if (cli_common_option(&a, &mc) != CLI_OK) {
                return CLI_USAGE;
            }
        } else if (a.opt[0] != '-' && !path) {
            path = a.opt;
        } else {
            return cli_unknown(&a);
        }
    }
    if (devices && path) {
        return cli_error(&a, "--devices takes no SCENE (see 'trac0r info --help')");
    }
    if (devices) {
        return cli_print_devices(stdout);
    }
    if (!path) {
        return cli_error(&a, "missing SCENE or --devices (see 'trac0r info --help')");
    }
    tr_scene_file f;
    memset(&f, 0, sizeof f);
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    if (!s) {
        return cli_error(&a, "%s", err.msg);
    }
    const int builtin = tr_scene_name_is_builtin(path);
    const tr_model_options mo = {mc.up_z, mc.model_scale, 0, 0, mc.model_camera};
    if (tr_scene_load(s, path, &mo, &f, &err) != TR_OK) {
        tr_scene_destroy(s);
        return cli_error(&a, "%s", err.msg);
    }
    printf("scene:      %s\n", path);
    printf("triangles:  %u (%u from %u mesh file%s in %u part%s, %u degenerate faces dropped)\n",
           tr_scene_triangle_count(s), f.mesh_triangles, f.mesh_count, f.mesh_count == 1 ? "" : "s",
           f.mesh_parts, f.mesh_parts == 1 ? "" : "s", f.degenerate_dropped);
    printf("shapes:     %u (%u boxes in the flat structure)\n", f.shape_count,
           tr_scene_shape_count(s));
    printf("materials:  %u\n", tr_scene_material_count(s));
    printf("emitters:   %u material%s, %u triangle%s\n", f.emitter_materials,
           f.emitter_materials == 1 ? "" : "s", f.emissive_triangles,
           f.emissive_triangles == 1 ? "" : "s");
    printf("bounds:     (%g, %g, %g) .. (%g, %g, %g)\n", (double)f.bounds.min.x,
           (double)f.bounds.min.y, (double)f.bounds.min.z, (double)f.bounds.max.x,
           (double)f.bounds.max.y, (double)f.bounds.max.z);
    const tr_camera *cam = tr_scene_camera(s);
    printf("camera:     at (%g, %g, %g), looking (%g, %g, %g), up (%g, %g, %g), vertical fov %g\n",
           (double)cam->pos.x, (double)cam->pos.y, (double)cam->pos.z, (double)cam->dir.x,
           (double)cam->dir.y, (double)cam->dir.z, (double)cam->up.x, (double)cam->up.y,
           (double)cam->up.z, (double)cam->vertical_fov);
    tr_vec3 sun_dir, sun_e;
    float sun_angle;
    if (tr_scene_sun(s, &sun_dir, &sun_angle, &sun_e)) {
        printf("sun:        towards (%g, %g, %g), %g degrees, irradiance (%g, %g, %g)\n",
               (double)sun_dir.x, (double)sun_dir.y, (double)sun_dir.z, (double)sun_angle,
               (double)sun_e.x, (double)sun_e.y, (double)sun_e.z);
    }
    uint32_t with_normals = 0;
    for (uint32_t i = 0; i < tr_scene_triangle_count(s); ++i) {
        tr_vec3 n[3];
        with_normals += (uint32_t)tr_scene_triangle_normals(s, i, n);
    }
    printf("normals:    %u triangles with vertex normals\n", with_normals);
    /* Per shape or mesh part: its triangles, its material and its bounds. */
    const uint32_t shown_max = 32, ns = tr_scene_shape_count(s);
    for (uint32_t i = 0; i < ns && i < shown_max; ++i) {
        tr_aabb b = tr_scene_shape_box(s, i);
        uint32_t first = 0;
        for (uint32_t k = 0; k < i; ++k) {
            first += tr_scene_shape_triangle_count(s, k);
        }
        printf("part %-5u  %u triangles, material %u, bounds (%g, %g, %g) .. (%g, %g, %g)\n", i,
               tr_scene_shape_triangle_count(s, i), tr_scene_triangle(s, first).material,
               (double)b.min.x, (double)b.min.y, (double)b.min.z, (double)b.max.x, (double)b.max.y,
               (double)b.max.z);
    }
    if (ns > shown_max) {
        printf("part ...    %u more\n", ns - shown_max);
    }
    for (uint32_t i = 0; i < tr_scene_material_count(s) && i < shown_max; ++i) {
        tr_material m = tr_scene_material(s, i);
        uint32_t maps = tr_scene_material_maps(s, i);
        printf("material %-3u %s, colour (%.3g, %.3g, %.3g)%s%s%s%s%s%s\n", i,
               tr_material_type_name(m.type) ? tr_material_type_name(m.type) : "?",
               (double)m.color.x, (double)m.color.y, (double)m.color.z, maps ? ", maps:" : "",
               maps & TR_MAP_BASE ? " base" : "",
               maps & TR_MAP_METALLIC_ROUGHNESS ? " metallic-roughness" : "",
               maps & TR_MAP_NORMAL ? " normal" : "", maps & TR_MAP_EMISSION ? " emission" : "",
               maps & TR_MAP_CUTOUT ? " cut-out" : "");
    }
    if (!builtin) {
        cli_common d; /* the integrator the command line defaults to */
        cli_common_default(&d);
        printf("render:     %ux%u%s, %u spp%s, max depth %d%s, integrator %s%s, accel %s%s\n",
               f.width, f.height, f.has_width || f.has_height ? "" : " (default)", f.spp,
               f.has_spp ? "" : " (default)",
               f.has_max_depth
                   ? f.max_depth
                   : tr_default_max_depth(f.has_integrator ? tr_integrator_from_name(f.integrator)
                                                           : d.integrator),
               f.has_max_depth ? "" : " (default)",
               f.has_integrator ? f.integrator : tr_integrator_name(d.integrator),
               f.has_integrator ? "" : " (default)", tr_accel_name(f.accel),
               f.has_accel ? "" : " (default)");
    }
    printf("warnings:   %u\n", f.warning_count);
    for (uint32_t i = 0; i < f.warning_count; ++i) {
        printf("  warning: %s\n", f.warnings[i]);
    }
    tr_scene_destroy(s);
    return CLI_OK;
}
