#!/usr/bin/env bash
# Installs the Debian packages screwfem needs (README.md, "Dependencies", says why each; details
# in docs/install.md), and only those that are missing. Silent when everything is already
# installed; needs root only to install.
set -euo pipefail

# Groups, so that a job installs only what it uses and the test job can compile while the
# packages only its tests need are being installed (scripts/run-tests.sh):
#   build  what configuring and compiling the Release tree needs;
#   main   build + what the main job's figures and viewer pages need (scripts/run-main.sh);
#   rest   the figures' and viewer's packages + what only the tests use (the sanitizer
#          compiler, clang-format for the lint, Chromium for the viewer test, venv/pip for
#          the package test, Dask, nbconvert and ipykernel for the tutorial notebooks,
#          websockets for Simulation.view's live view, mkdocs, pymdownx and MathJax for the
#          documentation site of the test docs_site);
#   bench  build + what only the benchmarks use: MuJoCo, which screwfem_bench_mujoco runs side
#          by side with screwfem on the same model (bench/RESULTS.md, "Spring chain against
#          MuJoCo"; the bench builds only when it is found, the tests never need it), and
#          NLopt, which screwfem_bench_inverse compares with Ceres (docs/inverse.md), and
#          numba (and typing_extensions, which PyElastica 1.0 imports), on which
#          bench/pyelastica_bench.py runs a checkout of PyElastica's source (bench/RESULTS.md,
#          "Sliding rod against PyElastica");
#   all    everything (the default).
# Usage: setup-deps.sh [build|main|rest|bench|all]
build_packages=(
  build-essential cmake
  libeigen3-dev libyaml-cpp-dev libcli11-dev
  googletest libgtest-dev libbenchmark-dev
  pybind11-dev python3-dev python3-numpy libsuitesparse-dev liburdfdom-dev libceres-dev
)
view_packages=(python3-matplotlib python3-pil libjs-three)
bench_packages=(libmujoco-dev libnlopt-dev python3-numba python3-typing-extensions)
test_packages=(
  clang clang-format python3-venv python3-pip
  python3-dask python3-distributed python3-pandas
  chromium python3-websocket python3-websockets
  jupyter-nbconvert python3-ipykernel
  mkdocs python3-pymdownx libjs-mathjax
)
case "${1:-all}" in
  build) packages=("${build_packages[@]}") ;;
  main) packages=("${build_packages[@]}" "${view_packages[@]}") ;;
  rest) packages=("${view_packages[@]}" "${test_packages[@]}") ;;
  bench) packages=("${build_packages[@]}" "${bench_packages[@]}") ;;
  all)
    packages=("${build_packages[@]}" "${view_packages[@]}" "${test_packages[@]}"
      "${bench_packages[@]}")
    ;;
  *)
    echo "setup-deps: unknown group '$1' (expected build, main, rest, bench or all)" >&2
    exit 2
    ;;
esac

if ! command -v dpkg-query > /dev/null 2>&1; then
  echo "setup-deps: dpkg-query not found; screwfem's scripts expect Debian 12 (bookworm)." >&2
  exit 1
fi

missing=()
for pkg in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${db:Status-Abbrev}' "$pkg" 2> /dev/null || true)
  [[ "$status" == ii* ]] || missing+=("$pkg")
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

if [[ $(id -u) -ne 0 ]]; then
  echo "setup-deps: missing Debian packages, and installing them needs root:" >&2
  echo "  apt-get install --no-install-recommends ${missing[*]}" >&2
  echo "setup-deps: run this script as root, or install them and run again." >&2
  exit 1
fi
echo "setup-deps: installing missing Debian packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup-deps: done"
