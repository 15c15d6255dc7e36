//! glTF textures into [`SceneTextures`]: each material's texture slots
//! (with `KHR_texture_transform`, `texCoord`, sampler wrap and filter), and
//! the images they use decoded to RGBA8 (PNG, JPEG).
//!
//! Images are untrusted: the size is read from the header and checked
//! (each side 1..=[`MAX_TEXTURE_SIDE`], all images together at most
//! [`MAX_TEXELS`]) before anything is decoded. An image that is missing,
//! refused or does not decode is a warning, and the slot falls back to its
//! factor alone. The raw JSON is read (not the `gltf` crate's typed
//! wrappers) so `KHR_texture_transform` is seen on every texture slot.

use std::collections::HashMap;
use std::io::Cursor;

use glam::Vec2;
use serde_json::Value;

use super::source::{MAX_FILE_BYTES, Source};
use crate::scene::Material;
use crate::texture::{
    GpuTexture, MAP_EXTRAS, MAP_GLTF, MAP_NONE, MAX_TEXELS, MAX_TEXTURE_SIDE, MaterialTextures,
    NO_TEXTURE, SceneTextures, TEX_NEAREST, TexRef, TextureInfo, WRAP_CLAMP, WRAP_MIRROR,
    WRAP_REPEAT,
};

/// Texture slots of every material, and the images they use.
pub fn collect(
    src: &Source,
    materials: &[Material],
    warnings: &mut Vec<String>,
) -> Result<SceneTextures, String> {
    let raw = &src.raw;
    let empty = Vec::new();
    let mats = raw["materials"].as_array().unwrap_or(&empty);
    let mut out = SceneTextures::default();
    // glTF texture index -> table index (NO_TEXTURE when its image failed).
    let mut loaded: HashMap<usize, u32> = HashMap::new();
    for (i, m) in mats.iter().enumerate() {
        let label = match m["name"].as_str() {
            Some(n) => format!("material {i} ('{n}')"),
            None => format!("material {i}"),
        };
        let has_extras_bsdf = m["extras"].get("bsdf").is_some();
        let pbr = &m["pbrMetallicRoughness"];
        let mut mt = MaterialTextures::default();
        let mut slot = |v: &Value, what: &str, out: &mut SceneTextures| -> Result<TexRef, String> {
            texref(src, v, &mut loaded, out, warnings).map_err(|e| format!("{label}: {what}: {e}"))
        };
        mt.base_color = slot(&pbr["baseColorTexture"], "baseColorTexture", &mut out)?;
        if !has_extras_bsdf {
            mt.metallic_roughness = slot(
                &pbr["metallicRoughnessTexture"],
                "metallicRoughnessTexture",
                &mut out,
            )?;
        }
        mt.normal = slot(&m["normalTexture"], "normalTexture", &mut out)?;
        if mt.normal.is_some() {
            mt.normal.scale = m["normalTexture"]["scale"].as_f64().unwrap_or(1.0) as f32;
        }
        mt.emissive = slot(&m["emissiveTexture"], "emissiveTexture", &mut out)?;
        let ext = &m["extensions"];
        if !has_extras_bsdf {
            let tr = &ext["KHR_materials_transmission"];
            mt.transmission = slot(&tr["transmissionTexture"], "transmissionTexture", &mut out)?;
            let cc = &ext["KHR_materials_clearcoat"];
            mt.clearcoat = slot(&cc["clearcoatTexture"], "clearcoatTexture", &mut out)?;
            mt.clearcoat_normal = slot(
                &cc["clearcoatNormalTexture"],
                "clearcoatNormalTexture",
                &mut out,
            )?;
            if mt.clearcoat_normal.is_some() {
                mt.clearcoat_normal.scale = cc["clearcoatNormalTexture"]["scale"]
                    .as_f64()
                    .unwrap_or(1.0) as f32;
            }
            mt.clearcoat_roughness = slot(
                &cc["clearcoatRoughnessTexture"],
                "clearcoatRoughnessTexture",
                &mut out,
            )?;
            let sp = &ext["KHR_materials_specular"];
            mt.specular = slot(&sp["specularTexture"], "specularTexture", &mut out)?;
            mt.specular_color = slot(
                &sp["specularColorTexture"],
                "specularColorTexture",
                &mut out,
            )?;
        }
        factors(m, &mut mt).map_err(|e| format!("{label}: {e}"))?;
        let textured_base =
            mt.base_color.is_some() || mt.metallic_roughness.is_some() || mt.has_coat_textures();
        mt.mode = if !textured_base {
            MAP_NONE
        } else if has_extras_bsdf {
            MAP_EXTRAS
        } else {
            MAP_GLTF
        };
        out.materials.push(mt);
    }
    // The glTF default material (appended by the caller) has no textures.
    out.materials
        .resize(materials.len(), MaterialTextures::default());
    if out.is_empty() {
        return Ok(SceneTextures::default());
    }
    Ok(out)
}

/// The factors a material's textures multiply, and its alpha mode. The
/// loader (`material::gltf_coat`) has checked the coat's ranges.
fn factors(m: &Value, mt: &mut MaterialTextures) -> Result<(), String> {
    let pbr = &m["pbrMetallicRoughness"];
    let ext = &m["extensions"];
    let num = |v: &Value, d: f64| v.as_f64().unwrap_or(d) as f32;
    // An RGB(A) array, 1 where absent.
    let color = |v: &Value| {
        let a = v.as_array();
        [0, 1, 2, 3].map(|k| num(a.and_then(|a| a.get(k)).unwrap_or(&Value::Null), 1.0))
    };
    let [r, g, b, alpha] = color(&pbr["baseColorFactor"]);
    mt.base_factor = [r, g, b, 1.0];
    mt.base_alpha = alpha;
    mt.mr_factor = [
        num(&pbr["metallicFactor"], 1.0),
        num(&pbr["roughnessFactor"], 1.0),
        num(
            &ext["KHR_materials_transmission"]["transmissionFactor"],
            0.0,
        ),
        num(&ext["KHR_materials_ior"]["ior"], 1.5),
    ];
    let cc = &ext["KHR_materials_clearcoat"];
    let sp = &ext["KHR_materials_specular"];
    mt.coat_factor = [
        num(&cc["clearcoatFactor"], 0.0),
        num(&cc["clearcoatRoughnessFactor"], 0.0),
        num(&sp["specularFactor"], 1.0),
        0.0,
    ];
    let [r, g, b, _] = color(&sp["specularColorFactor"]);
    mt.specular_color_factor = [r, g, b, 1.0];
    match m["alphaMode"].as_str() {
        Some("MASK") => {
            let c = num(&m["alphaCutoff"], 0.5);
            if !(c.is_finite() && c >= 0.0) {
                return Err(format!("alphaCutoff must be finite and >= 0, got {c}"));
            }
            mt.alpha_cutoff = c;
        }
        // Stochastic transparency (SceneTextures::alpha_pass): no
        // sorting, no order-dependent compositing, unbiased.
        Some("BLEND") => mt.blend = 1,
        _ => {}
    }
    Ok(())
}

/// One `textureInfo` (or absent: no texture).
fn texref(
    src: &Source,
    info: &Value,
    loaded: &mut HashMap<usize, u32>,
    out: &mut SceneTextures,
    warnings: &mut Vec<String>,
) -> Result<TexRef, String> {
    let mut r = TexRef::default();
    if info.is_null() {
        return Ok(r);
    }
    let index = info["index"].as_u64().ok_or("has no texture \"index\"")? as usize;
    let textures = src.raw["textures"].as_array();
    let tex = textures
        .and_then(|t| t.get(index))
        .ok_or_else(|| format!("texture {index} does not exist"))?;
    let mut tex_coord = info["texCoord"].as_u64().unwrap_or(0);
    if let Some(t) = info["extensions"].get("KHR_texture_transform") {
        let pair = |key: &str, d: f32| -> Vec2 {
            let a = t[key].as_array();
            let g = |k: usize| {
                a.and_then(|a| a.get(k))
                    .and_then(Value::as_f64)
                    .map_or(d, |x| x as f32)
            };
            Vec2::new(g(0), g(1))
        };
        let offset = pair("offset", 0.0);
        let scale = pair("scale", 1.0);
        let rotation = t["rotation"].as_f64().unwrap_or(0.0) as f32;
        if !(offset.is_finite() && scale.is_finite() && rotation.is_finite()) {
            return Err("KHR_texture_transform has a non-finite value".into());
        }
        r.set_transform(offset, rotation, scale);
        if let Some(tc) = t["texCoord"].as_u64() {
            tex_coord = tc;
        }
    }
    if tex_coord > 1 {
        warnings.push(format!(
            "texture {index}: texCoord {tex_coord} is not supported (TEXCOORD_0 and _1 are); the factor alone is used"
        ));
        return Ok(r);
    }
    r.tex_coord = tex_coord as u32;
    let slot = match loaded.get(&index) {
        Some(&s) => s,
        None => {
            let s = match load_texture(src, tex, out) {
                Ok(s) => s,
                Err(e) => {
                    warnings.push(format!("texture {index}: {e}; the factor alone is used"));
                    NO_TEXTURE
                }
            };
            loaded.insert(index, s);
            s
        }
    };
    r.texture = slot;
    Ok(r)
}

fn wrap_mode(v: &Value) -> u32 {
    match v.as_u64() {
        Some(33071) => WRAP_CLAMP,
        Some(33648) => WRAP_MIRROR,
        _ => WRAP_REPEAT,
    }
}

/// Decode texture `index`'s image into the texel array; its table index.
fn load_texture(src: &Source, tex: &Value, out: &mut SceneTextures) -> Result<u32, String> {
    let raw = &src.raw;
    let image_index = tex["source"]
        .as_u64()
        .ok_or("has no image source (or only an extension's, which glint does not read)")?
        as usize;
    let image = raw["images"]
        .as_array()
        .and_then(|a| a.get(image_index))
        .ok_or_else(|| format!("image {image_index} does not exist"))?;
    let mut flags = 0;
    if let Some(s) = tex["sampler"].as_u64() {
        let sampler = raw["samplers"]
            .as_array()
            .and_then(|a| a.get(s as usize))
            .ok_or_else(|| format!("sampler {s} does not exist"))?;
        flags = wrap_mode(&sampler["wrapS"]) | (wrap_mode(&sampler["wrapT"]) << 2);
        if sampler["magFilter"].as_u64() == Some(9728) {
            flags |= TEX_NEAREST;
        }
    }
    let name = image["name"]
        .as_str()
        .or(image["uri"].as_str().filter(|u| !u.starts_with("data:")))
        .map_or_else(|| format!("image {image_index}"), str::to_string);
    let bytes = image_bytes(src, image).map_err(|e| format!("image {image_index}: {e}"))?;
    let rgba =
        decode(&bytes, out.texels.len() as u64).map_err(|e| format!("image {image_index}: {e}"))?;
    let (width, height) = rgba.dimensions();
    let offset = out.texels.len() as u32;
    out.texels
        .extend(rgba.pixels().map(|p| u32::from_le_bytes(p.0)));
    out.table.push(GpuTexture {
        offset,
        width,
        height,
        flags,
    });
    out.info.push(TextureInfo {
        name,
        width,
        height,
    });
    Ok(out.table.len() as u32 - 1)
}

fn image_bytes(src: &Source, image: &Value) -> Result<Vec<u8>, String> {
    if let Some(uri) = image["uri"].as_str() {
        return src.read_uri(uri, MAX_FILE_BYTES);
    }
    let view = image["bufferView"]
        .as_u64()
        .ok_or("has neither a uri nor a bufferView")? as usize;
    let v = src
        .doc
        .as_json()
        .buffer_views
        .get(view)
        .ok_or_else(|| format!("buffer view {view} does not exist"))?;
    let data = src
        .buffers
        .get(v.buffer.value())
        .ok_or_else(|| format!("buffer {} does not exist", v.buffer.value()))?;
    let start = v.byte_offset.map_or(0, |o| o.0) as usize;
    let end = start
        .checked_add(v.byte_length.0 as usize)
        .filter(|&e| e <= data.len())
        .ok_or_else(|| format!("buffer view {view} runs past the end of its buffer"))?;
    Ok(data[start..end].to_vec())
}

/// Decode PNG or JPEG bytes to RGBA8, checking the header's size first;
/// `already` texels are held by earlier images.
fn decode(bytes: &[u8], already: u64) -> Result<image::RgbaImage, String> {
    let reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    match reader.format() {
        Some(image::ImageFormat::Png) | Some(image::ImageFormat::Jpeg) => {}
        Some(f) => return Err(format!("{f:?} images are not supported (PNG and JPEG are)")),
        None => return Err("not a PNG or JPEG image".into()),
    }
    let (w, h) = reader
        .into_dimensions()
        .map_err(|e| format!("does not decode: {e}"))?;
    if w == 0 || h == 0 || w > MAX_TEXTURE_SIDE || h > MAX_TEXTURE_SIDE {
        return Err(format!(
            "is {w}x{h}; glint reads images of 1..={MAX_TEXTURE_SIDE} pixels a side"
        ));
    }
    if already + w as u64 * h as u64 > MAX_TEXELS {
        return Err(format!(
            "{w}x{h} would take the scene's images past {MAX_TEXELS} texels"
        ));
    }
    let mut reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    // RGBA16 of the largest image, plus slack for the decoder.
    limits.max_alloc = Some(w as u64 * h as u64 * 8 + (64 << 20));
    reader.limits(limits);
    let img = reader
        .decode()
        .map_err(|e| format!("does not decode: {e}"))?;
    Ok(img.to_rgba8())
}
