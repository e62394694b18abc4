# layering_compiler_refuses (tests/layering/CMakeLists.txt): builds the layering probes in the
# build tree and checks that every allowed probe compiles and every forbidden one fails with
# "<its file>:<line>:<col>: fatal error: <its forbidden header>" not found (gcc: "No such file
# or directory", clang: "file not found").
#   cmake -DBUILD_DIR=<build> -DPROBES=<compile_probes_list.cmake> -DGENERATOR=<gen> -P ...
include(${PROBES})

execute_process(COMMAND ${CMAKE_COMMAND} --build ${BUILD_DIR} --parallel 2 --target ${GOOD_PROBES}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "an allowed include does not compile in its layer:\n${out}")
endif()

set(targets)
foreach(p IN LISTS BAD_PROBES)
  string(REPLACE "|" ";" p "${p}")
  list(GET p 0 target)
  list(APPEND targets ${target})
endforeach()
# Keep going past the first failure: every probe must be tried.
set(keep_going)
if(GENERATOR MATCHES "Ninja")
  set(keep_going -- -k 0)
elseif(GENERATOR MATCHES "Makefiles")
  set(keep_going -- -k)
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BUILD_DIR} --parallel 2 --target ${targets}
                        ${keep_going}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)

set(problems)
set(count 0)
foreach(p IN LISTS BAD_PROBES)
  string(REPLACE "|" ";" p "${p}")
  list(GET p 1 file)
  list(GET p 2 header)
  math(EXPR count "${count} + 1")
  # Paths here are [a-z0-9_/.] only: '.' is the one regex character to escape.
  string(REPLACE "." "\\." file_re "${file}")
  string(REPLACE "." "\\." header_re "${header}")
  if(NOT out MATCHES "layering/bad/${file_re}:[0-9]+:[0-9]+: fatal error: '?${header_re}'?(: No such file or directory| file not found)")
    string(APPEND problems "  bad/${file}: not refused with \"${header}\" not found\n")
  endif()
endforeach()
if(rc EQUAL 0 OR problems)
  message(FATAL_ERROR "the include paths let a layer see what it must not:\n${problems}"
                      "build exit ${rc}, output:\n${out}")
endif()
message(STATUS "layering_compiler_refuses: ${count} forbidden includes refused by the compiler")
