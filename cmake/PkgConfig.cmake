# PkgConfig.cmake - writes trac0r.pc (cmake -P, run by `cmake --install`; cmake/Install.cmake).
#
# Libs: is all a program linking libtrac0r.so needs. Libs.private (read by
# `pkg-config --static`) is taken from the shared library itself: one -l per DT_NEEDED
# entry, so it lists exactly what the library was linked against. Requires.private stays
# empty: pkg-config would add those modules' Cflags to every `--cflags` and insist that
# each module's .pc exists (Embree ships none), although no public header includes them.
foreach(var TR_SO TR_OBJDUMP TR_IN TR_OUT TR_PREFIX TR_LIBDIR TR_INCLUDEDIR TR_VERSION)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "PkgConfig.cmake: ${var} is not set")
  endif()
endforeach()
execute_process(COMMAND ${TR_OBJDUMP} -p ${TR_SO} OUTPUT_VARIABLE dump RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "PkgConfig.cmake: '${TR_OBJDUMP} -p ${TR_SO}' failed")
endif()
string(REGEX MATCHALL "NEEDED +[^\n]+" needed "${dump}")
set(TR_LIBS_PRIVATE "")
foreach(entry ${needed})
  string(REGEX REPLACE "^NEEDED +" "" lib "${entry}")
  string(STRIP "${lib}" lib)
  # The C library and the dynamic loader come with every link.
  if(lib MATCHES "^(libc|ld-linux.*|libgcc_s)\\.so")
    continue()
  endif()
  if(NOT lib MATCHES "^lib(.+)\\.so(\\..*)?$")
    message(FATAL_ERROR "PkgConfig.cmake: cannot turn DT_NEEDED '${lib}' into -l")
  endif()
  string(APPEND TR_LIBS_PRIVATE " -l${CMAKE_MATCH_1}")
endforeach()
string(STRIP "${TR_LIBS_PRIVATE}" TR_LIBS_PRIVATE)
configure_file(${TR_IN} ${TR_OUT} @ONLY)
