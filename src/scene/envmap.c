/* envmap.c - the environment light's host side: the map and the CDFs that
 * src/kernel/envmap.h samples it by. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "kernel/envmap.h"
#include "scene/scene_internal.h"
#include "scene/texture.h"

int tr_scene_set_environment(tr_scene *s, tr_vec3 color, float strength, float rotation,
                             const float *rgb, uint32_t width, uint32_t height, tr_error *err) {
    if (!v3_is_finite(color) || color.x < 0.0f || color.y < 0.0f || color.z < 0.0f ||
        !(strength >= 0.0f) || !isfinite(strength) || !isfinite(rotation)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "environment colour, strength and rotation must be finite and "
                            "non-negative");
    }
    if (rgb && (width == 0 || height == 0 || (uint64_t)width * height > TR_TEXTURE_MAX_TEXELS)) {
        return tr_error_set(err, TR_STATUS_LIMIT, "environment map of %ux%u texels", width, height);
    }
    float *texels = NULL, *cdf = NULL;
    uint32_t nt = 0, nc = 0;
    double sum = 0.0;
    if (rgb) {
        const size_t n = (size_t)width * height;
        nt = (uint32_t)(3 * n);
        nc = (height + 1) + height * (width + 1);
        texels = malloc((size_t)nt * sizeof *texels);
        cdf = malloc((size_t)nc * sizeof *cdf);
        double *row_sum = malloc((size_t)height * sizeof *row_sum);
        if (!texels || !cdf || !row_sum) {
            free(texels);
            free(cdf);
            free(row_sum);
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for the environment");
        }
        for (size_t i = 0; i < 3 * n; ++i) {
            float x = rgb[i];
            texels[i] = x >= 0.0f && x <= 1e30f ? x : (x > 1e30f ? 1e30f : 0.0f);
        }
        /* Weights as the kernel computes them (tr_env_weight), summed in double. */
        tr_env tmp;
        memset(&tmp, 0, sizeof tmp);
        tmp.width = width;
        tmp.height = height;
        tr_scene_view v;
        memset(&v, 0, sizeof v);
        v.env = &tmp;
        v.env_count = 1;
        v.env_texels = texels;
        for (uint32_t j = 0; j < height; ++j) {
            float *row = cdf + (height + 1) + (size_t)j * (width + 1);
            double acc = 0.0;
            row[0] = 0.0f;
            for (uint32_t i = 0; i < width; ++i) {
                acc += tr_env_weight(&v, j * width + i, j);
                row[i + 1] = (float)acc;
            }
            row_sum[j] = acc;
            for (uint32_t i = 1; i <= width; ++i) {
                /* A black row keeps a uniform CDF; the marginal never picks it. */
                row[i] = acc > 0.0 ? (float)(row[i] / acc) : (float)i / (float)width;
            }
            row[width] = 1.0f;
            sum += acc;
        }
        double acc = 0.0;
        cdf[0] = 0.0f;
        for (uint32_t j = 0; j < height; ++j) {
            acc += row_sum[j];
            cdf[j + 1] = sum > 0.0 ? (float)(acc / sum) : (float)(j + 1) / (float)height;
        }
        cdf[height] = 1.0f;
        free(row_sum);
    }
    free(s->env_texels);
    free(s->env_cdf);
    s->env_texels = texels;
    s->env_texel_count = nt;
    s->env_cdf = cdf;
    s->env_cdf_count = nc;
    memset(&s->env, 0, sizeof s->env);
    s->env.color = color;
    s->env.strength = strength;
    s->env.rot_cos = cosf(rotation);
    s->env.rot_sin = sinf(rotation);
    s->env.width = rgb ? width : 0;
    s->env.height = rgb ? height : 0;
    s->env.weight_sum = (float)sum;
    s->env_count = 1;
    s->generation++;
    return TR_OK;
}

int tr_scene_load_environment(tr_scene *s, const char *path, tr_vec3 color, float strength,
                              float rotation, tr_error *err) {
    unsigned char *data;
    size_t len;
    if (tr_read_image_file(path, &data, &len, err) != TR_OK) {
        return TR_ERR;
    }
    float *rgb;
    uint32_t w, h;
    int rc = tr_image_decode_rgbf(data, len, path, &rgb, &w, &h, err);
    free(data);
    if (rc != TR_OK) {
        return TR_ERR;
    }
    rc = tr_scene_set_environment(s, color, strength, rotation, rgb, w, h, err);
    free(rgb);
    return rc;
}
