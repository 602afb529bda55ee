# rtfuse_lcmtypes(TARGET <name> FILES <a.lcm>...)
# Generates C++ headers (an INTERFACE library <name>), and where javac is
# present a jar rtfuse_lcmtypes.jar, plus Python modules under
# ${CMAKE_BINARY_DIR}/lcmtypes/python. Generated files live in the build tree.
function(rtfuse_lcmtypes)
  cmake_parse_arguments(ARG "" "TARGET" "FILES" ${ARGN})
  set(gen_dir ${CMAKE_BINARY_DIR}/lcmtypes)
  set(cpp_dir ${gen_dir}/cpp)
  set(py_dir ${gen_dir}/python)
  set(java_dir ${gen_dir}/java)
  set(cpp_outputs)
  set(py_outputs)
  set(java_sources)
  foreach(f ${ARG_FILES})
    get_filename_component(abs ${f} ABSOLUTE)
    get_filename_component(name ${f} NAME_WE)
    file(STRINGS ${abs} pkg_line REGEX "^package ")
    string(REGEX MATCH "^package +([a-zA-Z0-9_.]+)" _m "${pkg_line}")
    set(pkg "${CMAKE_MATCH_1}")
    string(REPLACE "." "/" pkg_path "${pkg}")
    list(APPEND cpp_outputs ${cpp_dir}/${pkg_path}/${name}.hpp)
    list(APPEND py_outputs ${py_dir}/${pkg_path}/${name}.py)
    list(APPEND java_sources ${java_dir}/${pkg_path}/${name}.java)
    list(APPEND abs_files ${abs})
  endforeach()

  add_custom_command(
    OUTPUT ${cpp_outputs}
    COMMAND ${LCM_GEN_EXECUTABLE} --lazy -x --cpp-hpath ${cpp_dir} ${abs_files}
    DEPENDS ${abs_files}
    COMMENT "lcm-gen C++")
  add_custom_command(
    OUTPUT ${py_outputs}
    COMMAND ${LCM_GEN_EXECUTABLE} --lazy -p --ppath ${py_dir} ${abs_files}
    DEPENDS ${abs_files}
    COMMENT "lcm-gen Python")
  add_custom_target(${ARG_TARGET}_gen ALL DEPENDS ${cpp_outputs} ${py_outputs})

  add_library(${ARG_TARGET} INTERFACE)
  add_dependencies(${ARG_TARGET} ${ARG_TARGET}_gen)
  target_include_directories(${ARG_TARGET} SYSTEM INTERFACE ${cpp_dir})
  target_link_libraries(${ARG_TARGET} INTERFACE rtfuse_lcm)
  set(RTFUSE_LCMTYPES_PYTHON_DIR ${py_dir} CACHE INTERNAL "")

  if(JAVAC_EXECUTABLE AND JAR_EXECUTABLE AND LCM_JAR)
    set(jar ${CMAKE_BINARY_DIR}/rtfuse_lcmtypes.jar)
    add_custom_command(
      OUTPUT ${jar}
      COMMAND ${CMAKE_COMMAND} -E remove_directory ${java_dir}
      COMMAND ${LCM_GEN_EXECUTABLE} -j --jpath ${java_dir} ${abs_files}
      COMMAND ${CMAKE_COMMAND} -E make_directory ${gen_dir}/classes
      COMMAND ${JAVAC_EXECUTABLE} -nowarn -source 8 -target 8 -cp ${LCM_JAR}
              -d ${gen_dir}/classes ${java_sources}
      COMMAND ${JAR_EXECUTABLE} cf ${jar} -C ${gen_dir}/classes .
      DEPENDS ${abs_files}
      COMMENT "lcm-gen Java -> rtfuse_lcmtypes.jar")
    add_custom_target(${ARG_TARGET}_jar ALL DEPENDS ${jar})
    set(RTFUSE_LCMTYPES_JAR ${jar} CACHE INTERNAL "")
  else()
    message(STATUS "javac, jar or lcm.jar missing: rtfuse_lcmtypes.jar will not be built")
    set(RTFUSE_LCMTYPES_JAR "" CACHE INTERNAL "")
  endif()
endfunction()
