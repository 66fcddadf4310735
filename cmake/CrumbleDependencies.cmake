# Every dependency comes from a Debian 12 package; a missing one is named with its package.
find_package(PkgConfig QUIET)

macro(crumble_require found pkg what)
  if(NOT ${found})
    message(FATAL_ERROR "crumble: ${what} not found. Install the Debian package: apt-get install ${pkg}"
                        "  (or turn the feature off with the matching CRUMBLE_WITH_* option)")
  endif()
endmacro()

find_package(nlohmann_json 3.10 QUIET)
crumble_require(nlohmann_json_FOUND nlohmann-json3-dev "nlohmann_json")

find_package(Eigen3 3.3 QUIET NO_MODULE)
crumble_require(Eigen3_FOUND libeigen3-dev "Eigen3")

find_package(OpenMP QUIET COMPONENTS CXX)
crumble_require(OpenMP_CXX_FOUND "g++ (libgomp)" "OpenMP")

find_package(Threads REQUIRED)

# The compressed binary arrays of the ParaView files (output.vtk_format).
find_package(ZLIB QUIET)
crumble_require(ZLIB_FOUND zlib1g-dev "zlib")

find_package(CLI11 QUIET CONFIG)
crumble_require(CLI11_FOUND libcli11-dev "CLI11")

if(CRUMBLE_WITH_BULLET)
  if(NOT PkgConfig_FOUND)
    message(FATAL_ERROR "crumble: pkg-config is needed to find Bullet: apt-get install pkg-config")
  endif()
  # Debian ships Bullet twice; only the float64 build may be linked, always together with
  # BT_USE_DOUBLE_PRECISION (mixing them corrupts memory silently).
  pkg_check_modules(BULLET64 QUIET IMPORTED_TARGET bullet-float64)
  crumble_require(BULLET64_FOUND libbullet-dev "Bullet (double precision, pkg-config bullet-float64)")
  get_target_property(_bt_defs PkgConfig::BULLET64 INTERFACE_COMPILE_OPTIONS)
  if(NOT "${BULLET64_CFLAGS}" MATCHES "BT_USE_DOUBLE_PRECISION")
    message(FATAL_ERROR "crumble: bullet-float64.pc does not define BT_USE_DOUBLE_PRECISION; refusing to mix precisions")
  endif()
endif()

if(CRUMBLE_WITH_ODE)
  pkg_check_modules(ODE QUIET IMPORTED_TARGET ode)
  crumble_require(ODE_FOUND libode-dev "ODE")
  # Only the double-precision build may be used (dReal = double on both sides).
  pkg_get_variable(ODE_PRECISION ode precision)
  if(NOT ODE_PRECISION STREQUAL "dDOUBLE")
    message(FATAL_ERROR "crumble: ode.pc says precision=${ODE_PRECISION}; the ode engine needs libode built with dDOUBLE")
  endif()
endif()

if(CRUMBLE_WITH_CGAL)
  find_package(CGAL QUIET)
  crumble_require(CGAL_FOUND libcgal-dev "CGAL")
endif()

if(CRUMBLE_MPI)
  find_package(MPI QUIET COMPONENTS CXX)
  if(NOT MPI_CXX_FOUND)
    message(FATAL_ERROR "crumble: CRUMBLE_MPI=ON but no MPI C++ development files were found. Install the Debian "
                        "package: apt-get install libopenmpi-dev (or run scripts/setup.sh --mpi), or configure "
                        "with -DCRUMBLE_MPI=OFF (the default)")
  endif()
endif()

if(CRUMBLE_BUILD_TESTS)
  find_package(GTest QUIET)
  crumble_require(GTest_FOUND libgtest-dev "GoogleTest")
endif()
