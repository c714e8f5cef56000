#!/usr/bin/env bash
# Runs one libFuzzer target for SECONDS from its seed corpus (copied to a scratch
# directory: libFuzzer adds what it finds to its first corpus directory) and prints the
# figures it ends with. Exit status: libFuzzer's (0: no crash, leak or UBSan report).
#   tests/fuzz/run_fuzzer.sh FUZZ_BUILD TARGET SECONDS
set -euo pipefail
build=$1 target=$2 seconds=$3
here=$(cd "$(dirname "$0")" && pwd)
source_dir=$(cd "$here/../.." && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/mbsflow_fuzz_${target}.XXXXXX")
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/corpus"
case $target in
  fuzz_model_reader) cp "$source_dir"/examples/models/*.json "$source_dir"/tests/io/bad_models/*.json "$work/corpus/" ;;
  *) cp "$here/corpus/${target#fuzz_}"/* "$work/corpus/" ;;
esac
cd "$work"
# Inputs up to 64 KB; a run of one input over 10 s counts as a hang; 2 GB RSS at most.
status=0
UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  "$build/$target" -max_total_time="$seconds" -max_len=65536 -timeout=10 -rss_limit_mb=2048 \
  -print_final_stats=1 corpus > log.txt 2>&1 || status=$?
if [ "$status" -ne 0 ]; then
  tail -n 60 log.txt
  ls crash-* leak-* timeout-* oom-* 2>/dev/null | while read -r f; do echo "$target: failing input $f:"; head -c 600 "$f" | od -c | head -20; done
else
  grep -E "^(#[0-9]+.*DONE|stat::|Done)" log.txt
fi
exit "$status"
