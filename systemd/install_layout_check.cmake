# Installs the build in BINARY_DIR under PREFIX, as `cmake --install --prefix` does for a staging or inspection
# install, and checks that every file went under PREFIX (the autostart entry too: a /usr/local build staged
# elsewhere wrote it into the real /etc) and that the units name the programs where they now are. The component
# is named so that the install writes install_manifest_Unspecified.txt, leaving install_manifest.txt, which
# scripts/install keeps, alone.
#   cmake -DBINARY_DIR=... -DPREFIX=... -P install_layout_check.cmake
file(REMOVE_RECURSE "${PREFIX}")
execute_process(COMMAND "${CMAKE_COMMAND}" --install "${BINARY_DIR}" --prefix "${PREFIX}" --component Unspecified
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "cmake --install --prefix ${PREFIX} failed (${status}): ${err}")
endif()
file(STRINGS "${BINARY_DIR}/install_manifest_Unspecified.txt" installed)
list(LENGTH installed count)
if(count LESS 10)
  message(FATAL_ERROR "the install listed ${count} files")
endif()
foreach(file IN LISTS installed)
  string(FIND "${file}" "${PREFIX}/" at)
  if(NOT at EQUAL 0 OR NOT EXISTS "${file}")
    message(FATAL_ERROR "installed outside ${PREFIX}, or not there: ${file}")
  endif()
endforeach()
file(STRINGS "${PREFIX}/lib/systemd/system/pseudohapticd.service" exec REGEX "^ExecStart=")
if(NOT exec MATCHES "^ExecStart=${PREFIX}/sbin/pseudohapticd( |$)")
  message(FATAL_ERROR "the unit's ${exec} does not name ${PREFIX}/sbin/pseudohapticd")
endif()
if(EXISTS "${PREFIX}/bin/pseudohaptic-session" AND NOT EXISTS "${PREFIX}/etc/xdg/autostart/pseudohaptic-session.desktop")
  message(FATAL_ERROR "the session helper's autostart entry is not under ${PREFIX}/etc/xdg/autostart")
endif()
file(REMOVE_RECURSE "${PREFIX}")
message(STATUS "${count} files, all under ${PREFIX}")
