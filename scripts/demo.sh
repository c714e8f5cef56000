#!/usr/bin/env bash
# Installs what is missing, builds in Release, runs the default example simulation
# and plots it.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
jobs=$(nproc 2>/dev/null || echo 2)
cmake --preset release >/dev/null
# Only what the demo needs: the program (test.sh builds the rest, the Python module
# included, with the same configuration, so nothing built here is compiled again).
cmake --build --preset release -j "$jobs" --target mbsflow_cli
exe=build/release/apps/mbsflow
out=results/demo
mkdir -p "$out"
"$exe" generate chain --bodies 200 -o "$out/chain.json"
"$exe" run "$out/chain.json" --t-end 2 --output "$out/chain.h5"
"$exe" info "$out/chain.h5"
"$exe" plot "$out/chain.h5" -o "$out/chain.png" >/dev/null
"$exe" view "$out/chain.h5" -o "$out/chain.html" 2>/dev/null
echo
echo "demo: model    $out/chain.json"
echo "demo: results  $out/chain.h5 (open $out/chain.xdmf in ParaView; mbsflow export $out/chain.h5 --csv DIR for CSV)"
echo "demo: plot     $out/chain.png"
echo "demo: motion   $out/chain.html (open it in a browser: play, seek, orbit)"
echo "demo: python   cmake --build --preset release --target mbsflow_python (test.sh builds it too), then"
echo "              PYTHONPATH=build/release/python /usr/bin/python3 -c \"import mbsflow; r = mbsflow.Results.open('$out/chain.h5'); print(r.position.shape)\" (docs/python.md)"
