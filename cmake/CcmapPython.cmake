# CCMAP_BUILD_PYTHON: the Python module `ccmap` (tools/python, pybind11 + NumPy), a host tool
# that is never part of the flight core.
#   AUTO (default)  ON when this is a host build with the tools and Debian's pybind11 and NumPy
#                   are found, else OFF (with a status line saying why)
#   ON              required: a missing pybind11/NumPy stops the configure with the apt-get line
#   OFF             not built
# The interpreter is Debian's /usr/bin/python3 unless Python3_EXECUTABLE says otherwise (an
# interpreter from pyenv or a venv does not see Debian's python3-numpy and python3-pybind11).
# Sets CCMAP_PYTHON_ENABLED.
set(CCMAP_BUILD_PYTHON AUTO CACHE STRING
    "Build the Python module (tools/python): AUTO (when pybind11 and NumPy are found on a host build), ON, OFF")
set_property(CACHE CCMAP_BUILD_PYTHON PROPERTY STRINGS AUTO ON OFF)
set(_ccmap_python_apt "apt-get install pybind11-dev python3-pybind11 python3-numpy (or: tools/install-deps python)")

set(CCMAP_PYTHON_ENABLED OFF)
string(TOUPPER "${CCMAP_BUILD_PYTHON}" _ccmap_python_mode)
if(_ccmap_python_mode STREQUAL "AUTO")
  set(_ccmap_python_required OFF)
elseif(CCMAP_BUILD_PYTHON)
  set(_ccmap_python_required ON)
else()
  return()
endif()

if(CMAKE_CROSSCOMPILING OR NOT CCMAP_BUILD_TOOLS)
  if(_ccmap_python_required)
    message(FATAL_ERROR "CCMAP_BUILD_PYTHON=ON needs a host build with CCMAP_BUILD_TOOLS=ON")
  endif()
  return()
endif()
# Under CCMAP_SANITIZE the module is instrumented too; an uninstrumented interpreter can load it
# only with the sanitizer runtimes preloaded: CCMAP_PYTHON_PRELOAD (the tests set LD_PRELOAD to
# it). gcc's runtimes are found with -print-file-name; other compilers leave the module out.
set(CCMAP_PYTHON_PRELOAD "")
if(CCMAP_SANITIZE)
  foreach(_runtime libasan.so libubsan.so)
    execute_process(COMMAND ${CMAKE_CXX_COMPILER} -print-file-name=${_runtime}
                    OUTPUT_VARIABLE _path OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
    if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "GNU" OR NOT IS_ABSOLUTE "${_path}" OR NOT EXISTS "${_path}")
      if(_ccmap_python_required)
        message(FATAL_ERROR "CCMAP_BUILD_PYTHON=ON with CCMAP_SANITIZE: ${_runtime} of gcc not found")
      endif()
      message(STATUS "ccmap: Python module not built (CCMAP_SANITIZE needs gcc's ${_runtime} to preload)")
      return()
    endif()
    string(APPEND CCMAP_PYTHON_PRELOAD "${_path} ")
  endforeach()
  string(STRIP "${CCMAP_PYTHON_PRELOAD}" CCMAP_PYTHON_PRELOAD)
endif()

if(NOT DEFINED Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
  set(Python3_EXECUTABLE /usr/bin/python3 CACHE FILEPATH "Interpreter the Python module is built for")
endif()
find_package(Python3 3.7 COMPONENTS Interpreter Development.Module NumPy QUIET)
if(Python3_FOUND)
  find_package(pybind11 2.6 CONFIG QUIET)
endif()
if(NOT Python3_FOUND OR NOT pybind11_FOUND)
  if(_ccmap_python_required)
    message(FATAL_ERROR "CCMAP_BUILD_PYTHON=ON: pybind11 or NumPy for ${Python3_EXECUTABLE} not found: ${_ccmap_python_apt}")
  endif()
  message(STATUS "ccmap: Python module not built (pybind11 or NumPy not found: ${_ccmap_python_apt})")
  return()
endif()
set(CCMAP_PYTHON_ENABLED ON)
message(STATUS "ccmap: Python module for ${Python3_EXECUTABLE} (${Python3_VERSION}), pybind11 ${pybind11_VERSION}")
