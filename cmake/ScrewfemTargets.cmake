# Compile settings for screwfem's own targets (never applied to dependencies):
#   screwfem_options       the library, the CLI, the examples, the Python module, benchmarks;
#   screwfem_test_options  the GoogleTest programs.
# They differ only in the sanitizer build (SCREWFEM_SANITIZE): everything is compiled with
# AddressSanitizer, and everything but the test programs' own sources also with
# UndefinedBehaviorSanitizer. UBSan doubles the compile time of the Eigen-heavy test sources
# (tests/lie/se3_identities_test.cpp: 52 s against 27 s with ASan alone at -O1), which made up
# most of the sanitizer build; the library code they exercise is instrumented by both.
add_library(screwfem_options INTERFACE)
add_library(screwfem_test_options INTERFACE)
foreach(options screwfem_options screwfem_test_options)
  target_compile_options(${options} INTERFACE -Wall -Wextra -Wpedantic -Wshadow
                         -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual)
  if(SCREWFEM_WERROR)
    target_compile_options(${options} INTERFACE -Werror)
  endif()
  if(SCREWFEM_SANITIZE)
    target_compile_options(${options} INTERFACE -fno-sanitize-recover=all -fno-omit-frame-pointer)
    # Linked with both runtimes (the libraries carry UBSan code either way).
    target_link_options(${options} INTERFACE -fsanitize=address,undefined)
    # GCC 12 reports false 'may be used uninitialized' inside Eigen's evaluators when the
    # sanitizers instrument optimised code; the Release build keeps the warning as an error.
    # (Clang has no such warning.)
    target_compile_options(${options} INTERFACE
                           $<$<CXX_COMPILER_ID:GNU>:-Wno-maybe-uninitialized>)
  endif()
  # Eigen: keep eigen_assert active in the sanitizer build only.
  target_compile_definitions(${options} INTERFACE
                             $<$<NOT:$<BOOL:${SCREWFEM_SANITIZE}>>:EIGEN_NO_DEBUG>)
endforeach()
# The test programs' own sources are compiled at -O1 in Release builds (after the -O3 of
# CMAKE_CXX_FLAGS_RELEASE, so it wins): they are Eigen-heavy (finite-difference oracles,
# long-double references, many expression types) and took 70 % of the Release build's compile
# time; -O1 compiles them in 25-35 % less time (tests/lie/se3_identities_test.cpp 41 -> 31 s,
# tests/linalg/banded_lu_test.cpp 27 -> 17 s, GCC 12). The library they test stays at -O3, and
# without -ffast-math and with -ffp-contract=off the optimisation level changes no result.
target_compile_options(screwfem_test_options INTERFACE $<$<CONFIG:Release>:-O1>)
if(SCREWFEM_SANITIZE)
  target_compile_options(screwfem_options INTERFACE -fsanitize=address,undefined)
  target_compile_options(screwfem_test_options INTERFACE -fsanitize=address)
endif()
# Fuzzing (tests/fuzz): the library and the harnesses carry libFuzzer's coverage
# instrumentation; only the fuzz programs link libFuzzer itself (-fsanitize=fuzzer), so the
# same build tree serves the test suite and the fuzzers.
if(SCREWFEM_FUZZ)
  target_compile_options(screwfem_options INTERFACE -fsanitize=fuzzer-no-link)
endif()

# screwfem_add_library(NAME SOURCES ... DEPS ...)
function(screwfem_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(screwfem_${name} STATIC ${ARG_SOURCES})
  add_library(screwfem::${name} ALIAS screwfem_${name})
  # Position-independent, so the Python extension (a shared object) can link them too.
  set_target_properties(screwfem_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  target_include_directories(screwfem_${name} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:include>)
  # The compile settings stay in the build tree (an installed library's users do not get them).
  target_link_libraries(screwfem_${name} PUBLIC ${ARG_DEPS}
                        PRIVATE $<BUILD_INTERFACE:screwfem_options>)
  set_target_properties(screwfem_${name} PROPERTIES EXPORT_NAME ${name})
  set_property(GLOBAL APPEND PROPERTY SCREWFEM_LIBRARIES screwfem_${name})
  if(SCREWFEM_SANITIZE)
    target_link_options(screwfem_${name} PUBLIC -fsanitize=address,undefined)
  endif()
endfunction()
