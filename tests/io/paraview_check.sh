#!/usr/bin/env bash
# Results in the real ParaView: runs a model as one process, partitioned on threads, on
# worker processes and loosely coupled, and opens each run's XDMF sidecar with pvpython
# (both XDMF readers, every time step against the HDF5 file, a rendered picture).
# usage: paraview_check.sh MBSFLOW SOURCE_DIR WORK_DIR
set -euo pipefail
mbsflow=$(realpath "$1") source=$(realpath "$2") work=$3
for tool in pvpython xvfb-run; do
  command -v "$tool" >/dev/null || { echo "paraview_check: $tool is missing: run scripts/install-deps.sh" >&2; exit 1; }
done
rm -rf "$work" && mkdir -p "$work" && cd "$work"
"$mbsflow" generate grid --rows 3 --cols 4 -o grid.json 2>/dev/null
runs=(
  "single:"
  "threads:--partitions 2 --threads 2"
  "processes:--processes 2"
  "loose:--partitions 2 --coupling loose"
)
for entry in "${runs[@]}"; do
  name=${entry%%:*} options=${entry#*:}
  # shellcheck disable=SC2086
  "$mbsflow" run grid.json --t-end 0.05 --output-interval 0.01 --fields all $options -o "$name.h5" 2>/dev/null
  /usr/bin/python3 "$source/tests/io/check_xdmf.py" "$name.xdmf"
  # A second try if the first fails to start: xvfb-run picks its display by lock files,
  # and the log says what happened either way.
  for try in 1 2; do
    status=0
    xvfb-run -a -e "$name.xvfb.log" pvpython "$source/tests/io/paraview_xdmf.py" "$work/$name.xdmf" "$work/$name.png" \
      > "$name.log" 2>&1 || status=$?
    grep -v -e "^$" -e "Skipping" "$name.log"
    grep -q "rendered" "$name.log" && break
    echo "paraview_check: try $try on the $name run failed (exit $status); Xvfb said:" >&2
    cat "$name.xvfb.log" >&2 || true
    [ "$try" = 2 ] && { echo "paraview_check: ParaView failed on the $name run" >&2; exit 1; }
  done
done
# A long run: the sidecar shows at most 1000 snapshots, the first and last among them.
"$mbsflow" generate chain --bodies 3 -o chain.json 2>/dev/null
"$mbsflow" run chain.json --t-end 1.2 --output-interval 0.001 -o long.h5 2>/dev/null
/usr/bin/python3 "$source/tests/io/check_xdmf.py" long.xdmf
echo "paraview_check: ${#runs[@]} runs read by both ParaView readers"
