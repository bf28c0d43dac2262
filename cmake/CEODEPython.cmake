# The Python module (python/): ON by default when pybind11 (Debian: pybind11-dev) and a Python 3
# with its headers and NumPy are found, OFF otherwise with the reason. -DCEODE_BUILD_PYTHON=ON
# makes a missing dependency an error; OFF skips the search. The interpreter is FindPython3's
# (the first python3 on PATH): -DPython3_EXECUTABLE=/usr/bin/python3 selects Debian's.
set(CEODE_PYTHON_MISSING "")
if(NOT DEFINED CEODE_BUILD_PYTHON OR CEODE_BUILD_PYTHON)
  find_package(Python3 3.7 COMPONENTS Interpreter Development.Module NumPy QUIET)
  if(NOT Python3_FOUND)
    string(CONCAT CEODE_PYTHON_MISSING
           "no Python 3 with development headers and NumPy (interpreter: '${Python3_EXECUTABLE}'; "
           "Debian: python3-dev python3-numpy, or -DPython3_EXECUTABLE=/usr/bin/python3)")
  else()
    set(PYBIND11_FINDPYTHON ON)  # pybind11 takes the Python3 found above
    find_package(pybind11 CONFIG QUIET)
    if(NOT pybind11_FOUND)
      set(CEODE_PYTHON_MISSING "pybind11 not found (Debian: pybind11-dev)")
    endif()
  endif()
endif()
if(DEFINED CEODE_BUILD_PYTHON AND CEODE_BUILD_PYTHON AND CEODE_PYTHON_MISSING)
  message(FATAL_ERROR "CEODE_BUILD_PYTHON=ON, but ${CEODE_PYTHON_MISSING}")
endif()
if(CEODE_PYTHON_MISSING)
  set(CEODE_PYTHON_DEFAULT OFF)
else()
  set(CEODE_PYTHON_DEFAULT ON)
endif()
option(CEODE_BUILD_PYTHON "Build the Python module ceode (needs pybind11 and NumPy)"
       ${CEODE_PYTHON_DEFAULT})
if(CEODE_BUILD_PYTHON)
  message(STATUS "CEODE: Python module ON (Python ${Python3_VERSION}, ${Python3_EXECUTABLE})")
elseif(CEODE_PYTHON_MISSING)
  message(STATUS "CEODE: Python module OFF: ${CEODE_PYTHON_MISSING}")
else()
  message(STATUS "CEODE: Python module OFF (CEODE_BUILD_PYTHON=OFF)")
endif()
