#!/usr/bin/env bash
# The installed package serves an engine: cmake --install into a temporary prefix, then the
# embedding examples built out of tree with find_package(Chladni) and with pkg-config, and run.
# Usage: install_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$1 src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" > "$tmp/install.log"
test -x "$tmp/prefix/bin/chladni"
test -f "$tmp/prefix/include/chladni/chladni.h"
if find "$tmp/prefix" -iname '*tetgen*' -o -iname '*cgal*' -o -iname '*precompute*' | grep -q .; then
  echo "the package must not carry the precompute side (TetGen, CGAL)" >&2
  exit 1
fi
cmake -S "$src/examples/embedding" -B "$tmp/embed" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$tmp/prefix" > "$tmp/configure.log"
cmake --build "$tmp/embed" > "$tmp/build.log"
"$tmp/embed/minimal_c"
"$tmp/embed/minimal_cpp"
# pkg-config, from C, as a Makefile would: the static libraries with a C++ linker.
PKG_CONFIG_PATH=$(dirname "$(find "$tmp/prefix" -name chladni.pc)")
export PKG_CONFIG_PATH
cc -std=c11 -c "$src/examples/embedding/minimal.c" $(pkg-config --cflags chladni-static) -o "$tmp/m.o"
c++ "$tmp/m.o" $(pkg-config --libs chladni-static) -o "$tmp/minimal_pc"
# The shared library exports the C API's symbols and nothing else, and a C linker suffices:
# through pkg-config, and through find_package in a C-only CMake project.
so=$(find "$tmp/prefix" -name 'libchladni.so.2')
test -n "$so"
declared=$(grep -oE '\bchladni_[a-z_]+\(' "$tmp/prefix/include/chladni/chladni.h" | tr -d '(' | sort -u)
exported=$(nm -D --defined-only "$so" | awk '{ print $3 }' | sort -u)
if [[ "$declared" != "$exported" ]]; then
  echo "libchladni.so must export exactly the functions chladni.h declares (< declared, > exported):" >&2
  diff <(echo "$declared") <(echo "$exported") >&2 || true
  exit 1
fi
cc -std=c11 "$src/examples/embedding/minimal.c" $(pkg-config --cflags --libs chladni) -lm \
  -o "$tmp/minimal_so"
readelf -d "$tmp/minimal_so" | grep -q 'libchladni.so.2'
LD_LIBRARY_PATH=$(dirname "$so") "$tmp/minimal_so"
cmake -S "$src/tests/c_consumer" -B "$tmp/c_consumer" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$tmp/prefix" > "$tmp/c-configure.log"
cmake --build "$tmp/c_consumer" > "$tmp/c-build.log"
"$tmp/c_consumer/minimal_shared"
# The runtime carries no GPL code: an engine's binary links neither FFTW nor the precompute side.
for bin in "$tmp/embed/minimal_c" "$tmp/embed/minimal_cpp" "$tmp/minimal_pc" "$tmp/minimal_so"; do
  if LD_LIBRARY_PATH=$(dirname "$so") ldd "$bin" | grep -Eiq 'fftw|tet|cgal|cholmod|hmat'; then
    echo "$bin links a GPL/AGPL library:" >&2
    ldd "$bin" >&2
    exit 1
  fi
done
"$tmp/minimal_pc"
# The example host (Bullet): its first sound starts with its first impact, within 1 ms; its
# bodies slide and roll through continuous contacts.
cmake -S "$src/examples/falling-objects" -B "$tmp/falling" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$tmp/prefix" > "$tmp/falling-configure.log"
cmake --build "$tmp/falling" > "$tmp/falling-build.log"
# --check: every logged sliding or rolling interval has its contact's own sound, and each contact
# that ends stops driving its body within 50 ms (the program exits 1 otherwise).
(cd "$tmp" && "$tmp/falling/falling_objects" --seconds 2 --check -o f.wav --log f.csv) |
  tee "$tmp/f.out"
test "$(grep -c ',impact,' "$tmp/f.csv")" -gt 4
test "$(grep -c ',slide,' "$tmp/f.csv")" -gt 0  # bodies slide ...
test "$(grep -c ',roll,' "$tmp/f.csv")" -gt 0   # ... and the ball rolls
grep -q ' 0 without sound; [1-9][0-9]* ends, 0 driven on past 50 ms' "$tmp/f.out"
awk '/first impact at/ { i = $(NF-9); s = $(NF-4); d = s - i; if (i < 0 || d < 0 || d > 0.001) exit 1 }' \
  "$tmp/f.out"
# The windowed renderer example builds against the package as shown in its CMakeLists.txt (the
# test RendererExample.* runs it, headless).
cmake -S "$src/examples/renderer" -B "$tmp/renderer" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$tmp/prefix" > "$tmp/renderer-configure.log"
cmake --build "$tmp/renderer" > "$tmp/renderer-build.log"
test -x "$tmp/renderer/renderer"
echo "installed package: find_package and pkg-config builds run (static and shared), and so does the Bullet host; the renderer example builds"
