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

/// Named metals: RGB complex IOR (eta, k) relative to vacuum, as Mitsuba 3
/// renders its `conductor` `material` names in its RGB variants: its
/// measured spectra converted to linear sRGB (integrated against the CIE
/// 1931 matching functions), read from Mitsuba 3.9.1 itself by
/// `scripts/mitsuba_metals.py` (`mi.traverse` of the loaded BSDF,
/// `scalar_rgb`). So a scene that names "Au" renders the gold Mitsuba
/// renders. Every name Mitsuba 3.9.1 loads is here but AlSb (its RGB eta
/// has a zero channel, an out-of-gamut spectrum clamped); the contract's
/// five, with their full names as aliases:
///
/// | metal | eta (R G B)                | k (R G B)                  | normal-incidence R |
/// |-------|----------------------------|----------------------------|--------------------|
/// | Ag    | 0.155276 0.116728 0.138388 | 4.82835 3.12222 2.1469     | 0.975 0.958 0.906  |
/// | Al    | 1.6575 0.880405 0.521244   | 9.22381 6.2695 4.837       | 0.928 0.918 0.919  |
/// | Au    | 0.143036 0.375307 1.44205  | 3.983 2.38556 1.60336      | 0.967 0.802 0.324  |
/// | Cr    | 4.36967 2.91651 1.6549     | 5.20655 4.23131 3.7547     | 0.688 0.649 0.687  |
/// | Cu    | 0.201005 0.92375 1.10222   | 3.91326 2.45305 2.14209    | 0.952 0.620 0.511  |
///
/// Before, the channels were the spectra's values at 650, 550 and 450 nm
/// (pbrt-v4's tables; Cr from Rakic et al. 1998): the same metals, but a
/// point sample is not the colour the spectrum has, and gold's normal-
/// incidence reflectance differed from Mitsuba's by up to 0.062 (blue).
/// `cpu/tests/named_metals.rs` keeps those sources as a check of each
/// entry's channel order and magnitude.
///
/// The R column is ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2), the conductor
/// Fresnel term at normal incidence (a test checks it against the table).
const METALS: &[(&[&str], [f32; 3], [f32; 3])] = &[
    (
        &["a-c"],
        [2.94405, 2.22714, 1.96816],
        [0.887465, 0.799299, 0.81529],
    ),
    (
        &["ag", "silver"],
        [0.155276, 0.116728, 0.138388],
        [4.82835, 3.12222, 2.1469],
    ),
    (
        &["al", "aluminium", "aluminum"],
        [1.6575, 0.880405, 0.521244],
        [9.22381, 6.2695, 4.837],
    ),
    (
        &["alas"],
        [3.6053, 3.23294, 2.21632],
        [0.000679437, 0.0, 0.00751271],
    ),
    (
        &["au", "gold"],
        [0.143036, 0.375307, 1.44205],
        [3.983, 2.38556, 1.60336],
    ),
    (
        &["be"],
        [4.18501, 3.18503, 2.78406],
        [3.83547, 3.01012, 2.86899],
    ),
    (
        &["cr", "chromium"],
        [4.36967, 2.91651, 1.6549],
        [5.20655, 4.23131, 3.7547],
    ),
    (&["csi"], [2.1449, 1.70232, 1.66243], [0.0, 0.0, 0.0]),
    (
        &["cu", "copper"],
        [0.201005, 0.92375, 1.10222],
        [3.91326, 2.45305, 2.14209],
    ),
    (
        &["cu2o"],
        [3.55177, 2.94987, 2.75188],
        [0.114207, 0.193897, 0.606134],
    ),
    (
        &["cuo"],
        [3.24754, 2.44781, 2.21022],
        [0.52109, 0.570031, 0.722179],
    ),
    (&["d-c"], [2.70872, 2.31883, 2.2289], [0.0, 0.0, 0.0]),
    (
        &["hg"],
        [2.39894, 1.44003, 0.90957],
        [6.32759, 4.37192, 3.42176],
    ),
    (
        &["hgte"],
        [4.77904, 3.2312, 2.6599],
        [1.63161, 1.58081, 1.72929],
    ),
    (
        &["ir"],
        [3.0863, 2.08219, 1.61791],
        [5.59215, 4.06709, 3.26731],
    ),
    (
        &["k"],
        [0.0640432, 0.0464098, 0.0381849],
        [2.1042, 1.34894, 0.913126],
    ),
    (
        &["li"],
        [0.265791, 0.195618, 0.220949],
        [3.54015, 2.31112, 1.66861],
    ),
    (
        &["mgo"],
        [2.08958, 1.65072, 1.59488],
        [4.3327e-12, 0.0, 2.49865e-11],
    ),
    (
        &["mo"],
        [4.48397, 3.52513, 2.77631],
        [4.11144, 3.42083, 3.15061],
    ),
    (
        &["na_palik"],
        [0.0602694, 0.0561409, 0.0619884],
        [3.17927, 2.11249, 1.57904],
    ),
    (
        &["nb"],
        [3.42007, 2.79009, 2.39563],
        [3.44139, 2.73767, 2.57975],
    ),
    (
        &["ni_palik"],
        [2.3673, 1.66337, 1.46708],
        [4.49881, 3.05015, 2.34544],
    ),
    (
        &["rh"],
        [2.58579, 1.86022, 1.55426],
        [6.78226, 4.70299, 3.97607],
    ),
    (
        &["se"],
        [4.05831, 2.84294, 2.82085],
        [0.75405, 0.638444, 0.521808],
    ),
    (
        &["sic"],
        [3.17234, 2.52597, 2.47937],
        [7.53766e-07, 0.0, 1.01925e-05],
    ),
    (&["snte"], [4.52425, 1.98164, 1.28159], [0.0, 0.0, 0.0]),
    (
        &["ta"],
        [2.06272, 2.39294, 2.62793],
        [2.40836, 1.74149, 1.94703],
    ),
    (
        &["te"],
        [7.39023, 4.4821, 2.63711],
        [3.25602, 3.52706, 3.29205],
    ),
    (&["thf4"], [1.83071, 1.44223, 1.38765], [0.0, 0.0, 0.0]),
    (
        &["tic"],
        [3.70053, 2.83742, 2.58229],
        [3.26564, 2.35159, 2.17279],
    ),
    (
        &["tin"],
        [1.64845, 1.15052, 1.37982],
        [3.36833, 1.9435, 1.10207],
    ),
    (
        &["tio2"],
        [3.45661, 2.80174, 2.90517],
        [0.000105265, 0.0, 0.000652887],
    ),
    (
        &["vc"],
        [3.65757, 2.75274, 2.53267],
        [3.0683, 2.19869, 1.96319],
    ),
    (
        &["vn"],
        [2.8656, 2.11919, 1.94009],
        [3.03224, 2.05612, 1.61631],
    ),
    (
        &["w"],
        [4.37082, 3.30025, 2.99841],
        [3.50064, 2.60487, 2.27323],
    ),
];

pub(crate) fn metal(name: &str) -> Option<(Vec3, Vec3)> {
    let name = name.trim();
    METALS
        .iter()
        .find(|(names, _, _)| names.iter().any(|n| n.eq_ignore_ascii_case(name)))
        .map(|&(_, eta, k)| (Vec3::from(eta), Vec3::from(k)))
}
