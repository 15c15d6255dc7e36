#!/usr/bin/env python3
"""Scenes for checking glint against Mitsuba 3 where the translation is exact.

Writes glTF files into OUT (default target/peer-scenes); `glint export`
writes each without an approximation (no warning), so
`scripts/mitsuba_bench.py` on them gives, in its "relMSE Mitsuba ref vs
glint ref" column, how far the two renderers are apart (the references'
own noise where they agree):

  python3 scripts/make_peer_scenes.py
  python3 scripts/mitsuba_bench.py 256 96 4096 1 $(ls target/peer-scenes/*.gltf | paste -sd,)

- cond_uv, cond_nouv, diel_uv, diel_nouv: a smooth UV sphere of anisotropic
  rough copper (alpha_u 0.3, alpha_v 0.03) and of anisotropic rough bk7
  glass (0.02 x 0.3), with TEXCOORD_0 (the lobe follows dP/du of the
  coordinates) and without (it follows each triangle's first edge,
  Mitsuba's dP/du of the barycentric parameterization).
- plastics: Mitsuba's `plastic` (linear and nonlinear) and `roughplastic`
  (alpha 0.05 and 0.3).
- glass: `thindielectric`, `dielectric` of water and diamond, and a
  `roughdielectric` of alpha 0.2.
- tinted: `dielectric` and `roughdielectric` with Mitsuba's
  `specular_reflectance` and `specular_transmittance`.
- metals: `roughconductor` (alpha 0.15) of each named metal (Ag, Al, Au,
  Cr, Cu) and a smooth `conductor` with a specular_reflectance.
- punctual: diffuse and rough spheres under a point and a directional
  light (no spot: glTF's cone ramp is not Mitsuba's).

All rough models use `separable` shadowing (Mitsuba's), on a grey floor,
under a tilted area light and a dim constant background.
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_assets import Builder, look_rotation, quad, sphere  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

COPPER = {"type": "roughconductor", "material": "Cu", "alpha_u": 0.3, "alpha_v": 0.03,
          "shadowing": "separable"}
GLASS = {"type": "roughdielectric", "int_ior": "bk7", "alpha_u": 0.02, "alpha_v": 0.3,
         "shadowing": "separable"}


def stage(b, area=True):
    """The floor, the area light and the camera of every scene."""
    grey = b.material("floor", {"type": "diffuse", "reflectance": [0.5, 0.5, 0.5]}, base=(0.5,) * 3)
    floor = quad([-3, 0, 2], [6, 0, 0], [0, 0, -4])
    b.node(name="floor", mesh=b.mesh("floor", b.geometry(*floor), grey))
    if area:
        light = b.material("light", {"type": "diffuse", "reflectance": [0, 0, 0]}, base=(0, 0, 0),
                           emission=(1, 1, 1), strength=8.0)
        panel = quad([-0.8, 2.0, 0.3], [1.6, 0, 0], [0, -0.4, 0.8])
        b.node(name="light", mesh=b.mesh("light", b.geometry(*panel), light))


def scene(path, uvs, bsdf):
    b = Builder()
    mat = b.material("anisotropic", bsdf, base=(0.9, 0.6, 0.5), metallic=1.0, roughness=0.4)
    pos, nrm, uv, idx = sphere(0.5, [0, 0.5, 0], seg=32, rings=16)
    b.node(name="sphere", mesh=b.mesh("sphere", b.geometry(pos, nrm, uv if uvs else None, idx), mat))
    stage(b)
    b.camera("main", [0, 1.3, 3.2], [0, 0.45, 0], 0.5, aspect=1.0)
    b.write(path, (0.1, 0.1, 0.12))


def row(path, bsdfs, area=True, lights=()):
    """Spheres of `bsdfs` in a row along x."""
    b = Builder()
    n = len(bsdfs)
    r = 0.3
    for i, bsdf in enumerate(bsdfs):
        x = (i - (n - 1) / 2) * 2.2 * r
        mat = b.material(f"m{i}", bsdf)
        geo = b.geometry(*sphere(r, [x, r, 0], seg=32, rings=16))
        b.node(name=f"s{i}", mesh=b.mesh(f"s{i}", geo, mat))
    stage(b, area)
    for name, kind, intensity, place in lights:
        if kind == "point":
            b.light(name, "point", (1.0, 0.9, 0.8), intensity, translation=place)
        else:
            b.light(name, "directional", (0.9, 0.95, 1.0), intensity,
                    rotation=look_rotation([0, 0, 0], place))
    b.camera("main", [0, 1.1, 3.4], [0, 0.3, 0], 0.6, aspect=2.0)
    b.write(path, (0.1, 0.1, 0.12))


def rough(t, **kw):
    return {"type": t, "distribution": "ggx", "shadowing": "separable", **kw}


PLASTICS = [
    {"type": "plastic", "diffuse_reflectance": [0.6, 0.2, 0.1]},
    {"type": "plastic", "diffuse_reflectance": [0.1, 0.3, 0.6], "nonlinear": True},
    rough("roughplastic", diffuse_reflectance=[0.2, 0.6, 0.2], alpha=0.05),
    rough("roughplastic", diffuse_reflectance=[0.7, 0.7, 0.7], alpha=0.3, int_ior=1.6),
]
GLASSES = [
    {"type": "thindielectric", "int_ior": "bk7"},
    {"type": "dielectric", "int_ior": "water"},
    {"type": "dielectric", "int_ior": "diamond"},
    rough("roughdielectric", int_ior=1.5, alpha=0.2),
]
METALS = [rough("roughconductor", material=m, alpha=0.15) for m in ("Ag", "Al", "Au", "Cr", "Cu")] + [
    {"type": "conductor", "material": "Au", "specular_reflectance": [0.5, 0.8, 1.0]}]
TINTED = [
    {"type": "dielectric", "int_ior": "bk7", "specular_transmittance": [0.3, 0.8, 1.0]},
    {"type": "dielectric", "int_ior": 1.5, "specular_reflectance": [1.0, 0.4, 0.1],
     "specular_transmittance": [0.9, 0.9, 0.5]},
    rough("roughdielectric", int_ior=1.5, alpha=0.15, specular_transmittance=[0.5, 1.0, 0.6]),
]
PUNCTUAL = [
    {"type": "diffuse", "reflectance": [0.7, 0.5, 0.3]},
    rough("roughconductor", material="Al", alpha=0.25),
    rough("roughplastic", diffuse_reflectance=[0.3, 0.3, 0.8], alpha=0.1),
]


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target", "peer-scenes")
    os.makedirs(out, exist_ok=True)
    for name, bsdf in (("cond", COPPER), ("diel", GLASS)):
        scene(os.path.join(out, f"{name}_uv.gltf"), True, bsdf)
        scene(os.path.join(out, f"{name}_nouv.gltf"), False, bsdf)
    row(os.path.join(out, "plastics.gltf"), PLASTICS)
    row(os.path.join(out, "glass.gltf"), GLASSES)
    row(os.path.join(out, "metals.gltf"), METALS)
    row(os.path.join(out, "tinted.gltf"), TINTED)
    row(os.path.join(out, "punctual.gltf"), PUNCTUAL, area=False,
        lights=[("point", "point", 3.0, [1.0, 1.8, 1.2]), ("sun", "directional", 1.5, [-0.4, -1.0, -0.5])])


if __name__ == "__main__":
    main()
