#!/usr/bin/env python3
"""glint's CPU backend against Mitsuba 3 (llvm_ad_rgb) on the bundled scenes,
in one run on one machine: time per sample and efficiency at equal error.

For every scene: `glint export` writes the prepared scene as Mitsuba XML (the
same geometry, camera, lights and image; Mitsuba's own BSDFs exactly, the
glTF materials approximated, with warnings; the textures as bitmaps). Each renderer renders a
high-spp reference of its own scene and ROUNDS timed renders at SPP (other
seeds); relMSE (the contract's) of each render against its own reference,
and of Mitsuba's reference against glint's (how far the translation is from
exact: near the references' own noise where the models are Mitsuba's).
Efficiency is 1 / (relMSE x seconds); the ratio glint / Mitsuba says how
many times faster glint reaches the same error (> 1: glint ahead).

Timing: glint's `--stats` render_seconds (sampling only, all cores);
Mitsuba's `mi.render` after a warm-up render of the same size and spp (its
LLVM kernels compiled and cached), with `dr.eval` and `dr.sync_thread`, all
cores. Medians of the rounds.

Set-up (first run): a venv under target/mitsuba-venv with mitsuba and numpy
from PyPI, and Debian's libllvm19 (Dr.Jit's LLVM backend needs LLVM >= 16;
bookworm's default 14/15 fail to select `fminimum`) installed with apt from
the machine's own sources where it is missing.

Usage: [GLINT_BIN=target/pgo/release/glint] python3 scripts/mitsuba_bench.py [SPP] [WIDTH] [REF_SPP] [ROUNDS] [SCENES]
  defaults: 256 spp, 128 px, 4096 reference spp, 3 rounds, every assets/*.gltf
Output: target/mitsuba-bench/ (scenes, images, table.md); the table on stdout.
"""

import glob
import hashlib
import json
import os
import shutil
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "target", "mitsuba-bench")
VENV = os.path.join(ROOT, "target", "mitsuba-venv")
# GLINT_BIN: the glint binary to time (say scripts/build.sh's PGO build),
# used as it is; by default the plain release build, built here.
GLINT_BIN = os.environ.get("GLINT_BIN")
GLINT = GLINT_BIN or os.path.join(ROOT, "target", "release", "glint")
MITSUBA_VERSION = "3.9.1"


def export_digest(d):
    """A digest of what `glint export` wrote into `d` (scene.xml, meshes,
    textures): the references are kept under it, so a scene, a translation
    or a loader that changes makes new ones. (A change to glint's renderer
    that changes its images needs `rm -r target/mitsuba-bench`.)"""
    h = hashlib.sha256()
    files = [os.path.join(d, "scene.xml")]
    for sub in ("meshes", "textures"):
        files += sorted(glob.glob(os.path.join(d, sub, "*")))
    for f in files:
        h.update(os.path.relpath(f, d).encode())
        with open(f, "rb") as fh:
            h.update(fh.read())
    return h.hexdigest()[:12]


def run(cmd, **kw):
    return subprocess.run(cmd, check=True, **kw)


def libllvm():
    """The newest libLLVM >= 16 on the machine, installing libllvm19 if none."""
    def find():
        best = None
        for p in glob.glob("/usr/lib/x86_64-linux-gnu/libLLVM*.so*"):
            name = os.path.basename(p)
            digits = "".join(c if c.isdigit() else " " for c in name).split()
            if digits and int(digits[0]) >= 16:
                if best is None or int(digits[0]) > best[0]:
                    best = (int(digits[0]), p)
        return best[1] if best else None

    path = find()
    if path is None:
        sudo = [] if os.geteuid() == 0 else ["sudo"]
        env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
        run(sudo + ["apt-get", "update", "-qq"], env=env)
        run(sudo + ["apt-get", "install", "-y", "-qq", "libllvm19"], env=env,
            stdout=subprocess.DEVNULL)
        path = find()
    if path is None:
        sys.exit("mitsuba_bench: no libLLVM >= 16 found or installable")
    return path


def python():
    py = os.path.join(VENV, "bin", "python")
    if not os.path.exists(py):
        run([sys.executable, "-m", "venv", VENV])
    probe = subprocess.run([py, "-c", "import mitsuba; print(mitsuba.__version__)"],
                           capture_output=True, text=True)
    if probe.returncode != 0 or probe.stdout.strip() != MITSUBA_VERSION:
        run([py, "-m", "pip", "install", "-q", f"mitsuba=={MITSUBA_VERSION}", "numpy"])
    return py


# Runs inside the venv: render a Mitsuba scene, print JSON {seconds}.
MITSUBA_RENDER = r"""
import json, sys, time
import drjit as dr, mitsuba as mi, numpy as np
mi.set_variant('llvm_ad_rgb')
xml, spp, out, seeds, mode = sys.argv[1], int(sys.argv[2]), sys.argv[3], [int(s) for s in sys.argv[4].split(',')], sys.argv[5]
scene = mi.load_file(xml)
warm = mi.render(scene, spp=spp, seed=10**6)
dr.eval(warm); dr.sync_thread()
times, total = [], None
for seed in seeds:
    t = time.perf_counter()
    img = mi.render(scene, spp=spp, seed=seed)
    dr.eval(img); dr.sync_thread()
    times.append(time.perf_counter() - t)
    if mode == 'mean':
        a = np.array(img, dtype=np.float64)
        total = a if total is None else total + a
    else:
        mi.util.write_bitmap(out.replace('SEED', str(seed)), img)
if mode == 'mean':
    mi.util.write_bitmap(out, mi.TensorXf((total / len(seeds)).astype(np.float32)))
print(json.dumps({'seconds': times}))
"""


def relmse(a, b):
    """The contract's relMSE of image `b` against reference `a` (glint diff)."""
    j = os.path.join(OUT, "diff.json")
    subprocess.run([GLINT, "diff", a, b, "--json", j, "--max-relmse", "1e30"],
                   check=True, capture_output=True)
    with open(j) as f:
        return json.load(f)["relmse"]


def glint_render(scene, width, spp, seed, out):
    stats = out + ".json"
    run([GLINT, "render", scene, "-o", out, "--backend", "cpu", "--width", str(width),
         "--spp", str(spp), "--seed", str(seed), "--stats", stats, "--quiet"])
    with open(stats) as f:
        return json.load(f)["render_seconds"]


def mitsuba_render(py, env, xml, spp, out, seeds, mean=False):
    """Render `xml` once per seed to `out` (SEED replaced by the seed), or
    with `mean`, the mean of those renders to `out` (a reference in passes
    of `spp`, so the wavefront stays the timed renders' size)."""
    r = subprocess.run([py, "-c", MITSUBA_RENDER, xml, str(spp), out,
                        ",".join(map(str, seeds)), "mean" if mean else "each"],
                       check=True, capture_output=True, text=True, env=env)
    return json.loads(r.stdout.strip().splitlines()[-1])["seconds"]


def main():
    args = sys.argv[1:]
    spp = int(args[0]) if len(args) > 0 else 256
    width = int(args[1]) if len(args) > 1 else 128
    ref_spp = int(args[2]) if len(args) > 2 else 4096
    rounds = int(args[3]) if len(args) > 3 else 3
    scenes = (args[4].split(",") if len(args) > 4
              else sorted(glob.glob(os.path.join(ROOT, "assets", "*.gltf"))))
    os.makedirs(OUT, exist_ok=True)
    if not GLINT_BIN:
        run(["cargo", "build", "--release", "--locked", "--quiet"], cwd=ROOT)
    py = python()
    env = dict(os.environ, DRJIT_LIBLLVM_PATH=libllvm())
    started = time.strftime("%Y-%m-%d")
    rows = []
    for scene in scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        d = os.path.join(OUT, name)
        for sub in ("meshes", "textures"):  # a previous export's files
            shutil.rmtree(os.path.join(d, sub), ignore_errors=True)
        ex = subprocess.run([GLINT, "export", scene, "-o", d, "--width", str(width),
                             "--spp", str(spp)], capture_output=True, text=True)
        if ex.returncode != 0:
            print(f"{name}: export failed: {ex.stderr.strip()}", file=sys.stderr)
            continue
        approximate = sum(1 for l in ex.stderr.splitlines() if "warning" in l)
        xml = os.path.join(d, "scene.xml")
        key = export_digest(d)
        g_ref = os.path.join(d, f"glint-ref-{width}-{ref_spp}-{key}.exr")
        m_ref = os.path.join(d, f"mitsuba-ref-{width}-{ref_spp}-{key}.exr")
        if not os.path.exists(g_ref):
            glint_render(scene, width, ref_spp, 999_983, g_ref)
        if not os.path.exists(m_ref):
            passes = max(1, ref_spp // spp)
            mitsuba_render(py, env, xml, spp, m_ref, [999_000 + k for k in range(passes)],
                           mean=True)
        cross = relmse(g_ref, m_ref)
        seeds = [11 + r for r in range(rounds)]
        g_s, g_e = [], []
        for seed in seeds:
            img = os.path.join(d, f"glint-{seed}.exr")
            g_s.append(glint_render(scene, width, spp, seed, img))
            g_e.append(relmse(g_ref, img))
        m_s = mitsuba_render(py, env, xml, spp, os.path.join(d, "mitsuba-SEED.exr"), seeds)
        m_e = [relmse(m_ref, os.path.join(d, f"mitsuba-{s}.exr")) for s in seeds]
        gs, ge, ms, me = map(statistics.median, (g_s, g_e, m_s, m_e))
        rows.append((name, approximate, cross, gs, ms, ge, me,
                     ms / gs, me / ge, (me * ms) / (ge * gs)))
        print(f"{name}: glint {gs:.3f} s relMSE {ge:.3e}; mitsuba {ms:.3f} s relMSE {me:.3e}",
              file=sys.stderr)
    binary = f"GLINT_BIN={os.path.relpath(GLINT, ROOT)} " if GLINT_BIN else ""
    lines = [
        f"`{binary}python3 scripts/mitsuba_bench.py {spp} {width} {ref_spp} {rounds}` on {started}, "
        f"{os.cpu_count()} cores: glint CPU backend (all cores, Sobol) against Mitsuba "
        f"{MITSUBA_VERSION} `llvm_ad_rgb` (all cores, independent sampler), {width} px wide, "
        f"{spp} spp, medians of {rounds} renders; references {ref_spp} spp, each renderer its own.",
        "",
        "| scene | approximations | relMSE Mitsuba ref vs glint ref | glint s | Mitsuba s | "
        "glint relMSE | Mitsuba relMSE | speed per sample glint/Mitsuba | relMSE Mitsuba/glint | "
        "efficiency glint/Mitsuba |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(f"| {r[0]} | {r[1]} | {r[2]:.2e} | {r[3]:.3f} | {r[4]:.3f} | {r[5]:.3e} | "
                     f"{r[6]:.3e} | {r[7]:.2f} | {r[8]:.2f} | {r[9]:.2f} |")
    if rows:
        eff = sorted(r[9] for r in rows)
        sp = sorted(r[7] for r in rows)
        lines += ["", f"Efficiency glint/Mitsuba: median {statistics.median(eff):.2f} "
                  f"(range {eff[0]:.2f}-{eff[-1]:.2f}); speed per sample median "
                  f"{statistics.median(sp):.2f} (range {sp[0]:.2f}-{sp[-1]:.2f})."]
    table = "\n".join(lines) + "\n"
    with open(os.path.join(OUT, "table.md"), "w") as f:
        f.write(table)
    print(table)


if __name__ == "__main__":
    main()
