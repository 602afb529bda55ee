# Cross build for the NVIDIA Jetson TX2 (aarch64) with Debian's
# aarch64-linux-gnu GCC (package g++-aarch64-linux-gnu).
#
#   cmake -S . -B build/aarch64 -G Ninja \
#     -DCMAKE_TOOLCHAIN_FILE=toolchains/aarch64-jetson-tx2.cmake \
#     -DRTFUSE_SYSROOT=/path/to/Linux_for_Tegra/rootfs
#
# RTFUSE_SYSROOT (or the environment variable of the same name) is the
# target's root file system: NVIDIA's Linux_for_Tegra/rootfs for a real board,
# or the stand-in tools/make-sysroot.sh builds from Debian 12 arm64 packages.
# Headers, libraries and CMake packages are looked up only there; programs
# (lcm-gen, javac, python) only on the host.

set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

set(RTFUSE_SYSROOT "$ENV{RTFUSE_SYSROOT}" CACHE PATH "Target root file system (Linux_for_Tegra/rootfs or tools/make-sysroot.sh output)")
if(NOT RTFUSE_SYSROOT OR NOT EXISTS "${RTFUSE_SYSROOT}/usr/include")
  message(FATAL_ERROR
    "aarch64-jetson-tx2: RTFUSE_SYSROOT='${RTFUSE_SYSROOT}' is not a target root file system "
    "(no usr/include in it). Pass -DRTFUSE_SYSROOT=<Linux_for_Tegra/rootfs>, or build a "
    "stand-in with tools/make-sysroot.sh build/sysroot-arm64.")
endif()
set(CMAKE_SYSROOT "${RTFUSE_SYSROOT}")
# try_compile projects get a fresh cache: hand the sysroot on to them.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES RTFUSE_SYSROOT)

set(RTFUSE_CROSS_PREFIX aarch64-linux-gnu- CACHE STRING "Prefix of the cross compiler's programs")
set(CMAKE_C_COMPILER ${RTFUSE_CROSS_PREFIX}gcc)
set(CMAKE_CXX_COMPILER ${RTFUSE_CROSS_PREFIX}g++)

# Cortex-A57: the TX2's A57 cluster; its Denver2 cores run the same code.
set(CMAKE_C_FLAGS_INIT "-mcpu=cortex-a57")
set(CMAKE_CXX_FLAGS_INIT "-mcpu=cortex-a57")

# A stock TX2 (JetPack 4.6: Ubuntu 18.04, glibc 2.27, GCC 7) has a libstdc++
# older than GCC 12's. Linking libstdc++ and libgcc into the executables
# removes every GLIBCXX_/GCC_ symbol version from them; glibc stays dynamic
# (it cannot be linked statically with dlopen/NSS users like LCM's glib), so
# the glibc of the sysroot decides the GLIBC_ versions: check them with
# tools/check-target-abi.sh.
option(RTFUSE_STATIC_LIBSTDCXX "Link libstdc++ and libgcc statically into target executables" ON)
if(RTFUSE_STATIC_LIBSTDCXX)
  set(CMAKE_EXE_LINKER_FLAGS_INIT "-static-libstdc++ -static-libgcc")
endif()

set(CMAKE_FIND_ROOT_PATH "${RTFUSE_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# pkg-config, where a find module uses it, must read the target's .pc files.
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${RTFUSE_SYSROOT}")
set(ENV{PKG_CONFIG_LIBDIR} "${RTFUSE_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${RTFUSE_SYSROOT}/usr/share/pkgconfig")

# Test programs run under user-mode emulation with the sysroot as their root
# for the dynamic loader and libraries (Debian's qemu-user). CTest and
# gtest_discover_tests prefix test executables with it.
find_program(RTFUSE_QEMU_AARCH64 NAMES qemu-aarch64 qemu-aarch64-static NO_CMAKE_FIND_ROOT_PATH)
if(RTFUSE_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR "${RTFUSE_QEMU_AARCH64};-L;${RTFUSE_SYSROOT}")
endif()
