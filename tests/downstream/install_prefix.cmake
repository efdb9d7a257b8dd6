# ctest `package_install`: installs the build into a fresh prefix (the fixture of the other
# package_* tests) and checks that the installed CMake package names no path of the source or
# build tree. Run with -DBUILD_DIR= -DSOURCE_DIR= -DPREFIX=.
file(REMOVE_RECURSE ${PREFIX})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${PREFIX}
                RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install ${BUILD_DIR} failed (${rc}): ${err}")
endif()
set(package_dir ${PREFIX}/lib/cmake/ringtrack)
foreach(f ringtrackConfig.cmake ringtrackConfigVersion.cmake ringtrackTargets.cmake
          ../../../include/ringtrack/version.hpp ../../../include/ringtrack/pipeline/pipeline.hpp
          ../../../share/ringtrack/config/default.yaml
          ../../../share/ringtrack/scripts/plot_stage_times.py ../../../bin/ringtrack)
  if(NOT EXISTS ${package_dir}/${f})
    message(FATAL_ERROR "not installed: ${package_dir}/${f}")
  endif()
endforeach()
file(GLOB package_files ${package_dir}/*.cmake)
foreach(f ${package_files})
  file(READ ${f} text)
  foreach(tree ${SOURCE_DIR} ${BUILD_DIR})
    string(FIND "${text}" "${tree}" at)
    if(NOT at EQUAL -1)
      message(FATAL_ERROR "${f} names ${tree}: the installed package must not")
    endif()
  endforeach()
endforeach()
message(STATUS "installed into ${PREFIX}")
