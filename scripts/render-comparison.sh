#!/usr/bin/env bash
# The README's rendering table: `rdbvh render` through `--structure global` and `lights` on the
# built-in room and three scenes of ../shared/scenes, one markdown row per scene. Each row checks
# that the two PNGs are byte-identical. Usage: bash scripts/render-comparison.sh [SCENES_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
scenes=${1:-../shared/scenes}
cargo build --release -q -p rdbvh
bin=target/release/rdbvh
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cat >"$work/sponza.toml" <<'TOML'
[[light]]
kind = "point"
position = [0.0, 800.0, 0.0]
intensity = [400000.0, 380000.0, 340000.0]
TOML

row() {
    local name=$1
    shift
    for s in global lights; do
        "$bin" render "$@" --structure "$s" --out "$work/$s.png" --json | tail -n 1 >"$work/$s.json"
    done
    local same=no
    cmp -s "$work/global.png" "$work/lights.png" && same=yes
    python3 - "$name" "$same" "$work" <<'PY'
import json, sys
name, same, work = sys.argv[1:]
g, l = (json.load(open(f"{work}/{s}.json")) for s in ("global", "lights"))
def tests(j):
    n = j["shadow_rays"]
    return f"{j['shadow_node_tests'] / n:.2f} + {j['shadow_triangle_tests'] / n:.2f}"
print(f"| {name} | {g['triangles']:,} | {g['shadow_rays']:,} | {tests(g)} → {tests(l)} "
      f"| {g['shadow_ms']:.0f} → {l['shadow_ms']:.0f} ms, **{l['shadow_ms'] / g['shadow_ms']:.2f}x** "
      f"| {l['render_ms'] / g['render_ms']:.2f}x | {g['build_ms']:.0f} → {l['build_ms']:.0f} ms "
      f"({l['light_buffers']} kept, {l['light_buffers_dropped']} dropped) | {same} |")
PY
}

size=(--width 512 --height 512 --spp 8)
echo "| scene, light | triangles | shadow rays | nodes + triangles a shadow ray | shadow_ms (1 thread) | frame time | build (buffers) | same PNG |"
echo "|---|---|---|---|---|---|---|---|"
row "room, emissive quad" builtin:room --eye 5,5,0.3 --look-at 5,4,10 --fov 75 "${size[@]}"
if [ -d "$scenes" ]; then
    row "Cornell box, emissive quad" "$scenes/cornell_box.obj" "${size[@]}"
    row "Sponza, point light" "$scenes/sponza_crytek.obj" --lights "$work/sponza.toml" \
        --eye 1100,200,-50 --look-at -900,400,0 --fov 60 "${size[@]}"
    row "Sibenik, 1,719 emissive window triangles" "$scenes/sibenik.obj" \
        --eye 1200,300,100 --look-at -1000,300,100 --fov 70 "${size[@]}"
else
    echo "note: $scenes not found: only the built-in room" >&2
fi
