//! Writes the energy-compensation tables of `multiscatter` from glint's own
//! single-scattering GGX lobe: `cpu/src/bsdf/ms_tables.bin`. The GPU reads
//! the same numbers from a storage buffer (`multiscatter::gpu_tables`).
//!
//!     cargo run --release -p glint-cpu --example ms_tables
//!
//! E(mu, alpha): the F = 1 directional albedo on a 32 x 32 grid (mu and
//! alpha uniform over [0, 1]), 256 x 256 stratified visible-normal samples
//! each; E_avg(alpha) = 2 int E mu dmu by a 128-point midpoint rule over mu
//! with 64 x 64 samples per point. One table per Smith form.

use glint_cpu::bsdf::ms_tables::encode_ms_tables;
use glint_cpu::bsdf::multiscatter::{dielectric_albedo_reference, ms_albedo_reference, ms_t_eta};
use rayon::prelude::*;

const N: usize = 32;
/// Grid of the dielectric table (mu, alpha, ln eta').
const MS_T_N: usize = 24;

fn main() -> std::io::Result<()> {
    let mut e = vec![vec![0f32; N * N]; 2];
    let mut e_avg = vec![vec![0f32; N]; 2];
    for sep in 0..2 {
        let separable = sep == 1;
        e[sep] = (0..N * N)
            .into_par_iter()
            .map(|idx| {
                let (j, i) = (idx / N, idx % N);
                let mu = i as f32 / (N - 1) as f32;
                let alpha = j as f32 / (N - 1) as f32;
                ms_albedo_reference(mu, alpha, separable, 256) as f32
            })
            .collect();
        e_avg[sep] = (0..N)
            .into_par_iter()
            .map(|j| {
                let alpha = j as f32 / (N - 1) as f32;
                let m = 128;
                let s: f64 = (0..m)
                    .map(|i| {
                        let mu = (i as f64 + 0.5) / m as f64;
                        2.0 * mu * ms_albedo_reference(mu as f32, alpha, separable, 64)
                    })
                    .sum();
                (s / m as f64) as f32
            })
            .collect();
    }
    // Rough dielectric flux albedo over (eta', alpha, mu), per Smith form.
    let nt = MS_T_N;
    let t: Vec<Vec<f32>> = [false, true]
        .iter()
        .map(|&separable| {
            (0..nt * nt * nt)
                .into_par_iter()
                .map(|idx| {
                    let (k, j, i) = (idx / (nt * nt), (idx / nt) % nt, idx % nt);
                    let mu = i as f32 / (nt - 1) as f32;
                    let alpha = j as f32 / (nt - 1) as f32;
                    dielectric_albedo_reference(mu, alpha, ms_t_eta(k, nt), separable, 48) as f32
                })
                .collect()
        })
        .collect();
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let path = format!("{root}/cpu/src/bsdf/ms_tables.bin");
    std::fs::write(&path, encode_ms_tables(&e, &e_avg, &t))?;
    eprintln!("wrote {path} (the GPU reads the same numbers from a storage buffer)");
    Ok(())
}
