/* sun.c - the sun's host side: its cone and radiance from what a scene file says. */
#include <math.h>
#include <string.h>

#include "scene/scene_internal.h"

int tr_scene_set_sun(tr_scene *s, tr_vec3 dir, float angle_deg, tr_vec3 irradiance, tr_error *err) {
    const float len = v3_length(dir);
    if (!v3_is_finite(dir) || !(len > 0.0f) || !isfinite(len)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "sun direction (%g, %g, %g) must be a finite non-zero vector",
                            (double)dir.x, (double)dir.y, (double)dir.z);
    }
    if (!(angle_deg >= TR_SUN_MIN_ANGLE && angle_deg <= TR_SUN_MAX_ANGLE)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "sun angle %g must be in [%g, %g] degrees", (double)angle_deg,
                            (double)TR_SUN_MIN_ANGLE, (double)TR_SUN_MAX_ANGLE);
    }
    if (!v3_is_finite(irradiance) || irradiance.x < 0.0f || irradiance.y < 0.0f ||
        irradiance.z < 0.0f) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "sun irradiance must be finite and non-negative");
    }
    /* Half the diameter, in double: 1 - cos t = 2 sin^2(t / 2) without cancellation. */
    const double t = 0.5 * (double)angle_deg * 3.14159265358979323846 / 180.0;
    const double sh = sin(0.5 * t), st = sin(t);
    const double omc = 2.0 * sh * sh;
    /* E = L pi sin^2 t for a surface facing the disc. */
    const double k = 1.0 / (3.14159265358979323846 * st * st);
    memset(&s->sun, 0, sizeof s->sun);
    s->sun.dir = v3_scale(dir, 1.0f / len);
    s->sun.one_minus_cos = (float)omc;
    s->sun.radiance =
        v3((float)(irradiance.x * k), (float)(irradiance.y * k), (float)(irradiance.z * k));
    s->sun.pdf = (float)(1.0 / (2.0 * 3.14159265358979323846 * omc));
    s->sun_count = 1;
    s->generation++;
    return TR_OK;
}

int tr_scene_sun(const tr_scene *s, tr_vec3 *dir, float *angle_deg, tr_vec3 *irradiance) {
    if (!s->sun_count) {
        return 0;
    }
    /* The inverse of tr_scene_set_sun's: t = 2 asin(sqrt((1 - cos t) / 2)). */
    const double t = 2.0 * asin(sqrt(0.5 * (double)s->sun.one_minus_cos));
    const double k = 3.14159265358979323846 * sin(t) * sin(t);
    if (dir) {
        *dir = s->sun.dir;
    }
    if (angle_deg) {
        *angle_deg = (float)(2.0 * t * 180.0 / 3.14159265358979323846);
    }
    if (irradiance) {
        *irradiance = v3((float)(s->sun.radiance.x * k), (float)(s->sun.radiance.y * k),
                         (float)(s->sun.radiance.z * k));
    }
    return 1;
}
