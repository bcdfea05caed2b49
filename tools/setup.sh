#!/usr/bin/env bash
# Shared by tools/test.sh and tools/quickstart.sh (sourced): install the Debian 12 packages the
# project needs, and configure and build it in build/.
#   mesopen_install   installs whatever is missing (nothing, and no apt-get update, if all present)
#   mesopen_build     cmake configure (Ninja, Release) and build in $MESOPEN_ROOT/build
# Run directly (bash tools/setup.sh) it only installs the packages.

# The repository root, from this file's own location.
MESOPEN_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

# Notes on the list:
# - libvtk9-dev conflicts with Debian's paraview package: do not install paraview beside it
#   (use a ParaView from paraview.org to open the .vtu/.pvd files).
# - LIGGGHTS (libliggghts-dev) needs libopenmpi-dev for mpi.h; openmpi-bin provides mpirun (the DEM
#   coupling and the runs over several processes).
# - Spectra and SuiteSparse solve the eigenproblem of `mesopen modal`.
# - python3-matplotlib/numpy/h5py are used through /usr/bin/python3 (plots, post-processing).
# - python3-vtk9 (VTK's Python bindings, the libvtk9 of libvtk9-dev) reads the VTK files back and
#   renders a frame off screen in the test liggghts_vtk_files; xvfb (xvfb-run) and xauth give that
#   rendering an X display where there is none (CI). ParaView itself is not needed.
# - yade runs the test yade_spheres_at_rest (label yade): 63 packages, 118 MB download, 0.8 GB disk.
# - libtrilinos-zoltan-dev is Zoltan (RCB), which partitions the FE bodies among the MPI ranks
#   (parallel/zoltan_partitioner.cpp; it brings trilinos-dev's CMake files and Scotch's runtime
#   libraries). Its CMake target links libptscotch.so, libscotch.so and libz.so by path:
#   libptscotch-dev (with libscotch-dev) and zlib1g-dev provide them.
MESOPEN_PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev libeigen3-dev
  libhdf5-dev libvtk9-dev libtomlplusplus-dev libcli11-dev nlohmann-json3-dev libgtest-dev
  libliggghts-dev libopenmpi-dev openmpi-bin
  libtrilinos-zoltan-dev libptscotch-dev zlib1g-dev
  libspectra-dev libsuitesparse-dev
  python3 python3-matplotlib python3-numpy python3-h5py python3-vtk9 xvfb xauth
  clang-format
  yade
)

# Prints the packages of MESOPEN_PACKAGES that are not installed, one per line.
mesopen_missing_packages() {
  local p
  for p in "${MESOPEN_PACKAGES[@]}"; do
    if ! dpkg -s "$p" 2>/dev/null | grep -q '^Status: install ok installed$'; then
      echo "$p"
    fi
  done
}

mesopen_install() {
  if ! command -v dpkg >/dev/null 2>&1 || ! command -v apt-get >/dev/null 2>&1; then
    echo "setup: dpkg/apt-get not found; this script expects Debian 12 (bookworm)" >&2
    return 1
  fi
  local missing
  mapfile -t missing < <(mesopen_missing_packages)
  if [ "${#missing[@]}" -eq 0 ]; then
    echo "setup: all ${#MESOPEN_PACKAGES[@]} packages are installed"
    return 0
  fi
  local -a as_root=()
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then
      as_root=(sudo)
    else
      echo "setup: not root and no sudo; install these packages first: ${missing[*]}" >&2
      return 1
    fi
  fi
  echo "setup: installing ${missing[*]}"
  "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get -qq update
  "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
    -o Dpkg::Use-Pty=0 -o APT::Color=0 "${missing[@]}"
  mapfile -t missing < <(mesopen_missing_packages)
  if [ "${#missing[@]}" -ne 0 ]; then
    echo "setup: still missing after apt-get install: ${missing[*]}" >&2
    return 1
  fi
}

mesopen_build() {
  cd "$MESOPEN_ROOT"
  # An existing build/ keeps the generator it was configured with (cmake refuses to switch).
  local -a generator=(-G Ninja)
  if [ -f build/CMakeCache.txt ]; then
    generator=()
  fi
  cmake -S . -B build "${generator[@]}" -DCMAKE_BUILD_TYPE=Release
  cmake --build build -j "$(nproc)"
}

if [ "${BASH_SOURCE[0]}" = "$0" ]; then
  set -euo pipefail
  mesopen_install
fi
