#!/usr/bin/env bash
# The viewer's browser test (ctest viewer_browser): the checked-in bundle is what viewer/src
# builds to; then pages `prtsub view` writes for the bundled example, loaded in headless chromium
# at fixed views, match `prtsub render`'s frames of the same asset (viewer/test/viewer_test.mjs),
# under every kind of light, an environment map, a rotated light and the automatic camera; the
# AO view of an AO asset; the error view loads; dragging, the wheel and the panel redraw it
# (interaction_test.mjs); and compare's report renders with its plots, frames and embedded viewer. Exit 77 (skip) without chromium, Node.js or
# `npm ci` in viewer/, except in CI, where that is a failure.
#   bash viewer/test/run.sh PRTSUB_BINARY WORK_DIR
set -euo pipefail
prtsub=$1 work=$2
here=$(cd "$(dirname "$0")/.." && pwd)
mesh="$here/../examples/spot/spot_control_mesh.obj"
if ! command -v node >/dev/null || [ ! -x "${CHROMIUM:-/usr/bin/chromium}" ] || [ ! -d "$here/node_modules/playwright-core" ] || [ ! -d "$here/node_modules/pngjs" ]; then
  echo "viewer test: needs Node.js, Debian's chromium and 'npm ci' in $here (.ci/deps installs them)"
  [ -n "${CI:-}" ] && exit 1
  exit 77
fi
rm -rf "$work" && mkdir -p "$work"
cd "$here"
node build.mjs "$work/viewer.js"
if ! cmp -s "$work/viewer.js" dist/viewer.js; then
  echo "FAIL viewer/dist/viewer.js is not what viewer/src builds to: run 'npm ci && node build.mjs' in viewer/"
  exit 1
fi
"$prtsub" bake "$mesh" -o "$work/spot.glb" --quantize --compress > /dev/null
"$prtsub" bake "$mesh" -o "$work/spot_ao.glb" --signal ao > /dev/null
"$prtsub" view "$work/spot.glb" -o "$work/spot.html" --source "$mesh" --rays 512 > /dev/null
"$prtsub" view "$work/spot_ao.glb" -o "$work/spot_ao.html" > /dev/null
size=320,240
camera=eye=2,1.5,3:target=0,0.3,0:up=0,1,0:fov=40
failed=0
check() {  # NAME PAGE REFERENCE QUERY
  echo "== $1"
  node test/viewer_test.mjs "$2" "$3" "size=$size&ui=0&$4" 50 "$work/$1.png" || failed=1
}
i=0
for spec in "sun:0.5,1,0.6,2|" "sky|" "random:3|" "sh:1,0.5,-0.3,0.2,0.1|" "const:0.8,0.9,1|" "sky|x,30" "env:$here/assets/studio.png|"; do
  light=${spec%%|*} rotate=${spec#*|}
  args=(--light "$light") query="light=${light}"
  [ -n "$rotate" ] && args+=(--light-rotate "$rotate") && query+="&light-rotate=$rotate"
  [[ $light == env:* ]] && query="light=env"
  i=$((i + 1))
  "$prtsub" render "$work/spot.glb" "${args[@]}" --camera "$camera" --size "$size" -o "$work/ref$i.png" > /dev/null
  check "light$i" "$work/spot.html" "$work/ref$i.png" "$query&camera=$camera"
done
"$prtsub" render "$work/spot.glb" --light sky --size "$size" -o "$work/ref_auto.png" > /dev/null
check auto_camera "$work/spot.html" "$work/ref_auto.png" "light=sky"
"$prtsub" render "$work/spot_ao.glb" --light const:1 --albedo 1 --camera "$camera" --size "$size" -o "$work/ref_ao.png" > /dev/null
check ao_view "$work/spot_ao.html" "$work/ref_ao.png" "view=ao&camera=$camera"
check error_view "$work/spot.html" - "view=error&light=sky&camera=$camera"
# Spherical-Gaussian lobes, z-up so the glTF turns their axes: the page projects each light onto
# the lobes as render does (through SH of the asset's shading order), under every kind of light.
"$prtsub" bake "$mesh" -o "$work/spot_sg.glb" --basis sg:12 --up z --rays 128 > /dev/null
"$prtsub" view "$work/spot_sg.glb" -o "$work/spot_sg.html" --source "$mesh" --rays 64 > /dev/null
i=0
for light in "sun:0.5,1,0.6,2" sky random:3 "env:$here/assets/studio.png"; do
  query="light=${light}"
  [[ $light == env:* ]] && query="light=env"
  i=$((i + 1))
  "$prtsub" render "$work/spot_sg.glb" --light "$light" --camera "$camera" --size "$size" -o "$work/ref_sg$i.png" > /dev/null
  check "sg_light$i" "$work/spot_sg.html" "$work/ref_sg$i.png" "$query&camera=$camera"
done
check sg_error_view "$work/spot_sg.html" - "view=error&light=sky&camera=$camera"
# The AO view of lobes: t0 = g_0 y_0 Σ c_k, what render shows under constant light 1 at albedo 1.
"$prtsub" render "$work/spot_sg.glb" --light const:1 --albedo 1 --camera "$camera" --size "$size" -o "$work/ref_sg_ao.png" > /dev/null
check sg_ao_view "$work/spot_sg.html" "$work/ref_sg_ao.png" "view=ao&camera=$camera"
# The mouse and the panel: drags, the wheel, the light menu and the views redraw and change it.
echo "== interaction"
node test/interaction_test.mjs "$work/spot.html" || failed=1
# compare's report: plots, frames, heat maps and the embedded viewer render (report_test.mjs).
echo "== report"
"$prtsub" compare "$mesh" --budgets 1488 --max-levels 1 --estimates root --frame-size 240,180 --frame-rays 64 --eval-points 2000 \
  --rays 64 -o "$work/compare" > /dev/null
node test/report_test.mjs "$work/compare/report.html" "$work/report.png" || failed=1
[ $failed -eq 0 ] && echo "viewer test: passed" || echo "viewer test: FAILED"
exit $failed
