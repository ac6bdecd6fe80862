# Compile settings for screwfem's own targets (never applied to dependencies).
add_library(screwfem_options INTERFACE)
target_compile_options(screwfem_options INTERFACE -Wall -Wextra -Wpedantic -Wshadow
                       -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual)
if(SCREWFEM_WERROR)
  target_compile_options(screwfem_options INTERFACE -Werror)
endif()
if(SCREWFEM_SANITIZE)
  target_compile_options(screwfem_options INTERFACE -fsanitize=address,undefined
                         -fno-sanitize-recover=all -fno-omit-frame-pointer)
  target_link_options(screwfem_options INTERFACE -fsanitize=address,undefined)
  # GCC 12 reports false 'may be used uninitialized' inside Eigen's evaluators when the
  # sanitizers instrument optimised code; the Release build keeps the warning as an error.
  target_compile_options(screwfem_options INTERFACE -Wno-maybe-uninitialized)
endif()
# Eigen: no vectorisation-alignment surprises across translation units, and keep
# eigen_assert active in the sanitizer build only.
target_compile_definitions(screwfem_options INTERFACE $<$<NOT:$<BOOL:${SCREWFEM_SANITIZE}>>:EIGEN_NO_DEBUG>)

# screwfem_add_library(NAME SOURCES ... DEPS ...)
function(screwfem_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(screwfem_${name} STATIC ${ARG_SOURCES})
  add_library(screwfem::${name} ALIAS screwfem_${name})
  # Position-independent, so the Python extension (a shared object) can link them too.
  set_target_properties(screwfem_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  target_include_directories(screwfem_${name} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:include>)
  target_link_libraries(screwfem_${name} PUBLIC ${ARG_DEPS} PRIVATE screwfem_options)
  if(SCREWFEM_SANITIZE)
    target_link_options(screwfem_${name} PUBLIC -fsanitize=address,undefined)
  endif()
endfunction()
