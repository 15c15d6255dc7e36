//! The prepared scene as a Mitsuba 3 scene (`glint export`): `scene.xml`
//! and one binary PLY per material, so the peer renders exactly the
//! geometry, camera, lights and image glint renders, after glint's own
//! loading (node transforms, the default camera and lighting, the
//! load-time simplifications). `scripts/mitsuba_bench.py` times both
//! renderers on what this writes.
//!
//! Exact where the models are Mitsuba's own (the contract's `extras.bsdf`
//! types: `diffuse`, `conductor`, `roughconductor`, `dielectric`,
//! `roughdielectric`, `plastic`, `roughplastic`, `thindielectric`), the
//! emitters (area lights from emissive triangles, point, directional,
//! constant background and the environment map, as `envmap` with its turn)
//! and the camera (a box filter one pixel wide, the
//! vertical field of view, `path` with the same `max_depth` and Russian
//! roulette from depth 5). Approximate, with a warning each: the glTF
//! non-metal and metallic blend (Mitsuba's `principled`), height-correlated
//! shadowing (Mitsuba's GGX is separable), `multiscatter`, anisotropic
//! lobes where the file's TANGENT turns within a face (elsewhere the PLY's
//! texture coordinates carry glint's tangent as their dP/du, the axis
//! Mitsuba orients the lobe by), the spot light's
//! falloff (glTF's quadratic ramp against Mitsuba's smoothstep), the
//! environment map's filter (Mitsuba's bilinear against glint's nearest
//! texel) and interior absorption (not written).
//!
//! Textures of the glTF metallic-roughness model are written as bitmaps
//! (`textures/*.exr`, linear, their factors multiplied in) on the meshes'
//! texture coordinates, with their wrap mode, filter and
//! `KHR_texture_transform`: base colour, metallic and roughness on
//! `principled`, the normal map as Mitsuba's `normalmap` (its tangent frame
//! is Mitsuba's own, from the texture coordinates), the alpha mask as
//! `mask` (MASK: opacity 0 or 1 at the cutoff; BLEND: the alpha) and the
//! emissive texture on the area light; a base colour texture on a
//! `diffuse` extras model. The coat's other textures (transmission, clear
//! coat, specular) keep their factors, with a warning.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use glam::{Mat4, Vec3};
use glint_cpu::bsdf::{Bsdf, ConductorParams, Roughness, Shadowing, Tint};
use glint_cpu::camera::scene_camera;
use glint_cpu::envmap::EnvMap;
use glint_cpu::frame::Frame;
use glint_cpu::loader::dpdu;
use glint_cpu::scene::{NO_LIGHT, TRI_NORMALS, TRI_SHADING_SHIFT, TRI_TANGENTS};
use glint_cpu::{PunctualLight, RenderOptions, Scene};

mod textures;
use textures::{Bitmaps, emission_xml, textured_bsdf_xml, uv_set};

/// What `export` wrote: the files (relative to the folder) and what it
/// could only approximate, one line each.
pub struct Export {
    pub files: Vec<String>,
    pub warnings: Vec<String>,
}

fn rgb(name: &str, v: Vec3) -> String {
    format!(
        r#"<rgb name="{name}" value="{:e}, {:e}, {:e}"/>"#,
        v.x, v.y, v.z
    )
}

fn float(name: &str, v: f32) -> String {
    format!(r#"<float name="{name}" value="{v:e}"/>"#)
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The GGX parameters of a rough model (`distribution`, alphas, visible
/// normal sampling), and a warning where glint's shadowing is not Mitsuba's.
fn ggx(r: &Roughness, what: &str, warnings: &mut Vec<String>) -> String {
    if r.shadowing == Shadowing::Correlated {
        warnings.push(format!(
            "{what}: height-correlated Smith shadowing written as Mitsuba's separable G1 G1"
        ));
    }
    if r.multiscatter {
        warnings.push(format!("{what}: multiscatter (energy compensation) has no Mitsuba form: single scattering written"));
    }
    format!(
        r#"<string name="distribution" value="ggx"/>{}{}<boolean name="sample_visible" value="true"/>"#,
        float("alpha_u", r.alpha_u),
        float("alpha_v", r.alpha_v)
    )
}

fn conductor(c: &ConductorParams, what: &str, warnings: &mut Vec<String>) -> String {
    let common = format!(
        "{}{}{}",
        rgb("eta", c.eta),
        rgb("k", c.k),
        rgb("specular_reflectance", c.specular_reflectance)
    );
    if c.roughness.is_smooth() {
        format!(r#"<bsdf type="conductor">{common}</bsdf>"#)
    } else {
        let g = ggx(&c.roughness, what, warnings);
        format!(r#"<bsdf type="roughconductor">{common}{g}</bsdf>"#)
    }
}

/// Mitsuba's `principled` for the glTF non-metal (`metallic` 0) and the
/// metallic blend: base colour, roughness sqrt(alpha), the coat's IOR and
/// thin transmission. An approximation: a different layering model.
fn principled(base: Vec3, metallic: f32, alpha: f32, eta: f32, spec_trans: f32) -> String {
    principled_xml(
        &rgb("base_color", base),
        &float("metallic", metallic),
        &float("roughness", alpha.max(0.0).sqrt()),
        eta,
        spec_trans,
    )
}

/// [`principled`] with its base colour, metallic and roughness given as
/// XML (values or textures).
fn principled_xml(
    base: &str,
    metallic: &str,
    roughness: &str,
    eta: f32,
    spec_trans: f32,
) -> String {
    format!(
        r#"<bsdf type="principled">{base}{metallic}{roughness}{}{}</bsdf>"#,
        float("eta", eta.max(1.0001)),
        float("spec_trans", spec_trans)
    )
}

/// The warning for a glTF model (`model`: "non-metal", "metallic blend")
/// written as `principled`.
fn principled_warning(what: &str, model: &str) -> String {
    format!("{what}: the glTF {model} written as Mitsuba's principled (another layering model)")
}

/// A dielectric's `specular_reflectance` and `specular_transmittance`.
fn tint_xml(tint: &Tint) -> String {
    rgb("specular_reflectance", tint.reflect) + &rgb("specular_transmittance", tint.transmit)
}

/// A material's BSDF as Mitsuba XML.
fn bsdf_xml(bsdf: &Bsdf, what: &str, warnings: &mut Vec<String>) -> String {
    match bsdf {
        Bsdf::Diffuse { reflectance } => {
            format!(
                r#"<bsdf type="diffuse">{}</bsdf>"#,
                rgb("reflectance", *reflectance)
            )
        }
        Bsdf::Conductor(c) => conductor(c, what, warnings),
        Bsdf::Dielectric {
            eta,
            roughness,
            tint,
        } => {
            let mut iors = format!("{}{}", float("int_ior", *eta), float("ext_ior", 1.0));
            if *tint != Tint::NONE {
                iors += &tint_xml(tint);
            }
            if roughness.is_smooth() {
                format!(r#"<bsdf type="dielectric">{iors}</bsdf>"#)
            } else {
                let g = ggx(roughness, what, warnings);
                format!(r#"<bsdf type="roughdielectric">{iors}{g}</bsdf>"#)
            }
        }
        Bsdf::Plastic(p) => format!(
            r#"<bsdf type="plastic">{}{}{}{}<boolean name="nonlinear" value="{}"/></bsdf>"#,
            rgb("diffuse_reflectance", p.diffuse),
            rgb("specular_reflectance", p.specular),
            float("int_ior", p.eta),
            float("ext_ior", 1.0),
            p.nonlinear
        ),
        Bsdf::RoughPlastic(rp) => {
            let p = &rp.plastic;
            let mut r = rp.roughness;
            // roughplastic is isotropic: alpha_u only.
            r.alpha_v = r.alpha_u;
            let g = ggx(&r, what, warnings).replace(&float("alpha_v", r.alpha_v), "");
            format!(
                r#"<bsdf type="roughplastic">{}{}{}{}<boolean name="nonlinear" value="{}"/>{}</bsdf>"#,
                rgb("diffuse_reflectance", p.diffuse),
                rgb("specular_reflectance", p.specular),
                float("int_ior", p.eta),
                float("ext_ior", 1.0),
                p.nonlinear,
                g.replace("alpha_u", "alpha")
            )
        }
        Bsdf::ThinDielectric { eta, tint } => format!(
            r#"<bsdf type="thindielectric">{}{}{}</bsdf>"#,
            float("int_ior", *eta),
            float("ext_ior", 1.0),
            tint_xml(tint)
        ),
        Bsdf::Coated {
            base,
            coat,
            roughness,
        } => {
            warnings.push(principled_warning(what, "non-metal"));
            principled(*base, 0.0, roughness.alpha_u, coat.eta, coat.transmission)
        }
        Bsdf::Metallic {
            metallic,
            base,
            conductor,
            coat,
        } => {
            warnings.push(principled_warning(what, "metallic blend"));
            principled(
                *base,
                *metallic,
                conductor.roughness.alpha_u,
                coat.eta,
                coat.transmission,
            )
        }
    }
}

/// `xml` (the BSDF `bsdf` of a material, `double_sided` as glTF's
/// doubleSided) reflecting on both sides where the material is double-sided.
/// glint's opaque models reflect on both sides of the geometry; Mitsuba's
/// are black from behind, so a double-sided material (a leaf, a plane seen
/// from either side) is wrapped in `twosided`. A single-sided one is not:
/// Mitsuba's `twosided` also reflects where only the shading normal turns
/// away from the viewer (at smooth silhouettes), where glint's light-leak
/// rule gives nothing, as the one-sided model does; a transmissive model
/// keeps its sides.
fn two_sided(bsdf: &Bsdf, double_sided: bool, xml: String) -> String {
    if !double_sided || bsdf.has_transmission() {
        xml
    } else {
        format!(r#"<bsdf type="twosided">{xml}</bsdf>"#)
    }
}

/// A triangle list as a binary little-endian PLY: three vertices per
/// triangle (positions, and normals and texture coordinates where given),
/// faces in order.
fn write_ply(
    path: &Path,
    positions: &[[f32; 3]],
    normals: Option<&[[f32; 3]]>,
    uvs: Option<&[[f32; 2]]>,
) -> Result<()> {
    let mut out = Vec::new();
    let n = positions.len();
    write!(
        out,
        "ply\nformat binary_little_endian 1.0\nelement vertex {n}\n\
         property float x\nproperty float y\nproperty float z\n"
    )?;
    if normals.is_some() {
        write!(
            out,
            "property float nx\nproperty float ny\nproperty float nz\n"
        )?;
    }
    if uvs.is_some() {
        write!(out, "property float u\nproperty float v\n")?;
    }
    write!(
        out,
        "element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        n / 3
    )?;
    for (i, p) in positions.iter().enumerate() {
        for c in p {
            out.extend_from_slice(&c.to_le_bytes());
        }
        if let Some(ns) = normals {
            for c in &ns[i] {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        if let Some(uvs) = uvs {
            for c in &uvs[i] {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    for f in 0..(n / 3) as i32 {
        out.push(3);
        for k in 0..3 {
            out.extend_from_slice(&(3 * f + k).to_le_bytes());
        }
    }
    std::fs::write(path, out).with_context(|| format!("{}", path.display()))
}

/// One mesh per (material, emitting): its triangles' vertices and
/// normals (each triangle's own, or its geometric normal where it has none).
struct Mesh {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    smooth: bool,
    /// Texture coordinate set `uv_set`'s, or coordinates that carry
    /// glint's tangents ([`tangent_uvs`]), where asked for.
    uvs: Vec<[f32; 2]>,
    /// Triangles whose tangent Mitsuba derives otherwise than glint holds
    /// it ([`same_tangent`]), where the material is anisotropic.
    other_frames: usize,
}

impl Mesh {
    /// The warning where Mitsuba will orient an anisotropic lobe otherwise
    /// than glint on some triangles (`other_frames`).
    fn frames_warning(&self, what: &str) -> Option<String> {
        (self.other_frames > 0).then(|| {
            format!(
                "{what}: anisotropic: on {} of {} triangles Mitsuba's tangent frame (dP/du of \
                 the texture coordinates written) is not glint's (from the file's TANGENT or TEXCOORD_0)",
                self.other_frames,
                self.positions.len() / 3
            )
        })
    }
}

/// Per-corner texture coordinates of triangle `p` whose dP/du is `t`
/// projected onto its plane (normal `ng`): the map from the plane onto
/// (t, ng x t) is an isometry, so Mitsuba's `dp_du` of them is that
/// projection, the axis glint's readers orient the lobe by.
fn tangent_uvs(p: [Vec3; 3], ng: Vec3, t: Vec3) -> [[f32; 2]; 3] {
    let s = (t - ng * ng.dot(t)).normalize_or_zero();
    let s = if s == Vec3::ZERO {
        Frame::from_normal(ng).s
    } else {
        s
    };
    let b = ng.cross(s);
    p.map(|q| [(q - p[0]).dot(s), (q - p[0]).dot(b)])
}

/// Whether Mitsuba 3 orients triangle `p` (texture coordinates `uv` as
/// written, or none) as glint does (`t`: glint's tangent at each corner):
/// Mitsuba takes dP/du of the coordinates (the loader's [`dpdu`]), or of
/// the barycentric parameterization (p1 - p0) where there are none or
/// they are degenerate; glint interpolates its corners' tangents. Both
/// then project onto the shading normal, so parallel is the same.
fn same_tangent(p: [Vec3; 3], uv: Option<[[f32; 2]; 3]>, t: [Vec3; 3]) -> bool {
    let m = uv
        .map(|uv| dpdu(p, uv.map(glam::Vec2::from)))
        .filter(|d| *d != Vec3::ZERO)
        .unwrap_or_else(|| (p[1] - p[0]).normalize_or_zero());
    m != Vec3::ZERO && t.iter().all(|t| t.normalize_or_zero().dot(m) > 1.0 - 1e-5)
}

/// The triangles of material `m` that emit (or not), with texture
/// coordinate set `uv_set` (0 or 1) where it is Some, or None when it has
/// none.
fn mesh_of(scene: &Scene, m: u32, emitting: bool, uv_set: Option<u32>) -> Option<Mesh> {
    let mut mesh = Mesh {
        positions: Vec::new(),
        normals: Vec::new(),
        smooth: false,
        uvs: Vec::new(),
        other_frames: 0,
    };
    let aniso = scene.material_is_anisotropic(m as usize);
    for (i, t) in scene.triangles.iter().enumerate() {
        if t.material != m || (t.light != NO_LIGHT) != emitting {
            continue;
        }
        let [a, b, c] = t.vertices();
        let ng = t.geometric_normal().normalize_or_zero();
        // glint's tangent at each corner (the frame of the geometric
        // normal where the triangle holds none), for an anisotropic lobe.
        let tangents = aniso.then(|| {
            if t.flags & TRI_TANGENTS != 0 {
                scene.shading_of(i).t.map(|c| Vec3::from_slice(&c[..3]))
            } else {
                [Frame::from_normal(ng).s; 3]
            }
        });
        let uv = match (uv_set, tangents) {
            (Some(set), _) => {
                let uv = &scene.textures.uvs[i].uv;
                let o = if set == 1 { 2 } else { 0 };
                Some([0, 1, 2].map(|k| [uv[k][o], uv[k][o + 1]]))
            }
            (None, Some(ts)) => Some(tangent_uvs([a, b, c], ng, ts[0] + ts[1] + ts[2])),
            (None, None) => None,
        };
        if let Some(ts) = tangents
            && !same_tangent([a, b, c], uv, ts)
        {
            mesh.other_frames += 1;
        }
        mesh.uvs.extend(uv.into_iter().flatten());
        let mut ns = [ng; 3];
        if t.flags & TRI_NORMALS != 0 {
            let off = (t.flags >> TRI_SHADING_SHIFT) as usize;
            for (k, n) in ns.iter_mut().enumerate() {
                *n = Vec3::from_slice(&scene.shading[off + k][..3]);
            }
            mesh.smooth = true;
        }
        for (p, n) in [a, b, c].into_iter().zip(ns) {
            mesh.positions.push(p.into());
            mesh.normals.push(n.into());
        }
    }
    (!mesh.positions.is_empty()).then_some(mesh)
}

/// The sensor: glTF's camera (looking down -Z, +X right) in Mitsuba's
/// convention (looking down +Z, +X left): the same world transform times
/// diag(-1, 1, -1).
fn sensor_xml(scene: &Scene, opts: &RenderOptions) -> String {
    let cam = scene_camera(scene, opts.camera);
    let to_world = cam.to_world * Mat4::from_scale(Vec3::new(-1.0, 1.0, -1.0));
    let rows = to_world.transpose().to_cols_array();
    let matrix = rows.map(|v| format!("{v:e}")).join(" ");
    format!(
        r#"  <sensor type="perspective">
    <string name="fov_axis" value="y"/>
    {fov}
    {near}
    <transform name="to_world"><matrix value="{matrix}"/></transform>
    <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
    <film type="hdrfilm">
      <integer name="width" value="{w}"/>
      <integer name="height" value="{h}"/>
      <string name="pixel_format" value="rgb"/>
      <rfilter type="box"/>
    </film>
  </sensor>
"#,
        fov = float("fov", cam.yfov.to_degrees()),
        near = float("near_clip", 1e-4),
        spp = opts.spp,
        w = opts.width,
        h = opts.height,
    )
}

/// A linear RGB EXR of `mean` (row by row, top first), through glint's own
/// writer: the same texels give the same bytes, so an export can be
/// compared or committed (the `image` crate's EXR header came out in
/// another order at every run).
pub(super) fn write_exr(path: &Path, width: u32, height: u32, mean: Vec<Vec3>) -> Result<()> {
    glint_cpu::exr_file::RadianceImage {
        width,
        height,
        mean,
        variance: None,
        meta: None,
    }
    .write_file(path)
    .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}

/// The environment map as Mitsuba's `envmap`: its texels as glint holds
/// them (the scale applied, non-finite ones 0) in `textures/envmap.exr`,
/// turned about +Y by its rotation. Both map a direction d to
/// (atan2(d.x, -d.z) / 2 pi, acos(d.y) / pi) in the map's frame and turn
/// it right-handed about +Y (rendered against each other on a sky-only
/// view: docs/benchmarks.md; `tests/export.rs` checks the file and the
/// turn); Mitsuba filters the map bilinearly where glint takes the nearest
/// texel, a warning says so.
fn envmap_xml(env: &EnvMap, dir: &Path, warnings: &mut Vec<String>) -> Result<(String, String)> {
    let file = "textures/envmap.exr".to_string();
    std::fs::create_dir_all(dir.join("textures")).with_context(|| format!("{}", dir.display()))?;
    let mean = env
        .texels
        .iter()
        .map(|t| Vec3::new(t[0], t[1], t[2]))
        .collect();
    write_exr(&dir.join(&file), env.width, env.height, mean)?;
    warnings.push(
        "the environment map: Mitsuba filters it bilinearly, glint takes the nearest texel".into(),
    );
    let xml = format!(
        r#"  <emitter type="envmap"><string name="filename" value="{file}"/><transform name="to_world"><rotate y="1" angle="{:e}"/></transform></emitter>"#,
        env.rotation.to_degrees()
    );
    Ok((xml, file))
}

/// The punctual lights, and the background: the environment map (its
/// file written into `dir` and named in `files`) or the constant.
fn lights_xml(
    scene: &Scene,
    dir: &Path,
    files: &mut Vec<String>,
    warnings: &mut Vec<String>,
) -> Result<String> {
    let mut xml = String::new();
    for l in &scene.lights {
        let _ = match *l {
            PunctualLight::Point {
                position,
                intensity,
            } => writeln!(
                xml,
                r#"  <emitter type="point"><point name="position" x="{:e}" y="{:e}" z="{:e}"/>{}</emitter>"#,
                position.x,
                position.y,
                position.z,
                rgb("intensity", intensity)
            ),
            PunctualLight::Spot {
                position,
                direction,
                intensity,
                inner_cone_angle,
                outer_cone_angle,
            } => {
                warnings.push(
                    "a spot light: glTF's quadratic cone ramp written as Mitsuba's spot falloff"
                        .into(),
                );
                let target = position + direction;
                writeln!(
                    xml,
                    r#"  <emitter type="spot"><transform name="to_world"><lookat origin="{:e}, {:e}, {:e}" target="{:e}, {:e}, {:e}" up="{}"/></transform>{}{}{}</emitter>"#,
                    position.x,
                    position.y,
                    position.z,
                    target.x,
                    target.y,
                    target.z,
                    if direction.y.abs() > 0.9 {
                        "1, 0, 0"
                    } else {
                        "0, 1, 0"
                    },
                    rgb("intensity", intensity),
                    float("cutoff_angle", outer_cone_angle.to_degrees()),
                    float("beam_width", inner_cone_angle.to_degrees())
                )
            }
            PunctualLight::Directional {
                direction,
                irradiance,
            } => writeln!(
                xml,
                r#"  <emitter type="directional"><vector name="direction" x="{:e}" y="{:e}" z="{:e}"/>{}</emitter>"#,
                direction.x,
                direction.y,
                direction.z,
                rgb("irradiance", irradiance)
            ),
        };
    }
    if let Some(env) = &scene.envmap {
        let (env_xml, file) = envmap_xml(env, dir, warnings)?;
        let _ = writeln!(xml, "{env_xml}");
        files.push(file);
    } else if scene.background.max_element() > 0.0 {
        let _ = writeln!(
            xml,
            r#"  <emitter type="constant">{}</emitter>"#,
            rgb("radiance", scene.background)
        );
    }
    Ok(xml)
}

/// Write `scene` as Mitsuba 3 XML and PLY meshes into `dir` (created),
/// for the render `opts` describes (size, spp, depth, camera).
pub fn export(scene: &Scene, opts: &RenderOptions, dir: &Path) -> Result<Export> {
    std::fs::create_dir_all(dir.join("meshes")).with_context(|| format!("{}", dir.display()))?;
    let mut warnings = Vec::new();
    let mut files = Vec::new();
    let mut shapes = String::new();
    let mut bitmaps = Bitmaps {
        scene,
        dir,
        files: Vec::new(),
    };
    for (m, mat) in scene.materials.iter().enumerate() {
        let what = format!("material {m} ({})", mat.name);
        if mat.absorption != Vec3::ZERO {
            warnings.push(format!("{what}: interior absorption is not written"));
        }
        let mt = scene.textures.material(m as u32);
        let textured = match mt {
            Some(mt) => textured_bsdf_xml(&mut bitmaps, mt, mat, &what, &mut warnings)?,
            None => None,
        };
        let emission_tex = match mt {
            Some(mt) if mat.is_emissive() => {
                emission_xml(&mut bitmaps, mt, mat.emission, &mut warnings)?
            }
            _ => None,
        };
        if textured.is_none() && mt.is_some_and(|t| t.has_alpha_test()) {
            warnings.push(format!("{what}: the alpha mask is not written"));
        }
        let uv_set = match mt {
            Some(mt) if textured.is_some() || emission_tex.is_some() => {
                Some(uv_set(mt, &what, &mut warnings))
            }
            _ => None,
        };
        let bsdf = match textured {
            Some(xml) => xml,
            None => two_sided(
                &mat.bsdf,
                mat.double_sided,
                bsdf_xml(&mat.bsdf, &what, &mut warnings),
            ),
        };
        if mat.is_emissive() && mat.double_sided {
            warnings.push(format!(
                "{what}: a double-sided emitter written one-sided (Mitsuba's area lights emit from the front)"
            ));
        }
        for emitting in [false, true] {
            {
                let Some(mesh) = mesh_of(scene, m as u32, emitting, uv_set) else {
                    continue;
                };
                let id = format!("m{m}{}", if emitting { "e" } else { "" });
                let name = format!("meshes/{id}.ply");
                let normals = mesh.smooth.then_some(&mesh.normals[..]);
                let uvs = (!mesh.uvs.is_empty()).then_some(&mesh.uvs[..]);
                warnings.extend(mesh.frames_warning(&what));
                write_ply(&dir.join(&name), &mesh.positions, normals, uvs)?;
                files.push(name.clone());
                let emitter = if emitting {
                    let radiance = emission_tex
                        .clone()
                        .unwrap_or_else(|| rgb("radiance", mat.emission));
                    format!(r#"<emitter type="area">{radiance}</emitter>"#)
                } else {
                    String::new()
                };
                let _ = writeln!(
                    shapes,
                    r#"  <shape type="ply" id="{}"><string name="filename" value="{name}"/>{}{bsdf}{emitter}</shape>"#,
                    xml_escape(&id),
                    if mesh.smooth {
                        ""
                    } else {
                        r#"<boolean name="face_normals" value="true"/>"#
                    },
                );
            }
        }
    }
    let lights = lights_xml(scene, dir, &mut files, &mut warnings)?;
    let depth = opts.max_depth;
    let xml = format!(
        r#"<?xml version="1.0" encoding="utf-8"?>
<!-- Written by glint export: the prepared scene for Mitsuba 3. -->
<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="{depth}"/><integer name="rr_depth" value="5"/></integrator>
{sensor}{lights}{shapes}</scene>
"#,
        sensor = sensor_xml(scene, opts),
    );
    std::fs::write(dir.join("scene.xml"), xml)
        .with_context(|| format!("{}", dir.join("scene.xml").display()))?;
    files.insert(0, "scene.xml".into());
    files.extend(bitmaps.files);
    warnings.dedup();
    Ok(Export { files, warnings })
}
