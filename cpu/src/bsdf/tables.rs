//! Named indices of refraction and named metals.

use glam::Vec3;

/// Mitsuba 3's table of named dielectric IORs (its `dielectric` plugin
/// documentation), plus the contract's aliases `ice` and `crown glass`.
/// Names are matched case-insensitively.
const IORS: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.333),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.47),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("crown glass", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.575),
    ("diamond", 2.419),
];

pub(crate) fn ior(name: &str) -> Option<f32> {
    let name = name.trim();
    IORS.iter()
        .find(|(n, _)| n.eq_ignore_ascii_case(name))
        .map(|&(_, v)| v)
}

/// Named metals: RGB complex IOR (eta, k) relative to vacuum, the channels
/// being the spectral values at 650 nm (R), 550 nm (G) and 450 nm (B).
///
/// | metal | eta (650/550/450 nm)   | k (650/550/450 nm)     | normal-incidence R |
/// |-------|------------------------|------------------------|--------------------|
/// | Au    | 0.1678 0.3504 1.5085   | 3.1378 2.7141 1.8788   | 0.940 0.847 0.386  |
/// | Ag    | 0.1394 0.1248 0.1517   | 4.1288 3.3396 2.4704   | 0.970 0.960 0.918  |
/// | Cu    | 0.2166 0.9582 1.1658   | 3.6377 2.5771 2.3939   | 0.941 0.634 0.553  |
/// | Al    | 1.4748 0.9586 0.6180   | 7.7941 6.6870 5.4694   | 0.912 0.921 0.924  |
/// | Cr    | 3.5348 2.9007 2.1448   | 4.3476 4.2311 3.8623   | 0.642 0.650 0.654  |
///
/// Sources:
/// - Au, Ag, Cu, Al: the measured spectra pbrt-v4 ships as `metal-Au-eta`,
///   `metal-Au-k`, ... (`src/pbrt/util/spectrum.cpp`, arrays `Au_eta`,
///   `Au_k`, `Ag_*`, `Cu_*`, `Al_*`), linearly interpolated between the
///   tabulated wavelengths around 650, 550 and 450 nm.
/// - Cr (absent from pbrt-v4's tables): the Lorentz-Drude model of Rakic,
///   Djurisic, Elazar & Majewski, "Optical properties of metallic films for
///   vertical-cavity optoelectronic devices", Appl. Opt. 37, 5271 (1998),
///   table for Cr (omega_p = 10.75 eV, f0 = 0.168, Gamma0 = 0.047 eV, four
///   oscillators), eps(omega) evaluated at the three wavelengths and
///   n + i k = sqrt(eps).
///
/// The R column is ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2), the conductor
/// Fresnel term at normal incidence (a test checks the code against it).
const METALS: &[(&[&str], [f32; 3], [f32; 3])] = &[
    (
        &["au", "gold"],
        [0.1678, 0.3504, 1.5085],
        [3.1378, 2.7141, 1.8788],
    ),
    (
        &["ag", "silver"],
        [0.1394, 0.1248, 0.1517],
        [4.1288, 3.3396, 2.4704],
    ),
    (
        &["cu", "copper"],
        [0.2166, 0.9582, 1.1658],
        [3.6377, 2.5771, 2.3939],
    ),
    (
        &["al", "aluminium", "aluminum"],
        [1.4748, 0.9586, 0.6180],
        [7.7941, 6.6870, 5.4694],
    ),
    (
        &["cr", "chromium"],
        [3.5348, 2.9007, 2.1448],
        [4.3476, 4.2311, 3.8623],
    ),
];

pub(crate) fn metal(name: &str) -> Option<(Vec3, Vec3)> {
    let name = name.trim();
    METALS
        .iter()
        .find(|(names, _, _)| names.iter().any(|n| n.eq_ignore_ascii_case(name)))
        .map(|&(_, eta, k)| (Vec3::from(eta), Vec3::from(k)))
}
