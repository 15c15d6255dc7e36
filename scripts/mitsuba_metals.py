#!/usr/bin/env python3
"""The named metals' RGB complex IORs as Mitsuba 3 renders them.

Mitsuba 3's `conductor` (and `roughconductor`) `material` names load its
measured spectra (eta, k) and, in its RGB variants, convert each to linear
sRGB (the spectrum integrated against the CIE 1931 matching functions).
This prints those RGB values from Mitsuba itself (`mi.traverse` of the
loaded BSDF, `scalar_rgb`), the table `cpu/src/bsdf/tables.rs` holds and
`cpu/tests/named_metals.rs` pins, so a scene that names "Au" renders the
gold Mitsuba renders.

Runs in the venv of scripts/mitsuba_bench.py (made there on first use):
  target/mitsuba-venv/bin/python scripts/mitsuba_metals.py
Names Mitsuba cannot load (V in 3.9.1) or whose RGB eta has a zero channel
(AlSb: a clamped out-of-gamut spectrum; glint's conductor needs eta > 0)
are reported and left out.
"""

import mitsuba as mi

mi.set_variant("scalar_rgb")
# Its out-of-gamut clamping warnings would interleave with the rows.
mi.set_log_level(mi.LogLevel.Error)

NAMES = ["a-C", "Ag", "Al", "AlAs", "AlSb", "Au", "Be", "Cr", "CsI", "Cu", "Cu2O", "CuO",
         "d-C", "Hg", "HgTe", "Ir", "K", "Li", "MgO", "Mo", "Na_palik", "Nb", "Ni_palik", "Rh",
         "Se", "SiC", "SnTe", "Ta", "Te", "ThF4", "TiC", "TiN", "TiO2", "VC", "V", "VN", "W"]

print(f"// Mitsuba {mi.__version__}, scalar_rgb")
for name in NAMES:
    try:
        params = mi.traverse(mi.load_dict({"type": "conductor", "material": name}))
    except Exception as e:  # noqa: BLE001 - report and go on
        print(f"// {name}: not loaded ({str(e).splitlines()[0][:60]})")
        continue
    eta = [float(x) for x in params["eta.value"]]
    k = [float(x) for x in params["k.value"]]
    if min(eta) <= 0.0:
        print(f"// {name}: eta {eta} has a zero channel, left out")
        continue
    f = lambda v: ", ".join(f"{x:.6}" for x in v)  # noqa: E731
    print(f'("{name}", [{f(eta)}], [{f(k)}]),')
