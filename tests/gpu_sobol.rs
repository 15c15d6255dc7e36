//! shaders/integrator/sobol.glsl (through shaders/tests/sobol_test.comp)
//! against cpu/src/sobol.rs, bit for bit: `sobol_sample` on 10^6 (seed key,
//! pixel, sample, dimension) tuples, sample indices past the 2^16 of the
//! tables and dimensions far past a path's, and the path sampler of both
//! kinds (pixel 2D and one bounce's eight numbers) for the same tuples.

mod common;

use glint::cpu::sampling::Pcg32;
use glint::gpu::groups;
use glint_cpu::SamplerKind;
use glint_cpu::sampling::seed_key;
use glint_cpu::sobol::{PathSampler, sobol_sample};

const N: usize = 1_000_000;

#[test]
fn glsl_sobol_returns_the_cpu_bits() {
    let ctx = common::context();
    let mut rng = Pcg32::from_state(0x853c_49e6_748f_ea9b);
    let keys = [seed_key(0), seed_key(1), seed_key(7), 0, u32::MAX];
    let mut queries = Vec::with_capacity(N);
    for _ in 0..N {
        let r = rng.next_u32();
        let key = if r.is_multiple_of(4) {
            rng.next_u32()
        } else {
            keys[(r >> 2) as usize % keys.len()]
        };
        let pixel = match (r >> 8) % 3 {
            0 => rng.next_u32() % 4096,
            1 => rng.next_u32() % (16384 * 16384),
            _ => rng.next_u32(),
        };
        let sample = match (r >> 12) % 4 {
            0 => rng.next_u32() % 256,
            1 => rng.next_u32() % 65536,
            2 => 65536 * (1 + rng.next_u32() % 8) + rng.next_u32() % 4096,
            _ => rng.next_u32(),
        };
        let dim = match (r >> 16) % 4 {
            0 | 1 => rng.next_u32() % 64,
            2 => rng.next_u32() % 4096,
            _ => rng.next_u32(),
        };
        queries.push([key, pixel, sample, dim]);
    }
    let mut results = vec![[0u32; 4]; 3 * N];
    let n = N as u32;
    ctx.run_kernel(
        "tests/sobol_test",
        &[bytemuck::cast_slice(&queries)],
        &mut [bytemuck::cast_slice_mut(&mut results)],
        bytemuck::bytes_of(&n),
        [groups(n, 64), 1, 1],
    )
    .unwrap();

    let mut failures = Vec::new();
    for (i, &[key, pixel, sample, dim]) in queries.iter().enumerate() {
        let v = sobol_sample(key, pixel, sample, dim);
        let kind = if dim & 1 == 1 {
            SamplerKind::Sobol
        } else {
            SamplerKind::Independent
        };
        let mut s = PathSampler::new(kind, key, pixel, sample);
        let px = s.pixel_2d();
        for _ in 0..(dim >> 1) % 6 {
            s.bounce();
        }
        let b = s.bounce();
        let want = [
            v,
            px.x,
            px.y,
            b.light_cat,
            b.light_idx,
            b.light.x,
            b.light.y,
            b.bsdf_lobe,
            b.bsdf.x,
            b.bsdf.y,
            b.rr,
        ]
        .map(f32::to_bits);
        let got: Vec<u32> = results[3 * i..3 * i + 3]
            .iter()
            .flatten()
            .copied()
            .collect();
        if got[..11] != want {
            failures.push(format!(
                "key {key:#x} pixel {pixel} sample {sample} dim {dim}: gpu {:x?} cpu {want:x?}",
                &got[..11]
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {N} tuples differ:\n{}",
        failures.len(),
        failures[..failures.len().min(8)].join("\n")
    );
    let messages = ctx.finish();
    assert!(messages.is_empty(), "validation: {messages:?}");
}
