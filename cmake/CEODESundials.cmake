# SUNDIALS 6.4 and 7.x from one source tree (docs/user_guide.md, "SUNDIALS 6.4 and 7.x").
# SUNDIALS 7 renamed SUNDIALS::generic to SUNDIALS::core; on an MPI build core also
# carries MPI::MPI_C, which its headers need (they include mpi.h).
if(TARGET SUNDIALS::core)
  set(CEODE_SUNDIALS_CORE SUNDIALS::core)
else()
  set(CEODE_SUNDIALS_CORE SUNDIALS::generic)
endif()
# Recorded in CEODEConfig.cmake: a consumer gets the SUNDIALS CEODE was built with.
get_filename_component(CEODE_SUNDIALS_DIR "${SUNDIALS_DIR}" REALPATH)
set(CEODE_SUNDIALS_VERSION ${SUNDIALS_VERSION})
message(STATUS "CEODE: SUNDIALS ${SUNDIALS_VERSION} from ${CEODE_SUNDIALS_DIR}")

# Tests, examples and benchmarks: support/ceode_sundials_compat.h (not installed).
add_library(ceode_sundials_compat INTERFACE)
target_include_directories(ceode_sundials_compat INTERFACE ${CMAKE_CURRENT_LIST_DIR}/../support)
target_link_libraries(ceode_sundials_compat INTERFACE ${CEODE_SUNDIALS_CORE})
# One source serves 6.4, where ERKStep*/ARKStep* are the only option calls; 7.1 deprecated
# them in favour of ARKode* (same behaviour), which would flood the build log.
if(SUNDIALS_VERSION VERSION_GREATER_EQUAL 7.1)
  target_compile_options(ceode_sundials_compat INTERFACE -Wno-deprecated-declarations)
endif()
# An installed libceode must find a SUNDIALS off the system path (its libraries are
# linked by full path, which INSTALL_RPATH_USE_LINK_PATH does not cover).
get_filename_component(CEODE_SUNDIALS_LIBDIR "${CEODE_SUNDIALS_DIR}/../.." ABSOLUTE)
if(NOT CEODE_SUNDIALS_LIBDIR IN_LIST CMAKE_CXX_IMPLICIT_LINK_DIRECTORIES)
  set(CEODE_SUNDIALS_RPATH ${CEODE_SUNDIALS_LIBDIR})
endif()
