# ctest `package_downstream`: configures and builds tests/downstream (a project of its own) against
# the prefix package_install filled, runs it and checks what it prints. Run with -DPREFIX=
# -DSOURCE_DIR= (tests/downstream) -DWORK_DIR= -DGENERATOR= -DCXX= -DVERSION=.
file(REMOVE_RECURSE ${WORK_DIR})
# The package registry off: the package must come from the prefix, nowhere else.
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR} -G ${GENERATOR}
                        -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_BUILD_TYPE=Release
                        -DCMAKE_PREFIX_PATH=${PREFIX} -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring the downstream project failed (${rc}):\n${out}\n${err}")
endif()
file(STRINGS ${WORK_DIR}/CMakeCache.txt found REGEX "^ringtrack_DIR:")
if(NOT found STREQUAL "ringtrack_DIR:PATH=${PREFIX}/lib/cmake/ringtrack")
  message(FATAL_ERROR "the downstream project found ringtrack elsewhere: ${found}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the downstream project failed (${rc}):\n${out}\n${err}")
endif()
execute_process(COMMAND ${WORK_DIR}/downstream RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
message(STATUS "downstream: ${out}${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the downstream program failed (${rc})")
endif()
string(REPLACE "." "\\." version_re ${VERSION})
if(NOT out MATCHES "^ringtrack ${version_re}: 40 scans, ([0-9]+) reported tracks, ([1-9][0-9]*) on a true person\n$")
  message(FATAL_ERROR "unexpected output of the downstream program")
endif()
