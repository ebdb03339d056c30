# Compiler settings of the instrumented builds (RGBDSLAM_SANITIZE, RGBDSLAM_FUZZ; the
# top-level CMakeLists.txt includes this before its subdirectories and calls
# rgbdslam_unity_exceptions() after them). scripts/lib/sanitizer_build.sh configures them.
#
# These builds exist to check, not to run fast, and CI builds both from scratch on 2 cores,
# so they are compiled cheaply (measured in docs/hostile_input.md, "Cost"):
# - -O1: ASan's and UBSan's checks need no more; the build type's -O2 comes earlier on the
#   command line and is overridden. NDEBUG stays as the build type has it.
# - line tables only (gcc -g1, clang -gline-tables-only): a report's stack still names file
#   and line, without the types and variables of full -g.
# - frame pointers, for the sanitizers' fast stack unwinder.
# - unity builds (CMAKE_UNITY_BUILD, batches of 8 sources per compiler run): the Eigen,
#   OpenCV, Ceres and gtest headers are parsed, and their inline code instrumented, once per
#   batch instead of once per file. -DCMAKE_UNITY_BUILD=OFF builds file by file.
# An error ends the program (-fno-sanitize-recover).
set(RGBDSLAM_SANITIZERS address,undefined)
if(RGBDSLAM_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "RGBDSLAM_FUZZ needs clang: CC=clang CXX=clang++")
  endif()
  set(RGBDSLAM_SANITIZERS ${RGBDSLAM_SANITIZERS},fuzzer-no-link)
endif()
if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
  set(rgbdslam_compiler_options -gline-tables-only)
else()
  # gcc's -Wsubobject-linkage spares types of the main file only; in a unity batch every
  # source is an included file, so a class using its own anonymous-namespace types warns.
  set(rgbdslam_compiler_options -g1 -Wno-subobject-linkage)
endif()
add_compile_options(-fsanitize=${RGBDSLAM_SANITIZERS} -fno-sanitize-recover=undefined
                    -fno-omit-frame-pointer -O1 ${rgbdslam_compiler_options})
add_link_options(-fsanitize=address,undefined)
if(NOT DEFINED CMAKE_UNITY_BUILD)
  set(CMAKE_UNITY_BUILD ON)
endif()

# Sources compiled on their own in a unity build: each declares, in an anonymous namespace,
# a name that another source of its batch declares too (kRoundHalf, Candidate, test
# helpers such as makeXi, texture, kS, kDegree), or a `using Status` that makes the
# library's Status ambiguous. A new source that clashes the same way stops the unity build
# with "redefinition of" or "is ambiguous" naming it: add it here.
function(rgbdslam_unity_exceptions)
  if(NOT CMAKE_UNITY_BUILD)
    return()
  endif()
  set(lib ${PROJECT_SOURCE_DIR}/lib/src)
  # codec_jpeg_png.cpp: jpeglib.h and jerror.h define macros (TRUE, FALSE, LOCAL, GLOBAL,
  # ERREXIT, ...) and typedefs (boolean, INT32) that must not reach another source.
  set_source_files_properties(${lib}/image/pyramid.cpp ${lib}/model/point_creation.cpp
      ${lib}/image/codec_jpeg_png.cpp
      DIRECTORY ${PROJECT_SOURCE_DIR}/lib PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON)
  if(RGBDSLAM_BUILD_TESTS)
    set(tests ${PROJECT_SOURCE_DIR}/tests)
    set_source_files_properties(${tests}/geometry/test_se3.cpp ${tests}/image/test_patch.cpp
        ${tests}/mapping/test_bundle_adjuster.cpp ${tests}/sync/test_sync_protocol.cpp
        ${tests}/tracking/test_tracker.cpp ${tests}/util/test_option_registry.cpp
        DIRECTORY ${PROJECT_SOURCE_DIR}/tests PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON)
  endif()
endfunction()
