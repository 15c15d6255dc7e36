//! Writes Mitsuba 3 `roughplastic`'s interface tables
//! (`cpu/src/bsdf/roughplastic_tables.bin`) from glint's own GGX interface
//! (`roughplastic::rp_interface_reference`):
//!
//!     cargo run --release -p glint-cpu --example roughplastic_tables
//!
//! T(mu, alpha, eta): the external transmittance on Mitsuba's 64 uniform mu
//! nodes (mu = 0 taken as 1e-6, as Mitsuba does) x 32 sqrt(alpha) x 32
//! sqrt((eta - 1) / (eta + 1)) nodes, 96 x 96 visible normals each, per
//! Smith form; R_int(alpha, eta) = 2 x the mean over the same 64 mu nodes
//! of mu R(mu), R the reflectance seen from inside (relative IOR 1 / eta):
//! Mitsuba's rule.

use glint_cpu::bsdf::coated::{coat_eta_of, encode_table};
use glint_cpu::bsdf::roughplastic::{RP_N_ALPHA, RP_N_ETA, RP_N_MU, rp_interface_reference};
use rayon::prelude::*;

fn main() -> std::io::Result<()> {
    let (nm, na, ne) = (RP_N_MU, RP_N_ALPHA, RP_N_ETA);
    let mu = |i: usize| i as f32 / (nm - 1) as f32;
    let alpha = |j: usize| (j as f32 / (na - 1) as f32).powi(2);
    let eta = |k: usize| coat_eta_of(k as f32 / (ne - 1) as f32).min(1e4);
    let mut v = Vec::new();
    for separable in [false, true] {
        let t: Vec<f32> = (0..nm * na * ne)
            .into_par_iter()
            .map(|idx| {
                let (k, j, i) = (idx / (nm * na), (idx / nm) % na, idx % nm);
                rp_interface_reference(mu(i), alpha(j), eta(k), separable, true, 96) as f32
            })
            .collect();
        v.extend(t);
    }
    for separable in [false, true] {
        let r: Vec<f32> = (0..na * ne)
            .into_par_iter()
            .map(|idx| {
                let (k, j) = (idx / na, idx % na);
                let s: f64 = (0..nm)
                    .map(|i| {
                        mu(i).max(1e-6) as f64
                            * rp_interface_reference(
                                mu(i),
                                alpha(j),
                                1.0 / eta(k),
                                separable,
                                false,
                                96,
                            )
                    })
                    .sum();
                (2.0 * s / nm as f64) as f32
            })
            .collect();
        v.extend(r);
    }
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/src/bsdf/roughplastic_tables.bin"
    );
    std::fs::write(path, encode_table(b"GLRP", [nm, na, ne], &v))?;
    println!("wrote {path}");
    Ok(())
}
