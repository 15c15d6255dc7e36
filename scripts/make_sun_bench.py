#!/usr/bin/env python3
"""The envmap MIS benchmark's inputs (Python 3 standard library only):

    python3 scripts/make_sun_bench.py DIR   # writes DIR/floor.gltf, DIR/sun.hdr

floor.gltf: a 6 x 6 diffuse floor (baseColor 0.7) and a camera, no light.
sun.hdr: a 64 x 32 equirectangular sky of radiance 0.05 with a 2 x 2 texel
sun of radiance 5000 (flat RGBE scanlines)."""

import base64
import json
import math
import os
import struct
import sys


def rgbe(v):
    if v < 1e-32:
        return bytes(4)
    e = math.frexp(v)[1]
    m = int(v * 256.0 / 2 ** e)
    return bytes([m, m, m, e + 128])


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "."
    os.makedirs(out, exist_ok=True)
    w, h = 64, 32
    with open(os.path.join(out, "sun.hdr"), "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, w))
        for y in range(h):
            f.write(b"".join(rgbe(5000.0 if x in (38, 39) and y in (8, 9) else 0.05) for x in range(w)))
    buf = struct.pack("<12f", -3, 0, 3, 3, 0, 3, 3, 0, -3, -3, 0, -3) + struct.pack("<6H", 0, 1, 2, 0, 2, 3)
    doc = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0, 2, 4], "rotation": [-0.2588, 0, 0, 0.9659]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1], "metallicFactor": 0}}],
        "buffers": [{"byteLength": len(buf),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(buf).decode()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
                      {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}],
    }
    with open(os.path.join(out, "floor.gltf"), "w") as f:
        json.dump(doc, f)


if __name__ == "__main__":
    main()
