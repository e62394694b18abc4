# Usage requirements, export and installation of every rackcat library, applied once all
# folders have been added (rackcat_finalize_libraries() at the end of the top-level
# CMakeLists.txt). A library's own CMakeLists.txt only lists its sources and what it links.
#
# Each library target rackcat_<name> becomes:
#  - include root: in the build tree a view of its OWN headers only,
#    build/include/rackcat_<name>/<folder>/<header> (symbolic links into the source tree), so
#    sources still write #include "coe/sdo_server.hpp" but a target sees exactly the headers of
#    itself and of the libraries it links (usage requirements are transitive): an #include of
#    a layer the target does not link is "No such file or directory" at compile time. Installed,
#    the root is <prefix>/include/rackcat, all headers (docs/ESC.md "Layers").
#    A library's headers are the *.hpp of its folder; where one folder holds several libraries,
#    all but one list theirs in the target property RACKCAT_HEADERS (file names; may be empty)
#    and the one without it takes the rest;
#  - the imported target rackcat::<name> and the package component <name>
#    (find_package(rackcat COMPONENTS <name> ...)), installed as lib/librackcat_<name>.a with
#    lib/cmake/rackcat/rackcat-<name>-targets.cmake. A component's dependency file finds only
#    the packages its own targets link (rackcat-<name>-dependencies.cmake), so coe alone needs
#    nothing but the C++ library.
# Programs get a view too: rackcat_private_headers(target) for a program's own folder (the
# CLI's apps/*.hpp), rackcat_folder_view() for whole trees (tests/ for the test, benchmark and
# fuzz programs; tests/layering/check_layers.py keeps their finer rules).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(RACKCAT_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/rackcat)

# Imported-target namespace (or plain target) -> the find_package() call that defines it.
set(_rackcat_pkg_Threads "Threads")
set(_rackcat_pkg_Eigen3 "Eigen3 3.3 NO_MODULE")
set(_rackcat_pkg_yaml-cpp "yaml-cpp")
set(_rackcat_pkg_fmt "fmt")
set(_rackcat_pkg_spdlog "spdlog")
set(_rackcat_pkg_nlohmann_json "nlohmann_json 3")
set(_rackcat_pkg_pugixml "pugixml")
set(_rackcat_pkg_CLI11 "CLI11")
set(_rackcat_pkg_OpenSSL "OpenSSL")
set(_rackcat_pkg_ZLIB "ZLIB")

function(_rackcat_collect_libraries dir out)
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  set(libs)
  foreach(t IN LISTS targets)
    get_target_property(type ${t} TYPE)
    if(t MATCHES "^rackcat_" AND type MATCHES "^(STATIC_LIBRARY|SHARED_LIBRARY|INTERFACE_LIBRARY)$")
      list(APPEND libs ${t})
    endif()
  endforeach()
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(sub IN LISTS subdirs)
    _rackcat_collect_libraries(${sub} sub_libs)
    list(APPEND libs ${sub_libs})
  endforeach()
  set(${out} ${libs} PARENT_SCOPE)
endfunction()

# _rackcat_make_view(<name> <repository-relative paths>...): the directory
# build/include/<name> holding a symbolic link <path> -> <source tree>/<path> for each path and
# nothing else. Rebuilt at every configure, so a header moved or removed leaves no stale link.
function(_rackcat_make_view name)
  set(root ${PROJECT_BINARY_DIR}/include/${name})
  file(REMOVE_RECURSE ${root})
  file(MAKE_DIRECTORY ${root})
  foreach(rel IN LISTS ARGN)
    cmake_path(GET rel PARENT_PATH parent)
    file(MAKE_DIRECTORY ${root}/${parent})
    file(CREATE_LINK ${PROJECT_SOURCE_DIR}/${rel} ${root}/${rel} SYMBOLIC)
  endforeach()
  set(_rackcat_view_dir ${root} PARENT_SCOPE)
endfunction()

# The headers (repository-relative) a library owns; see the header comment.
function(_rackcat_headers_of target all_libs out)
  get_target_property(src_dir ${target} SOURCE_DIR)
  file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${src_dir})
  get_property(explicit TARGET ${target} PROPERTY RACKCAT_HEADERS SET)
  if(explicit)
    get_target_property(names ${target} RACKCAT_HEADERS)
  else()
    file(GLOB paths CONFIGURE_DEPENDS ${src_dir}/*.hpp)
    set(names)
    foreach(p IN LISTS paths)
      cmake_path(GET p FILENAME n)
      list(APPEND names ${n})
    endforeach()
    foreach(other IN LISTS all_libs)
      get_target_property(other_dir ${other} SOURCE_DIR)
      get_property(other_explicit TARGET ${other} PROPERTY RACKCAT_HEADERS SET)
      if(NOT other STREQUAL target AND other_dir STREQUAL src_dir AND other_explicit)
        get_target_property(taken ${other} RACKCAT_HEADERS)
        if(taken)
          list(REMOVE_ITEM names ${taken})
        endif()
      endif()
    endforeach()
  endif()
  set(headers)
  foreach(n IN LISTS names)
    if(NOT EXISTS ${src_dir}/${n})
      message(FATAL_ERROR "${target}: RACKCAT_HEADERS names ${rel}/${n}, which does not exist")
    endif()
    list(APPEND headers ${rel}/${n})
  endforeach()
  set(${out} ${headers} PARENT_SCOPE)
endfunction()

# The include root as a usage requirement: drop a plain source-tree path a folder may have set,
# add the build view / install pair.
function(_rackcat_set_include_root target headers)
  get_target_property(type ${target} TYPE)
  set(scope PUBLIC)
  if(type STREQUAL "INTERFACE_LIBRARY")
    set(scope INTERFACE)
  endif()
  foreach(prop INTERFACE_INCLUDE_DIRECTORIES INCLUDE_DIRECTORIES)
    get_target_property(dirs ${target} ${prop})
    if(dirs)
      if(${PROJECT_SOURCE_DIR} IN_LIST dirs)
        message(FATAL_ERROR "${target}: the repository root must not be an include directory "
                            "(the build gives each library a view of its own headers)")
      endif()
    endif()
  endforeach()
  _rackcat_make_view(${target} ${headers})
  target_include_directories(${target} ${scope}
    $<BUILD_INTERFACE:${_rackcat_view_dir}>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/rackcat>)
endfunction()

# rackcat_folder_view(<view> <out-var> <folder>...): an include root holding only the named
# repository folders (whole trees), e.g. rackcat_folder_view(tests_view dir tests).
function(rackcat_folder_view view out)
  _rackcat_make_view(${view} ${ARGN})
  set(${out} ${_rackcat_view_dir} PARENT_SCOPE)
endfunction()

# rackcat_private_headers(<target>): a program (not a library) sees its own folder's headers,
# e.g. apps/commands.hpp for the rackcat CLI.
function(rackcat_private_headers target)
  get_target_property(src_dir ${target} SOURCE_DIR)
  file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${src_dir})
  file(GLOB paths CONFIGURE_DEPENDS ${src_dir}/*.hpp)
  set(headers)
  foreach(p IN LISTS paths)
    file(RELATIVE_PATH r ${PROJECT_SOURCE_DIR} ${p})
    list(APPEND headers ${r})
  endforeach()
  _rackcat_make_view(${target} ${headers})
  target_include_directories(${target} PRIVATE ${_rackcat_view_dir})
endfunction()

function(rackcat_finalize_libraries)
  _rackcat_collect_libraries(${PROJECT_SOURCE_DIR} libs)
  set(components)
  foreach(t IN LISTS libs)
    string(REGEX REPLACE "^rackcat_" "" name ${t})
    list(APPEND components ${name})
    _rackcat_headers_of(${t} "${libs}" headers)
    set_property(GLOBAL PROPERTY _rackcat_headers_${t} ${headers})
    _rackcat_set_include_root(${t} "${headers}")
    set_target_properties(${t} PROPERTIES EXPORT_NAME ${name})
    if(NOT TARGET rackcat::${name})
      add_library(rackcat::${name} ALIAS ${t})
    endif()
  endforeach()
  if(NOT RACKCAT_INSTALL)
    return()
  endif()

  foreach(t IN LISTS libs)
    string(REGEX REPLACE "^rackcat_" "" name ${t})
    install(TARGETS ${t} EXPORT rackcat-${name} COMPONENT dev
            ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
            LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
    install(EXPORT rackcat-${name} NAMESPACE rackcat:: FILE rackcat-${name}-targets.cmake
            DESTINATION ${RACKCAT_INSTALL_CMAKEDIR} COMPONENT dev)
    # Dependencies: other rackcat components and external packages its link interface names.
    get_target_property(links ${t} INTERFACE_LINK_LIBRARIES)
    if(NOT links)
      set(links)
    endif()
    set(deps "# Generated: what component ${name} needs before its targets are loaded.\n")
    foreach(l IN LISTS links)
      string(REGEX REPLACE "^\\$<LINK_ONLY:(.*)>$" "\\1" l "${l}")
      string(REGEX REPLACE "^\\$<BUILD_INTERFACE:.*>$" "" l "${l}")
      if(l STREQUAL "")
        continue()
      endif()
      if(l MATCHES "^rackcat_(.*)$")
        string(APPEND deps "_rackcat_load_component(${CMAKE_MATCH_1})\n")
      elseif(l MATCHES "^([A-Za-z0-9_+-]+)::")
        set(pkg ${CMAKE_MATCH_1})
        if(DEFINED _rackcat_pkg_${pkg})
          string(APPEND deps "find_dependency(${_rackcat_pkg_${pkg}})\n")
        endif()
      elseif(DEFINED _rackcat_pkg_${l})
        string(APPEND deps "find_dependency(${_rackcat_pkg_${l}})\n")
      endif()
    endforeach()
    file(GENERATE OUTPUT ${PROJECT_BINARY_DIR}/cmake/rackcat-${name}-dependencies.cmake
         CONTENT "${deps}")
    install(FILES ${PROJECT_BINARY_DIR}/cmake/rackcat-${name}-dependencies.cmake
            DESTINATION ${RACKCAT_INSTALL_CMAKEDIR} COMPONENT dev)
  endforeach()

  # Public headers: each library's own, under include/rackcat/<folder>/.
  foreach(t IN LISTS libs)
    get_property(headers GLOBAL PROPERTY _rackcat_headers_${t})
    foreach(h IN LISTS headers)
      cmake_path(GET h PARENT_PATH rel)
      install(FILES ${PROJECT_SOURCE_DIR}/${h} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/rackcat/${rel}
              COMPONENT dev)
    endforeach()
  endforeach()

  set(RACKCAT_COMPONENTS ${components})
  configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/rackcatConfig.cmake.in
    ${PROJECT_BINARY_DIR}/cmake/rackcatConfig.cmake INSTALL_DESTINATION ${RACKCAT_INSTALL_CMAKEDIR})
  write_basic_package_version_file(${PROJECT_BINARY_DIR}/cmake/rackcatConfigVersion.cmake
    VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
  install(FILES ${PROJECT_BINARY_DIR}/cmake/rackcatConfig.cmake
                ${PROJECT_BINARY_DIR}/cmake/rackcatConfigVersion.cmake
          DESTINATION ${RACKCAT_INSTALL_CMAKEDIR} COMPONENT dev)
endfunction()
