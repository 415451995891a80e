# Installs the build in BINARY_DIR under PREFIX (not /usr nor /usr/local), as `cmake --install --prefix` does for a
# staging or inspection install, into the folder STAGE (DESTDIR: nothing reaches the real system, whatever the
# build's settings), and checks that every file went under PREFIX (the autostart entry too: a /usr/local build
# staged elsewhere wrote it into the real /etc) and that the unit names the daemon where it now is. The component
# is named so that the install writes install_manifest_Unspecified.txt, leaving install_manifest.txt, which
# scripts/install keeps, alone. Paths are compared as text, not as regular expressions (a build folder may have
# "c++" in its path).
#   cmake -DBINARY_DIR=... -DSTAGE=... -DPREFIX=/opt/... -DAUTOSTART_DIR=... -P install_layout_check.cmake
file(REMOVE_RECURSE "${STAGE}")
set(ENV{DESTDIR} "${STAGE}")
execute_process(COMMAND "${CMAKE_COMMAND}" --install "${BINARY_DIR}" --prefix "${PREFIX}" --component Unspecified
                RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "cmake --install --prefix ${PREFIX} (DESTDIR ${STAGE}) failed (${status}): ${err}")
endif()
file(STRINGS "${BINARY_DIR}/install_manifest_Unspecified.txt" installed)
list(LENGTH installed count)
if(count LESS 10)
  message(FATAL_ERROR "the install listed ${count} files")
endif()
# (The manifest names the files without DESTDIR.)
set(staged "${STAGE}${PREFIX}/")
foreach(file IN LISTS installed)
  string(FIND "${file}" "${PREFIX}/" at)
  if(NOT at EQUAL 0 OR NOT EXISTS "${STAGE}${file}")
    set(hint "")
    if(file MATCHES "autostart")
      set(hint " (PH_XDG_AUTOSTART_DIR is ${AUTOSTART_DIR}: auto follows the prefix in force at install time)")
    endif()
    message(FATAL_ERROR "installed outside the prefix ${PREFIX}, or not there: ${file}${hint}")
  endif()
endforeach()
file(STRINGS "${staged}lib/systemd/system/pseudohapticd.service" exec REGEX "^ExecStart=")
string(FIND "${exec}" "ExecStart=${PREFIX}/sbin/pseudohapticd" at)
if(NOT at EQUAL 0)
  message(FATAL_ERROR "the unit's ${exec} does not name ${PREFIX}/sbin/pseudohapticd")
endif()
if(EXISTS "${staged}bin/pseudohaptic-session" AND NOT EXISTS "${staged}etc/xdg/autostart/pseudohaptic-session.desktop")
  message(FATAL_ERROR "the session helper's autostart entry is not under ${PREFIX}/etc/xdg/autostart")
endif()
file(REMOVE_RECURSE "${STAGE}")
message(STATUS "${count} files, all under ${PREFIX} (staged in ${STAGE})")
