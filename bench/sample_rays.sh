#!/usr/bin/env bash
# Issue 11, point 2: rays per sample chosen by the pilot (the default) against the fixed 16 of
# `--sample-rays 16`, for the same sample rays. Each baked twice, alternating, and timed by the
# faster run; both judged by one fixed reference (eval --rays 2048 at its seeded points).
# usage: bash bench/sample_rays.sh BUILD_DIR SCENES_DIR OUT_DIR "SCENE..." "SIGNAL..." [bake options]
set -euo pipefail
build=$1 scenes=$2 out=$3 scene_list=$4 signal_list=$5
shift 5
mkdir -p "$out"
echo "| scene | signal | chosen | its relative error per choice (4, 16, 32) | E chosen % | E at 16 % | chosen / 16 | s chosen | s at 16 |"
echo "|---|---|---:|---|---:|---:|---:|---:|---:|"
for scene in $scene_list; do
  name=${scene%.*}
  for signal in $signal_list; do
    stem="$out/${name}_${signal}"
    # Twice each, alternating, timed by the faster of the two (the assets are the same each time).
    for run in 1 2; do
      "$build/prtsub" bake "$scenes/$scene" --signal "$signal" --sample-rays 16 "$@" -o "$stem.fixed.ply" --report "$stem.fixed$run.json" > /dev/null
      "$build/prtsub" bake "$scenes/$scene" --signal "$signal" "$@" -o "$stem.auto.ply" --report "$stem.auto$run.json" > /dev/null
    done
    for v in auto fixed; do
      "$build/prtsub" eval "$stem.$v.ply" --source "$scenes/$scene" --rays 2048 --report "$stem.$v.eval.json" > /dev/null
      rm -f "$stem.$v.ply"
    done
    python3 - "$stem" "$name" "$signal" <<'PY'
import json, re, sys
stem, name, signal = sys.argv[1:]
a, b = json.load(open(stem + '.auto1.json')), json.load(open(stem + '.fixed1.json'))
sa = min(json.load(open(stem + '.auto%d.json' % k))['seconds_total'] for k in (1, 2))
sb = min(json.load(open(stem + '.fixed%d.json' % k))['seconds_total'] for k in (1, 2))
ea, eb = (json.load(open(stem + '.%s.eval.json' % v))['rms_percent'] for v in ('auto', 'fixed'))
trials = ', '.join(re.findall(r'\d+: ([\d.]+)', a.get('sample_rays_trials', ''))) or '(not measured)'
print('| %s | %s | %d | %s | %.3f | %.3f | %.3f | %.2f | %.2f |' % (name, signal, a['sample_rays'], trials, ea, eb, ea / eb,
      sa, sb))
PY
  done
done
