# `cmake --install`: the modules' static libraries and headers, the generated version header and
# a CMake package, so that another project can find_package(ringtrack) and link
# ringtrack::ringtrack or single modules ringtrack::<module> (docs/cpp.md).
include(CMakePackageConfigHelpers)
set(RINGTRACK_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/ringtrack)

# The whole library as one target.
set_target_properties(ringtrack_all PROPERTIES EXPORT_NAME ringtrack)
add_library(ringtrack::ringtrack ALIAS ringtrack_all)
install(TARGETS ringtrack_all EXPORT ringtrackTargets)
install(FILES ${PROJECT_BINARY_DIR}/generated/ringtrack/version.hpp
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/ringtrack)
if(RINGTRACK_SANITIZE)
  # Instrumented libraries need instrumented users, compiled as well as linked: besides the
  # runtimes, Eigen picks its allocator by __SANITIZE_ADDRESS__ (its own aligned malloc under
  # ASan, plain malloc otherwise), so a matrix the library allocates and a user's inline code
  # frees (~Pipeline) is a bad free (package_downstream caught it).
  target_compile_options(ringtrack_core INTERFACE
                         $<INSTALL_INTERFACE:-fsanitize=address,undefined>)
  target_link_options(ringtrack_core INTERFACE $<INSTALL_INTERFACE:-fsanitize=address,undefined>)
endif()

install(EXPORT ringtrackTargets NAMESPACE ringtrack:: DESTINATION ${RINGTRACK_INSTALL_CMAKEDIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/ringtrackConfig.cmake.in
  ${PROJECT_BINARY_DIR}/ringtrackConfig.cmake INSTALL_DESTINATION ${RINGTRACK_INSTALL_CMAKEDIR})
# SameMinorVersion, not SameMajorVersion: below 1.0 a minor release may break the API (semantic
# versioning's 0.y rule), so find_package(ringtrack 0.2) must accept 0.2.x only, never 0.3.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/ringtrackConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/ringtrackConfig.cmake
              ${PROJECT_BINARY_DIR}/ringtrackConfigVersion.cmake
        DESTINATION ${RINGTRACK_INSTALL_CMAKEDIR})

# What the CLI runs and reads besides its code, where it looks for them when installed
# (apps/ringtrack/data_dirs.cpp): the plot scripts and the shipped configuration (presets,
# scenarios, validation scenarios, the tuner's search space).
install(DIRECTORY ${PROJECT_SOURCE_DIR}/config/ DESTINATION ${CMAKE_INSTALL_DATADIR}/ringtrack/config)
install(PROGRAMS ${PROJECT_SOURCE_DIR}/scripts/plot_maps.py
                 ${PROJECT_SOURCE_DIR}/scripts/plot_map_errors.py
                 ${PROJECT_SOURCE_DIR}/scripts/plot_stage_times.py
        DESTINATION ${CMAKE_INSTALL_DATADIR}/ringtrack/scripts)
