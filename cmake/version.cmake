# Writes OUTPUT, the C++ source of mesopen::programVersion(): the project's VERSION and
# `git describe` of SOURCE_DIR ("unknown" outside a git clone). Run at every build; the file is
# rewritten only when its text changes, so that an unchanged version rebuilds nothing.
execute_process(
  COMMAND git -C "${SOURCE_DIR}" describe --always --dirty --tags
  OUTPUT_VARIABLE describe
  OUTPUT_STRIP_TRAILING_WHITESPACE
  ERROR_QUIET
  RESULT_VARIABLE failed)
if(failed OR describe STREQUAL "")
  set(describe "unknown")
endif()
string(CONCAT text "// Written at build time by cmake/version.cmake.\n#include \"version.hpp\"\n\n"
         "const char *mesopen::programVersion() { return \"${VERSION} (git ${describe})\"; }\n")
set(old "")
if(EXISTS "${OUTPUT}")
  file(READ "${OUTPUT}" old)
endif()
if(NOT old STREQUAL text)
  file(WRITE "${OUTPUT}" "${text}")
endif()
