/* test_image.c - tonemapping and the PNG/PFM writers and readers. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

static char dir[256];

static const char *path_in(const char *name) {
    static char buf[512];
    snprintf(buf, sizeof buf, "%s/%s", dir, name);
    return buf;
}

static int files_in_dir(void) {
    DIR *d = opendir(dir);
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d));) {
        n += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    }
    if (d) {
        closedir(d);
    }
    return n;
}

static void write_file(const char *name, const void *data, size_t n) {
    FILE *fp = fopen(path_in(name), "wb");
    if (fp) {
        fwrite(data, 1, n, fp);
        fclose(fp);
    }
}

static void test_tonemap(void) {
    CHECK(tr_tonemap_srgb8(0.0f, 0.0f) == 0, "black");
    CHECK(tr_tonemap_srgb8(1.0f, 0.0f) == 255, "white");
    CHECK(tr_tonemap_srgb8(100.0f, 0.0f) == 255, "clamped above");
    CHECK(tr_tonemap_srgb8(-1.0f, 0.0f) == 0, "clamped below");
    CHECK(tr_tonemap_srgb8(NAN, 0.0f) == 0, "NaN maps to black");
    /* sRGB(0.5) = 1.055 * 0.5^(1/2.4) - 0.055 = 0.7354 -> 187.5; sRGB(0.002) = 0.02584 -> 6.59 */
    CHECK(tr_tonemap_srgb8(0.5f, 0.0f) == 188, "mid grey: %d", tr_tonemap_srgb8(0.5f, 0.0f));
    CHECK(tr_tonemap_srgb8(0.002f, 0.0f) == 7, "linear toe: %d", tr_tonemap_srgb8(0.002f, 0.0f));
    CHECK(tr_tonemap_srgb8(0.25f, 1.0f) == tr_tonemap_srgb8(0.5f, 0.0f), "one stop doubles");
    int prev = -1, monotonic = 1;
    for (int i = 0; i <= 1000; ++i) {
        int v = tr_tonemap_srgb8((float)i / 1000.0f, 0.0f);
        monotonic &= v >= prev;
        prev = v;
    }
    CHECK(monotonic, "tonemap is not monotonic");
}

/* A film whose pixels hold distinct values, some of them beyond [0, 1]. */
static void fill_film(tr_film *f) {
    for (uint32_t y = 0; y < f->height; ++y) {
        for (uint32_t x = 0; x < f->width; ++x) {
            size_t i = (size_t)y * f->width + x;
            f->count[i] = 1 + (uint32_t)(i % 3);
            f->sum[3 * i] = (float)x * 0.37f * (float)f->count[i];
            f->sum[3 * i + 1] = (float)y * 0.011f * (float)f->count[i];
            f->sum[3 * i + 2] = (float)(x * y) * 1e-3f * (float)f->count[i];
        }
    }
}

static void test_roundtrip(void) {
    tr_error err;
    tr_film f;
    CHECK(tr_film_init(&f, 13, 7, &err) == TR_OK, "%s", err.msg);
    fill_film(&f);
    tr_image img;
    CHECK(tr_film_write(&f, path_in("a.pfm"), 0.0f, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_image_read_pfm(&img, path_in("a.pfm"), &err) == TR_OK, "%s", err.msg);
    int diff = img.width != 13 || img.height != 7;
    for (uint32_t y = 0; !diff && y < 7; ++y) {
        for (uint32_t x = 0; x < 13; ++x) {
            tr_vec3 c = tr_film_pixel(&f, x, y);
            const float *p = img.rgb + 3 * (y * 13 + x);
            diff += p[0] != c.x || p[1] != c.y || p[2] != c.z;
        }
    }
    CHECK(diff == 0, "PFM round trip differs in %d pixels", diff);
    tr_image_free(&img);

    const float exposure = -1.5f;
    CHECK(tr_film_write(&f, path_in("a.PNG"), exposure, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_image_read_png(&img, path_in("a.PNG"), &err) == TR_OK, "%s", err.msg);
    diff = img.width != 13 || img.height != 7;
    for (uint32_t y = 0; !diff && y < 7; ++y) {
        for (uint32_t x = 0; x < 13; ++x) {
            tr_vec3 c = tr_film_pixel(&f, x, y);
            const float *p = img.rgb + 3 * (y * 13 + x);
            diff += (int)(p[0] * 255.0f + 0.5f) != tr_tonemap_srgb8(c.x, exposure) ||
                    (int)(p[1] * 255.0f + 0.5f) != tr_tonemap_srgb8(c.y, exposure) ||
                    (int)(p[2] * 255.0f + 0.5f) != tr_tonemap_srgb8(c.z, exposure);
        }
    }
    CHECK(diff == 0, "PNG round trip differs in %d pixels", diff);
    /* tr_image_read: a PNG comes back decoded to linear, a PFM as it is. */
    tr_image lin;
    CHECK(tr_image_read(&lin, path_in("a.PNG"), &err) == TR_OK, "%s", err.msg);
    for (size_t i = 0; i < 3u * 13u * 7u; ++i) {
        diff += lin.rgb[i] != tr_srgb_to_linear(img.rgb[i]);
    }
    CHECK(diff == 0, "tr_image_read's PNG differs in %d values", diff);
    tr_image_free(&lin);
    CHECK(tr_image_read(&lin, path_in("a.pfm"), &err) == TR_OK && lin.width == 13, "%s", err.msg);
    tr_image_free(&lin);
    CHECK_STATUS(tr_image_read(&lin, path_in("a.bmp"), &err), err, TR_STATUS_UNSUPPORTED,
                 "read an unknown extension");
    tr_image_free(&img);
    CHECK(files_in_dir() == 2, "%d files, expected a.pfm and a.PNG only", files_in_dir());

    CHECK_STATUS(tr_film_write(&f, path_in("a.bmp"), 0.0f, &err), err, TR_STATUS_UNSUPPORTED,
                 "unknown extension");
    CHECK_STATUS(tr_film_write(&f, path_in("no/such/dir/a.png"), 0.0f, &err), err,
                 TR_STATUS_NOT_FOUND, "missing directory");
    CHECK(strstr(err.msg, "no/such/dir/a.png"), "the file is not named: %s", err.msg);
    CHECK(tr_image_check_writable(path_in("b.png"), &err) == TR_OK, "%s", err.msg);
    CHECK(files_in_dir() == 2, "failed writes or the writability check left files behind");
    CHECK(tr_image_format_from_path("x.pfm") == TR_IMAGE_PFM &&
              tr_image_format_from_path("dir.png/x") == TR_IMAGE_UNKNOWN &&
              tr_image_format_from_path("png") == TR_IMAGE_UNKNOWN,
          "format from path");
    tr_film_free(&f);
}

static void test_bad_files(void) {
    tr_error err;
    tr_image img;
    const char truncated[] = "PF\n4 4\n-1.0\n\x00\x00\x80\x3f";
    write_file("t.pfm", truncated, sizeof truncated - 1);
    CHECK_STATUS(tr_image_read_pfm(&img, path_in("t.pfm"), &err), err, TR_STATUS_PARSE,
                 "truncated PFM");
    const char huge[] = "PF\n100000 100000\n-1.0\n";
    write_file("h.pfm", huge, sizeof huge - 1);
    CHECK_STATUS(tr_image_read_pfm(&img, path_in("h.pfm"), &err), err, TR_STATUS_LIMIT, "huge PFM");
    const char garbage[] = "P6\n4 4\n255\n";
    write_file("g.pfm", garbage, sizeof garbage - 1);
    CHECK_STATUS(tr_image_read_pfm(&img, path_in("g.pfm"), &err), err, TR_STATUS_PARSE,
                 "PPM read as PFM");
    write_file("g.png", garbage, sizeof garbage - 1);
    CHECK_STATUS(tr_image_read_png(&img, path_in("g.png"), &err), err, TR_STATUS_PARSE,
                 "garbage read as PNG");
    CHECK_STATUS(tr_image_read_pfm(&img, path_in("missing.pfm"), &err), err, TR_STATUS_NOT_FOUND,
                 "missing file");
    CHECK(strstr(err.msg, "missing.pfm"), "the file is not named: %s", err.msg);
    const char gray[] = "Pf\n1 1\n-1.0\n\x00\x00\x00\x3f";
    write_file("gray.pfm", gray, sizeof gray - 1);
    CHECK(tr_image_read_pfm(&img, path_in("gray.pfm"), &err) == TR_OK && img.rgb[0] == 0.5f &&
              img.rgb[2] == 0.5f,
          "greyscale PFM: %s", err.msg);
    tr_image_free(&img);
}

static void cleanup(void) {
    DIR *d = opendir(dir);
    for (struct dirent *e; d && (e = readdir(d));) {
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0) {
            unlink(path_in(e->d_name));
        }
    }
    if (d) {
        closedir(d);
    }
    rmdir(dir);
}

int main(void) {
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/trac0r-test-image-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    test_tonemap();
    test_roundtrip();
    test_bad_files();
    cleanup();
    return check_finish("test_image");
}
