#!/usr/bin/env python3
"""Anisotropic spheres for checking glint's tangent frame against Mitsuba 3.

Writes four glTF files into OUT (default target/tangent-scenes): a smooth
UV sphere of anisotropic rough copper (alpha_u 0.3, alpha_v 0.03) and of
anisotropic rough bk7 glass (alpha_u 0.02, alpha_v 0.3), each with
TEXCOORD_0 (`*_uv`: the lobe follows dP/du of the coordinates) and without
(`*_nouv`: it follows the first edge of each triangle, Mitsuba's dP/du of
the barycentric parameterization), separable shadowing (Mitsuba's), on a
grey floor under a tilted area light. `glint export` writes them exactly,
so `scripts/mitsuba_bench.py` on them gives, in its "relMSE Mitsuba ref vs
glint ref" column, how far the two renderers' frames are apart:

  python3 scripts/make_tangent_scenes.py
  python3 scripts/mitsuba_bench.py 256 96 4096 1 \\
      target/tangent-scenes/cond_uv.gltf,target/tangent-scenes/cond_nouv.gltf,\\
target/tangent-scenes/diel_uv.gltf,target/tangent-scenes/diel_nouv.gltf
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_assets import Builder, quad, sphere  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

COPPER = {"type": "roughconductor", "material": "Cu", "alpha_u": 0.3, "alpha_v": 0.03,
          "shadowing": "separable"}
GLASS = {"type": "roughdielectric", "int_ior": "bk7", "alpha_u": 0.02, "alpha_v": 0.3,
         "shadowing": "separable"}


def scene(path, uvs, bsdf):
    b = Builder()
    mat = b.material("anisotropic", bsdf, base=(0.9, 0.6, 0.5), metallic=1.0, roughness=0.4)
    pos, nrm, uv, idx = sphere(0.5, [0, 0.5, 0], seg=32, rings=16)
    b.node(name="sphere", mesh=b.mesh("sphere", b.geometry(pos, nrm, uv if uvs else None, idx), mat))
    grey = b.material("floor", {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]}, base=(0.5,) * 3)
    floor = quad([-2, 0, 2], [4, 0, 0], [0, 0, -4])
    b.node(name="floor", mesh=b.mesh("floor", b.geometry(*floor), grey))
    light = b.material("light", {"type": "diffuse", "reflectance": [0, 0, 0]}, base=(0, 0, 0),
                       emission=(1, 1, 1), strength=8.0)
    panel = quad([-0.8, 2.0, 0.3], [1.6, 0, 0], [0, -0.4, 0.8])
    b.node(name="light", mesh=b.mesh("light", b.geometry(*panel), light))
    b.camera("main", [0, 1.3, 3.2], [0, 0.45, 0], 0.5, aspect=1.0)
    b.write(path, (0.1, 0.1, 0.12))


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target", "tangent-scenes")
    os.makedirs(out, exist_ok=True)
    for name, bsdf in (("cond", COPPER), ("diel", GLASS)):
        scene(os.path.join(out, f"{name}_uv.gltf"), True, bsdf)
        scene(os.path.join(out, f"{name}_nouv.gltf"), False, bsdf)


if __name__ == "__main__":
    main()
