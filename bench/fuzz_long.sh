#!/usr/bin/env bash
# Long fuzzing runs (issue 16: at least an hour per reader), beside other work: each target runs
# at nice $NICE (default 19; NICE=0 on an otherwise idle core) with its own growing corpus,
# and /usr/bin/time records the CPU time it actually got
# (libFuzzer's -max_total_time is wall time). Same flags as .ci/fuzz. Build the targets first:
#   bash .ci/fuzz obj ply off stl asset    (builds build-sanitize/, then runs each for 60 s)
# usage: bash bench/fuzz_long.sh OUT_DIR SECONDS READER...   (readers run concurrently)
#   then: tail -n 12 OUT_DIR/log_READER.txt; cat OUT_DIR/time_READER.txt
set -euo pipefail
out=$1 seconds=$2
shift 2
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out/bin"
cp "$root"/build-sanitize/tests/fuzz/fuzz_* "$out/bin/"
[ -d "$out/corpus" ] || python3 "$root/tests/fuzz/make_corpus.py" "$out/corpus"
for reader in "$@"; do
  mkdir -p "$out/art/$reader"
  (set +e; cd "$out" || exit 1; /usr/bin/time -f "cpu_user=%U cpu_sys=%S wall=%e maxrss_kb=%M" -o "time_$reader.txt" \
     nice -n "${NICE:-19}" "bin/fuzz_$reader" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
     -artifact_prefix="art/$reader/" "corpus/$reader" > "log_$reader.txt" 2>&1; echo "exit=$?" >> "time_$reader.txt") &
done
wait
