/* test_parse.c - the shared number rules (trac0r/parse.h): no leading or trailing blanks,
 * no wrap-around past the type, no sign on unsigned values, limits compared in the
 * value's own type (a float's documented minimum 0.1 accepts "0.1"), WxH sizes. */
#include <stdint.h>

#include "check.h"
#include "trac0r/parse.h"

int main(void) {
    int64_t i = 0;
    uint64_t u = 0;
    float f = 0.0f;
    double d = 0.0;
    uint32_t w = 0, h = 0;

    CHECK(tr_parse_int64("12", 1, 100, &i) == TR_OK && i == 12, "12");
    CHECK(tr_parse_int64("-3", -5, 5, &i) == TR_OK && i == -3, "-3");
    CHECK(tr_parse_int64(" 1", 1, 100, &i) == TR_ERR, "a leading blank");
    CHECK(tr_parse_int64("1 ", 1, 100, &i) == TR_ERR, "a trailing blank");
    CHECK(tr_parse_int64("+1", 1, 100, &i) == TR_ERR, "a plus sign");
    CHECK(tr_parse_int64("", 0, 100, &i) == TR_ERR, "empty");
    CHECK(tr_parse_int64("101", 1, 100, &i) == TR_ERR, "above the limit");
    CHECK(tr_parse_int64("9223372036854775808", INT64_MIN, INT64_MAX, &i) == TR_ERR, "past int64");
    CHECK(tr_parse_int64("-9223372036854775808", INT64_MIN, INT64_MAX, &i) == TR_OK &&
              i == INT64_MIN,
          "int64's least");

    CHECK(tr_parse_uint64("4294967304", 0, UINT32_MAX, &u) == TR_ERR, "2^32 + 8 as uint32");
    CHECK(tr_parse_uint64("18446744073709551616", 0, UINT64_MAX, &u) == TR_ERR, "2^64");
    CHECK(tr_parse_uint64("18446744073709551615", 0, UINT64_MAX, &u) == TR_OK && u == UINT64_MAX,
          "2^64 - 1");
    CHECK(tr_parse_uint64("-1", 0, UINT64_MAX, &u) == TR_ERR, "a sign on an unsigned value");

    CHECK(tr_parse_float("0.1", 0.1f, 1000.0f, &f) == TR_OK && f == 0.1f,
          "a float's documented minimum");
    CHECK(tr_parse_float("0.001", 0.001f, 90.0f, &f) == TR_OK, "0.001 against 0.001f");
    CHECK(tr_parse_float("0.09", 0.1f, 1000.0f, &f) == TR_ERR, "below the minimum");
    CHECK(tr_parse_float(" 1", 0.0f, 10.0f, &f) == TR_ERR, "a leading blank");
    CHECK(tr_parse_float("1e39", 0.0f, 3e38f, &f) == TR_ERR, "beyond float");
    CHECK(tr_parse_float("nan", -1.0f, 1.0f, &f) == TR_ERR, "nan");
    CHECK(tr_parse_float("inf", 0.0f, 1e30f, &f) == TR_ERR, "inf");
    CHECK(tr_parse_float(".5", 0.0f, 1.0f, &f) == TR_OK && f == 0.5f, ".5");
    CHECK(tr_parse_double("2.5", 0.0, 3.0, &d) == TR_OK && d == 2.5, "2.5");
    CHECK(tr_parse_double("2.5x", 0.0, 3.0, &d) == TR_ERR, "trailing text");

    CHECK(tr_parse_size("640x480", 16384, &w, &h) == TR_OK && w == 640 && h == 480, "640x480");
    CHECK(tr_parse_size("4294967304x8", 16384, &w, &h) == TR_ERR, "a wrapped width");
    CHECK(tr_parse_size("8x4294967304", UINT32_MAX, &w, &h) == TR_ERR, "a wrapped height");
    CHECK(tr_parse_size(" 8x8", 16384, &w, &h) == TR_ERR, "a leading blank");
    CHECK(tr_parse_size("8x 8", 16384, &w, &h) == TR_ERR, "a blank after x");
    CHECK(tr_parse_size("0x8", 16384, &w, &h) == TR_ERR, "a zero side");
    CHECK(tr_parse_size("8x8x", 16384, &w, &h) == TR_ERR, "trailing text");

    /* Fractions 1/N: four spellings of a quarter, and what is not a 1/N in range. */
    const char *quarter[4] = {"1/4", "0.25", "\xc2\xbc", "2.5e-1"};
    for (int q = 0; q < 4; ++q) {
        w = 0;
        CHECK(tr_parse_fraction(quarter[q], 16, &w) == TR_OK && w == 4, "'%s': %u", quarter[q], w);
    }
    CHECK(tr_parse_fraction("\xc2\xbd", 16, &w) == TR_OK && w == 2, "the half sign");
    CHECK(tr_parse_fraction("1", 16, &w) == TR_OK && w == 1, "1");
    const char *bad[8] = {"0.3", "1/17", "1/0", "0", "2", " 1/4", "1/4294967300", "1/-4"};
    for (int q = 0; q < 8; ++q) {
        CHECK(tr_parse_fraction(bad[q], 16, &w) == TR_ERR, "'%s' accepted", bad[q]);
    }
    uint32_t r[4] = {0, 0, 0, 0};
    CHECK(tr_parse_rect("1,2,30,40", 100, r) == TR_OK && r[0] == 1 && r[1] == 2 && r[2] == 30 &&
              r[3] == 40,
          "1,2,30,40");
    const char *bad_rect[6] = {"1,2,0,4", "1,2,3", "1,2,3,4,", " 1,2,3,4", "1,2,3,101", "1,-2,3,4"};
    for (int q = 0; q < 6; ++q) {
        CHECK(tr_parse_rect(bad_rect[q], 100, r) == TR_ERR, "'%s' accepted", bad_rect[q]);
    }
    return check_finish("test_parse");
}
