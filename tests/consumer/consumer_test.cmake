# Installs ${BUILD_DIR} into a prefix, moves the prefix, then configures, builds and runs
# ${EXAMPLE_DIR} against the moved prefix. Fails with the failing step's output.
function(step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${ARGN}\n${out}\n${err}")
  endif()
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")

step("install" ${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${WORK}/staging")
# A relocatable package works wherever the prefix ends up.
file(RENAME "${WORK}/staging" "${WORK}/prefix")
set(prefix "${WORK}/prefix")

foreach(f include/stabint/stabint.hpp include/stabint/io.hpp bin/stabint-run)
  if(NOT EXISTS "${prefix}/${f}")
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
file(GLOB_RECURSE configs "${prefix}/*/stabintConfig.cmake")
file(GLOB_RECURSE finders "${prefix}/*/cmake/stabint/FindCHOLMOD.cmake")
file(GLOB_RECURSE libs "${prefix}/*/libstabint.a")
if(NOT configs OR NOT finders OR NOT libs)
  message(FATAL_ERROR "package incomplete: config '${configs}', FindCHOLMOD '${finders}', library '${libs}'")
endif()
# No absolute path of the build or source tree may leak into the installed package.
file(GLOB_RECURSE package_files "${prefix}/*/cmake/stabint/*.cmake")
foreach(f ${package_files})
  file(READ "${f}" text)
  string(FIND "${text}" "${BUILD_DIR}" at)
  if(NOT at EQUAL -1)
    message(FATAL_ERROR "${f} refers to the build tree ${BUILD_DIR}")
  endif()
endforeach()

step("configure the example" ${CMAKE_COMMAND} -S "${EXAMPLE_DIR}" -B "${WORK}/build" -G "${GENERATOR}"
     -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_PREFIX_PATH=${prefix}
     -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF)
step("build the example" ${CMAKE_COMMAND} --build "${WORK}/build" -j2)
step("run the example" "${WORK}/build/cloth_energy" 20 cpu)

string(REGEX MATCHALL "\n[0-9]+ [^\n]*" rows "\n${step_output}")
list(LENGTH rows n)
if(NOT step_output MATCHES "frame time kinetic elastic external total target branch" OR NOT n EQUAL 20)
  message(FATAL_ERROR "unexpected example output (${n} frame rows, expected 20):\n${step_output}")
endif()
if(step_output MATCHES "nan|inf")
  message(FATAL_ERROR "non-finite energy in the example output:\n${step_output}")
endif()
list(GET rows 19 last)
if(NOT last MATCHES "^\n20 0\\.3333 ")
  message(FATAL_ERROR "last row should be frame 20 at t = 1/3: '${last}'")
endif()

# The installed tool runs from the moved prefix too.
step("run the installed stabint-run" "${prefix}/bin/stabint-run" --scene chain --backend cpu --frames 2 --quiet --csv -)
if(NOT step_output MATCHES "\n2,")
  message(FATAL_ERROR "installed stabint-run printed no frame 2:\n${step_output}")
endif()
message(STATUS "consumer example OK:${last}")
