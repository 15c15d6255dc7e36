#!/usr/bin/env python3
"""Calibration of glint's estimated relMSE, the quantity `--target-error`
stops on (issue 23).

    cargo build --release && python3 scripts/calibrate_error.py [SEEDS] [SPP] [WIDTH] [REF_SPP]

defaults 20 seeds, 64 spp, width 16, reference 16384 spp; CPU backend.

Per bundled scene (assets/*.gltf) and sampler (independent, sobol): SEEDS
renders of SPP samples with `--target-error 1e-12 --spp SPP` (so the render
runs SPP samples and `--stats` reports `estimated_relmse`, the estimate the
stopping rule reads), each measured against a reference of REF_SPP samples
(independent sampler, another seed) by `glint diff --json` (`relmse`, the
contract's relMSE); the reference's own error, REF_SPP / SPP times smaller,
is subtracted with its estimate. The ratio is mean estimated / mean true
relMSE over the seeds: 1 is an honest estimate, above 1 a conservative one
(stopping late), below 1 premature stopping.

Prints a Markdown table (docs/benchmarks.md holds the measured one).
"""
import glob
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GLINT = os.path.join(ROOT, "target", "release", "glint")


def render(scene, out, spp, seed, sampler, width, stats=None):
    cmd = [GLINT, "render", scene, "--backend", "cpu", "--width", str(width), "--spp", str(spp),
           "--seed", str(seed), "--sampler", sampler, "--variance", "--quiet", "-o", out]
    if stats:
        cmd += ["--target-error", "1e-12", "--stats", stats]
    subprocess.run(cmd, check=True)


def main():
    arg = lambda i, d: int(sys.argv[i]) if len(sys.argv) > i else d
    seeds, spp, width, ref_spp = arg(1, 20), arg(2, 64), arg(3, 16), arg(4, 16384)
    work = os.path.join(ROOT, "target", "calibrate-error")
    os.makedirs(work, exist_ok=True)
    rows = []
    for scene in sorted(glob.glob(os.path.join(ROOT, "assets", "*.gltf"))):
        name = os.path.basename(scene)[:-5]
        ref = os.path.join(work, f"{name}-ref.exr")
        ref_stats = os.path.join(work, f"{name}-ref.json")
        render(scene, ref, ref_spp, 999, "independent", width, ref_stats)
        ref_est = json.load(open(ref_stats))["estimated_relmse"]
        for sampler in ["independent", "sobol"]:
            est, true = [], []
            for seed in range(1, seeds + 1):
                out = os.path.join(work, f"{name}-{sampler}.exr")
                stats = os.path.join(work, f"{name}-{sampler}.json")
                render(scene, out, spp, seed, sampler, width, stats)
                est.append(json.load(open(stats))["estimated_relmse"])
                d = os.path.join(work, "diff.json")
                subprocess.run([GLINT, "diff", out, ref, "--json", d], capture_output=True)
                true.append(max(json.load(open(d))["relmse"] - ref_est, 1e-30))
            e, t = sum(est) / seeds, sum(true) / seeds
            rows.append((name, sampler, e, t, e / t))
            print(f"{name} {sampler}: estimated {e:.3e} true {t:.3e} ratio {e / t:.2f}",
                  file=sys.stderr)
    print(f"\n{seeds} seeds of {spp} spp per scene and sampler, width {width}, CPU, reference "
          f"{ref_spp} spp\n")
    print("| scene | sampler | estimated relMSE | true relMSE | estimated / true |")
    print("|---|---|---|---|---|")
    for name, sampler, e, t, r in rows:
        print(f"| {name} | {sampler} | {e:.3e} | {t:.3e} | {r:.2f} |")


if __name__ == "__main__":
    main()
