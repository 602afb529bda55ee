# The Debian package of rtfuse (docs/packaging.md): install rules and CPack.
#
#   cmake --build BUILD --target rtfuse_deb      # builds what it packs, then cpack
#   cpack -G DEB --config BUILD/CPackConfig.cmake
#
# Both write BUILD/packages/rtfuse_<version>_<arch>.deb, where <arch> is the
# Debian architecture of the compiler's target (arm64 in a cross tree made
# with toolchains/aarch64-jetson-tx2.cmake), never the host's. Depends is
# worked out when cpack runs, from the NEEDED entries and symbol versions of
# the packed programs (packaging/deb-depends.cmake), so a static libstdc++
# (the cross toolchain's default) drops libstdc++6 and a native build keeps it.

set(RTFUSE_PACKAGE_PROGRAMS rtfused rtfuse-replay rtfuse-sim rtfuse-camera-snapshot rtfuse-canopen-node)
foreach(prog IN LISTS RTFUSE_PACKAGE_PROGRAMS)
  if(NOT TARGET ${prog})
    message(FATAL_ERROR "Packaging: program target '${prog}' does not exist (src/apps)")
  endif()
endforeach()

# --- Debian architecture of the target -------------------------------------
# The compiler knows what it builds for (x86_64-linux-gnu, aarch64-linux-gnu);
# CMAKE_SYSTEM_PROCESSOR is the fallback (in a native build it is uname -m).
execute_process(COMMAND ${CMAKE_CXX_COMPILER} -dumpmachine
                OUTPUT_VARIABLE _rtfuse_triplet OUTPUT_STRIP_TRAILING_WHITESPACE
                RESULT_VARIABLE _rtfuse_dump_rc ERROR_QUIET)
if(_rtfuse_dump_rc EQUAL 0 AND _rtfuse_triplet)
  string(REGEX REPLACE "-.*" "" _rtfuse_cpu "${_rtfuse_triplet}")
else()
  set(_rtfuse_cpu "${CMAKE_SYSTEM_PROCESSOR}")
endif()
string(TOLOWER "${_rtfuse_cpu}" _rtfuse_cpu)
if(_rtfuse_cpu MATCHES "^(aarch64|arm64)$")
  set(RTFUSE_DEB_ARCH arm64)
elseif(_rtfuse_cpu MATCHES "^(x86_64|amd64)$")
  set(RTFUSE_DEB_ARCH amd64)
elseif(_rtfuse_cpu MATCHES "^(i[3-6]86)$")
  set(RTFUSE_DEB_ARCH i386)
elseif(_rtfuse_cpu MATCHES "^arm")
  set(RTFUSE_DEB_ARCH armhf)
else()
  message(FATAL_ERROR "Packaging: no Debian architecture known for target CPU '${_rtfuse_cpu}' "
                      "(compiler ${CMAKE_CXX_COMPILER}, triplet '${_rtfuse_triplet}')")
endif()

# --- What the package installs ----------------------------------------------
# Destinations are relative to the root of the package (cpack installs with
# the prefix "/"), so the tree is Debian's layout, /etc included; a plain
# `cmake --install` goes under CMAKE_INSTALL_PREFIX and never writes to the
# host's /etc or /usr/bin.
install(TARGETS ${RTFUSE_PACKAGE_PROGRAMS} RUNTIME DESTINATION usr/bin)

# Every config of config/ (sim.toml, sim_lcm.toml, robot_linux.toml,
# example_robot.toml, ...) and its scenarios.
file(GLOB RTFUSE_PACKAGE_CONFIGS CONFIGURE_DEPENDS ${CMAKE_SOURCE_DIR}/config/*.toml)
install(FILES ${RTFUSE_PACKAGE_CONFIGS} DESTINATION etc/rtfuse)
file(GLOB RTFUSE_PACKAGE_SCENARIOS CONFIGURE_DEPENDS ${CMAKE_SOURCE_DIR}/config/scenarios/*.toml)
install(FILES ${RTFUSE_PACKAGE_SCENARIOS} DESTINATION etc/rtfuse/scenarios)
# Camera factory calibrations the configs name (sim.toml's simulated camera).
file(GLOB RTFUSE_PACKAGE_CALIBRATIONS CONFIGURE_DEPENDS ${CMAKE_SOURCE_DIR}/config/calibration/*.conf)
install(FILES ${RTFUSE_PACKAGE_CALIBRATIONS} DESTINATION etc/rtfuse/calibration)
# The service's config: the real robot's, to be edited on the board.
install(FILES ${CMAKE_SOURCE_DIR}/config/robot_linux.toml DESTINATION etc/rtfuse RENAME rtfused.toml)

# /lib, not /usr/lib: Debian 12 packages keep units there (usrmerge moratorium),
# and so does the Ubuntu 18.04 of a stock TX2.
install(FILES ${CMAKE_SOURCE_DIR}/packaging/rtfused.service DESTINATION lib/systemd/system)

# Python: the generated types where tools/rtfuse_tools/lcmtypes_path.py looks
# (INSTALLED_DIR), the tools beside their rtfuse_tools package (they put their
# own folder on sys.path).
install(DIRECTORY ${RTFUSE_LCMTYPES_PYTHON_DIR}/ DESTINATION usr/share/rtfuse/python
        FILES_MATCHING PATTERN "*.py" PATTERN "__pycache__" EXCLUDE)
file(GLOB RTFUSE_PACKAGE_PY_TOOLS CONFIGURE_DEPENDS ${CMAKE_SOURCE_DIR}/tools/*.py)
install(PROGRAMS ${RTFUSE_PACKAGE_PY_TOOLS} ${CMAKE_SOURCE_DIR}/tools/lcm-spy
        DESTINATION usr/share/rtfuse/tools)
install(DIRECTORY ${CMAKE_SOURCE_DIR}/tools/rtfuse_tools DESTINATION usr/share/rtfuse/tools
        FILES_MATCHING PATTERN "*.py" PATTERN "__pycache__" EXCLUDE)

install(FILES ${CMAKE_SOURCE_DIR}/docs/packaging.md DESTINATION usr/share/doc/rtfuse)

if(RTFUSE_LCMTYPES_JAR)
  install(FILES ${RTFUSE_LCMTYPES_JAR} DESTINATION usr/share/java)
  # tools/lcm-spy looks for the jar in /usr/share/rtfuse/java/.
  install(CODE "set(d \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/usr/share/rtfuse/java\")
                file(MAKE_DIRECTORY \"\${d}\")
                file(CREATE_LINK ../../java/rtfuse_lcmtypes.jar \"\${d}/rtfuse_lcmtypes.jar\" SYMBOLIC)")
else()
  message(WARNING "Packaging: rtfuse_lcmtypes.jar is not built (javac, jar or lcm.jar missing): "
                  "the package will lack /usr/share/java/rtfuse_lcmtypes.jar and its test will fail")
endif()

# --- CPack ------------------------------------------------------------------
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME rtfuse)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DIRECTORY ${CMAKE_BINARY_DIR}/packages)
set(CPACK_PACKAGING_INSTALL_PREFIX "/")
set(CPACK_PACKAGE_CONTACT "rtfuse maintainers <rtfuse@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "real-time EKF sensor fusion daemon for robots (LCM in, LCM out)")
string(CONCAT CPACK_PACKAGE_DESCRIPTION
  "rtfused fuses wheel encoders on SocketCAN and an MPU-6050 IMU on i2c-dev\n"
  "in a fixed-rate real-time loop and publishes odometry over LCM. Includes\n"
  "the rtfused.service systemd unit, rtfuse-replay, rtfuse-sim,\n"
  "rtfuse-camera-snapshot, rtfuse-canopen-node, example configs in /etc/rtfuse, the LCM types as\n"
  "a jar and Python modules.")
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE ${RTFUSE_DEB_ARCH})
set(CPACK_DEBIAN_FILE_NAME "rtfuse_${PROJECT_VERSION}_${RTFUSE_DEB_ARCH}.deb")
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# Depends is filled in at cpack time (packaging/deb-depends.cmake) from the
# programs themselves; adduser is for the postinst.
set(RTFUSE_DEB_EXTRA_DEPENDS "adduser")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "python3")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "liblcm-java, libjchart2d-java, python3-matplotlib, python3-yaml")
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS OFF)

# Every file in /etc/rtfuse is a conffile: dpkg keeps the admin's edits on
# upgrade and removes them only on purge.
set(_rtfuse_conffiles "")
foreach(c IN LISTS RTFUSE_PACKAGE_CONFIGS)
  get_filename_component(n ${c} NAME)
  string(APPEND _rtfuse_conffiles "/etc/rtfuse/${n}\n")
endforeach()
string(APPEND _rtfuse_conffiles "/etc/rtfuse/rtfused.toml\n")
foreach(s IN LISTS RTFUSE_PACKAGE_SCENARIOS)
  get_filename_component(n ${s} NAME)
  string(APPEND _rtfuse_conffiles "/etc/rtfuse/scenarios/${n}\n")
endforeach()
foreach(s IN LISTS RTFUSE_PACKAGE_CALIBRATIONS)
  get_filename_component(n ${s} NAME)
  string(APPEND _rtfuse_conffiles "/etc/rtfuse/calibration/${n}\n")
endforeach()
file(WRITE ${CMAKE_BINARY_DIR}/packaging/conffiles "${_rtfuse_conffiles}")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${CMAKE_BINARY_DIR}/packaging/conffiles
    ${CMAKE_SOURCE_DIR}/packaging/postinst
    ${CMAKE_SOURCE_DIR}/packaging/prerm
    ${CMAKE_SOURCE_DIR}/packaging/postrm)
# Maintainer scripts 0755 and conffiles 0644 whatever the checkout's modes.
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)

# Read by cpack itself: the paths of the built programs for the Depends.
set(_rtfuse_program_files "")
foreach(prog IN LISTS RTFUSE_PACKAGE_PROGRAMS)
  list(APPEND _rtfuse_program_files "$<TARGET_FILE:${prog}>")
endforeach()
list(JOIN _rtfuse_program_files ";" _rtfuse_program_files)
find_program(RTFUSE_READELF NAMES ${CMAKE_READELF} readelf)
file(GENERATE OUTPUT ${CMAKE_BINARY_DIR}/packaging/CPackProjectConfig.cmake CONTENT
"set(RTFUSE_PACKAGE_FILES \"${_rtfuse_program_files}\")
set(RTFUSE_READELF \"${RTFUSE_READELF}\")
set(RTFUSE_DEB_EXTRA_DEPENDS \"${RTFUSE_DEB_EXTRA_DEPENDS}\")
include(\"${CMAKE_SOURCE_DIR}/packaging/deb-depends.cmake\")
")
set(CPACK_PROJECT_CONFIG_FILE ${CMAKE_BINARY_DIR}/packaging/CPackProjectConfig.cmake)

include(CPack)

# Builds only what the package holds (not the tests), then packs it.
set(_rtfuse_deb_deps ${RTFUSE_PACKAGE_PROGRAMS} rtfuse_lcmtypes_gen)
if(TARGET rtfuse_lcmtypes_jar)
  list(APPEND _rtfuse_deb_deps rtfuse_lcmtypes_jar)
endif()
# What the package holds, built without packing it (tools/test-cross.sh
# builds this and the unit tests only).
add_custom_target(rtfuse_deb_inputs)
add_dependencies(rtfuse_deb_inputs ${_rtfuse_deb_deps})
add_custom_target(rtfuse_deb
  COMMAND ${CMAKE_CPACK_COMMAND} -G DEB --config ${CMAKE_BINARY_DIR}/CPackConfig.cmake
  DEPENDS ${_rtfuse_deb_deps}
  WORKING_DIRECTORY ${CMAKE_BINARY_DIR}
  COMMENT "cpack -G DEB -> packages/rtfuse_${PROJECT_VERSION}_${RTFUSE_DEB_ARCH}.deb"
  USES_TERMINAL)
set(RTFUSE_DEB_FILE ${CPACK_PACKAGE_DIRECTORY}/${CPACK_DEBIAN_FILE_NAME})
