// exr_dump.cpp - an EXR reader independent of trac0r's: OpenEXR's C++ library reads one
// layer of an image and writes it as PFM (the layout trac0r writes: little-endian, rows
// bottom to top), so tests can compare trac0r's EXR files with its PFM files bit for bit.
//
//     exr_dump IN.exr LAYER OUT.pfm   LAYER "" (R, G, B), "albedo" (albedo.R, ...),
//                                     "normal" (normal.X, ...), "depth" (depth.Z x 3)
//     exr_dump --half IN.pfm OUT.pfm  every value rounded to half by Imath (what a
//                                     `--exr-type half` file must hold)
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <half.h>

#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

static bool write_pfm(const char *path, int w, int h, const std::vector<float> &rgb) {
    FILE *fp = std::fopen(path, "wb");
    if (!fp) {
        return false;
    }
    std::fprintf(fp, "PF\n%d %d\n-1.0\n", w, h);
    for (int y = h - 1; y >= 0; --y) {
        std::fwrite(&rgb[static_cast<size_t>(y) * w * 3], sizeof(float), static_cast<size_t>(w) * 3,
                    fp);
    }
    return std::fclose(fp) == 0;
}

static int round_to_half(const char *in, const char *out) {
    FILE *fp = std::fopen(in, "rb");
    int w = 0, h = 0;
    float scale = 0.0f;
    if (!fp || std::fscanf(fp, "PF %d %d %f", &w, &h, &scale) != 3 || std::fgetc(fp) != '\n' ||
        w <= 0 || h <= 0 || scale >= 0.0f) {
        std::fprintf(stderr, "exr_dump: %s: not a little-endian colour PFM\n", in);
        return 1;
    }
    std::vector<float> rgb(static_cast<size_t>(w) * h * 3);
    for (int y = h - 1; y >= 0; --y) {
        if (std::fread(&rgb[static_cast<size_t>(y) * w * 3], sizeof(float),
                       static_cast<size_t>(w) * 3, fp) != static_cast<size_t>(w) * 3) {
            std::fprintf(stderr, "exr_dump: %s: truncated\n", in);
            return 1;
        }
    }
    std::fclose(fp);
    for (float &v : rgb) {
        v = static_cast<float>(half(v));
    }
    return write_pfm(out, w, h, rgb) ? 0 : 1;
}

int main(int argc, char **argv) {
    if (argc == 4 && std::strcmp(argv[1], "--half") == 0) {
        return round_to_half(argv[2], argv[3]);
    }
    if (argc != 4) {
        std::fprintf(stderr, "usage: exr_dump IN.exr LAYER OUT.pfm | --half IN.pfm OUT.pfm\n");
        return 2;
    }
    try {
        Imf::InputFile file(argv[1]);
        const Imath::Box2i dw = file.header().dataWindow();
        const int w = dw.max.x - dw.min.x + 1, h = dw.max.y - dw.min.y + 1;
        const std::string layer = argv[2];
        const std::string prefix = layer.empty() ? "" : layer + ".";
        const char *names[3] = {"R", "G", "B"};
        if (layer == "normal") {
            names[0] = "X", names[1] = "Y", names[2] = "Z";
        } else if (layer == "depth") {
            names[0] = names[1] = names[2] = "Z";
        }
        std::vector<float> rgb(static_cast<size_t>(w) * h * 3);
        Imf::FrameBuffer fb;
        for (int k = 0; k < 3; ++k) {
            const std::string name = prefix + names[k];
            if (!file.header().channels().findChannel(name)) {
                std::fprintf(stderr, "exr_dump: %s: no channel %s\n", argv[1], name.c_str());
                return 1;
            }
            // The frame buffer's base is the address of pixel (0, 0) of the data window.
            char *base = reinterpret_cast<char *>(rgb.data() + k) -
                         (static_cast<ptrdiff_t>(dw.min.y) * w + dw.min.x) * 3 *
                             static_cast<ptrdiff_t>(sizeof(float));
            if (k == 0 || std::strcmp(names[k], names[k - 1]) != 0) {
                fb.insert(name, Imf::Slice(Imf::FLOAT, base, 3 * sizeof(float),
                                           3 * sizeof(float) * static_cast<size_t>(w)));
            }
        }
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        if (names[1] == names[0]) { // one channel shown in all three
            for (size_t i = 0; i < static_cast<size_t>(w) * h; ++i) {
                rgb[3 * i + 1] = rgb[3 * i + 2] = rgb[3 * i];
            }
        }
        return write_pfm(argv[3], w, h, rgb) ? 0 : 1;
    } catch (const std::exception &e) {
        std::fprintf(stderr, "exr_dump: %s\n", e.what());
        return 1;
    }
}
