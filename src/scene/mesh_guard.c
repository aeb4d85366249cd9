/* mesh_guard.c - Assimp's file access for trac0r: regular files, confined, sizes checked. */
#define _GNU_SOURCE /* realpath, pipe2 */
#include "scene/mesh_guard.h"

#include <assimp/cexport.h>
#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/scene.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "trac0r/parse.h"
#include "util/infile.h"

typedef struct guard_file guard_file;

typedef struct guard {
    const char *model; /* the path given */
    guard_file *open;  /* files Assimp has not closed yet */
    char model_real[PATH_MAX];
    char root[PATH_MAX];     /* the model's directory, resolved */
    char allowed[PATH_MAX];  /* TRAC0R_MODEL_ROOT resolved, or "" */
    unsigned long long read; /* bytes read so far */
    char reason[512];        /* the first refusal, "" for none */
} guard;

struct guard_file {
    FILE *fp;
    unsigned long long size;
    guard *g;
    struct aiFile *ai;
    guard_file *prev, *next;
};

static void refuse(guard *g, const char *fmt, const char *a, const char *b) {
    if (!g->reason[0]) {
        snprintf(g->reason, sizeof g->reason, fmt, a, b);
    }
}

/* `path` (resolved) lies in the tree under `dir` (resolved). */
static int under(const char *path, const char *dir) {
    size_t n = strlen(dir);
    if (n == 0) {
        return 0;
    }
    if (n == 1 && dir[0] == '/') {
        return 1;
    }
    return strncmp(path, dir, n) == 0 && (path[n] == '/' || path[n] == '\0');
}

static unsigned long long ply_type_size(const char *t) {
    static const struct {
        const char *name;
        unsigned size;
    } types[] = {{"char", 1},  {"int8", 1},    {"uchar", 1},  {"uint8", 1},
                 {"short", 2}, {"int16", 2},   {"ushort", 2}, {"uint16", 2},
                 {"int", 4},   {"int32", 4},   {"uint", 4},   {"uint32", 4},
                 {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
    for (size_t i = 0; i < sizeof types / sizeof types[0]; ++i) {
        if (strcmp(t, types[i].name) == 0) {
            return types[i].size;
        }
    }
    return 1;
}

/* A PLY header's elements need at least COUNT x (bytes per instance) after the header:
 * in binary the properties' sizes (a list its count alone), in ASCII two characters per
 * property (a digit and a separator), and never less than one byte per instance. */
static int check_ply(const char *name, const unsigned char *head, size_t n,
                     unsigned long long file_size, tr_error *err) {
    const char *end = NULL;
    for (size_t i = 0; i + 10 <= n; ++i) {
        if (memcmp(head + i, "end_header", 10) == 0) {
            end = (const char *)head + i;
            break;
        }
    }
    if (!end) {
        return TR_OK; /* no header in the first bytes read: Assimp's parser decides */
    }
    const char *p = (const char *)head, *stop = end;
    size_t header_len = (size_t)(end - p) + 10;
    int binary = 0;
    unsigned long long need = 0, count = 0, per = 0;
    int in_element = 0;
    while (p < stop) {
        const char *eol = memchr(p, '\n', (size_t)(stop - p));
        if (!eol) {
            eol = stop;
        }
        char line[256];
        size_t len = (size_t)(eol - p) < sizeof line - 1 ? (size_t)(eol - p) : sizeof line - 1;
        memcpy(line, p, len);
        line[len] = '\0';
        p = eol + 1;
        char w1[32] = "", w2[32] = "", w3[32] = "";
        int k = sscanf(line, "%31s %31s %31s", w1, w2, w3);
        if (k >= 2 && strcmp(w1, "format") == 0) {
            binary = strncmp(w2, "binary", 6) == 0;
        } else if (k >= 3 && strcmp(w1, "element") == 0) {
            if (in_element) {
                need += count * (per ? per : 1);
            }
            char *e;
            errno = 0;
            count = strtoull(w3, &e, 10);
            if (*e != '\0' || errno || w3[0] == '-' || count > file_size) {
                return tr_error_set(err, TR_STATUS_LIMIT,
                                    "'%.200s': PLY element '%s' claims %s instances in a file of "
                                    "%llu bytes",
                                    name, w2, w3, file_size);
            }
            per = 0;
            in_element = 1;
        } else if (k >= 2 && strcmp(w1, "property") == 0 && in_element) {
            if (strcmp(w2, "list") == 0) {
                per += binary ? ply_type_size(w3) : 2;
            } else {
                per += binary ? ply_type_size(w2) : 2;
            }
        }
        if (need > file_size) {
            break;
        }
    }
    if (in_element) {
        need += count * (per ? per : 1);
    }
    if (need > file_size - (header_len < file_size ? header_len : file_size)) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "'%.200s': the PLY header declares elements of at least %llu bytes, "
                            "but the file has %llu",
                            name, need, file_size);
    }
    return TR_OK;
}

static unsigned long long le32(const unsigned char *b) {
    return (unsigned long long)b[0] | (unsigned long long)b[1] << 8 |
           (unsigned long long)b[2] << 16 | (unsigned long long)b[3] << 24;
}

/* A binary glTF: a 12-byte header with the total length, then chunks of (length, type,
 * data). Every length must fit in the file. */
static int check_glb(const char *name, const unsigned char *head, size_t n,
                     unsigned long long file_size, tr_error *err) {
    if (n < 12) {
        return TR_OK;
    }
    unsigned long long total = le32(head + 8);
    if (total > file_size) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "'%.200s': the GLB header claims %llu bytes, the file has %llu", name,
                            total, file_size);
    }
    unsigned long long off = 12;
    for (int chunk = 0; chunk < 2 && off + 8 <= file_size && off + 8 <= n; ++chunk) {
        unsigned long long len = le32(head + off);
        if (len > file_size - off - 8) {
            return tr_error_set(err, TR_STATUS_LIMIT,
                                "'%.200s': GLB chunk %d claims %llu bytes, the file has %llu "
                                "after it",
                                name, chunk, len, file_size - off - 8);
        }
        off += 8 + len;
    }
    return TR_OK;
}

int tr_mesh_check_declared_sizes(const char *name, const unsigned char *head, size_t size,
                                 unsigned long long file_size, tr_error *err) {
    if (size >= 4 && memcmp(head, "glTF", 4) == 0) {
        return check_glb(name, head, size, file_size, err);
    }
    if (size >= 4 && memcmp(head, "ply", 3) == 0 && (head[3] == '\n' || head[3] == '\r')) {
        return check_ply(name, head, size, file_size, err);
    }
    return TR_OK;
}

static size_t g_read(struct aiFile *f, char *buf, size_t size, size_t count) {
    guard_file *gf = (guard_file *)f->UserData;
    if (size == 0 || count == 0) {
        return 0;
    }
    size_t got = fread(buf, size, count, gf->fp);
    gf->g->read += (unsigned long long)got * size;
    if (gf->g->read > TR_MESH_MAX_READ_BYTES) {
        refuse(gf->g, "'%.200s': the import read more than its budget of %s", gf->g->model,
               "1 GiB");
        return 0;
    }
    return got;
}

static size_t g_write(struct aiFile *f, const char *buf, size_t size, size_t count) {
    (void)f;
    (void)buf;
    (void)size;
    (void)count;
    return 0;
}

static size_t g_tell(struct aiFile *f) {
    long t = ftell(((guard_file *)f->UserData)->fp);
    return t < 0 ? 0 : (size_t)t;
}

static size_t g_size(struct aiFile *f) {
    return (size_t)((guard_file *)f->UserData)->size;
}

static enum aiReturn g_seek(struct aiFile *f, size_t off, enum aiOrigin origin) {
    int whence = origin == aiOrigin_SET ? SEEK_SET : origin == aiOrigin_CUR ? SEEK_CUR : SEEK_END;
    /* Assimp passes a negative offset from the end or the current position as size_t. */
    long o = off > (size_t)LONG_MAX ? -(long)(SIZE_MAX - off) - 1 : (long)off;
    return fseek(((guard_file *)f->UserData)->fp, o, whence) == 0 ? aiReturn_SUCCESS
                                                                  : aiReturn_FAILURE;
}

static void g_flush(struct aiFile *f) {
    (void)f;
}

static struct aiFile *g_open(struct aiFileIO *io, const char *name, const char *mode) {
    guard *g = (guard *)io->UserData;
    if (strchr(mode, 'w') || strchr(mode, 'a') || strchr(mode, '+')) {
        return NULL;
    }
    char real[PATH_MAX];
    if (!realpath(name, real)) {
        return NULL; /* missing: Assimp says so, or tries another name */
    }
    if (strcmp(real, g->model_real) != 0 && !under(real, g->root) && !under(real, g->allowed)) {
        refuse(g,
               "'%.200s' refers to '%.150s' outside its directory (set TRAC0R_MODEL_ROOT to a "
               "directory that holds both to allow it)",
               g->model, name);
        return NULL;
    }
    tr_error e;
    uint64_t size = 0;
    FILE *fp = tr_infile_open(name, &size, &e);
    if (!fp) {
        refuse(g, "%s%s", e.msg, "");
        return NULL;
    }
    unsigned char head[65536];
    size_t n = fread(head, 1, sizeof head, fp);
    if (tr_mesh_check_declared_sizes(name, head, n, size, &e) != TR_OK || fseek(fp, 0, SEEK_SET)) {
        refuse(g, "%s%s", e.msg, "");
        fclose(fp);
        return NULL;
    }
    guard_file *gf = malloc(sizeof *gf);
    struct aiFile *f = malloc(sizeof *f);
    if (!gf || !f) {
        free(gf);
        free(f);
        fclose(fp);
        return NULL;
    }
    gf->fp = fp;
    gf->size = size;
    gf->g = g;
    gf->ai = f;
    gf->prev = NULL;
    gf->next = g->open;
    if (g->open) {
        g->open->prev = gf;
    }
    g->open = gf;
    f->ReadProc = g_read;
    f->WriteProc = g_write;
    f->TellProc = g_tell;
    f->FileSizeProc = g_size;
    f->SeekProc = g_seek;
    f->FlushProc = g_flush;
    f->UserData = (aiUserData)gf;
    return f;
}

static void close_file(guard_file *gf) {
    guard *g = gf->g;
    if (gf->prev) {
        gf->prev->next = gf->next;
    } else {
        g->open = gf->next;
    }
    if (gf->next) {
        gf->next->prev = gf->prev;
    }
    fclose(gf->fp);
    free(gf->ai);
    free(gf);
}

static void g_close(struct aiFileIO *io, struct aiFile *f) {
    (void)io;
    if (f) {
        close_file((guard_file *)f->UserData);
    }
}

/* Assimp's message on one line. */
static void one_line(char *out, size_t n, const char *msg) {
    size_t j = 0;
    for (size_t i = 0; msg && msg[i] && j + 1 < n; ++i) {
        unsigned char ch = (unsigned char)msg[i];
        out[j++] = (ch == '\n' || ch == '\r' || ch == '\t') ? ' ' : (ch < 32 ? '?' : (char)ch);
    }
    while (j > 0 && out[j - 1] == ' ') {
        j--;
    }
    out[j] = '\0';
}

static const struct aiScene *import_here(const char *path, unsigned int flags, tr_error *err) {
    guard *g = calloc(1, sizeof *g);
    if (!g) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "'%.200s': out of memory", path);
        return NULL;
    }
    g->model = path;
    char dir[PATH_MAX];
    const char *slash = strrchr(path, '/');
    if (!slash) {
        snprintf(dir, sizeof dir, ".");
    } else if (slash == path) {
        snprintf(dir, sizeof dir, "/");
    } else {
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    }
    if (!realpath(dir, g->root) || !realpath(path, g->model_real)) {
        int e = errno;
        free(g);
        tr_error_set(err, tr_status_from_errno(e), "cannot open '%.200s': %s", path, strerror(e));
        return NULL;
    }
    const char *allow = getenv("TRAC0R_MODEL_ROOT");
    if (allow && allow[0] && !realpath(allow, g->allowed)) {
        g->allowed[0] = '\0';
    }
    struct aiFileIO io = {g_open, g_close, (aiUserData)g};
    const struct aiScene *ai = aiImportFileEx(path, flags, &io);
    /* Some of Assimp's importers throw past an open stream (the glTF importer on a buffer
     * longer than its file) and never close it: the import is over, so close them here. */
    while (g->open) {
        close_file(g->open);
    }
    /* A refusal fails the import even where Assimp went on without the file (an OBJ
     * whose material library is refused still loads, with default materials). */
    if (!ai || !ai->mRootNode || (ai->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || g->reason[0]) {
        if (g->reason[0]) {
            tr_error_set(err, TR_STATUS_LIMIT, "%s", g->reason);
        } else {
            char msg[300];
            one_line(msg, sizeof msg, aiGetErrorString());
            tr_error_set(err, TR_STATUS_PARSE, "Assimp cannot read '%.200s': %s", path,
                         msg[0] ? msg : "no meshes");
        }
        if (ai) {
            aiReleaseImport(ai);
        }
        free(g);
        return NULL;
    }
    free(g);
    return ai;
}

#if defined(__unix__) && !defined(__EMSCRIPTEN__) && !defined(TR_MESH_IMPORT_IN_PROCESS)
#define TR_MESH_TRIAL 1
/* Seconds of CPU time an import may take (TRAC0R_IMPORT_CPU_SECONDS), and of wall time
 * (twice that, at least 10: an import blocked on I/O spends none). */
static unsigned trial_cpu_seconds(void) {
    const char *e = getenv("TRAC0R_IMPORT_CPU_SECONDS");
    uint64_t v = 0;
    if (e && *e && tr_parse_uint64(e, 1, 86400, &v) == TR_OK) {
        return (unsigned)v;
    }
    return TR_MESH_IMPORT_CPU_SECONDS;
}

/* What the child sends back through its pipe: one byte, 'I' once the import has succeeded
 * (before the export, which can fail on its own: Assimp 5.2's scene copy asserts on some
 * glTF lights) or 'E' where it failed, then this header and `size` bytes: the scene in
 * Assimp's own binary form ("assbin", written by aiExportSceneToBlob) where code is TR_OK,
 * else the import's error message. size 0 with TR_OK: the scene could not be exported, so
 * the parent imports the file itself, as it does where the child ends after the 'I'. */
typedef struct trial_head {
    char magic[4]; /* "TRIM" */
    int32_t code;
    uint64_t size;
} trial_head;

static int write_all(int fd, const void *data, size_t n) {
    const char *p = data;
    while (n > 0) {
        const ssize_t w = write(fd, p, n);
        if (w < 0 && errno == EINTR) {
            continue;
        }
        if (w <= 0) {
            return -1;
        }
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

/* Whether Assimp 5.2's assbin round trip keeps what trac0r reads of this scene. It loses
 * the names embedded textures are found by (Collada's .zae, FBX and Half-Life MDL files
 * name theirs) and area lights' sizes: such scenes are imported again in the parent. */
static int assbin_keeps(const struct aiScene *ai) {
    if (ai->mNumTextures > 0) {
        return 0;
    }
    for (unsigned i = 0; i < ai->mNumLights; ++i) {
        if (ai->mLights[i] && ai->mLights[i]->mType == aiLightSource_AREA) {
            return 0;
        }
    }
    return 1;
}

/* The child: imports under its limits and sends the result. */
static void child_import(int fd, const char *path, unsigned int flags, unsigned cpu) {
    const struct rlimit cpu_limit = {cpu, cpu + 1};
    setrlimit(RLIMIT_CPU, &cpu_limit);
#if !defined(__SANITIZE_ADDRESS__)
    const struct rlimit as_limit = {TR_MESH_IMPORT_MAX_MEMORY, TR_MESH_IMPORT_MAX_MEMORY};
    setrlimit(RLIMIT_AS, &as_limit);
#endif
    tr_error e;
    const struct aiScene *ai = import_here(path, flags, &e);
    trial_head h = {{'T', 'R', 'I', 'M'}, TR_OK, 0};
    const void *body = NULL;
    if (write_all(fd, ai ? "I" : "E", 1) != 0) {
        _exit(3);
    }
    if (!ai) {
        h.code = e.code;
        h.size = strlen(e.msg);
        body = e.msg;
    } else {
        const int null = open("/dev/null", O_WRONLY);
        if (null >= 0) {
            dup2(null, 2); /* an assertion's text in the export is not the user's business */
        }
        const struct aiExportDataBlob *b =
            assbin_keeps(ai) ? aiExportSceneToBlob(ai, "assbin", 0) : NULL;
        if (b && !b->next) {
            h.size = b->size;
            body = b->data;
        }
    }
    const int ok = write_all(fd, &h, sizeof h) == 0 && write_all(fd, body, (size_t)h.size) == 0;
    _exit(ok ? 0 : 3); /* the scene and the blob are freed with the process */
}

/* The parent's side: the child's bytes, read as they come (a pipe holds 64 KiB) until it
 * closes the pipe and ends, within `wall` seconds and TR_MESH_IMPORT_MAX_MEMORY bytes. */
typedef struct trial_read {
    unsigned char *data;
    size_t n, cap;
    int status, eof, too_big, timed_out;
} trial_read;

static void read_child(int fd, pid_t pid, double wall, trial_read *r) {
    struct timespec t0, now;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    int exited = 0;
    while (!(exited && r->eof)) {
        if (!r->eof) {
            struct pollfd p = {fd, POLLIN, 0};
            if (poll(&p, 1, exited ? 0 : 5) > 0) {
                if (r->n == r->cap) {
                    const size_t cap = r->cap ? 2 * r->cap : 65536;
                    unsigned char *d =
                        cap <= TR_MESH_IMPORT_MAX_MEMORY ? realloc(r->data, cap) : NULL;
                    if (!d) {
                        r->too_big = 1;
                        break;
                    }
                    r->data = d;
                    r->cap = cap;
                }
                const ssize_t got = read(fd, r->data + r->n, r->cap - r->n);
                if (got > 0) {
                    r->n += (size_t)got;
                } else if (got == 0 || errno != EINTR) {
                    r->eof = 1;
                }
            } else if (exited) {
                r->eof = 1; /* nothing left, the writer gone */
            }
        }
        if (!exited) {
            const pid_t w = waitpid(pid, &r->status, WNOHANG);
            exited = w == pid || (w < 0 && errno != EINTR);
        }
        clock_gettime(CLOCK_MONOTONIC, &now);
        if (!exited &&
            (double)(now.tv_sec - t0.tv_sec) + 1e-9 * (double)(now.tv_nsec - t0.tv_nsec) > wall) {
            r->timed_out = 1;
            break;
        }
    }
    if (!exited) {
        kill(pid, SIGKILL);
        waitpid(pid, &r->status, 0);
    }
}

/* Imports the model in a forked child under limits on memory and CPU time: Assimp crashes
 * (Debian's 5.2.5 segfaults in its PLY parser) and loops for ever on inputs a fuzzer finds
 * in seconds, and none of that may take this process down. The child sends the imported
 * scene back in Assimp's binary form, which this process reads into its own scene
 * (aiImportFileFromMemory: a few milliseconds where the import itself took tens). *ai is
 * NULL where the child could not export (the file is then imported here). A process that
 * cannot fork or make a pipe imports in-process as before. */
static int import_in_child(const char *path, unsigned int flags, const struct aiScene **ai,
                           tr_error *err) {
    *ai = NULL;
    const unsigned cpu = trial_cpu_seconds();
    int fd[2];
    if (pipe2(fd, O_CLOEXEC) != 0) {
        return TR_OK;
    }
    const pid_t pid = fork();
    if (pid < 0) {
        close(fd[0]);
        close(fd[1]);
        return TR_OK;
    }
    if (pid == 0) {
        close(fd[0]);
        child_import(fd[1], path, flags, cpu);
    }
    close(fd[1]);
    const double wall = 2.0 * cpu > 10.0 ? 2.0 * cpu : 10.0;
    trial_read r;
    memset(&r, 0, sizeof r);
    read_child(fd[0], pid, wall, &r);
    close(fd[0]);
    int rc = TR_OK;
    trial_head h;
    const int imported = r.n >= 1 && r.data[0] == 'I';
    const int whole = r.n >= 1 + sizeof h && (memcpy(&h, r.data + 1, sizeof h), 1) &&
                      memcmp(h.magic, "TRIM", 4) == 0 && h.size == r.n - 1 - sizeof h;
    if (imported && !whole && !r.timed_out && !r.too_big) {
        /* The import succeeded and the export ended the child: import here (*ai NULL). */
    } else if (r.timed_out) {
        rc = tr_error_set(err, TR_STATUS_LIMIT,
                          "the importer did not finish '%.200s' within %.0f s", path, wall);
    } else if (r.too_big) {
        rc = tr_error_set(err, TR_STATUS_LIMIT, "the imported '%.200s' is larger than %llu bytes",
                          path, (unsigned long long)TR_MESH_IMPORT_MAX_MEMORY);
    } else if (WIFSIGNALED(r.status)) {
        const int sig = WTERMSIG(r.status);
        if (sig == SIGXCPU || sig == SIGKILL) {
            rc = tr_error_set(err, TR_STATUS_LIMIT,
                              "the importer ran past its CPU time limit (%u s, "
                              "TRAC0R_IMPORT_CPU_SECONDS) on '%.200s'",
                              cpu, path);
        } else {
            rc = tr_error_set(err, TR_STATUS_PARSE, "the importer crashed on '%.200s': signal %d",
                              path, sig);
        }
    } else if (!WIFEXITED(r.status) || WEXITSTATUS(r.status) != 0 || !whole) {
        rc = tr_error_set(err, TR_STATUS_LIMIT,
                          "the importer failed on '%.200s' (status %d: out of its memory "
                          "limit?)",
                          path, WIFEXITED(r.status) ? WEXITSTATUS(r.status) : -1);
    } else if (h.code != TR_OK) {
        /* The child's own message: its status is one of the library's (a bad file). */
        const int code = h.code > 0 && h.code < 64 ? h.code : TR_STATUS_PARSE;
        rc = tr_error_set(err, (tr_status)code, "%.*s", (int)(h.size < 400 ? h.size : 400),
                          (const char *)r.data + 1 + sizeof h);
    } else if (h.size > 0 && h.size <= UINT_MAX) { /* else import here */
        *ai = aiImportFileFromMemory((const char *)r.data + 1 + sizeof h, (unsigned int)h.size, 0,
                                     "assbin");
        if (!*ai) {
            rc = tr_error_set(err, TR_STATUS_PARSE,
                              "'%.200s': the importer's result could not be read back", path);
        }
    }
    free(r.data);
    return rc;
}
#endif

const struct aiScene *tr_mesh_guarded_import(const char *path, unsigned int flags, tr_error *err) {
#ifdef TR_MESH_TRIAL
    const struct aiScene *ai = NULL;
    if (import_in_child(path, flags, &ai, err) != TR_OK) {
        return NULL;
    }
    if (ai) {
        return ai;
    }
#endif
    return import_here(path, flags, err);
}

int tr_mesh_check_confined(const char *model_dir, const char *file, tr_error *err) {
    char root[PATH_MAX], real[PATH_MAX], allowed[PATH_MAX] = "";
    if (!realpath(model_dir[0] ? model_dir : ".", root) || !realpath(file, real)) {
        const int e = errno;
        return tr_error_set(err, tr_status_from_errno(e), "cannot open '%.200s': %s", file,
                            strerror(e));
    }
    const char *allow = getenv("TRAC0R_MODEL_ROOT");
    if (allow && allow[0] && !realpath(allow, allowed)) {
        allowed[0] = '\0';
    }
    if (!under(real, root) && !under(real, allowed)) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "'%.150s' lies outside the model's directory (set TRAC0R_MODEL_ROOT "
                            "to a directory that holds both to allow it)",
                            file);
    }
    return TR_OK;
}
