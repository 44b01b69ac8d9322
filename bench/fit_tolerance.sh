#!/usr/bin/env bash
# How exactly the fit's system needs solving (issue 11, point 4): each scene baked with every
# vertex an unknown (--sample-allocation area, the fit's largest system), by conjugate gradients
# stopped at each tolerance and by CHOLMOD's factorisation. Per row: CG iterations, the fit's
# seconds, eval's error against one fixed reference, and the largest difference of any stored
# value from the factorisation's asset, over the largest value (assets store float32: 6e-8).
# usage: bash bench/fit_tolerance.sh BUILD_DIR SCENES_DIR OUT_DIR "SCENE..." "TOLERANCE..." [BAKE OPTIONS...]
set -euo pipefail
build=$1 scenes=$2 out=$3 scene_list=$4 tolerances=$5
shift 5
mkdir -p "$out"
echo "| scene | solve | CG iterations | fit s (assemble + solve) | E % | max value difference / max value |"
echo "|---|---|---:|---:|---:|---:|"
for scene in $scene_list; do
  name=${scene%.*}
  for t in cholmod $tolerances; do
    stem="$out/${name}_$t"
    if [ "$t" = cholmod ]; then solve=(--solver cholmod); else solve=(--cg-tolerance "$t"); fi
    "$build/prtsub" bake "$scenes/$scene" --sample-allocation area "${solve[@]}" "$@" -o "$stem.ply" --report "$stem.bake.json" > /dev/null
    "$build/prtsub" eval "$stem.ply" --source "$scenes/$scene" --rays 2048 --report "$stem.eval.json" > /dev/null
    /usr/bin/python3 - "$stem" "$out/${name}_cholmod.ply" "$name" "$t" <<'PY'
import json, sys
import numpy as np

def values(path):
    """The asset's vertex values (t0..tK or ao) as stored: binary little-endian float32 rows."""
    with open(path, 'rb') as f:
        props, element, n = [], None, 0
        while True:
            line = f.readline().decode().split()
            if line[:1] == ['element']: element = line[1]; n = int(line[2]) if element == 'vertex' else n
            elif line[:1] == ['property'] and element == 'vertex': props.append(line[2])
            elif line[:1] == ['end_header']: break
        data = np.frombuffer(f.read(4 * n * len(props)), dtype='<f4').reshape(n, len(props))
    return data[:, [i for i, p in enumerate(props) if p == 'ao' or (p[:1] == 't' and p[1:].isdigit())]]

stem, reference, name, t = sys.argv[1:]
b, e = json.load(open(stem + '.bake.json')), json.load(open(stem + '.eval.json'))
x, r = values(stem + '.ply'), values(reference)
print('| %s | %s | %d | %.3f | %.4f | %.1e |' % (name, t if t == 'cholmod' else 'CG to ' + t, b['fit_cg_iterations'],
      b['seconds_fit_assemble'] + b['seconds_fit_factor'] + b['seconds_fit_solve'], e['rms_percent'],
      np.abs(x - r).max() / np.abs(r).max()))
PY
  done
  rm -f "$out/${name}"_*.ply
done
