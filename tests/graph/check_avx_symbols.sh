#!/bin/sh
# The AVX build of the lane kernels (graph/src/lane_kernels_avx.cpp) may define no shared
# (weak or unique) function outside its own namespace lanes_avx: the linker could
# otherwise pick such an AVX-built copy of a template or inline function for the whole
# library, and a CPU without AVX would then fault in code that never asked for AVX.
# (Shared data, such as an inline constant table, holds no instructions.) Arguments: the
# graph library's object files.
found=0
for o in "$@"; do
  case "$o" in
    *lane_kernels_avx.cpp.o)
      found=1
      shared=$(readelf -sW "$o" | awk '$4 == "FUNC" && ($5 == "WEAK" || $5 == "UNIQUE") && $7 != "UND" {print $8}' |
        c++filt | grep -v 'lanes_avx')
      if [ -n "$shared" ]; then
        echo "lane_kernels_avx.cpp.o shares functions built for AVX:"
        echo "$shared"
        exit 1
      fi
      nm -C --defined-only "$o" | grep -q 'bushings_on_lanes_avx' || { echo "no bushings_on_lanes_avx in $o"; exit 1; }
      ;;
  esac
done
[ "$found" = 1 ] || { echo "lane_kernels_avx.cpp.o not among the objects"; exit 1; }
echo "lane_kernels_avx.cpp.o shares no function built for AVX"
