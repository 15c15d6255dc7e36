//! Differential test of shaders/texture.glsl (through the kernel
//! shaders/tests/texture_test.comp) against glint_cpu::texture: the texel
//! lookup at random UVs (in and far outside [0, 1], every wrap mode, both
//! filters, sRGB on and off), a material's slot lookup through the UV
//! transform and the triangle's texture coordinates, the alpha test and
//! the textured glTF mapping, under the validation layer.

mod common;

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3, Vec4};
use glint::gpu::groups;
use glint_cpu::Bsdf;
use glint_cpu::sampling::Pcg32;
use glint_cpu::scene::GpuMaterial;
use glint_cpu::texture::{
    GpuTexture, MAP_GLTF, MaterialTextures, SceneTextures, TEX_NEAREST, TexRef, TriangleUv,
    blend_random, texture_sample, textured_bsdf,
};

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct Query {
    uv_srgb: [f32; 4],
    ids: [u32; 4],
    bary: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct GpuResult {
    sample: [f32; 4],
    base: [f32; 4],
    reflectance: [f32; 4],
    k_alpha: [f32; 4],
    flags: [u32; 4],
    coat: [f32; 4],
    extra: [f32; 4],
}

/// Random images of odd sizes with every wrap/filter combination.
fn textures(rng: &mut Pcg32) -> SceneTextures {
    let mut st = SceneTextures::default();
    let sizes = [(1, 1), (2, 2), (3, 5), (7, 2), (16, 9)];
    for (k, &(w, h)) in sizes.iter().cycle().take(18).enumerate() {
        let offset = st.texels.len() as u32;
        for _ in 0..w * h {
            st.texels.push(rng.next_u32());
        }
        let wrap_s = (k % 3) as u32;
        let wrap_t = ((k / 3) % 3) as u32;
        let nearest = if k % 2 == 0 { TEX_NEAREST } else { 0 };
        st.table.push(GpuTexture {
            offset,
            width: w,
            height: h,
            flags: wrap_s | (wrap_t << 2) | nearest,
        });
    }
    st
}

#[test]
fn glsl_texture_lookups_match_the_cpu_crate() {
    let ctx = common::context();
    let mut rng = Pcg32::from_state(0x2545f4914f6cdd1d);
    let mut st = textures(&mut rng);
    // Materials: glTF mapping with base colour and metallicRoughness
    // textures, transformed UVs on set 0 or 1, masked or not.
    for k in 0..6u32 {
        // k = 1 and 4: alphaMode BLEND (stochastic, the ray's hash decides).
        let blend = k % 3 == 1;
        let mut mt = MaterialTextures {
            mode: MAP_GLTF,
            alpha_cutoff: if k % 2 == 0 && !blend { 0.5 } else { -1.0 },
            blend: blend as u32,
            base_alpha: 0.9,
            base_factor: [0.9, 0.8, 0.7, 1.0],
            mr_factor: [if k < 3 { 1.0 } else { 0.6 }, 0.8, 0.0, 1.5],
            ..MaterialTextures::default()
        };
        mt.base_color = TexRef {
            texture: k * 3 % 18,
            tex_coord: k % 2,
            ..TexRef::default()
        };
        mt.base_color
            .set_transform(Vec2::new(0.3, -0.2), 0.4 * k as f32, Vec2::new(1.5, 0.75));
        mt.metallic_roughness = TexRef {
            texture: (k * 5 + 1) % 18,
            ..TexRef::default()
        };
        // The coat's textures (transmission, clear coat, specular) on
        // k = 2..5, each on its own image and UV set; k = 5 has only the
        // specular colour (the specular factor stays untextured).
        if k >= 2 {
            let tex = |j: u32| TexRef {
                texture: (k * 7 + j * 3 + 2) % 18,
                tex_coord: (k + j) % 2,
                ..TexRef::default()
            };
            mt.mr_factor[2] = 0.7;
            mt.coat_factor = [0.8, 0.6, 0.9, 0.0];
            mt.specular_color_factor = [1.2, 0.5, 0.9, 1.0];
            mt.specular_color = tex(4);
            if k < 5 {
                mt.transmission = tex(0);
                mt.clearcoat = tex(1);
                mt.clearcoat_roughness = tex(2);
                mt.specular = tex(3);
                mt.specular
                    .set_transform(Vec2::new(-0.1, 0.2), 0.3, Vec2::new(2.0, 0.5));
            }
        }
        st.materials.push(mt);
    }
    for _ in 0..32 {
        let mut t = TriangleUv::default();
        for v in &mut t.uv {
            *v = [0; 4].map(|_| rng.f32() * 6.0 - 3.0);
        }
        st.uvs.push(t);
    }
    let n = 20_000u32;
    let queries: Vec<Query> = (0..n)
        .map(|i| {
            // Mostly near [0, 1], some far out, some exactly on texel edges.
            let coord = |rng: &mut Pcg32| match i % 4 {
                0 => rng.f32() * 40.0 - 20.0,
                1 => (rng.next_u32() % 33) as f32 / 16.0 - 0.5,
                _ => rng.f32() * 1.4 - 0.2,
            };
            let (u, v) = (coord(&mut rng), coord(&mut rng));
            let b = Vec2::new(rng.f32(), rng.f32());
            let b = if b.x + b.y > 1.0 { Vec2::ONE - b } else { b };
            Query {
                uv_srgb: [u, v, (i % 2) as f32, 0.0],
                ids: [
                    rng.next_u32() % 18,
                    rng.next_u32() % 6,
                    rng.next_u32() % 32,
                    0,
                ],
                bary: [b.x, b.y, rng.f32() * 8.0 - 4.0, rng.f32() * 2.0 - 1.0],
            }
        })
        .collect();
    let mut results = vec![GpuResult::default(); queries.len()];
    ctx.run_kernel(
        "tests/texture_test",
        &[
            bytemuck::cast_slice(&st.texels),
            bytemuck::cast_slice(&st.table),
            bytemuck::cast_slice(&st.materials),
            bytemuck::cast_slice(&st.uvs),
            bytemuck::cast_slice(&queries),
        ],
        &mut [bytemuck::cast_slice_mut(&mut results)],
        bytemuck::bytes_of(&n),
        [groups(n, 64), 1, 1],
    )
    .unwrap();
    let base_bsdf = Bsdf::Diffuse {
        reflectance: Vec3::splat(0.5),
    };
    let mut failures = Vec::new();
    let close =
        |a: Vec4, b: [f32; 4], tol: f32| (a - Vec4::from_array(b)).abs().max_element() <= tol;
    for (q, g) in queries.iter().zip(&results) {
        let [tex, mat, tri, _] = q.ids;
        let s = texture_sample(
            &st.texels,
            &st.table[tex as usize],
            Vec2::new(q.uv_srgb[0], q.uv_srgb[1]),
            q.uv_srgb[2] != 0.0,
        );
        // Bilinear weights from a floor near an integer can differ by an
        // ulp of the coordinate; texels are 8-bit, so 1e-4 is far tighter
        // than any texel step.
        if !close(s, g.sample, 2e-4) {
            failures.push(format!("texture_sample {q:?}: cpu {s} gpu {:?}", g.sample));
        }
        let mt = &st.materials[mat as usize];
        let (u, v) = (q.bary[0], q.bary[1]);
        let base = st.lookup(&mt.base_color, tri, u, v, true);
        if !close(base, g.base, 2e-4) {
            failures.push(format!("texture_lookup {q:?}: cpu {base} gpu {:?}", g.base));
        }
        // The alpha test's ray (texture_test.comp): o = (uv, bary.z), d =
        // (bary.xy, bary.w). BLEND's hash must agree to the bit.
        let o = Vec3::new(q.uv_srgb[0], q.uv_srgb[1], q.bary[2]);
        let d = Vec3::new(q.bary[0], q.bary[1], q.bary[3]);
        let xi = blend_random(tri, o, d);
        if xi.to_bits() != g.flags[2] {
            failures.push(format!(
                "blend_random {q:?}: cpu {xi} gpu {}",
                f32::from_bits(g.flags[2])
            ));
        }
        if st.alpha_pass(mat, tri, u, v, o, d) != (g.flags[0] == 1) {
            // Alpha exactly at the cutoff (or at the BLEND number): only a
            // rounding apart.
            let a = mt.base_alpha * base.w;
            let edge = if mt.is_blended() { xi } else { mt.alpha_cutoff };
            if (a - edge).abs() > 1e-4 {
                failures.push(format!("alpha_pass {q:?}: alpha {a}"));
            }
        }
        let b = textured_bsdf(&st, mt, &base_bsdf, tri, u, v);
        let gm = GpuMaterial::from(&glint_cpu::Material {
            name: String::new(),
            bsdf: b,
            emission: Vec3::ZERO,
            double_sided: false,
            absorption: glam::Vec3::ZERO,
        });
        if gm.kind != g.flags[1]
            || !close(Vec4::from_array(gm.reflectance), g.reflectance, 2e-4)
            || !close(
                Vec4::new(gm.k[0], gm.k[1], gm.k[2], gm.alpha_u),
                g.k_alpha,
                2e-3 * gm.k[0].max(gm.k[1]).max(gm.k[2]).max(1.0),
            )
        {
            failures.push(format!("textured_bsdf {q:?}: cpu {gm:?} gpu {g:?}"));
        }
        // The textured coat (textured_coat): specular scale and IOR,
        // transmission, clear-coat weight and alpha.
        if !close(Vec4::from_array(gm.coat), g.coat, 2e-4)
            || !close(Vec4::from_array(gm.extra), g.extra, 2e-4)
        {
            failures.push(format!(
                "textured_coat {q:?}: cpu coat {:?} extra {:?} gpu coat {:?} extra {:?}",
                gm.coat, gm.extra, g.coat, g.extra
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {n} queries differ; first:\n{}",
        failures.len(),
        failures[..failures.len().min(8)].join("\n")
    );
}
