/* abi.c - the public structs' sizes as this build of the library sees them (abi.h). */
#include "trac0r/abi.h"

size_t tr_abi_sizeof(tr_abi_type type) {
    switch (type) {
#define TR_ABI_CASE(name, t)                                                                       \
    case TR_ABI_##name:                                                                            \
        return sizeof(t);
        TR_ABI_TYPES(TR_ABI_CASE)
#undef TR_ABI_CASE
    case TR_ABI_TYPE_COUNT:
        break;
    }
    return 0;
}
