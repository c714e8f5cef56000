#!/usr/bin/env bash
# Installs the Debian packages mbsflow needs, and only those that are missing,
# so a second run installs nothing. Needs root (or sudo) only when something is missing.
set -euo pipefail

packages=(
  cmake ninja-build g++ pkg-config
  libeigen3-dev nlohmann-json3-dev libcli11-dev catch2
  libtbb-dev libzmq3-dev cppzmq-dev libboost-graph-dev libmetis-dev libhdf5-dev hdf5-tools
  python3 python3-h5py python3-matplotlib
  iproute2  # ip netns, for the test across two network namespaces
  libsundials-dev libboost-dev
  libsuitesparse-dev  # KLU, the sparse LU of the implicit methods; CHOLMOD, the Cholesky of mbsflow reduce
  libopenblas0-pthread  # the BLAS under CHOLMOD and the reduction's dense products: 7x the reference BLAS on a 200 000-DOF part
  libspectra-dev  # Spectra: the sparse shift-invert eigensolver of mbsflow modes
  calculix-ccx  # tests only: the FE code whose matrices mbsflow reduce reads and whose frequencies it is checked against
  clang libclang-rt-14-dev  # libFuzzer targets (tests/fuzz); Debian 12's clang is 14
  paraview python3-paraview xvfb  # the results opened in the real ParaView (tests/io/paraview_check.sh)
  libjs-three  # three.js, inlined by mbsflow view
  pybind11-dev python3-dev python3-numpy python3-scipy python3-pytest  # the Python package and its tests
  chromium chromium-driver python3-selenium python3-pil  # the viewer tested in a real browser
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "mbsflow: all build dependencies present"
  exit 0
fi
echo "mbsflow: installing ${missing[*]}"
sudo=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "mbsflow: need root or sudo to install: ${missing[*]}" >&2; exit 2; }
  sudo="sudo"
fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
