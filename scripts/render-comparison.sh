#!/usr/bin/env bash
# The README's rendering table: `rdbvh render` through `--structure global`, `lights` and `thesis`
# on the built-in room and four scenes of ../shared/scenes, Sponza twice (a point light, and a
# quad light 100 units a side), at 512 x 512, 16 samples, 3 bounces and the same seed: one
# markdown row per scene and structure, each ratio against `global` of the same run. Each row
# checks that its PNG is byte-identical to `global`'s. The three structures run in turn REPEATS
# times (default 3), each repeat starting with the next one; every time is the best of its
# repeats, so that a shared machine's load hits all three alike. In brackets after frame + build,
# the median over the repeats of each repeat's ratio to global's in that repeat.
# Usage: [REPEATS=N] bash scripts/render-comparison.sh [SCENES_DIR]
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
cat >"$work/sponza-quad.toml" <<'TOML'
[[light]]
kind = "quad"
corner = [-50.0, 800.0, -50.0]
edge1 = [100.0, 0.0, 0.0]
edge2 = [0.0, 0.0, 100.0]
radiance = [40.0, 38.0, 34.0]
TOML
cat >"$work/sibenik.toml" <<'TOML'
[[light]]
kind = "point"
position = [-200.0, 550.0, 100.0]
intensity = [300000.0, 280000.0, 250000.0]

[[light]]
kind = "spot"
position = [600.0, 650.0, 100.0]
direction = [0.0, -1.0, 0.0]
angle_deg = 40.0
intensity = [600000.0, 600000.0, 600000.0]
TOML
cat >"$work/bunny.toml" <<'TOML'
[[light]]
kind = "quad"
corner = [-0.1, 0.25, -0.1]
edge1 = [0.2, 0.0, 0.0]
edge2 = [0.0, 0.0, 0.2]
radiance = [8.0, 8.0, 8.0]
TOML

row() {
    local name=$1
    shift
    rm -f "$work"/*.json
    local order=(global lights thesis)
    for r in $(seq "${REPEATS:-3}"); do
        # Each repeat starts with another structure, so that none always runs first (after the
        # previous scene) or last.
        for k in 0 1 2; do
            local s=${order[$(((r + k) % 3))]}
            "$bin" render "$@" --structure "$s" --out "$work/$s.png" --json | tail -n 1 >"$work/$s.$r.json"
        done
    done
    local same_l=no same_t=no
    cmp -s "$work/global.png" "$work/lights.png" && same_l=yes
    cmp -s "$work/global.png" "$work/thesis.png" && same_t=yes
    python3 - "$name" "$same_l" "$same_t" "$work" <<'PY'
import glob, json, sys
name, same_l, same_t, work = sys.argv[1:]
def repeats(s):
    return {f.split(".")[-2]: json.load(open(f)) for f in glob.glob(f"{work}/{s}.*.json")}
def best(s):
    by_repeat = repeats(s)
    runs = list(by_repeat.values())
    j = dict(runs[0])
    for key in ("shadow_ms", "render_ms", "build_ms"):
        j[key] = min(r[key] for r in runs)
    j["total_ms"] = min(r["render_ms"] + r["build_ms"] for r in runs)
    # The light buffers, the eye buffer and the choice among them, apart from the global BVH and
    # the pilot.
    j["buffers_x"] = min((r["build_ms"] - r["global_build_ms"] - r["pilot_ms"]) / r["global_build_ms"]
                         for r in runs)
    # Each repeat's frame + build over global's in the same repeat (the three ran back to
    # back), the median over the repeats: steadier than a ratio of bests when the machine's
    # speed drifts between repeats.
    g_by_repeat = repeats("global")
    ratios = sorted((r["render_ms"] + r["build_ms"])
                    / (g_by_repeat[k]["render_ms"] + g_by_repeat[k]["build_ms"])
                    for k, r in by_repeat.items())
    j["paired_x"] = ratios[len(ratios) // 2] if len(ratios) % 2 else \
        (ratios[len(ratios) // 2 - 1] + ratios[len(ratios) // 2]) / 2
    return j
g, l, t = (best(s) for s in ("global", "lights", "thesis"))
def tests(j):
    n = j["shadow_rays"]
    return (j["shadow_node_tests"] + j["shadow_triangle_tests"]) / n, \
        f"{j['shadow_node_tests'] / n:.2f} + {j['shadow_triangle_tests'] / n:.2f}"
def parts(j):
    if j["structure"] == "lights":
        eye = {True: "kept", False: "dropped"}[j["eye_buffer"]] if j["eye_buffer_tests"] else "not built"
        return (f"{j['light_buffers']} kept, {j['light_buffers_dropped']} dropped; "
                f"buffers {j['buffers_x']:.2f}x global; eye buffer {eye}"
                + (f" ({j['eye_buffer_tests']:.2f}x the camera rays' tests)" if j["eye_buffer_tests"] else ""))
    if j["structure"] == "thesis":
        return f"{j['influence_areas']} areas"
    return ""
gt = tests(g)[0]
for j, same in ((g, "-"), (l, same_l), (t, same_t)):
    total, split = tests(j)
    print(f"| {name} | {j['structure']} | {g['triangles']:,} | {g['shadow_rays']:,} "
          f"| {split} (**{total / gt:.2f}x**) "
          f"| {j['shadow_ms']:.0f} ms (**{j['shadow_ms'] / g['shadow_ms']:.2f}x**) "
          f"| {j['render_ms']:.0f} ms ({j['render_ms'] / g['render_ms']:.2f}x) "
          f"| {j['build_ms']:.0f} ms ({j['build_ms'] / g['build_ms']:.2f}x) {parts(j)} "
          f"| {j['total_ms'] / g['total_ms']:.2f}x ({j['paired_x']:.2f}x) | {same} |")
PY
}

size=(--width 512 --height 512 --spp 16 --max-bounces 3)
echo "| scene, light | structure | triangles | shadow rays | nodes + triangles a shadow ray | shadow_ms (1 thread) | frame | build | frame + build (paired) | same PNG |"
echo "|---|---|---|---|---|---|---|---|---|---|"
row "room, emissive quad" builtin:room --eye 5,5,0.3 --look-at 5,4,10 --fov 75 "${size[@]}"
if [ -d "$scenes" ]; then
    row "Cornell box, emissive quad" "$scenes/cornell_box.obj" "${size[@]}"
    row "Sponza, point light" "$scenes/sponza_crytek.obj" --lights "$work/sponza.toml" \
        --eye 1100,200,-50 --look-at -900,400,0 --fov 60 "${size[@]}"
    row "Sponza, quad light" "$scenes/sponza_crytek.obj" --lights "$work/sponza-quad.toml" \
        --eye 1100,200,-50 --look-at -900,400,0 --fov 60 "${size[@]}"
    row "Sibenik, point + spot + 1,719 emissive window triangles" "$scenes/sibenik.obj" \
        --lights "$work/sibenik.toml" --eye 1200,300,100 --look-at -1000,300,100 --fov 70 "${size[@]}"
    row "bunny, quad light" "$scenes/bunny.obj" --lights "$work/bunny.toml" "${size[@]}"
else
    echo "note: $scenes not found: only the built-in room" >&2
fi
