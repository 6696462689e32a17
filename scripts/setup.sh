#!/usr/bin/env bash
# One-command set-up on Debian 12: installs what is missing, builds, then
#   scripts/setup.sh demo   runs the demo (biomechreg with no argument)
#   scripts/setup.sh test   runs the test suite (ctest -j2)
#   scripts/setup.sh build  only builds
# BUILD_DIR (default ./build) and JOBS (default: number of cores) may be set.
set -euo pipefail
mode="${1:-demo}"
case "$mode" in demo|test|build) ;; *) echo "usage: $0 demo|test|build" >&2; exit 2 ;; esac
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${BUILD_DIR:-$root/build}"
jobs="${JOBS:-$(nproc)}"

packages=(build-essential cmake ninja-build libinsighttoolkit5-dev libvtk9-dev libeigen3-dev libcgal-dev
  libgdcm-dev libfftw3-dev libsuitesparse-dev libopenblas-dev libmetis-dev libtbb-dev libjemalloc-dev nlohmann-json3-dev time python3-matplotlib python3-numpy
  python3-dev pybind11-dev python3-pytest python3-pydicom libxml2-utils zlib1g-dev
  snakemake plastimatch dicom3tools)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "Installing: ${missing[*]}"
  sudo_cmd=""; [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# CHOLMOD is 5x slower with the reference BLAS: make sure OpenBLAS is the one loaded.
if command -v update-alternatives >/dev/null; then
  blas=$(update-alternatives --query libblas.so.3-x86_64-linux-gnu 2>/dev/null | awk '/^Value:/{print $2}')
  case "$blas" in *openblas*|"") ;; *) echo "warning: libblas.so.3 is $blas, not OpenBLAS; CHOLMOD will be slow" >&2 ;; esac
fi

# The Python package is built for Debian's python3 (which has numpy), not for another python3 earlier on the PATH.
python=()
[ -x /usr/bin/python3 ] && python=(-DPython3_EXECUTABLE=/usr/bin/python3)
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=ON "${python[@]}"
cmake --build "$build" -j "$jobs"
# The Python package into python3's site-packages, so that `python3 -c "import biomechreg"` works (when built).
if grep -q "^BMR_WRAP_PYTHON:BOOL=ON" "$build/CMakeCache.txt"; then
  sudo_cmd=""; [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd cmake --install "$build" --component python >/dev/null ||
    echo "note: the Python package was not installed (no permission); use PYTHONPATH=$build/python" >&2
fi

case "$mode" in
  demo) cd "$root" && "$root/scripts/run_demo.sh" "$build" ;;
  test) cd "$build" && ctest -j2 --output-on-failure --timeout 1500 --no-tests=error ;;
  build) ;;
esac
