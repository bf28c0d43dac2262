# Driver of the packaging test (cmake -P): install the current build tree into a
# fresh prefix, then configure, build and run test/consumer against that prefix.
# Inputs: CEODE_BINARY_DIR, CONSUMER_SOURCE_DIR, WORK_DIR, GENERATOR, BUILD_TYPE, C_COMPILER,
# EXTRA_FLAGS (compile and link flags of the consumer, e.g. sanitizers), SUNDIALS_DIR_BUILT (the
# SUNDIALS CEODE was built with: the consumer must get that one, even behind a decoy).
foreach(var CEODE_BINARY_DIR CONSUMER_SOURCE_DIR WORK_DIR)
  if(NOT ${var})
    message(FATAL_ERROR "run_consumer.cmake needs -D${var}=...")
  endif()
endforeach()
if(NOT BUILD_TYPE)
  set(BUILD_TYPE Release)
endif()

set(prefix ${WORK_DIR}/prefix)
set(build ${WORK_DIR}/build)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})

function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rv OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${out}")
  if(NOT rv EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rv}):\n${err}")
  endif()
endfunction()

run_step("cmake --install" ${CMAKE_COMMAND} --install ${CEODE_BINARY_DIR} --prefix ${prefix}
         --config ${BUILD_TYPE})

set(gen_args)
if(GENERATOR)
  list(APPEND gen_args -G ${GENERATOR})
endif()
if(C_COMPILER)
  list(APPEND gen_args -DCMAKE_C_COMPILER=${C_COMPILER})
endif()
if(EXTRA_FLAGS)
  list(APPEND gen_args -DCMAKE_C_FLAGS=${EXTRA_FLAGS} -DCMAKE_EXE_LINKER_FLAGS=${EXTRA_FLAGS})
endif()
# A decoy SUNDIALS of the same version, first on the search path (SUNDIALS_ROOT): CEODEConfig.cmake
# must go to the SUNDIALS it was built with instead (6.4.1 in /usr vs an -O3 copy, say).
set(decoy ${WORK_DIR}/decoy/lib/cmake/sundials)
file(WRITE ${decoy}/SUNDIALSConfig.cmake "message(FATAL_ERROR \"decoy SUNDIALS found\")\n")
file(WRITE ${decoy}/SUNDIALSConfigVersion.cmake
     "set(PACKAGE_VERSION \"${SUNDIALS_VERSION_BUILT}\")\nset(PACKAGE_VERSION_COMPATIBLE TRUE)\n"
     "set(PACKAGE_VERSION_EXACT TRUE)\n")
# Only the prefix may provide CEODE: no package registry, no build-tree export.
run_step("configure consumer" ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE_DIR} -B ${build} ${gen_args}
         -DCMAKE_BUILD_TYPE=${BUILD_TYPE} -DCMAKE_PREFIX_PATH=${prefix}
         -DSUNDIALS_ROOT=${WORK_DIR}/decoy
         -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON
         -DCMAKE_BUILD_RPATH=${prefix}/lib)
file(READ ${build}/ceode_dir.txt ceode_dir)
file(REAL_PATH ${prefix} real_prefix)
file(REAL_PATH ${ceode_dir} real_ceode_dir)
string(FIND "${real_ceode_dir}" "${real_prefix}/" pos)
if(NOT pos EQUAL 0)
  message(FATAL_ERROR "CEODE was found at ${ceode_dir}, not in the install prefix ${prefix}")
endif()
if(SUNDIALS_DIR_BUILT)
  file(READ ${build}/sundials_dir.txt sundials_dir)
  file(REAL_PATH ${sundials_dir} real_sundials_dir)
  file(REAL_PATH ${SUNDIALS_DIR_BUILT} real_sundials_built)
  if(NOT real_sundials_dir STREQUAL real_sundials_built)
    message(FATAL_ERROR "The consumer got SUNDIALS from ${sundials_dir}, CEODE was built with "
                        "${SUNDIALS_DIR_BUILT}")
  endif()
endif()
run_step("build consumer" ${CMAKE_COMMAND} --build ${build} --config ${BUILD_TYPE})

find_program(consumer_exe consumer PATHS ${build} ${build}/${BUILD_TYPE} NO_DEFAULT_PATH)
if(NOT consumer_exe)
  message(FATAL_ERROR "The consumer executable was not built in ${build}")
endif()
run_step("run consumer" ${consumer_exe})
