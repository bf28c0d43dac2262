# Driver of the packaging test (cmake -P): install the current build tree into a fresh prefix,
# then, against that prefix only: configure, build and run test/consumer with find_package(CEODE);
# run the installed ceode-stability; move the prefix elsewhere, run the tool again (it must load
# libceode from beside it, not from the build tree) and build and run the same consumer with
# `pkg-config --cflags --libs ceode` (the .pc file must follow the move).
# Inputs: CEODE_BINARY_DIR, CONSUMER_SOURCE_DIR, WORK_DIR, GENERATOR, BUILD_TYPE, C_COMPILER,
# EXTRA_FLAGS (compile and link flags of the consumer, e.g. sanitizers), SUNDIALS_DIR_BUILT (the
# SUNDIALS CEODE was built with: the consumer must get that one, even behind a decoy), LIBDIR and
# BINDIR (CMAKE_INSTALL_LIBDIR/BINDIR), PKG_CONFIG (the pkg-config program), CEODE_VERSION.
foreach(var CEODE_BINARY_DIR CONSUMER_SOURCE_DIR WORK_DIR LIBDIR BINDIR PKG_CONFIG CEODE_VERSION)
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
         -DCMAKE_BUILD_RPATH=${prefix}/${LIBDIR})
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

# The installed tool, from the prefix and from a moved copy of it (RPATH $ORIGIN/../lib).
function(run_tool root)
  set(tool ${root}/${BINDIR}/ceode-stability)
  execute_process(COMMAND ${tool} --method G5_O4 RESULT_VARIABLE rv OUTPUT_VARIABLE out
                  ERROR_VARIABLE err)
  string(FIND "${out}" "Omega_max 1.97065" pos)
  if(NOT rv EQUAL 0 OR pos EQUAL -1)
    message(FATAL_ERROR "${tool} --method G5_O4 failed (${rv}):\n${out}${err}")
  endif()
  message("${tool} --method G5_O4:\n${out}")
  find_program(LDD ldd)
  if(LDD)
    execute_process(COMMAND ${LDD} ${tool} OUTPUT_VARIABLE libs)
    set(loaded "")
    if(libs MATCHES "libceode[^ \t\n]* => ([^ \t\n]+)")
      get_filename_component(loaded "${CMAKE_MATCH_1}" DIRECTORY)
      file(REAL_PATH "${loaded}" loaded)
    endif()
    file(REAL_PATH ${root}/${LIBDIR} real_libdir)
    if(NOT loaded STREQUAL real_libdir)
      message(FATAL_ERROR "${tool} does not load libceode from ${root}/${LIBDIR}:\n${libs}")
    endif()
  endif()
endfunction()
run_tool(${prefix})
set(moved ${WORK_DIR}/moved)
file(RENAME ${prefix} ${moved})
run_tool(${moved})

# The consumer again, compiled by hand with the flags of the moved prefix's ceode.pc.
set(ENV{PKG_CONFIG_PATH} ${moved}/${LIBDIR}/pkgconfig)
execute_process(COMMAND ${PKG_CONFIG} --modversion ceode OUTPUT_VARIABLE pc_version
                OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rv)
if(NOT rv EQUAL 0 OR NOT pc_version STREQUAL CEODE_VERSION)
  message(FATAL_ERROR "pkg-config ceode: version '${pc_version}' (${rv}), expected ${CEODE_VERSION}")
endif()
execute_process(COMMAND ${PKG_CONFIG} --cflags --libs ceode OUTPUT_VARIABLE pc_flags
                OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rv)
if(NOT rv EQUAL 0)
  message(FATAL_ERROR "pkg-config --cflags --libs ceode failed (${rv})")
endif()
message("pkg-config --cflags --libs ceode: ${pc_flags}")
separate_arguments(pc_flags UNIX_COMMAND "${pc_flags}")
separate_arguments(extra UNIX_COMMAND "${EXTRA_FLAGS}")
# Every library directory of the flags also as a run path (the prefix, a SUNDIALS elsewhere).
set(rpaths)
foreach(flag IN LISTS pc_flags)
  if(flag MATCHES "^-L(.+)")
    list(APPEND rpaths "-Wl,-rpath,${CMAKE_MATCH_1}")
  endif()
endforeach()
if(NOT C_COMPILER)
  set(C_COMPILER cc)
endif()
set(pc_exe ${WORK_DIR}/consumer_pkg_config)
run_step("build consumer with pkg-config" ${C_COMPILER} ${extra} ${CONSUMER_SOURCE_DIR}/main.c
         -o ${pc_exe} ${pc_flags} -lsundials_nvecserial -lm ${rpaths})
run_step("run consumer built with pkg-config" ${pc_exe})
