/* registry.c - name tables generated from the X-macro lists of material types,
 * integrators and acceleration structures (trac0r/registry.h). */
#include "trac0r/registry.h"

#include <stdio.h>
#include <string.h>

/* Index of name in names[0 .. count), or -1. */
static int find_name(const char *const *names, size_t count, const char *name) {
    for (size_t i = 0; name && i < count; ++i) {
        if (strcmp(names[i], name) == 0) {
            return (int)i;
        }
    }
    return -1;
}

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

/* Material types. */
#define MAT_NAME(id, value, name, required, optional) name,
#define MAT_VALUE(id, value, name, required, optional) value,
static const char *const material_names[] = {TR_MATERIAL_TYPES(MAT_NAME)};
static const uint32_t material_values[] = {TR_MATERIAL_TYPES(MAT_VALUE)};

int tr_material_type_from_name(const char *name) {
    int i = find_name(material_names, COUNT(material_names), name);
    return i < 0 ? -1 : (int)material_values[i];
}

const char *tr_material_type_name(uint32_t type) {
    for (size_t i = 0; i < COUNT(material_values); ++i) {
        if (material_values[i] == type) {
            return material_names[i];
        }
    }
    return NULL;
}

const char *const *tr_material_type_names(size_t *count) {
    *count = COUNT(material_names);
    return material_names;
}

/* Integrators. */
#define INT_NAME(id, value, name, description) name,
#define INT_VALUE(id, value, name, description) value,
#define INT_DESCRIPTION(id, value, name, description) description,
static const char *const integrator_names[] = {TR_INTEGRATORS(INT_NAME)};
static const int integrator_values[] = {TR_INTEGRATORS(INT_VALUE)};
static const char *const integrator_descriptions[] = {TR_INTEGRATORS(INT_DESCRIPTION)};

static int integrator_index(int integrator) {
    for (size_t i = 0; i < COUNT(integrator_values); ++i) {
        if (integrator_values[i] == integrator) {
            return (int)i;
        }
    }
    return -1;
}

int tr_integrator_from_name(const char *name) {
    int i = find_name(integrator_names, COUNT(integrator_names), name);
    return i < 0 ? -1 : integrator_values[i];
}

const char *tr_integrator_name(int integrator) {
    int i = integrator_index(integrator);
    return i < 0 ? NULL : integrator_names[i];
}

const char *tr_integrator_description(int integrator) {
    int i = integrator_index(integrator);
    return i < 0 ? NULL : integrator_descriptions[i];
}

const char *const *tr_integrator_names(size_t *count) {
    *count = COUNT(integrator_names);
    return integrator_names;
}

/* Acceleration structures. */
#define ACC_NAME(id, value, name, description) name,
#define ACC_VALUE(id, value, name, description) TR_ACCEL_TYPE_##id,
#define ACC_DESCRIPTION(id, value, name, description) description,
static const char *const accel_names[] = {TR_ACCEL_TYPES(ACC_NAME)};
static const tr_accel_type accel_values[] = {TR_ACCEL_TYPES(ACC_VALUE)};
static const char *const accel_descriptions[] = {TR_ACCEL_TYPES(ACC_DESCRIPTION)};

static int accel_index(tr_accel_type type) {
    for (size_t i = 0; i < COUNT(accel_values); ++i) {
        if (accel_values[i] == type) {
            return (int)i;
        }
    }
    return -1;
}

int tr_accel_from_name(const char *name) {
    int i = find_name(accel_names, COUNT(accel_names), name);
    return i < 0 ? -1 : (int)accel_values[i];
}

const char *tr_accel_name(tr_accel_type type) {
    int i = accel_index(type);
    return i < 0 ? "unknown" : accel_names[i];
}

const char *tr_accel_description(tr_accel_type type) {
    int i = accel_index(type);
    return i < 0 ? NULL : accel_descriptions[i];
}

const char *const *tr_accel_names(size_t *count) {
    *count = COUNT(accel_names);
    return accel_names;
}

int tr_accel_available(tr_accel_type type) {
    if (accel_index(type) < 0) {
        return 0;
    }
#ifndef TRAC0R_HAVE_EMBREE
    if (type == TR_ACCEL_TYPE_EMBREE) {
        return 0; /* Embree is the one structure that needs a library at build time */
    }
#endif
    return 1;
}

void tr_names_join(char *buf, size_t size, const char *const *names, size_t count,
                   const char *last_sep) {
    if (size == 0) {
        return;
    }
    buf[0] = '\0';
    size_t used = 0;
    for (size_t i = 0; i < count && used < size; ++i) {
        const char *sep = i == 0 ? "" : (i + 1 == count && last_sep) ? last_sep : ", ";
        int n = snprintf(buf + used, size - used, "%s%s", sep, names[i]);
        if (n < 0) {
            break;
        }
        used += (size_t)n;
    }
}

int tr_names_parse_list(const char *list, int (*lookup)(const char *name), int *out, int max,
                        const char *what, const char *kind, const char *available, tr_error *err) {
    char name[64];
    int n = 0;
    const char *p = list ? list : "";
    const char *sep = available ? " (available: " : "";
    const char *end = available ? ")" : "";
    available = available ? available : "";
    do {
        const size_t len = strcspn(p, ",");
        int value = -1;
        if (len > 0 && len < sizeof name) {
            memcpy(name, p, len);
            name[len] = '\0';
            value = lookup(name);
        }
        if (len == 0) {
            tr_error_set(
                err, TR_STATUS_INVALID_ARGUMENT, "%s: '%.200s' %s%s%s%s", what, list ? list : "",
                *p || p == list ? "has an empty item" : "ends with a comma", sep, available, end);
            return -1;
        }
        if (value < 0) {
            tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "%s: unknown %s '%.*s' in '%.200s'%s%s%s",
                         what, kind, (int)(len < 64 ? len : 64), p, list, sep, available, end);
            return -1;
        }
        if (n == max) {
            tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "%s: more than %d items in '%.200s'",
                         what, max, list);
            return -1;
        }
        out[n++] = value;
        p += len;
    } while (*p++ == ',');
    return n;
}

/* Edit distance with adjacent transpositions (optimal string alignment: Damerau 1964,
 * "A technique for computer detection and correction of spelling errors"), capped:
 * strings longer than 31 bytes are "far". */
static int edit_distance(const char *a, const char *b) {
    size_t n = strlen(a), m = strlen(b);
    if (n > 31 || m > 31) {
        return 99;
    }
    int d[32][32];
    for (size_t i = 0; i <= n; ++i) {
        d[i][0] = (int)i;
    }
    for (size_t j = 0; j <= m; ++j) {
        d[0][j] = (int)j;
    }
    for (size_t i = 1; i <= n; ++i) {
        for (size_t j = 1; j <= m; ++j) {
            int best = d[i - 1][j - 1] + (a[i - 1] != b[j - 1]);
            if (d[i - 1][j] + 1 < best) {
                best = d[i - 1][j] + 1;
            }
            if (d[i][j - 1] + 1 < best) {
                best = d[i][j - 1] + 1;
            }
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] &&
                d[i - 2][j - 2] + 1 < best) {
                best = d[i - 2][j - 2] + 1;
            }
            d[i][j] = best;
        }
    }
    return d[n][m];
}

const char *tr_names_closest(const char *s, const char *const *names, size_t count) {
    const char *best = NULL;
    int best_d = 1 + (int)strlen(s) / 4;
    if (best_d > 3) {
        best_d = 3;
    }
    for (size_t i = 0; i < count; ++i) {
        int d = edit_distance(s, names[i]);
        if (d <= best_d && (!best || d < edit_distance(s, best))) {
            best = names[i];
        }
    }
    return best;
}
