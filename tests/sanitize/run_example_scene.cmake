# Runs one example scene through the command-line program for its first steps. Registered by
# tests/CMakeLists.txt in the sanitizer build only, once per examples/**/*.yaml (tests
# sanitizer_scene_<directory>_<name>): there the program is instrumented, and a report of
# AddressSanitizer or UndefinedBehaviorSanitizer ends it with a non-zero status. Together the
# scenes parse, build, step and write out every element kind the examples use (rods, rigid
# bodies, the joint library, tendons, pressure chambers, rest curvature, contact with friction,
# run-time inputs) under the sanitizers. Their physics is asserted by the Release suite; this
# test asserts that the program reports a completed run (a dynamic one to its end time, a static
# one to its load factor) and exits with status 0.
#   cmake -DCLI=<screwfem> -DSOURCE_DIR=<repository> -DSCENE=examples/<dir>/<name>.yaml
#         -DWORK_DIR=<dir> [-DEND_TIME=0.05] -P tests/sanitize/run_example_scene.cmake

foreach(var CLI SOURCE_DIR SCENE WORK_DIR)
  if(NOT ${var})
    message(FATAL_ERROR "run_example_scene: pass -D${var}=...")
  endif()
endforeach()
if(NOT END_TIME)
  set(END_TIME 0.05)
endif()

execute_process(
  COMMAND "${CLI}" run "${SOURCE_DIR}/${SCENE}" -o "${WORK_DIR}" --force --quiet
          --set "analysis.end_time=${END_TIME}"
  WORKING_DIRECTORY "${SOURCE_DIR}"
  RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT status EQUAL 0 OR NOT "${out}${err}" MATCHES "completed: (t = |load factor)")
  message(FATAL_ERROR "${SCENE}: exit status ${status}\n${out}${err}")
endif()
message(STATUS "${SCENE}: ${out}${err}")
