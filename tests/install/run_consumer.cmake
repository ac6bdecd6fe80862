# The test `install_consumer`: installs the build tree BUILD_DIR into a fresh prefix, configures
# and builds tests/install/consumer against it with find_package(screwfem), runs the program,
# and checks that the installed CLI finds its plot tool. Fails on the first step that fails.
#   cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... [-DPYTHON=/usr/bin/python3] -P ...
foreach(var BUILD_DIR SOURCE_DIR WORK_DIR)
  if(NOT ${var})
    message(FATAL_ERROR "run_consumer: pass -D${var}=...")
  endif()
endforeach()
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${out}")
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "run_consumer: '${ARGN}' failed (${status}):\n${out}\n${err}")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
run(${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/install/consumer -B ${WORK_DIR}/build
    -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/consumer ${SOURCE_DIR}/tests/data/pendulum.yaml)
if(NOT last_output MATCHES "consumer: ok")
  message(FATAL_ERROR "run_consumer: the consumer did not report success")
endif()
# The installed CLI runs a scene and finds its plot tool beside itself (share/screwfem).
run(${prefix}/bin/screwfem check ${SOURCE_DIR}/tests/data/pendulum.yaml)
if(NOT EXISTS ${prefix}/share/screwfem/screwfem_plot.py)
  message(FATAL_ERROR "run_consumer: share/screwfem/screwfem_plot.py was not installed")
endif()
# The installed Python package imports with the installed extension (when it was built).
if(PYTHON)
  run(${CMAKE_COMMAND} -E env PYTHONPATH=${prefix}/share/screwfem/python PYTHONDONTWRITEBYTECODE=1
      ${PYTHON} -c "import screwfem, sys
print('consumer: python package', screwfem.__file__)
sys.exit(0 if screwfem.__file__.startswith('${prefix}') else 1)")
endif()
message(STATUS "run_consumer: installed, built and ran the consumer")
