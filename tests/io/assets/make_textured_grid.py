#!/usr/bin/env python3
"""Writes textured_grid.glb: a bumpy 8 x 8 grid of quads with TEXCOORD_0 over [0, 1]^2 and a
2 x 2 base colour texture (embedded PNG), the source of the compressed copies whose texture
coordinates tests/io/gltf_compressed_scenes_test.cpp compares (make_assets.sh)."""
import json
import struct
import sys
import zlib


def png(width, height, pixels):
    rows = b"".join(b"\x00" + bytes(c for rgb in pixels[y * width:(y + 1) * width] for c in rgb)
                    for y in range(height))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows)) +
            chunk(b"IEND", b""))


def pad4(data, fill):
    return data + fill * (-len(data) % 4)


def main(path):
    n = 8
    positions, uvs, indices = [], [], []
    for j in range(n + 1):
        for i in range(n + 1):
            positions += [i / n * 2 - 1, j / n * 2 - 1, 0.1 * ((i * j) % 3)]
            uvs += [i / n, 1 - j / n]
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            indices += [a, a + 1, a + n + 2, a, a + n + 2, a + n + 1]
    image = png(2, 2, [(255, 0, 0), (0, 255, 0), (0, 0, 255), (255, 255, 0)])
    parts = [struct.pack("<%df" % len(positions), *positions),
             struct.pack("<%df" % len(uvs), *uvs),
             pad4(struct.pack("<%dH" % len(indices), *indices), b"\x00"), pad4(image, b"\x00")]
    views, offset = [], 0
    for part in parts:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(part)})
        offset += len(part)
    views[3]["byteLength"] = len(image)
    binary = b"".join(parts)
    document = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1},
                                    "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9728, "minFilter": 9728}],
        "images": [{"bufferView": 3, "mimeType": "image/png"}],
        "buffers": [{"byteLength": len(binary)}], "bufferViews": views,
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(positions) // 3,
             "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0.2]},
            {"bufferView": 1, "componentType": 5126, "count": len(uvs) // 2, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": len(indices), "type": "SCALAR"}]}
    text = pad4(json.dumps(document).encode(), b" ")
    with open(path, "wb") as out:
        out.write(struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(binary)))
        out.write(struct.pack("<II", len(text), 0x4E4F534A) + text)
        out.write(struct.pack("<II", len(binary), 0x004E4942) + binary)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "textured_grid.glb")
