# Project-wide warning and sanitizer flags, applied through the interface target
# ringtrack_options so that third-party headers keep their own settings.
add_library(ringtrack_options INTERFACE)
target_compile_options(ringtrack_options INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
  -Wnon-virtual-dtor -Wold-style-cast -Woverloaded-virtual -Wnull-dereference
  $<$<BOOL:${RINGTRACK_WERROR}>:-Werror>)
if(RINGTRACK_SANITIZE)
  target_compile_options(ringtrack_options INTERFACE
    -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
  target_link_options(ringtrack_options INTERFACE -fsanitize=address,undefined)
endif()

# Adds a library target for one module: ringtrack_<name>, alias ringtrack::<name>. It installs
# with its headers (include/ringtrack/<name>/) and is exported as ringtrack::<name>
# (cmake/install.cmake).
function(ringtrack_add_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPENDS" ${ARGN})
  add_library(ringtrack_${name} STATIC ${ARG_SOURCES})
  add_library(ringtrack::${name} ALIAS ringtrack_${name})
  target_include_directories(ringtrack_${name} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src> $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  # The headers need C++20 (std::span, designated initializers), so users' code does too.
  target_compile_features(ringtrack_${name} PUBLIC cxx_std_20)
  # The warning and sanitizer flags are this build's own: BUILD_INTERFACE keeps them (and the
  # target, which install(EXPORT) would otherwise demand) out of the installed package.
  target_link_libraries(ringtrack_${name} PUBLIC ${ARG_DEPENDS}
                        PRIVATE $<BUILD_INTERFACE:ringtrack_options>)
  set_target_properties(ringtrack_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON
                        EXPORT_NAME ${name})
  install(TARGETS ringtrack_${name} EXPORT ringtrackTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
  # Every header of the folder: public headers include the module's internal ones.
  install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/ringtrack/${name} FILES_MATCHING PATTERN "*.hpp")
endfunction()
