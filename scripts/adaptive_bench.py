#!/usr/bin/env python3
"""Adaptive against uniform sampling at equal cost (issue 23), per bundled
scene and backend, through `glint converge` in one run.

    cargo build --release && python3 scripts/adaptive_bench.py [WIDTH] [SPP] [REF_SPP] [T] [BACKENDS]

defaults width 32, --spp 64,256, reference 4096 spp, --adaptive 0.05,
backends cpu,gpu. Per scene one `glint converge` with, per backend, a
uniform variant and an `--adaptive T` variant (each --spp budget its cap);
the efficiency is 1 / (relMSE x seconds) of the render at the largest cap,
and the ratio adaptive / uniform above 1 means adaptive sampling wins at
equal time. Prints a Markdown table (docs/benchmarks.md holds the measured one).
"""
import csv
import glob
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GLINT = os.path.join(ROOT, "target", "release", "glint")


def main():
    width = sys.argv[1] if len(sys.argv) > 1 else "32"
    spp = sys.argv[2] if len(sys.argv) > 2 else "64,256"
    ref = sys.argv[3] if len(sys.argv) > 3 else "4096"
    t = sys.argv[4] if len(sys.argv) > 4 else "0.05"
    backends = (sys.argv[5] if len(sys.argv) > 5 else "cpu,gpu").split(",")
    work = os.path.join(ROOT, "target", "adaptive-bench")
    rows = []
    for scene in sorted(glob.glob(os.path.join(ROOT, "assets", "*.gltf"))):
        name = os.path.basename(scene)[:-5]
        out = os.path.join(work, name)
        cmd = [GLINT, "converge", scene, "-o", out, "--width", width, "--spp", spp,
               "--reference-spp", ref]
        for b in backends:
            cmd += ["--variant", f"{b}-uniform=--backend {b}",
                    "--variant", f"{b}-adaptive=--backend {b} --adaptive {t}"]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            print(f"{name}: {r.stderr.strip().splitlines()[-1]}", file=sys.stderr)
            continue
        last = {}
        for row in csv.DictReader(open(os.path.join(out, "converge.csv"))):
            last[row["variant"]] = row  # the largest cap comes last
        for b in backends:
            u, a = last[f"{b}-uniform"], last[f"{b}-adaptive"]
            eff = lambda x: 1.0 / (float(x["relmse"]) * float(x["seconds"]))
            rows.append((name, b, u, a, eff(a) / eff(u)))
        print(f"{name} done", file=sys.stderr)
    cap = spp.split(",")[-1]
    print(f"\n`glint converge` per scene, width {width}, caps {spp}, reference {ref} spp, "
          f"`--adaptive {t}`; figures at the {cap}-spp cap\n")
    print("| scene | backend | uniform relMSE | uniform s | adaptive mean spp | adaptive relMSE "
          "| adaptive s | efficiency adaptive / uniform |")
    print("|---|---|---|---|---|---|---|---|")
    for name, b, u, a, ratio in rows:
        print(f"| {name} | {b} | {float(u['relmse']):.3e} | {float(u['seconds']):.3f} | "
              f"{float(a['spp']):.1f} | {float(a['relmse']):.3e} | {float(a['seconds']):.3f} | "
              f"{ratio:.2f} |")


if __name__ == "__main__":
    main()
