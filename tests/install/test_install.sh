#!/bin/sh
# Installs the build into a fresh prefix and builds against the installed package as a user
# would: tests/install/coe_only (COMPONENTS coe must find no other package),
# tests/install/coe_mdp (COMPONENTS coe mdp: no ESC, modules or ESI) and the example
# device examples/tiny_device (coe, esi, ecat_host). tests/interop/test_tiny_device.py then
# takes that device to OP under pysoem.
#
#   test_install.sh BUILD_DIR WORK_DIR     (WORK_DIR is emptied first)
set -eu
build=$(cd "$1" && pwd)
work=$2
src=$(cd "$(dirname "$0")/../.." && pwd)
rm -rf "$work"
mkdir -p "$work"
prefix="$work/prefix"

echo "== cmake --install $build --prefix $prefix"
cmake --install "$build" --prefix "$prefix" >"$work/install.log"
for f in bin/rackcat share/man/man1/rackcat.1 share/bash-completion/completions/rackcat \
         include/rackcat/coe/sdo_server.hpp include/rackcat/ecat/application.hpp; do
  test -e "$prefix/$f" || { echo "missing after install: $f"; exit 1; }
done
config=$(find "$prefix" -name rackcatConfig.cmake)
test -n "$config" || { echo "missing after install: rackcatConfig.cmake"; exit 1; }
"$prefix/bin/rackcat" --help >/dev/null
bash -n "$prefix/share/bash-completion/completions/rackcat"

launcher=""
if command -v ccache >/dev/null 2>&1; then launcher="-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"; fi
for project in "$src/tests/install/coe_only" "$src/tests/install/coe_mdp" "$src/examples/tiny_device"; do
  name=$(basename "$project")
  echo "== $name against the installed package"
  # shellcheck disable=SC2086
  cmake -S "$project" -B "$work/$name" -G Ninja -DCMAKE_BUILD_TYPE=Release \
        -DCMAKE_PREFIX_PATH="$prefix" $launcher >"$work/$name.configure.log" ||
    { cat "$work/$name.configure.log"; exit 1; }
  cmake --build "$work/$name" >"$work/$name.build.log" || { cat "$work/$name.build.log"; exit 1; }
done
"$work/coe_only/coe_only"
"$work/coe_mdp/coe_mdp"
echo "ok: $work/tiny_device/tiny_device"
