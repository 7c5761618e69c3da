#!/usr/bin/env python3
"""Writes the seeds of fuzz_gltf_loader into tests/fuzz/seeds/gltf_loader/ (docs/testing.md).

    python3 tests/fuzz/make_gltf_seeds.py [SHARED_SCENES_DIR]

Three families, every one small (the largest is well under fuzz.sh's -max_len):

- scene_*: each shared scene (../shared/scenes/*.glb) shrunk by shrink_scene(): at most a few
  meshes of a few triangles, few keyframes, no names, materials, normals or texture
  coordinates, but the same kinds of structure (node hierarchy and transforms, mesh reuse,
  index types, skins with JOINTS_0 / WEIGHTS_0 and inverse bind matrices, morph targets,
  animations and their interpolations).
- ok_* and anim_*: small valid files, like the loader tests' and the animation tests' (every
  topology, strides and offsets, transforms, default scenes, skins, morph targets, STEP /
  LINEAR / CUBICSPLINE channels).
- ok_gpu_*, ok_quantized_*, bad_gpu_*: EXT_mesh_gpu_instancing (with a zero-scale, hidden
  instance) and KHR_mesh_quantization files, valid and broken.
- bad_*: every input the loader rejects (tests/io/gltf_scene_test.cpp,
  tests/cli/bad_input_test.cpp, docs/testing.md "Bad input"), as a small file.

Whole documents are written both as .gltf (buffer in a data: URI) and as .glb (BIN chunk), so
both containers are explored from the start; container damage (truncated GLB, a header
claiming 4 GiB, broken JSON) is written in its own container only. Hand-written .gltf seeds
in the folder (two_meshes.gltf) are kept and get a .glb twin; so are the tool_*.glb seeds,
Draco, meshopt, quantized and instanced copies of scene_*.glb seeds made by the glTF Transform command
line (tests/io/assets/make_assets.sh). Only the standard library is
used; the output is deterministic, so running the script again changes nothing.
"""
import base64
import copy
import json
import math
import os
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "seeds", "gltf_loader")
DEFAULT_SHARED = os.path.normpath(os.path.join(HERE, "..", "..", "..", "shared", "scenes"))

UNSIGNED_BYTE, UNSIGNED_SHORT, UNSIGNED_INT, FLOAT, BYTE, SHORT = 5121, 5123, 5125, 5126, 5120, 5122
COMPONENT = {BYTE: ("b", 1), UNSIGNED_BYTE: ("B", 1), SHORT: ("h", 2), UNSIGNED_SHORT: ("H", 2),
             UNSIGNED_INT: ("I", 4), FLOAT: ("f", 4)}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
DATA_URI = "data:application/octet-stream;base64,"
# The largest seed must fit fuzz.sh's -max_len, or libFuzzer truncates it on loading.
SEED_BUDGET = 12 * 1024


# ---- A small glTF writer (the counterpart of tests/support/gltf_test_files.h) ---------------

class Doc:
    def __init__(self):
        self.json = {"asset": {"version": "2.0"}}
        self.bin = bytearray()

    def append(self, array, item):
        self.json.setdefault(array, []).append(item)
        return len(self.json[array]) - 1

    def add_view(self, data, stride=0):
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if stride:
            view["byteStride"] = stride
        self.bin += data
        self.bin += b"\0" * (-len(self.bin) % 4)
        return self.append("bufferViews", view)

    def add_accessor(self, view, component_type, count, type_, byte_offset=0, **extra):
        accessor = {"bufferView": view, "componentType": component_type, "count": count,
                    "type": type_}
        if byte_offset:
            accessor["byteOffset"] = byte_offset
        accessor.update(extra)
        return self.append("accessors", accessor)

    def add_values(self, values, component_type, type_, **extra):
        fmt, _ = COMPONENT[component_type]
        data = struct.pack("<%d%s" % (len(values), fmt), *values)
        view = self.add_view(data)
        return self.add_accessor(view, component_type, len(values) // WIDTH[type_], type_, **extra)

    def add_positions(self, points):
        flat = [c for p in points for c in p]
        finite = [p for p in points if all(math.isfinite(c) for c in p)] or [(0, 0, 0)]
        lo = [min(p[i] for p in finite) for i in range(3)]
        hi = [max(p[i] for p in finite) for i in range(3)]
        return self.add_values(flat, FLOAT, "VEC3", min=lo, max=hi)

    def add_indices(self, indices, component_type=UNSIGNED_INT):
        return self.add_values(indices, component_type, "SCALAR")

    def add_mesh(self, primitives, name=None):
        mesh = {"primitives": primitives}
        if name:
            mesh["name"] = name
        return self.append("meshes", mesh)

    def add_node(self, node):
        return self.append("nodes", node)

    def add_scene(self, roots):
        return self.append("scenes", {"nodes": roots})

    def finished(self, uri):
        out = copy.deepcopy(self.json)
        if self.bin and "buffers" not in out:
            out["buffers"] = [{"byteLength": len(self.bin)}]
            if uri is not None:
                out["buffers"][0]["uri"] = uri
        return out

    def gltf_bytes(self):
        uri = DATA_URI + base64.b64encode(bytes(self.bin)).decode() if self.bin else None
        return dump(self.finished(uri)).encode()

    def glb_bytes(self):
        return glb(dump(self.finished(None)).encode(), bytes(self.bin))


def primitive(position, indices=-1, mode=4):
    p = {"attributes": {"POSITION": position}, "mode": mode}
    if indices >= 0:
        p["indices"] = indices
    return p


def dump(doc):
    return json.dumps(doc, separators=(",", ":"), allow_nan=False)


def glb(json_bytes, bin_bytes=b""):
    json_bytes += b" " * (-len(json_bytes) % 4)
    chunks = struct.pack("<II", len(json_bytes), 0x4E4F534A) + json_bytes
    if bin_bytes:
        bin_bytes += b"\0" * (-len(bin_bytes) % 4)
        chunks += struct.pack("<II", len(bin_bytes), 0x004E4942) + bin_bytes
    return b"glTF" + struct.pack("<II", 2, 12 + len(chunks)) + chunks


SEEDS = {}


def seed(name, data):
    assert name not in SEEDS, name
    SEEDS[name] = data


def seed_doc(name, doc):
    """A whole document, in both containers."""
    seed(name + ".gltf", doc.gltf_bytes())
    seed(name + ".glb", doc.glb_bytes())


# ---- Shared scenes, shrunk ----------------------------------------------------------------

def read_glb(path):
    data = open(path, "rb").read()
    assert data[:4] == b"glTF", path
    json_length = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + json_length])
    bin_start = 20 + json_length
    bin_data = b""
    if bin_start + 8 <= len(data):
        bin_length = struct.unpack_from("<I", data, bin_start)[0]
        bin_data = data[bin_start + 8:bin_start + 8 + bin_length]
    return doc, bin_data


def read_accessor(doc, bin_data, index):
    """The accessor's elements as tuples (dense accessors over the one buffer only)."""
    accessor = doc["accessors"][index]
    fmt, size = COMPONENT[accessor["componentType"]]
    width = WIDTH[accessor["type"]]
    view = doc["bufferViews"][accessor["bufferView"]]
    stride = view.get("byteStride", size * width)
    start = view.get("byteOffset", 0) + accessor.get("byteOffset", 0)
    return [struct.unpack_from("<%d%s" % (width, fmt), bin_data, start + i * stride)
            for i in range(accessor["count"])]


def short_number(x):
    """Transform and keyframe values with 6 significant digits: a shorter seed, same kinds."""
    if isinstance(x, float):
        r = float("%.6g" % x)
        return int(r) if r.is_integer() and abs(r) < 1e15 else r
    return x


def shrink_scene(doc, bin_data, max_meshes, max_triangles, max_keys, max_channels):
    """A small document with the structure of `doc` (see the module's docstring)."""
    out = Doc()
    nodes = doc.get("nodes", [])
    scene_index = doc.get("scene", 0)
    roots = doc["scenes"][scene_index]["nodes"]
    # Meshes in the order the scene first reaches them (depth first, as the loader numbers
    # instances); the first max_meshes are kept.
    order, stack = [], list(reversed(roots))
    while stack:
        n = stack.pop()
        order.append(n)
        stack.extend(reversed(nodes[n].get("children", [])))
    kept_meshes = []
    for n in order:
        m = nodes[n].get("mesh")
        if m is not None and m not in kept_meshes and len(kept_meshes) < max_meshes:
            kept_meshes.append(m)
    mesh_nodes = [n for n in order if nodes[n].get("mesh") in kept_meshes]
    kept_skins = sorted({nodes[n]["skin"] for n in mesh_nodes if "skin" in nodes[n]})
    # Nodes kept: those instancing a kept mesh, the joints of their skins, their ancestors.
    parent = {}
    for i, node in enumerate(nodes):
        for c in node.get("children", []):
            parent[c] = i
    wanted = set(mesh_nodes)
    for s in kept_skins:
        wanted |= set(doc["skins"][s]["joints"])
        if "skeleton" in doc["skins"][s]:
            wanted.add(doc["skins"][s]["skeleton"])
    for n in list(wanted):
        while n in parent:
            n = parent[n]
            wanted.add(n)
    node_map = {old: new for new, old in enumerate(sorted(wanted))}
    mesh_map = {old: new for new, old in enumerate(kept_meshes)}
    skin_map = {old: new for new, old in enumerate(kept_skins)}

    copied = {}  # (accessor, vertex subset) -> new accessor: keeps sharing between primitives

    def copy_values(old, picked=None, key=None):
        cache_key = (old, key)
        if cache_key in copied:
            return copied[cache_key]
        accessor = doc["accessors"][old]
        elements = read_accessor(doc, bin_data, old)
        if picked is not None:
            elements = [elements[i] for i in picked]
        flat = [c for e in elements for c in e]
        extra = {}
        if accessor.get("normalized"):
            extra["normalized"] = True
        if accessor["type"] == "VEC3" and accessor["componentType"] == FLOAT and elements:
            extra["min"] = [min(e[i] for e in elements) for i in range(3)]
            extra["max"] = [max(e[i] for e in elements) for i in range(3)]
        new = out.add_values(flat, accessor["componentType"], accessor["type"], **extra)
        copied[cache_key] = new
        return new

    for m in kept_meshes:
        primitives = []
        for p in doc["meshes"][m]["primitives"]:
            mode = p.get("mode", 4)
            count = doc["accessors"][p["attributes"]["POSITION"]]["count"]
            if "indices" in p:
                indices = [e[0] for e in read_accessor(doc, bin_data, p["indices"])]
            else:
                indices = list(range(count))
            keep = {4: 3 * max_triangles, 5: max_triangles + 2, 6: max_triangles + 2}.get(mode, 4)
            indices = indices[:keep]
            picked = sorted(set(indices))
            remap = {old: new for new, old in enumerate(picked)}
            key = tuple(picked)
            new_p = {"attributes": {}}
            for attribute in ("POSITION", "JOINTS_0", "WEIGHTS_0"):
                if attribute in p["attributes"]:
                    new_p["attributes"][attribute] = copy_values(p["attributes"][attribute],
                                                                 picked, key)
            if "targets" in p:
                new_p["targets"] = [{"POSITION": copy_values(t["POSITION"], picked, key)}
                                    for t in p["targets"] if "POSITION" in t]
            if "indices" in p:
                component = doc["accessors"][p["indices"]]["componentType"]
                new_p["indices"] = out.add_indices([remap[i] for i in indices], component)
            if mode != 4:
                new_p["mode"] = mode
            primitives.append(new_p)
        mesh = {"primitives": primitives}
        if "weights" in doc["meshes"][m]:
            mesh["weights"] = [short_number(w) for w in doc["meshes"][m]["weights"]]
        out.append("meshes", mesh)

    for s in kept_skins:
        skin = doc["skins"][s]
        new_skin = {"joints": [node_map[j] for j in skin["joints"]]}
        if "skeleton" in skin:
            new_skin["skeleton"] = node_map[skin["skeleton"]]
        if "inverseBindMatrices" in skin:
            new_skin["inverseBindMatrices"] = copy_values(skin["inverseBindMatrices"])
        out.append("skins", new_skin)

    for old in sorted(wanted):
        node = nodes[old]
        new_node = {}
        for key in ("matrix", "translation", "rotation", "scale", "weights"):
            if key in node:
                new_node[key] = [short_number(x) for x in node[key]]
        children = [node_map[c] for c in node.get("children", []) if c in node_map]
        if children:
            new_node["children"] = children
        if node.get("mesh") in mesh_map:
            new_node["mesh"] = mesh_map[node["mesh"]]
            if "skin" in node:
                new_node["skin"] = skin_map[node["skin"]]
        out.add_node(new_node)
    out.json["scenes"] = [{"nodes": [node_map[r] for r in roots if r in node_map]}]
    if "scene" in doc:
        out.json["scene"] = 0

    animations = []
    for animation in doc.get("animations", []):
        samplers, channels, sampler_map = [], [], {}
        for channel in animation["channels"]:
            target = channel["target"]
            if target.get("node") not in node_map or len(channels) >= max_channels:
                continue
            old_sampler = channel["sampler"]
            if old_sampler not in sampler_map:
                sampler = animation["samplers"][old_sampler]
                interpolation = sampler.get("interpolation", "LINEAR")
                times = read_accessor(doc, bin_data, sampler["input"])
                keys = list(range(len(times)))
                if len(keys) > max_keys:  # first, last and evenly spaced ones between
                    keys = sorted({round(i * (len(times) - 1) / (max_keys - 1))
                                   for i in range(max_keys)})
                values = read_accessor(doc, bin_data, sampler["output"])
                per_key = len(values) // max(len(times), 1)  # weights: one per target
                if interpolation == "CUBICSPLINE":
                    per_key //= 3
                picked_values = []
                for k in keys:
                    for part in range(3 if interpolation == "CUBICSPLINE" else 1):
                        base = (k * (3 if interpolation == "CUBICSPLINE" else 1) + part) * per_key
                        picked_values.extend(values[base:base + per_key])
                accessor = doc["accessors"][sampler["output"]]
                input_accessor = out.add_values(
                    [short_number(times[k][0]) for k in keys], FLOAT, "SCALAR",
                    min=[short_number(times[keys[0]][0])], max=[short_number(times[keys[-1]][0])])
                output_accessor = out.add_values(
                    [short_number(c) if accessor["componentType"] == FLOAT else c
                     for v in picked_values for c in v],
                    accessor["componentType"], accessor["type"],
                    **({"normalized": True} if accessor.get("normalized") else {}))
                sampler_map[old_sampler] = len(samplers)
                new_sampler = {"input": input_accessor, "output": output_accessor}
                if interpolation != "LINEAR":
                    new_sampler["interpolation"] = interpolation
                samplers.append(new_sampler)
            channels.append({"sampler": sampler_map[old_sampler],
                             "target": {"node": node_map[target["node"]],
                                        "path": target["path"]}})
        if channels:
            animations.append({"samplers": samplers, "channels": channels})
    if animations:
        out.json["animations"] = animations
    return out


def shared_scene_seeds(folder):
    if not os.path.isdir(folder):
        sys.exit("make_gltf_seeds.py: no shared scenes in %s" % folder)
    for file in sorted(os.listdir(folder)):
        if not file.endswith(".glb"):
            continue
        doc, bin_data = read_glb(os.path.join(folder, file))
        # From generous to tight until the .gltf form fits the budget.
        for limits in ((8, 8, 4, 24), (6, 4, 3, 12), (4, 2, 3, 8), (3, 1, 2, 6), (2, 1, 2, 3)):
            small = shrink_scene(doc, bin_data, *limits)
            if len(small.gltf_bytes()) <= SEED_BUDGET:
                break
        else:
            sys.exit("make_gltf_seeds.py: cannot shrink %s below %d bytes" % (file, SEED_BUDGET))
        seed_doc("scene_" + file[:-4], small)


# ---- Small valid files --------------------------------------------------------------------

FIVE_POINTS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0, 1)]
TRIANGLE = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]


def single_mesh(primitives_of):
    """One mesh whose primitives primitives_of(doc) makes, one node, one scene."""
    doc = Doc()
    doc.add_mesh(primitives_of(doc), "m")
    doc.add_node({"mesh": 0})
    doc.add_scene([0])
    return doc


def triangle_with_nodes(nodes, roots):
    doc = Doc()
    doc.add_mesh([primitive(doc.add_positions(TRIANGLE))])
    for node in nodes:
        doc.add_node(node)
    doc.add_scene(roots)
    return doc


def valid_file():
    return triangle_with_nodes([{"mesh": 0}], [0])


def valid_seeds():
    seed_doc("ok_triangle", valid_file())
    seed_doc("ok_strip_u16", single_mesh(lambda d: [primitive(
        d.add_positions(FIVE_POINTS), d.add_indices([2, 3, 1, 4, 0], UNSIGNED_SHORT), 5)]))
    seed_doc("ok_fan_u8", single_mesh(lambda d: [primitive(
        d.add_positions(FIVE_POINTS), d.add_indices([4, 0, 1, 2, 3], UNSIGNED_BYTE), 6)]))

    def mixed(d):
        tri = d.add_positions(TRIANGLE)
        quad = d.add_positions([(0, 0, 1), (1, 0, 1), (0, 1, 1), (1, 1, 1)])
        return [primitive(tri)] + [primitive(quad, -1, mode) for mode in (0, 1, 2, 3, 5, 6)]
    seed_doc("ok_mixed_modes", single_mesh(mixed))
    six = FIVE_POINTS + [(3, 3, 3)]
    seed_doc("ok_nonindexed", single_mesh(lambda d: [primitive(d.add_positions(six))]))
    seed_doc("ok_degenerate", single_mesh(lambda d: [primitive(
        d.add_positions(TRIANGLE), d.add_indices([0, 0, 1, 0, 1, 2]))]))

    def interleaved(d):
        d.add_view(b"pad!")
        records = [9, 9, 1, 2, 3, 9, 9, 4, 5, 6, 9, 9, 7, 8, 9]
        view = d.add_view(struct.pack("<15f", *records), stride=20)
        positions = d.add_accessor(view, FLOAT, 3, "VEC3", 8)
        index_view = d.add_view(struct.pack("<4H", 7, 2, 1, 0))
        indices = d.add_accessor(index_view, UNSIGNED_SHORT, 3, "SCALAR", 2)
        return [primitive(positions, indices)]
    seed_doc("ok_interleaved", single_mesh(interleaved))

    h = math.sqrt(0.5)
    seed_doc("ok_trs_and_matrix", triangle_with_nodes(
        [{"mesh": 0, "translation": [1, 2, 3], "rotation": [0, 0, h, h], "scale": [2, 3, 4]},
         {"mesh": 0, "matrix": [0, 2, 0, 0, -3, 0, 0, 0, 0, 0, 4, 0, 1, 2, 3, 1]}], [0, 1]))
    seed_doc("ok_nested_transforms", triangle_with_nodes(
        [{"translation": [10, 0, 0], "rotation": [0, 0, h, h], "children": [1]},
         {"mesh": 0, "translation": [1, 0, 0], "scale": [2, 2, 2]}], [0]))

    dfs = Doc()
    positions = dfs.add_positions(TRIANGLE)
    for m in range(6):
        dfs.add_mesh([primitive(positions)], "mesh%d" % m)
    for node in ({"mesh": 0}, {"mesh": 1, "children": [4, 2]}, {"children": [5]},
                 {"mesh": 3, "children": [1]}, {"mesh": 4}, {"mesh": 5}):
        dfs.add_node(node)
    dfs.add_scene([3, 0])
    seed_doc("ok_depth_first_instances", dfs)

    default_scene = triangle_with_nodes([{"mesh": 0}, {"mesh": 0}, {"mesh": 0}], [0])
    default_scene.add_scene([1, 2])
    default_scene.json["scene"] = 1
    seed_doc("ok_default_scene", default_scene)

    deep = Doc()
    deep.add_mesh([primitive(deep.add_positions(TRIANGLE))])
    depth = 200
    for n in range(depth):
        node = {"translation": [0, 0, 1e-5]}
        if n + 1 < depth:
            node["children"] = [n + 1]
        else:
            node["mesh"] = 0
        deep.add_node(node)
    deep.add_scene([0])
    seed_doc("ok_deep_node_hierarchy", deep)

    no_primitives = valid_file()
    no_primitives.json["meshes"].append({"primitives": []})
    no_primitives.add_node({"mesh": 1})
    no_primitives.json["scenes"][0]["nodes"] = [0, 1]
    seed_doc("ok_mesh_without_primitives", no_primitives)

    # Within the JSON nesting limit (512 levels): tinygltf converts `extras` recursively.
    nested = valid_file()
    seed("ok_nested_extras_500.gltf", dump(nested.finished(
        DATA_URI + base64.b64encode(bytes(nested.bin)).decode()))[:-1].encode() +
        b',"extras":' + b"[" * 500 + b"]" * 500 + b"}")


# ---- Animations, skins, morph targets (tests/support/gltf_animation_files.h) ---------------

def z_rotation(degrees):
    half = math.radians(degrees) / 2
    return [0.0, 0.0, math.sin(half), math.cos(half)]


def add_channel_animation(doc, node, path, times, values, type_, interpolation="LINEAR"):
    inp = doc.add_values(times, FLOAT, "SCALAR", min=[min(times)], max=[max(times)])
    outp = doc.add_values(values, FLOAT, type_)
    doc.append("animations", {
        "samplers": [{"input": inp, "output": outp, "interpolation": interpolation}],
        "channels": [{"sampler": 0, "target": {"node": node, "path": path}}]})


def two_joint_skin(joint_type=UNSIGNED_SHORT, weight_type=FLOAT, vertex_1_weights=(1, 1),
                   inverse_bind_matrices=True, extra_skinned_nodes=0, static_user=False,
                   vertex_2_joint=1, morph_target=False):
    doc = Doc()
    positions = doc.add_positions([(0, 0, 0), (2, 0, 0), (2, 0, 1)])
    joints = doc.add_values([0, 7, 0, 0, 0, 1, 0, 0, vertex_2_joint, 0, 0, 0], joint_type, "VEC4")
    one = {UNSIGNED_BYTE: 255, UNSIGNED_SHORT: 65535}.get(weight_type, 1)
    raw = [one, 0, 0, 0, vertex_1_weights[0], vertex_1_weights[1], 0, 0, one, 0, 0, 0]
    if weight_type == FLOAT:
        weights = doc.add_values([float(w) for w in raw], FLOAT, "VEC4")
    else:
        weights = doc.add_values(raw, weight_type, "VEC4", normalized=True)
    p = primitive(positions)
    p["attributes"]["JOINTS_0"] = joints
    p["attributes"]["WEIGHTS_0"] = weights
    if morph_target:
        p["targets"] = [{"POSITION": doc.add_positions([(0, 0, 0), (0, 0, 0), (1, 0, 0)])}]
    mesh = doc.add_mesh([p], "skinned")
    skin = {"joints": [1, 2]}
    if inverse_bind_matrices:
        skin["inverseBindMatrices"] = doc.add_values(
            [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1,
             1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, -1, 0, 0, 1], FLOAT, "MAT4")
    doc.append("skins", skin)
    doc.add_node({"mesh": mesh, "skin": 0, "translation": [100, 0, 0]})
    if morph_target:
        doc.json["nodes"][0]["weights"] = [1.0]
    doc.add_node({"children": [2], "name": "joint 0"})
    doc.add_node({"translation": [1, 0, 0], "name": "joint 1"})
    roots = [0, 1]
    for _ in range(extra_skinned_nodes):
        roots.append(doc.add_node({"mesh": mesh, "skin": 0}))
    if static_user:
        roots.append(doc.add_node({"mesh": mesh}))
    doc.add_scene(roots)
    add_channel_animation(doc, 2, "rotation", [0, 1], z_rotation(0) + z_rotation(90), "VEC4")
    return doc


def morph_base(mesh_weights):
    doc = Doc()
    positions = doc.add_positions(TRIANGLE)
    t0 = doc.add_positions([(0, 0, 2), (0, 0, 0), (0, 0, 0)])
    t1 = doc.add_positions([(0, 0, 0), (0, 4, 0), (0, 0, 0)])
    p = primitive(positions)
    p["targets"] = [{"POSITION": t0}, {"POSITION": t1}]
    doc.add_mesh([p], "morphed")
    if mesh_weights:
        doc.json["meshes"][0]["weights"] = mesh_weights
    return doc


def animation_seeds():
    seed_doc("anim_skin_u16_float", two_joint_skin())
    seed_doc("anim_skin_u8_normalized_u8", two_joint_skin(UNSIGNED_BYTE, UNSIGNED_BYTE, (100, 155)))
    seed_doc("anim_skin_normalized_u16_shared", two_joint_skin(
        UNSIGNED_SHORT, UNSIGNED_SHORT, (30000, 35535), extra_skinned_nodes=2, static_user=True))
    seed_doc("anim_skin_no_inverse_bind_matrices", two_joint_skin(inverse_bind_matrices=False))
    seed_doc("anim_skin_with_morph_target", two_joint_skin(morph_target=True))
    seed_doc("anim_skin_joint_past_the_skin", two_joint_skin(vertex_2_joint=5))

    morph = morph_base([0.5, 0.25])
    morph.add_node({"mesh": 0})
    morph.add_node({"mesh": 0, "weights": [1, 0]})
    morph.add_scene([0, 1])
    add_channel_animation(morph, 0, "weights", [0, 1, 2], [0, 0, 1, 0, 0, 1], "SCALAR")
    seed_doc("anim_morph_weights", morph)

    for interpolation in ("STEP", "LINEAR", "CUBICSPLINE"):
        doc = triangle_with_nodes([{"mesh": 0}, {"mesh": 0, "children": [2]}, {"mesh": 0}],
                                  [0, 1])
        cubic = interpolation == "CUBICSPLINE"

        def keys(values, width):  # CUBICSPLINE: in-tangent, value, out-tangent per key
            if not cubic:
                return values
            out = []
            for i in range(0, len(values), width):
                out += [0.0] * width + values[i:i + width] + [0.0] * width
            return out
        add_channel_animation(doc, 0, "translation", [0, 0.5, 1],
                              keys([0, 0, 0, 1, 0, 0, 2, 1, 0], 3), "VEC3", interpolation)
        add_channel_animation(doc, 1, "rotation", [0, 1],
                              keys(z_rotation(0) + z_rotation(180), 4), "VEC4", interpolation)
        add_channel_animation(doc, 2, "scale", [0.25, 1],
                              keys([1, 1, 1, 2, 0.5, 1], 3), "VEC3", interpolation)
        seed_doc("anim_channels_" + interpolation.lower(), doc)

    bad_keys = triangle_with_nodes([{"mesh": 0}], [0])
    add_channel_animation(bad_keys, 0, "translation", [1, 0.5, float("nan")],
                          [0] * 9, "VEC3")
    bad_keys.json["accessors"][-2].pop("min")  # NaN has no JSON spelling
    bad_keys.json["accessors"][-2].pop("max")
    seed_doc("anim_bad_keys_decreasing_and_nan", bad_keys)


# ---- Rejected inputs ----------------------------------------------------------------------

def broken(name, edit, base=valid_file):
    doc = base()
    edit(doc.json)
    seed_doc("bad_" + name, doc)


def bad_seeds():
    seed("bad_malformed_json.gltf", b'{ "asset": [1, 2')
    seed("bad_unclosed_nodes.gltf", b'{"asset": {"version": "2.0"}, "nodes": [')
    seed("bad_empty.gltf", b"")
    whole = valid_file().glb_bytes()
    for keep in (10, 24, len(whole) // 2, len(whole) - 4):
        seed("bad_truncated_glb_%d.glb" % keep, whole[:keep])
    seed("bad_glb_claims_4gib.glb", whole[:8] + struct.pack("<I", 0xFFFFFFFF) + whole[12:])
    seed("bad_glb_bin_chunk_past_end.glb",
         whole[:-len(valid_file().bin) - 8] + struct.pack("<II", 1 << 20, 0x004E4942) +
         bytes(valid_file().bin))
    seed("bad_glb_bad_magic.glb", b"gltf" + whole[4:])
    seed("bad_nested_json_600.gltf", b'{"asset":{"version":"2.0"},"extras":' +
         b"[" * 600 + b"]" * 600 + b"}")
    seed("bad_nested_json_unclosed.gltf", b'{"asset":{"version":"2.0"},"extras":' + b"[{" * 300)

    def set_accessor(**fields):
        return lambda j: j["accessors"][0].update(fields)
    broken("accessor_past_its_view", set_accessor(count=4))
    broken("accessor_offset_past_its_view", set_accessor(byteOffset=4))
    broken("view_past_its_buffer", lambda j: j["bufferViews"][0].update(byteOffset=4))
    broken("count_2pow40", set_accessor(count=1 << 40))
    broken("count_overflowing", set_accessor(count=(2 ** 64 - 1) // 2))

    def count_2pow62_stride_12(j):
        j["accessors"][0]["count"] = 1 << 62
        j["bufferViews"][0]["byteStride"] = 12
    broken("count_2pow62_stride_12", count_2pow62_stride_12)
    broken("view_of_1tib", lambda j: j["bufferViews"][0].update(byteLength=1 << 40))

    def buffer_of_1tib(doc):
        doc.json["buffers"] = [{"byteLength": 1 << 40}]
        return doc
    seed("bad_buffer_of_1tib.glb", buffer_of_1tib(valid_file()).glb_bytes())
    for name, uri in (("missing_external_buffer", "no_such_file.bin"),
                      ("dev_zero_buffer", "/dev/zero"),
                      ("bad_data_uri", DATA_URI + "!!not base64!!")):
        doc = valid_file()
        doc.json["buffers"] = [{"byteLength": len(doc.bin), "uri": uri}]
        seed("bad_%s.gltf" % name, dump(doc.json).encode())

    index_past = single_mesh(lambda d: [primitive(
        d.add_positions(TRIANGLE), d.add_indices([0, 1, 2, 2, 1, 7]))])
    seed_doc("bad_index_past_the_vertex_count", index_past)
    # NaN and infinity cannot be written in JSON, only in the buffer.
    for name, bad in (("nan", float("nan")), ("inf", float("inf"))):
        seed_doc("bad_%s_vertex" % name, single_mesh(
            lambda d: [primitive(d.add_positions([(0, 0, 0), (1, bad, 0), (0, 1, 0)]))]))

    def nodes(name, node_list, roots):
        seed_doc("bad_" + name, triangle_with_nodes(node_list, roots))
    nodes("node_cycle", [{"mesh": 0, "children": [1]}, {"children": [0]}], [0])
    nodes("node_is_its_own_child", [{"mesh": 0, "children": [0]}], [0])
    nodes("shared_child", [{"children": [2]}, {"children": [2]}, {"mesh": 0}], [0, 1])
    nodes("root_twice", [{"mesh": 0}], [0, 0])
    nodes("missing_child", [{"mesh": 0, "children": [5]}], [0])
    nodes("missing_root", [{"mesh": 0}], [3])
    nodes("missing_mesh", [{"mesh": 3}], [0])
    nodes("no_roots", [{"mesh": 0}], [])
    nodes("no_mesh_nodes", [{"name": "camera"}], [0])
    broken("invalid_default_scene", lambda j: j.update(scene=2))
    broken("no_scenes", lambda j: j.pop("scenes"))
    broken("requires_an_extension", lambda j: j.update(
        extensionsUsed=["KHR_draco_mesh_compression"],
        extensionsRequired=["KHR_draco_mesh_compression"]))

    def transform(name, **fields):
        nodes(name, [dict({"mesh": 0}, **fields)], [0])
    transform("zero_scale", scale=[1, 0, 1])
    transform("translation_beyond_float", translation=[1e39, 0, 0])
    transform("short_matrix", matrix=[1, 0, 0])
    transform("singular_matrix", matrix=[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1])
    transform("zero_quaternion", rotation=[0, 0, 0, 0])
    transform("projective_matrix", matrix=[1, 0, 0, 0.5, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])
    transform("tiny_scale", scale=[1e-20, 1e-20, 1e-20])
    nodes("scales_overflowing_when_composed",
          [{"scale": [1e200, 1, 1], "children": [1]}, {"mesh": 0, "scale": [1e200, 1, 1]}], [0])

    def sparse(j):
        j["accessors"][0]["sparse"] = {
            "count": 1, "indices": {"bufferView": 0, "componentType": UNSIGNED_BYTE},
            "values": {"bufferView": 0}}
    broken("sparse_accessor", sparse)
    broken("vec2_positions", set_accessor(type="VEC2"))
    broken("short_positions", set_accessor(componentType=UNSIGNED_SHORT))
    broken("no_position", lambda j: j["meshes"][0]["primitives"][0].update(
        attributes={"NORMAL": 0}))
    broken("float_indices", lambda j: j["meshes"][0]["primitives"][0].update(indices=0))

    def topology(mesh_0_is_strip):
        doc = Doc()
        positions = doc.add_positions(FIVE_POINTS)
        four = doc.add_indices([0, 1, 2, 3])
        two = doc.add_indices([0, 1])
        doc.add_mesh([primitive(positions, two, 5) if mesh_0_is_strip else
                      primitive(positions, four)])
        doc.add_node({"mesh": 0})
        doc.add_scene([0])
        return doc
    seed_doc("bad_index_count_not_a_multiple_of_3", topology(False))
    seed_doc("bad_strip_of_two_indices", topology(True))


def instancing(attributes):
    return {"EXT_mesh_gpu_instancing": {"attributes": attributes}}


def gpu_instanced(edit=None, required=True):
    """Node 0 plain; node 1 (translated) instanced three times, with child node 2."""
    doc = triangle_with_nodes([], [])
    translation = doc.add_values([10, 0, 0, 0, 10, 0, 0, 0, 10], FLOAT, "VEC3")
    half = round(math.sqrt(0.5) * 32767)
    rotation = doc.add_values([0, 0, 0, 32767, 0, 0, half, half, 0, 0, 0, 32767], SHORT, "VEC4",
                              normalized=True)
    scale = doc.add_values([1, 1, 1, 0, 0, 0, 3, 3, 3], FLOAT, "VEC3")
    doc.add_node({"mesh": 0})
    doc.add_node({"mesh": 0, "translation": [0, 0, 100], "children": [2],
                  "extensions": instancing({"TRANSLATION": translation, "ROTATION": rotation,
                                            "SCALE": scale})})
    doc.add_node({"mesh": 0, "scale": [0, 0, 0]})
    doc.json["scenes"] = [{"nodes": [0, 1]}]
    doc.json["extensionsUsed"] = ["EXT_mesh_gpu_instancing"]
    if required:
        doc.json["extensionsRequired"] = ["EXT_mesh_gpu_instancing"]
    if edit:
        edit(doc)
    return doc


def extension_seeds():
    """EXT_mesh_gpu_instancing, hidden (zero-scale) instances, KHR_mesh_quantization."""
    seed_doc("ok_gpu_instancing_with_hidden", gpu_instanced())
    seed_doc("ok_gpu_instancing_not_required", gpu_instanced(required=False))

    def quantized(component_type, normalized, values):
        doc = Doc()
        fmt, size = COMPONENT[component_type]
        data = b"".join(struct.pack("<3" + fmt, *values[3 * v:3 * v + 3]) +
                        b"\0" * (-3 * size % 4) for v in range(3))
        view = doc.add_view(data, 4 if size == 1 else 8)
        positions = doc.add_accessor(view, component_type, 3, "VEC3", normalized=normalized)
        doc.add_mesh([primitive(positions)])
        doc.add_node({"mesh": 0, "scale": [2, 2, 2]})
        doc.add_scene([0])
        doc.json["extensionsUsed"] = doc.json["extensionsRequired"] = ["KHR_mesh_quantization"]
        return doc
    seed_doc("ok_quantized_byte_normalized", quantized(BYTE, True, [0, 0, 0, 127, 0, -128, 0, 127, 0]))
    seed_doc("ok_quantized_ushort", quantized(UNSIGNED_SHORT, False, [0, 0, 0, 900, 0, 2, 0, 3, 0]))

    def accessor_edit(index, **fields):
        return lambda doc: doc.json["accessors"][index].update(fields)

    def extension_edit(change):
        return lambda doc: change(doc.json["nodes"][1]["extensions"]["EXT_mesh_gpu_instancing"])
    seed_doc("bad_gpu_counts_differ", gpu_instanced(accessor_edit(3, count=2)))
    seed_doc("bad_gpu_count_zero", gpu_instanced(
        lambda doc: [doc.json["accessors"][a].update(count=0) for a in (1, 2, 3)]))
    seed_doc("bad_gpu_translation_ushort", gpu_instanced(accessor_edit(1, componentType=UNSIGNED_SHORT)))
    seed_doc("bad_gpu_rotation_not_normalized", gpu_instanced(accessor_edit(2, normalized=False)))
    seed_doc("bad_gpu_past_its_buffer", gpu_instanced(accessor_edit(1, count=300)))
    seed_doc("bad_gpu_without_mesh", gpu_instanced(lambda doc: doc.json["nodes"][1].pop("mesh")))
    seed_doc("bad_gpu_unknown_attribute",
             gpu_instanced(extension_edit(lambda e: e["attributes"].update(COLOR=1))))
    seed_doc("bad_gpu_missing_accessor",
             gpu_instanced(extension_edit(lambda e: e["attributes"].update(SCALE=99))))

    def rotation_seed(name, w):
        doc = triangle_with_nodes([], [])
        rotation = doc.add_values([0, 0, 0, 1, 0, 0, 0, w], FLOAT, "VEC4")
        doc.add_node({"mesh": 0, "extensions": instancing({"ROTATION": rotation})})
        doc.json["scenes"] = [{"nodes": [0]}]
        seed_doc(name, doc)
    rotation_seed("bad_gpu_rotation_not_unit", 0.5)
    rotation_seed("bad_gpu_rotation_zero", 0.0)


def hand_written_twins():
    """A .glb twin of every hand-written .gltf seed (two_meshes.gltf) in the folder."""
    for file in sorted(os.listdir(OUT)) if os.path.isdir(OUT) else []:
        if not file.endswith(".gltf") or file in SEEDS:
            continue
        doc = json.load(open(os.path.join(OUT, file)))
        bin_data = b""
        if doc.get("buffers") and doc["buffers"][0].get("uri", "").startswith(DATA_URI):
            bin_data = base64.b64decode(doc["buffers"][0].pop("uri")[len(DATA_URI):])
        seed(file[:-5] + ".glb", glb(dump(doc).encode(), bin_data))


def main():
    shared = sys.argv[1] if len(sys.argv) > 1 else DEFAULT_SHARED
    shared_scene_seeds(shared)
    valid_seeds()
    animation_seeds()
    bad_seeds()
    extension_seeds()
    hand_written_twins()
    os.makedirs(OUT, exist_ok=True)
    for name in sorted(SEEDS):
        with open(os.path.join(OUT, name), "wb") as f:
            f.write(SEEDS[name])
    largest = max(SEEDS, key=lambda n: len(SEEDS[n]))
    print("%d seeds in %s, %d bytes in all, largest %s (%d bytes)" % (
        len(SEEDS), os.path.relpath(OUT), sum(map(len, SEEDS.values())), largest,
        len(SEEDS[largest])))


if __name__ == "__main__":
    main()
