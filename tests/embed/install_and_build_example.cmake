# Installs mbsflow into a temporary prefix, builds examples/embed against it as a
# separate project and runs it. Called by ctest with -DBUILD_DIR -DSOURCE_DIR -DWORK_DIR.
file(REMOVE_RECURSE "${WORK_DIR}")
function(step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  message(STATUS "${what}: ok\n${out}")
endfunction()
step("install" ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${WORK_DIR}/prefix")
step("configure the example" ${CMAKE_COMMAND} -S "${SOURCE_DIR}/examples/embed" -B "${WORK_DIR}/build"
     -G Ninja -DCMAKE_BUILD_TYPE=Release "-DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix")
step("build the example" ${CMAKE_COMMAND} --build "${WORK_DIR}/build")
step("run the example" "${WORK_DIR}/build/embed_example" "${WORK_DIR}/embed.h5")
step("run the ODE example" "${WORK_DIR}/build/ode_example")
step("run the controller example" "${WORK_DIR}/build/controller_example")
file(REMOVE_RECURSE "${WORK_DIR}")
