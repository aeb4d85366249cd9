/* test_abi.c - every public struct has the same size in a plain client (abi_client.c,
 * compiled with -Iinclude alone as C99, and as C++17 where a C++ compiler exists) as in
 * the library, which is compiled with -march=native, TRAC0R_HAVE_EMBREE and the rest:
 * a struct whose layout depended on a compile flag would differ here. */
#include <stdio.h>

#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/abi.h"

size_t abi_client_c_sizeof(int type);
#ifdef TR_TEST_ABI_CXX
size_t abi_client_cxx_sizeof(int type);
#endif

int main(void) {
    static const char *const names[] = {
#define NAME_ENTRY(name, type) #type,
        TR_ABI_TYPES(NAME_ENTRY)
#undef NAME_ENTRY
    };
    CHECK(TR_ABI_TYPE_COUNT == sizeof names / sizeof names[0], "the table and the enum differ");
    for (int t = 0; t < TR_ABI_TYPE_COUNT; ++t) {
        const size_t lib = tr_abi_sizeof((tr_abi_type)t);
        const size_t c = abi_client_c_sizeof(t);
        CHECK(lib > 0, "%s: the library reports no size", names[t]);
        CHECK(lib == c, "%s: %zu bytes in the library, %zu in a plain C99 client", names[t], lib,
              c);
#ifdef TR_TEST_ABI_CXX
        const size_t cxx = abi_client_cxx_sizeof(t);
        CHECK(lib == cxx, "%s: %zu bytes in the library, %zu in a C++17 client", names[t], lib,
              cxx);
#endif
        printf("%-24s %5zu bytes\n", names[t], lib);
    }
    CHECK(tr_abi_sizeof(TR_ABI_TYPE_COUNT) == 0, "an out-of-range type has a size");
    return check_finish("test_abi");
}
