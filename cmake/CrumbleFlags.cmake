add_library(crumble_flags INTERFACE)
target_compile_options(crumble_flags INTERFACE -Wall -Wextra -Wno-unused-parameter)
target_include_directories(crumble_flags INTERFACE ${PROJECT_SOURCE_DIR} ${PROJECT_BINARY_DIR}/generated)

# CRUMBLE_SANITIZE: a list of sanitizers for -fsanitize= (e.g. "address,undefined"); ON means
# "address,undefined". Every crumble target (and the test programs, through crumble_flags) is
# instrumented; a UBSan finding aborts instead of printing and continuing, so a test that
# triggers one fails. scripts/sanitize.sh configures build-asan this way and runs the tests.
if(CRUMBLE_SANITIZE)
  if(CRUMBLE_SANITIZE STREQUAL "ON" OR CRUMBLE_SANITIZE STREQUAL "TRUE" OR CRUMBLE_SANITIZE STREQUAL "1")
    set(_crumble_sanitizers "address,undefined")
  else()
    set(_crumble_sanitizers "${CRUMBLE_SANITIZE}")
  endif()
  if(NOT _crumble_sanitizers MATCHES "^[a-z,]+$")
    message(FATAL_ERROR "CRUMBLE_SANITIZE='${CRUMBLE_SANITIZE}': expected a comma-separated list such as address,undefined")
  endif()
  message(STATUS "crumble: sanitizers ${_crumble_sanitizers}")
  set(_crumble_sanitize_flags -fsanitize=${_crumble_sanitizers} -fno-omit-frame-pointer)
  if(_crumble_sanitizers MATCHES "undefined")
    list(APPEND _crumble_sanitize_flags -fno-sanitize-recover=undefined)
  endif()
  target_compile_options(crumble_flags INTERFACE ${_crumble_sanitize_flags})
  target_link_options(crumble_flags INTERFACE -fsanitize=${_crumble_sanitizers})
endif()
