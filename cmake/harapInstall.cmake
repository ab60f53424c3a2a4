# The installable package: `cmake --install build --prefix P` puts the `harap` command in P/bin,
# the headers in P/include/harap (included as "framework/mesh.h", "api/deform.h", ...),
# the static libraries in P/lib, the Python package in P/${HARAP_PYTHON_INSTALL_DIR} and
# P/lib/cmake/harap/harapConfig.cmake, so that a consumer's
#
#   find_package(harap REQUIRED)
#   target_link_libraries(app PRIVATE harap::harap)
#
# gets every harap library and, through harapConfig.cmake's find_dependency calls, their
# dependencies (examples/cpp is such a consumer; a ctest builds it against an installed tree).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# harap::harap: everything (the composition root and every module it links).
add_library(harap_library INTERFACE)
target_link_libraries(harap_library INTERFACE harap::api)
set_target_properties(harap_library PROPERTIES EXPORT_NAME harap)
add_library(harap::harap ALIAS harap_library)

set(harap_exported_libraries harap_framework harap_io harap_energies harap_solvers
    harap_optimizers harap_hierarchies harap_upsamplers harap_spatial harap_api)
foreach(library ${harap_exported_libraries})
  string(REPLACE "harap_" "" export_name ${library})
  set_target_properties(${library} PROPERTIES EXPORT_NAME ${export_name})
endforeach()
# The warning and flag targets are linked privately; static libraries still name them in their
# link interface (as $<LINK_ONLY:...>), so they are part of the export (they add nothing to a
# consumer's compile lines).
install(TARGETS ${harap_exported_libraries} harap_library harap_warnings harap_flags
        EXPORT harapTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/harap)
install(TARGETS harap RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

foreach(module framework io energies solvers hierarchies spatial api)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${module} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/harap
          FILES_MATCHING PATTERN "*.h"
          # Internal: exposes toml++, which the installed interface does not.
          PATTERN "toml_reading.h" EXCLUDE)
endforeach()

set(harap_config_dir ${CMAKE_INSTALL_LIBDIR}/cmake/harap)
install(EXPORT harapTargets NAMESPACE harap:: DESTINATION ${harap_config_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/harapConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/harapConfig.cmake
                              INSTALL_DESTINATION ${harap_config_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/harapConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/harapConfig.cmake ${PROJECT_BINARY_DIR}/harapConfigVersion.cmake
        DESTINATION ${harap_config_dir})

# Not in sanitizer builds: an instrumented install is no package anyone consumes.
if(HARAP_BUILD_TESTS AND NOT HARAP_SANITIZE)
  set(harap_consumer_python)
  if(TARGET harap_python)
    set(harap_consumer_python -DPYTHON=${Python3_EXECUTABLE}
        -DPYTHON_DIR=${HARAP_PYTHON_INSTALL_DIR})
  endif()
  add_test(NAME "package: install, then build and run examples/cpp against it"
           COMMAND ${CMAKE_COMMAND} -DBUILD_DIR=${PROJECT_BINARY_DIR}
                   -DSOURCE_DIR=${PROJECT_SOURCE_DIR}
                   -DWORK_DIR=${PROJECT_BINARY_DIR}/package-test
                   -DGENERATOR=${CMAKE_GENERATOR} -DCXX_COMPILER=${CMAKE_CXX_COMPILER}
                   -DLAUNCHER=${CMAKE_CXX_COMPILER_LAUNCHER} ${harap_consumer_python}
                   -P ${PROJECT_SOURCE_DIR}/tests/package/consumer_test.cmake)
endif()
