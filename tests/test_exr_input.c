/* test_exr_input.c - EXR files are read as untrusted input: a scanline chunk whose data is
 * shorter than its lines is refused (its pixels would otherwise come from memory never
 * written), and channels stored subsampled (xSampling or ySampling above 1) are refused
 * rather than read as if they were not. The files are written here byte by byte, with no
 * compression, so that each lie is exactly the one meant; a true file reads. */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "trac0r/image.h"

#define W 4
#define H 2

static char path[256];

static void put(FILE *fp, const void *p, size_t n) {
    fwrite(p, 1, n, fp);
}

static void put_i32(FILE *fp, int32_t v) {
    put(fp, &v, 4);
}

static void attr(FILE *fp, const char *name, const char *type, int32_t size) {
    put(fp, name, strlen(name) + 1);
    put(fp, type, strlen(type) + 1);
    put_i32(fp, size);
}

/* A W x H RGB float image of 0.5 everywhere, uncompressed, one line a chunk; the B and R
 * channels stored with the given sampling; line 0's chunk `short_by` bytes short. */
static void write_exr(int sampling, int32_t short_by) {
    FILE *fp = fopen(path, "wb");
    CHECK(fp != NULL, "cannot write %s", path);
    if (!fp) {
        return;
    }
    const unsigned char magic[4] = {0x76, 0x2f, 0x31, 0x01};
    put(fp, magic, 4);
    put_i32(fp, 2);
    const char *names[3] = {"B", "G", "R"};
    attr(fp, "channels", "chlist", 3 * (2 + 16) + 1);
    for (int c = 0; c < 3; ++c) {
        const int s = c == 1 ? 1 : sampling;
        put(fp, names[c], 2);
        put_i32(fp, 2); /* FLOAT */
        const unsigned char linear[4] = {0, 0, 0, 0};
        put(fp, linear, 4);
        put_i32(fp, s);
        put_i32(fp, 1);
    }
    put(fp, "", 1);
    attr(fp, "compression", "compression", 1);
    put(fp, "", 1); /* NONE */
    const int32_t box[4] = {0, 0, W - 1, H - 1};
    attr(fp, "dataWindow", "box2i", 16);
    put(fp, box, 16);
    attr(fp, "displayWindow", "box2i", 16);
    put(fp, box, 16);
    attr(fp, "lineOrder", "lineOrder", 1);
    put(fp, "", 1);
    const float one = 1.0f, zero[2] = {0.0f, 0.0f};
    attr(fp, "pixelAspectRatio", "float", 4);
    put(fp, &one, 4);
    attr(fp, "screenWindowCenter", "v2f", 8);
    put(fp, zero, 8);
    attr(fp, "screenWindowWidth", "float", 4);
    put(fp, &one, 4);
    put(fp, "", 1);
    /* The chunks: y, size, then each channel's line in channel order. */
    const int32_t sub = W / sampling;
    const int32_t line = 4 * (W + 2 * sub);
    const long table = ftell(fp);
    uint64_t offsets[H];
    uint64_t at = (uint64_t)table + sizeof offsets;
    for (int y = 0; y < H; ++y) {
        offsets[y] = at;
        at += 8 + (uint64_t)(line - (y == 0 ? short_by : 0));
    }
    put(fp, offsets, sizeof offsets);
    const float half = 0.5f;
    for (int y = 0; y < H; ++y) {
        const int32_t size = line - (y == 0 ? short_by : 0);
        put_i32(fp, y);
        put_i32(fp, size);
        for (int32_t k = 0; k < size / 4; ++k) {
            put(fp, &half, 4);
        }
    }
    fclose(fp);
}

/* Reads the file: TR_OK with every value 0.5, or the error's code. */
static int read_flat(int *flat) {
    tr_image img;
    tr_error err;
    *flat = 0;
    if (tr_image_read(&img, path, &err) != TR_OK) {
        return err.code;
    }
    *flat = img.width == W && img.height == H;
    for (size_t i = 0; *flat && i < (size_t)W * H * 3; ++i) {
        *flat = img.rgb[i] == 0.5f;
    }
    tr_image_free(&img);
    return TR_OK;
}

int main(void) {
    snprintf(path, sizeof path, "/tmp/trac0r-test-exr-input-%ld.exr", (long)getpid());
    int flat = 0;
    write_exr(1, 0);
    CHECK(read_flat(&flat) == TR_OK && flat, "a true uncompressed EXR does not read flat");

    write_exr(1, 4);
    CHECK(read_flat(&flat) != TR_OK, "a chunk one value short of its line was accepted");

    /* Subsampled: read right (flat) or refused, never read wrong. */
    write_exr(2, 0);
    const int rc = read_flat(&flat);
    CHECK(rc != TR_OK || flat, "x-subsampled channels were read wrong");
    remove(path);
    return check_finish("test_exr_input");
}
