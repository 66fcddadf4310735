# The Python package (python/, docs/python.md) needs pybind11 and Python's headers. When either
# is missing, the module is skipped with one line saying how to get it; the C++ build is
# unaffected. The module links the same static libraries as the binary, so they are built as
# position-independent code when it is built.
option(CRUMBLE_WITH_PYTHON "Python module crumble (pybind11-dev, python3-dev; docs/python.md)" ON)
set(CRUMBLE_PYTHON_MODULE OFF)
if(CRUMBLE_WITH_PYTHON)
  # Debian's interpreter: python3-numpy, -pandas and -pytest install for it (another python3
  # earlier on PATH, e.g. a pyenv shim, would not see them). -DPython3_EXECUTABLE=... wins.
  if(NOT Python3_EXECUTABLE AND EXISTS /usr/bin/python3)
    set(Python3_EXECUTABLE /usr/bin/python3 CACHE FILEPATH "Python interpreter of the crumble module")
  endif()
  find_package(Python3 COMPONENTS Interpreter Development.Module)
  find_package(pybind11 CONFIG QUIET)
  if(NOT Python3_Development.Module_FOUND)
    set(_crumble_py_missing "Python headers not found")
  elseif(NOT pybind11_FOUND)
    set(_crumble_py_missing "pybind11 not found")
  endif()
  if(_crumble_py_missing)
    message(NOTICE "crumble: Python module skipped (${_crumble_py_missing}): apt-get install pybind11-dev python3-dev, or run scripts/setup.sh")
  else()
    set(CRUMBLE_PYTHON_MODULE ON)
    set(CMAKE_POSITION_INDEPENDENT_CODE ON)
  endif()
endif()
