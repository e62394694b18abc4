#!/bin/sh
# cpack -G DEB in the build directory; the package must hold the CLI, its man page and
# completion, the headers and the CMake package config.
#   test_deb.sh BUILD_DIR VERSION
set -eu
cd "$1"
cpack -G DEB >cpack.log 2>&1 || { cat cpack.log; exit 1; }
deb=$(ls rackcat_"$2"_*.deb)
contents=$(dpkg-deb -c "$deb")
for f in ./usr/bin/rackcat ./usr/share/man/man1/rackcat.1 \
         ./usr/share/bash-completion/completions/rackcat ./usr/include/rackcat/coe/sdo_server.hpp \
         rackcatConfig.cmake; do
  echo "$contents" | grep -q -- "$f" || { echo "$deb lacks $f"; exit 1; }
done
dpkg-deb -f "$deb" Package Version Depends
echo "ok: $deb"
