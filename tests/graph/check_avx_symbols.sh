#!/bin/sh
# The AVX build of the lane kernels (graph/src/lane_kernels_avx.cpp) may define no shared
# (weak) symbol outside its own namespace lanes_avx: the linker could otherwise pick such
# an AVX-built copy of a template or inline function for the whole library, and a CPU
# without AVX would then fault in code that never asked for AVX. Arguments: the graph
# library's object files.
found=0
for o in "$@"; do
  case "$o" in
    *lane_kernels_avx.cpp.o)
      found=1
      shared=$(nm -C --defined-only "$o" | awk '$2 ~ /^[WVuw]$/' | grep -v 'lanes_avx')
      if [ -n "$shared" ]; then
        echo "lane_kernels_avx.cpp.o shares symbols built for AVX:"
        echo "$shared"
        exit 1
      fi
      nm -C --defined-only "$o" | grep -q 'bushings_on_lanes_avx' || { echo "no bushings_on_lanes_avx in $o"; exit 1; }
      ;;
  esac
done
[ "$found" = 1 ] || { echo "lane_kernels_avx.cpp.o not among the objects"; exit 1; }
echo "lane_kernels_avx.cpp.o shares no AVX-built symbol"
