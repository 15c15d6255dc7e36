//! glTF materials to glint's [`Material`]: `extras.bsdf` (Mitsuba 3 names and
//! parameters) when present, else the glTF metallic-roughness model mapped
//! onto the same BSDFs (see the contract's "Materials" section).

use glam::Vec3;
use serde_json::{Map, Value};

use crate::bsdf::coated::CoatParams;
use crate::bsdf::plastic::PlasticParams;
use crate::bsdf::roughplastic::RoughPlasticParams;
use crate::bsdf::{Bsdf, ConductorParams, Roughness, Shadowing, Tint, named_ior, named_metal};
use crate::scene::Material;

/// Mitsuba 3's default GGX alpha for `roughconductor` and `roughdielectric`
/// when neither `alpha` nor `alpha_u`/`alpha_v` is given.
pub const DEFAULT_ALPHA: f32 = 0.1;
/// Mitsuba 3's `dielectric` defaults: BK7 inside, air outside.
pub const DEFAULT_INT_IOR: f32 = 1.5046;
pub const DEFAULT_EXT_IOR: f32 = 1.000277;
/// Mitsuba 3's default `diffuse` reflectance.
pub const DEFAULT_REFLECTANCE: f32 = 0.5;
/// KHR_materials_ior's default index.
pub const GLTF_DEFAULT_IOR: f32 = 1.5;
/// F0 is clamped below 1 so k = 2 sqrt(F0 / (1 - F0)) stays finite.
pub const MAX_F0: f32 = 0.999;

/// The conductor whose Fresnel reflectance at normal incidence is exactly
/// `f0` per channel: with eta = 1, R(0) = ((eta-1)^2 + k^2) / ((eta+1)^2 + k^2)
/// = k^2 / (4 + k^2), which equals F0 for k = 2 sqrt(F0 / (1 - F0)).
pub fn conductor_from_f0(f0: Vec3, roughness: Roughness) -> ConductorParams {
    let f0 = f0.clamp(Vec3::ZERO, Vec3::splat(MAX_F0));
    ConductorParams {
        eta: Vec3::ONE,
        k: 2.0 * (f0 / (Vec3::ONE - f0)).powf(0.5),
        specular_reflectance: Vec3::ONE,
        roughness,
    }
}

/// The glTF default material (glTF 2.0 spec, section 3.9.6: baseColor 1,
/// metallic 1, roughness 1, no emission, single-sided) as glint maps it: a
/// white-F0 GGX conductor with alpha 1. Primitives without a material use it.
pub fn gltf_default_material() -> Material {
    Material {
        name: "glTF default material".into(),
        bsdf: Bsdf::Conductor(conductor_from_f0(Vec3::ONE, isotropic(1.0))),
        emission: Vec3::ZERO,
        double_sided: false,
        absorption: glam::Vec3::ZERO,
    }
}

fn isotropic(alpha: f32) -> Roughness {
    Roughness {
        alpha_u: alpha,
        alpha_v: alpha,
        shadowing: Shadowing::Correlated,
        multiscatter: false,
    }
}

/// Map one glTF material. `multiscatter` is `--multiscatter`: the energy
/// compensation of every rough model whose `extras.bsdf` does not say.
pub fn convert(
    m: &gltf::Material,
    raw: &Value,
    multiscatter: bool,
    warnings: &mut Vec<String>,
) -> Result<Material, String> {
    let label = match m.name() {
        Some(n) => format!("material {} ('{n}')", m.index().unwrap_or(0)),
        None => format!("material {}", m.index().unwrap_or(0)),
    };
    convert_inner(m, raw, multiscatter, warnings, &label).map_err(|e| format!("{label}: {e}"))
}

fn convert_inner(
    m: &gltf::Material,
    raw: &Value,
    multiscatter: bool,
    warnings: &mut Vec<String>,
    label: &str,
) -> Result<Material, String> {
    let extras = match m.extras() {
        Some(raw) => {
            Some(serde_json::from_str::<Value>(raw.get()).map_err(|e| format!("extras: {e}"))?)
        }
        None => None,
    };
    let bsdf = match extras.as_ref().and_then(|e| e.get("bsdf")) {
        Some(b) => {
            bsdf_from_extras_with(b, multiscatter).map_err(|e| format!("extras.bsdf: {e}"))?
        }
        None => bsdf_from_gltf(m, raw, multiscatter, warnings, label)?,
    };
    let factor = Vec3::from(m.emissive_factor());
    check_range(factor, 0.0, 1.0, "emissiveFactor")?;
    let strength = m.emissive_strength().unwrap_or(1.0);
    if !(strength.is_finite() && strength >= 0.0) {
        return Err(format!(
            "emissiveStrength must be finite and >= 0, got {strength}"
        ));
    }
    // The interior's absorption: a solid dielectric (KHR_materials_volume
    // with a thickness, or extras.bsdf's dielectric) only.
    let absorption = match (&bsdf, m.volume()) {
        (Bsdf::Dielectric { .. }, Some(v)) => {
            volume_absorption(Vec3::from(v.attenuation_color()), v.attenuation_distance())
        }
        _ => Vec3::ZERO,
    };
    Ok(Material {
        name: m.name().unwrap_or_default().to_string(),
        bsdf,
        emission: factor * strength,
        double_sided: m.double_sided(),
        absorption,
    })
}

/// KHR_materials_volume's Beer-Lambert coefficient: the transmittance
/// over a distance x is `color^(x / distance)`, so sigma_a =
/// -ln(color) / distance per channel (0 for an infinite distance; a black
/// channel absorbs within 1e-20 of its distance, finite so that
/// sigma_a t never makes a NaN).
pub fn volume_absorption(color: Vec3, distance: f32) -> Vec3 {
    if !distance.is_finite() {
        return Vec3::ZERO;
    }
    color
        .max(Vec3::splat(1e-20))
        .min(Vec3::ONE)
        .map(|c| -c.ln() / distance)
}

fn check_range(v: Vec3, lo: f32, hi: f32, what: &str) -> Result<(), String> {
    if v.is_finite() && v.cmpge(Vec3::splat(lo)).all() && v.cmple(Vec3::splat(hi)).all() {
        Ok(())
    } else {
        Err(format!("{what} must lie in [{lo}, {hi}], got {v}"))
    }
}

fn check_unit(x: f32, what: &str) -> Result<f32, String> {
    if (0.0..=1.0).contains(&x) {
        Ok(x)
    } else {
        Err(format!("{what} must lie in [0, 1], got {x}"))
    }
}

/// The coat of the glTF non-metal: `KHR_materials_ior` (default 1.5,
/// against air taken as 1.0) and `KHR_materials_specular` (specularFactor
/// x specularColorFactor scales the coat's Fresnel term; clamped to 1 per
/// channel so the base term stays energy conserving, with a warning).
/// These are the factors; their textures (and transmissionTexture) are
/// applied per hit by `texture::textured_coat`.
pub fn gltf_coat(
    m: &gltf::Material,
    raw: &Value,
    warnings: &mut Vec<String>,
    label: &str,
) -> Result<CoatParams, String> {
    let eta = m.ior().unwrap_or(GLTF_DEFAULT_IOR);
    if !(eta.is_finite() && eta >= 1.0) {
        return Err(format!(
            "KHR_materials_ior ior must be finite and >= 1, got {eta}"
        ));
    }
    let mut specular = Vec3::ONE;
    if let Some(s) = m.specular() {
        let factor = check_unit(s.specular_factor(), "KHR_materials_specular specularFactor")?;
        let color = Vec3::from(s.specular_color_factor());
        if !(color.is_finite() && color.min_element() >= 0.0) {
            return Err(format!(
                "KHR_materials_specular specularColorFactor must be finite and >= 0, got {color}"
            ));
        }
        specular = factor * color;
        if specular.max_element() > 1.0 {
            warnings.push(format!(
                "{label}: KHR_materials_specular scale {specular} clamped to 1 (energy conservation)"
            ));
            specular = specular.min(Vec3::ONE);
        }
    }
    let transmission = match m.transmission() {
        Some(t) => check_unit(t.transmission_factor(), "transmissionFactor")?,
        None => 0.0,
    };
    let (clearcoat, clearcoat_alpha) = gltf_clearcoat(raw)?;
    Ok(CoatParams {
        eta,
        specular,
        transmission,
        clearcoat,
        clearcoat_alpha,
        clearcoat_normal: glam::Vec2::ZERO,
    })
}

/// `KHR_materials_clearcoat`: (clearcoatFactor, clearcoatRoughnessFactor^2).
fn gltf_clearcoat(raw: &Value) -> Result<(f32, f32), String> {
    let cc = &raw["extensions"]["KHR_materials_clearcoat"];
    if cc.is_null() {
        return Ok((0.0, 0.0));
    }
    let num = |key: &str| -> Result<f32, String> {
        match cc.get(key) {
            None => Ok(0.0),
            Some(v) => v
                .as_f64()
                .map(|x| x as f32)
                .ok_or_else(|| format!("KHR_materials_clearcoat {key} must be a number, got {v}")),
        }
    };
    let factor = check_unit(
        num("clearcoatFactor")?,
        "KHR_materials_clearcoat clearcoatFactor",
    )?;
    let rough = check_unit(
        num("clearcoatRoughnessFactor")?,
        "KHR_materials_clearcoat clearcoatRoughnessFactor",
    )?;
    // Its textures are read per hit (`texture::textured_coat`), its
    // normal texture by the integrator (`texture::clearcoat_normal`).
    Ok((factor, rough * rough))
}

/// The contract's core-glTF mapping: transmission first, then the metal
/// (metallic 1), the non-metal (metallic 0: a coat over a Lambertian base)
/// or their blend by probability `metallic`. Textures are applied per hit
/// (`texture::textured_bsdf`); here their factors are used.
fn bsdf_from_gltf(
    m: &gltf::Material,
    raw: &Value,
    multiscatter: bool,
    warnings: &mut Vec<String>,
    label: &str,
) -> Result<Bsdf, String> {
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, _alpha] = pbr.base_color_factor();
    let base = Vec3::new(r, g, b);
    check_range(base, 0.0, 1.0, "baseColorFactor")?;
    let metallic = check_unit(pbr.metallic_factor(), "metallicFactor")?;
    let roughness = check_unit(pbr.roughness_factor(), "roughnessFactor")?;
    // Perceptual roughness to GGX alpha, as the glTF BRDF appendix defines it.
    let alpha = roughness * roughness;
    let rough = Roughness {
        multiscatter,
        ..isotropic(alpha)
    };
    // KHR_materials_transmission with a thickness (KHR_materials_volume):
    // the mesh bounds a solid dielectric; without one the surface is
    // thin-walled, the non-metal's transmission lobe (`gltf_coat`).
    let transmission = match m.transmission() {
        Some(t) => check_unit(t.transmission_factor(), "transmissionFactor")?,
        None => 0.0,
    };
    let thickness = match m.volume() {
        Some(v) => {
            let d = v.thickness_factor();
            if !(d.is_finite() && d >= 0.0) {
                return Err(format!(
                    "KHR_materials_volume thicknessFactor must be finite and >= 0, got {d}"
                ));
            }
            let a = v.attenuation_distance();
            if a.is_nan() || a <= 0.0 {
                return Err(format!(
                    "KHR_materials_volume attenuationDistance must be > 0, got {a}"
                ));
            }
            let c = Vec3::from(v.attenuation_color());
            check_range(c, 0.0, 1.0, "KHR_materials_volume attenuationColor")?;
            d
        }
        None => 0.0,
    };
    if transmission > 0.0 && thickness > 0.0 {
        let ior = m.ior().unwrap_or(GLTF_DEFAULT_IOR);
        if !(ior.is_finite() && ior >= 1.0) {
            return Err(format!(
                "KHR_materials_ior ior must be finite and >= 1, got {ior}"
            ));
        }
        return Ok(Bsdf::Dielectric {
            eta: ior,
            roughness: rough,
            tint: Tint::NONE,
        });
    }
    // A metallicRoughnessTexture can make a metallic-1 material a blend
    // per hit: it keeps its coat.
    // (So does a clear coat: the blend at metallic 1 carries it.)
    let textured = pbr.metallic_roughness_texture().is_some();
    let coat = gltf_coat(m, raw, warnings, label)?;
    if metallic >= 1.0 && !textured && coat.clearcoat <= 0.0 {
        return Ok(Bsdf::Conductor(conductor_from_f0(base, rough)));
    }
    Ok(gltf_blend(metallic, base, rough, coat))
}

/// The glTF metal/non-metal blend for metallic < 1: the coated non-metal
/// alone at metallic 0, else the blend (the CPU twin of the per-hit
/// mapping's tail).
pub fn gltf_blend(metallic: f32, base: Vec3, rough: Roughness, coat: CoatParams) -> Bsdf {
    let metallic = metallic.clamp(0.0, 1.0);
    if metallic > 0.0 {
        Bsdf::Metallic {
            metallic,
            base,
            conductor: conductor_from_f0(base, rough),
            coat,
        }
    } else {
        Bsdf::Coated {
            base,
            coat,
            roughness: rough,
        }
    }
}

const TYPES: &str = "diffuse, conductor, roughconductor, dielectric, roughdielectric, \
                     thindielectric, plastic, roughplastic or twosided";
/// Mitsuba 3's `plastic` default int_ior ("polypropylene").
pub const DEFAULT_PLASTIC_INT_IOR: f32 = 1.49;
const ROUGH_KEYS: &[&str] = &[
    "alpha",
    "alpha_u",
    "alpha_v",
    "distribution",
    "shadowing",
    "multiscatter",
    "sample_visible",
];

/// The dielectrics' own parameters (`dielectric`, `roughdielectric`,
/// `thindielectric`).
const DIELECTRIC_KEYS: [&str; 4] = [
    "int_ior",
    "ext_ior",
    "specular_reflectance",
    "specular_transmittance",
];

/// Parse `extras.bsdf` with Mitsuba 3's plugin names and parameters. Like
/// Mitsuba, a parameter the type does not take is an error (it catches typos).
pub fn bsdf_from_extras(v: &Value) -> Result<Bsdf, String> {
    bsdf_from_extras_with(v, false)
}

/// The parameters an `extras.bsdf` type takes besides the roughness ones,
/// and whether it takes those.
fn bsdf_parameters(ty: &str) -> Result<(&'static [&'static str], bool), String> {
    Ok(match ty {
        "diffuse" => (&["reflectance"], false),
        "conductor" => (&["eta", "k", "material", "specular_reflectance"], false),
        "roughconductor" => (&["eta", "k", "material", "specular_reflectance"], true),
        "dielectric" => (&DIELECTRIC_KEYS, false),
        "roughdielectric" => (&DIELECTRIC_KEYS, true),
        "thindielectric" => (&DIELECTRIC_KEYS, false),
        "plastic" => (
            &[
                "diffuse_reflectance",
                "specular_reflectance",
                "int_ior",
                "ext_ior",
                "nonlinear",
            ],
            false,
        ),
        "roughplastic" => (
            &[
                "diffuse_reflectance",
                "specular_reflectance",
                "int_ior",
                "ext_ior",
                "nonlinear",
            ],
            true,
        ),
        _ => return Err(format!("unknown BSDF type \"{ty}\" (expected {TYPES})")),
    })
}

/// [`bsdf_from_extras`] with `multiscatter` the default of rough models
/// that do not give it (`--multiscatter`).
pub fn bsdf_from_extras_with(v: &Value, multiscatter_default: bool) -> Result<Bsdf, String> {
    let obj = v.as_object().ok_or("must be an object with a \"type\"")?;
    let ty = match obj.get("type") {
        Some(Value::String(s)) => s.as_str(),
        Some(other) => return Err(format!("\"type\" must be a string, got {other}")),
        None => return Err("has no \"type\"".into()),
    };
    if ty == "twosided" {
        return twosided(obj, multiscatter_default);
    }
    let (own, rough) = bsdf_parameters(ty)?;
    for key in obj.keys() {
        let known = key == "type"
            || own.contains(&key.as_str())
            || (rough && ROUGH_KEYS.contains(&key.as_str()));
        if !known {
            let mut all: Vec<&str> = own.to_vec();
            if rough {
                all.extend_from_slice(ROUGH_KEYS);
            }
            return Err(format!(
                "\"{ty}\" takes no parameter \"{key}\" (it takes {})",
                all.join(", ")
            ));
        }
    }
    let roughness = if rough {
        parse_roughness(obj, multiscatter_default)?
    } else {
        Roughness::SMOOTH
    };
    match ty {
        "diffuse" => Ok(Bsdf::Diffuse {
            reflectance: rgb(obj, "reflectance", 0.0, 1.0)?
                .unwrap_or(Vec3::splat(DEFAULT_REFLECTANCE)),
        }),
        "conductor" | "roughconductor" => Ok(Bsdf::Conductor(parse_conductor(obj, roughness)?)),
        "thindielectric" => Ok(Bsdf::ThinDielectric {
            eta: relative_ior(obj, DEFAULT_INT_IOR)?,
            tint: parse_tint(obj)?,
        }),
        "plastic" => Ok(Bsdf::Plastic(parse_plastic(obj)?)),
        "roughplastic" => {
            if roughness.alpha_u != roughness.alpha_v {
                return Err("\"roughplastic\" is isotropic (as Mitsuba's): give \"alpha\"".into());
            }
            if obj.contains_key("multiscatter") {
                return Err("\"roughplastic\" is Mitsuba's single-scattering model and takes no \"multiscatter\"".into());
            }
            Ok(Bsdf::RoughPlastic(RoughPlasticParams {
                plastic: parse_plastic(obj)?,
                roughness: Roughness {
                    multiscatter: false,
                    ..roughness
                },
            }))
        }

        _ => Ok(Bsdf::Dielectric {
            eta: relative_ior(obj, DEFAULT_INT_IOR)?,
            roughness,
            tint: parse_tint(obj)?,
        }),
    }
}

/// A dielectric's `specular_reflectance` and `specular_transmittance`
/// (each in [0, 1], default 1), Mitsuba's factors on its two parts.
fn parse_tint(obj: &Map<String, Value>) -> Result<Tint, String> {
    Ok(Tint {
        reflect: rgb(obj, "specular_reflectance", 0.0, 1.0)?.unwrap_or(Vec3::ONE),
        transmit: rgb(obj, "specular_transmittance", 0.0, 1.0)?.unwrap_or(Vec3::ONE),
    })
}

/// Mitsuba 3's `twosided` around one opaque BSDF (its one nested object,
/// under any key, as Mitsuba names nested plugins): that BSDF, since
/// glint's opaque models reflect on both sides already. Like Mitsuba, a
/// transmissive one is an error; so are two (a front and a back BSDF).
fn twosided(obj: &Map<String, Value>, multiscatter_default: bool) -> Result<Bsdf, String> {
    let nested: Vec<(&String, &Value)> = obj.iter().filter(|(k, _)| *k != "type").collect();
    let [(_, inner)] = nested[..] else {
        return Err(format!(
            "\"twosided\" takes one nested BSDF (an object with a \"type\"), got {} entries",
            nested.len()
        ));
    };
    let bsdf = bsdf_from_extras_with(inner, multiscatter_default)
        .map_err(|e| format!("in \"twosided\": {e}"))?;
    if bsdf.has_transmission() {
        return Err(
            "\"twosided\" takes an opaque BSDF (as Mitsuba's), not a transmissive one".into(),
        );
    }
    Ok(bsdf)
}

/// `plastic`'s parameters (also `roughplastic`'s), Mitsuba 3's defaults.
fn parse_plastic(obj: &Map<String, Value>) -> Result<PlasticParams, String> {
    Ok(PlasticParams {
        diffuse: rgb(obj, "diffuse_reflectance", 0.0, 1.0)?
            .unwrap_or(Vec3::splat(DEFAULT_REFLECTANCE)),
        specular: rgb(obj, "specular_reflectance", 0.0, 1.0)?.unwrap_or(Vec3::ONE),
        eta: relative_ior(obj, DEFAULT_PLASTIC_INT_IOR)?,
        nonlinear: match obj.get("nonlinear") {
            None => false,
            Some(Value::Bool(b)) => *b,
            Some(v) => return Err(format!("\"nonlinear\" must be true or false, got {v}")),
        },
    })
}

/// int_ior / ext_ior, with Mitsuba's defaults (`int_default` inside, air
/// outside).
fn relative_ior(obj: &Map<String, Value>, int_default: f32) -> Result<f32, String> {
    let int_ior = ior(obj, "int_ior")?.unwrap_or(int_default);
    let ext_ior = ior(obj, "ext_ior")?.unwrap_or(DEFAULT_EXT_IOR);
    Ok(int_ior / ext_ior)
}

fn parse_conductor(
    obj: &Map<String, Value>,
    roughness: Roughness,
) -> Result<ConductorParams, String> {
    let eta = rgb(obj, "eta", 0.0, f32::INFINITY)?;
    let k = rgb(obj, "k", 0.0, f32::INFINITY)?;
    let material = match obj.get("material") {
        None => None,
        Some(Value::String(s)) => Some(s.as_str()),
        Some(other) => return Err(format!("\"material\" must be a metal name, got {other}")),
    };
    let (eta, k) = match (material, eta, k) {
        (Some(_), Some(_), _) | (Some(_), _, Some(_)) => {
            return Err("give either \"material\" or \"eta\" and \"k\", not both".into());
        }
        (Some(name), None, None) => metal(name)?,
        (None, Some(eta), Some(k)) => (eta, k),
        (None, Some(_), None) | (None, None, Some(_)) => {
            return Err("\"eta\" and \"k\" must be given together".into());
        }
        // Mitsuba 3's default `material` is "none": a perfect mirror.
        (None, None, None) => metal("none")?,
    };
    if (eta.cmpeq(Vec3::ZERO) & k.cmpeq(Vec3::ZERO)).any() {
        return Err("\"eta\" and \"k\" are both 0 in some channel (no such conductor)".into());
    }
    Ok(ConductorParams {
        eta,
        k,
        specular_reflectance: rgb(obj, "specular_reflectance", 0.0, 1.0)?.unwrap_or(Vec3::ONE),
        roughness,
    })
}

/// A named metal's (eta, k). "none" is Mitsuba's ideal mirror: the purely
/// imaginary index eta = 0, k = 1 has |r| = 1 at every angle.
fn metal(name: &str) -> Result<(Vec3, Vec3), String> {
    if name.eq_ignore_ascii_case("none") {
        return Ok((Vec3::ZERO, Vec3::ONE));
    }
    named_metal(name).ok_or_else(|| format!("unknown metal \"{name}\""))
}

fn parse_roughness(
    obj: &Map<String, Value>,
    multiscatter_default: bool,
) -> Result<Roughness, String> {
    if let Some(d) = obj.get("distribution") {
        match d.as_str() {
            Some(s) if s.eq_ignore_ascii_case("ggx") => {}
            _ => {
                return Err(format!(
                    "\"distribution\" must be \"ggx\" (the only one glint has), got {d}"
                ));
            }
        }
    }
    let shadowing = match obj.get("shadowing") {
        None => Shadowing::Correlated,
        Some(v) => match v.as_str() {
            Some("correlated") => Shadowing::Correlated,
            Some("separable") => Shadowing::Separable,
            _ => {
                return Err(format!(
                    "\"shadowing\" must be \"correlated\" or \"separable\", got {v}"
                ));
            }
        },
    };
    // Mitsuba's choice between sampling the visible normals (its default,
    // and glint's only way) and the whole distribution: the same image in
    // expectation, other noise, so either value is taken.
    if let Some(v) = obj.get("sample_visible")
        && !v.is_boolean()
    {
        return Err(format!("\"sample_visible\" must be true or false, got {v}"));
    }
    let multiscatter = match obj.get("multiscatter") {
        None => multiscatter_default,
        Some(Value::Bool(b)) => *b,
        Some(v) => return Err(format!("\"multiscatter\" must be true or false, got {v}")),
    };
    let a = |key| number(obj, key, 0.0, f32::INFINITY);
    let (alpha_u, alpha_v) = match (a("alpha")?, a("alpha_u")?, a("alpha_v")?) {
        (Some(a), None, None) => (a, a),
        (None, Some(u), Some(v)) => (u, v),
        (None, None, None) => (DEFAULT_ALPHA, DEFAULT_ALPHA),
        (Some(_), _, _) => {
            return Err("give either \"alpha\" or \"alpha_u\" and \"alpha_v\", not both".into());
        }
        _ => return Err("\"alpha_u\" and \"alpha_v\" must be given together".into()),
    };
    Ok(Roughness {
        alpha_u,
        alpha_v,
        shadowing,
        multiscatter,
    })
}

fn number(obj: &Map<String, Value>, key: &str, lo: f32, hi: f32) -> Result<Option<f32>, String> {
    match obj.get(key) {
        None => Ok(None),
        Some(v) => {
            let x = v
                .as_f64()
                .ok_or_else(|| format!("\"{key}\" must be a number, got {v}"))?
                as f32;
            if x.is_finite() && x >= lo && x <= hi {
                Ok(Some(x))
            } else {
                Err(format!(
                    "\"{key}\" must be a finite number in [{lo}, {hi}], got {v}"
                ))
            }
        }
    }
}

/// An RGB parameter: `[r, g, b]`, or one number for grey (as Mitsuba accepts).
fn rgb(obj: &Map<String, Value>, key: &str, lo: f32, hi: f32) -> Result<Option<Vec3>, String> {
    let v = match obj.get(key) {
        None => return Ok(None),
        Some(v) => v,
    };
    // Mitsuba's dictionary form, {"type": "rgb", "value": [r, g, b]} (or a
    // number), as its Python scenes write colours: the value inside.
    let v = match v {
        Value::Object(o) if o.get("type").and_then(Value::as_str) == Some("rgb") => {
            match (o.get("value"), o.len()) {
                (Some(inner), 2) => inner,
                _ => {
                    return Err(format!(
                        "\"{key}\": an {{\"type\": \"rgb\"}} object takes one \"value\", got {v}"
                    ));
                }
            }
        }
        v => v,
    };
    let c = match v {
        Value::Number(n) => Vec3::splat(n.as_f64().unwrap_or(f64::NAN) as f32),
        Value::Array(a) if a.len() == 3 => {
            let mut c = [0.0f32; 3];
            for (ci, x) in c.iter_mut().zip(a) {
                *ci = x
                    .as_f64()
                    .ok_or_else(|| format!("\"{key}\" must hold numbers, got {v}"))?
                    as f32;
            }
            Vec3::from(c)
        }
        Value::Array(a) => {
            return Err(format!(
                "\"{key}\" must be [r, g, b] (3 numbers), got {} values",
                a.len()
            ));
        }
        _ => return Err(format!("\"{key}\" must be [r, g, b] or a number, got {v}")),
    };
    if c.is_finite() && c.cmpge(Vec3::splat(lo)).all() && c.cmple(Vec3::splat(hi)).all() {
        Ok(Some(c))
    } else {
        let range = if hi.is_finite() {
            format!("in [{lo}, {hi}]")
        } else {
            format!(">= {lo}")
        };
        Err(format!(
            "\"{key}\" values must be finite and {range}, got {v}"
        ))
    }
}

/// An index of refraction: a positive number or a name from `named_ior`.
fn ior(obj: &Map<String, Value>, key: &str) -> Result<Option<f32>, String> {
    match obj.get(key) {
        None => Ok(None),
        Some(Value::String(name)) => named_ior(name)
            .map(Some)
            .ok_or_else(|| format!("unknown IOR name \"{name}\" for \"{key}\"")),
        Some(v) => {
            let x = v
                .as_f64()
                .ok_or_else(|| format!("\"{key}\" must be a number or a name, got {v}"))?
                as f32;
            if x.is_finite() && x > 0.0 {
                Ok(Some(x))
            } else {
                Err(format!("\"{key}\" must be a finite number > 0, got {v}"))
            }
        }
    }
}
