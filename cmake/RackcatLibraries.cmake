# Usage requirements, export and installation of every rackcat library, applied once all
# folders have been added (rackcat_finalize_libraries() at the end of the top-level
# CMakeLists.txt). A library's own CMakeLists.txt only lists its sources and what it links.
#
# Each library target rackcat_<name> becomes:
#  - include root: the repository root in the build tree, <prefix>/include/rackcat installed
#    (sources write #include "coe/sdo_server.hpp" either way);
#  - the imported target rackcat::<name> and the package component <name>
#    (find_package(rackcat COMPONENTS <name> ...)), installed as lib/librackcat_<name>.a with
#    lib/cmake/rackcat/rackcat-<name>-targets.cmake. A component's dependency file finds only
#    the packages its own targets link (rackcat-<name>-dependencies.cmake), so coe alone needs
#    nothing but the C++ library.
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

# The include root as a usage requirement: drop a plain source-tree path a folder may have set,
# add the build/install pair.
function(_rackcat_set_include_root target)
  get_target_property(type ${target} TYPE)
  set(scope PUBLIC)
  if(type STREQUAL "INTERFACE_LIBRARY")
    set(scope INTERFACE)
  endif()
  foreach(prop INTERFACE_INCLUDE_DIRECTORIES INCLUDE_DIRECTORIES)
    get_target_property(dirs ${target} ${prop})
    if(dirs)
      list(REMOVE_ITEM dirs ${PROJECT_SOURCE_DIR})
      set_target_properties(${target} PROPERTIES ${prop} "${dirs}")
    endif()
  endforeach()
  target_include_directories(${target} ${scope}
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/rackcat>)
endfunction()

function(rackcat_finalize_libraries)
  _rackcat_collect_libraries(${PROJECT_SOURCE_DIR} libs)
  set(components)
  foreach(t IN LISTS libs)
    string(REGEX REPLACE "^rackcat_" "" name ${t})
    list(APPEND components ${name})
    _rackcat_set_include_root(${t})
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

  # Public headers: every .hpp of the folders that hold a library, under include/rackcat/.
  set(header_dirs)
  foreach(t IN LISTS libs)
    get_target_property(src_dir ${t} SOURCE_DIR)
    file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${src_dir})
    list(APPEND header_dirs ${rel})
  endforeach()
  list(REMOVE_DUPLICATES header_dirs)
  foreach(rel IN LISTS header_dirs)
    file(GLOB headers CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/${rel}/*.hpp)
    if(headers)
      install(FILES ${headers} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/rackcat/${rel} COMPONENT dev)
    endif()
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
