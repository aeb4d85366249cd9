/* test_registry.c - the registries of material types, integrators and acceleration
 * structures (trac0r/registry.h, src/scene/material_registry.h).
 *
 * (a) Every name parses back to its value and every value prints as its name; names are
 *     unique; unknown names (case or spelling off, empty, NULL) are refused.
 * (b) The material types keep the thesis's numbers (listing 2), which the kernel's
 *     switches and scene files rely on; tr_material_check refuses numbers outside the
 *     list and accepts each type's neutral material.
 * (c) The scene loader follows the registry: for every type, a material with exactly its
 *     required keys loads as that type; leaving out a required key, adding a key that
 *     only another type takes, or an unknown type name fails. */
#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "scene/material_registry.h"
#include "trac0r/registry.h"
#include "trac0r/scene_file.h"
#include "trac0r/trac0r.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void names_unique(const char *const *names, size_t count, const char *what) {
    for (size_t i = 0; i < count; ++i) {
        for (size_t j = i + 1; j < count; ++j) {
            CHECK(strcmp(names[i], names[j]) != 0, "%s: '%s' twice", what, names[i]);
        }
    }
}

/* (a) + (b) */
static void round_trips(void) {
    static const char *const unknown[] = {"", "PT", "Naive", "bvh3", "glas", "pt ", "emitters"};
    size_t n;
    const char *const *names = tr_material_type_names(&n);
    CHECK(n == 5, "%zu material types", n);
    names_unique(names, n, "material types");
    for (size_t i = 0; i < n; ++i) {
        int t = tr_material_type_from_name(names[i]);
        CHECK(t > 0 && tr_material_type_name((uint32_t)t) &&
                  strcmp(tr_material_type_name((uint32_t)t), names[i]) == 0,
              "material '%s' -> %d", names[i], t);
        uint32_t req, opt;
        CHECK(tr_material_type_keys((uint32_t)t, &req, &opt) && req != 0u && (req & opt) == 0u,
              "material '%s': keys %x / %x", names[i], req, opt);
        tr_material m = tr_material_default((uint32_t)t);
        tr_error err;
        CHECK(tr_material_check(&m, &err) == TR_OK, "neutral %s refused: %s", names[i], err.msg);
    }
    /* The thesis's numbering. */
    CHECK(
        tr_material_type_from_name("emitter") == 1 && tr_material_type_from_name("diffuse") == 2 &&
            tr_material_type_from_name("glass") == 3 && tr_material_type_from_name("glossy") == 4 &&
            tr_material_type_from_name("principled") == 5,
        "material numbers");
    for (uint32_t t = 0; t < 8; ++t) {
        tr_material m = tr_material_default(t);
        tr_error err;
        int known = tr_material_type_name(t) != NULL;
        CHECK((tr_material_check(&m, &err) == TR_OK) == known && known == (t >= 1 && t <= 5),
              "type %u: known %d", t, known);
    }

    names = tr_integrator_names(&n);
    CHECK(n == 4, "%zu integrators", n);
    names_unique(names, n, "integrators");
    for (size_t i = 0; i < n; ++i) {
        int k = tr_integrator_from_name(names[i]);
        CHECK(k >= 0 && strcmp(tr_integrator_name(k), names[i]) == 0 &&
                  tr_integrator_description(k) && tr_integrator_description(k)[0],
              "integrator '%s' -> %d", names[i], k);
    }
    CHECK(tr_integrator_from_name("pt") == TR_INTEGRATOR_PT &&
              tr_integrator_from_name("naive") == TR_INTEGRATOR_NAIVE &&
              tr_integrator_from_name("bdpt") == TR_INTEGRATOR_BDPT &&
              tr_integrator_from_name("vcm") == TR_INTEGRATOR_VCM,
          "integrator values");
    CHECK(tr_integrator_name(7) == NULL && tr_integrator_description(-1) == NULL,
          "unknown integrator values have no name");

    names = tr_accel_names(&n);
    CHECK(n == 4, "%zu acceleration structures", n);
    names_unique(names, n, "accels");
    for (size_t i = 0; i < n; ++i) {
        int a = tr_accel_from_name(names[i]);
        CHECK(a >= 0 && strcmp(tr_accel_name((tr_accel_type)a), names[i]) == 0 &&
                  tr_accel_description((tr_accel_type)a),
              "accel '%s' -> %d", names[i], a);
    }
    CHECK(tr_accel_from_name("flat") == TR_ACCEL_TYPE_FLAT &&
              tr_accel_from_name("bvh") == TR_ACCEL_TYPE_BVH &&
              tr_accel_from_name("embree") == TR_ACCEL_TYPE_EMBREE &&
              tr_accel_from_name("bvh2") == TR_ACCEL_TYPE_BVH2,
          "accel values");
    CHECK(tr_accel_available(TR_ACCEL_TYPE_FLAT) && tr_accel_available(TR_ACCEL_TYPE_BVH) &&
              tr_accel_available(TR_ACCEL_TYPE_BVH2) && !tr_accel_available((tr_accel_type)9) &&
              strcmp(tr_accel_name((tr_accel_type)9), "unknown") == 0,
          "accel availability");

    for (size_t i = 0; i < sizeof unknown / sizeof unknown[0]; ++i) {
        CHECK(tr_material_type_from_name(unknown[i]) == -1 &&
                  tr_integrator_from_name(unknown[i]) == -1 && tr_accel_from_name(unknown[i]) == -1,
              "'%s' accepted", unknown[i]);
    }
    CHECK(tr_material_type_from_name(NULL) == -1 && tr_integrator_from_name(NULL) == -1 &&
              tr_accel_from_name(NULL) == -1,
          "NULL accepted");

    char buf[64];
    const char *const abc[] = {"a", "b", "c"};
    tr_names_join(buf, sizeof buf, abc, 3, " or ");
    CHECK(strcmp(buf, "a, b or c") == 0, "join: '%s'", buf);
    tr_names_join(buf, sizeof buf, abc, 3, NULL);
    CHECK(strcmp(buf, "a, b, c") == 0, "join: '%s'", buf);
    tr_names_join(buf, 4, abc, 3, NULL);
    CHECK(strlen(buf) == 3, "join truncates: '%s'", buf);

    /* "Did you mean": a near miss (a typo, a swap, a letter short) finds its name; a word
     * far from every name finds none. */
    const char *const opts[] = {"--width", "--height", "--spp", "--noise-threshold"};
    const char *near = tr_names_closest("--widht", opts, 4);
    CHECK(near && strcmp(near, "--width") == 0, "--widht: %s", near ? near : "(none)");
    near = tr_names_closest("--noise-treshold", opts, 4);
    CHECK(near && strcmp(near, "--noise-threshold") == 0, "--noise-treshold: %s",
          near ? near : "(none)");
    CHECK(tr_names_closest("--zzzzzz", opts, 4) == NULL && tr_names_closest("x", opts, 0) == NULL,
          "far words matched");

    /* Lists of names: every item kept in order, none cut, bad items refused. */
    int v[4];
    tr_error err;
    CHECK(tr_names_parse_list("pt,naive", tr_integrator_from_name, v, 4, "m", "integrator", NULL,
                              &err) == 2 &&
              v[0] == TR_INTEGRATOR_PT && v[1] == TR_INTEGRATOR_NAIVE,
          "list of two");
    const char *const bad[] = {"",   ",", "pt,", ",pt", "pt,,naive", "pt,nope", "pt,pt,pt,pt,pt",
                               " pt"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        err.code = TR_STATUS_OK;
        CHECK(tr_names_parse_list(bad[i], tr_integrator_from_name, v, 4, "m", "integrator", "x",
                                  &err) == -1 &&
                  err.code == TR_STATUS_INVALID_ARGUMENT,
              "list '%s' accepted", bad[i]);
    }
    /* A list longer than any buffer is read whole: its 200th item is checked too. */
    char longlist[1200] = "";
    for (int i = 0; i < 200; ++i) {
        strcat(longlist, i ? ",pt" : "pt");
    }
    int many[256];
    CHECK(tr_names_parse_list(longlist, tr_integrator_from_name, many, 256, "m", "integrator", NULL,
                              &err) == 200,
          "long list");
    strcat(longlist, "x");
    CHECK(tr_names_parse_list(longlist, tr_integrator_from_name, many, 256, "m", "integrator", NULL,
                              &err) == -1,
          "long list with a bad last item accepted");
}

/* The JSON value a scene file gives key k in this test. */
static const char *key_value(const tr_material_key_info *k) {
    switch (k->kind) {
    case TR_KEY_COLOR:
        return "[0.5, 0.5, 0.5]";
    case TR_KEY_FLAG:
        return "true";
    default:
        return k->lo >= 1.0 ? "1.5" : "0.5";
    }
}

/* Parses a one-material scene; returns the status and the material's type. */
static int parse_material(const char *type, const char *body, uint32_t *out_type) {
    char text[1024];
    snprintf(text, sizeof text,
             "{\"camera\": {\"position\": [0, 0, -2], \"look_at\": [0, 0, 0], \"fov\": 60},"
             " \"materials\": {\"lamp\": {\"type\": \"emitter\", \"color\": [1, 1, 1],"
             " \"emittance\": 5}, \"m\": {\"type\": \"%s\"%s}},"
             " \"shapes\": [{\"type\": \"plane\", \"material\": \"m\"},"
             " {\"type\": \"plane\", \"position\": [0, 1, 0], \"material\": \"lamp\"}]}",
             type, body);
    tr_scene s = {0};
    tr_scene_file f;
    tr_error err;
    int rc = tr_scene_file_parse(&s, "mem.json", text, strlen(text), NULL, &f, &err);
    *out_type = 0;
    if (rc == TR_OK) {
        *out_type = s.materials[1].type;
        tr_scene_clear(&s);
    }
    return rc;
}

/* Appends , "key": value for every key in mask (a name once) to body. */
static void add_keys(char *body, size_t size, uint32_t mask, uint32_t skip) {
    size_t nk;
    const tr_material_key_info *keys = tr_material_keys(&nk);
    for (size_t k = 0; k < nk; ++k) {
        if ((keys[k].key & mask) && !(keys[k].key & skip) &&
            !strstr(body, keys[k].name)) { /* "color" of two keys once */
            size_t used = strlen(body);
            snprintf(body + used, size - used, ", \"%s\": %s", keys[k].name, key_value(&keys[k]));
        }
    }
}

/* (c) */
static void scene_files(void) {
    size_t n, nk;
    const char *const *names = tr_material_type_names(&n);
    const tr_material_key_info *keys = tr_material_keys(&nk);
    int rejected_foreign = 0;
    for (size_t i = 0; i < n; ++i) {
        uint32_t t = (uint32_t)tr_material_type_from_name(names[i]), req, opt, got;
        tr_material_type_keys(t, &req, &opt);
        char body[512] = "";
        add_keys(body, sizeof body, req | opt, 0u);
        CHECK(parse_material(names[i], body, &got) == TR_OK && got == t,
              "%s with keys%s: not loaded as type %u (%u)", names[i], body, t, got);
        /* Every required key left out in turn. */
        for (size_t k = 0; k < nk; ++k) {
            if (!(keys[k].key & req)) {
                continue;
            }
            char less[512] = "";
            add_keys(less, sizeof less, req, keys[k].key);
            CHECK(parse_material(names[i], less, &got) != TR_OK, "%s without %s loaded", names[i],
                  keys[k].name);
        }
        /* A key another type takes and this one does not. */
        for (size_t k = 0; k < nk; ++k) {
            int own = 0;
            for (size_t j = 0; j < nk; ++j) {
                own |= (keys[j].key & (req | opt)) && strcmp(keys[j].name, keys[k].name) == 0;
            }
            if (own) {
                continue;
            }
            char more[512] = "";
            add_keys(more, sizeof more, req | opt, 0u);
            size_t used = strlen(more);
            snprintf(more + used, sizeof more - used, ", \"%s\": %s", keys[k].name,
                     key_value(&keys[k]));
            CHECK(parse_material(names[i], more, &got) != TR_OK, "%s with %s loaded", names[i],
                  keys[k].name);
            ++rejected_foreign;
        }
    }
    CHECK(rejected_foreign >= 8, "only %d foreign keys tried", rejected_foreign);
    uint32_t got;
    CHECK(parse_material("plastic", ", \"color\": [0.5, 0.5, 0.5]", &got) != TR_OK,
          "unknown material type loaded");
    CHECK(parse_material("Diffuse", ", \"color\": [0.5, 0.5, 0.5]", &got) != TR_OK,
          "material type names are case-sensitive");
}

/* The one-line description of the committed structure names it and its counts, and
 * stays inside a short buffer. */
static void describe_accel(void) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    CHECK(s && tr_scene_builtin(s, "cornell", 8, 8, &err) == TR_OK, "builtin: %s", err.msg);
    char buf[256], want[64];
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_scene_accel_describe(s, 1, buf, sizeof buf);
    CHECK(strncmp(buf, "bvh (", 5) == 0 && strstr(buf, "binary nodes"), "bvh: '%s'", buf);
    tr_scene_accel_describe(s, 0, buf, sizeof buf);
    CHECK(strncmp(buf, "bvh (", 5) == 0 && strstr(buf, "-wide") && !strstr(buf, "nodes"),
          "bvh, short: '%s'", buf);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_FLAT, &err) == TR_OK, "%s", err.msg);
    tr_scene_accel_describe(s, 1, buf, sizeof buf);
    snprintf(want, sizeof want, "flat (%u shape boxes)", tr_scene_shape_count(s));
    CHECK(strcmp(buf, want) == 0, "flat: '%s'", buf);
    tr_scene_accel_describe(s, 0, buf, sizeof buf);
    CHECK(strcmp(buf, "flat") == 0, "flat, short: '%s'", buf);
    memset(buf, 'x', sizeof buf);
    tr_scene_accel_describe(s, 1, buf, 6);
    CHECK(strcmp(buf, "flat ") == 0, "short buffer: '%.8s'", buf);

    /* The scene in words: its counts, the parts listed up to the limit, no render
     * defaults for a built-in scene. */
    tr_scene_file info;
    memset(&info, 0, sizeof info);
    CHECK(tr_scene_load(s, "builtin:cornell", NULL, &info, &err) == TR_OK, "%s", err.msg);
    char *text = tr_scene_describe(s, "builtin:cornell", &info, 2);
    snprintf(want, sizeof want, "triangles:  %u ", tr_scene_triangle_count(s));
    CHECK(text && strstr(text, want) != NULL, "no '%s' in: %s", want, text ? text : "(null)");
    snprintf(want, sizeof want, "part ...    %u more\n", tr_scene_shape_count(s) - 2);
    CHECK(text && strstr(text, want) && strstr(text, "part 1 ") && !strstr(text, "part 2 ") &&
              !strstr(text, "render:") && strstr(text, "warnings:   0\n"),
          "parts, render line or warnings: %s", text ? text : "(null)");
    free(text);
    tr_scene_destroy(s);
}

int main(void) {
    round_trips();
    scene_files();
    describe_accel();
    return check_finish("test_registry");
}
