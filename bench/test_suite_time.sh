#!/usr/bin/env bash
# The test suite's wall time, two builds alternated in one session (the machine is shared and
# noisy), and the start-up of one small test in each build's runner.
#   bash bench/test_suite_time.sh OLD_BUILD NEW_BUILD [RUNS]
# OLD_BUILD is a build of an earlier commit, e.g.
#   git worktree add /tmp/old c1dfbd4 && cmake -S /tmp/old -B /tmp/old/build -G Ninja && cmake --build /tmp/old/build
# (with ../shared beside /tmp/old, so its scene tests run too).
set -euo pipefail
old=$1 new=$2 runs=${3:-3}
for i in $(seq "$runs"); do
  for b in "$old" "$new"; do
    /usr/bin/time -o /tmp/suite_time.txt -f "$b run $i: %e s wall, %U s user" ctest --test-dir "$b" -j2 > /tmp/suite_time.log 2>&1 ||
      { echo "$b: tests failed"; exit 1; }
    echo "$(cat /tmp/suite_time.txt); $(grep -h "tests passed" /tmp/suite_time.log)"
  done
done
for b in "$old" "$new"; do
  for runner in "$b"/tests/prtsub_tests "$b"/tests/prtsub_prt_tests; do
    [ -x "$runner" ] || continue
    /usr/bin/time -f "$runner, one SH test: %e s ($(ldd "$runner" | wc -l) shared libraries)" \
      "$runner" --gtest_filter='SphericalHarmonics.ClosedForms*' > /dev/null
  done
done
