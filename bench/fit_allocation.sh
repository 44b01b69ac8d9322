#!/usr/bin/env bash
# Where the fit's samples go (issue 11, point 2): every face by area (the paper's) against the
# pilot pass, which samples only faces where interpolating the vertex values fails. Same vertex
# rays, same fixed reference (2048 rays at the eval command's seeded points) for both.
# usage: bash bench/fit_allocation.sh BUILD_DIR SCENES_DIR OUT_DIR SCENE... [-- extra eval options]
set -euo pipefail
build=$1 scenes=$2 out=$3
shift 3
list=() extra=()
while [ $# -gt 0 ]; do [ "$1" = "--" ] && { shift; extra=("$@"); break; }; list+=("$1"); shift; done
mkdir -p "$out"
echo "| scene | signal | triangles | E_point | area: samples | area: sample s | area: E_default | pilot: sampled faces | pilot: samples (+ pilot) | pilot: sample s (pilot incl.) | pilot: E_default |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for scene in "${list[@]}"; do
  name=${scene%.*}
  for signal in transfer ao; do
    for a in area pilot; do
      "$build/prtsub" eval --fits "$scenes/$scene" --signal "$signal" --reference-rays 2048 --sample-allocation "$a" \
        ${extra[@]+"${extra[@]}"} --report "$out/${name}_${signal}_$a.json" > /dev/null
    done
    python3 - "$out/${name}_${signal}_area.json" "$out/${name}_${signal}_pilot.json" <<'PY'
import json, sys
a, p = (json.load(open(f)) for f in sys.argv[1:3])
print('| %s | %s | %d | %.3f | %d | %.2f | %.3f | %d (%.0f%%) | %d (+ %d) | %.2f | %.3f |' % (
    a['input'].split('/')[-1].rsplit('.', 1)[0], a['signal'], a['triangles'], a['e_point_percent'], a['samples'],
    a['seconds_rays_samples'], a['e_default_percent'], p['sampled_faces'], 100.0 * p['sampled_faces'] / p['triangles'],
    p['samples'], p['pilot_samples'], p['seconds_rays_samples'], p['e_default_percent']))
PY
  done
done
