# Compile settings for screwfem's own targets (never applied to dependencies):
#   screwfem_options       the library, the CLI, the examples, the Python module, benchmarks;
#   screwfem_test_options  the GoogleTest programs.
# They differ in Release builds (the test sources at -O1, below) and in the sanitizer build
# (SCREWFEM_SANITIZE): the library and everything but the test programs is compiled with
# AddressSanitizer and UndefinedBehaviorSanitizer; the test programs' own sources are not
# instrumented and are linked with the runtimes (reasons below).
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
# The sanitizers instrument the product: the libraries, the CLI, the examples, the Python
# module and the fuzz programs (screwfem_options). The test programs' own sources are compiled
# without instrumentation and without debug information (-g0 after the build type's -g1) and
# linked with the sanitizer runtimes, so every call they make into the library is checked; a
# report points into the library, which keeps its line tables. What is not checked: the test
# code itself, and an inline function of a library header that is not inlined and whose copy
# the linker takes from a test object. It halves the test programs' compile time with Clang
# (tests/io/run_test.cpp: 13.3 s with ASan and -g1, 7.8 s without ASan, 10.1 s with -g0; the
# test programs were 82 % of the sanitizer build). SCREWFEM_SANITIZED tells the tests that the
# runtime is there (they cannot ask the compiler, which did not instrument them).
# Three of UndefinedBehaviorSanitizer's checks are left out of the instrumentation: alignment,
# null and object-size. They check every access through Eigen's expressions: with them the
# instrumented libraries took 535 CPU-s to compile, without them 426 (Clang 14, -O1; one
# source, src/elements/tendon.cpp with the fuzzer's coverage: 32.8 s with all of 'undefined',
# 19.1 s without the three; 15.0 s uninstrumented). AddressSanitizer covers them: a null
# dereference ends in its SEGV report with a stack trace, and its redzones catch an access
# outside an object exactly where object-size would only bound it. The alignment Eigen needs
# for its vectorised fixed-size types is asserted by Eigen itself (eigen_assert is active in
# this build). Every other check of 'undefined' stays (signed overflow, shifts, division by
# zero, float-to-int overflow, bounds of arrays, invalid bool and enum values, pointer
# overflow, vptr and function types).
if(SCREWFEM_SANITIZE)
  target_compile_options(screwfem_options INTERFACE -fsanitize=address,undefined
                         -fno-sanitize=alignment,null,object-size)
  target_compile_options(screwfem_test_options INTERFACE -g0)
  target_compile_definitions(screwfem_test_options INTERFACE SCREWFEM_SANITIZED=1)
endif()
# The sanitizer build compiles the test programs' own sources and the command-line program's
# main.cpp at -O0: they run once per test or per scene, and instrumented code compiles 2.2
# times faster at -O0 than at -O1 (Clang 14, every translation unit of the sanitizer build).
# The libraries stay at the build type's -O1: at -O0 they ran far slower (the build fuzzer ran
# 1 input per second instead of 1066, and 63 per second with only the model, build and io
# libraries at -O0, which saved 10 % of the build).
if(SCREWFEM_SANITIZE)
  target_compile_options(screwfem_test_options INTERFACE -O0)
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
  # Unity build: a library's sources are compiled in batches of five per translation unit.
  # Parsing Eigen's and the library's headers is most of the cost of a small source
  # (src/io/scene.cpp: 6.9 s to compile, 5.7 s of it -fsyntax-only, GCC 12), so each batch
  # parses them once. Helpers in a source's anonymous namespace must therefore have names
  # unique within their library (docs/architecture.md, "Sources").
  set_target_properties(screwfem_${name} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 5)
  set_property(GLOBAL APPEND PROPERTY SCREWFEM_LIBRARIES screwfem_${name})
  if(SCREWFEM_SANITIZE)
    target_link_options(screwfem_${name} PUBLIC -fsanitize=address,undefined)
  endif()
endfunction()
