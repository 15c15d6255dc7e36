#!/usr/bin/env python3
"""Generate glint's example scenes in assets/ (Python 3 standard library only).

    python3 scripts/make_assets.py            # writes assets/*.gltf

Each scene is one .gltf with its buffer embedded as a base64 data URI, so a
file is self-contained and the output is byte-for-byte reproducible.

Scenes:
  cornell.gltf          Cornell-style box (red left, green right, white floor,
                        ceiling and back), an emissive quad under the ceiling,
                        and one sphere per BSDF type (diffuse, conductor Au,
                        anisotropic roughconductor Cu, dielectric bk7,
                        roughdielectric alpha 0.1). Camera aspect 1.
  diffuse.gltf          diffuse sphere on a checker plane; emissive area light
                        and a background colour.
  conductor.gltf        smooth gold sphere; point light and background.
  roughconductor.gltf   anisotropic rough copper sphere; spot light and
                        background.
  dielectric.gltf       bk7 glass sphere; directional light and background.
  roughdielectric.gltf  rough glass sphere; emissive area light and a point
                        light.
  textured.gltf         glTF textures, procedural PNGs embedded in the buffer:
                        a checker baseColor floor, a metal panel whose
                        roughness ramps across it (metallicRoughness G), a
                        panel with a normal map of 4x4 hemispherical bumps, and
                        an alpha-masked leaf (MASK, cutoff 0.5); a sun and a
                        background.
  materials.gltf        core glTF materials without extras.bsdf, one sphere
                        each: rows of metals (metallic 1), the metal/non-metal
                        blend (metallic 0.5), black and red non-metals (the
                        coat over a Lambertian base) and thin-walled
                        transmission (KHR_materials_transmission), over
                        roughness 0, 0.25, 0.5, 0.75, 1; a sun and a sky.
  bunny.glb             (not generated: the shared Stanford Bunny) gets a
                        directional light and a background added to its JSON.

Materials name their BSDF in extras.bsdf (Mitsuba 3 names) and also carry
approximate glTF metallic-roughness factors so other viewers show something
sensible.
"""

import base64
import json
import math
import os
import struct
import sys
import zlib

FLOAT = 5126
USHORT = 5123
ARRAY_BUFFER = 34962
ELEMENT_ARRAY_BUFFER = 34963


class Builder:
    """Accumulates one glTF document and its single embedded buffer."""

    def __init__(self):
        self.buf = bytearray()
        self.doc = {
            "asset": {"version": "2.0", "generator": "glint scripts/make_assets.py"},
            "scene": 0,
            "scenes": [{"nodes": []}],
            "nodes": [],
            "meshes": [],
            "materials": [],
            "accessors": [],
            "bufferViews": [],
            "buffers": [],
        }
        self.extensions = set()

    def _view(self, data, target, stride=None):
        while len(self.buf) % 4:
            self.buf.append(0)
        view = {"buffer": 0, "byteOffset": len(self.buf), "byteLength": len(data), "target": target}
        if stride:
            view["byteStride"] = stride
        self.buf.extend(data)
        self.doc["bufferViews"].append(view)
        return len(self.doc["bufferViews"]) - 1

    def _accessor(self, view, ctype, count, typ, lo=None, hi=None):
        acc = {"bufferView": view, "componentType": ctype, "count": count, "type": typ}
        if lo is not None:
            acc["min"], acc["max"] = lo, hi
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def geometry(self, positions, normals, uvs, indices):
        """Store a vertex set; returns the primitive attributes and indices."""
        n = len(positions)
        pos = self._view(struct.pack(f"<{3 * n}f", *[c for p in positions for c in p]), ARRAY_BUFFER)
        lo = [min(p[i] for p in positions) for i in range(3)]
        hi = [max(p[i] for p in positions) for i in range(3)]
        attrs = {"POSITION": self._accessor(pos, FLOAT, n, "VEC3", lo, hi)}
        nrm = self._view(struct.pack(f"<{3 * n}f", *[c for v in normals for c in v]), ARRAY_BUFFER)
        attrs["NORMAL"] = self._accessor(nrm, FLOAT, n, "VEC3")
        if uvs:
            uv = self._view(struct.pack(f"<{2 * n}f", *[c for v in uvs for c in v]), ARRAY_BUFFER)
            attrs["TEXCOORD_0"] = self._accessor(uv, FLOAT, n, "VEC2")
        idx = self._view(struct.pack(f"<{len(indices)}H", *indices), ELEMENT_ARRAY_BUFFER)
        return attrs, self._accessor(idx, USHORT, len(indices), "SCALAR")

    def material(self, name, bsdf=None, base=(0.8, 0.8, 0.8), metallic=0.0, roughness=1.0,
                 emission=None, strength=None, transmission=None, ior=None):
        m = {"name": name, "pbrMetallicRoughness": {
            "baseColorFactor": [*base, 1.0], "metallicFactor": metallic, "roughnessFactor": roughness}}
        if bsdf:
            m["extras"] = {"bsdf": bsdf}
        ext = {}
        if emission:
            m["emissiveFactor"] = list(emission)
            if strength is not None:
                ext["KHR_materials_emissive_strength"] = {"emissiveStrength": strength}
        if transmission is not None:
            ext["KHR_materials_transmission"] = {"transmissionFactor": transmission}
        if ior is not None:
            ext["KHR_materials_ior"] = {"ior": ior}
        if ext:
            m["extensions"] = ext
            self.extensions.update(ext)
        self.doc["materials"].append(m)
        return len(self.doc["materials"]) - 1

    def image_png(self, name, width, height, rgba):
        """A PNG texture (rgba: rows top first, 4 bytes a pixel) embedded in
        the buffer; returns the texture index."""
        data = png(width, height, rgba)
        while len(self.buf) % 4:
            self.buf.append(0)
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": len(self.buf), "byteLength": len(data)})
        self.buf.extend(data)
        images = self.doc.setdefault("images", [])
        images.append({"name": name, "bufferView": len(self.doc["bufferViews"]) - 1, "mimeType": "image/png"})
        textures = self.doc.setdefault("textures", [])
        textures.append({"source": len(images) - 1})
        return len(textures) - 1

    def raw_material(self, m):
        self.doc["materials"].append(m)
        return len(self.doc["materials"]) - 1

    def mesh(self, name, geometry, material):
        attrs, indices = geometry
        self.doc["meshes"].append({"name": name, "primitives": [
            {"attributes": attrs, "indices": indices, "material": material}]})
        return len(self.doc["meshes"]) - 1

    def node(self, **node):
        self.doc["nodes"].append(node)
        self.doc["scenes"][0]["nodes"].append(len(self.doc["nodes"]) - 1)
        return len(self.doc["nodes"]) - 1

    def camera(self, name, eye, target, yfov, aspect=1.0):
        self.doc.setdefault("cameras", []).append({"name": name, "type": "perspective", "perspective": {
            "yfov": yfov, "aspectRatio": aspect, "znear": 0.01}})
        self.node(name=name, camera=len(self.doc["cameras"]) - 1,
                  rotation=look_rotation(eye, target), translation=list(eye))

    def light(self, name, kind, color, intensity, translation=None, rotation=None, spot=None):
        ext = self.doc.setdefault("extensions", {}).setdefault("KHR_lights_punctual", {"lights": []})
        light = {"name": name, "type": kind, "color": list(color), "intensity": intensity}
        if spot:
            light["spot"] = {"innerConeAngle": spot[0], "outerConeAngle": spot[1]}
        ext["lights"].append(light)
        self.extensions.add("KHR_lights_punctual")
        node = {"name": name, "extensions": {"KHR_lights_punctual": {"light": len(ext["lights"]) - 1}}}
        if translation:
            node["translation"] = list(translation)
        if rotation:
            node["rotation"] = rotation
        self.node(**node)

    def write(self, path, background=None):
        self.doc["buffers"] = [{
            "byteLength": len(self.buf),
            "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(self.buf)).decode(),
        }]
        if background is not None:
            self.doc["scenes"][0]["extras"] = {"background": list(background)}
        if self.extensions:
            self.doc["extensionsUsed"] = sorted(self.extensions)
        for key in [k for k, v in self.doc.items() if v == []]:
            del self.doc[key]
        with open(path, "w") as f:
            json.dump(self.doc, f, indent=1)
            f.write("\n")
        print(f"{path}: {os.path.getsize(path)} bytes")


def png(width, height, rgba):
    """A minimal RGBA8 PNG (zlib level 9, filter 0 on every row)."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    raw = b"".join(b"\x00" + bytes(rgba[y * width * 4:(y + 1) * width * 4]) for y in range(height))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def normalize(v):
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def quat_from_basis(x, y, z):
    """Unit quaternion [x, y, z, w] of the rotation whose columns are x, y, z."""
    m00, m11, m22 = x[0], y[1], z[2]
    tr = m00 + m11 + m22
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = [(y[2] - z[1]) / s, (z[0] - x[2]) / s, (x[1] - y[0]) / s, 0.25 * s]
    elif m00 > m11 and m00 > m22:
        s = math.sqrt(1.0 + m00 - m11 - m22) * 2
        q = [0.25 * s, (y[0] + x[1]) / s, (z[0] + x[2]) / s, (y[2] - z[1]) / s]
    elif m11 > m22:
        s = math.sqrt(1.0 + m11 - m00 - m22) * 2
        q = [(y[0] + x[1]) / s, 0.25 * s, (z[1] + y[2]) / s, (z[0] - x[2]) / s]
    else:
        s = math.sqrt(1.0 + m22 - m00 - m11) * 2
        q = [(z[0] + x[2]) / s, (z[1] + y[2]) / s, 0.25 * s, (x[1] - y[0]) / s]
    return [round(c, 7) for c in normalize(q)]


def look_rotation(eye, target, up=(0.0, 1.0, 0.0)):
    """Rotation making local -Z point from eye to target, +Y as close to up."""
    z = normalize([e - t for e, t in zip(eye, target)])
    x = normalize(cross(up, z))
    y = cross(z, x)
    return quat_from_basis(x, y, z)


def sphere(radius, center, seg=24, rings=12):
    """UV sphere: u runs around +Y (longitude), v from the north pole down."""
    pos, nrm, uv, idx = [], [], [], []
    for r in range(rings + 1):
        theta = math.pi * r / rings
        for s in range(seg + 1):
            phi = 2 * math.pi * s / seg
            n = [math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi)]
            nrm.append(n)
            pos.append([center[i] + radius * n[i] for i in range(3)])
            uv.append([s / seg, r / rings])
    for r in range(rings):
        for s in range(seg):
            a, b = r * (seg + 1) + s, (r + 1) * (seg + 1) + s
            # Counter-clockwise seen from outside.
            if r > 0:
                idx += [a, b, a + 1]
            if r < rings - 1:
                idx += [a + 1, b, b + 1]
    return pos, nrm, uv, idx


def quad(corner, edge_u, edge_v):
    """A parallelogram facing edge_u x edge_v (counter-clockwise)."""
    p = [corner, [c + u for c, u in zip(corner, edge_u)],
         [c + u + v for c, u, v in zip(corner, edge_u, edge_v)], [c + v for c, v in zip(corner, edge_v)]]
    n = normalize(cross(edge_u, edge_v))
    return p, [n] * 4, [[0, 0], [1, 0], [1, 1], [0, 1]], [0, 1, 2, 0, 2, 3]


def checker(size, tiles, y=0.0):
    """Two interleaved tile sets (for two materials) of a +Y-facing plane."""
    sets = ([], [])
    step = 2 * size / tiles
    for i in range(tiles):
        for j in range(tiles):
            x0, z0 = -size + i * step, -size + j * step
            sets[(i + j) % 2].append(quad([x0, y, z0 + step], [step, 0, 0], [0, 0, -step]))
    return [merge(s) for s in sets]


def merge(parts):
    pos, nrm, uv, idx = [], [], [], []
    for p, n, t, i in parts:
        idx += [k + len(pos) for k in i]
        pos += p
        nrm += n
        uv += t
    return pos, nrm, uv, idx


WHITE = (0.725, 0.71, 0.68)
RED = (0.63, 0.065, 0.05)
GREEN = (0.14, 0.45, 0.091)

BSDFS = {
    "diffuse": ({"type": "diffuse", "reflectance": [0.2, 0.35, 0.7]},
                dict(base=(0.2, 0.35, 0.7))),
    "conductor": ({"type": "conductor", "material": "Au"},
                  dict(base=(1.0, 0.78, 0.34), metallic=1.0, roughness=0.0)),
    "roughconductor": ({"type": "roughconductor", "material": "Cu", "alpha_u": 0.3, "alpha_v": 0.05},
                       dict(base=(0.96, 0.64, 0.54), metallic=1.0, roughness=0.4)),
    "dielectric": ({"type": "dielectric", "int_ior": "bk7", "ext_ior": "air"},
                   dict(base=(1, 1, 1), roughness=0.0, transmission=1.0, ior=1.5046)),
    "roughdielectric": ({"type": "roughdielectric", "int_ior": "bk7", "ext_ior": "air", "alpha": 0.1},
                        dict(base=(1, 1, 1), roughness=0.316, transmission=1.0, ior=1.5046)),
}


def cornell(path):
    b = Builder()
    white = b.material("white", {"type": "diffuse", "reflectance": list(WHITE)}, base=WHITE)
    red = b.material("red", {"type": "diffuse", "reflectance": list(RED)}, base=RED)
    green = b.material("green", {"type": "diffuse", "reflectance": list(GREEN)}, base=GREEN)
    light = b.material("light", {"type": "diffuse", "reflectance": [0, 0, 0]}, base=(0, 0, 0),
                       emission=(1.0, 0.85, 0.6), strength=15.0)
    # The box spans x, z in [-1, 1], y in [0, 2], open towards +Z; every wall
    # faces the inside.
    walls = [
        ("floor", quad([-1, 0, 1], [2, 0, 0], [0, 0, -2]), white),
        ("ceiling", quad([-1, 2, -1], [2, 0, 0], [0, 0, 2]), white),
        ("back", quad([-1, 0, -1], [2, 0, 0], [0, 2, 0]), white),
        ("left", quad([-1, 0, 1], [0, 0, -2], [0, 2, 0]), red),
        ("right", quad([1, 0, -1], [0, 0, 2], [0, 2, 0]), green),
        # Facing down (-Y), just under the ceiling.
        ("light", quad([-0.25, 1.98, -0.25], [0.5, 0, 0], [0, 0, 0.5]), light),
    ]
    for name, geo, mat in walls:
        b.node(name=name, mesh=b.mesh(name, b.geometry(*geo), mat))
    r = 0.27
    spots = {"diffuse": (-0.62, -0.45), "conductor": (0.0, -0.5), "roughconductor": (0.62, -0.45),
             "dielectric": (-0.33, 0.3), "roughdielectric": (0.33, 0.3)}
    for name, (x, z) in spots.items():
        bsdf, pbr = BSDFS[name]
        mat = b.material(name, bsdf, **pbr)
        b.node(name=name, mesh=b.mesh(name, b.geometry(*sphere(r, [x, r, z])), mat))
    b.camera("front", [0, 1, 3.9], [0, 1, 0], 0.6911)
    b.write(path)


def single(path, name, lights, background=None):
    b = Builder()
    bsdf, pbr = BSDFS[name]
    mat = b.material(name, bsdf, **pbr)
    b.node(name=name, mesh=b.mesh(name, b.geometry(*sphere(0.5, [0, 0.5, 0])), mat))
    light_grey = b.material("tile light", {"type": "diffuse", "reflectance": [0.7, 0.7, 0.7]}, base=(0.7,) * 3)
    dark_grey = b.material("tile dark", {"type": "diffuse", "reflectance": [0.2, 0.2, 0.2]}, base=(0.2,) * 3)
    tiles_a, tiles_b = checker(2.0, 8)
    b.node(name="tiles light", mesh=b.mesh("tiles light", b.geometry(*tiles_a), light_grey))
    b.node(name="tiles dark", mesh=b.mesh("tiles dark", b.geometry(*tiles_b), dark_grey))
    b.camera("main", [0, 1.3, 3.2], [0, 0.45, 0], 0.6, aspect=4 / 3)
    for light in lights:
        if light == "area":
            emitter = b.material("area light", {"type": "diffuse", "reflectance": [0, 0, 0]}, base=(0, 0, 0),
                                 emission=(1, 1, 1), strength=8.0)
            # 1 x 1 quad at y = 2.5 facing down.
            geo = quad([-0.5, 2.5, -0.5], [1, 0, 0], [0, 0, 1])
            b.node(name="area light", mesh=b.mesh("area light", b.geometry(*geo), emitter))
        elif light == "point":
            b.light("point light", "point", (1.0, 0.95, 0.9), 6.0, translation=[1.5, 2.5, 1.5])
        elif light == "spot":
            eye = [-1.5, 3.0, 1.5]
            b.light("spot light", "spot", (1.0, 1.0, 1.0), 20.0, translation=eye,
                    rotation=look_rotation(eye, [0, 0.3, 0]), spot=(0.3, 0.5))
        elif light == "directional":
            b.light("sun", "directional", (1.0, 0.97, 0.9), 2.5,
                    rotation=look_rotation([0, 0, 0], [-0.5, -1.0, -0.6]))
    b.write(path, background)


def checker_image(n=64, tiles=8, a=(230, 200, 120), b=(40, 60, 110)):
    out = []
    for y in range(n):
        for x in range(n):
            c = a if ((x * tiles // n) + (y * tiles // n)) % 2 == 0 else b
            out += [*c, 255]
    return out


def roughness_ramp(n=64):
    """metallicRoughness: G (roughness) ramps 0 -> 1 left to right, B
    (metallic) 1."""
    out = []
    for y in range(n):
        for x in range(n):
            out += [0, round(255 * x / (n - 1)), 255, 255]
    return out


def bump_normals(n=64, bumps=4):
    """Tangent-space normals of `bumps` x `bumps` hemispherical domes of
    radius 0.4 cells: glTF convention, +X right, +Y up the image."""
    out = []
    cell = n / bumps
    for y in range(n):
        for x in range(n):
            cx = ((x + 0.5) % cell) / cell - 0.5
            cy = ((y + 0.5) % cell) / cell - 0.5
            r2 = cx * cx + cy * cy
            if r2 < 0.16:
                # Sphere of radius 0.4 centred in the cell; image y runs
                # down, tangent-space +Y up.
                nz = math.sqrt(0.16 - r2)
                v = normalize([cx, -cy, nz])
            else:
                v = [0.0, 0.0, 1.0]
            out += [round((c + 1) * 127.5) for c in v] + [255]
    return out


def leaf_image(n=64):
    """A leaf: an ellipse (alpha 255) with a paler midrib; alpha 0 outside."""
    out = []
    for y in range(n):
        for x in range(n):
            u, v = (x + 0.5) / n - 0.5, (y + 0.5) / n - 0.5
            inside = (u / 0.22) ** 2 + (v / 0.47) ** 2 <= 1.0
            rib = abs(u) < 0.015
            c = (150, 200, 90) if rib else (50, 130, 40)
            out += [*c, 255 if inside else 0]
    return out


def textured(path):
    b = Builder()
    checker_tex = b.image_png("checker", 64, 64, checker_image())
    ramp_tex = b.image_png("roughness ramp", 64, 64, roughness_ramp())
    bump_tex = b.image_png("bumps", 64, 64, bump_normals())
    leaf_tex = b.image_png("leaf", 64, 64, leaf_image())
    b.doc["samplers"] = [{"magFilter": 9728, "wrapS": 10497, "wrapT": 10497}]
    b.doc["textures"][checker_tex]["sampler"] = 0
    floor = b.raw_material({"name": "checker floor", "pbrMetallicRoughness": {
        "baseColorTexture": {"index": checker_tex}, "metallicFactor": 0, "roughnessFactor": 1}})
    metal = b.raw_material({"name": "roughness ramp metal", "pbrMetallicRoughness": {
        "baseColorFactor": [0.95, 0.93, 0.88, 1], "metallicRoughnessTexture": {"index": ramp_tex},
        "metallicFactor": 1, "roughnessFactor": 1}})
    bumpy = b.raw_material({"name": "bumps", "pbrMetallicRoughness": {
        "baseColorFactor": [0.7, 0.3, 0.25, 1], "metallicFactor": 0},
        "normalTexture": {"index": bump_tex, "scale": 1.0}})
    leaf = b.raw_material({"name": "leaf", "doubleSided": True, "alphaMode": "MASK", "alphaCutoff": 0.5,
                           "pbrMetallicRoughness": {"baseColorTexture": {"index": leaf_tex}, "metallicFactor": 0}})
    # Floor: 4 x 4 at y = 0, UVs tiled twice (REPEAT).
    p, n, t, i = quad([-2, 0, 2], [4, 0, 0], [0, 0, -4])
    t = [[0, 2], [2, 2], [2, 0], [0, 0]]
    b.node(name="floor", mesh=b.mesh("floor", b.geometry(p, n, t, i), floor))
    # Upright panels facing +Z; glTF UVs: (0, 0) at the top-left.
    uv = [[0, 1], [1, 1], [1, 0], [0, 0]]
    for name, mat, x in [("ramp panel", metal, -0.65), ("bump panel", bumpy, 0.65)]:
        p, n, _, i = quad([x - 0.55, 0.05, -0.6], [1.1, 0, 0], [0, 1.1, 0])
        b.node(name=name, mesh=b.mesh(name, b.geometry(p, n, uv, i), mat))
    # The leaf leans in front of the panels.
    p, n, _, i = quad([-0.3, 0.02, 0.55], [0.6, 0, 0], [0, 0.9, -0.35])
    b.node(name="leaf", mesh=b.mesh("leaf", b.geometry(p, n, uv, i), leaf))
    b.camera("main", [0, 1.2, 3.0], [0, 0.5, 0], 0.65, aspect=4 / 3)
    b.light("sun", "directional", (1.0, 0.96, 0.9), 3.0,
            rotation=look_rotation([0, 0, 0], [-0.4, -1.0, -0.7]))
    b.write(path, background=(0.25, 0.3, 0.4))


def light_bunny(path):
    """Give the bundled bunny a light and a background (it had none, so it
    rendered black): a directional sun and a sky colour, added to the GLB's
    JSON chunk (idempotent: an existing light is replaced)."""
    data = open(path, "rb").read()
    json_len = struct.unpack("<I", data[12:16])[0]
    doc = json.loads(data[20:20 + json_len])
    rest = data[20 + json_len:]
    nodes = [n for n in doc["nodes"] if "extensions" not in n]
    doc["nodes"] = nodes
    doc["scenes"][0]["nodes"] = list(range(len(nodes)))
    doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"name": "sun", "type": "directional", "color": [1.0, 0.97, 0.92], "intensity": 3.0}]}}
    doc["extensionsUsed"] = ["KHR_lights_punctual"]
    doc["nodes"].append({"name": "sun", "rotation": look_rotation([0, 0, 0], [-0.5, -1.0, -0.6]),
                         "extensions": {"KHR_lights_punctual": {"light": 0}}})
    doc["scenes"][0]["nodes"].append(len(doc["nodes"]) - 1)
    doc["scenes"][0]["extras"] = {"background": [0.3, 0.35, 0.45]}
    js = json.dumps(doc, separators=(",", ":")).encode()
    while len(js) % 4:
        js += b" "
    body = struct.pack("<I", len(js)) + b"JSON" + js + rest
    out = b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body
    with open(path, "wb") as f:
        f.write(out)
    print(f"{path}: {len(out)} bytes")


def materials(path):
    b = Builder()
    rows = [
        ("metal", dict(base=(1.0, 0.78, 0.34), metallic=1.0)),
        ("blend", dict(base=(0.9, 0.55, 0.3), metallic=0.5)),
        ("black", dict(base=(0.0, 0.0, 0.0), metallic=0.0)),
        ("red", dict(base=(0.7, 0.08, 0.05), metallic=0.0)),
        ("thin glass", dict(base=(0.9, 0.95, 1.0), metallic=0.0, transmission=1.0)),
    ]
    rough = [0.0, 0.25, 0.5, 0.75, 1.0]
    for r, (name, pbr) in enumerate(rows):
        y = 0.3 + 0.5 * (len(rows) - 1 - r)
        for c, roughness in enumerate(rough):
            label = f"{name} {roughness}"
            mat = b.material(label, None, roughness=roughness, **pbr)
            geo = sphere(0.2, [-1.0 + 0.5 * c, y, 0.0])
            b.node(name=label, mesh=b.mesh(label, b.geometry(*geo), mat))
    light_grey = b.material("tile light", None, base=(0.7,) * 3)
    dark_grey = b.material("tile dark", None, base=(0.2,) * 3)
    tiles_a, tiles_b = checker(3.0, 12)
    b.node(name="tiles light", mesh=b.mesh("tiles light", b.geometry(*tiles_a), light_grey))
    b.node(name="tiles dark", mesh=b.mesh("tiles dark", b.geometry(*tiles_b), dark_grey))
    b.camera("main", [0, 1.3, 4.2], [0, 1.3, 0], 0.75, aspect=1.0)
    b.light("sun", "directional", (1.0, 0.97, 0.9), 2.0,
            rotation=look_rotation([0, 0, 0], [-0.4, -0.8, -0.6]))
    b.write(path, background=(0.55, 0.6, 0.7))


def main():
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "assets")
    out = sys.argv[1] if len(sys.argv) > 1 else root
    os.makedirs(out, exist_ok=True)
    cornell(os.path.join(out, "cornell.gltf"))
    single(os.path.join(out, "diffuse.gltf"), "diffuse", ["area"], background=(0.05, 0.06, 0.08))
    single(os.path.join(out, "conductor.gltf"), "conductor", ["point"], background=(0.3, 0.35, 0.45))
    single(os.path.join(out, "roughconductor.gltf"), "roughconductor", ["spot"], background=(0.2, 0.2, 0.25))
    single(os.path.join(out, "dielectric.gltf"), "dielectric", ["directional"], background=(0.4, 0.45, 0.55))
    single(os.path.join(out, "roughdielectric.gltf"), "roughdielectric", ["area", "point"])
    textured(os.path.join(out, "textured.gltf"))
    materials(os.path.join(out, "materials.gltf"))
    bunny = os.path.join(out, "bunny.glb")
    if os.path.exists(bunny):
        light_bunny(bunny)


if __name__ == "__main__":
    main()
