# Installs rubdyn from its build tree into a scratch prefix, builds examples/consumer against it
# with find_package(rubdyn), runs it on the reference case, and checks that the installed
# library computes what the CLI of the build tree computes (omega at the end, bitwise; a wrong
# or stale install, a missing header or dependency fails here).
#   cmake -DBUILD=<rubdyn build dir> -DSOURCE=<rubdyn source dir> -DWORK=<scratch dir>
#         -DCLI=<rubdyn executable> -P consumer_test.cmake
file(REMOVE_RECURSE ${WORK})
function(run)
  execute_process(COMMAND ${ARGV} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGV}\n${out}\n${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()

run(${CMAKE_COMMAND} --install ${BUILD} --prefix ${WORK}/prefix)
foreach(f include/rubdyn/hybrid/event_driven.hpp lib/cmake/rubdyn/rubdynConfig.cmake
          lib/cmake/rubdyn/rubdynConfigVersion.cmake bin/rubdyn)
  if(NOT EXISTS ${WORK}/prefix/${f})
    message(FATAL_ERROR "not installed: ${f}")
  endif()
endforeach()
run(${CMAKE_COMMAND} -S ${SOURCE}/examples/consumer -B ${WORK}/build -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_PREFIX_PATH=${WORK}/prefix)
run(${CMAKE_COMMAND} --build ${WORK}/build)
# 50 ms of the reference case: 6 events, a few ms of run time
run(${WORK}/build/consumer ${SOURCE}/cases/reference.toml run.t_end=0.05
    output.folder=${WORK}/unused)
string(REGEX MATCH "omega ([^ ]+) rad/s" _ "${out}")
set(omega_consumer ${CMAKE_MATCH_1})
run(${CLI} run ${SOURCE}/cases/reference.toml --t-end 0.05 --out ${WORK}/cli)
file(READ ${WORK}/cli/summary.json summary)
string(JSON omega_cli GET "${summary}" omega_final)
message(STATUS "consumer: omega ${omega_consumer}; CLI: omega ${omega_cli}")
if(NOT omega_consumer OR NOT omega_consumer EQUAL omega_cli)
  message(FATAL_ERROR "the installed library gives omega ${omega_consumer}, the CLI ${omega_cli}")
endif()
