# Install and export (docs/install.md, "Install"): `cmake --install <build> --prefix <dir>` installs
#   include/screwfem/...                     the public headers
#   lib/libscrewfem_<layer>.a                one static library per layer
#   lib/cmake/screwfem/screwfemConfig.cmake  find_package(screwfem) -> screwfem::core, ::io, ...
#   bin/screwfem                             the command-line program
#   share/screwfem/                          the tools `screwfem plot` and `view` run, the
#                                            Python package (python/CMakeLists.txt)
# The CLI finds its tools in ../share/screwfem next to its own directory, in the build tree as
# in an installation (app/CMakeLists.txt copies them there at build time).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(SCREWFEM_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/screwfem)
get_property(screwfem_libraries GLOBAL PROPERTY SCREWFEM_LIBRARIES)
set_target_properties(screwfem_core PROPERTIES EXPORT_NAME core)

install(TARGETS ${screwfem_libraries} screwfem_core
  EXPORT screwfemTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/screwfem
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS screwfem_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
foreach(file IN LISTS SCREWFEM_TOOL_FILES)
  get_filename_component(subdir ${file} DIRECTORY)
  install(FILES ${PROJECT_SOURCE_DIR}/tools/${file}
          DESTINATION ${CMAKE_INSTALL_DATADIR}/screwfem/${subdir})
endforeach()

install(EXPORT screwfemTargets NAMESPACE screwfem:: DESTINATION ${SCREWFEM_INSTALL_CMAKEDIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/screwfemConfig.cmake.in
  ${PROJECT_BINARY_DIR}/screwfemConfig.cmake
  INSTALL_DESTINATION ${SCREWFEM_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/screwfemConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/screwfemConfig.cmake
              ${PROJECT_BINARY_DIR}/screwfemConfigVersion.cmake
  DESTINATION ${SCREWFEM_INSTALL_CMAKEDIR})
