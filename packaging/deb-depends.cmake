# Included by cpack (CPACK_PROJECT_CONFIG_FILE, written by cmake/Packaging.cmake):
# sets CPACK_DEBIAN_PACKAGE_DEPENDS from what the packed programs need.
#
# Input: RTFUSE_PACKAGE_FILES (the built programs), RTFUSE_READELF,
# RTFUSE_DEB_EXTRA_DEPENDS (packages the maintainer scripts use).
#
# Each NEEDED soname maps to the Debian 12 package that ships it; the version
# floor comes from the newest symbol version the programs use from it
# (GLIBC_2.34 -> libc6 (>= 2.34)), which is what dpkg-shlibdeps would derive
# from the symbols files. dpkg-shlibdeps itself cannot be used: a cross tree's
# sysroot (tools/make-sysroot.sh) is unpacked with dpkg -x and has no dpkg
# database to look the libraries up in. A soname missing from the table stops
# cpack: adding a library to rtfuse means adding it here.

if(NOT CPACK_GENERATOR STREQUAL "DEB")
  return()
endif()

# soname -> package (and a fixed floor where the library has no symbol
# versions of its own; from the package's shlibs file).
set(_soname_pkg_libc.so.6 libc6)
set(_soname_pkg_libm.so.6 libc6)
set(_soname_pkg_libpthread.so.0 libc6)
set(_soname_pkg_libdl.so.2 libc6)
set(_soname_pkg_librt.so.1 libc6)
set(_soname_pkg_ld-linux-aarch64.so.1 libc6)
set(_soname_pkg_ld-linux-x86-64.so.2 libc6)
set(_soname_pkg_libstdc++.so.6 libstdc++6)
set(_soname_pkg_libgcc_s.so.1 libgcc-s1)
set(_soname_pkg_liblcm.so.1 liblcm1)
set(_soname_pkg_libgpiod.so.2 "libgpiod2 (>= 1.6.3)")
set(_soname_pkg_libglib-2.0.so.0 "libglib2.0-0 (>= 2.56)")
set(_soname_pkg_libtomlplusplus.so.3 "libtomlplusplus3 (>= 3.3.0)")
set(_soname_pkg_libpng16.so.16 "libpng16-16 (>= 1.6.2-1)")
set(_soname_pkg_libz.so.1 "zlib1g (>= 1:1.2.0)")

# GLIBCXX_3.4.N -> the first GCC whose libstdc++ has it (Debian's libstdc++6
# is versioned by GCC release).
set(_glibcxx_gcc_21 5)
set(_glibcxx_gcc_22 6)
set(_glibcxx_gcc_23 7)
set(_glibcxx_gcc_24 7.2)
set(_glibcxx_gcc_25 8)
set(_glibcxx_gcc_26 9)
set(_glibcxx_gcc_27 9.2)
set(_glibcxx_gcc_28 9.3)
set(_glibcxx_gcc_29 11)
set(_glibcxx_gcc_30 12)
set(_glibcxx_gcc_31 13)
set(_glibcxx_gcc_32 13.2)

if(NOT RTFUSE_READELF)
  message(FATAL_ERROR "rtfuse packaging: readelf not found (apt-get install binutils)")
endif()

set(_needed "")
set(_floor_libc6 "")
set(_floor_libstdc++6 "")
set(_floor_libgcc-s1 "")
foreach(bin IN LISTS RTFUSE_PACKAGE_FILES)
  if(NOT EXISTS "${bin}")
    message(FATAL_ERROR "rtfuse packaging: ${bin} is not built: build the target rtfuse_deb "
                        "(cmake --build BUILD --target rtfuse_deb) or the programs first")
  endif()
  execute_process(COMMAND ${RTFUSE_READELF} -d -W "${bin}" OUTPUT_VARIABLE _dyn RESULT_VARIABLE _rc)
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "rtfuse packaging: readelf -d ${bin} failed")
  endif()
  string(REGEX MATCHALL "\\(NEEDED\\)[^\n]*\\[[^]\n]+\\]" _lines "${_dyn}")
  foreach(l IN LISTS _lines)
    string(REGEX REPLACE ".*\\[([^]]+)\\]" "\\1" so "${l}")
    list(APPEND _needed "${so}")
  endforeach()
  # Version needs: "Name: GLIBC_2.34  Flags: none  Version: 5"
  execute_process(COMMAND ${RTFUSE_READELF} -V -W "${bin}" OUTPUT_VARIABLE _ver)
  string(REGEX MATCHALL "Name: (GLIBC|GLIBCXX|GCC)_[0-9.]+" _tags "${_ver}")
  foreach(t IN LISTS _tags)
    string(REGEX REPLACE "Name: " "" t "${t}")
    if(t MATCHES "^GLIBC_([0-9.]+)$")
      set(pkg libc6)
      set(v ${CMAKE_MATCH_1})
    elseif(t MATCHES "^GLIBCXX_3\\.4\\.([0-9]+)$")
      set(pkg libstdc++6)
      set(v "${_glibcxx_gcc_${CMAKE_MATCH_1}}")
      if(NOT v)
        set(v 4.8)  # 3.4.20 and older: any libstdc++6 still around
        if(CMAKE_MATCH_1 GREATER 32)
          message(FATAL_ERROR "rtfuse packaging: ${t} is newer than the table in ${CMAKE_CURRENT_LIST_FILE}")
        endif()
      endif()
    elseif(t MATCHES "^GCC_([0-9]+\\.[0-9]+)")
      set(pkg libgcc-s1)
      set(v ${CMAKE_MATCH_1})
    else()
      continue()  # GLIBCXX_TUNABLES-like tags without a plain version
    endif()
    if(NOT _floor_${pkg} OR v VERSION_GREATER _floor_${pkg})
      set(_floor_${pkg} ${v})
    endif()
  endforeach()
endforeach()
list(REMOVE_DUPLICATES _needed)

set(_deps "")
foreach(so IN LISTS _needed)
  if(NOT DEFINED _soname_pkg_${so})
    message(FATAL_ERROR "rtfuse packaging: no Debian package known for NEEDED library '${so}' "
                        "of ${RTFUSE_PACKAGE_FILES}: add it to ${CMAKE_CURRENT_LIST_FILE}")
  endif()
  set(dep "${_soname_pkg_${so}}")
  if(DEFINED _floor_${dep} AND _floor_${dep})
    set(dep "${dep} (>= ${_floor_${dep}})")
  endif()
  list(APPEND _deps "${dep}")
endforeach()
list(REMOVE_DUPLICATES _deps)
list(SORT _deps)
list(APPEND _deps ${RTFUSE_DEB_EXTRA_DEPENDS})
list(JOIN _deps ", " CPACK_DEBIAN_PACKAGE_DEPENDS)
message(STATUS "rtfuse packaging: Depends: ${CPACK_DEBIAN_PACKAGE_DEPENDS}")
