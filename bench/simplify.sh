#!/usr/bin/env bash
# Simplification (issue 12): each scene brought to 50%, 25% and 10% of its triangles with the
# transfer-aware metric and with the geometric quadric alone (--simplify-metric geometry), both
# fitted to samples of the source surface, plus the transfer-aware one with point values at
# 10%; every asset judged by one fixed reference (eval --rays 2048 --points 20000, closest-point
# location). Prints a Markdown table, with the error each fitted bake predicts for itself on
# samples held out of the source surface.
#   bench/simplify.sh BUILD_DIR SHARED_SCENES_DIR OUT_DIR [SCENES...]
set -euo pipefail
B="$1/prtsub"; S="$2"; O="$3"; shift 3
scenes=("${@:-bunny.ply armadillo.ply chinese_dragon.obj mori_knob.obj sibenik.obj}")
mkdir -p "$O"
field() { python3 -c "import json,sys; print(json.load(open(sys.argv[1])).get(sys.argv[2], '-'))" "$1" "$2"; }
predicted() { python3 -c "import json,sys; p=json.load(open(sys.argv[1])).get('predicted_error_percent'); print('-' if p is None else '%.3f' % p)" "$1"; }
echo "| scene | share | metric | fit | triangles | bake s | simplify s | peak MiB | RMS % | predicted % |"
echo "|---|---:|---|---|---:|---:|---:|---:|---:|---:|"
for sc in ${scenes[@]}; do
  n=${sc%.*}
  "$B" bake "$S/$sc" -o "$O/$n.count.ply" --rays 1 --fit point --report "$O/$n.count.json" > /dev/null
  F=$(field "$O/$n.count.json" triangles_out)
  for share in 50 25 10; do
    T=$((F * share / 100))
    runs="transfer:lsq geometry:lsq"
    [ "$share" = 10 ] && runs="$runs transfer:point"
    for run in $runs; do
      metric=${run%:*}; fit=${run#*:}; a="$O/$n.$share.$metric.$fit"
      "$B" bake "$S/$sc" -o "$a.ply" --refine adaptive --budget "$T" --simplify-metric "$metric" --fit "$fit" \
        --report "$a.json" > "$a.log" 2>&1
      "$B" eval "$a.ply" --source "$S/$sc" --rays 2048 --points 20000 --report "$a.eval.json" > /dev/null
      echo "| $n | $share% | $metric | $fit | $(field "$a.json" triangles_out) | $(printf %.1f "$(field "$a.json" seconds_bake)") |" \
           "$(printf %.1f "$(field "$a.json" seconds_simplify)") | $(printf %.0f "$(field "$a.json" peak_memory_mib)") |" \
           "$(printf %.3f "$(field "$a.eval.json" rms_percent)") | $(predicted "$a.json") |"
    done
  done
done
