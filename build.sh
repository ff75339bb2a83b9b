#!/usr/bin/env bash
# Set up and build hsnc on Debian 12: install the Debian packages it needs
# (only those missing), configure with CMake and build. Idempotent; quick when
# everything is already there. Usage: ./build.sh [BUILD_DIR] (default: build)
set -euo pipefail
cd "$(dirname "$0")"
build_dir=${1:-build}

packages=(
  build-essential cmake pkg-config
  libginac-dev libcln-dev        # symbolic derivation of the segment formulas
  libeigen3-dev                  # linear algebra (modal analysis) at run time
  libspectra-dev                 # sparse eigenproblems (the fixed-interface modes of [reduction])
  libtomlplusplus-dev            # the model file
  libcli11-dev                   # command line parsing
  libsundials-dev                # the CVODE baseline (--method cvode)
  libmatio-dev                   # [structure] matrices from MATLAB .mat files
  libhdf5-dev                    # --h5 result files
  llvm-14-dev libclang-cpp14-dev libclang-14-dev  # compiling kernels in-process
  libgtest-dev                   # tests
  gnuplot-nox fonts-dejavu-core   # plots (pngcairo needs a font)
  python3-dev pybind11-dev python3-numpy  # the Python module (import hsnc)
  python3-pytest python3-matplotlib       # its tests, examples/scenario2.py
  python3-dask                   # the test of hsnc.sweep_map on a Dask bag
  python3-nbconvert python3-ipykernel python3-nbformat python3-scipy  # the notebooks, run as tests (SciPy: their oracles)
  python3-h5py                   # hsnc.to_h5 and the tests that read --h5 files
  libopenmpi-dev openmpi-bin     # hsnc sweep over MPI ranks (mpirun -np K hsnc sweep ...)
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "build.sh: installing missing Debian packages: ${missing[*]}" >&2
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi

if [ ! -f "$build_dir/CMakeCache.txt" ]; then
  cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release >&2
fi
cmake --build "$build_dir" -j"$(nproc)" >&2

# `import hsnc` in Debian's python3 from any directory: a .pth file in its
# user site directory names the module built in BUILD_DIR/python (the last
# checkout built with ./build.sh wins). HSNC_NO_PTH=1 skips it.
if [ -f "$build_dir/python/hsnc/__init__.py" ] && [ -z "${HSNC_NO_PTH:-}" ]; then
  site=$(/usr/bin/python3 -m site --user-site)
  mkdir -p "$site"
  (cd "$build_dir/python" && pwd) > "$site/hsnc.pth"
  echo "build.sh: /usr/bin/python3 imports hsnc from $(cat "$site/hsnc.pth") ($site/hsnc.pth)" >&2
fi
