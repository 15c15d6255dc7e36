#!/usr/bin/env python3
"""Calibration and power of `glint test` on the files glint writes (issue 22).

    cargo build --release && python3 scripts/calibrate_suite.py [TRIALS] [DETECT] [WIDTH]

defaults 200 trials, detect 0.02, width 32, CPU backend, alpha 1e-3.

1. False alarms: a suite of the bundled scenes gets its references once
   (`glint test --update`), then TRIALS unchanged re-renders
   (`glint test --seed S`, independent seeds); per scene the count of
   `differ` verdicts, against alpha's binomial bound (the 1 - 1e-3 upper
   quantile of Binomial(TRIALS, alpha)).
2. Power: per scene, one material (one that covers at least a tenth of the
   image: the Cornell box's white walls, the other scenes' light floor
   tiles) has its base colour scaled by 1 + DETECT; TRIALS renders of the
   changed scene (`glint render --variance` at the spp `detect` chose, read
   from the suite's JUnit) are diffed with `glint diff` against the suite's
   reference: the rate of `differ`.

Prints a Markdown table (docs/benchmarks.md holds the measured one).
"""
import json
import math
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GLINT = os.path.join(ROOT, "target", "release", "glint")
SCENES = {  # scene: the material changed for the power test
    "diffuse": "tile light",
    "cornell": "white",
    "conductor": "tile light",
    "roughconductor": "tile light",
    "dielectric": "tile light",
    "roughdielectric": "tile light",
}


def binom_upper(n, p, a):
    """Smallest k with P(X > k) <= a for X ~ Binomial(n, p)."""
    cdf, k = 0.0, 0
    while True:
        cdf += math.comb(n, k) * p**k * (1 - p) ** (n - k)
        if 1 - cdf <= a:
            return k
        k += 1


def main():
    trials = int(sys.argv[1]) if len(sys.argv) > 1 else 200
    delta = float(sys.argv[2]) if len(sys.argv) > 2 else 0.02
    width = int(sys.argv[3]) if len(sys.argv) > 3 else 32
    alpha = 1e-3
    work = os.path.join(ROOT, "target", "calibrate-suite")
    os.makedirs(work, exist_ok=True)
    suite = os.path.join(work, "suite.toml")
    with open(suite, "w") as f:
        f.write(f'[defaults]\nbackend = "cpu"\nwidth = {width}\nalpha = {alpha}\n')
        f.write(f"detect = {delta}\nspp = 65536\n")
        for s in SCENES:
            f.write(f'[[scene]]\nname = "{s}"\nfile = "{ROOT}/assets/{s}.gltf"\n')
    subprocess.run([GLINT, "test", suite, "--update", "--jobs", "2"], check=True)
    junit = os.path.join(work, "junit.xml")
    alarms = {s: 0 for s in SCENES}
    spp = {}
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
    caught = {}
    for s, material in SCENES.items():
        g = json.load(open(os.path.join(ROOT, "assets", f"{s}.gltf")))
        for m in g["materials"]:
            if m.get("name") == material:
                # The glTF base colour and glint's own extras.bsdf
                # reflectance (which wins where present).
                colours = [m["pbrMetallicRoughness"]["baseColorFactor"]]
                colours += [m.get("extras", {}).get("bsdf", {}).get("reflectance")]
                for c in filter(None, colours):
                    for i in range(3):
                        c[i] *= 1 + delta
        # Buffers are relative to the scene: write it beside the original.
        changed = os.path.join(ROOT, "assets", f".calibrate-{s}.gltf")
        json.dump(g, open(changed, "w"))
        caught[s] = 0
        try:
            for t in range(trials):
                exr = os.path.join(work, f"{s}-changed.exr")
                subprocess.run([GLINT, "render", changed, "--backend", "cpu", "--width",
                                str(width), "--spp", str(spp[s]), "--seed", str(5000 + t),
                                "--variance", "--quiet", "-o", exr], check=True)
                r = subprocess.run([GLINT, "diff", exr, os.path.join(work, "refs", f"{s}.exr"),
                                    "--alpha", str(alpha)], capture_output=True)
                caught[s] += r.returncode == 1
        finally:
            os.remove(changed)
    bound = binom_upper(trials, alpha, 1e-3)
    print(f"\n{trials} trials per scene, width {width}, CPU, alpha {alpha}, detect {delta}; "
          f"false alarms allowed by Binomial({trials}, {alpha}) at 1e-3: <= {bound}\n")
    print("| scene | spp (detect) | false alarms | material +{:.0%} | caught |".format(delta))
    print("|---|---|---|---|---|")
    for s in SCENES:
        print(f"| {s} | {spp[s]} | {alarms[s]}/{trials} | {SCENES[s]} | "
              f"{caught[s]}/{trials} ({caught[s] / trials:.0%}) |")


if __name__ == "__main__":
    main()
