#!/usr/bin/env bash
# Embree's own viewer (Debian's embree-tools) with and without librebraid_preload.so, on the
# shared glTF scenes exported with `rebraid export --embree-xml`, instanced
# (`--instancing geometry`, one Embree instance per instance over shared meshes).
# Usage: bench/preload_viewer.sh [BUILD_DIR [SCENE_NAME...]]  (defaults: build, every shared
# scene but the animated ones). Prints one line per scene: the viewer's
# BENCHMARK_RENDER_MRAYPS_AVG (median of RUNS runs each, alternating), the speedup, rebraid's
# build time (the preload's log) and the time the viewer took to create and commit its Embree
# objects (its --verbose 1 timeline). The numbers are indicative: run it on an idle machine.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
shift || true
scenes=("$@")
if [ ${#scenes[@]} -eq 0 ]; then
    scenes=(brainstem cg57_cruiser two_cylinder_engine bunny armadillo chinese_dragon fzk_haus)
fi
runs=${RUNS:-3}
preload="$PWD/$build/lib/librebraid_preload.so"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
mrayps() { grep "^BENCHMARK_RENDER_MRAYPS_AVG " | awk '{print $2}'; }

printf "%-22s %12s %12s %8s %14s %14s\n" scene embree_mrays preload_mrays speedup \
    rebraid_build_ms embree_objects_ms
for name in "${scenes[@]}"; do
    "$build/examples/rebraid" export "../shared/scenes/$name.glb" --embree-xml "$work/$name" \
        >/dev/null
    viewer=(viewer -i "$work/$name/scene.xml" -c "$work/$name/camera.cfg"
            --instancing geometry --size 640 360 --benchmark 2 8)
    embree=() with=()
    for _ in $(seq "$runs"); do
        embree+=("$("${viewer[@]}" 2>/dev/null | mrayps)")
        with+=("$(LD_PRELOAD="$preload" "${viewer[@]}" 2>/dev/null | mrayps)")
    done
    embree_median=$(printf "%s\n" "${embree[@]}" | median)
    with_median=$(printf "%s\n" "${with[@]}" | median)
    build_ms=$(LD_PRELOAD="$preload" REBRAID_PRELOAD_LOG=1 "${viewer[@]:0:7}" --size 64 36 \
        -o "$work/image.ppm" 2>&1 >/dev/null | sed -n 's/.*(build \([0-9.]*\) ms.*/\1/p' | head -1)
    objects_ms=$("${viewer[@]:0:7}" --size 64 36 -o "$work/image.ppm" --verbose 1 2>/dev/null |
        awk '/creating ISPC compatible scene done/ {start=$2}
             /creating Embree objects done/ {sub(/s,/, "", $2); sub(/s,/, "", start);
                                              printf "%.1f", 1000 * ($2 - start)}' | tr -d '[')
    printf "%-22s %12s %12s %8.2f %14s %14s\n" "$name" "$embree_median" "$with_median" \
        "$(echo "$with_median / $embree_median" | bc -l)" "${build_ms:-?}" "${objects_ms:-?}"
done
