# cmake -P script run by ctest (see CMakeLists.txt next to it). Fails with a message on the
# first step that does not do what a plugin author would expect.
function(step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  set(step_output "${out}${err}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK})
set(prefix ${WORK}/prefix)
step("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
foreach(f bin/crumble include/crumble/core/BreakageModel.h include/crumble/scenarios/Plugins.h
          include/crumble/scenarios/Methods.h
          include/crumble/crumble_config.h lib/cmake/crumble/crumbleConfig.cmake)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "cmake --install did not install ${f}")
  endif()
endforeach()
if(NOT EXISTS ${prefix}/share/doc/crumble/LICENSE)
  message(FATAL_ERROR "cmake --install did not install the licence (share/doc/crumble/LICENSE)")
endif()

# One version: the installed binary's --version, the SDK's CRUMBLE_VERSION and its CMake
# package version (all from CMake's project version).
step("crumble --version" ${prefix}/bin/crumble --version)
string(REGEX MATCH "^crumble ([0-9]+\\.[0-9]+\\.[0-9]+)" _ "${step_output}")
set(printed "${CMAKE_MATCH_1}")
file(STRINGS ${prefix}/include/crumble/crumble_config.h _macro REGEX "#define CRUMBLE_VERSION \"")
string(REGEX MATCH "\"([0-9.]+)\"" _ "${_macro}")
set(sdk "${CMAKE_MATCH_1}")
file(STRINGS ${prefix}/lib/cmake/crumble/crumbleConfigVersion.cmake _pkg REGEX "set\\(PACKAGE_VERSION \"")
string(REGEX MATCH "\"([0-9.]+)\"" _ "${_pkg}")
set(package "${CMAKE_MATCH_1}")
if(printed STREQUAL "" OR NOT printed STREQUAL sdk OR NOT printed STREQUAL package)
  message(FATAL_ERROR "versions differ: --version '${printed}', CRUMBLE_VERSION '${sdk}', package '${package}'")
endif()

if(EXISTS ${prefix}/include/crumble/geometry/cgal/CgalMesh.h)
  message(FATAL_ERROR "the SDK must not ship headers that need CGAL")
endif()

set(launcher "")
if(LAUNCHER)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
step("configure the example plugin against the installed SDK"
     ${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples/plugin_diametral_split -B ${WORK}/build
     -DCMAKE_PREFIX_PATH=${prefix} -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${CXX} ${launcher})
step("build the example plugin" ${CMAKE_COMMAND} --build ${WORK}/build)
set(plugin ${WORK}/build/diametral_split.so)

step("crumble --plugin ... list" ${prefix}/bin/crumble --plugin ${plugin} list)
if(NOT step_output MATCHES "diametral_split")
  message(FATAL_ERROR "the plugin's model is not listed:\n${step_output}")
endif()
if(NOT step_output MATCHES "diametral_split_lsdem — ")
  message(FATAL_ERROR "the plugin's method is not listed:\n${step_output}")
endif()

# A 2 mm grain between platens: with a Weibull modulus of 1000 at d_c = d the strength is
# sigma_0 within 0.5 %, so the grain must split at F = sigma_0 d^2 = 80 N, within the check
# interval of the scene (0.1 MPa of platen stress, about 3.6 N).
step("run the single-grain scene with the plugin's model"
     ${prefix}/bin/crumble --plugin ${plugin} run ${SOURCE_DIR}/scenarios/single_grain_pd.json
     --out ${WORK}/run --quiet
     --set breakage.type=diametral_split --set breakage.strength=20e6 --set breakage.weibull_modulus=1000
     --set breakage.reference_diameter=2e-3)
file(READ ${WORK}/run/summary.json summary)
string(JSON events GET "${summary}" breakage_events)
string(JSON force GET "${summary}" crushing_force_N)
if(NOT events EQUAL 1)
  message(FATAL_ERROR "expected one breakage event, summary says ${events}")
endif()
if(force LESS 79 OR force GREATER 90)
  message(FATAL_ERROR "crushing force ${force} N, expected 80 N + one check interval")
endif()
message(STATUS "example plugin: ${events} event, crushing force ${force} N")
