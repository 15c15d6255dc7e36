//! `named_metal` pinned to its sources, not to itself.
//!
//! - The values: Mitsuba 3.9.1's, as its RGB variants render its
//!   `conductor` `material` names (the measured spectra converted to linear
//!   sRGB), printed by `scripts/mitsuba_metals.py` from Mitsuba itself and
//!   copied into [`MITSUBA`] below.
//! - Their colour: the same metals' spectra at 650, 550 and 450 nm from
//!   the literature, independent of Mitsuba: pbrt-v4's measured spectra
//!   for Au, Ag, Cu, Al (`src/pbrt/util/spectrum.cpp`, arrays `Au_eta`,
//!   `Au_k`, ..., interleaved (wavelength nm, value) pairs; only the
//!   samples bracketing 450, 550 and 650 nm are copied here, interpolated
//!   linearly as pbrt's `PiecewiseLinearSpectrum` does) and the
//!   Lorentz-Drude model of Rakic, Djurisic, Elazar & Majewski, Appl. Opt.
//!   37, 5271 (1998) for Cr (omega_p = 10.75 eV, f0 = 0.168, Gamma0 = 0.047
//!   eV and four Lorentz oscillators; also in MEEP's materials library). A
//!   point sample is not the spectrum's RGB colour, so the check is loose
//!   (normal-incidence reflectance within 0.07 per channel), but it catches
//!   a swapped channel, another metal or a typo.
//!
//! The doc comment's table in `cpu/src/bsdf/tables.rs` is parsed and its
//! eta, k and normal-incidence reflectance columns are checked too.

use glint_cpu::bsdf::named_metal;

/// Wavelengths of the channels, nm.
const LAMBDA: [f64; 3] = [650.0, 550.0, 450.0];

/// The two tabulated (lambda, value) samples of pbrt-v4's arrays that
/// bracket each of 650, 550 and 450 nm, in that order.
type Brackets = [[(f64, f64); 2]; 3];

const AU_ETA: Brackets = [
    [(635.816284, 0.177750), (652.548279, 0.166000)],
    [(539.061646, 0.402000), (551.040771, 0.345500)],
    [(442.800629, 1.562000), (450.851562, 1.502125)],
];
const AU_K: Brackets = [
    [(635.816284, 3.070000), (652.548279, 3.150000)],
    [(539.061646, 2.540000), (551.040771, 2.730625)],
    [(442.800629, 1.904000), (450.851562, 1.875875)],
];
const AG_ETA: Brackets = [
    [(635.816284, 0.136125), (652.548279, 0.140000)],
    [(539.061646, 0.129000), (551.040771, 0.124375)],
    [(442.800629, 0.157000), (450.851562, 0.151063)],
];
const AG_K: Brackets = [
    [(635.816284, 4.010625), (652.548279, 4.150000)],
    [(539.061646, 3.250000), (551.040771, 3.348125)],
    [(442.800629, 2.400000), (450.851562, 2.478750)],
];
const CU_ETA: Brackets = [
    [(635.816284, 0.230813), (652.548279, 0.214000)],
    [(539.061646, 1.040000), (551.040771, 0.950375)],
    [(442.800629, 1.170000), (450.851562, 1.165312)],
];
const CU_K: Brackets = [
    [(635.816284, 3.458187), (652.548279, 3.670000)],
    [(539.061646, 2.583000), (551.040771, 2.576500)],
    [(442.800629, 2.362000), (450.851562, 2.397625)],
];
const AL_ETA: Brackets = [
    [(635.816284, 1.390000), (652.548279, 1.490000)],
    [(539.061646, 0.912000), (551.040771, 0.963000)],
    [(442.800629, 0.598000), (450.851562, 0.620313)],
];
const AL_K: Brackets = [
    [(635.816284, 7.650000), (652.548279, 7.820000)],
    [(539.061646, 6.550000), (551.040771, 6.700000)],
    [(442.800629, 5.380000), (450.851562, 5.480000)],
];

/// Linear interpolation of the bracketing samples at the channel's
/// wavelength (checking that they do bracket it).
fn interp(b: &Brackets, c: usize) -> f64 {
    let [(l0, v0), (l1, v1)] = b[c];
    let l = LAMBDA[c];
    assert!(l0 <= l && l <= l1, "{l} not in [{l0}, {l1}]");
    v0 + (l - l0) / (l1 - l0) * (v1 - v0)
}

/// A minimal complex number for the Lorentz-Drude model.
#[derive(Clone, Copy, Debug)]
struct C(f64, f64);

impl C {
    fn add(self, o: C) -> C {
        C(self.0 + o.0, self.1 + o.1)
    }
    fn mul(self, o: C) -> C {
        C(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
    }
    fn div(self, o: C) -> C {
        let d = o.0 * o.0 + o.1 * o.1;
        C(
            (self.0 * o.0 + self.1 * o.1) / d,
            (self.1 * o.0 - self.0 * o.1) / d,
        )
    }
    /// Principal square root (real part >= 0; imaginary part with the
    /// sign of the argument's, so k >= 0 for Im eps >= 0).
    fn sqrt(self) -> C {
        let r = (self.0 * self.0 + self.1 * self.1).sqrt();
        C(
            ((r + self.0) / 2.0).sqrt(),
            ((r - self.0) / 2.0).sqrt().copysign(self.1),
        )
    }
}

/// Rakic et al. 1998, LD model, Cr: plasma frequency (eV), Drude strength
/// and damping (eV), then the oscillators (f_j, Gamma_j eV, omega_j eV).
const CR_WP: f64 = 10.75;
const CR_F0: f64 = 0.168;
const CR_G0: f64 = 0.047;
const CR_OSC: [(f64, f64, f64); 4] = [
    (0.151, 3.175, 0.121),
    (0.150, 1.305, 0.543),
    (1.149, 2.676, 1.970),
    (0.825, 1.335, 8.775),
];

/// n + i k of Cr at `lambda` nm from the Lorentz-Drude model:
/// eps = 1 - f0 wp^2 / (w (w + i G0)) + sum f_j wp^2 / (w_j^2 - w^2 - i w G_j).
fn cr_nk(lambda: f64) -> (f64, f64) {
    let w = 1239.84193 / lambda; // hbar omega, eV
    let wp2 = CR_WP * CR_WP;
    let mut eps = C(1.0, 0.0).add(C(-CR_F0 * wp2, 0.0).div(C(w, 0.0).mul(C(w, CR_G0))));
    for (f, g, wj) in CR_OSC {
        eps = eps.add(C(f * wp2, 0.0).div(C(wj * wj - w * w, -w * g)));
    }
    let n = eps.sqrt();
    assert!(n.1 >= 0.0);
    (n.0, n.1)
}

/// Normal-incidence reflectance of a conductor.
fn r0(eta: f64, k: f64) -> f64 {
    ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k)
}

/// The literature's (eta, k) per channel for each metal symbol.
fn literature(metal: &str) -> [(f64, f64); 3] {
    let from = |e: &Brackets, k: &Brackets| std::array::from_fn(|c| (interp(e, c), interp(k, c)));
    match metal {
        "Au" => from(&AU_ETA, &AU_K),
        "Ag" => from(&AG_ETA, &AG_K),
        "Cu" => from(&CU_ETA, &CU_K),
        "Al" => from(&AL_ETA, &AL_K),
        "Cr" => std::array::from_fn(|c| cr_nk(LAMBDA[c])),
        _ => unreachable!(),
    }
}

const METALS: [(&str, &str); 5] = [
    ("Au", "gold"),
    ("Ag", "silver"),
    ("Cu", "copper"),
    ("Al", "aluminium"),
    ("Cr", "chromium"),
];

/// Mitsuba 3.9.1's RGB (eta, k) of the contract's five metals and a few
/// more, as `scripts/mitsuba_metals.py` printed them (six significant
/// digits).
const MITSUBA: [(&str, [f64; 3], [f64; 3]); 8] = [
    (
        "Au",
        [0.143036, 0.375307, 1.44205],
        [3.983, 2.38556, 1.60336],
    ),
    (
        "Ag",
        [0.155276, 0.116728, 0.138388],
        [4.82835, 3.12222, 2.1469],
    ),
    (
        "Cu",
        [0.201005, 0.92375, 1.10222],
        [3.91326, 2.45305, 2.14209],
    ),
    ("Al", [1.6575, 0.880405, 0.521244], [9.22381, 6.2695, 4.837]),
    ("Cr", [4.36967, 2.91651, 1.6549], [5.20655, 4.23131, 3.7547]),
    (
        "W",
        [4.37082, 3.30025, 2.99841],
        [3.50064, 2.60487, 2.27323],
    ),
    (
        "Ni_palik",
        [2.3673, 1.66337, 1.46708],
        [4.49881, 3.05015, 2.34544],
    ),
    ("CsI", [2.1449, 1.70232, 1.66243], [0.0, 0.0, 0.0]),
];

#[test]
fn table_is_mitsubas() {
    for (sym, eta, k) in MITSUBA {
        let (te, tk) = named_metal(sym).unwrap_or_else(|| panic!("{sym} missing"));
        for c in 0..3 {
            let close = |t: f32, m: f64| (t as f64 - m).abs() <= 1e-6 * m.abs().max(1e-3);
            assert!(
                close(te[c], eta[c]),
                "{sym} eta[{c}]: {} vs Mitsuba {}",
                te[c],
                eta[c]
            );
            assert!(
                close(tk[c], k[c]),
                "{sym} k[{c}]: {} vs Mitsuba {}",
                tk[c],
                k[c]
            );
        }
    }
    for (sym, alias) in METALS {
        assert_eq!(named_metal(alias), named_metal(sym), "{alias}");
        assert_eq!(named_metal(&sym.to_lowercase()), named_metal(sym));
    }
    // AlSb's RGB eta has a zero channel in Mitsuba: left out, an error.
    assert!(named_metal("AlSb").is_none());
}

#[test]
fn table_keeps_the_literatures_colour() {
    let mut failures = Vec::new();
    for (sym, _) in METALS {
        let (eta, k) = named_metal(sym).unwrap();
        let lit = literature(sym);
        for c in 0..3 {
            let table = r0(eta[c] as f64, k[c] as f64);
            let point = r0(lit[c].0, lit[c].1);
            eprintln!(
                "{sym} {} nm: table R {table:.3}, literature R {point:.3}",
                LAMBDA[c]
            );
            if (table - point).abs() > 0.07 {
                failures.push(format!(
                    "{sym} channel {c}: R {table:.3} vs the spectrum's {point:.3} at {} nm",
                    LAMBDA[c]
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The interpolation and the LD model themselves, against independent
/// anchors: pbrt-v4's sample at 551.04 nm is gold's (0.3455, 2.730625)
/// exactly (quoted in bsdf_physics' fresnel test), and Cr's dielectric
/// function at 550 nm is a strongly absorbing metal's (Re eps < 0).
#[test]
fn literature_helpers_are_sane() {
    assert_eq!(AU_ETA[1][1], (551.040771, 0.3455));
    assert_eq!(AU_K[1][1], (551.040771, 2.730625));
    // Interpolation at a tabulated wavelength returns the sample.
    let b: Brackets = [[(600.0, 1.0), (700.0, 3.0)]; 3];
    assert!((interp(&b, 0) - 2.0).abs() < 1e-12);
    // Cr: n^2 - k^2 = Re eps < 0 in the visible (a metal), k > n / 2.
    for l in LAMBDA {
        let (n, k) = cr_nk(l);
        assert!(n * n - k * k < 0.0 && k > 0.5 * n, "{l}: {n} {k}");
    }
    // The principal root: sqrt(-1) = i, sqrt(i) = (1 + i)/sqrt 2.
    let s = C(-1.0, 0.0).sqrt();
    assert!(s.0.abs() < 1e-15 && (s.1 - 1.0).abs() < 1e-15);
    let s = C(0.0, 1.0).sqrt();
    assert!((s.0 - s.1).abs() < 1e-15 && (s.0 - 0.5f64.sqrt()).abs() < 1e-15);
}

/// The doc comment's table of `cpu/src/bsdf/tables.rs`: its eta and k
/// columns equal the table, and its normal-incidence R column equals
/// ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2) of the table's values within
/// half a unit of its third printed decimal: every entry is the correctly
/// rounded value (this test once found a doubly rounded 0.848 for 0.84748).
#[test]
fn doc_table_columns() {
    let src = include_str!("../src/bsdf/tables.rs");
    let mut seen = 0;
    for line in src.lines() {
        let Some(rest) = line.trim().strip_prefix("/// |") else {
            continue;
        };
        let cols: Vec<&str> = rest.split('|').map(str::trim).collect();
        let Some(&(sym, _)) = METALS.iter().find(|(s, _)| *s == cols[0]) else {
            continue;
        };
        let nums =
            |s: &str| -> Vec<f64> { s.split_whitespace().map(|x| x.parse().unwrap()).collect() };
        let (de, dk, dr) = (nums(cols[1]), nums(cols[2]), nums(cols[3]));
        assert_eq!((de.len(), dk.len(), dr.len()), (3, 3, 3), "{line}");
        let (eta, k) = named_metal(sym).unwrap();
        for c in 0..3 {
            assert!(
                (de[c] - eta[c] as f64).abs() < 1e-6,
                "{sym} doc eta {} vs table {}",
                de[c],
                eta[c]
            );
            assert!(
                (dk[c] - k[c] as f64).abs() < 1e-6,
                "{sym} doc k {} vs table {}",
                dk[c],
                k[c]
            );
            let want = r0(eta[c] as f64, k[c] as f64);
            let rounded = (want * 1e3).round() / 1e3;
            eprintln!(
                "{sym} channel {c}: doc R {:.3} table R {want:.5}{}",
                dr[c],
                if (rounded - dr[c]).abs() > 1e-9 {
                    format!("  (rounds to {rounded:.3})")
                } else {
                    String::new()
                }
            );
            assert!(
                (dr[c] - want).abs() <= 5e-4 + 1e-9,
                "{sym} channel {c}: doc R {} vs the table's {want:.5}",
                dr[c]
            );
        }
        seen += 1;
    }
    assert_eq!(seen, METALS.len(), "doc table rows found");
}

/// `docs/metals.md` lists every name with the table's values, and every
/// name it lists is taken.
#[test]
fn docs_list_every_metal() {
    let doc = include_str!("../../docs/metals.md");
    let mut names = 0;
    for line in doc.lines() {
        let cols: Vec<&str> = line.split('|').map(str::trim).collect();
        if cols.len() != 6 || cols[1] == "name" || cols[1].starts_with("---") {
            continue;
        }
        let (eta, k) = named_metal(cols[1]).unwrap_or_else(|| panic!("{} not taken", cols[1]));
        let nums =
            |s: &str| -> Vec<f32> { s.split_whitespace().map(|x| x.parse().unwrap()).collect() };
        assert_eq!(nums(cols[2]), eta.to_array(), "{line}");
        assert_eq!(nums(cols[3]), k.to_array(), "{line}");
        names += 1;
    }
    assert_eq!(names, 35, "rows in docs/metals.md");
}
