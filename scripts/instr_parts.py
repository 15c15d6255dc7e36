#!/usr/bin/env python3
"""Where a sample's instructions go, from a callgrind profile of
`scripts/instr_count.sh` (collection switched on inside `trace_wave`).

Usage: scripts/instr_parts.py CALLGRIND_OUT STATS_JSON
Prints "part<TAB>instructions per sample" lines: the inclusive counts of the
functions the compiler keeps out of line, grouped by part (traversal by
query, light sampling, the Sobol numbers, the BSDFs' other models, the
shading frame, textures), and the rest of trace_wave (the camera, hit
points, MIS, ray offsets, the inlined Lambertian and everything else
inlined into it). None of the grouped functions calls another group's, so
the parts add up to the total. What a build inlines counts in the rest: the
profile-guided build inlines light sampling and the shading frame, so split
a plain build's profile.
"""
import collections
import json
import re
import sys

# Part, and a pattern of callgrind's demangled function names. The first
# part that matches a function takes it.
PARTS = [
    ("closest hit, one ray",
     r"wide_traverse::x86::intersect_(avx2|avx|sse2)$|wide_traverse::intersect(_masked)?$"),
    ("closest hit, camera packets", r"packet::x86::intersect_packet_avx2$"),
    ("any hit (shadow rays)",
     r"wide_traverse::x86::occluded_(avx2|avx|sse2)$|wide_traverse::(any_hit|occluded_masked)$"),
    ("light sampling", r"lights::Lights::sample$"),
    ("Sobol numbers", r"sobol::SampleBatch::bounces$|sobol::PathSampler::bounce$"),
    ("BSDFs out of line", r"bsdf::BsdfAt::(sample|eval|pdf)_any$"),
    ("shading frame", r"integrator::PathTracer::surface$"),
    ("textures", r"integrator::PathTracer::apply_textures$"),
]


def inclusive(path):
    """Per function: its own cost plus the inclusive cost of its calls (the
    cost line that follows each `calls=` line), and the profile's total."""
    names, cost = {}, collections.Counter()
    fn, total = "", 0
    with open(path) as f:
        for line in f:
            if line.startswith(("summary:", "totals:")):
                total = int(line.split()[1])
                continue
            m = re.match(r"(c?fn)=\((\d+)\)(?: (.*))?", line)
            if m:
                if m.group(3):
                    names[m.group(2)] = m.group(3).strip()
                if m.group(1) == "fn":
                    fn = names.get(m.group(2), "")
                continue
            if line[:1].isdigit() or line[:1] in "+-*":
                cost[fn] += int(line.split()[-1])
    return cost, total


def main():
    if len(sys.argv) != 3:
        print("usage: scripts/instr_parts.py CALLGRIND_OUT STATS_JSON", file=sys.stderr)
        sys.exit(2)
    cost, total = inclusive(sys.argv[1])
    samples = json.load(open(sys.argv[2]))["samples"]
    # A function's name ends before its " [binary]" or "'2" suffixes.
    base = {f: re.sub(r"(\s*\[.*\])?('\d+)?$", "", f) for f in cost}
    taken, rest = set(), total
    for part, pattern in PARTS:
        fns = {f for f in cost if f not in taken and re.search(pattern, base[f])}
        taken |= fns
        n = sum(cost[f] for f in fns)
        rest -= n
        print(f"{part}\t{n / samples:.0f}")
    print(f"the rest of trace_wave\t{rest / samples:.0f}")


if __name__ == "__main__":
    main()
