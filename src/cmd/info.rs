//! `glint info SCENE`: what the scene holds and what glint will use.

use std::fmt::Write as _;
use std::mem::size_of;

use anyhow::Result;
use glint::cpu::bsdf::{Bsdf, ConductorParams, Roughness, Tint};
use glint::cpu::lights::{GpuEmitter, GpuLight};
use glint::cpu::texture::{MAP_EXTRAS, MAP_GLTF, MaterialTextures, TexRef};
use glint::cpu::{Bvh4Node, GpuMaterial, PunctualLight, Scene, Triangle, TriangleShading};

use super::{load_quiet, one_line, scene_options};
use crate::cli::InfoArgs;

pub fn run(args: &InfoArgs) -> Result<()> {
    args.env.check(args.background.is_some())?;
    let options = scene_options(
        args.allow_any_path,
        args.multiscatter,
        args.background,
        &args.env,
    );
    let prepared = load_quiet(&args.scene, &options)?;
    let (scene, simplified) = (prepared.scene, prepared.simplified);
    if args.strict
        && let Some(w) = scene.warnings.first()
    {
        anyhow::bail!("{}: {} (--strict)", args.scene.display(), one_line(w));
    }
    print!("{}", describe(&args.scene.display().to_string(), &scene));
    for n in simplified {
        println!("simplified at load: {n}");
    }
    Ok(())
}

fn rgb(v: glam::Vec3) -> String {
    format!("{:.4},{:.4},{:.4}", v.x, v.y, v.z)
}

fn roughness(r: &Roughness) -> String {
    let alpha = if r.alpha_u == r.alpha_v {
        format!("alpha {:.4}", r.alpha_u)
    } else {
        format!("alpha_u {:.4} alpha_v {:.4}", r.alpha_u, r.alpha_v)
    };
    if r.multiscatter {
        format!("{alpha} multiscatter")
    } else {
        alpha
    }
}

fn conductor(c: &ConductorParams) -> String {
    let name = if c.roughness.is_smooth() {
        "conductor".to_string()
    } else {
        format!("roughconductor {}", roughness(&c.roughness))
    };
    format!("{name} eta {} k {}", rgb(c.eta), rgb(c.k))
}

/// A glTF metallic-roughness material whose channels are textured: each
/// channel as "texture N x factor" (metallic from the texture's B,
/// roughness from its G), or the bare factor where untextured.
fn gltf_channels(mt: &MaterialTextures) -> String {
    let channel = |name: &str, r: &TexRef, texel: &str, factor: String| {
        if r.is_some() {
            format!("{name} texture {}{texel} x {factor}", r.texture)
        } else {
            format!("{name} {factor}")
        }
    };
    let [metallic, roughness, transmission, ior] = mt.mr_factor;
    let mut parts = vec![
        channel(
            "baseColor",
            &mt.base_color,
            "",
            rgb(glam::Vec3::from_slice(&mt.base_factor[..3])),
        ),
        channel(
            "metallic",
            &mt.metallic_roughness,
            ".B",
            format!("{metallic:.4}"),
        ),
        channel(
            "roughness",
            &mt.metallic_roughness,
            ".G",
            format!("{roughness:.4}"),
        ),
    ];
    parts.push(format!("coat ior {ior:.4}"));
    if transmission > 0.0 || mt.transmission.is_some() {
        parts.push(channel(
            "transmission",
            &mt.transmission,
            ".R",
            format!("{transmission:.4}"),
        ));
    }
    let [clearcoat, clearcoat_roughness, specular, _] = mt.coat_factor;
    if clearcoat > 0.0 {
        parts.push(channel(
            "clearcoat",
            &mt.clearcoat,
            ".R",
            format!("{clearcoat:.4}"),
        ));
        parts.push(channel(
            "clearcoatRoughness",
            &mt.clearcoat_roughness,
            ".G",
            format!("{clearcoat_roughness:.4}"),
        ));
    }

    if mt.specular.is_some() || mt.specular_color.is_some() {
        parts.push(channel(
            "specular",
            &mt.specular,
            ".A",
            format!("{specular:.4}"),
        ));
        parts.push(channel(
            "specularColor",
            &mt.specular_color,
            "",
            rgb(glam::Vec3::from_slice(&mt.specular_color_factor[..3])),
        ));
    }
    format!(
        "glTF per texel: metal/coated non-metal blend, {}",
        parts.join(", ")
    )
}

/// A dielectric's `specular_reflectance` and `specular_transmittance`.
fn tint_text(tint: &Tint) -> String {
    format!(
        "specular_reflectance {} specular_transmittance {}",
        rgb(tint.reflect),
        rgb(tint.transmit)
    )
}

/// The model a material maps to, Mitsuba 3's names.
pub fn model(b: &Bsdf) -> String {
    match b {
        Bsdf::Diffuse { reflectance } => format!("diffuse reflectance {}", rgb(*reflectance)),
        Bsdf::Conductor(c) => conductor(c),
        Bsdf::Dielectric {
            eta,
            roughness: r,
            tint,
        } => {
            let name = if r.is_smooth() {
                format!("dielectric eta {eta:.4}")
            } else {
                format!("roughdielectric eta {eta:.4} {}", roughness(r))
            };
            if *tint == Tint::NONE {
                name
            } else {
                format!("{name} {}", tint_text(tint))
            }
        }
        Bsdf::Plastic(p) => format!(
            "plastic diffuse_reflectance {} specular_reflectance {} eta {:.4}{}",
            rgb(p.diffuse),
            rgb(p.specular),
            p.eta,
            if p.nonlinear { " nonlinear" } else { "" }
        ),
        Bsdf::RoughPlastic(rp) => format!(
            "roughplastic {} diffuse_reflectance {} specular_reflectance {} eta {:.4}{}",
            roughness(&rp.roughness),
            rgb(rp.plastic.diffuse),
            rgb(rp.plastic.specular),
            rp.plastic.eta,
            if rp.plastic.nonlinear {
                " nonlinear"
            } else {
                ""
            }
        ),
        Bsdf::ThinDielectric { eta, tint } => {
            format!("thindielectric eta {eta:.4} {}", tint_text(tint))
        }
        Bsdf::Coated {
            base,
            coat,
            roughness: r,
        } => coated(*base, coat, r),
        Bsdf::Metallic {
            metallic,
            base,
            conductor: c,
            coat,
        } => format!(
            "blend {metallic:.3} x ({}) + {:.3} x ({})",
            conductor(c),
            1.0 - metallic,
            coated(*base, coat, &c.roughness)
        ),
    }
}

/// The glTF non-metal: a dielectric coat over a Lambertian base.
fn coated(base: glam::Vec3, coat: &glint::cpu::bsdf::coated::CoatParams, r: &Roughness) -> String {
    let coat_name = if r.is_smooth() {
        "smooth coat".to_string()
    } else {
        format!("ggx coat {}", roughness(r))
    };
    let spec = if coat.specular == glam::Vec3::ONE {
        String::new()
    } else {
        format!(" specular {}", rgb(coat.specular))
    };
    format!(
        "coated non-metal ({coat_name} ior {:.4}{spec} over diffuse base {})",
        coat.eta,
        rgb(base)
    )
}

fn bytes(n: usize) -> String {
    if n >= 1 << 20 {
        format!("{n} B ({:.1} MiB)", n as f64 / (1 << 20) as f64)
    } else if n >= 1 << 10 {
        format!("{n} B ({:.1} KiB)", n as f64 / 1024.0)
    } else {
        format!("{n} B")
    }
}

/// The report, one section per kind of thing.
pub fn describe(path: &str, s: &Scene) -> String {
    let mut o = String::new();
    let _ = writeln!(o, "scene: {path}");
    cameras(&mut o, s);
    let _ = writeln!(o, "materials: {}", s.materials.len());
    for (i, m) in s.materials.iter().enumerate() {
        let _ = writeln!(o, "  {i}: {}", material_line(s, i, m));
    }
    textures(&mut o, s);
    lights(&mut o, s);
    geometry(&mut o, s);
    let _ = writeln!(o, "warnings: {}", s.warnings.len());
    for w in &s.warnings {
        let _ = writeln!(o, "  {}", one_line(w));
    }
    o
}

fn cameras(o: &mut String, s: &Scene) {
    let _ = writeln!(o, "cameras: {}", s.cameras.len());
    for (i, c) in s.cameras.iter().enumerate() {
        let p = c.to_world.w_axis.truncate();
        let _ = writeln!(
            o,
            "  {i}: {} at {} yfov {:.2} deg{}",
            c.name.as_deref().unwrap_or("(unnamed)"),
            rgb(p),
            c.yfov.to_degrees(),
            c.aspect_ratio
                .map(|a| format!(" aspect {a:.4}"))
                .unwrap_or_default()
        );
    }
    if s.cameras.is_empty() {
        let _ = writeln!(o, "  (none: the default viewpoint frames the scene)");
    }
}

/// One material: its model (per texel where textured), then what else it
/// has (emission, sides, interior, texture slots).
fn material_line(s: &Scene, i: usize, m: &glint::cpu::Material) -> String {
    let mut extra = Vec::new();
    let mt = s.textures.materials.get(i);
    let textured_emission = mt.is_some_and(|mt| mt.emissive.is_some());
    if m.is_emissive() {
        extra.push(match mt {
            Some(mt) if textured_emission => format!(
                "emission texture {} x {} (textured: not the scene's lighting)",
                mt.emissive.texture,
                rgb(m.emission)
            ),
            _ => format!("emission {}", rgb(m.emission)),
        });
    }
    if m.double_sided {
        extra.push("double-sided".into());
    }
    if m.absorption != glam::Vec3::ZERO {
        extra.push(format!("absorbing interior sigma_a {}", rgb(m.absorption)));
    }
    let mut bsdf = model(&m.bsdf);
    if let Some(mt) = mt {
        if mt.mode == MAP_GLTF {
            // The BSDF is recomputed per texel: the factor-only model
            // (a metal "k 63.2" from base colour 1) would mislead.
            bsdf = gltf_channels(mt);
        } else if mt.mode == MAP_EXTRAS {
            extra.push(format!(
                "baseColor texture {} x the reflectance above",
                mt.base_color.texture
            ));
        }
        if mt.normal.is_some() {
            extra.push(format!(
                "normal texture {} x scale {}",
                mt.normal.texture, mt.normal.scale
            ));
        }
        if mt.clearcoat_normal.is_some() {
            extra.push(format!(
                "clear-coat normal texture {} x scale {}",
                mt.clearcoat_normal.texture, mt.clearcoat_normal.scale
            ));
        }
        if mt.is_masked() {
            extra.push(format!("alpha mask < {}", mt.alpha_cutoff));
        }
        if mt.is_blended() {
            extra.push("alpha blend (stochastic)".into());
        }
    }
    let extra = if extra.is_empty() {
        String::new()
    } else {
        format!("; {}", extra.join("; "))
    };
    let name = if m.name.is_empty() {
        "(unnamed)"
    } else {
        &m.name
    };
    format!("{name}: {bsdf}{extra}")
}

fn textures(o: &mut String, s: &Scene) {
    let t = &s.textures;
    let _ = writeln!(o, "textures: {}", t.table.len());
    for (i, (g, info)) in t.table.iter().zip(&t.info).enumerate() {
        let wrap = |m: u32| match m {
            1 => "clamp",
            2 => "mirror",
            _ => "repeat",
        };
        let _ = writeln!(
            o,
            "  {i}: {} {}x{} wrap {}/{} {}",
            info.name,
            info.width,
            info.height,
            wrap(g.flags & 3),
            wrap((g.flags >> 2) & 3),
            if g.flags & glint::cpu::texture::TEX_NEAREST != 0 {
                "nearest"
            } else {
                "bilinear"
            }
        );
    }
}

fn lights(o: &mut String, s: &Scene) {
    let emitters = s.emitter_triangles().len();
    let background = match &s.envmap {
        Some(env) => format!(
            "an environment map of {}x{} texels turned {:.2} degrees about +Y",
            env.width,
            env.height,
            env.rotation.to_degrees()
        ),
        None => rgb(s.background),
    };
    let _ = writeln!(
        o,
        "lights: {emitters} emissive triangles, {} punctual, background {background}",
        s.lights.len(),
    );
    for (i, l) in s.lights.iter().enumerate() {
        let d = match l {
            PunctualLight::Point {
                position,
                intensity,
            } => format!("point at {} intensity {}", rgb(*position), rgb(*intensity)),
            PunctualLight::Spot {
                position,
                direction,
                intensity,
                inner_cone_angle,
                outer_cone_angle,
            } => format!(
                "spot at {} toward {} intensity {} cone {:.1}-{:.1} deg",
                rgb(*position),
                rgb(*direction),
                rgb(*intensity),
                inner_cone_angle.to_degrees(),
                outer_cone_angle.to_degrees()
            ),
            PunctualLight::Directional {
                direction,
                irradiance,
            } => format!(
                "directional toward {} irradiance {}",
                rgb(*direction),
                rgb(*irradiance)
            ),
        };
        let _ = writeln!(o, "  {i}: {d}");
    }
}

/// Triangles, bounds, the kernel's features and what the GPU holds.
fn geometry(o: &mut String, s: &Scene) {
    let t = &s.textures;
    let emitters = s.emitter_triangles().len();
    let (lo, hi) = s.bounds();
    let _ = writeln!(o, "triangles: {}", s.triangles.len());
    let _ = writeln!(o, "bounds: min {} max {}", rgb(lo), rgb(hi));
    // What the specialised GPU kernel is built for (at the default
    // options: unbounded depth, NEE on), plus the data it reads.
    let f = glint::cpu::features::Features::of(s, &glint::cpu::RenderOptions::new(1, 1));
    let _ = writeln!(o, "kernel features: {}", f.names().join(", "));
    let rows = [
        ("triangles", s.triangles.len() * size_of::<Triangle>()),
        ("bvh nodes", s.bvh.nodes.len() * size_of::<Bvh4Node>()),
        ("shading", s.shading.len() * 16),
        ("materials", s.materials.len() * size_of::<GpuMaterial>()),
        ("emitters", emitters * size_of::<GpuEmitter>()),
        ("lights", s.lights.len() * size_of::<GpuLight>()),
        ("texels", t.texels.len() * 4),
        ("texture table", t.table.len() * 16),
        (
            "material textures",
            t.materials.len() * size_of::<MaterialTextures>(),
        ),
        ("triangle uvs", t.uvs.len() * 64),
    ];
    let total: usize = rows.iter().map(|r| r.1).sum();
    let _ = writeln!(
        o,
        "memory (bytes uploaded per GPU buffer): {}",
        bytes(total)
    );
    for (name, n) in rows {
        if n > 0 {
            let _ = writeln!(o, "  {name}: {}", bytes(n));
        }
    }
    // Per triangle: what the triangles, shading and uv buffers hold, and
    // what one full shading record per triangle (the layout before
    // Scene::set_shading packed them) would have made it.
    let n_tris = s.triangles.len().max(1) as f64;
    let uv_bytes = t.uvs.len() as f64 * 64.0 / n_tris;
    let _ = writeln!(
        o,
        "bytes per triangle: {:.1} (triangle {}, shading {:.1}, uv {:.1}; {:.1} with a shading record on every triangle)",
        s.gpu_bytes_per_triangle(),
        size_of::<Triangle>(),
        s.shading.len() as f64 * 16.0 / n_tris,
        uv_bytes,
        (size_of::<Triangle>() + size_of::<TriangleShading>()) as f64 + uv_bytes,
    );
}
