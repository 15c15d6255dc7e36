//! Writes the glTF non-metal's coat tables (`cpu/src/bsdf/coat_tables.bin`)
//! from glint's own single-scattering GGX coat (`coated::coat_albedo_reference`):
//!
//!     cargo run --release -p glint-cpu --example coat_tables
//!
//! E(mu, alpha, x): the coat's directional albedo (exact dielectric Fresnel,
//! height-correlated Smith) on a 64 x 64 x 32 grid uniform in mu^(1/4),
//! sqrt(alpha) and sqrt(x), x = (eta - 1) / (eta + 1), over [0, 1], 128 x 128 stratified
//! visible-normal samples each; the alpha = 0 row is the exact F(mu).
//! E_avg(alpha, x) = 2 int E(mu) mu dmu of the table's own piecewise-linear
//! E in mu^(1/4) (so that the base term's cosine integral is exactly
//! 1 - E_avg for what the renderer looks up), except the alpha = 0 row, which
//! the smooth coat uses with the exact F: 2 int F mu dmu by a 4096-point
//! midpoint rule.

use glint_cpu::bsdf::coated::{
    COAT_N_ALPHA, COAT_N_ETA, COAT_N_MU, coat_albedo_reference, coat_alpha_value, coat_eta_of,
    coat_mu_value, encode_coat_tables,
};
use glint_cpu::bsdf::fresnel::fresnel_dielectric;
use rayon::prelude::*;

fn main() -> std::io::Result<()> {
    let (nm, na, ne) = (COAT_N_MU, COAT_N_ALPHA, COAT_N_ETA);
    let e: Vec<f32> = (0..nm * na * ne)
        .into_par_iter()
        .map(|idx| {
            let (k, j, i) = (idx / (nm * na), (idx / nm) % na, idx % nm);
            let mu = coat_mu_value(i as f32 / (nm - 1) as f32);
            let alpha = coat_alpha_value(j as f32 / (na - 1) as f32);
            let eta = coat_eta_of(k as f32 / (ne - 1) as f32);
            coat_albedo_reference(mu, alpha, eta, 128) as f32
        })
        .collect();
    let steps = 4096;
    let e_avg: Vec<f32> = (0..na * ne)
        .into_par_iter()
        .map(|idx| {
            let (k, j) = (idx / na, idx % na);
            let eta = coat_eta_of(k as f32 / (ne - 1) as f32);
            let row = &e[(k * na + j) * nm..(k * na + j + 1) * nm];
            let s: f64 = (0..steps)
                .map(|s| {
                    let mu = (s as f64 + 0.5) / steps as f64;
                    let v = if j == 0 {
                        fresnel_dielectric(mu as f32, eta) as f64
                    } else {
                        let y = mu.sqrt().sqrt() * (nm - 1) as f64;
                        let i0 = (y as usize).min(nm - 2);
                        let f = y - i0 as f64;
                        row[i0] as f64 + (row[i0 + 1] as f64 - row[i0] as f64) * f
                    };
                    2.0 * mu * v
                })
                .sum();
            (s / steps as f64) as f32
        })
        .collect();
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/src/bsdf/coat_tables.bin");
    std::fs::write(path, encode_coat_tables(&e, &e_avg))?;
    println!("wrote {path}");
    Ok(())
}
