/* exr.c - OpenEXR output and input through OpenEXRCore, OpenEXR's C API.
 *
 * One scanline part, ZIP-compressed (16 lines a chunk), channels in the sorted order the
 * format wants: B, G, R (the mean radiance), then the passes as layers, albedo.{B,G,R},
 * depth.Z, id (a UINT channel), normal.{X,Y,Z}, variance.{B,G,R} (of the mean radiance,
 * from the film's sums of squares: tr_film_variance). The file goes through outfile.h: the
 * library writes into the temporary file by a write callback and the commit renames it. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <openexr.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "util/infile.h"
#include "trac0r/image.h"
#include "trac0r/outfile.h"

/* The first message the library reported on a context (it reports through a callback). */
typedef struct exr_io {
    int fd;
    char msg[256];
} exr_io;

static void on_exr_error(exr_const_context_t ctxt, exr_result_t code, const char *msg) {
    exr_io *io = NULL;
    if (exr_get_user_data(ctxt, (void **)&io) == EXR_ERR_SUCCESS && io && !io->msg[0]) {
        snprintf(io->msg, sizeof io->msg, "%s (%s)", msg, exr_get_error_code_as_string(code));
    }
}

static int64_t write_at(exr_const_context_t ctxt, void *user, const void *buf, uint64_t size,
                        uint64_t offset, exr_stream_error_func_ptr_t error_cb) {
    const exr_io *io = user;
    const unsigned char *p = buf;
    uint64_t done = 0;
    while (done < size) {
        const ssize_t n = pwrite(io->fd, p + done, size - done, (off_t)(offset + done));
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n <= 0) {
            error_cb(ctxt, EXR_ERR_WRITE_IO, "write failed: %s", strerror(errno));
            return -1;
        }
        done += (uint64_t)n;
    }
    return (int64_t)size;
}

/* IEEE binary16 from binary32, rounding to nearest even; overflow gives infinity. */
static uint16_t float_to_half(float f) {
    uint32_t x;
    memcpy(&x, &f, sizeof x);
    const uint16_t sign = (uint16_t)((x >> 16) & 0x8000u);
    const uint32_t mag = x & 0x7fffffffu;
    if (mag >= 0x7f800000u) { /* inf or NaN (kept a quiet NaN) */
        return (uint16_t)(sign | 0x7c00u | (mag > 0x7f800000u ? 0x200u : 0u));
    }
    if (mag >= 0x477ff000u) { /* rounds to beyond 65504 */
        return (uint16_t)(sign | 0x7c00u);
    }
    if (mag < 0x38800000u) { /* a half subnormal or zero: scale by 2^24 and round */
        const float v = fabsf(f) * 16777216.0f;
        return (uint16_t)(sign | (uint16_t)lrintf(v));
    }
    /* Rebias the exponent (127 -> 15) and round the 13 dropped mantissa bits. */
    uint32_t h = (mag - 0x38000000u) >> 13;
    const uint32_t rest = mag & 0x1fffu;
    if (rest > 0x1000u || (rest == 0x1000u && (h & 1u))) {
        ++h;
    }
    return (uint16_t)(sign | h);
}

/* One output channel: its name and where its value for pixel i comes from. */
typedef struct exr_channel {
    const char *name;
    uint32_t pass; /* 0: radiance, else the TR_PASS_* bit */
    int component; /* 0..2 */
    int is_uint;   /* the primitive id */
} exr_channel;

static const exr_channel all_channels[] = {
    {"B", 0, 2, 0},
    {"G", 0, 1, 0},
    {"R", 0, 0, 0},
    {"albedo.B", TR_PASS_ALBEDO, 2, 0},
    {"albedo.G", TR_PASS_ALBEDO, 1, 0},
    {"albedo.R", TR_PASS_ALBEDO, 0, 0},
    {"depth.Z", TR_PASS_DEPTH, 0, 0},
    {"id", TR_PASS_PRIM, 0, 1},
    {"normal.X", TR_PASS_NORMAL, 0, 0},
    {"normal.Y", TR_PASS_NORMAL, 1, 0},
    {"normal.Z", TR_PASS_NORMAL, 2, 0},
    {"variance.B", TR_PASS_VARIANCE, 2, 0},
    {"variance.G", TR_PASS_VARIANCE, 1, 0},
    {"variance.R", TR_PASS_VARIANCE, 0, 0},
};
#define EXR_MAX_CHANNELS (sizeof all_channels / sizeof all_channels[0])

/* What one file holds: the passes of `f`, the radiance of `rgb` (f itself, or the
 * denoised image of f). */
typedef struct exr_source {
    const tr_film *f, *rgb;
} exr_source;

/* The value of channel ch at pixel i: a pass's or the radiance's mean (sum / count, 0
 * where no sample landed), or the variance of the mean radiance. */
static float channel_mean(const exr_source *src, const exr_channel *ch, size_t i) {
    if (ch->pass == TR_PASS_VARIANCE) {
        return tr_film_variance(src->f, i, ch->component);
    }
    const tr_film *f = ch->pass == 0u ? src->rgb : src->f;
    const uint32_t n = f->count[i];
    if (n == 0u) {
        return 0.0f;
    }
    const float inv = 1.0f / (float)n;
    switch (ch->pass) {
    case TR_PASS_ALBEDO:
        return f->albedo[3 * i + (size_t)ch->component] * inv;
    case TR_PASS_NORMAL:
        return f->normal[3 * i + (size_t)ch->component] * inv;
    case TR_PASS_DEPTH:
        return f->depth[i] * inv;
    default:
        return f->sum[3 * i + (size_t)ch->component] * inv;
    }
}

static int exr_fail(tr_error *err, const char *path, const exr_io *io, exr_result_t rc) {
    return tr_error_set(err, rc == EXR_ERR_OUT_OF_MEMORY ? TR_STATUS_OUT_OF_MEMORY : TR_STATUS_IO,
                        "%s: OpenEXR: %s", path,
                        io->msg[0] ? io->msg : exr_get_default_error_message(rc));
}

static exr_result_t write_chunks(exr_context_t ctxt, const exr_source *src, const exr_channel **chs,
                                 int nch, int half, unsigned char *buf) {
    const tr_film *f = src->f;
    int32_t lines = 1;
    exr_result_t rc = exr_get_scanlines_per_chunk(ctxt, 0, &lines);
    exr_encode_pipeline_t enc;
    memset(&enc, 0, sizeof enc);
    int started = 0;
    const size_t w = f->width;
    for (uint32_t y0 = 0; rc == EXR_ERR_SUCCESS && y0 < f->height; y0 += (uint32_t)lines) {
        const uint32_t y1 = y0 + (uint32_t)lines < f->height ? y0 + (uint32_t)lines : f->height;
        const size_t plane = w * (y1 - y0) * 4; /* bytes a channel's lines take at most */
        exr_chunk_info_t cinfo;
        rc = exr_write_scanline_chunk_info(ctxt, 0, (int)y0, &cinfo);
        if (rc == EXR_ERR_SUCCESS) {
            rc = started ? exr_encoding_update(ctxt, 0, &cinfo, &enc)
                         : exr_encoding_initialize(ctxt, 0, &cinfo, &enc);
            started = 1;
        }
        if (rc != EXR_ERR_SUCCESS) {
            break;
        }
        for (int c = 0; c < nch; ++c) {
            /* enc.channels is in the file's (sorted) order, as chs is. */
            unsigned char *dst = buf + (size_t)c * plane;
            const int bytes = chs[c]->is_uint || !half ? 4 : 2;
            for (uint32_t y = y0; y < y1; ++y) {
                for (size_t x = 0; x < w; ++x) {
                    const size_t i = (size_t)y * w + x;
                    const size_t o = ((size_t)(y - y0) * w + x) * (size_t)bytes;
                    if (chs[c]->is_uint) {
                        memcpy(dst + o, &f->prim[i], 4);
                    } else if (half) {
                        const uint16_t h = float_to_half(channel_mean(src, chs[c], i));
                        memcpy(dst + o, &h, 2);
                    } else {
                        const float v = channel_mean(src, chs[c], i);
                        memcpy(dst + o, &v, 4);
                    }
                }
            }
            exr_coding_channel_info_t *ci = &enc.channels[c];
            ci->encode_from_ptr = dst;
            ci->user_bytes_per_element = (int16_t)bytes;
            ci->user_data_type =
                chs[c]->is_uint ? EXR_PIXEL_UINT : (half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT);
            ci->user_pixel_stride = bytes;
            ci->user_line_stride = (int32_t)(w * (size_t)bytes);
        }
        if (y0 == 0) {
            rc = exr_encoding_choose_default_routines(ctxt, 0, &enc);
        }
        if (rc == EXR_ERR_SUCCESS) {
            rc = exr_encoding_run(ctxt, 0, &enc);
        }
    }
    if (started) {
        const exr_result_t d = exr_encoding_destroy(ctxt, &enc);
        rc = rc == EXR_ERR_SUCCESS ? d : rc;
    }
    return rc;
}

int tr_film_write_exr(const tr_film *f, const char *path, int half, tr_error *err) {
    return tr_film_write_exr_rgb(f, f, path, half, err);
}

int tr_film_write_exr_rgb(const tr_film *f, const tr_film *rgb, const char *path, int half,
                          tr_error *err) {
    if (rgb->width != f->width || rgb->height != f->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "%s: the radiance is %ux%u but the passes %ux%u", path, rgb->width,
                            rgb->height, f->width, f->height);
    }
    const exr_source src = {f, rgb};
    const exr_channel *chs[EXR_MAX_CHANNELS];
    int nch = 0;
    for (size_t k = 0; k < EXR_MAX_CHANNELS; ++k) {
        if (all_channels[k].pass == 0u || (f->passes & all_channels[k].pass) != 0u) {
            chs[nch++] = &all_channels[k];
        }
    }
    unsigned char *buf = malloc((size_t)nch * f->width * 16u * 4u);
    if (!buf) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    tr_outfile *out = tr_outfile_create(path, err);
    if (!out) {
        free(buf);
        return TR_ERR;
    }
    exr_io io = {fileno(tr_outfile_stream(out)), ""};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.user_data = &io;
    init.write_fn = write_at;
    init.error_handler_fn = on_exr_error;
    exr_context_t ctxt = NULL;
    exr_result_t rc = exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, &init);
    int part = 0;
    if (rc == EXR_ERR_SUCCESS) {
        rc = exr_add_part(ctxt, "rgb", EXR_STORAGE_SCANLINE, &part);
    }
    if (rc == EXR_ERR_SUCCESS) {
        rc = exr_initialize_required_attr_simple(ctxt, part, (int32_t)f->width, (int32_t)f->height,
                                                 EXR_COMPRESSION_ZIP);
    }
    for (int c = 0; c < nch && rc == EXR_ERR_SUCCESS; ++c) {
        const exr_pixel_type_t t =
            chs[c]->is_uint ? EXR_PIXEL_UINT : (half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT);
        /* The hint lossy codecs read: colours are perceived logarithmically, the
         * geometric passes are plain numbers. */
        const exr_perceptual_treatment_t p = chs[c]->pass == 0u || chs[c]->pass == TR_PASS_ALBEDO
                                                 ? EXR_PERCEPTUALLY_LOGARITHMIC
                                                 : EXR_PERCEPTUALLY_LINEAR;
        rc = exr_add_channel(ctxt, part, chs[c]->name, t, p, 1, 1);
    }
    if (rc == EXR_ERR_SUCCESS) {
        rc = exr_write_header(ctxt);
    }
    if (rc == EXR_ERR_SUCCESS) {
        rc = write_chunks(ctxt, &src, chs, nch, half, buf);
    }
    if (ctxt) {
        /* exr_finish writes the chunk offset table. */
        const exr_result_t fin = exr_finish(&ctxt);
        rc = rc == EXR_ERR_SUCCESS ? fin : rc;
    }
    free(buf);
    if (rc != EXR_ERR_SUCCESS) {
        tr_outfile_abort(out);
        return exr_fail(err, path, &io, rc);
    }
    return tr_outfile_commit(out, err);
}

/* Reads the channels named names[0..2] (as floats, whatever their type in the file) of
 * part 0 into img. */
static int read_channels(exr_context_t ctxt, const char *path, exr_io *io, const char *names[3],
                         tr_image *img, tr_error *err) {
    exr_attr_box2i_t dw;
    exr_result_t rc = exr_get_data_window(ctxt, 0, &dw);
    if (rc != EXR_ERR_SUCCESS) {
        return exr_fail(err, path, io, rc);
    }
    const int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
    if (w < 1 || h < 1 || w > TR_FILM_MAX_SIDE || h > TR_FILM_MAX_SIDE ||
        w * h > TR_FILM_MAX_PIXELS) {
        return tr_error_set(err, TR_STATUS_LIMIT, "%s: image size %lldx%lld out of range", path,
                            (long long)w, (long long)h);
    }
    exr_storage_t storage;
    if (exr_get_storage(ctxt, 0, &storage) != EXR_ERR_SUCCESS || storage != EXR_STORAGE_SCANLINE) {
        return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                            "%s: only scanline EXR images are read (this one is tiled or deep)",
                            path);
    }
    /* Every channel's bytes a pixel, for checking each chunk against what its lines need;
     * subsampled channels (stored at every 2nd pixel or line, say) are refused: this reader
     * places one value per pixel. */
    const exr_attr_chlist_t *list = NULL;
    exr_compression_t comp = EXR_COMPRESSION_NONE;
    if (exr_get_channels(ctxt, 0, &list) != EXR_ERR_SUCCESS || !list ||
        exr_get_compression(ctxt, 0, &comp) != EXR_ERR_SUCCESS) {
        return tr_error_set(err, TR_STATUS_PARSE, "%s: unreadable channel list", path);
    }
    uint64_t pixel_bytes = 0;
    for (int c = 0; c < list->num_channels; ++c) {
        const exr_attr_chlist_entry_t *e = &list->entries[c];
        if (e->x_sampling != 1 || e->y_sampling != 1) {
            return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                                "%s: channel %s is subsampled (%dx%d); only full-resolution "
                                "channels are read",
                                path, e->name.str, e->x_sampling, e->y_sampling);
        }
        pixel_bytes += e->pixel_type == EXR_PIXEL_HALF ? 2u : 4u;
    }
    img->width = (uint32_t)w;
    img->height = (uint32_t)h;
    img->rgb = calloc((size_t)(w * h * 3), sizeof *img->rgb);
    if (!img->rgb) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    int32_t lines = 1;
    rc = exr_get_scanlines_per_chunk(ctxt, 0, &lines);
    exr_decode_pipeline_t dec;
    memset(&dec, 0, sizeof dec);
    int started = 0;
    for (int64_t y = 0; rc == EXR_ERR_SUCCESS && y < h; y += lines) {
        exr_chunk_info_t cinfo;
        rc = exr_read_scanline_chunk_info(ctxt, 0, (int)(dw.min.y + y), &cinfo);
        /* The chunk must hold its lines whole: one whose data is short (stored, or
         * decompressing to less) would leave pixels of memory never written. */
        if (rc == EXR_ERR_SUCCESS) {
            const int64_t top = cinfo.start_y < dw.min.y ? dw.min.y : cinfo.start_y;
            const int64_t end = (int64_t)cinfo.start_y + cinfo.height;
            const uint64_t need = (uint64_t)cinfo.width * (uint64_t)cinfo.height * pixel_bytes;
            if (cinfo.width != w || cinfo.height < 1 || cinfo.height > lines || top >= end ||
                end - 1 > dw.max.y || cinfo.unpacked_size != need ||
                (comp == EXR_COMPRESSION_NONE && cinfo.packed_size != need)) {
                free(img->rgb);
                memset(img, 0, sizeof *img);
                if (started) {
                    exr_decoding_destroy(ctxt, &dec);
                }
                return tr_error_set(err, TR_STATUS_PARSE,
                                    "%s: the chunk of line %lld holds %llu bytes where its %d "
                                    "lines need %llu",
                                    path, (long long)cinfo.start_y,
                                    (unsigned long long)cinfo.packed_size, (int)cinfo.height,
                                    (unsigned long long)need);
            }
        }
        if (rc == EXR_ERR_SUCCESS) {
            rc = started ? exr_decoding_update(ctxt, 0, &cinfo, &dec)
                         : exr_decoding_initialize(ctxt, 0, &cinfo, &dec);
            started = 1;
        }
        if (rc != EXR_ERR_SUCCESS) {
            break;
        }
        /* The chunk's first line may be above the data window's (y is aligned). */
        const int64_t first = (int64_t)cinfo.start_y - dw.min.y;
        for (int c = 0; c < dec.channel_count; ++c) {
            exr_coding_channel_info_t *ci = &dec.channels[c];
            ci->decode_to_ptr = NULL;
            for (int k = 0; k < 3; ++k) {
                if (strcmp(ci->channel_name, names[k]) == 0) {
                    ci->decode_to_ptr = (uint8_t *)(img->rgb + (size_t)(first * w * 3) + k);
                    ci->user_bytes_per_element = 4;
                    ci->user_data_type = EXR_PIXEL_FLOAT;
                    ci->user_pixel_stride = 12;
                    ci->user_line_stride = (int32_t)(w * 12);
                }
            }
        }
        if (y == 0) {
            rc = exr_decoding_choose_default_routines(ctxt, 0, &dec);
        }
        if (rc == EXR_ERR_SUCCESS) {
            rc = exr_decoding_run(ctxt, 0, &dec);
        }
        y = first; /* continue from the chunk's real first line */
    }
    if (started) {
        const exr_result_t d = exr_decoding_destroy(ctxt, &dec);
        rc = rc == EXR_ERR_SUCCESS ? d : rc;
    }
    if (rc != EXR_ERR_SUCCESS) {
        /* Freed here rather than by tr_image_free: image.c calls this file (the writer's
         * dispatch by extension), so this file calls nothing of image.c's. */
        free(img->rgb);
        memset(img, 0, sizeof *img);
        return exr_fail(err, path, io, rc);
    }
    return TR_OK;
}

int tr_image_read_exr(tr_image *img, const char *path, const char *layer, tr_error *err) {
    memset(img, 0, sizeof *img);
    exr_io io = {-1, ""};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.user_data = &io;
    init.error_handler_fn = on_exr_error;
    /* Regular files only: OpenEXR's own open() would block on a FIFO. */
    if (tr_infile_check(path, err) != TR_OK) {
        return TR_ERR;
    }
    exr_context_t ctxt = NULL;
    exr_result_t rc = exr_start_read(&ctxt, path, &init);
    if (rc != EXR_ERR_SUCCESS) {
        exr_finish(&ctxt);
        return tr_error_set(err, rc == EXR_ERR_FILE_ACCESS ? TR_STATUS_IO : TR_STATUS_PARSE,
                            "%s: not a readable EXR image: %s", path,
                            io.msg[0] ? io.msg : exr_get_default_error_message(rc));
    }
    const exr_attr_chlist_t *list = NULL;
    rc = exr_get_channels(ctxt, 0, &list);
    /* R, G, B of the layer; a layer of X, Y, Z (normal) or a lone channel (depth.Z, Y)
     * fills all three from what it has. */
    static const char *const sets[3][3] = {{"R", "G", "B"}, {"X", "Y", "Z"}, {"Z", "Z", "Z"}};
    char full[3][128];
    const char *names[3] = {NULL, NULL, NULL};
    for (int s = 0; s < 3 && rc == EXR_ERR_SUCCESS && !names[0]; ++s) {
        int found = 0;
        for (int k = 0; k < 3; ++k) {
            snprintf(full[k], sizeof full[k], "%s%s%s", layer ? layer : "", layer ? "." : "",
                     sets[s][k]);
            for (int c = 0; list && c < list->num_channels; ++c) {
                found += strcmp(list->entries[c].name.str, full[k]) == 0;
            }
        }
        if (found == 3) {
            names[0] = full[0];
            names[1] = full[1];
            names[2] = full[2];
        }
    }
    int status = TR_OK;
    if (rc != EXR_ERR_SUCCESS) {
        status = exr_fail(err, path, &io, rc);
    } else if (!names[0]) {
        status = tr_error_set(err, TR_STATUS_NOT_FOUND, "%s: no %s%s%s channels in the image", path,
                              layer ? layer : "", layer ? "." : "", "R, G, B");
    } else {
        status = read_channels(ctxt, path, &io, names, img, err);
    }
    exr_finish(&ctxt);
    return status;
}
