# Packaging test: the installed CEODE package works for an out-of-tree C consumer, from a
# temporary prefix: with find_package(CEODE) + CEODE::ceode and with pkg-config (ceode.pc); the
# installed ceode-stability runs from the prefix and from a moved copy of it.
# A sanitized CEODE needs a sanitized consumer (the runtime must come first).
find_program(CEODE_PKG_CONFIG NAMES pkg-config pkgconf REQUIRED)
set(CEODE_CONSUMER_FLAGS "")
if(CEODE_SANITIZE)
  set(CEODE_CONSUMER_FLAGS "-fsanitize=address,undefined")
endif()
add_test(NAME package_installed_consumer
  COMMAND ${CMAKE_COMMAND}
    -DCEODE_BINARY_DIR=${PROJECT_BINARY_DIR}
    -DCONSUMER_SOURCE_DIR=${CMAKE_CURRENT_SOURCE_DIR}/consumer
    -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR}/consumer_work
    -DGENERATOR=${CMAKE_GENERATOR}
    -DBUILD_TYPE=$<IF:$<CONFIG:>,${CMAKE_BUILD_TYPE},$<CONFIG>>
    -DC_COMPILER=${CMAKE_C_COMPILER}
    "-DEXTRA_FLAGS=${CEODE_CONSUMER_FLAGS}"
    -DSUNDIALS_DIR_BUILT=${CEODE_SUNDIALS_DIR} -DSUNDIALS_VERSION_BUILT=${CEODE_SUNDIALS_VERSION}
    -DLIBDIR=${CMAKE_INSTALL_LIBDIR} -DBINDIR=${CMAKE_INSTALL_BINDIR}
    -DPKG_CONFIG=${CEODE_PKG_CONFIG} -DCEODE_VERSION=${CEODE_VERSION_STRING}
    -P ${CMAKE_CURRENT_SOURCE_DIR}/consumer/run_consumer.cmake)
# Configures and builds a project: seconds, not milliseconds.
set_tests_properties(package_installed_consumer PROPERTIES LABELS "packaging;slow" TIMEOUT 600)
