# web.cmake - the web build (included by CMakeLists.txt when the compiler is Emscripten's:
# `cmake --preset web`, docs/web.md). The library's sources compiled to WebAssembly with
# web/main.c, the C interface the page calls, into build/web/: the page (index.html,
# app.js), the module (trac0r.js, trac0r.wasm, trac0r.worker.js), a single-threaded
# module without SIMD for browsers without SharedArrayBuffer (trac0r-st.js, .wasm) and
# the shipped scene files.
#
# Debian's Emscripten fetches no ports, so the optional dependencies stay out: no Assimp
# (scene files load without their meshes), no OpenEXR, no libpng or libjpeg (textures
# decode through stb_image, web/codec_web.c; nothing is written as PNG), no OpenCL, no
# Embree, no MPI, no SDL. cJSON is replaced by web/cjson/cJSON.c, the OpenMP runtime by
# web/omp/omp_runtime.c (a team of pthreads, which run as web workers).

# Node.js runs Emscripten's JavaScript optimiser when a module links; Debian installs
# the packages it needs (acorn) under /usr/share/nodejs, where Debian's node does not
# always look. The link runs with that directory added to NODE_PATH.
set(TRAC0R_WEB_NODE_PATH "$ENV{NODE_PATH}")
if(EXISTS /usr/share/nodejs/acorn)
  if(TRAC0R_WEB_NODE_PATH)
    string(APPEND TRAC0R_WEB_NODE_PATH ":/usr/share/nodejs")
  else()
    set(TRAC0R_WEB_NODE_PATH "/usr/share/nodejs")
  endif()
endif()
if(TRAC0R_WEB_NODE_PATH)
  set(CMAKE_C_LINKER_LAUNCHER ${CMAKE_COMMAND} -E env "NODE_PATH=${TRAC0R_WEB_NODE_PATH}")
endif()

set(CMAKE_C_FLAGS_RELEASE "-O3 -DNDEBUG")

# The library's sources: those CMakeLists.txt lists for trac0r_lib (read from it, so that
# a source added there is compiled here too), but the ones that need a library Emscripten
# lacks, which web/codec_web.c and web/mesh_web.c replace (image.c and exr.c write and
# read image files: nothing here calls them); then the always-compiled adapters and the
# web's own files.
file(READ ${PROJECT_SOURCE_DIR}/CMakeLists.txt _tr_top)
string(REGEX MATCH "add_library\\(trac0r_lib STATIC([^)]*)\\)" _tr_lib "${_tr_top}")
string(REGEX MATCHALL "src/[A-Za-z0-9_/]+\\.c" TRAC0R_WEB_LIB_SOURCES "${CMAKE_MATCH_1}")
if(NOT TRAC0R_WEB_LIB_SOURCES)
  message(FATAL_ERROR "web/web.cmake: no add_library(trac0r_lib STATIC ...) in CMakeLists.txt")
endif()
list(REMOVE_ITEM TRAC0R_WEB_LIB_SOURCES src/scene/image_codec.c src/scene/mesh.c
     src/scene/mesh_guard.c src/io/exr.c src/io/image.c)
list(APPEND TRAC0R_WEB_LIB_SOURCES
  src/accel/embree.c
  src/device/opencl.c
  web/cjson/cJSON.c
  web/omp/omp_runtime.c
  web/codec_web.c
  web/mesh_web.c
  web/main.c
)

# stb_image (Debian: libstb-dev) for the textures, outside Emscripten's sysroot.
# Only its directory goes on the include path: /usr/include itself holds the host's C
# headers, which must not shadow Emscripten's.
find_path(TRAC0R_WEB_STB_DIR stb_image.h PATHS /usr/include /usr/local/include
          PATH_SUFFIXES stb NO_DEFAULT_PATH NO_CMAKE_FIND_ROOT_PATH)
if(NOT TRAC0R_WEB_STB_DIR)
  message(FATAL_ERROR "The web build needs stb_image.h (Debian: libstb-dev)")
endif()

set(TRAC0R_WEB_EXPORTS
  "['ccall','cwrap','UTF8ToString','stringToUTF8','lengthBytesUTF8','FS']")

# One module per variant: NAME, its compile flags, its link flags.
function(trac0r_web_module name cflags lflags)
  add_executable(${name} ${TRAC0R_WEB_LIB_SOURCES})
  target_include_directories(${name} PRIVATE include src web/omp web/cjson)
  target_include_directories(${name} SYSTEM PRIVATE ${TRAC0R_WEB_STB_DIR})
  target_compile_options(${name} PRIVATE -Wall -Wextra -Werror -Wshadow -Wstrict-prototypes
                                         -Wmissing-prototypes -ffp-contract=off -fopenmp ${cflags})
  target_link_options(${name} PRIVATE ${cflags} --no-entry -sMODULARIZE=1
    -sEXPORT_NAME=createTrac0r -sENVIRONMENT=web,worker -sALLOW_MEMORY_GROWTH=1
    -sINITIAL_MEMORY=67108864 -sMAXIMUM_MEMORY=2147483648 -sTOTAL_STACK=8388608
    -sFORCE_FILESYSTEM=1 "-sEXPORTED_RUNTIME_METHODS=${TRAC0R_WEB_EXPORTS}" ${lflags})
  set_target_properties(${name} PROPERTIES SUFFIX ".js" RUNTIME_OUTPUT_DIRECTORY
                                           ${PROJECT_BINARY_DIR})
endfunction()

# Threads and 128-bit SIMD: the wide BVH's SSE traversal through Emscripten's SSE
# intrinsics (src/accel/wbvh.c offers it where TR_WBVH_HAVE_SSE_ONLY is set).
trac0r_web_module(trac0r "-pthread;-msimd128;-msse;-msse2"
  "-sPTHREAD_POOL_SIZE=navigator.hardwareConcurrency;-sDEFAULT_PTHREAD_STACK_SIZE=4194304")
target_sources(trac0r PRIVATE src/accel/wbvh_sse2.c)
target_compile_definitions(trac0r PRIVATE TR_WBVH_HAVE_SSE_ONLY=1)
# One thread, no SIMD: for browsers without SharedArrayBuffer (no cross-origin isolation)
# or without WebAssembly SIMD.
trac0r_web_module(trac0r-st "" "")

# The page and the scene files beside the modules.
file(GLOB TRAC0R_WEB_SCENES CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/scenes/*.json
     ${PROJECT_SOURCE_DIR}/scenes/textures/*)
file(GLOB TRAC0R_WEB_PAGE CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/web/*.html ${PROJECT_SOURCE_DIR}/web/*.js)
add_custom_command(
  OUTPUT ${PROJECT_BINARY_DIR}/scenes/index.json
  COMMAND ${CMAKE_COMMAND} -DSRC=${PROJECT_SOURCE_DIR} -DDST=${PROJECT_BINARY_DIR}
          -P ${PROJECT_SOURCE_DIR}/web/copy-assets.cmake
  DEPENDS ${TRAC0R_WEB_SCENES} ${TRAC0R_WEB_PAGE} ${PROJECT_SOURCE_DIR}/web/copy-assets.cmake
  COMMENT "Copying the page and the scene files"
  VERBATIM)
add_custom_target(trac0r_web_assets ALL DEPENDS ${PROJECT_BINARY_DIR}/scenes/index.json)
