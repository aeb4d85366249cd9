/* image.c - PNG (libpng) and PFM output, written to a temporary file and renamed. */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "trac0r/image.h"
#include "util/infile.h"
#include "trac0r/outfile.h"
#include "trac0r/post.h"

tr_image_format tr_image_format_from_path(const char *path) {
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash)) {
        return TR_IMAGE_UNKNOWN;
    }
    if (strcasecmp(dot, ".png") == 0) {
        return TR_IMAGE_PNG;
    }
    if (strcasecmp(dot, ".pfm") == 0) {
        return TR_IMAGE_PFM;
    }
    if (strcasecmp(dot, ".exr") == 0) {
        return TR_IMAGE_EXR;
    }
    return TR_IMAGE_UNKNOWN;
}

int tr_image_check_writable(const char *path, tr_error *err) {
    return tr_outfile_check(path, err);
}

/* libpng's errors, kept for the one-line message instead of printed to stderr. */
typedef struct png_failure {
    char msg[128];
    int errnum; /* errno when libpng gave up: a failed fwrite() says why */
} png_failure;

static void png_on_error(png_structp png, png_const_charp msg) {
    png_failure *pf = png_get_error_ptr(png);
    pf->errnum = errno;
    snprintf(pf->msg, sizeof pf->msg, "%s", msg ? msg : "unknown error");
    png_longjmp(png, 1);
}

static void png_on_warning(png_structp png, png_const_charp msg) {
    (void)png;
    (void)msg;
}

static int write_png_rows(FILE *fp, const tr_film *f, float exposure, uint8_t *row,
                          png_failure *pf) {
    png_structp png =
        png_create_write_struct(PNG_LIBPNG_VER_STRING, pf, png_on_error, png_on_warning);
    if (!png) {
        snprintf(pf->msg, sizeof pf->msg, "out of memory");
        return TR_ERR;
    }
    png_infop info = png_create_info_struct(png);
    if (!info || setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return TR_ERR;
    }
    png_init_io(png, fp);
    png_set_IHDR(png, info, f->width, f->height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_write_info(png, info);
    for (uint32_t y = 0; y < f->height; ++y) {
        /* The viewer's transform too (post.h), so a PNG holds the bytes it showed. */
        if (tr_tonemap_film(f, 0, y, f->width, 1, exposure, TR_PIXEL_RGB8, row,
                            (size_t)f->width * 3, NULL) != TR_OK) {
            png_destroy_write_struct(&png, &info);
            snprintf(pf->msg, sizeof pf->msg, "tone mapping failed");
            return TR_ERR;
        }
        png_write_row(png, row);
    }
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    return TR_OK;
}

int tr_film_write_png(const tr_film *f, const char *path, float exposure, tr_error *err) {
    uint8_t *row = malloc((size_t)f->width * 3);
    if (!row) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "%.200s: out of memory", path);
    }
    tr_outfile *t = tr_outfile_create(path, err);
    if (!t) {
        free(row);
        return TR_ERR;
    }
    png_failure pf = {"", 0};
    int ok = write_png_rows(tr_outfile_stream(t), f, exposure, row, &pf) == TR_OK;
    free(row);
    if (!ok) {
        tr_outfile_abort(t);
        /* A write that failed says why through errno (a full disk, EFBIG); other
         * failures through libpng's message. */
        if (pf.errnum) {
            return tr_error_set(err, tr_status_from_errno(pf.errnum), "%.200s: write failed: %s",
                                path, strerror(pf.errnum));
        }
        return tr_error_set(err, TR_STATUS_IO, "%.200s: PNG encoding failed: %s", path, pf.msg);
    }
    return tr_outfile_commit(t, err);
}

int tr_film_write_pfm(const tr_film *f, const char *path, tr_error *err) {
    float *row = malloc((size_t)f->width * 3 * sizeof *row);
    if (!row) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "%.200s: out of memory", path);
    }
    tr_outfile *t = tr_outfile_create(path, err);
    if (!t) {
        free(row);
        return TR_ERR;
    }
    FILE *fp = tr_outfile_stream(t);
    /* A negative scale marks little-endian data; rows go bottom to top. */
    int ok = fprintf(fp, "PF\n%u %u\n-1.0\n", f->width, f->height) > 0;
    for (uint32_t yy = 0; ok && yy < f->height; ++yy) {
        uint32_t y = f->height - 1 - yy;
        for (uint32_t x = 0; x < f->width; ++x) {
            tr_vec3 c = tr_film_pixel(f, x, y);
            row[3 * x] = c.x;
            row[3 * x + 1] = c.y;
            row[3 * x + 2] = c.z;
        }
        ok = fwrite(row, sizeof *row, (size_t)f->width * 3, fp) == (size_t)f->width * 3;
    }
    free(row);
    if (!ok) {
        int e = errno;
        tr_outfile_abort(t);
        return tr_error_set(err, tr_status_from_errno(e), "%.200s: write failed: %s", path,
                            strerror(e));
    }
    return tr_outfile_commit(t, err);
}

int tr_film_write(const tr_film *f, const char *path, float exposure, tr_error *err) {
    switch (tr_image_format_from_path(path)) {
    case TR_IMAGE_PNG:
        return tr_film_write_png(f, path, exposure, err);
    case TR_IMAGE_PFM:
        return tr_film_write_pfm(f, path, err);
    case TR_IMAGE_EXR:
        return tr_film_write_exr(f, path, 0, err);
    default:
        return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                            "%.200s: unknown image extension (expected .png, .pfm or .exr)", path);
    }
}

int tr_film_write_curve(const tr_film *f, const char *path, float exposure, int curve,
                        tr_error *err) {
    if (curve == TR_TONEMAP_CLAMP || tr_image_format_from_path(path) != TR_IMAGE_PNG) {
        return tr_film_write(f, path, exposure, err);
    }
    tr_film disp;
    if (tr_tonemap_display_film(f, exposure, curve, &disp, err) != TR_OK) {
        return TR_ERR;
    }
    const int rc = tr_film_write(&disp, path, 0.0f, err); /* the exposure is applied */
    tr_film_free(&disp);
    return rc;
}

void tr_image_free(tr_image *img) {
    free(img->rgb);
    memset(img, 0, sizeof *img);
}

/* Reads one whitespace-delimited header token of at most n-1 characters. */
static int pfm_token(FILE *fp, char *buf, size_t n) {
    int c;
    do {
        c = fgetc(fp);
    } while (c != EOF && isspace(c));
    size_t len = 0;
    while (c != EOF && !isspace(c) && len + 1 < n) {
        buf[len++] = (char)c;
        c = fgetc(fp);
    }
    buf[len] = '\0';
    /* Exactly one whitespace byte separates the header from the data; it was consumed. */
    return len > 0 && c != EOF && isspace(c) ? TR_OK : TR_ERR;
}

int tr_image_read_pfm(tr_image *img, const char *path, tr_error *err) {
    memset(img, 0, sizeof *img);
    FILE *fp = tr_infile_open(path, NULL, err); /* regular files only: a FIFO would block */
    if (!fp) {
        return TR_ERR;
    }
    char magic[8], ws[32], hs[32], ss[64];
    if (pfm_token(fp, magic, sizeof magic) || pfm_token(fp, ws, sizeof ws) ||
        pfm_token(fp, hs, sizeof hs) || pfm_token(fp, ss, sizeof ss)) {
        fclose(fp);
        return tr_error_set(err, TR_STATUS_PARSE, "%.200s: not a PFM file (truncated header)",
                            path);
    }
    int channels = strcmp(magic, "PF") == 0 ? 3 : strcmp(magic, "Pf") == 0 ? 1 : 0;
    char *end;
    long w = strtol(ws, &end, 10);
    int bad = *end != '\0';
    long h = strtol(hs, &end, 10);
    bad |= *end != '\0';
    double scale = strtod(ss, &end);
    bad |= *end != '\0' || scale == 0.0 || !isfinite(scale);
    if (!channels || bad || w <= 0 || h <= 0) {
        fclose(fp);
        return tr_error_set(err, TR_STATUS_PARSE,
                            "%.200s: not a supported PFM file (header '%s %s %s %s')", path, magic,
                            ws, hs, ss);
    }
    if (w > (long)TR_FILM_MAX_SIDE || h > (long)TR_FILM_MAX_SIDE ||
        (uint64_t)w * (uint64_t)h > TR_FILM_MAX_PIXELS) {
        fclose(fp);
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "%.200s: PFM size %ldx%ld is more than %u per side or %u pixels", path,
                            w, h, TR_FILM_MAX_SIDE, TR_FILM_MAX_PIXELS);
    }
    if (scale > 0.0) {
        fclose(fp);
        return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                            "%.200s: big-endian PFM files are not supported", path);
    }
    size_t n = (size_t)w * (size_t)h;
    float *data = malloc(n * (size_t)channels * sizeof *data);
    img->rgb = malloc(n * 3 * sizeof *img->rgb);
    if (!data || !img->rgb) {
        free(data);
        fclose(fp);
        tr_image_free(img);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "%.200s: out of memory", path);
    }
    size_t got = fread(data, sizeof *data, n * (size_t)channels, fp);
    fclose(fp);
    if (got != n * (size_t)channels) {
        free(data);
        tr_image_free(img);
        return tr_error_set(err, TR_STATUS_PARSE, "%.200s: truncated PFM data (%zu of %zu floats)",
                            path, got, n * (size_t)channels);
    }
    img->width = (uint32_t)w;
    img->height = (uint32_t)h;
    for (size_t y = 0; y < (size_t)h; ++y) {
        const float *src = data + ((size_t)h - 1 - y) * (size_t)w * (size_t)channels;
        for (size_t x = 0; x < (size_t)w; ++x) {
            for (int c = 0; c < 3; ++c) {
                img->rgb[(y * (size_t)w + x) * 3 + (size_t)c] =
                    src[x * (size_t)channels + (channels == 3 ? (size_t)c : 0)];
            }
        }
    }
    free(data);
    return TR_OK;
}

int tr_image_read_png(tr_image *img, const char *path, tr_error *err) {
    memset(img, 0, sizeof *img);
    png_image p;
    memset(&p, 0, sizeof p);
    p.version = PNG_IMAGE_VERSION;
    /* Opened here rather than by libpng, so that a missing file is told apart by errno,
     * and a FIFO or device is refused before a read could block. */
    FILE *fp = tr_infile_open(path, NULL, err);
    if (!fp) {
        return TR_ERR;
    }
    if (!png_image_begin_read_from_stdio(&p, fp)) {
        fclose(fp);
        return tr_error_set(err, TR_STATUS_PARSE, "%.200s: cannot read PNG: %s", path, p.message);
    }
    p.format = PNG_FORMAT_RGB;
    /* The same caps as for PFM files and films, checked on the header before libpng
     * decodes (and this allocates) what the header claims. */
    if (p.width == 0 || p.height == 0 || p.width > TR_FILM_MAX_SIDE ||
        p.height > TR_FILM_MAX_SIDE || (uint64_t)p.width * p.height > TR_FILM_MAX_PIXELS) {
        png_image_free(&p);
        fclose(fp);
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "%.200s: PNG size %ux%u is more than %u per side or %u pixels", path,
                            p.width, p.height, TR_FILM_MAX_SIDE, TR_FILM_MAX_PIXELS);
    }
    size_t n = (size_t)p.width * p.height;
    uint8_t *buf = malloc(PNG_IMAGE_SIZE(p));
    img->rgb = malloc(n * 3 * sizeof *img->rgb);
    if (!buf || !img->rgb) {
        free(buf);
        png_image_free(&p);
        fclose(fp);
        tr_image_free(img);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "%.200s: out of memory", path);
    }
    const int decoded = png_image_finish_read(&p, NULL, buf, 0, NULL);
    fclose(fp);
    if (!decoded) {
        free(buf);
        tr_image_free(img);
        return tr_error_set(err, TR_STATUS_PARSE, "%.200s: cannot decode PNG: %s", path, p.message);
    }
    img->width = p.width;
    img->height = p.height;
    for (size_t i = 0; i < 3 * n; ++i) {
        img->rgb[i] = (float)buf[i] / 255.0f;
    }
    free(buf);
    return TR_OK;
}

int tr_image_read(tr_image *img, const char *path, tr_error *err) {
    switch (tr_image_format_from_path(path)) {
    case TR_IMAGE_PFM:
        return tr_image_read_pfm(img, path, err);
    case TR_IMAGE_EXR:
        return tr_image_read_exr(img, path, NULL, err);
    case TR_IMAGE_PNG: {
        if (tr_image_read_png(img, path, err) != TR_OK) {
            return TR_ERR;
        }
        const size_t n = 3 * (size_t)img->width * img->height;
        for (size_t i = 0; i < n; ++i) {
            img->rgb[i] = tr_srgb_to_linear(img->rgb[i]);
        }
        return TR_OK;
    }
    default:
        return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                            "%.200s: unknown image format (expected .pfm, .exr or .png)", path);
    }
}
