# A second configure of the same tree changes no compile command, so that test.sh after
# demo.sh (or any re-run of cmake) recompiles nothing. Configures SOURCE_DIR twice into
# WORK_DIR (tests and the Python module off: they take no part in the flags of the layers)
# and compares compile_commands.json.
foreach(v SOURCE_DIR WORK_DIR)
  if(NOT ${v})
    message(FATAL_ERROR "give -D${v}=...")
  endif()
endforeach()
file(REMOVE_RECURSE ${WORK_DIR})
set(args -S ${SOURCE_DIR} -B ${WORK_DIR} -G Ninja -DCMAKE_BUILD_TYPE=Release -DMBSFLOW_WERROR=ON
         -DMBSFLOW_BUILD_TESTS=OFF -DMBSFLOW_PYTHON_MODULE=OFF)
foreach(pass first second)
  execute_process(COMMAND ${CMAKE_COMMAND} ${args} RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "the ${pass} configure failed: ${err}")
  endif()
  file(READ ${WORK_DIR}/compile_commands.json ${pass})
endforeach()
if(NOT first STREQUAL second)
  file(WRITE ${WORK_DIR}/first.json "${first}")
  message(FATAL_ERROR "the second configure changed compile commands (diff ${WORK_DIR}/first.json "
                      "${WORK_DIR}/compile_commands.json): everything they name would be compiled again")
endif()
string(FIND "${first}" "\"command\"" any)
if(any EQUAL -1)
  message(FATAL_ERROR "compile_commands.json names no command")
endif()
message(STATUS "a second configure left every compile command as it was")
