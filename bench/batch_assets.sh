#!/usr/bin/env bash
# A batch of small generated props (issue 17, point 2): N meshes of 12-300 triangles (boxes on a
# ground plate, seeded), baked with the default settings by one batch process and by one process
# each, in the same run; prints wall and CPU seconds of both (/usr/bin/time) and checks that the
# two give byte-identical assets.
# usage: bash bench/batch_assets.sh BUILD_DIR OUT_DIR [N]
set -euo pipefail
build=$1 out=$2 n=${3:-1000}
rm -rf "$out" && mkdir -p "$out/props" "$out/batch" "$out/each"
python3 - "$out/props" "$n" <<'PY'
import os, random, sys
out, n = sys.argv[1], int(sys.argv[2])
rng = random.Random(17)
for i in range(n):
    v, f = [(-2, 0, -2), (2, 0, -2), (2, 0, 2), (-2, 0, 2)], [(1, 3, 2), (1, 4, 3)]
    for _ in range(rng.randint(1, 25)):  # boxes: 12 triangles each
        x, z, s, h = rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5), rng.uniform(0.1, 0.5), rng.uniform(0.1, 1.2)
        b = len(v)
        v += [(x + dx * s, y, z + dz * s) for dx in (-1, 1) for y in (0.001, h) for dz in (-1, 1)]
        for a, c, d, e in ((0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)):
            f += [(b + a + 1, b + c + 1, b + d + 1), (b + a + 1, b + d + 1, b + e + 1)]
    with open(os.path.join(out, "prop_%04d.obj" % i), "w") as o:
        o.write("".join("v %.6f %.6f %.6f\n" % p for p in v) + "".join("f %d %d %d\n" % t for t in f))
PY
tris=$(cat "$out"/props/*.obj | grep -c '^f ')
/usr/bin/time -f "%e %U %S %M" -o "$out/batch.time" "$build/prtsub" bake "$out/props" -o "$out/batch" > /dev/null
/usr/bin/time -f "%e %U %S %M" -o "$out/each.time" bash -c 'for f in "$1"/props/*.obj; do "$2/prtsub" bake "$f" -o "$1/each/$(basename "${f%.obj}").ply" > /dev/null; done' _ "$out" "$build"
same=0
for f in "$out"/each/*.ply; do cmp -s "$f" "$out/batch/$(basename "$f")" && same=$((same + 1)); done
read -r bw bu bs bm < "$out/batch.time"
read -r ew eu es em < "$out/each.time"
echo "| how | assets | triangles | wall s | CPU s (user + sys) | peak MiB |"
echo "|---|---:|---:|---:|---:|---:|"
echo "| one batch process | $n | $tris | $bw | $(python3 -c "print('%.2f' % ($bu + $bs))") | $((bm / 1024)) |"
echo "| one process each | $n | $tris | $ew | $(python3 -c "print('%.2f' % ($eu + $es))") | $((em / 1024)) (largest) |"
echo "byte-identical assets: $same of $n"
