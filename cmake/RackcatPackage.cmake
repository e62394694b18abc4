# CPack: `cpack -G DEB` in the build directory builds rackcat_<version>_<arch>.deb with the CLI,
# its man page and completion, the static libraries, their headers and the CMake package.
set(CPACK_PACKAGE_NAME rackcat)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "EtherCAT slave stack in C++20 emulating a modular I/O rack")
set(CPACK_PACKAGE_CONTACT "rackcat maintainers <rackcat@localhost>")
set(CPACK_PACKAGE_INSTALL_DIRECTORY rackcat)
set(CPACK_GENERATOR DEB)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION net)
# Run-time libraries of the CLI from its ELF dependencies (dpkg-shlibdeps); the development
# part (headers, static libraries, CMake package) needs the -dev packages its components link.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_SUGGESTS
    "libeigen3-dev, libyaml-cpp-dev, libfmt-dev, libspdlog-dev, nlohmann-json3-dev, libpugixml-dev, libssl-dev, zlib1g-dev, libcpp-httplib-dev")
include(CPack)
