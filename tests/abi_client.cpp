// abi_client.cpp - abi_client.c compiled as C++17 (see there).
#include "abi_client.c"
