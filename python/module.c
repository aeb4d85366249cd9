/* module.c - `import trac0r`: the CPython extension module (docs/python.md).
 *
 * A thin binding of the public API (include/trac0r/): scenes (tr_scene_file_*), offline
 * renders (tr_session), the real-time loop (tr_realtime), the image writers and readers,
 * the metrics and the tonemapper. Nothing here renders or filters by itself.
 *
 * Images reach NumPy without a copy where the library's buffer can be handed over: a
 * render's film becomes the arrays' memory (its sums are turned into means in place, as
 * tr_film_pixel computes them, bit for bit), kept alive by an owner object that is every
 * array's base. The GIL is released while the library works; the session's progress
 * callback takes it back after every pass to run Python's signal handlers (Ctrl-C
 * cancels the render and raises KeyboardInterrupt) and the caller's callback. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <structmember.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "trac0r/trac0r.h"

/* ---- errors --------------------------------------------------------------------- */

static PyObject *tr_py_error;                       /* trac0r.Error */
static PyObject *tr_py_status_exc[TR_STATUS_COUNT]; /* one subclass per tr_status */

typedef struct status_exc_def {
    tr_status code;
    const char *name; /* trac0r.NAME */
    int builtin;      /* 0: none, 1: ValueError, 2: MemoryError, 3: LookupError */
} status_exc_def;

static const status_exc_def status_excs[] = {
    {TR_STATUS_INVALID_ARGUMENT, "InvalidArgumentError", 1},
    {TR_STATUS_INVALID_OPERATION, "InvalidOperationError", 0},
    {TR_STATUS_OUT_OF_MEMORY, "OutOfMemoryError", 2},
    {TR_STATUS_LIMIT, "LimitError", 1},
    {TR_STATUS_NOT_FOUND, "NotFoundError", 3},
    {TR_STATUS_IO, "FileError", 0},
    {TR_STATUS_PARSE, "ParseError", 1},
    {TR_STATUS_UNSUPPORTED, "UnsupportedError", 0},
    {TR_STATUS_STALE_SCENE, "StaleSceneError", 0},
    {TR_STATUS_CANCELLED, "CancelledError", 0},
    {TR_STATUS_DEVICE, "DeviceError", 0},
};

/* Raises the exception of err's status, carrying .status (the tr_status code),
 * .status_name ("TR_STATUS_IO") and the library's message; returns NULL. */
static PyObject *raise_tr(const tr_error *err) {
    const tr_status code = err->code > 0 && err->code < TR_STATUS_COUNT ? err->code : 0;
    PyObject *type = code && tr_py_status_exc[code] ? tr_py_status_exc[code] : tr_py_error;
    PyObject *inst = PyObject_CallFunction(type, "s", err->msg);
    if (!inst) {
        return NULL;
    }
    PyObject *num = PyLong_FromLong((long)err->code);
    PyObject *name = PyUnicode_FromString(tr_status_name(err->code));
    if (num && name) {
        PyObject_SetAttrString(inst, "status", num);
        PyObject_SetAttrString(inst, "status_name", name);
    }
    Py_XDECREF(num);
    Py_XDECREF(name);
    PyErr_SetObject(type, inst);
    Py_DECREF(inst);
    return NULL;
}

/* The same for a failure the module finds itself (status and message of its own). */
static PyObject *raise_status(tr_status code, const char *fmt, ...) {
    tr_error err;
    err.code = code;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err.msg, sizeof err.msg, fmt, ap);
    va_end(ap);
    return raise_tr(&err);
}

/* ---- argument helpers ----------------------------------------------------------- */

/* An integer argument in lo..hi (None: keep *out); TypeError / ValueError name it. */
static int arg_long(PyObject *o, const char *name, long long lo, long long hi, long long *out) {
    if (!o || o == Py_None) {
        return 0;
    }
    if (PyBool_Check(o) || !PyLong_Check(o)) {
        PyErr_Format(PyExc_TypeError, "%s: expected an integer, got %s", name, Py_TYPE(o)->tp_name);
        return -1;
    }
    int overflow = 0;
    long long v = PyLong_AsLongLongAndOverflow(o, &overflow);
    if (v == -1 && PyErr_Occurred()) {
        return -1;
    }
    if (overflow || v < lo || v > hi) {
        PyErr_Format(PyExc_ValueError, "%s: expected an integer in %lld..%lld, got %R", name, lo,
                     hi, o);
        return -1;
    }
    *out = v;
    return 0;
}

static int arg_u32(PyObject *o, const char *name, uint32_t lo, uint32_t hi, uint32_t *out) {
    long long v = *out;
    if (arg_long(o, name, lo, hi, &v) < 0) {
        return -1;
    }
    *out = (uint32_t)v;
    return 0;
}

static int arg_int(PyObject *o, const char *name, int lo, int hi, int *out) {
    long long v = *out;
    if (arg_long(o, name, lo, hi, &v) < 0) {
        return -1;
    }
    *out = (int)v;
    return 0;
}

/* A 64-bit seed, 0..2^64-1. */
static int arg_seed(PyObject *o, uint64_t *out) {
    if (!o || o == Py_None) {
        return 0;
    }
    if (PyBool_Check(o) || !PyLong_Check(o)) {
        PyErr_Format(PyExc_TypeError, "seed: expected an integer, got %s", Py_TYPE(o)->tp_name);
        return -1;
    }
    unsigned long long v = PyLong_AsUnsignedLongLong(o);
    if (v == (unsigned long long)-1 && PyErr_Occurred()) {
        PyErr_Clear();
        PyErr_Format(PyExc_ValueError, "seed: expected an integer in 0..2^64-1, got %R", o);
        return -1;
    }
    *out = (uint64_t)v;
    return 0;
}

/* A finite number in lo..hi (None: keep *out). */
static int arg_double(PyObject *o, const char *name, double lo, double hi, double *out) {
    if (!o || o == Py_None) {
        return 0;
    }
    if (PyBool_Check(o) || !(PyFloat_Check(o) || PyLong_Check(o))) {
        PyErr_Format(PyExc_TypeError, "%s: expected a number, got %s", name, Py_TYPE(o)->tp_name);
        return -1;
    }
    double v = PyFloat_AsDouble(o);
    if (v == -1.0 && PyErr_Occurred()) {
        return -1;
    }
    if (!isfinite(v) || v < lo || v > hi) {
        PyErr_Format(PyExc_ValueError, "%s: expected a number in %g..%g, got %R", name, lo, hi, o);
        return -1;
    }
    *out = v;
    return 0;
}

/* A str argument (None: *out stays). The pointer lives as long as o. */
static int arg_str(PyObject *o, const char *name, const char **out) {
    if (!o || o == Py_None) {
        return 0;
    }
    if (!PyUnicode_Check(o)) {
        PyErr_Format(PyExc_TypeError, "%s: expected a str, got %s", name, Py_TYPE(o)->tp_name);
        return -1;
    }
    const char *s = PyUnicode_AsUTF8(o);
    if (!s) {
        return -1;
    }
    *out = s;
    return 0;
}

/* A path (str, bytes or os.PathLike) as a new bytes object; NULL with TypeError. */
static PyObject *arg_path(PyObject *o, const char *name) {
    PyObject *b = NULL;
    if (!o || !PyUnicode_FSConverter(o, &b)) {
        PyErr_Clear();
        PyErr_Format(PyExc_TypeError, "%s: expected a path (str or os.PathLike), got %s", name,
                     o ? Py_TYPE(o)->tp_name : "nothing");
        return NULL;
    }
    return b;
}

static int arg_integrator(PyObject *o, int *out) {
    const char *name = NULL;
    if (arg_str(o, "integrator", &name) < 0) {
        return -1;
    }
    if (!name) {
        return 0;
    }
    int k = tr_integrator_from_name(name);
    if (k < 0) {
        char names[160];
        size_t count;
        const char *const *list = tr_integrator_names(&count);
        tr_names_join(names, sizeof names, list, count, NULL);
        PyErr_Format(PyExc_ValueError, "integrator: unknown integrator '%s' (available: %s)", name,
                     names);
        return -1;
    }
    *out = k;
    return 0;
}

static int arg_sampler(PyObject *o, int *out) {
    const char *name = NULL;
    if (arg_str(o, "sampler", &name) < 0) {
        return -1;
    }
    if (!name) {
        return 0;
    }
    if (strcmp(name, "sobol") == 0) {
        *out = TR_SAMPLER_SOBOL;
    } else if (strcmp(name, "random") == 0) {
        *out = TR_SAMPLER_RANDOM;
    } else if (strcmp(name, "zsobol") == 0) {
        *out = TR_SAMPLER_ZSOBOL;
    } else {
        PyErr_Format(PyExc_ValueError,
                     "sampler: unknown sampler '%s' (available: sobol, random, "
                     "zsobol)",
                     name);
        return -1;
    }
    return 0;
}

/* "cpu", "opencl" (device 0) or "opencl:N", as the command's --device. */
static int arg_device(PyObject *o, char *out, size_t size) {
    const char *name = "cpu";
    if (arg_str(o, "device", &name) < 0) {
        return -1;
    }
    if (strcmp(name, "cpu") != 0 && strcmp(name, "opencl") != 0 &&
        strncmp(name, "opencl:", 7) != 0) {
        PyErr_Format(PyExc_ValueError,
                     "device: unknown device '%s' (expected cpu, opencl or opencl:N)", name);
        return -1;
    }
    snprintf(out, size, "%s", strcmp(name, "opencl") == 0 ? "opencl:0" : name);
    return 0;
}

/* The TR_PASS_* bit of a pass name; 0 for none. */
static uint32_t pass_bit(const char *name) {
    for (uint32_t bit = 1u; bit != 0u && bit <= (1u << 16); bit <<= 1) {
        const char *n = tr_pass_name(bit);
        if (n && strcmp(n, name) == 0) {
            return bit;
        }
    }
    return 0u;
}

/* passes=: a str or an iterable of str naming passes ("all": the command's five). */
static int arg_passes(PyObject *o, uint32_t *out) {
    *out = 0u;
    if (!o || o == Py_None) {
        return 0;
    }
    PyObject *seq = PyUnicode_Check(o) ? PyTuple_Pack(1, o) : PySequence_Fast(o, "");
    if (!seq) {
        PyErr_Clear();
        PyErr_Format(PyExc_TypeError, "passes: expected a str or a list of str, got %s",
                     Py_TYPE(o)->tp_name);
        return -1;
    }
    const Py_ssize_t n = PySequence_Fast_GET_SIZE(seq);
    for (Py_ssize_t i = 0; i < n; ++i) {
        const char *name = NULL;
        PyObject *item = PySequence_Fast_GET_ITEM(seq, i);
        if (arg_str(item, "passes", &name) < 0 || !name) {
            if (!PyErr_Occurred()) {
                PyErr_SetString(PyExc_TypeError, "passes: expected a str, got None");
            }
            Py_DECREF(seq);
            return -1;
        }
        const uint32_t bit =
            strcmp(name, "all") == 0 ? TR_PASS_ALL | TR_PASS_VARIANCE : pass_bit(name);
        if (!bit) {
            PyErr_Format(PyExc_ValueError,
                         "passes: unknown pass '%s' (available: albedo, normal, depth, id, "
                         "variance, direct, emission, all)",
                         name);
            Py_DECREF(seq);
            return -1;
        }
        *out |= bit;
    }
    Py_DECREF(seq);
    return 0;
}

/* ---- owners: the objects that keep arrays' memory alive ------------------------- */

/* What an array's memory belongs to: a session's film (with the session, its device and
 * the scene), a film of the module's own, or plain memory (an image read from a file).
 * Every array made from it has it as its base. */
typedef struct {
    PyObject_HEAD tr_session *session;
    tr_device *dev;
    PyObject *scene; /* keeps the scene (and its tr_scene) alive */
    tr_film film;    /* the film the arrays show (a session's, or owned: film_owned) */
    int film_owned;
    tr_film den; /* a denoised image, owned when den.sum is set */
    float *mem;  /* owned */
} OwnerObject;

static void scene_release_user(PyObject *scene);

static void owner_dealloc(OwnerObject *o) {
    tr_session_destroy(o->session);
    tr_device_destroy(o->dev);
    if (o->film_owned) {
        tr_film_free(&o->film);
    }
    if (o->den.sum) {
        tr_film_free(&o->den);
    }
    free(o->mem);
    if (o->scene) {
        scene_release_user(o->scene);
        Py_DECREF(o->scene);
    }
    Py_TYPE(o)->tp_free((PyObject *)o);
}

/* The addresses of the memory the owner holds, by the film's array names (and "image"
 * for a denoised or read image): what a test checks an array's data pointer against. */
static PyObject *owner_get_buffers(OwnerObject *o, void *unused) {
    (void)unused;
    static const char *names[TR_FILM_ARRAYS] = {"sum", "count",    "albedo", "normal",  "depth",
                                                "id",  "variance", "direct", "emission"};
    PyObject *d = PyDict_New();
    for (int i = 0; d && i < TR_FILM_ARRAYS; ++i) {
        void *p = o->film.count ? tr_film_array_data(&o->film, i) : NULL;
        PyObject *v = p ? PyLong_FromVoidPtr(p) : NULL;
        if (p && (!v || PyDict_SetItemString(d, names[i], v) < 0)) {
            Py_XDECREF(v);
            Py_CLEAR(d);
        }
        Py_XDECREF(v);
    }
    void *image = o->den.sum ? (void *)o->den.sum : (void *)o->mem;
    PyObject *v = image && d ? PyLong_FromVoidPtr(image) : NULL;
    if (v && PyDict_SetItemString(d, "image", v) < 0) {
        Py_CLEAR(d);
    }
    Py_XDECREF(v);
    return d;
}

static PyGetSetDef owner_getset[] = {
    {"buffers", (getter)owner_get_buffers, NULL,
     "The addresses of the library's buffers this owner keeps (by array name).", NULL},
    {NULL, NULL, NULL, NULL, NULL}};

static PyTypeObject OwnerType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "trac0r._Owner",
    .tp_basicsize = sizeof(OwnerObject),
    .tp_dealloc = (destructor)owner_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "The memory of arrays the module returns (their base).",
    .tp_getset = owner_getset,
};

static OwnerObject *owner_new(void) {
    OwnerObject *o = PyObject_New(OwnerObject, &OwnerType);
    if (o) {
        o->session = NULL;
        o->dev = NULL;
        o->scene = NULL;
        memset(&o->film, 0, sizeof o->film);
        o->film_owned = 0;
        memset(&o->den, 0, sizeof o->den);
        o->mem = NULL;
    }
    return o;
}

/* An array over `data` (no copy), height x width x channels of `type`, whose base is o. */
static PyObject *owner_array(OwnerObject *o, void *data, uint32_t height, uint32_t width,
                             int channels, int type) {
    npy_intp dims[3] = {(npy_intp)height, (npy_intp)width, (npy_intp)channels};
    PyObject *arr = PyArray_SimpleNewFromData(3, dims, type, data);
    if (!arr) {
        return NULL;
    }
    Py_INCREF(o);
    if (PyArray_SetBaseObject((PyArrayObject *)arr, (PyObject *)o) < 0) {
        Py_DECREF(arr);
        return NULL;
    }
    return arr;
}

/* Turns a film's sums into means in place, pixel by pixel as tr_film_pixel and
 * tr_film_pass_pixel compute them (so the arrays equal the library's images and the
 * command's files bit for bit); the variance pass from the sums before that. The film
 * accumulates nothing afterwards. */
static void film_to_means(tr_film *f) {
    const size_t n = (size_t)f->width * f->height;
    if (f->sq) {
        for (size_t i = 0; i < n; ++i) {
            for (int c = 0; c < 3; ++c) {
                f->sq[3 * i + (size_t)c] = tr_film_variance(f, i, c);
            }
        }
    }
    float *three[] = {f->sum, f->albedo, f->normal, f->direct, f->emission};
    for (size_t i = 0; i < n; ++i) {
        const uint32_t c = f->count[i];
        const float inv = c ? 1.0f / (float)c : 0.0f;
        for (size_t a = 0; a < sizeof three / sizeof *three; ++a) {
            if (three[a]) {
                for (size_t k = 3 * i; k < 3 * i + 3; ++k) {
                    three[a][k] = c ? three[a][k] * inv : 0.0f;
                }
            }
        }
        if (f->depth) {
            f->depth[i] = c ? f->depth[i] * inv : 0.0f;
        }
    }
}

/* A copy of a film (every array it keeps) into dst, allocated here. */
static int film_copy(tr_film *dst, const tr_film *src, tr_error *err) {
    if (tr_film_init_passes(dst, src->width, src->height, src->passes, err) != TR_OK) {
        return TR_ERR;
    }
    const size_t n = (size_t)src->width * src->height;
    for (int i = 0; i < TR_FILM_ARRAYS; ++i) {
        void *d = tr_film_array_data(dst, i);
        const void *s = tr_film_array_data(src, i);
        if (d && s) {
            memcpy(d, s, n * tr_film_array_pixel_bytes(i));
        }
    }
    return TR_OK;
}

/* ---- result types ---------------------------------------------------------------- */

static PyTypeObject ResultType, FrameType, MetricsType, ProgressType;

static PyStructSequence_Field result_fields[] = {
    {"image", "the mean radiance, float32 (height, width, 3), linear RGB"},
    {"passes", "dict: pass name -> array (depth (h, w, 1); id uint32 (h, w, 1); others 3)"},
    {"spp", "samples per pixel the render reached"},
    {"seconds", "wall time of the render"},
    {"rays", "intersection queries made"},
    {"end", "why it ended: done, converged, time_limit, cancelled, paused"},
    {NULL, NULL}};
static PyStructSequence_Desc result_desc = {"trac0r.Result", "An offline render's outcome.",
                                            result_fields, 6};

static PyStructSequence_Field frame_fields[] = {
    {"image", "the frame to show, float32 (height, width, 3)"},
    {"render_ms", "the sampling stage"},
    {"temporal_ms", "the temporal stage, the emission's resolve included"},
    {"spatial_ms", "the spatial filter"},
    {"resolve_ms", "the emission's resolve on the host"},
    {"spp", "samples per pixel in the film"},
    {"frame_spp", "samples per pixel this frame traced"},
    {"scale", "the full resolution's width over this frame's"},
    {"method", "the reconstruction that ran"},
    {NULL, NULL}};
static PyStructSequence_Desc frame_desc = {"trac0r.Frame", "A real-time frame and its timings.",
                                           frame_fields, 9};

static PyStructSequence_Field metrics_fields[] = {
    {"psnr", "dB, peak 1 (inf for identical images)"},
    {"mse", "mean squared error"},
    {"rmse", "root mean squared error"},
    {"relmse", "relative MSE, (a - ref)^2 / (ref^2 + 0.01)"},
    {"ssim", "structural similarity of the luminance"},
    {"max_error", "the largest per-pixel error"},
    {NULL, NULL}};
static PyStructSequence_Desc metrics_desc = {
    "trac0r.Metrics", "Errors of an image against a reference (values clamped to [0, 1]).",
    metrics_fields, 6};

static PyStructSequence_Field progress_fields[] = {
    {"samples", "passes made"},
    {"spp", "the most a pixel gets"},
    {"tiles", "adaptive tiles"},
    {"tiles_done", "of them converged or finished"},
    {"seconds", "wall time of the run"},
    {"rays", "intersection queries made"},
    {"end", "why the run ended (None while running)"},
    {NULL, NULL}};
static PyStructSequence_Desc progress_desc = {"trac0r.Progress", "Where a render stands.",
                                              progress_fields, 7};

static const char *end_name(tr_session_end e, int paused) {
    if (paused && e == TR_SESSION_CANCELLED) {
        return "paused";
    }
    switch (e) {
    case TR_SESSION_DONE:
        return "done";
    case TR_SESSION_CONVERGED:
        return "converged";
    case TR_SESSION_TIME_LIMIT:
        return "time_limit";
    case TR_SESSION_CANCELLED:
        return "cancelled";
    default:
        return NULL;
    }
}

static PyObject *progress_new(const tr_session_progress *p, int paused) {
    PyObject *r = PyStructSequence_New(&ProgressType);
    if (!r) {
        return NULL;
    }
    const char *end = end_name(p->end, paused);
    PyStructSequence_SET_ITEM(r, 0, PyLong_FromUnsignedLong(p->samples));
    PyStructSequence_SET_ITEM(r, 1, PyLong_FromUnsignedLong(p->spp));
    PyStructSequence_SET_ITEM(r, 2, PyLong_FromUnsignedLong(p->tiles));
    PyStructSequence_SET_ITEM(r, 3, PyLong_FromUnsignedLong(p->tiles_done));
    PyStructSequence_SET_ITEM(r, 4, PyFloat_FromDouble(p->seconds));
    PyStructSequence_SET_ITEM(r, 5, PyLong_FromUnsignedLongLong(p->rays));
    PyStructSequence_SET_ITEM(r, 6, end ? PyUnicode_FromString(end) : Py_NewRef(Py_None));
    for (Py_ssize_t i = 0; i < 7; ++i) {
        if (!PyStructSequence_GET_ITEM(r, i)) {
            Py_DECREF(r);
            return NULL;
        }
    }
    return r;
}

/* A Result over o's film (means already): the image (den's where o holds one) and the
 * passes in `passes` as views of o's memory. */
static PyObject *result_new(OwnerObject *o, uint32_t passes, const tr_session_progress *p,
                            int paused) {
    const tr_film *f = &o->film;
    const tr_film *img = o->den.sum ? &o->den : f;
    PyObject *image = owner_array(o, img->sum, img->height, img->width, 3, NPY_FLOAT32);
    PyObject *dict = PyDict_New();
    PyObject *r = PyStructSequence_New(&ResultType);
    if (!image || !dict || !r) {
        goto fail;
    }
    for (uint32_t bit = 1u; bit <= TR_PASS_EMISSION && bit != 0u; bit <<= 1) {
        if (!(passes & bit) || !(f->passes & bit)) {
            continue;
        }
        PyObject *arr = NULL;
        if (bit == TR_PASS_DEPTH) {
            arr = owner_array(o, f->depth, f->height, f->width, 1, NPY_FLOAT32);
        } else if (bit == TR_PASS_PRIM) {
            arr = owner_array(o, f->prim, f->height, f->width, 1, NPY_UINT32);
        } else {
            float *data = bit == TR_PASS_ALBEDO     ? f->albedo
                          : bit == TR_PASS_NORMAL   ? f->normal
                          : bit == TR_PASS_VARIANCE ? f->sq
                          : bit == TR_PASS_DIRECT   ? f->direct
                                                    : f->emission;
            arr = owner_array(o, data, f->height, f->width, 3, NPY_FLOAT32);
        }
        if (!arr || PyDict_SetItemString(dict, tr_pass_name(bit), arr) < 0) {
            Py_XDECREF(arr);
            goto fail;
        }
        Py_DECREF(arr);
    }
    const char *end = end_name(p->end, paused);
    PyStructSequence_SET_ITEM(r, 0, image);
    PyStructSequence_SET_ITEM(r, 1, dict);
    PyStructSequence_SET_ITEM(r, 2, PyLong_FromUnsignedLong(p->samples));
    PyStructSequence_SET_ITEM(r, 3, PyFloat_FromDouble(p->seconds));
    PyStructSequence_SET_ITEM(r, 4, PyLong_FromUnsignedLongLong(p->rays));
    PyStructSequence_SET_ITEM(r, 5, end ? PyUnicode_FromString(end) : Py_NewRef(Py_None));
    for (Py_ssize_t i = 2; i < 6; ++i) {
        if (!PyStructSequence_GET_ITEM(r, i)) {
            Py_DECREF(r);
            return NULL;
        }
    }
    return r;
fail:
    Py_XDECREF(image);
    Py_XDECREF(dict);
    Py_XDECREF(r);
    return NULL;
}

/* ---- Scene ---------------------------------------------------------------------- */

typedef struct {
    PyObject_HEAD tr_scene *scene;
    int closed;
    int users; /* sessions, real-time loops and results that hold the scene */
    int busy;  /* renders running now (the camera may not change) */
    uint32_t spp;
    int integrator;
    int max_depth;      /* resolved for `integrator` (0: its default) */
    int depth_asked;    /* given to load() or assigned (0: none) */
    int depth_file;     /* the file's render.max_depth (0: none) */
    PyObject *path;     /* str: the file or builtin:NAME */
    PyObject *file;     /* bytes: the file's path for checkpoints' identity, or None */
    PyObject *warnings; /* list of str */
} SceneObject;

static PyTypeObject SceneType;

static void scene_release_user(PyObject *obj) {
    SceneObject *s = (SceneObject *)obj;
    if (--s->users == 0 && s->closed) {
        tr_scene_destroy(s->scene);
        s->scene = NULL;
    }
}

static void scene_dealloc(SceneObject *s) {
    tr_scene_destroy(s->scene);
    Py_XDECREF(s->path);
    Py_XDECREF(s->file);
    Py_XDECREF(s->warnings);
    Py_TYPE(s)->tp_free((PyObject *)s);
}

/* The scene of an argument, open; NULL with TypeError or InvalidOperationError. */
static SceneObject *scene_arg(PyObject *o) {
    if (!PyObject_TypeCheck(o, &SceneType)) {
        PyErr_Format(PyExc_TypeError, "scene: expected a trac0r.Scene, got %s",
                     Py_TYPE(o)->tp_name);
        return NULL;
    }
    SceneObject *s = (SceneObject *)o;
    if (s->closed) {
        raise_status(TR_STATUS_INVALID_OPERATION, "scene: the scene is closed");
        return NULL;
    }
    return s;
}

static PyObject *vec3_tuple(tr_vec3 v) {
    return Py_BuildValue("(ddd)", (double)v.x, (double)v.y, (double)v.z);
}

static PyObject *camera_dict(const tr_camera *c) {
    return Py_BuildValue("{s:N,s:N,s:N,s:d,s:d,s:d,s:I,s:I,s:d,s:d}", "position",
                         vec3_tuple(c->pos), "direction", vec3_tuple(c->dir), "up",
                         vec3_tuple(c->world_up), "fov", (double)c->vertical_fov, "near",
                         (double)c->near_dist, "far", (double)c->far_dist, "width", c->screen_width,
                         "height", c->screen_height, "aperture_radius", (double)c->lens_radius,
                         "focus_distance", (double)c->focus_dist);
}

static int dict_vec3(PyObject *d, const char *key, tr_vec3 *out, int *given) {
    PyObject *v = PyDict_GetItemString(d, key);
    *given = v != NULL;
    if (!v) {
        return 0;
    }
    double x[3];
    PyObject *seq = PySequence_Fast(v, "");
    if (!seq || PySequence_Fast_GET_SIZE(seq) != 3) {
        Py_XDECREF(seq);
        PyErr_Clear();
        PyErr_Format(PyExc_TypeError, "camera['%s']: expected three numbers", key);
        return -1;
    }
    for (int k = 0; k < 3; ++k) {
        char name[48];
        snprintf(name, sizeof name, "camera['%s'][%d]", key, k);
        x[k] = 0.0;
        if (arg_double(PySequence_Fast_GET_ITEM(seq, k), name, -1e30, 1e30, &x[k]) < 0) {
            Py_DECREF(seq);
            return -1;
        }
    }
    Py_DECREF(seq);
    *out = tr_vec3_make((float)x[0], (float)x[1], (float)x[2]);
    return 0;
}

/* A camera from a dict (position, direction or look_at, up, fov, near, far, width,
 * height), every key it lacks taken from `base`. */
static int camera_from_dict(PyObject *d, const tr_camera *base, tr_camera *out) {
    if (!PyDict_Check(d)) {
        PyErr_Format(PyExc_TypeError, "camera: expected a dict, got %s", Py_TYPE(d)->tp_name);
        return -1;
    }
    static const char *keys[] = {
        "position", "direction",       "look_at",       "up", "fov", "near", "far", "width",
        "height",   "aperture_radius", "focus_distance"};
    PyObject *key;
    PyObject *value;
    Py_ssize_t pos = 0;
    while (PyDict_Next(d, &pos, &key, &value)) {
        int known = 0;
        for (size_t k = 0; k < sizeof keys / sizeof *keys; ++k) {
            known |= PyUnicode_Check(key) && PyUnicode_CompareWithASCIIString(key, keys[k]) == 0;
        }
        if (!known) {
            PyErr_Format(PyExc_ValueError,
                         "camera: unknown key %R (expected position, direction, look_at, up, "
                         "fov, near, far, width, height, aperture_radius, focus_distance)",
                         key);
            return -1;
        }
    }
    tr_vec3 p = base->pos, dir = base->dir, up = base->world_up, at;
    int g1, g2, g3;
    if (dict_vec3(d, "position", &p, &g1) < 0 || dict_vec3(d, "direction", &dir, &g2) < 0 ||
        dict_vec3(d, "up", &up, &g3) < 0 || dict_vec3(d, "look_at", &at, &g3) < 0) {
        return -1;
    }
    if (g3) {
        dir = tr_vec3_make(at.x - p.x, at.y - p.y, at.z - p.z);
    }
    double fov = base->vertical_fov, nd = base->near_dist, fd = base->far_dist;
    uint32_t w = base->screen_width, h = base->screen_height;
    if (arg_double(PyDict_GetItemString(d, "fov"), "camera['fov']", 0.0, 180.0, &fov) < 0 ||
        arg_double(PyDict_GetItemString(d, "near"), "camera['near']", 0.0, 1e30, &nd) < 0 ||
        arg_double(PyDict_GetItemString(d, "far"), "camera['far']", 0.0, 1e30, &fd) < 0 ||
        arg_u32(PyDict_GetItemString(d, "width"), "camera['width']", 1, TR_FILM_MAX_SIDE, &w) < 0 ||
        arg_u32(PyDict_GetItemString(d, "height"), "camera['height']", 1, TR_FILM_MAX_SIDE, &h) <
            0) {
        return -1;
    }
    double lr = base->lens_radius, fdist = base->focus_dist;
    if (arg_double(PyDict_GetItemString(d, "aperture_radius"), "camera['aperture_radius']", 0.0,
                   1e30, &lr) < 0 ||
        arg_double(PyDict_GetItemString(d, "focus_distance"), "camera['focus_distance']", 1e-30,
                   1e30, &fdist) < 0) {
        return -1;
    }
    tr_error err;
    if (tr_camera_make(out, p, dir, up, (float)fov, (float)nd, (float)fd, w, h, &err) != TR_OK ||
        tr_camera_set_lens(out, (float)lr, (float)fdist, &err) != TR_OK) {
        raise_tr(&err);
        return -1;
    }
    return 0;
}

static int scene_check_idle(SceneObject *s, const char *what) {
    if (s->closed) {
        raise_status(TR_STATUS_INVALID_OPERATION, "%s: the scene is closed", what);
        return -1;
    }
    if (s->busy) {
        raise_status(TR_STATUS_INVALID_OPERATION, "%s: the scene is being rendered", what);
        return -1;
    }
    return 0;
}

static PyObject *scene_get_camera(SceneObject *s, void *unused) {
    (void)unused;
    if (s->closed) {
        return raise_status(TR_STATUS_INVALID_OPERATION, "camera: the scene is closed");
    }
    return camera_dict(tr_scene_camera(s->scene));
}

static int scene_set_camera(SceneObject *s, PyObject *v, void *unused) {
    (void)unused;
    if (!v) {
        PyErr_SetString(PyExc_AttributeError, "camera: cannot be deleted");
        return -1;
    }
    if (scene_check_idle(s, "camera") < 0) {
        return -1;
    }
    tr_camera cam;
    if (camera_from_dict(v, tr_scene_camera(s->scene), &cam) < 0) {
        return -1;
    }
    tr_scene_set_camera(s->scene, &cam);
    return 0;
}

static PyObject *scene_get_size(SceneObject *s, void *which) {
    if (s->closed) {
        return raise_status(TR_STATUS_INVALID_OPERATION, "the scene is closed");
    }
    const tr_camera *c = tr_scene_camera(s->scene);
    return PyLong_FromUnsignedLong(which ? c->screen_height : c->screen_width);
}

/* The max depth a render of s with `integrator` takes, as tr_scene_file_apply resolves
 * it: the one asked for, else the file's (cut to bdpt's limit), else the integrator's
 * default (0). */
static int scene_depth_for(const SceneObject *s, int integrator) {
    if (s->depth_asked) {
        return s->depth_asked;
    }
    int depth = s->depth_file;
    if (tr_integrator_is_bidirectional(integrator) && depth > TR_MAX_DEPTH_BDPT) {
        depth = TR_MAX_DEPTH_BDPT;
    }
    return depth;
}

static PyObject *scene_get_integrator(SceneObject *s, void *unused) {
    (void)unused;
    return PyUnicode_FromString(tr_integrator_name(s->integrator));
}

static int scene_set_integrator(SceneObject *s, PyObject *v, void *unused) {
    (void)unused;
    if (!v || v == Py_None) {
        PyErr_SetString(PyExc_TypeError, "integrator: expected a str");
        return -1;
    }
    if (arg_integrator(v, &s->integrator) < 0) {
        return -1;
    }
    s->max_depth = scene_depth_for(s, s->integrator);
    return 0;
}

static PyObject *scene_get_spp(SceneObject *s, void *unused) {
    (void)unused;
    return PyLong_FromUnsignedLong(s->spp);
}

static int scene_set_spp(SceneObject *s, PyObject *v, void *unused) {
    (void)unused;
    if (!v || v == Py_None) {
        PyErr_SetString(PyExc_TypeError, "spp: expected an integer");
        return -1;
    }
    return arg_u32(v, "spp", 1, TR_SESSION_SPP_MAX, &s->spp);
}

static PyObject *scene_get_max_depth(SceneObject *s, void *unused) {
    (void)unused;
    return PyLong_FromLong(s->max_depth ? s->max_depth : tr_default_max_depth(s->integrator));
}

static int scene_set_max_depth(SceneObject *s, PyObject *v, void *unused) {
    (void)unused;
    if (!v || v == Py_None) {
        PyErr_SetString(PyExc_TypeError, "max_depth: expected an integer");
        return -1;
    }
    if (arg_int(v, "max_depth", 1, TR_MAX_DEPTH_LIMIT, &s->max_depth) < 0) {
        return -1;
    }
    s->depth_asked = s->max_depth;
    return 0;
}

static PyObject *scene_get_triangles(SceneObject *s, void *unused) {
    (void)unused;
    if (s->closed) {
        return raise_status(TR_STATUS_INVALID_OPERATION, "triangles: the scene is closed");
    }
    return PyLong_FromUnsignedLong(tr_scene_triangle_count(s->scene));
}

static PyObject *scene_get_accel(SceneObject *s, void *unused) {
    (void)unused;
    if (s->closed) {
        return raise_status(TR_STATUS_INVALID_OPERATION, "accel: the scene is closed");
    }
    return PyUnicode_FromString(tr_accel_name(tr_scene_accel(s->scene)));
}

static PyGetSetDef scene_getset[] = {
    {"camera", (getter)scene_get_camera, (setter)scene_set_camera,
     "The camera as a dict (position, direction, up, fov, near, far, width, height); assign a "
     "dict with some of the keys (or look_at) to change it.",
     NULL},
    {"width", (getter)scene_get_size, NULL, "The image width (the camera's).", NULL},
    {"height", (getter)scene_get_size, NULL, "The image height (the camera's).", (void *)1},
    {"spp", (getter)scene_get_spp, (setter)scene_set_spp, "Render default: samples per pixel.",
     NULL},
    {"integrator", (getter)scene_get_integrator, (setter)scene_set_integrator,
     "Render default: the integrator's name.", NULL},
    {"max_depth", (getter)scene_get_max_depth, (setter)scene_set_max_depth,
     "Render default: the path length limit.", NULL},
    {"triangles", (getter)scene_get_triangles, NULL, "Triangles in the scene.", NULL},
    {"accel", (getter)scene_get_accel, NULL, "The acceleration structure.", NULL},
    {NULL, NULL, NULL, NULL, NULL}};

static PyMemberDef scene_members[] = {
    {"path", T_OBJECT, offsetof(SceneObject, path), READONLY, "What was loaded."},
    {"warnings", T_OBJECT, offsetof(SceneObject, warnings), READONLY, "The loader's warnings."},
    {NULL, 0, 0, 0, NULL}};

static PyObject *scene_resize(SceneObject *s, PyObject *args, PyObject *kw) {
    static char *kwlist[] = {"width", "height", NULL};
    PyObject *ow, *oh;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "OO:resize", kwlist, &ow, &oh)) {
        return NULL;
    }
    uint32_t w = 0, h = 0;
    if (scene_check_idle(s, "resize") < 0 || arg_u32(ow, "width", 1, TR_FILM_MAX_SIDE, &w) < 0 ||
        arg_u32(oh, "height", 1, TR_FILM_MAX_SIDE, &h) < 0) {
        return NULL;
    }
    tr_error err;
    tr_camera cam = *tr_scene_camera(s->scene);
    if (tr_film_check_size(w, h, &err) != TR_OK || tr_camera_resize(&cam, w, h, &err) != TR_OK) {
        return raise_tr(&err);
    }
    tr_scene_set_camera(s->scene, &cam);
    Py_RETURN_NONE;
}

static PyObject *scene_close(SceneObject *s, PyObject *unused) {
    (void)unused;
    if (!s->closed) {
        s->closed = 1;
        if (s->users == 0) {
            tr_scene_destroy(s->scene);
            s->scene = NULL;
        }
    }
    Py_RETURN_NONE;
}

static PyObject *self_enter(PyObject *self, PyObject *unused) {
    (void)unused;
    return Py_NewRef(self);
}

static PyObject *scene_exit(SceneObject *s, PyObject *args) {
    (void)args;
    return scene_close(s, NULL);
}

static PyObject *scene_repr(SceneObject *s) {
    if (s->closed) {
        return PyUnicode_FromFormat("<trac0r.Scene %R (closed)>", s->path);
    }
    const tr_camera *c = tr_scene_camera(s->scene);
    return PyUnicode_FromFormat("<trac0r.Scene %R %ux%u, %u triangles>", s->path, c->screen_width,
                                c->screen_height, tr_scene_triangle_count(s->scene));
}

static PyMethodDef scene_methods[] = {
    {"resize", (PyCFunction)(void (*)(void))scene_resize, METH_VARARGS | METH_KEYWORDS,
     "resize(width, height): the camera's image size (the field of view is kept)."},
    {"close", (PyCFunction)scene_close, METH_NOARGS,
     "Releases the scene (at once, or when the last render holding it goes)."},
    {"__enter__", self_enter, METH_NOARGS, NULL},
    {"__exit__", (PyCFunction)scene_exit, METH_VARARGS, NULL},
    {NULL, NULL, 0, NULL}};

static PyTypeObject SceneType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "trac0r.Scene",
    .tp_basicsize = sizeof(SceneObject),
    .tp_dealloc = (destructor)scene_dealloc,
    .tp_repr = (reprfunc)scene_repr,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "A committed scene: trac0r.load() or trac0r.load_dict() makes one.",
    .tp_methods = scene_methods,
    .tp_members = scene_members,
    .tp_getset = scene_getset,
};

/* ---- load, load_dict --------------------------------------------------------------- */

/* What load() and load_dict() take beside the scene. */
typedef struct load_opts {
    uint32_t width, height; /* 0: the file's, else 800 x 600 */
    int up_z;
    double scale;
    const char *camera; /* a model file's camera: name, number or "frame" */
    char camera_num[24];
    int integrator; /* -1: the file's */
    int max_depth;  /* 0: the file's */
    const char *accel;
    const char *light_sampling;
    int allow_dark;
} load_opts;

static int parse_load_opts(PyObject *kw_width, PyObject *kw_height, PyObject *up, PyObject *scale,
                           PyObject *camera, PyObject *integrator, PyObject *max_depth,
                           PyObject *accel, PyObject *light_sampling, int allow_dark,
                           load_opts *o) {
    memset(o, 0, sizeof *o);
    o->scale = 1.0;
    o->integrator = -1;
    o->allow_dark = allow_dark;
    const char *upname = "y";
    if (arg_u32(kw_width, "width", 1, TR_FILM_MAX_SIDE, &o->width) < 0 ||
        arg_u32(kw_height, "height", 1, TR_FILM_MAX_SIDE, &o->height) < 0 ||
        arg_str(up, "up", &upname) < 0 || arg_double(scale, "scale", 1e-6, 1e6, &o->scale) < 0 ||
        arg_integrator(integrator, &o->integrator) < 0 ||
        arg_int(max_depth, "max_depth", 1, TR_MAX_DEPTH_LIMIT, &o->max_depth) < 0 ||
        arg_str(accel, "accel", &o->accel) < 0 ||
        arg_str(light_sampling, "light_sampling", &o->light_sampling) < 0) {
        return -1;
    }
    if (strcmp(upname, "y") != 0 && strcmp(upname, "z") != 0) {
        PyErr_Format(PyExc_ValueError, "up: expected 'y' or 'z', got '%s'", upname);
        return -1;
    }
    o->up_z = upname[0] == 'z';
    if (camera && camera != Py_None) {
        if (PyLong_Check(camera) && !PyBool_Check(camera)) {
            long long k = 0;
            if (arg_long(camera, "camera", 0, 1000000, &k) < 0) {
                return -1;
            }
            snprintf(o->camera_num, sizeof o->camera_num, "%lld", k);
            o->camera = o->camera_num;
        } else if (arg_str(camera, "camera", &o->camera) < 0) {
            return -1;
        }
        if (!o->camera[0]) {
            PyErr_SetString(PyExc_ValueError,
                            "camera: expected a camera's name or number, or 'frame'");
            return -1;
        }
    }
    if (o->light_sampling && tr_light_sampling_from_name(o->light_sampling) < 0) {
        PyErr_Format(PyExc_ValueError,
                     "light_sampling: unknown light sampling '%s' (available: auto, tree, power)",
                     o->light_sampling);
        return -1;
    }
    if (o->accel) {
        const int a = tr_accel_from_name(o->accel);
        if (a < 0) {
            PyErr_Format(PyExc_ValueError, "accel: unknown acceleration structure '%s'", o->accel);
            return -1;
        }
        if (!tr_accel_available((tr_accel_type)a)) {
            raise_status(TR_STATUS_UNSUPPORTED, "accel: '%s' is not available in this build",
                         o->accel);
            return -1;
        }
    }
    return 0;
}

static int is_builtin(const char *name) {
    return strncmp(name, "builtin:", 8) == 0 || (!strchr(name, '/') && !strchr(name, '.'));
}

/* Loads what `path` names into s (no GIL held): a built-in scene, a model file or a scene
 * file (text, when given, is the file's content), resolved as the command resolves its
 * options over the file's render block, and committed. */
static int load_into(tr_scene *s, const char *path, const char *text, size_t len,
                     const load_opts *o, SceneObject *out, tr_scene_file *file, tr_error *err) {
    memset(file, 0, sizeof *file);
    tr_render_request req = {0};
    req.width = o->width;
    req.height = o->height;
    req.max_depth = o->max_depth;
    req.integrator = o->integrator >= 0 ? tr_integrator_name(o->integrator) : NULL;
    req.accel = o->accel;
    req.light_sampling = o->light_sampling;
    req.allow_dark = o->allow_dark;
    tr_render_settings st;
    if (text) { /* a scene given as text: parsed, then resolved as tr_scene_open does */
        if (tr_scene_file_parse(s, path, text, len, NULL, file, err) != TR_OK ||
            tr_scene_file_apply(s, path, file, &req, &st, err) != TR_OK ||
            tr_scene_commit(s, st.accel, err) != TR_OK) {
            tr_scene_clear(s);
            return TR_ERR;
        }
    } else {
        tr_scene_open_desc d = {.model = {o->up_z, (float)o->scale, 0, 0, o->camera}};
        d.request = req;
        if (tr_scene_open(s, path, &d, file, &st, err) != TR_OK) {
            return TR_ERR;
        }
    }
    out->spp = st.spp;
    out->integrator = st.config.integrator;
    out->max_depth = st.config.max_depth;
    out->depth_asked = o->max_depth;
    out->depth_file = file->has_max_depth ? file->max_depth : 0;
    return TR_OK;
}

static PyObject *load_common(PyObject *name_obj, const char *path, const char *text, size_t len,
                             const load_opts *o) {
    tr_error err;
    tr_scene *scene = tr_scene_create(&err);
    if (!scene) {
        return raise_tr(&err);
    }
    SceneObject *s = PyObject_New(SceneObject, &SceneType);
    if (!s) {
        tr_scene_destroy(scene);
        return NULL;
    }
    s->scene = NULL;
    s->closed = 0;
    s->users = 0;
    s->busy = 0;
    s->path = NULL;
    s->file = NULL;
    s->warnings = NULL;
    tr_scene_file *file = malloc(sizeof *file);
    if (!file) {
        tr_scene_destroy(scene);
        Py_DECREF(s);
        return PyErr_NoMemory();
    }
    int rc;
    Py_BEGIN_ALLOW_THREADS;
    rc = load_into(scene, path, text, len, o, s, file, &err);
    Py_END_ALLOW_THREADS;
    if (rc != TR_OK) {
        free(file);
        tr_scene_destroy(scene);
        Py_DECREF(s);
        return raise_tr(&err);
    }
    s->scene = scene;
    s->path = Py_NewRef(name_obj);
    s->file = text || is_builtin(path) ? Py_NewRef(Py_None) : PyBytes_FromString(path);
    s->warnings = PyList_New(0);
    for (uint32_t i = 0; s->warnings && i < file->warning_count; ++i) {
        PyObject *w = PyUnicode_DecodeUTF8(file->warnings[i], (Py_ssize_t)strlen(file->warnings[i]),
                                           "replace");
        if (!w || PyList_Append(s->warnings, w) < 0) {
            Py_XDECREF(w);
            break;
        }
        Py_DECREF(w);
    }
    free(file);
    if (!s->file || !s->warnings || PyErr_Occurred()) {
        Py_DECREF(s);
        return NULL;
    }
    return (PyObject *)s;
}

static PyObject *py_load(PyObject *self, PyObject *args, PyObject *kw) {
    (void)self;
    static char *kwlist[] = {"path",  "width",          "height",     "up",
                             "scale", "camera",         "integrator", "max_depth",
                             "accel", "light_sampling", "allow_dark", NULL};
    PyObject *path_obj, *w = NULL, *h = NULL, *up = NULL, *scale = NULL, *camera = NULL,
                        *integrator = NULL, *max_depth = NULL, *accel = NULL, *ls = NULL;
    int allow_dark = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "O|$OOOOOOOOOp:load", kwlist, &path_obj, &w, &h, &up,
                                     &scale, &camera, &integrator, &max_depth, &accel, &ls,
                                     &allow_dark)) {
        return NULL;
    }
    PyObject *path = arg_path(path_obj, "path");
    if (!path) {
        return NULL;
    }
    load_opts o;
    PyObject *r = NULL;
    if (parse_load_opts(w, h, up, scale, camera, integrator, max_depth, accel, ls, allow_dark,
                        &o) == 0) {
        PyObject *name = PyUnicode_DecodeFSDefault(PyBytes_AS_STRING(path));
        if (name) {
            r = load_common(name, PyBytes_AS_STRING(path), NULL, 0, &o);
            Py_DECREF(name);
        }
    }
    Py_DECREF(path);
    return r;
}

static PyObject *py_load_dict(PyObject *self, PyObject *args, PyObject *kw) {
    (void)self;
    static char *kwlist[] = {"scene",     "base_dir", "width",          "height",     "integrator",
                             "max_depth", "accel",    "light_sampling", "allow_dark", NULL};
    PyObject *dict, *base = NULL, *w = NULL, *h = NULL, *integrator = NULL, *max_depth = NULL,
                    *accel = NULL, *ls = NULL;
    int allow_dark = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "O|$OOOOOOOp:load_dict", kwlist, &dict, &base, &w,
                                     &h, &integrator, &max_depth, &accel, &ls, &allow_dark)) {
        return NULL;
    }
    if (!PyDict_Check(dict)) {
        PyErr_Format(PyExc_TypeError, "scene: expected a dict, got %s", Py_TYPE(dict)->tp_name);
        return NULL;
    }
    load_opts o;
    if (parse_load_opts(w, h, NULL, NULL, NULL, integrator, max_depth, accel, ls, allow_dark, &o) <
        0) {
        return NULL;
    }
    PyObject *dir = base && base != Py_None ? arg_path(base, "base_dir") : PyBytes_FromString(".");
    if (!dir) {
        return NULL;
    }
    /* The scene-file format is JSON: the dict goes through the library's parser as the
     * text json.dumps makes of it (a value JSON cannot hold fails there). */
    PyObject *json = PyImport_ImportModule("json");
    PyObject *text = json ? PyObject_CallMethod(json, "dumps", "O", dict) : NULL;
    Py_XDECREF(json);
    PyObject *r = NULL;
    Py_ssize_t len = 0;
    const char *utf8 = text ? PyUnicode_AsUTF8AndSize(text, &len) : NULL;
    if (!utf8 && text) {
        Py_DECREF(text);
        text = NULL;
    }
    if (!text) {
        if (PyErr_ExceptionMatches(PyExc_TypeError) || PyErr_ExceptionMatches(PyExc_ValueError)) {
            PyObject *t, *v, *tb;
            PyErr_Fetch(&t, &v, &tb);
            PyErr_Format(PyExc_TypeError, "scene: not expressible as JSON: %S", v ? v : Py_None);
            Py_XDECREF(t);
            Py_XDECREF(v);
            Py_XDECREF(tb);
        }
        Py_DECREF(dir);
        return NULL;
    }
    /* Messages name "<dict>"; mesh paths are relative to base_dir. */
    PyObject *path = PyBytes_FromFormat("%s/<dict>", PyBytes_AS_STRING(dir));
    PyObject *name = PyUnicode_FromString("<dict>");
    if (path && name) {
        r = load_common(name, PyBytes_AS_STRING(path), utf8, (size_t)len, &o);
    }
    Py_XDECREF(path);
    Py_XDECREF(name);
    Py_DECREF(text);
    Py_DECREF(dir);
    return r;
}

/* ---- offline renders -------------------------------------------------------------- */

/* The progress callback's state: the caller's callable, a sample budget for this run
 * (Session.run), and whether Python raised (then the run stops and the exception
 * propagates). */
typedef struct progress_ctx {
    PyObject *callable;
    uint32_t limit;  /* passes this run may make; 0: no limit */
    uint32_t passes; /* passes this run made */
    int paused;      /* the limit stopped the run */
    int failed;      /* a Python exception is pending */
    tr_session_progress last;
} progress_ctx;

/* After every pass (on the thread that runs the session, GIL released): takes the GIL,
 * runs pending signal handlers (Ctrl-C raises KeyboardInterrupt here) and the caller's
 * callable; a nonzero return stops the render at the end of this pass. */
static int on_progress(void *user, const tr_session_progress *p) {
    progress_ctx *c = user;
    PyGILState_STATE g = PyGILState_Ensure();
    int stop = 0;
    c->last = *p;
    ++c->passes;
    if (c->failed || PyErr_CheckSignals() < 0) {
        c->failed = 1;
        stop = 1;
    } else if (c->callable) {
        PyObject *arg = progress_new(p, 0);
        PyObject *r = arg ? PyObject_CallOneArg(c->callable, arg) : NULL;
        Py_XDECREF(arg);
        stop = r ? PyObject_IsTrue(r) : -1;
        Py_XDECREF(r);
        if (stop < 0) {
            c->failed = 1;
            stop = 1;
        }
    }
    if (!stop && c->limit && c->passes >= c->limit) {
        c->paused = 1;
        stop = 1;
    }
    PyGILState_Release(g);
    return stop;
}

/* What render() and Session() take. */
typedef struct render_opts {
    tr_render_config cfg;
    tr_session_desc desc;
    char device[32];
    uint32_t passes; /* asked for (the film may keep more: denoise's guides) */
} render_opts;

static int parse_render_opts(SceneObject *s, PyObject *spp, PyObject *seed, PyObject *integrator,
                             PyObject *max_depth, PyObject *device, PyObject *threads,
                             PyObject *sampler, PyObject *passes, PyObject *noise,
                             PyObject *time_limit, PyObject *stride, int denoise, render_opts *o) {
    memset(o, 0, sizeof *o);
    o->cfg = tr_render_config_default();
    o->cfg.integrator = s->integrator;
    o->cfg.max_depth = s->max_depth;
    o->cfg.sampler = TR_SAMPLER_SOBOL;
    o->desc.spp = s->spp;
    double nt = 0.0, tl = 0.0;
    if (arg_u32(spp, "spp", 1, TR_SESSION_SPP_MAX, &o->desc.spp) < 0 ||
        arg_seed(seed, &o->cfg.seed) < 0 || arg_integrator(integrator, &o->cfg.integrator) < 0 ||
        arg_int(max_depth, "max_depth", 1, TR_MAX_DEPTH_LIMIT, &o->cfg.max_depth) < 0 ||
        arg_device(device, o->device, sizeof o->device) < 0 ||
        arg_int(threads, "threads", 0, TR_MAX_THREADS, &o->cfg.threads) < 0 ||
        arg_sampler(sampler, &o->cfg.sampler) < 0 || arg_passes(passes, &o->passes) < 0 ||
        arg_double(noise, "noise_threshold", 0.0, 1.0, &nt) < 0 ||
        arg_double(time_limit, "time_limit", 0.0, 1e6, &tl) < 0 ||
        arg_int(stride, "stride", 1, 64, &o->cfg.stride) < 0) {
        return -1;
    }
    if (integrator && integrator != Py_None && (!max_depth || max_depth == Py_None)) {
        o->cfg.max_depth = scene_depth_for(s, o->cfg.integrator);
    }
    o->cfg.passes = o->passes;
    o->desc.noise_threshold = (float)nt;
    o->desc.time_limit = tl;
    o->desc.denoise = denoise;
    o->desc.scene_file = s->file != Py_None ? PyBytes_AS_STRING(s->file) : NULL;
    tr_error err;
    if (tr_render_config_check(&o->cfg, &err) != TR_OK) {
        raise_tr(&err);
        return -1;
    }
    return 0;
}

/* A device with s's scene and a session on it (no GIL held). */
static int open_session(SceneObject *s, render_opts *o, progress_ctx *ctx, tr_device **dev,
                        tr_session **session, tr_error *err) {
    *session = NULL;
    *dev = tr_device_create(o->device, err);
    if (!*dev) {
        return TR_ERR;
    }
    o->desc.progress = on_progress;
    o->desc.progress_user = ctx;
    *session = tr_session_create(*dev, s->scene, &o->cfg, &o->desc, err);
    if (!*session) {
        tr_device_destroy(*dev);
        *dev = NULL;
        return TR_ERR;
    }
    return TR_OK;
}

static PyObject *py_render(PyObject *self, PyObject *args, PyObject *kw) {
    (void)self;
    static char *kwlist[] = {"scene",      "spp",     "seed",     "integrator", "max_depth",
                             "device",     "threads", "sampler",  "passes",     "noise_threshold",
                             "time_limit", "denoise", "progress", "stride",     NULL};
    PyObject *scene_obj, *spp = NULL, *seed = NULL, *integrator = NULL, *max_depth = NULL,
                         *device = NULL, *threads = NULL, *sampler = NULL, *passes = NULL,
                         *noise = NULL, *time_limit = NULL, *progress = NULL, *stride = NULL;
    int denoise = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "O|$OOOOOOOOOOpOO:render", kwlist, &scene_obj, &spp,
                                     &seed, &integrator, &max_depth, &device, &threads, &sampler,
                                     &passes, &noise, &time_limit, &denoise, &progress, &stride)) {
        return NULL;
    }
    SceneObject *s = scene_arg(scene_obj);
    if (!s) {
        return NULL;
    }
    if (progress && progress != Py_None && !PyCallable_Check(progress)) {
        PyErr_Format(PyExc_TypeError, "progress: expected a callable, got %s",
                     Py_TYPE(progress)->tp_name);
        return NULL;
    }
    render_opts o;
    if (parse_render_opts(s, spp, seed, integrator, max_depth, device, threads, sampler, passes,
                          noise, time_limit, stride, denoise, &o) < 0) {
        return NULL;
    }
    OwnerObject *own = owner_new();
    if (!own) {
        return NULL;
    }
    own->scene = Py_NewRef((PyObject *)s);
    ++s->users;
    progress_ctx ctx;
    memset(&ctx, 0, sizeof ctx);
    ctx.callable = progress && progress != Py_None ? progress : NULL;
    Py_XINCREF(ctx.callable);
    tr_error err;
    int rc;
    const tr_film *film = NULL;
    ++s->busy;
    Py_BEGIN_ALLOW_THREADS;
    rc = open_session(s, &o, &ctx, &own->dev, &own->session, &err);
    if (rc == TR_OK) {
        rc = tr_session_run(own->session, &err);
    }
    if (rc == TR_OK && !ctx.failed) {
        film = tr_session_film(own->session, &err);
        rc = film ? TR_OK : TR_ERR;
    }
    if (rc == TR_OK && !ctx.failed && denoise) {
        rc = tr_session_denoise(own->session, &own->den, &err);
    }
    Py_END_ALLOW_THREADS;
    --s->busy;
    Py_XDECREF(ctx.callable);
    if (ctx.failed || rc != TR_OK) {
        Py_DECREF(own);
        return ctx.failed ? NULL : raise_tr(&err);
    }
    tr_session_progress p;
    tr_session_progress_get(own->session, &p);
    /* The session's film becomes the arrays' memory: its means, computed in place. The
     * session renders nothing more. */
    own->film = *film;
    film_to_means(&own->film);
    if (own->den.sum) {
        film_to_means(&own->den);
    }
    PyObject *r = result_new(own, o.passes, &p, 0);
    Py_DECREF(own);
    return r;
}

/* ---- Session: a render made progressively ------------------------------------------ */

typedef struct {
    PyObject_HEAD tr_session *session;
    tr_device *dev;
    SceneObject *scene;
    progress_ctx ctx;
    uint32_t passes;
    int running;
} SessionObject;

static void session_free(SessionObject *o) {
    tr_session_destroy(o->session);
    o->session = NULL;
    tr_device_destroy(o->dev);
    o->dev = NULL;
    if (o->scene) {
        scene_release_user((PyObject *)o->scene);
        Py_CLEAR(o->scene);
    }
}

static void session_dealloc(SessionObject *o) {
    session_free(o);
    Py_TYPE(o)->tp_free((PyObject *)o);
}

static PyObject *session_new(PyTypeObject *type, PyObject *args, PyObject *kw) {
    static char *kwlist[] = {"scene",      "spp",     "seed",    "integrator", "max_depth",
                             "device",     "threads", "sampler", "passes",     "noise_threshold",
                             "time_limit", "denoise", "stride",  NULL};
    PyObject *scene_obj, *spp = NULL, *seed = NULL, *integrator = NULL, *max_depth = NULL,
                         *device = NULL, *threads = NULL, *sampler = NULL, *passes = NULL,
                         *noise = NULL, *time_limit = NULL, *stride = NULL;
    int denoise = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "O|$OOOOOOOOOOpO:Session", kwlist, &scene_obj, &spp,
                                     &seed, &integrator, &max_depth, &device, &threads, &sampler,
                                     &passes, &noise, &time_limit, &denoise, &stride)) {
        return NULL;
    }
    SceneObject *s = scene_arg(scene_obj);
    render_opts o;
    if (!s || parse_render_opts(s, spp, seed, integrator, max_depth, device, threads, sampler,
                                passes, noise, time_limit, stride, denoise, &o) < 0) {
        return NULL;
    }
    SessionObject *self = (SessionObject *)type->tp_alloc(type, 0);
    if (!self) {
        return NULL;
    }
    self->scene = (SceneObject *)Py_NewRef((PyObject *)s);
    ++s->users;
    self->passes = o.passes;
    tr_error err;
    int rc;
    ++s->busy;
    Py_BEGIN_ALLOW_THREADS;
    rc = open_session(s, &o, &self->ctx, &self->dev, &self->session, &err);
    Py_END_ALLOW_THREADS;
    --s->busy;
    if (rc != TR_OK) {
        Py_DECREF(self);
        return raise_tr(&err);
    }
    return (PyObject *)self;
}

static int session_check(SessionObject *o, const char *what) {
    if (!o->session) {
        raise_status(TR_STATUS_INVALID_OPERATION, "%s: the session is closed", what);
        return -1;
    }
    if (o->running) {
        raise_status(TR_STATUS_INVALID_OPERATION, "%s: the session is running in another thread",
                     what);
        return -1;
    }
    return 0;
}

static PyObject *session_run(SessionObject *o, PyObject *args, PyObject *kw) {
    static char *kwlist[] = {"samples", "progress", NULL};
    PyObject *samples = NULL, *progress = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "|O$O:run", kwlist, &samples, &progress)) {
        return NULL;
    }
    uint32_t limit = 0;
    if (session_check(o, "run") < 0 ||
        arg_u32(samples, "samples", 1, TR_SESSION_SPP_MAX, &limit) < 0) {
        return NULL;
    }
    if (progress && progress != Py_None && !PyCallable_Check(progress)) {
        PyErr_Format(PyExc_TypeError, "progress: expected a callable, got %s",
                     Py_TYPE(progress)->tp_name);
        return NULL;
    }
    o->ctx.callable = progress && progress != Py_None ? Py_NewRef(progress) : NULL;
    o->ctx.limit = limit;
    o->ctx.passes = 0;
    o->ctx.paused = 0;
    o->ctx.failed = 0;
    tr_error err;
    int rc;
    o->running = 1;
    ++o->scene->busy;
    Py_BEGIN_ALLOW_THREADS;
    rc = tr_session_run(o->session, &err);
    Py_END_ALLOW_THREADS;
    --o->scene->busy;
    o->running = 0;
    Py_CLEAR(o->ctx.callable);
    if (o->ctx.failed) {
        return NULL;
    }
    if (rc != TR_OK) {
        return raise_tr(&err);
    }
    tr_session_progress p;
    tr_session_progress_get(o->session, &p);
    o->ctx.last = p;
    return progress_new(&p, o->ctx.paused);
}

static PyObject *session_stop(SessionObject *o, PyObject *unused) {
    (void)unused;
    if (o->session) {
        tr_session_cancel(o->session);
    }
    Py_RETURN_NONE;
}

/* The film as it stands, as a Result of arrays of their own (the session goes on
 * accumulating into its film). */
static PyObject *session_result(SessionObject *o, PyObject *unused) {
    (void)unused;
    if (session_check(o, "result") < 0) {
        return NULL;
    }
    tr_error err;
    const tr_film *film = tr_session_film(o->session, &err);
    OwnerObject *own = film ? owner_new() : NULL;
    if (!film) {
        return raise_tr(&err);
    }
    if (!own) {
        return NULL;
    }
    int rc;
    Py_BEGIN_ALLOW_THREADS;
    rc = film_copy(&own->film, film, &err);
    Py_END_ALLOW_THREADS;
    if (rc != TR_OK) {
        Py_DECREF(own);
        return raise_tr(&err);
    }
    own->film_owned = 1;
    film_to_means(&own->film);
    tr_session_progress p;
    tr_session_progress_get(o->session, &p);
    PyObject *r = result_new(own, o->passes, &p, o->ctx.paused);
    Py_DECREF(own);
    return r;
}

static PyObject *session_get_progress(SessionObject *o, void *unused) {
    (void)unused;
    if (!o->session) {
        return raise_status(TR_STATUS_INVALID_OPERATION, "progress: the session is closed");
    }
    if (o->running) {
        /* The last pass's, recorded under the GIL by the progress callback. */
        return progress_new(&o->ctx.last, 0);
    }
    tr_session_progress p;
    tr_session_progress_get(o->session, &p);
    return progress_new(&p, o->ctx.paused);
}

static PyObject *session_close(SessionObject *o, PyObject *unused) {
    (void)unused;
    if (o->running) {
        return raise_status(TR_STATUS_INVALID_OPERATION,
                            "close: the session is running in another thread (stop() it first)");
    }
    session_free(o);
    Py_RETURN_NONE;
}

static PyObject *session_exit(SessionObject *o, PyObject *args) {
    (void)args;
    return session_close(o, NULL);
}

static PyMethodDef session_methods[] = {
    {"run", (PyCFunction)(void (*)(void))session_run, METH_VARARGS | METH_KEYWORDS,
     "run(samples=None, *, progress=None) -> Progress: renders until the session's spp (or "
     "`samples` more passes, or its limits); again after a stop to go on."},
    {"stop", (PyCFunction)session_stop, METH_NOARGS,
     "Asks a run (in another thread) to stop at the end of the pass under way."},
    {"result", (PyCFunction)session_result, METH_NOARGS,
     "The film as it stands, as a Result (arrays of their own)."},
    {"close", (PyCFunction)session_close, METH_NOARGS, "Releases the session and its device."},
    {"__enter__", self_enter, METH_NOARGS, NULL},
    {"__exit__", (PyCFunction)session_exit, METH_VARARGS, NULL},
    {NULL, NULL, 0, NULL}};

static PyGetSetDef session_getset[] = {
    {"progress", (getter)session_get_progress, NULL, "Where the render stands (Progress).", NULL},
    {NULL, NULL, NULL, NULL, NULL}};

static PyTypeObject SessionType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "trac0r.Session",
    .tp_basicsize = sizeof(SessionObject),
    .tp_dealloc = (destructor)session_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "Session(scene, *, spp=, seed=, ...): an offline render run in steps.",
    .tp_methods = session_methods,
    .tp_getset = session_getset,
    .tp_new = session_new,
};

/* ---- Realtime ------------------------------------------------------------------------ */

typedef struct {
    PyObject_HEAD tr_realtime *rt;
    tr_device *dev;
    SceneObject *scene;
    tr_camera cam; /* the frames' camera unless frame() gives one */
    int method;
    int running;
} RealtimeObject;

static void realtime_free(RealtimeObject *o) {
    tr_realtime_destroy(o->rt);
    o->rt = NULL;
    tr_device_destroy(o->dev);
    o->dev = NULL;
    if (o->scene) {
        scene_release_user((PyObject *)o->scene);
        Py_CLEAR(o->scene);
    }
}

static void realtime_dealloc(RealtimeObject *o) {
    realtime_free(o);
    Py_TYPE(o)->tp_free((PyObject *)o);
}

static int arg_recon(PyObject *v, int *out) {
    const char *name = NULL;
    if (arg_str(v, "recon", &name) < 0) {
        return -1;
    }
    if (name && (*out = tr_recon_parse(name)) < 0) {
        PyErr_Format(PyExc_ValueError,
                     "recon: unknown reconstruction '%s' (available: off, accumulate, bilateral, "
                     "atrous, svgf)",
                     name);
        return -1;
    }
    return 0;
}

static PyObject *realtime_new(PyTypeObject *type, PyObject *args, PyObject *kw) {
    static char *kwlist[] = {"scene",   "width",      "height",           "recon",  "spp",
                             "seed",    "integrator", "max_depth",        "device", "threads",
                             "sampler", "accumulate", "resolve_emission", NULL};
    PyObject *scene_obj, *w = NULL, *h = NULL, *recon = NULL, *spp = NULL, *seed = NULL,
                         *integrator = NULL, *max_depth = NULL, *device = NULL, *threads = NULL,
                         *sampler = NULL, *resolve = NULL;
    int accumulate = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "O|$OOOOOOOOOOpO:Realtime", kwlist, &scene_obj, &w,
                                     &h, &recon, &spp, &seed, &integrator, &max_depth, &device,
                                     &threads, &sampler, &accumulate, &resolve)) {
        return NULL;
    }
    SceneObject *s = scene_arg(scene_obj);
    if (!s) {
        return NULL;
    }
    tr_camera cam = *tr_scene_camera(s->scene);
    uint32_t width = cam.screen_width, height = cam.screen_height, fspp = 1;
    int method = TR_RECON_SVGF, sampler_kind = -1;
    char dev_name[32];
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = s->integrator;
    cfg.max_depth = s->max_depth;
    cfg.sampler = TR_SAMPLER_SOBOL;
    tr_recon_params params = tr_recon_params_default();
    if (arg_u32(w, "width", 1, TR_FILM_MAX_SIDE, &width) < 0 ||
        arg_u32(h, "height", 1, TR_FILM_MAX_SIDE, &height) < 0 || arg_recon(recon, &method) < 0 ||
        arg_u32(spp, "spp", 1, TR_REALTIME_MAX_SPP * 64, &fspp) < 0 ||
        arg_seed(seed, &cfg.seed) < 0 || arg_integrator(integrator, &cfg.integrator) < 0 ||
        arg_int(max_depth, "max_depth", 1, TR_MAX_DEPTH_LIMIT, &cfg.max_depth) < 0 ||
        arg_device(device, dev_name, sizeof dev_name) < 0 ||
        arg_int(threads, "threads", 0, TR_MAX_THREADS, &cfg.threads) < 0 ||
        arg_sampler(sampler, &sampler_kind) < 0 ||
        arg_int(resolve, "resolve_emission", 0, TR_RESOLVE_EMISSION_MAX, &params.emission_samples) <
            0) {
        return NULL;
    }
    if (integrator && integrator != Py_None && (!max_depth || max_depth == Py_None)) {
        cfg.max_depth = scene_depth_for(s, cfg.integrator);
    }
    tr_error err;
    if (tr_film_check_size(width, height, &err) != TR_OK ||
        tr_camera_resize(&cam, width, height, &err) != TR_OK) {
        return raise_tr(&err);
    }
    RealtimeObject *self = (RealtimeObject *)type->tp_alloc(type, 0);
    if (!self) {
        return NULL;
    }
    self->scene = (SceneObject *)Py_NewRef((PyObject *)s);
    ++s->users;
    self->cam = cam;
    self->method = method;
    tr_realtime_desc desc = {0};
    desc.config = &cfg;
    desc.recon = &params;
    desc.sampler = sampler_kind >= 0 ? TR_REALTIME_SAMPLER(sampler_kind) : 0;
    desc.spp = fspp;
    desc.accumulate = accumulate;
    desc.keep_passes = 1; /* frame(method=...) may change the method per frame */
    int rc = TR_ERR;
    ++s->busy;
    Py_BEGIN_ALLOW_THREADS;
    self->dev = tr_device_create(dev_name, &err);
    if (self->dev && tr_device_upload(self->dev, s->scene, &err) == TR_OK) {
        self->rt = tr_realtime_create(self->dev, s->scene, &desc, &err);
        rc = self->rt ? TR_OK : TR_ERR;
    }
    Py_END_ALLOW_THREADS;
    --s->busy;
    if (rc != TR_OK) {
        Py_DECREF(self);
        return raise_tr(&err);
    }
    return (PyObject *)self;
}

static PyObject *realtime_frame(RealtimeObject *o, PyObject *args, PyObject *kw) {
    static char *kwlist[] = {"camera", "recon", "moving", "budget_ms", "restart", NULL};
    PyObject *camera = NULL, *recon = NULL, *budget = NULL;
    int moving = 0, restart = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "|O$OpOp:frame", kwlist, &camera, &recon, &moving,
                                     &budget, &restart)) {
        return NULL;
    }
    if (!o->rt) {
        return raise_status(TR_STATUS_INVALID_OPERATION, "frame: the real-time loop is closed");
    }
    if (o->running) {
        return raise_status(TR_STATUS_INVALID_OPERATION,
                            "frame: a frame is being rendered in another thread");
    }
    int method = o->method;
    double budget_ms = 0.0;
    tr_camera cam = o->cam;
    if (arg_recon(recon, &method) < 0 ||
        arg_double(budget, "budget_ms", 0.0, 1e6, &budget_ms) < 0) {
        return NULL;
    }
    if (camera && camera != Py_None) {
        if (camera_from_dict(camera, &o->cam, &cam) < 0) {
            return NULL;
        }
        if (cam.screen_width != o->cam.screen_width || cam.screen_height != o->cam.screen_height) {
            PyErr_Format(PyExc_ValueError,
                         "camera: the real-time loop renders %ux%u (width and height are the "
                         "loop's)",
                         o->cam.screen_width, o->cam.screen_height);
            return NULL;
        }
        o->cam = cam;
    }
    tr_realtime_frame_desc fd = {0};
    fd.camera = &cam;
    fd.method = method;
    fd.moving = moving;
    fd.budget_ms = budget_ms;
    fd.restart = restart;
    tr_realtime_result res;
    tr_error err;
    int rc;
    o->running = 1;
    ++o->scene->busy;
    Py_BEGIN_ALLOW_THREADS;
    rc = tr_realtime_frame(o->rt, &fd, &res, &err);
    Py_END_ALLOW_THREADS;
    --o->scene->busy;
    o->running = 0;
    if (rc != TR_OK) {
        return raise_tr(&err);
    }
    if (PyErr_CheckSignals() < 0) {
        return NULL;
    }
    /* The library reuses its buffers next frame: the frame is copied out. */
    OwnerObject *own = owner_new();
    const size_t n = (size_t)res.width * res.height;
    if (!own || !(own->mem = malloc(3 * n * sizeof *own->mem))) {
        Py_XDECREF(own);
        return PyErr_NoMemory();
    }
    if (res.rgb) {
        memcpy(own->mem, res.rgb, 3 * n * sizeof *own->mem);
    } else {
        for (uint32_t y = 0; y < res.height; ++y) {
            for (uint32_t x = 0; x < res.width; ++x) {
                const tr_vec3 c = tr_film_pixel(res.film, x, y);
                float *d = own->mem + 3 * ((size_t)y * res.width + x);
                d[0] = c.x;
                d[1] = c.y;
                d[2] = c.z;
            }
        }
    }
    PyObject *image = owner_array(own, own->mem, res.height, res.width, 3, NPY_FLOAT32);
    Py_DECREF(own);
    PyObject *r = image ? PyStructSequence_New(&FrameType) : NULL;
    if (!r) {
        Py_XDECREF(image);
        return NULL;
    }
    const char *mname = tr_recon_name(res.method);
    PyStructSequence_SET_ITEM(r, 0, image);
    PyStructSequence_SET_ITEM(r, 1, PyFloat_FromDouble(res.render_ms));
    PyStructSequence_SET_ITEM(r, 2, PyFloat_FromDouble(res.temporal_ms));
    PyStructSequence_SET_ITEM(r, 3, PyFloat_FromDouble(res.spatial_ms));
    PyStructSequence_SET_ITEM(r, 4, PyFloat_FromDouble(res.resolve_ms));
    PyStructSequence_SET_ITEM(r, 5, PyLong_FromUnsignedLong(res.spp));
    PyStructSequence_SET_ITEM(r, 6, PyLong_FromUnsignedLong(res.frame_spp));
    PyStructSequence_SET_ITEM(r, 7, PyFloat_FromDouble((double)res.scale));
    PyStructSequence_SET_ITEM(r, 8, PyUnicode_FromString(mname ? mname : "off"));
    for (Py_ssize_t i = 1; i < 9; ++i) {
        if (!PyStructSequence_GET_ITEM(r, i)) {
            Py_DECREF(r);
            return NULL;
        }
    }
    return r;
}

static PyObject *realtime_get_camera(RealtimeObject *o, void *unused) {
    (void)unused;
    return camera_dict(&o->cam);
}

static PyObject *realtime_close(RealtimeObject *o, PyObject *unused) {
    (void)unused;
    if (o->running) {
        return raise_status(TR_STATUS_INVALID_OPERATION,
                            "close: a frame is being rendered in another thread");
    }
    realtime_free(o);
    Py_RETURN_NONE;
}

static PyObject *realtime_exit(RealtimeObject *o, PyObject *args) {
    (void)args;
    return realtime_close(o, NULL);
}

static PyMethodDef realtime_methods[] = {
    {"frame", (PyCFunction)(void (*)(void))realtime_frame, METH_VARARGS | METH_KEYWORDS,
     "frame(camera=None, *, recon=None, moving=False, budget_ms=None, restart=False) -> Frame"},
    {"close", (PyCFunction)realtime_close, METH_NOARGS, "Releases the loop and its device."},
    {"__enter__", self_enter, METH_NOARGS, NULL},
    {"__exit__", (PyCFunction)realtime_exit, METH_VARARGS, NULL},
    {NULL, NULL, 0, NULL}};

static PyGetSetDef realtime_getset[] = {
    {"camera", (getter)realtime_get_camera, NULL, "The last frame's camera (a dict).", NULL},
    {NULL, NULL, NULL, NULL, NULL}};

static PyTypeObject RealtimeType = {
    PyVarObject_HEAD_INIT(NULL, 0).tp_name = "trac0r.Realtime",
    .tp_basicsize = sizeof(RealtimeObject),
    .tp_dealloc = (destructor)realtime_dealloc,
    .tp_flags = Py_TPFLAGS_DEFAULT,
    .tp_doc = "Realtime(scene, *, width=, height=, recon='svgf', ...): the real-time loop.",
    .tp_methods = realtime_methods,
    .tp_getset = realtime_getset,
    .tp_new = realtime_new,
};

/* ---- images: write, read, compare, tonemap ------------------------------------------- */

/* An image argument as a C-contiguous float32 array of shape (h, w, 3) (a (h, w) or
 * (h, w, 1) one is repeated into three channels): a new reference. */
static PyArrayObject *image_arg(PyObject *o, const char *name) {
    PyArrayObject *a = (PyArrayObject *)PyArray_FROMANY(
        o, NPY_FLOAT32, 2, 3, NPY_ARRAY_C_CONTIGUOUS | NPY_ARRAY_ALIGNED | NPY_ARRAY_FORCECAST);
    if (!a) {
        PyObject *t, *v, *tb;
        PyErr_Fetch(&t, &v, &tb);
        PyErr_Format(PyExc_TypeError,
                     "%s: expected a float array of shape (height, width, 3), "
                     "(height, width, 1) or (height, width): %S",
                     name, v ? v : Py_None);
        Py_XDECREF(t);
        Py_XDECREF(v);
        Py_XDECREF(tb);
        return NULL;
    }
    const npy_intp *d = PyArray_DIMS(a);
    const int nd = PyArray_NDIM(a);
    const npy_intp c = nd == 3 ? d[2] : 1;
    if ((c != 1 && c != 3) || d[0] < 1 || d[1] < 1 || d[0] > TR_FILM_MAX_SIDE ||
        d[1] > TR_FILM_MAX_SIDE || (uint64_t)d[0] * (uint64_t)d[1] > TR_FILM_MAX_PIXELS) {
        PyErr_Format(PyExc_ValueError,
                     "%s: expected shape (height, width, 3 or 1) with sides in 1..%u, got %R", name,
                     TR_FILM_MAX_SIDE, PyObject_GetAttrString((PyObject *)a, "shape"));
        Py_DECREF(a);
        return NULL;
    }
    if (c == 3) {
        return a;
    }
    npy_intp dims[3] = {d[0], d[1], 3};
    PyArrayObject *rgb = (PyArrayObject *)PyArray_SimpleNew(3, dims, NPY_FLOAT32);
    if (rgb) {
        const float *src = PyArray_DATA(a);
        float *dst = PyArray_DATA(rgb);
        for (npy_intp i = 0; i < d[0] * d[1]; ++i) {
            dst[3 * i] = dst[3 * i + 1] = dst[3 * i + 2] = src[i];
        }
    }
    Py_DECREF(a);
    return rgb;
}

/* A radiance-only film over an (h, w, 3) array: the sums are the values, one sample each
 * (the counts are allocated; free them). */
static int film_over(PyArrayObject *a, tr_film *f) {
    memset(f, 0, sizeof *f);
    f->height = (uint32_t)PyArray_DIM(a, 0);
    f->width = (uint32_t)PyArray_DIM(a, 1);
    f->sum = PyArray_DATA(a);
    const size_t n = (size_t)f->width * f->height;
    f->count = malloc(n * sizeof *f->count);
    if (!f->count) {
        PyErr_NoMemory();
        return -1;
    }
    for (size_t i = 0; i < n; ++i) {
        f->count[i] = 1u;
    }
    return 0;
}

static int arg_curve(PyObject *o, int *curve) {
    const char *name = NULL;
    if (arg_str(o, "tonemap", &name) < 0) {
        return -1;
    }
    if (name && (*curve = tr_tonemap_curve_parse(name)) < 0) {
        PyErr_Format(PyExc_ValueError, "tonemap: expected clamp or filmic, got '%s'", name);
        return -1;
    }
    return 0;
}

static PyObject *py_write(PyObject *self, PyObject *args, PyObject *kw) {
    (void)self;
    static char *kwlist[] = {"path", "image", "exposure", "tonemap", "half", NULL};
    PyObject *path_obj, *img_obj, *exposure = NULL, *curve_obj = NULL;
    int half = 0;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "OO|$OOp:write", kwlist, &path_obj, &img_obj,
                                     &exposure, &curve_obj, &half)) {
        return NULL;
    }
    double ev = 0.0;
    int curve = TR_TONEMAP_CLAMP;
    if (arg_double(exposure, "exposure", -20.0, 20.0, &ev) < 0 ||
        arg_curve(curve_obj, &curve) < 0) {
        return NULL;
    }
    PyObject *path = arg_path(path_obj, "path");
    if (!path) {
        return NULL;
    }
    const char *p = PyBytes_AS_STRING(path);
    const tr_image_format fmt = tr_image_format_from_path(p);
    if (fmt == TR_IMAGE_UNKNOWN) {
        Py_DECREF(path);
        PyErr_Format(PyExc_ValueError,
                     "path: '%s' has an unknown extension (expected .png, .pfm "
                     "or .exr)",
                     p);
        return NULL;
    }
    PyArrayObject *a = image_arg(img_obj, "image");
    tr_film f;
    if (!a || film_over(a, &f) < 0) {
        Py_XDECREF(a);
        Py_DECREF(path);
        return NULL;
    }
    tr_error err;
    int rc;
    Py_BEGIN_ALLOW_THREADS;
    rc = fmt == TR_IMAGE_EXR ? tr_film_write_exr(&f, p, half, &err)
                             : tr_film_write_curve(&f, p, (float)ev, curve, &err);
    Py_END_ALLOW_THREADS;
    free(f.count);
    Py_DECREF(a);
    Py_DECREF(path);
    if (rc != TR_OK) {
        return raise_tr(&err);
    }
    Py_RETURN_NONE;
}

static PyObject *py_read(PyObject *self, PyObject *args, PyObject *kw) {
    (void)self;
    static char *kwlist[] = {"path", "layer", NULL};
    PyObject *path_obj, *layer_obj = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "O|$O:read", kwlist, &path_obj, &layer_obj)) {
        return NULL;
    }
    const char *layer = NULL;
    if (arg_str(layer_obj, "layer", &layer) < 0) {
        return NULL;
    }
    PyObject *path = arg_path(path_obj, "path");
    if (!path) {
        return NULL;
    }
    const char *p = PyBytes_AS_STRING(path);
    const tr_image_format fmt = tr_image_format_from_path(p);
    if (fmt == TR_IMAGE_UNKNOWN) {
        Py_DECREF(path);
        PyErr_Format(PyExc_ValueError,
                     "path: '%s' has an unknown extension (expected .png, .pfm or .exr)", p);
        return NULL;
    }
    tr_image img = {0};
    tr_error err;
    int rc;
    Py_BEGIN_ALLOW_THREADS;
    rc = fmt == TR_IMAGE_PFM   ? tr_image_read_pfm(&img, p, &err)
         : fmt == TR_IMAGE_PNG ? tr_image_read_png(&img, p, &err)
                               : tr_image_read_exr(&img, p, layer, &err);
    Py_END_ALLOW_THREADS;
    Py_DECREF(path);
    if (rc != TR_OK) {
        return raise_tr(&err);
    }
    OwnerObject *own = owner_new();
    if (!own) {
        tr_image_free(&img);
        return NULL;
    }
    own->mem = img.rgb; /* the reader's memory becomes the array's */
    PyObject *arr = owner_array(own, img.rgb, img.height, img.width, 3, NPY_FLOAT32);
    Py_DECREF(own);
    return arr;
}

static PyObject *py_compare(PyObject *self, PyObject *args, PyObject *kw) {
    (void)self;
    static char *kwlist[] = {"image", "reference", NULL};
    PyObject *ao, *bo;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "OO:compare", kwlist, &ao, &bo)) {
        return NULL;
    }
    PyArrayObject *a = image_arg(ao, "image");
    PyArrayObject *b = a ? image_arg(bo, "reference") : NULL;
    if (!b) {
        Py_XDECREF(a);
        return NULL;
    }
    if (PyArray_DIM(a, 0) != PyArray_DIM(b, 0) || PyArray_DIM(a, 1) != PyArray_DIM(b, 1)) {
        PyErr_Format(PyExc_ValueError, "reference: its size %ldx%ld is not the image's %ldx%ld",
                     (long)PyArray_DIM(b, 1), (long)PyArray_DIM(b, 0), (long)PyArray_DIM(a, 1),
                     (long)PyArray_DIM(a, 0));
        Py_DECREF(a);
        Py_DECREF(b);
        return NULL;
    }
    const uint32_t h = (uint32_t)PyArray_DIM(a, 0), w = (uint32_t)PyArray_DIM(a, 1);
    tr_image_metrics m;
    double ssim;
    const float *pa = PyArray_DATA(a), *pb = PyArray_DATA(b);
    Py_BEGIN_ALLOW_THREADS;
    m = tr_image_compare(pa, pb, (size_t)w * h);
    ssim = tr_ssim(pa, pb, w, h);
    Py_END_ALLOW_THREADS;
    Py_DECREF(a);
    Py_DECREF(b);
    if (isnan(ssim)) {
        return PyErr_NoMemory();
    }
    PyObject *r = PyStructSequence_New(&MetricsType);
    if (!r) {
        return NULL;
    }
    const double v[6] = {m.psnr, m.mse, m.rmse, m.relmse, ssim, m.max_error};
    for (Py_ssize_t i = 0; i < 6; ++i) {
        PyObject *x = PyFloat_FromDouble(v[i]);
        if (!x) {
            Py_DECREF(r);
            return NULL;
        }
        PyStructSequence_SET_ITEM(r, i, x);
    }
    return r;
}

static PyObject *py_tonemap(PyObject *self, PyObject *args, PyObject *kw) {
    (void)self;
    static char *kwlist[] = {"image", "exposure", "tonemap", NULL};
    PyObject *img_obj, *exposure = NULL, *curve_obj = NULL;
    if (!PyArg_ParseTupleAndKeywords(args, kw, "O|$OO:tonemap", kwlist, &img_obj, &exposure,
                                     &curve_obj)) {
        return NULL;
    }
    double ev = 0.0;
    int curve = TR_TONEMAP_CLAMP;
    if (arg_double(exposure, "exposure", -20.0, 20.0, &ev) < 0 ||
        arg_curve(curve_obj, &curve) < 0) {
        return NULL;
    }
    PyArrayObject *a = image_arg(img_obj, "image");
    tr_film f;
    if (!a || film_over(a, &f) < 0) {
        Py_XDECREF(a);
        return NULL;
    }
    npy_intp dims[3] = {(npy_intp)f.height, (npy_intp)f.width, 3};
    PyArrayObject *out = (PyArrayObject *)PyArray_SimpleNew(3, dims, NPY_UINT8);
    tr_error err;
    int rc = TR_OK;
    if (out) {
        void *dst = PyArray_DATA(out);
        Py_BEGIN_ALLOW_THREADS;
        rc = tr_tonemap_film_curve(&f, 0, 0, f.width, f.height, (float)ev, curve, TR_PIXEL_RGB8,
                                   dst, (size_t)f.width * 3, &err);
        Py_END_ALLOW_THREADS;
    }
    free(f.count);
    Py_DECREF(a);
    if (out && rc != TR_OK) {
        Py_DECREF(out);
        return raise_tr(&err);
    }
    return (PyObject *)out;
}

/* ---- the module ---------------------------------------------------------------------- */

static PyMethodDef module_methods[] = {
    {"load", (PyCFunction)(void (*)(void))py_load, METH_VARARGS | METH_KEYWORDS,
     "load(path, *, width=, height=, up='y', scale=1.0, camera=, integrator=, max_depth=, "
     "accel=, light_sampling=, allow_dark=False) -> Scene: a scene file, a model file or "
     "builtin:NAME."},
    {"load_dict", (PyCFunction)(void (*)(void))py_load_dict, METH_VARARGS | METH_KEYWORDS,
     "load_dict(scene, *, base_dir='.', width=, height=, ...) -> Scene: the scene-file format "
     "as a dict."},
    {"render", (PyCFunction)(void (*)(void))py_render, METH_VARARGS | METH_KEYWORDS,
     "render(scene, *, spp=, seed=0, integrator=, max_depth=, device='cpu', threads=0, "
     "sampler=, passes=(), noise_threshold=0, time_limit=0, denoise=False, progress=None) -> "
     "Result"},
    {"write", (PyCFunction)(void (*)(void))py_write, METH_VARARGS | METH_KEYWORDS,
     "write(path, image, *, exposure=0, tonemap='clamp', half=False): PNG, PFM or EXR by the "
     "extension."},
    {"read", (PyCFunction)(void (*)(void))py_read, METH_VARARGS | METH_KEYWORDS,
     "read(path, *, layer=None) -> array (height, width, 3): PFM, PNG (values in [0, 1]) or "
     "EXR."},
    {"compare", (PyCFunction)(void (*)(void))py_compare, METH_VARARGS | METH_KEYWORDS,
     "compare(image, reference) -> Metrics (psnr, mse, rmse, relmse, ssim, max_error)"},
    {"tonemap", (PyCFunction)(void (*)(void))py_tonemap, METH_VARARGS | METH_KEYWORDS,
     "tonemap(image, *, exposure=0, tonemap='clamp') -> uint8 array (height, width, 3), sRGB"},
    {NULL, NULL, 0, NULL}};

static struct PyModuleDef module_def = {
    PyModuleDef_HEAD_INIT,
    "trac0r",
    "trac0r: a path tracer (libtrac0r) rendering into NumPy arrays. See docs/python.md.",
    -1,
    module_methods,
    NULL,
    NULL,
    NULL,
    NULL};

static int add_names(PyObject *m, const char *attr, const char *const *names, size_t count) {
    PyObject *t = PyTuple_New((Py_ssize_t)count);
    for (size_t i = 0; t && i < count; ++i) {
        PyObject *s = PyUnicode_FromString(names[i]);
        if (!s) {
            Py_CLEAR(t);
            break;
        }
        PyTuple_SET_ITEM(t, (Py_ssize_t)i, s);
    }
    return t ? PyModule_AddObject(m, attr, t) : -1;
}

static int add_exceptions(PyObject *m) {
    tr_py_error = PyErr_NewExceptionWithDoc(
        "trac0r.Error",
        "A failure the library reported: .status is its tr_status code, .status_name the "
        "code's name (TR_STATUS_IO), str() its message.",
        NULL, NULL);
    if (!tr_py_error || PyModule_AddObject(m, "Error", Py_NewRef(tr_py_error)) < 0) {
        return -1;
    }
    for (size_t i = 0; i < sizeof status_excs / sizeof *status_excs; ++i) {
        const status_exc_def *d = &status_excs[i];
        PyObject *extra = d->builtin == 1   ? PyExc_ValueError
                          : d->builtin == 2 ? PyExc_MemoryError
                          : d->builtin == 3 ? PyExc_LookupError
                                            : NULL;
        PyObject *bases =
            extra ? PyTuple_Pack(2, tr_py_error, extra) : PyTuple_Pack(1, tr_py_error);
        char qual[64];
        snprintf(qual, sizeof qual, "trac0r.%s", d->name);
        PyObject *e = bases ? PyErr_NewException(qual, bases, NULL) : NULL;
        Py_XDECREF(bases);
        if (!e || PyModule_AddObject(m, d->name, Py_NewRef(e)) < 0) {
            Py_XDECREF(e);
            return -1;
        }
        tr_py_status_exc[d->code] = e;
    }
    return 0;
}

PyMODINIT_FUNC PyInit_trac0r(void);
PyMODINIT_FUNC PyInit_trac0r(void) {
    import_array();
    if (PyType_Ready(&OwnerType) < 0 || PyType_Ready(&SceneType) < 0 ||
        PyType_Ready(&SessionType) < 0 || PyType_Ready(&RealtimeType) < 0) {
        return NULL;
    }
    if ((!ResultType.tp_name && PyStructSequence_InitType2(&ResultType, &result_desc) < 0) ||
        (!FrameType.tp_name && PyStructSequence_InitType2(&FrameType, &frame_desc) < 0) ||
        (!MetricsType.tp_name && PyStructSequence_InitType2(&MetricsType, &metrics_desc) < 0) ||
        (!ProgressType.tp_name && PyStructSequence_InitType2(&ProgressType, &progress_desc) < 0)) {
        return NULL;
    }
    PyObject *m = PyModule_Create(&module_def);
    if (!m) {
        return NULL;
    }
    size_t count;
    const char *const *names = tr_integrator_names(&count);
    static const char *const recon[] = {"off", "accumulate", "bilateral", "atrous", "svgf"};
    static const char *const passes[] = {"albedo",   "normal", "depth",   "id",
                                         "variance", "direct", "emission"};
    if (add_exceptions(m) < 0 || PyModule_AddStringConstant(m, "__version__", TRAC0R_VERSION) < 0 ||
        add_names(m, "INTEGRATORS", names, count) < 0 || add_names(m, "RECON", recon, 5) < 0 ||
        add_names(m, "PASSES", passes, 7) < 0 ||
        PyModule_AddObject(m, "Scene", Py_NewRef((PyObject *)&SceneType)) < 0 ||
        PyModule_AddObject(m, "Session", Py_NewRef((PyObject *)&SessionType)) < 0 ||
        PyModule_AddObject(m, "Realtime", Py_NewRef((PyObject *)&RealtimeType)) < 0 ||
        PyModule_AddObject(m, "Result", Py_NewRef((PyObject *)&ResultType)) < 0 ||
        PyModule_AddObject(m, "Frame", Py_NewRef((PyObject *)&FrameType)) < 0 ||
        PyModule_AddObject(m, "Metrics", Py_NewRef((PyObject *)&MetricsType)) < 0 ||
        PyModule_AddObject(m, "Progress", Py_NewRef((PyObject *)&ProgressType)) < 0) {
        Py_DECREF(m);
        return NULL;
    }
    return m;
}
