# Installation and the Debian package (README "Packages"):
#   cmake --install build/release --prefix /usr/local
#   (cd build/release && cpack -G DEB)
# installs mocosim, mococheck and dmc-host, their man pages (made at build
# time from each program's --help by cmake/help_to_man.cmake), the device
# and rig profiles, the Wireshark dissector and the documents (docs/). The programs need nothing
# from the source tree at run time: every device model has its profile
# built in; the installed profiles are for --profile.
include(GNUInstallDirs)

install(TARGETS mocosim mococheck dmc-host mococheck-build-native
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# The host Arduino core's sources, which mococheck-build-native compiles with a
# sketch (it looks for them in ../share/mocosim/arduino beside itself).
foreach(part include core boards)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/conformance/arduino/${part}/
          DESTINATION ${CMAKE_INSTALL_DATADIR}/mocosim/arduino/${part})
endforeach()
install(FILES ${PROJECT_SOURCE_DIR}/conformance/arduino/link.h
        DESTINATION ${CMAKE_INSTALL_DATADIR}/mocosim/arduino)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/fixtures/profiles/
        DESTINATION ${CMAKE_INSTALL_DATADIR}/mocosim/profiles FILES_MATCHING PATTERN "*.json")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/fixtures/rigs/
        DESTINATION ${CMAKE_INSTALL_DATADIR}/mocosim/rigs FILES_MATCHING PATTERN "*.json")
# The board and step-driver profiles mococheck's --board and --driver take.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/fixtures/boards/
        DESTINATION ${CMAKE_INSTALL_DATADIR}/mocosim/boards FILES_MATCHING PATTERN "*.json")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/fixtures/drivers/
        DESTINATION ${CMAKE_INSTALL_DATADIR}/mocosim/drivers FILES_MATCHING PATTERN "*.json")
install(FILES ${PROJECT_SOURCE_DIR}/tools/wireshark/mocosim.lua
        DESTINATION ${CMAKE_INSTALL_DATADIR}/mocosim/wireshark)
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})
# The documents reports and evidence cite ("docs/device-facts.md, DMC v2",
# docs/rules.md), beside the README as in the source tree.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/docs
        FILES_MATCHING PATTERN "*.md" PATTERN "*.svg")

# Installed compressed (gzip -9n: no name or time stamp, so the same bytes
# every build), as Debian's policy has man pages.
set(moco_man_pages)
foreach(program mocosim mococheck dmc-host mococheck-build-native)
  set(page ${CMAKE_BINARY_DIR}/man/${program}.1)
  add_custom_command(
    OUTPUT ${page}.gz
    COMMAND ${CMAKE_COMMAND} -DPROGRAM=$<TARGET_FILE:${program}> -DNAME=${program}
            -DVERSION=${PROJECT_VERSION} -DOUTPUT=${page}
            -P ${PROJECT_SOURCE_DIR}/cmake/help_to_man.cmake
    COMMAND gzip -9nf ${page}
    DEPENDS ${program} ${PROJECT_SOURCE_DIR}/cmake/help_to_man.cmake
    COMMENT "Man page ${program}.1.gz from ${program} --help"
    VERBATIM)
  list(APPEND moco_man_pages ${page}.gz)
endforeach()
add_custom_target(man_pages ALL DEPENDS ${moco_man_pages})
install(FILES ${moco_man_pages} DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)

# The package's maintainer: whoever publishes it. The default is a
# placeholder with no mailbox behind it (ci/deb-check names it when lintian
# flags it); a publisher configures with -DMOCOSIM_PACKAGE_CONTACT="Name <address>".
set(MOCOSIM_PACKAGE_CONTACT "mocosim maintainers <mocosim@invalid>"
    CACHE STRING "Maintainer of the .deb, as Name <address>")

# Debian's policy asks every package for its copyright file and, a native
# package, for its changelog as changelog.gz, both in /usr/share/doc/<package>.
# The changelog's newest entry is this version: a version bump without one
# stops the configure.
file(STRINGS ${PROJECT_SOURCE_DIR}/cmake/debian/changelog.in moco_changelog_head LIMIT_COUNT 1)
if(NOT moco_changelog_head MATCHES "^mocosim \\(${PROJECT_VERSION}\\) ")
  message(FATAL_ERROR "cmake/debian/changelog.in starts with \"${moco_changelog_head}\", not "
                      "version ${PROJECT_VERSION}: add an entry for ${PROJECT_VERSION} at its top")
endif()
configure_file(${PROJECT_SOURCE_DIR}/cmake/debian/changelog.in ${CMAKE_BINARY_DIR}/debian/changelog
               @ONLY)
configure_file(${PROJECT_SOURCE_DIR}/cmake/debian/copyright.in ${CMAKE_BINARY_DIR}/debian/copyright
               @ONLY)
add_custom_command(
  OUTPUT ${CMAKE_BINARY_DIR}/debian/doc/changelog.gz
  COMMAND ${CMAKE_COMMAND} -E copy ${CMAKE_BINARY_DIR}/debian/changelog
          ${CMAKE_BINARY_DIR}/debian/doc/changelog
  COMMAND gzip -9nf ${CMAKE_BINARY_DIR}/debian/doc/changelog
  DEPENDS ${CMAKE_BINARY_DIR}/debian/changelog
  COMMENT "changelog.gz for the package"
  VERBATIM)
add_custom_target(debian_changelog ALL DEPENDS ${CMAKE_BINARY_DIR}/debian/doc/changelog.gz)
install(FILES ${CMAKE_BINARY_DIR}/debian/doc/changelog.gz ${CMAKE_BINARY_DIR}/debian/copyright
        DESTINATION ${CMAKE_INSTALL_DOCDIR})

# CPack: a .deb whose Depends are the Debian runtime packages the programs
# link (dpkg-shlibdeps, from dpkg-dev), e.g. libc6, libstdc++6, libbullet3.24.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME mocosim)
set(CPACK_PACKAGE_VENDOR "mocosim")
set(CPACK_PACKAGE_CONTACT "${MOCOSIM_PACKAGE_CONTACT}")
# At most 80 characters (Debian policy 3.4.1).
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "motion-control device emulator and conformance checker")
# Lines of at most 80 characters; one string: set() with several would join
# them with ";".
string(CONCAT CPACK_PACKAGE_DESCRIPTION
       "mocosim emulates a DMC-16 (DMC v2 binary protocol), a DFMoco Arduino\n"
       "and a Cognisys StackShot 3X on a PTY or a TCP port; mococheck checks a\n"
       "device's traffic against the rules of its protocol. With man pages,\n"
       "device profiles and a Wireshark dissector.")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION utils)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "tshark | wireshark")
set(CPACK_STRIP_FILES ON)
set(CPACK_PACKAGE_DIRECTORY ${CMAKE_BINARY_DIR}/packages)
include(CPack)

# The package is built, unpacked into a scratch root with dpkg -x, and the
# installed mococheck runs the DMC-16 suite in-process from there, away from
# the source tree (ci/deb-check).
if(MOCO_BUILD_TESTS)
  add_test(NAME package_deb_unpacked_runs_mococheck_from_the_installed_tree
           COMMAND bash ${PROJECT_SOURCE_DIR}/ci/deb-check ${CMAKE_BINARY_DIR}
                   ${CMAKE_BINARY_DIR}/deb-check)
  set_tests_properties(package_deb_unpacked_runs_mococheck_from_the_installed_tree
                       PROPERTIES SKIP_RETURN_CODE 77 TIMEOUT 600)
endif()
