# Checks that every #include "screwfem/<layer>/..." in src/ and include/screwfem/ points down
# the layer graph of docs/architecture.md (a file may include its own layer and the layers
# below it). Run by ctest (tests/CMakeLists.txt, test `layering`):
#   cmake -DSOURCE_DIR=<repository> -P tests/layering/check_layers.cmake
# Fails with the offending file, line and include.

# Layers and what each may include besides itself.
set(allowed_lie "")
set(allowed_linalg "")
set(allowed_model "lie;linalg")
set(allowed_elements "model;lie;linalg")
set(allowed_assemble "elements;model;lie;linalg")
set(allowed_build "elements;model;lie;linalg")
set(allowed_solve "assemble;elements;model;lie;linalg")
set(allowed_io "solve;build;assemble;elements;model;lie;linalg")
set(layers lie linalg model elements assemble build solve io)

if(NOT SOURCE_DIR)
  message(FATAL_ERROR "check_layers: pass -DSOURCE_DIR=<repository root>")
endif()

set(violations 0)
set(checked 0)
foreach(layer IN LISTS layers)
  file(GLOB_RECURSE files
    "${SOURCE_DIR}/src/${layer}/*.cpp" "${SOURCE_DIR}/src/${layer}/*.h"
    "${SOURCE_DIR}/include/screwfem/${layer}/*.h")
  foreach(file IN LISTS files)
    math(EXPR checked "${checked} + 1")
    file(STRINGS "${file}" lines REGEX "^[ \t]*#[ \t]*include[ \t]*\"screwfem/")
    foreach(line IN LISTS lines)
      string(REGEX MATCH "screwfem/([a-z_]+)/" _ "${line}")
      set(target "${CMAKE_MATCH_1}")
      if(target STREQUAL layer)
        continue()
      endif()
      list(FIND layers "${target}" known)
      list(FIND allowed_${layer} "${target}" ok)
      if(known EQUAL -1 OR ok EQUAL -1)
        file(RELATIVE_PATH rel "${SOURCE_DIR}" "${file}")
        message(SEND_ERROR
          "${rel}: layer '${layer}' includes '${target}' (${line}); '${layer}' may include "
          "only: ${allowed_${layer}} (docs/architecture.md, \"Layers\")")
        math(EXPR violations "${violations} + 1")
      endif()
    endforeach()
  endforeach()
endforeach()
if(checked EQUAL 0)
  message(FATAL_ERROR "check_layers: no source files found under ${SOURCE_DIR}")
endif()
if(violations GREATER 0)
  message(FATAL_ERROR "check_layers: ${violations} upward include(s) in ${checked} files")
endif()
message(STATUS "check_layers: ${checked} files, every include points down the layer graph")
