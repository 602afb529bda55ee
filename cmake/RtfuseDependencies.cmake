# Every dependency is a Debian 12 package; tools/setup-deps.sh installs them.

find_package(Eigen3 3.4 REQUIRED NO_MODULE)

# LCM: prefer LCM's own CMake config (upstream installs ship it). Debian's
# package ships only lcm.pc, which requires glib-2.0 without depending on its
# -dev package, so pkg-config is never relied upon: fall back to the header
# and library themselves.
find_package(lcm CONFIG QUIET)
if(TARGET lcm::lcm)
  add_library(rtfuse_lcm INTERFACE)
  target_link_libraries(rtfuse_lcm INTERFACE lcm::lcm)
else()
  find_path(LCM_INCLUDE_DIR lcm/lcm.h)
  find_library(LCM_LIBRARY NAMES lcm)
  if(NOT LCM_INCLUDE_DIR OR NOT LCM_LIBRARY)
    message(FATAL_ERROR "LCM not found: install liblcm-dev (apt-get install liblcm-dev liblcm-bin)")
  endif()
  add_library(rtfuse_lcm INTERFACE)
  target_include_directories(rtfuse_lcm SYSTEM INTERFACE ${LCM_INCLUDE_DIR})
  target_link_libraries(rtfuse_lcm INTERFACE ${LCM_LIBRARY})
endif()

# lcm-gen and javac are host tools, also when cross-compiling.
find_program(LCM_GEN_EXECUTABLE lcm-gen REQUIRED NO_CMAKE_FIND_ROOT_PATH)
find_program(JAVAC_EXECUTABLE javac NO_CMAKE_FIND_ROOT_PATH)
find_program(JAR_EXECUTABLE jar NO_CMAKE_FIND_ROOT_PATH)
find_file(LCM_JAR lcm.jar PATHS /usr/share/java /usr/local/share/java NO_CMAKE_FIND_ROOT_PATH)

# toml++, header-only: Debian's package config links the compiled
# libtomlplusplus.so.3, which a board's OS (JetPack's Ubuntu 18.04) does not
# have. Configs are parsed once at start-up, so the header-only build costs
# only compile time and leaves one runtime dependency fewer.
find_path(TOMLPP_INCLUDE_DIR toml++/toml.h)
if(NOT TOMLPP_INCLUDE_DIR)
  message(FATAL_ERROR "toml++ not found: install libtomlplusplus-dev")
endif()
add_library(rtfuse_toml INTERFACE)
target_include_directories(rtfuse_toml SYSTEM INTERFACE ${TOMLPP_INCLUDE_DIR})
target_compile_definitions(rtfuse_toml INTERFACE TOML_HEADER_ONLY=1)

find_package(CLI11 QUIET CONFIG)
if(NOT TARGET CLI11::CLI11)
  find_path(CLI11_INCLUDE_DIR CLI/CLI.hpp REQUIRED)
  add_library(CLI11::CLI11 INTERFACE IMPORTED)
  target_include_directories(CLI11::CLI11 INTERFACE ${CLI11_INCLUDE_DIR})
endif()

# libgpiod v1 (1.6 in Debian 12, the API Jetson images ship). The v2 API
# renamed most calls; refuse it explicitly rather than fail to compile later.
find_path(GPIOD_INCLUDE_DIR gpiod.h)
find_library(GPIOD_LIBRARY NAMES gpiod)
if(NOT GPIOD_INCLUDE_DIR OR NOT GPIOD_LIBRARY)
  message(FATAL_ERROR "libgpiod not found: install libgpiod-dev (v1.6)")
endif()
file(STRINGS ${GPIOD_INCLUDE_DIR}/gpiod.h gpiod_v1_marker REGEX "gpiod_line_request_rising_edge_events")
if(NOT gpiod_v1_marker)
  message(FATAL_ERROR "${GPIOD_INCLUDE_DIR}/gpiod.h is not the libgpiod v1 API (need 1.x, e.g. Debian 12's libgpiod-dev 1.6)")
endif()
add_library(rtfuse_gpiod INTERFACE)
target_include_directories(rtfuse_gpiod SYSTEM INTERFACE ${GPIOD_INCLUDE_DIR})
target_link_libraries(rtfuse_gpiod INTERFACE ${GPIOD_LIBRARY})
