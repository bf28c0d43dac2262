# Installs the build into a fresh prefix and imports ceode from there: the package lands in
# PREFIX/SITE and its extension finds the installed libceode (not the build tree's).
# Usage: cmake -DBUILD=<build> -DPREFIX=<dir> -DSITE=<rel. dir> -DPYTHON=<python3> -P install_check.cmake
file(REMOVE_RECURSE ${PREFIX})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --prefix ${PREFIX}
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install failed (${rc})")
endif()
set(check [=[
import os, sys, ceode
prefix = os.path.realpath(sys.argv[1])
assert os.path.realpath(ceode.__file__).startswith(prefix), ceode.__file__
maps = open("/proc/self/maps").read()
libs = {line.split()[-1] for line in maps.splitlines() if "libceode" in line}
assert libs and all(os.path.realpath(p).startswith(prefix) for p in libs), libs
s = ceode.Integrator(lambda t, x, v, out: out.__setitem__(0, -x[0]), 0.0, [1.0], [0.0])
s.set_fixed_step(1e-3)
t, x, v = s.evolve(1.0)
assert abs(x[0] - 0.5403023058681398) < 1e-9, x
print("ceode", ceode.version(), "from", os.path.dirname(ceode.__file__))
]=])
execute_process(COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${PREFIX}/${SITE} PYTHONDONTWRITEBYTECODE=1
                        ${PYTHON} -c "${check}" ${PREFIX}
                WORKING_DIRECTORY ${PREFIX} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the installed package did not import and run (${rc})")
endif()
