# The installed package works for a consumer (ctest "package: ..."; registered in
# cmake/harapInstall.cmake): installs this build into a temporary prefix, configures and builds
# examples/cpp against it with find_package(harap), runs it, and imports the installed Python
# package. Arguments (-D): BUILD_DIR, SOURCE_DIR, WORK_DIR, GENERATOR, CXX_COMPILER, LAUNCHER,
# PYTHON (empty: no Python module), PYTHON_DIR (the package's directory under the prefix).
cmake_minimum_required(VERSION 3.25)

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE output
                  ERROR_VARIABLE output)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "${what} failed (${status}):\n${output}")
  endif()
  set(last_output "${output}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)
run("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
foreach(file bin/harap lib/cmake/harap/harapConfig.cmake include/harap/api/deform.h)
  if(NOT EXISTS ${prefix}/${file})
    message(FATAL_ERROR "not installed: ${file}")
  endif()
endforeach()

set(launcher)
if(LAUNCHER)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
run("configuring examples/cpp" ${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples/cpp -B ${WORK_DIR}/build
    -G ${GENERATOR} -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${CXX_COMPILER} ${launcher}
    -DCMAKE_PREFIX_PATH=${prefix})
run("building examples/cpp" ${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run("running the example" ${WORK_DIR}/build/deform_cylinder 1500)
message(STATUS "example: ${last_output}")
if(NOT last_output MATCHES "converged")
  message(FATAL_ERROR "unexpected output of the example: ${last_output}")
endif()
run("running the installed harap" ${prefix}/bin/harap list)

if(PYTHON)
  run("importing the installed Python package" ${CMAKE_COMMAND} -E env
      PYTHONPATH=${prefix}/${PYTHON_DIR} ${PYTHON} -c
      "import harap\nV, F = harap.builtin_mesh('disk', vertices=50)\nprint(harap.__file__, len(V))")
  if(NOT last_output MATCHES "${prefix}")
    message(FATAL_ERROR "imported harap from elsewhere: ${last_output}")
  endif()
endif()
file(REMOVE_RECURSE ${WORK_DIR})
