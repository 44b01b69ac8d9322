#!/usr/bin/env bash
# Whole-process cost of starting prtsub (issue 17): `prtsub --version` and a bake of the bundled
# example, each run N times by each build in turn (alternating, so load on a shared machine
# falls on both), wall time and peak memory from /usr/bin/time; prints the median of each.
# usage: bash bench/startup.sh N BUILD_DIR...   e.g. bash bench/startup.sh 20 /tmp/old/build build
set -euo pipefail
n=$1
shift
root=$(cd "$(dirname "$0")/.." && pwd)
example="$root/examples/spot/spot_control_mesh.obj"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
echo "| build | command | median wall s | median peak MiB | shared libraries |"
echo "|---|---|---:|---:|---:|"
for what in version bake; do
  for ((i = 0; i < n; ++i)); do
    for build in "$@"; do
      tag=$(echo "$build" | tr '/' '_')
      if [ "$what" = version ]; then
        /usr/bin/time -f "%e %M" -a -o "$out/$tag.$what" "$build/prtsub" --version > /dev/null
      else
        /usr/bin/time -f "%e %M" -a -o "$out/$tag.$what" "$build/prtsub" bake "$example" -o "$out/spot.ply" > /dev/null
      fi
    done
  done
  for build in "$@"; do
    tag=$(echo "$build" | tr '/' '_')
    libs=$(ldd "$build/prtsub" | wc -l)
    python3 - "$out/$tag.$what" "$build" "$what" "$libs" <<'PY'
import statistics, sys
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
wall = statistics.median(float(r[0]) for r in rows)
mib = statistics.median(float(r[1]) for r in rows) / 1024
cmd = 'prtsub --version' if sys.argv[3] == 'version' else 'prtsub bake spot_control_mesh.obj'
print('| %s | %s | %.3f | %.0f | %s |' % (sys.argv[2], cmd, wall, mib, sys.argv[4]))
PY
  done
done
