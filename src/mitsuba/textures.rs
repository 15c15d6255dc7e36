//! A textured material for Mitsuba 3 (`glint export`): each texture a
//! bitmap of its own, every texel decoded as glint reads it and mapped to
//! what the Mitsuba parameter takes (the factor multiplied in, a channel
//! picked, the normal map's scale applied, the alpha cutoff applied), saved
//! as a linear EXR under `textures/`; the texture's wrap mode, filter and
//! `KHR_texture_transform` go with it (`to_uv`).

use std::path::Path;

use anyhow::{Context, Result};
use glam::{Vec3, Vec4};
use glint_cpu::bsdf::Bsdf;
use glint_cpu::texture::{
    MAP_EXTRAS, MAP_GLTF, MaterialTextures, TEX_NEAREST, TexRef, WRAP_CLAMP, WRAP_MIRROR,
    texture_fetch,
};
use glint_cpu::{Material, Scene};

use super::{bsdf_xml, float, principled_warning, principled_xml, rgb, two_sided};

/// Writes a scene's bitmaps into `dir` (`textures/t<n>.exr`), one per use.
pub(super) struct Bitmaps<'a> {
    pub scene: &'a Scene,
    pub dir: &'a Path,
    /// What was written, relative to `dir`.
    pub files: Vec<String>,
}

impl Bitmaps<'_> {
    /// The bitmap texture `name` of `r`: each texel (its rgb sRGB-decoded
    /// where `srgb`, its alpha linear) mapped by `f`, with `r`'s wrap
    /// mode, filter and transform. A texture whose two axes wrap
    /// differently takes the s axis' mode (Mitsuba has one), with a warning.
    pub fn bitmap(
        &mut self,
        name: &str,
        r: &TexRef,
        srgb: bool,
        warnings: &mut Vec<String>,
        f: impl Fn(Vec4) -> Vec3,
    ) -> Result<String> {
        let st = &self.scene.textures;
        let t = st.table[r.texture as usize];
        let mut pixels = Vec::with_capacity((t.width * t.height) as usize);
        for y in 0..t.height as i32 {
            for x in 0..t.width as i32 {
                pixels.push(f(texture_fetch(&st.texels, &t, x, y, srgb)));
            }
        }
        let file = format!("textures/t{}.exr", self.files.len());
        let path = self.dir.join(&file);
        std::fs::create_dir_all(self.dir.join("textures"))
            .with_context(|| format!("{}", self.dir.display()))?;
        super::write_exr(&path, t.width, t.height, pixels)?;
        self.files.push(file.clone());
        let mode = |m: u32| match m {
            WRAP_CLAMP => "clamp",
            WRAP_MIRROR => "mirror",
            _ => "repeat",
        };
        if t.flags & 3 != (t.flags >> 2) & 3 {
            warnings.push(format!(
                "texture {}: wrap modes differ between s and t; written as s's ({})",
                r.texture,
                mode(t.flags & 3)
            ));
        }
        let filter = if t.flags & TEX_NEAREST != 0 {
            "nearest"
        } else {
            "bilinear"
        };
        let matrix = to_uv(r).map(|v| format!("{v:e}")).join(" ");
        Ok(format!(
            r#"<texture type="bitmap" name="{name}"><string name="filename" value="{file}"/><boolean name="raw" value="true"/><string name="filter_type" value="{filter}"/><string name="wrap_mode" value="{}"/><transform name="to_uv"><matrix value="{matrix}"/></transform></texture>"#,
            mode(t.flags & 3)
        ))
    }
}

/// `r`'s `KHR_texture_transform`, uv' = (r0 . (u, v, 1), r1 . (u, v, 1)),
/// as the 4x4 matrix (row-major) whose 2D part Mitsuba's `to_uv` takes: z
/// passes through.
fn to_uv(r: &TexRef) -> [f32; 16] {
    let [r0, r1] = r.transform;
    [
        r0[0], r0[1], 0.0, r0[2], //
        r1[0], r1[1], 0.0, r1[2], //
        0.0, 0.0, 1.0, 0.0, //
        0.0, 0.0, 0.0, 1.0,
    ]
}

/// The texture coordinate set a material's textures read (the first used
/// one's), with a warning where they read different sets: a Mitsuba mesh
/// has one.
pub(super) fn uv_set(mt: &MaterialTextures, what: &str, warnings: &mut Vec<String>) -> u32 {
    let sets: Vec<u32> = used(mt).iter().map(|r| r.tex_coord).collect();
    let set = sets.first().copied().unwrap_or(0);
    if sets.iter().any(|&s| s != set) {
        warnings.push(format!(
            "{what}: textures on two texture coordinate sets; written on set {set}"
        ));
    }
    set
}

/// The textures the export writes (the others keep their factors).
fn used(mt: &MaterialTextures) -> Vec<&TexRef> {
    [
        &mt.base_color,
        &mt.metallic_roughness,
        &mt.normal,
        &mt.emissive,
    ]
    .into_iter()
    .filter(|r| r.is_some())
    .collect()
}

/// A material's BSDF (`mat.bsdf`, its factors) with its textures `mt` (and
/// its normal map and alpha mask on any model), or None where it has none
/// the export writes (then `bsdf_xml` writes it).
pub(super) fn textured_bsdf_xml(
    out: &mut Bitmaps,
    mt: &MaterialTextures,
    mat: &Material,
    what: &str,
    warnings: &mut Vec<String>,
) -> Result<Option<String>> {
    let bsdf = &mat.bsdf;
    for (r, name) in [
        (&mt.transmission, "transmission"),
        (&mt.clearcoat, "clear coat"),
        (&mt.clearcoat_roughness, "clear coat roughness"),
        (&mt.clearcoat_normal, "clear coat normal"),
        (&mt.specular, "specular"),
        (&mt.specular_color, "specular colour"),
    ] {
        if r.is_some() {
            warnings.push(format!(
                "{what}: the {name} texture is not written (its factor is)"
            ));
        }
    }
    let inner = match (mt.mode, bsdf) {
        (MAP_GLTF, Bsdf::Dielectric { .. }) => None,
        (MAP_GLTF, _) => {
            warnings.push(principled_warning(what, "metallic blend"));
            Some(gltf_principled(out, mt, bsdf, warnings)?)
        }
        (MAP_EXTRAS, Bsdf::Diffuse { reflectance }) if mt.base_color.is_some() => {
            let rho = *reflectance;
            let tex = out.bitmap("reflectance", &mt.base_color, true, warnings, |c| {
                rho * c.truncate()
            })?;
            Some(format!(r#"<bsdf type="diffuse">{tex}</bsdf>"#))
        }
        _ => None,
    };
    if inner.is_none() && (mt.base_color.is_some() || mt.metallic_roughness.is_some()) {
        warnings.push(format!(
            "{what}: textures on this model are not written (its factors are)"
        ));
    }
    if inner.is_none() && !mt.normal.is_some() && !mt.has_alpha_test() {
        return Ok(None);
    }
    let mut xml = two_sided(
        bsdf,
        mat.double_sided,
        match inner {
            Some(xml) => xml,
            None => bsdf_xml(bsdf, what, warnings),
        },
    );
    if mt.normal.is_some() {
        let scale = mt.normal.scale;
        let tex = out.bitmap("normalmap", &mt.normal, false, warnings, |c| {
            let m = c.truncate() * 2.0 - Vec3::ONE;
            let m = Vec3::new(m.x * scale, m.y * scale, m.z);
            m * 0.5 + Vec3::splat(0.5)
        })?;
        warnings.push(format!(
            "{what}: the normal map on Mitsuba's tangent frame (from the texture coordinates, not the file's tangents)"
        ));
        xml = format!(r#"<bsdf type="normalmap">{tex}{xml}</bsdf>"#);
    }
    if mt.has_alpha_test() {
        let (a0, cutoff, blend) = (mt.base_alpha, mt.alpha_cutoff, mt.blend != 0);
        let opacity = |a: f32| {
            if blend {
                a
            } else if a >= cutoff {
                1.0
            } else {
                0.0
            }
        };
        let tex = if mt.base_color.is_some() {
            out.bitmap("opacity", &mt.base_color, false, warnings, |c| {
                Vec3::splat(opacity(a0 * c.w))
            })?
        } else {
            float("opacity", opacity(a0))
        };
        xml = format!(r#"<bsdf type="mask">{tex}{xml}</bsdf>"#);
    }
    Ok(Some(xml))
}

/// glTF's metallic-roughness model (a [`Bsdf::Metallic`] blend or its
/// ends) as `principled`, base colour, metallic and roughness textured
/// where the material has the textures.
fn gltf_principled(
    out: &mut Bitmaps,
    mt: &MaterialTextures,
    bsdf: &Bsdf,
    warnings: &mut Vec<String>,
) -> Result<String> {
    let [metallic, roughness, transmission, eta] = mt.mr_factor;
    let factor = Vec3::from_slice(&mt.base_factor[..3]);
    let base = if mt.base_color.is_some() {
        out.bitmap("base_color", &mt.base_color, true, warnings, |c| {
            factor * c.truncate()
        })?
    } else {
        rgb("base_color", factor)
    };
    let (metal, rough) = if mt.metallic_roughness.is_some() {
        let r = &mt.metallic_roughness;
        (
            out.bitmap("metallic", r, false, warnings, |c| {
                Vec3::splat(metallic * c.z)
            })?,
            out.bitmap("roughness", r, false, warnings, |c| {
                Vec3::splat(roughness * c.y)
            })?,
        )
    } else {
        (float("metallic", metallic), float("roughness", roughness))
    };
    // The coat's IOR and transmission as the factors' model has them.
    let (eta, transmission) = match bsdf {
        Bsdf::Coated { coat, .. } | Bsdf::Metallic { coat, .. } => (coat.eta, coat.transmission),
        _ => (eta, transmission),
    };
    Ok(principled_xml(&base, &metal, &rough, eta, transmission))
}

/// The emissive texture of `mt` on an area light of radiance `emission`
/// (the emissive factor and strength), where it has one.
pub(super) fn emission_xml(
    out: &mut Bitmaps,
    mt: &MaterialTextures,
    emission: Vec3,
    warnings: &mut Vec<String>,
) -> Result<Option<String>> {
    if !mt.emissive.is_some() {
        return Ok(None);
    }
    out.bitmap("radiance", &mt.emissive, true, warnings, |c| {
        emission * c.truncate()
    })
    .map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Mat4, Vec2};

    /// The matrix sends (u, v, 0, 1) where the texture's transform sends
    /// (u, v), for a rotated, scaled and offset transform.
    #[test]
    fn to_uv_is_the_texture_transform() {
        let (c, s) = (0.3f32.cos(), 0.3f32.sin());
        let r = TexRef {
            transform: [
                [c * 2.0, s * 0.5, 0.25, 0.0],
                [-s * 2.0, c * 0.5, -0.75, 0.0],
            ],
            ..TexRef::default()
        };
        let m = Mat4::from_cols_array(&to_uv(&r)).transpose();
        for uv in [
            Vec2::ZERO,
            Vec2::new(1.0, 0.0),
            Vec2::new(0.3, 0.8),
            Vec2::new(-2.0, 5.0),
        ] {
            let got = m * Vec4::new(uv.x, uv.y, 0.0, 1.0);
            let want = r.apply(uv);
            assert!(
                (got.truncate().truncate() - want).length() < 1e-6,
                "{uv}: {got} vs {want}"
            );
            assert_eq!((got.z, got.w), (0.0, 1.0));
        }
    }
}
