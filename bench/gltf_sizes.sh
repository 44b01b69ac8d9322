#!/usr/bin/env bash
# glTF asset sizes (issue 14): each scene baked with the default settings into the PLY asset
# and the four glTF variants (float, --quantize, --compress, both), each checked by `inspect`;
# prints a Markdown table of file sizes and the seconds the write took (seconds_write in the
# bake's report). Quantization's error is measured by eval against one fixed reference.
# usage: bash bench/gltf_sizes.sh BUILD_DIR SCENES_DIR OUT_DIR "scene.ply scene.obj ..."
set -euo pipefail
build=$1 scenes=$2 out=$3
mkdir -p "$out"
echo "| scene | vertices | PLY | GLB | GLB --quantize | GLB --compress | GLB --quantize --compress | write s (PLY / GLB / both) | eval RMS % (PLY / quantized) |"
echo "|---|---:|---:|---:|---:|---:|---:|---|---|"
for scene in $4; do
  name=${scene%.*}
  declare -A size seconds
  for variant in ply glb q c qc; do
    case $variant in
      ply) file="$out/$name.ply" flags=() ;;
      glb) file="$out/$name.glb" flags=() ;;
      q) file="$out/$name.q.glb" flags=(--quantize) ;;
      c) file="$out/$name.c.glb" flags=(--compress) ;;
      qc) file="$out/$name.qc.glb" flags=(--quantize --compress) ;;
    esac
    "$build/prtsub" bake "$scenes/$scene" -o "$file" "${flags[@]}" --report "$out/$name.$variant.json" > /dev/null
    "$build/prtsub" inspect "$file" > /dev/null
    size[$variant]=$(stat -c %s "$file")
    seconds[$variant]=$(python3 -c "import json,sys; print('%.3f' % json.load(open(sys.argv[1]))['seconds_write'])" "$out/$name.$variant.json")
  done
  vertices=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['vertices_out'])" "$out/$name.ply.json")
  e_ply=$("$build/prtsub" eval "$out/$name.ply" --source "$scenes/$scene" --rays 2048 --report "$out/$name.eval_ply.json" > /dev/null &&
          python3 -c "import json,sys; print('%.4f' % json.load(open(sys.argv[1]))['rms_percent'])" "$out/$name.eval_ply.json")
  e_q=$("$build/prtsub" eval "$out/$name.q.glb" --source "$scenes/$scene" --rays 2048 --report "$out/$name.eval_q.json" > /dev/null &&
        python3 -c "import json,sys; print('%.4f' % json.load(open(sys.argv[1]))['rms_percent'])" "$out/$name.eval_q.json")
  mib() { python3 -c "import sys; print('%.2f MiB (%.2f)' % (int(sys.argv[1]) / 2**20, int(sys.argv[1]) / int(sys.argv[2])))" "$1" "${size[ply]}"; }
  echo "| $name | $vertices | $(mib ${size[ply]}) | $(mib ${size[glb]}) | $(mib ${size[q]}) | $(mib ${size[c]}) | $(mib ${size[qc]}) | ${seconds[ply]} / ${seconds[glb]} / ${seconds[qc]} | $e_ply / $e_q |"
  unset size seconds
done
