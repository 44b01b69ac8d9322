#!/usr/bin/env bash
# --refine auto at the input's own triangle count against the input's own triangles (issue 12,
# point 3): each scene baked with the defaults (refine none) and with --refine auto --budget F,
# both judged by one fixed reference (eval --rays 1024, its default points). Prints RMS and 95th
# percentile error, the bake seconds, what auto simplified to, and the error auto's bake predicts
# for itself on its hold-out (its ratio to eval's).
# usage: bash bench/both_ways.sh BUILD_DIR SCENES_DIR OUT_DIR [SCENE...] [-- bake options]
set -euo pipefail
build=$1 scenes=$2 out=$3
shift 3
names=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do names+=("$1"); shift; done
[ "${1:-}" = -- ] && shift
[ ${#names[@]} -gt 0 ] || names=(house_on_site.obj sibenik.obj conference.ply)
prtsub=$build/prtsub
mkdir -p "$out"
echo "| scene | triangles | none RMS % | none p95 % | auto RMS % | auto p95 % | RMS ratio | simplified to | none s | auto s | auto predicted % | predicted / eval |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for name in "${names[@]}"; do
  mesh=$scenes/$name base=$out/${name%.*}
  "$prtsub" bake "$mesh" "$@" -o "$base.none.ply" --report "$base.none.json" > /dev/null
  F=$(python3 -c "import json; print(json.load(open('$base.none.json'))['triangles_in'])")
  "$prtsub" bake "$mesh" "$@" --refine auto --budget "$F" -o "$base.auto.ply" --report "$base.auto.json" > /dev/null
  for a in none auto; do "$prtsub" eval "$base.$a.ply" --source "$mesh" --rays 1024 --report "$base.$a.eval.json" > /dev/null; done
  python3 - "$base" "$name" "$F" <<'PY'
import json, sys
base, name, F = sys.argv[1:]
e = {a: json.load(open("%s.%s.eval.json" % (base, a))) for a in ("none", "auto")}
b = {a: json.load(open("%s.%s.json" % (base, a))) for a in ("none", "auto")}
p = b["auto"].get("predicted_error_percent")
pred = ("%.3f +- %.3f" % (p, b["auto"]["predicted_error_standard_error"]), "%.2f" % (p / e["auto"]["rms_percent"])) if p is not None else ("-", "-")
print("| %s | %s | %.3f | %.3f | %.3f | %.3f | %.2f | %s | %.1f | %.1f | %s | %s |" % (
    name, F, e["none"]["rms_percent"], e["none"]["p95_percent"], e["auto"]["rms_percent"], e["auto"]["p95_percent"],
    e["auto"]["rms_percent"] / e["none"]["rms_percent"], b["auto"].get("simplified_to", "?"), b["none"]["seconds_total"],
    b["auto"]["seconds_total"], pred[0], pred[1]))
PY
done
