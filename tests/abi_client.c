/* abi_client.c - the public structs' sizes as a client sees them: compiled with nothing
 * but -Iinclude (no definitions, no -march, C99; as C++17 too through abi_client.cpp),
 * never with the library's flags. test_abi.c compares them with tr_abi_sizeof. */
#include "trac0r/abi.h"

#define ABI_CLIENT_CASE(name, type)                                                                \
    case TR_ABI_##name:                                                                            \
        return sizeof(type);

#ifdef __cplusplus
extern "C" size_t abi_client_cxx_sizeof(int type);
size_t abi_client_cxx_sizeof(int type) {
#else
size_t abi_client_c_sizeof(int type);
size_t abi_client_c_sizeof(int type) {
#endif
    switch (type) {
        TR_ABI_TYPES(ABI_CLIENT_CASE)
    default:
        break;
    }
    return 0;
}
