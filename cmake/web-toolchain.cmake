# The web build's toolchain (CMakePresets.json, preset "web"): Emscripten's own CMake
# platform file, found from the emcc on PATH (Debian's /usr/bin/emcc links into
# /usr/share/emscripten; emsdk's emcc lies beside it) or from $EMSCRIPTEN. The same as
# `emcmake cmake`, without needing the wrapper around every configure.
find_program(TRAC0R_EMCC emcc)
set(_tr_em_roots "$ENV{EMSCRIPTEN}")
if(TRAC0R_EMCC)
  get_filename_component(_tr_emcc_real "${TRAC0R_EMCC}" REALPATH)
  get_filename_component(_tr_emcc_dir "${_tr_emcc_real}" DIRECTORY)
  list(APPEND _tr_em_roots "${_tr_emcc_dir}")
endif()
set(_tr_em_platform "")
foreach(_tr_root IN LISTS _tr_em_roots)
  if(_tr_root AND EXISTS "${_tr_root}/cmake/Modules/Platform/Emscripten.cmake")
    set(_tr_em_platform "${_tr_root}/cmake/Modules/Platform/Emscripten.cmake")
    break()
  endif()
endforeach()
if(NOT _tr_em_platform)
  message(FATAL_ERROR "The web build needs Emscripten: no emcc on PATH (Debian: apt install "
                      "emscripten) and no $EMSCRIPTEN naming its directory")
endif()
include("${_tr_em_platform}")
