#!/usr/bin/env bash
# Budget policy: exact SAH of the paper's rules and of the default rules for budget
# factors 1..64, the per-primitive rule and the budget search, one `rebraid bench` per scene
# (16 rays: the SAH is what counts here). Writes OUT_DIR/SCENE.json; bench/budget_table.py
# OUT_DIR prints the tables of bench/RESULTS.md (budget policy).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/eval/budget}
binary=./build/examples/rebraid
accels=flat,twolevel
for factor in 1 2 4 8 16 32 64; do
    accels=$accels,rebraid:opening=extent:bref-bounds=box:budget-factor=$factor,rebraid:budget-factor=$factor
done
accels=$accels,rebraid:opening=extent:bref-bounds=box:budget-rule=primitives,rebraid:budget-rule=primitives
accels=$accels,rebraid:budget-doublings=4
mkdir -p "$out"
for scene in default ../shared/scenes/{cg57_cruiser,fzk_haus,two_cylinder_engine,brainstem,motion_capture_rom}.glb \
    out/scenes/{crown,city,trees2k,powerplant}.glb; do
    "$binary" bench "$scene" --accel "$accels" --rays 16 --repetitions 1 --json > "$out/$(basename "$scene" .glb).json"
done
