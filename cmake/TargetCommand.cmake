# rtfuse_target_command(<out-var> <target>)
#
# Sets <out-var> to a path that runs <target>'s executable on this host:
# the executable itself in a native build, and in a cross build with
# CMAKE_CROSSCOMPILING_EMULATOR (toolchains/aarch64-jetson-tx2.cmake) a
# generated script that execs it under the emulator. CTest prefixes the
# emulator only to a test's own COMMAND; the integration tests start the
# daemon, the simulator and the replay tool from Python by path, so they get
# these paths. The script execs, so signals sent to it (SIGINT to stop a live
# rtfused) reach qemu, which passes them on to the program.
function(rtfuse_target_command out target)
  if(NOT CMAKE_CROSSCOMPILING_EMULATOR)
    set(${out} "$<TARGET_FILE:${target}>" PARENT_SCOPE)
    return()
  endif()
  if(CMAKE_VERSION VERSION_LESS 3.20)
    message(FATAL_ERROR "cross builds with an emulator need CMake >= 3.20 (file(GENERATE ... FILE_PERMISSIONS))")
  endif()
  set(emulator "")
  foreach(arg IN LISTS CMAKE_CROSSCOMPILING_EMULATOR)
    string(APPEND emulator "'${arg}' ")
  endforeach()
  set(script "${CMAKE_BINARY_DIR}/emulated/${target}")
  set(${out} "${script}" PARENT_SCOPE)
  # One script per target, whichever test folder asks first.
  get_property(done GLOBAL PROPERTY RTFUSE_EMULATED_${target})
  if(done)
    return()
  endif()
  set_property(GLOBAL PROPERTY RTFUSE_EMULATED_${target} TRUE)
  file(GENERATE OUTPUT "${script}"
       CONTENT "#!/bin/sh\nexec ${emulator}'$<TARGET_FILE:${target}>' \"$@\"\n"
       FILE_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)
endfunction()
