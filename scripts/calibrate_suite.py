#!/usr/bin/env python3
"""Calibration and power of `glint test` on the files glint writes (issue 22).

    cargo build --release && python3 scripts/calibrate_suite.py \
        [TRIALS] [DETECT] [WIDTH] [POWER_TRIALS] [CAP] [SCENE,SCENE,...]

defaults 200 trials, detect 0.02, width 16, 100 power trials, cap 16384,
all six bundled scenes; CPU backend, alpha 1e-3.

1. False alarms: a suite of the bundled scenes gets its references once
   (`glint test --update`), then TRIALS unchanged re-renders
   (`glint test --seed S`, independent seeds); per scene the count of
   `differ` verdicts, against alpha's binomial bound (the 1 - 1e-3 upper
   quantile of Binomial(TRIALS, alpha)).
2. Power: per scene, each material `detect` sized for (the JUnit property
   `detect_materials`: those covering at least a tenth of the image) is
   changed by -DETECT in turn (a diffuse `reflectance`, a conductor's
   `specular_reflectance`, and the base colour, each x (1 - DETECT); a
   smooth or rough dielectric has no such factor in glint and is left out);
   POWER_TRIALS renders of the changed scene (`glint render --variance` at
   the spp `detect` chose) are diffed with `glint diff` against the suite's
   reference: the rate of `differ`. A scene whose spp reached the cap is
   reported as capped: the rule's guarantee does not hold there.

Prints a Markdown table (docs/benchmarks.md holds the measured one).
"""
import json
import math
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GLINT = os.path.join(ROOT, "target", "release", "glint")
SCENES = ["diffuse", "cornell", "conductor", "roughconductor", "dielectric",
          "roughdielectric"]


def change_material(m, delta):
    """Scale what the material reflects and transmits by 1 - delta."""
    f = 1 - delta
    pbr = m.setdefault("pbrMetallicRoughness", {})
    c = pbr.get("baseColorFactor", [1, 1, 1, 1])
    pbr["baseColorFactor"] = [c[0] * f, c[1] * f, c[2] * f, c[3]]
    bsdf = m.get("extras", {}).get("bsdf")
    if bsdf is None:
        return
    if bsdf["type"] == "diffuse":
        bsdf["reflectance"] = [v * f for v in bsdf.get("reflectance", [0.5] * 3)]
    elif "conductor" in bsdf["type"]:
        v = bsdf.get("specular_reflectance", [1.0, 1.0, 1.0])
        bsdf["specular_reflectance"] = [x * f for x in v]


def changeable(m):
    bsdf = m.get("extras", {}).get("bsdf")
    return bsdf is None or bsdf["type"] in ("diffuse", "conductor", "roughconductor")


def binom_upper(n, p, a):
    """Smallest k with P(X > k) <= a for X ~ Binomial(n, p)."""
    cdf, k = 0.0, 0
    while True:
        cdf += math.comb(n, k) * p**k * (1 - p) ** (n - k)
        if 1 - cdf <= a:
            return k
        k += 1


def main():
    arg = lambda i, d, t: t(sys.argv[i]) if len(sys.argv) > i else d
    trials = arg(1, 200, int)
    delta = arg(2, 0.02, float)
    width = arg(3, 16, int)
    power_trials = arg(4, 100, int)
    cap = arg(5, 16384, int)
    scenes = arg(6, SCENES, lambda s: s.split(","))
    alpha = 1e-3
    work = os.path.join(ROOT, "target", "calibrate-suite")
    os.makedirs(work, exist_ok=True)
    suite = os.path.join(work, "suite.toml")
    with open(suite, "w") as f:
        f.write(f'[defaults]\nbackend = "cpu"\nwidth = {width}\nalpha = {alpha}\n')
        f.write(f"detect = {delta}\nspp = {cap}\n")
        if os.environ.get("SAMPLER"):
            f.write(f'sampler = "{os.environ["SAMPLER"]}"\n')
        for s in scenes:
            f.write(f'[[scene]]\nname = "{s}"\nfile = "{ROOT}/assets/{s}.gltf"\n')
    subprocess.run([GLINT, "test", suite, "--update", "--jobs", "2"], check=True)
    junit = os.path.join(work, "junit.xml")
    alarms = {s: 0 for s in scenes}
    spp, by, sized = {}, {}, {}
    for seed in range(1, trials + 1):
        r = subprocess.run([GLINT, "test", suite, "--seed", str(10 + seed), "--jobs", "2",
                            "--junit", junit], capture_output=True, text=True)
        if r.returncode not in (0, 1):
            sys.exit(f"glint test failed: {r.stdout}{r.stderr}")
        for case in ET.parse(junit).getroot().iter("testcase"):
            name = case.get("name")
            if case.find("failure") is not None:
                alarms[name] += 1
            for p in case.iter("property"):
                if p.get("name") == "spp":
                    spp[name] = int(p.get("value"))
                if p.get("name") == "detect_by":
                    by[name] = p.get("value")
                if p.get("name") == "detect_materials":
                    sized[name] = re.findall(r"material (.+?) \((\d+)% of the image\)",
                                             p.get("value"))
    caught = {}  # (scene, material): (share %, caught)
    for s in scenes:
        original = json.load(open(os.path.join(ROOT, "assets", f"{s}.gltf")))
        for material, share in sized.get(s, []):
            g = json.loads(json.dumps(original))
            ms = [m for m in g["materials"] if m.get("name") == material]
            if not ms or not all(changeable(m) for m in ms):
                continue
            for m in ms:
                change_material(m, delta)
            # Buffers are relative to the scene: write it beside the original.
            changed = os.path.join(ROOT, "assets", f".calibrate-{s}.gltf")
            json.dump(g, open(changed, "w"))
            n = 0
            try:
                for t in range(power_trials):
                    exr = os.path.join(work, f"{s}-changed.exr")
                    subprocess.run([GLINT, "render", changed, "--backend", "cpu", "--width",
                                    str(width), "--spp", str(spp[s]), "--seed", str(5000 + t),
                                    "--variance", "--quiet", "-o", exr]
                                   + (["--sampler", os.environ["SAMPLER"]]
                                      if os.environ.get("SAMPLER") else []), check=True)
                    r = subprocess.run([GLINT, "diff", exr,
                                        os.path.join(work, "refs", f"{s}.exr"),
                                        "--alpha", str(alpha)], capture_output=True)
                    n += r.returncode == 1
            finally:
                os.remove(changed)
            caught[(s, material)] = (share, n)
    bound = binom_upper(trials, alpha, 1e-3)
    print(f"\n{trials} unchanged trials and {power_trials} changed ones per scene, width {width}, "
          f"CPU, alpha {alpha}, detect {delta}, cap {cap} spp; false alarms allowed by "
          f"Binomial({trials}, {alpha}) at 1e-3: <= {bound}\n")
    print("| scene | spp (detect) | set by | false alarms |")
    print("|---|---|---|---|")
    for s in scenes:
        capped = " (capped)" if spp[s] >= cap else ""
        print(f"| {s} | {spp[s]}{capped} | {by.get(s, 'the whole image')} | "
              f"{alarms[s]}/{trials} |")
    print(f"\n| scene | material (share) changed by -{delta:.0%} | caught |")
    print("|---|---|---|")
    for (s, material), (share, n) in caught.items():
        print(f"| {s} | {material} ({share}%) | {n}/{power_trials} ({n / power_trials:.0%}) |")

if __name__ == "__main__":
    main()
