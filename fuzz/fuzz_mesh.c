/* fuzz_mesh.c - libFuzzer target for the mesh import path (src/scene/mesh.c through
 * src/scene/mesh_guard.c into Assimp).
 *
 * The first byte picks the file type (OBJ, PLY, glTF, GLB, STL, OFF), the rest is the
 * file: it is written to a private directory and imported with a small triangle budget.
 * The declared-size check also runs on the bytes directly, where it cannot be masked by
 * Assimp refusing the file first. Assimp itself is not instrumented; what is checked is
 * that trac0r's side never crashes, leaks or hangs, that a failed import leaves the scene
 * as it was, and that the guard keeps Assimp's memory within -rss_limit_mb.
 * Built by fuzz/build.sh; run by fuzz/run.sh.
 *
 * Built with -DTR_FUZZ_GUARD_ONLY (fuzz_mesh_guard, what CI runs) it stops after the
 * declared-size check: Debian's Assimp 5.2.5 crashes (SEGV in its PLY parser) and hangs on
 * inputs this target finds within seconds, which no check of ours short of a parser of
 * each format can keep from it; the full target stays for finding such inputs by hand
 * (fuzz/run.sh with TRAC0R_FUZZ_ASSIMP=1). */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "scene/mesh_guard.h"
#include "scene/scene_internal.h"
#include "trac0r/scene_file.h"

static char dir[64];

/* The private directory goes when libFuzzer exits. */
static void remove_dir(void) {
    static const char *const names[] = {"model.obj", "model.ply", "model.gltf", "model.glb",
                                        "model.stl", "model.off", "image.png",  "image.pfm"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i) {
        char p[128];
        snprintf(p, sizeof p, "%s/%s", dir, names[i]);
        unlink(p);
    }
    rmdir(dir);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static const char *const ext[] = {"obj", "ply", "gltf", "glb", "stl", "off"};
    if (size < 1) {
        return 0;
    }
    if (!dir[0]) {
        snprintf(dir, sizeof dir, "/tmp/trac0r-fuzz-mesh-%ld", (long)getpid());
        if (mkdir(dir, 0700) != 0 && errno != EEXIST) {
            abort();
        }
        atexit(remove_dir);
    }
    tr_error err;
    tr_mesh_check_declared_sizes("fuzz", data + 1, size - 1, size - 1, &err);
#ifdef TR_FUZZ_GUARD_ONLY
    return 0;
#endif
    char path[128];
    snprintf(path, sizeof path, "%s/model.%s", dir, ext[data[0] % 6]);
    FILE *fp = fopen(path, "wb");
    if (!fp || fwrite(data + 1, 1, size - 1, fp) != size - 1 || fclose(fp) != 0) {
        abort();
    }
    tr_scene s = {0};
    tr_mesh_import_stats st;
    if (tr_scene_import_mesh(&s, path, NULL, -1, 20000, &st, &err) == TR_OK) {
        if (s.triangle_count != st.triangles || st.triangles == 0 || st.triangles > 20000) {
            abort();
        }
        for (uint32_t i = 0; i < s.triangle_count; ++i) {
            if (s.triangles[i].material >= s.material_count) {
                abort();
            }
        }
    } else if (s.triangle_count || s.shape_count || s.material_count) {
        abort(); /* a failed import adds nothing */
    }
    tr_scene_clear(&s);
    return 0;
}
