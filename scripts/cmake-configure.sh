# Sourced by the scripts of this folder. configure DIR CMAKE_ARGS...: configures the source
# tree (the current directory) into DIR with the Ninja generator. Ninja compiles the objects of
# all layers' libraries in parallel; Make waits for each library before compiling the objects
# of the layers above it, which left one of the two cores idle through most of the library
# (screwfem is eight layer libraries, docs/architecture.md). A DIR configured with another
# generator is configured afresh (CMake refuses to switch generators in place).
configure() {
  local dir=$1
  shift
  if [[ -f "$dir/CMakeCache.txt" ]] &&
      ! grep -q '^CMAKE_GENERATOR:INTERNAL=Ninja$' "$dir/CMakeCache.txt"; then
    echo "configure: $dir was configured with another generator; configuring it afresh with Ninja"
    rm -rf "$dir/CMakeCache.txt" "$dir/CMakeFiles"
  fi
  cmake -S . -B "$dir" -G Ninja "$@"
}
