#!/usr/bin/env bash
# Remakes the compressed and instanced copies of shared scenes that
# tests/io/gltf_compressed_scenes_test.cpp compares with the originals. Needs the glTF Transform
# command line (npm install -g @gltf-transform/cli; these were made with version 4.5.1) and
# the shared scenes beside the repository (../shared/scenes). Not part of the build or CI:
# the files it writes are committed.
set -euo pipefail
cd "$(dirname "$0")"
scenes=../../../../shared/scenes
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Positions quantized to normalized shorts (KHR_mesh_quantization), then meshopt-compressed.
gltf-transform meshopt "$scenes/chinese_dragon.glb" chinese_dragon_meshopt.glb
# Draco with its default 14-bit position quantization.
gltf-transform draco "$scenes/chinese_dragon.glb" chinese_dragon_draco.glb
# Reused meshes turned into EXT_mesh_gpu_instancing nodes, then quantized and meshopt-compressed
# (the instanced file alone is 780 KB).
gltf-transform instance "$scenes/fzk_haus.glb" "$work/fzk_haus_instanced.glb"
gltf-transform meshopt "$work/fzk_haus_instanced.glb" fzk_haus_instanced_meshopt.glb
# A small textured grid (its texture coordinates compressed along with the positions).
python3 make_textured_grid.py textured_grid.glb
gltf-transform draco textured_grid.glb textured_grid_draco.glb
gltf-transform meshopt textured_grid.glb textured_grid_meshopt.glb

# Fuzz seeds for the same paths (tests/fuzz/make_gltf_seeds.py keeps them): copies of shrunk
# shared-scene seeds, small enough for fuzz.sh's -max_len.
seeds=../../fuzz/seeds/gltf_loader
gltf-transform instance --min 2 "$seeds/scene_two_cylinder_engine.glb" \
    "$seeds/tool_two_cylinder_engine_instanced.glb"
gltf-transform meshopt "$seeds/tool_two_cylinder_engine_instanced.glb" \
    "$seeds/tool_two_cylinder_engine_instanced_meshopt.glb"
gltf-transform draco "$seeds/scene_fzk_haus.glb" "$seeds/tool_fzk_haus_draco.glb"
gltf-transform quantize "$seeds/scene_fzk_haus.glb" "$seeds/tool_fzk_haus_quantized.glb"
cp textured_grid_draco.glb "$seeds/tool_textured_grid_draco.glb"
cp textured_grid_meshopt.glb "$seeds/tool_textured_grid_meshopt.glb"
