//! `glint stability --methods`: where the sampling methods fail. Veach's
//! test (thesis 1997, figure 9.2): a plate from near-mirror to rough, lit
//! by a light from point-like to large at equal power, rendered with each
//! technique (BSDF sampling alone, light sampling alone, MIS with the
//! balance and the power heuristic, adaptive sampling) at equal time on
//! each backend, and measured against one high-spp reference per cell.
//!
//! The scene of a cell (built in code, [`scene`]): a square plate of the
//! cell's model in the y = 0 plane, seen from 45 degrees above, and a
//! black background. The light, in the mirror direction of the view ray at
//! the plate's centre and out of the camera's view, is one of three
//! families ([`Family`]):
//! - `sphere` (Veach's): a sphere of radius r and radiance 10 / r^2 (power
//!   40 pi^2 at every radius, so the plate's diffuse radiance is of order
//!   1), centred 2.5 away. Its 1024 triangles each subtend under 2e-3 sr
//!   from the plate, so light sampling picks their points by area.
//! - `quad`: a one-sided square of half-side r facing the plate's centre
//!   2.5 away, radiance 10 pi / r^2 (the same power): two triangles that
//!   subtend up to about 1 sr each from the plate's far side, where light
//!   sampling picks points by solid angle (`--light-sampling`); the sweep
//!   also renders it by area, before and after.
//! - `envmap`: an environment map, black but for a sun disc of angular
//!   radius r whose radiance times its solid angle is 5 (the sphere's
//!   irradiance at the plate's centre), importance sampled by texel.
//!
//! Where the lobe is narrow and the light large, light sampling fails (its
//! samples fall outside the lobe); where the lobe is wide and the light
//! small, BSDF sampling fails (its samples miss the light). MIS should be
//! close to the better of the two everywhere.

use std::f32::consts::PI;

use glam::{Mat4, Vec2, Vec3};
use glint_cpu::bsdf::plastic::PlasticParams;
use glint_cpu::bsdf::roughplastic::RoughPlasticParams;
use glint_cpu::bsdf::{Bsdf, ConductorParams, Roughness, Shadowing};
use glint_cpu::envmap::{EnvMap, uv_to_map_direction};
use glint_cpu::metrics::{self, ImageRef};
use glint_cpu::{
    Camera, Film, LightSampling, Material, Mis, NO_LIGHT, RenderOptions, Scene, Triangle,
};

/// A sampling technique, as the render options select it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Technique {
    /// BSDF sampling alone (`--nee off`).
    Bsdf,
    /// Light sampling alone for the area light (`--mis none`).
    Light,
    /// MIS, balance heuristic (`--mis balance`).
    MisBalance,
    /// MIS, power heuristic (the default).
    MisPower,
    /// MIS (power) with per-pixel adaptive sampling (`--adaptive`
    /// [`ADAPTIVE_THRESHOLD`]): it cannot take a time limit, so its cap is
    /// the samples the power heuristic reached in the cell's time, and its
    /// relMSE is scaled to the cell's time like the others'.
    Adaptive,
}

/// The adaptive technique's per-pixel relative error target: low enough
/// that the noisy pixels run to the cap while the converged ones stop.
pub const ADAPTIVE_THRESHOLD: f64 = 0.01;

impl Technique {
    pub const ALL: [Technique; 5] = [
        Technique::Bsdf,
        Technique::Light,
        Technique::MisBalance,
        Technique::MisPower,
        Technique::Adaptive,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Technique::Bsdf => "bsdf",
            Technique::Light => "light",
            Technique::MisBalance => "mis-balance",
            Technique::MisPower => "mis-power",
            Technique::Adaptive => "adaptive",
        }
    }

    /// `o` with this technique's switches.
    pub fn options(self, o: &RenderOptions) -> RenderOptions {
        let (nee, mis) = match self {
            Technique::Bsdf => (false, Mis::Power),
            Technique::Light => (true, Mis::None),
            Technique::MisBalance => (true, Mis::Balance),
            Technique::MisPower | Technique::Adaptive => (true, Mis::Power),
        };
        RenderOptions {
            nee,
            mis,
            adaptive: (self == Technique::Adaptive).then_some(ADAPTIVE_THRESHOLD),
            ..o.clone()
        }
    }
}

/// The plate's model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Model {
    /// `roughconductor`, aluminium (GGX, height-correlated Smith).
    Conductor,
    /// Mitsuba's `roughplastic` (GGX coat over a 0.5 grey base).
    RoughPlastic,
}

impl Model {
    pub const ALL: [Model; 2] = [Model::Conductor, Model::RoughPlastic];

    pub fn name(self) -> &'static str {
        match self {
            Model::Conductor => "roughconductor",
            Model::RoughPlastic => "roughplastic",
        }
    }

    fn bsdf(self, alpha: f32) -> Bsdf {
        let roughness = Roughness {
            alpha_u: alpha,
            alpha_v: alpha,
            shadowing: Shadowing::Correlated,
            multiscatter: false,
        };
        match self {
            Model::Conductor => {
                let (eta, k) = glint_cpu::bsdf::named_metal("Al").expect("a tabulated metal");
                Bsdf::Conductor(ConductorParams {
                    eta,
                    k,
                    specular_reflectance: Vec3::ONE,
                    roughness,
                })
            }
            Model::RoughPlastic => Bsdf::RoughPlastic(RoughPlasticParams {
                plastic: PlasticParams {
                    diffuse: Vec3::splat(0.5),
                    specular: Vec3::ONE,
                    eta: 1.49,
                    nonlinear: false,
                },
                roughness,
            }),
        }
    }
}

/// The light of a cell's scene (module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Family {
    /// Veach's sphere light: many small triangles.
    Sphere,
    /// A close square light: two large triangles.
    Quad,
    /// A sun disc in an environment map.
    Envmap,
}

impl Family {
    pub const ALL: [Family; 3] = [Family::Sphere, Family::Quad, Family::Envmap];

    pub fn name(self) -> &'static str {
        match self {
            Family::Sphere => "sphere",
            Family::Quad => "quad",
            Family::Envmap => "envmap",
        }
    }

    /// The stem of the family's CSV and chart in the output folder
    /// (Veach's sphere keeps the contract's `methods`).
    pub fn stem(self) -> &'static str {
        match self {
            Family::Sphere => "methods",
            Family::Quad => "methods-quad",
            Family::Envmap => "methods-envmap",
        }
    }

    /// What the column parameter r is.
    pub fn radius_meaning(self) -> &'static str {
        match self {
            Family::Sphere => "sphere light of radius r",
            Family::Quad => "square light of half-side r, 2.5 away",
            Family::Envmap => "environment sun of angular radius r (radians)",
        }
    }
}

/// One cell of the sweep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    pub family: Family,
    pub model: Model,
    pub alpha: f32,
    pub radius: f32,
}

/// The sweep's extent and budgets.
#[derive(Clone, Debug)]
pub struct Sweep {
    pub alphas: Vec<f32>,
    /// Each family's light sizes (the columns), in [`Family::ALL`]'s order.
    pub radii: Vec<(Family, Vec<f32>)>,
    /// Image side, pixels.
    pub size: u32,
    /// Each technique's time per cell and backend (seconds of rendering).
    pub seconds: f64,
    /// The spp cap of a timed render (never reached in practice).
    pub max_spp: u32,
    /// The reference's spp (MIS, power heuristic).
    pub reference_spp: u32,
}

impl Sweep {
    /// The full sweep, or the small one CI runs.
    pub fn new(quick: bool) -> Sweep {
        if quick {
            Sweep {
                alphas: vec![0.002, 0.05, 1.0],
                radii: vec![
                    (Family::Sphere, vec![0.01, 0.1, 0.6]),
                    (Family::Quad, vec![0.05, 1.5]),
                    (Family::Envmap, vec![0.02, 0.5]),
                ],
                size: 24,
                seconds: 0.05,
                max_spp: 1 << 16,
                reference_spp: 1024,
            }
        } else {
            Sweep {
                alphas: vec![0.001, 0.005, 0.02, 0.08, 0.3, 1.0],
                radii: vec![
                    (Family::Sphere, vec![0.005, 0.02, 0.08, 0.25, 0.6]),
                    (Family::Quad, vec![0.02, 0.08, 0.3, 0.8, 1.5]),
                    (Family::Envmap, vec![0.02, 0.06, 0.2, 0.5, 0.7]),
                ],
                size: 32,
                seconds: 0.25,
                max_spp: 1 << 20,
                reference_spp: 4096,
            }
        }
    }

    /// The sizes of `family`'s lights.
    pub fn radii(&self, family: Family) -> &[f32] {
        self.radii
            .iter()
            .find(|r| r.0 == family)
            .map_or(&[], |r| &r.1[..])
    }

    /// Whether `c` is at a corner of its family's grid (the smallest or
    /// largest alpha with the smallest or largest light), where one
    /// technique's variance is infinite-like.
    pub fn corner(&self, c: &Cell) -> bool {
        let (a, r) = (&self.alphas, self.radii(c.family));
        (c.alpha == a[0] || c.alpha == a[a.len() - 1])
            && (c.radius == r[0] || c.radius == r[r.len() - 1])
    }

    /// Every cell: family, model, alpha, radius, in that nesting.
    pub fn cells(&self) -> Vec<Cell> {
        let mut v = Vec::new();
        for (family, radii) in &self.radii {
            for model in Model::ALL {
                for &alpha in &self.alphas {
                    for &radius in radii {
                        v.push(Cell {
                            family: *family,
                            model,
                            alpha,
                            radius,
                        });
                    }
                }
            }
        }
        v
    }

    /// The options of a cell's renders (before the technique's switches).
    pub fn options(&self, seed: u64) -> RenderOptions {
        RenderOptions {
            seed,
            // Direct lighting only: the plate is the only reflector, so a
            // second bounce adds nothing but the technique's own noise.
            max_depth: 2,
            ..RenderOptions::new(self.size, self.size)
        }
    }
}

/// The sphere light's radiance at radius `r`: equal power (4 pi^2 r^2 L)
/// at every radius.
pub fn light_radiance(r: f32) -> f32 {
    10.0 / (r * r)
}

/// The quad light's radiance at half-side `r`: the sphere's power
/// (one-sided, pi (2r)^2 L).
pub fn quad_radiance(r: f32) -> f32 {
    10.0 * PI / (r * r)
}

/// The sun's radiance times its solid angle (the sphere light's
/// irradiance at the plate's centre, 10 pi cos 45 / 2.5^2, rounded).
pub const SUN_POWER: f32 = 5.0;
/// The environment map's size: a texel spans 0.012 rad, so the smallest
/// sun (0.02 rad) covers several.
pub const ENVMAP_SIZE: (u32, u32) = (512, 256);

fn tri(a: Vec3, b: Vec3, c: Vec3, material: u32) -> Triangle {
    Triangle {
        p0: a.into(),
        material,
        p1: b.into(),
        light: NO_LIGHT,
        p2: c.into(),
        flags: 0,
    }
}

/// A flat-shaded UV sphere with outward faces.
fn sphere(c: Vec3, r: f32, n_phi: u32, n_theta: u32, material: u32) -> Vec<Triangle> {
    let p = |i: u32, j: u32| {
        let th = PI * i as f32 / n_theta as f32;
        let ph = 2.0 * PI * j as f32 / n_phi as f32;
        c + r * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin())
    };
    let mut out = Vec::new();
    for i in 0..n_theta {
        for j in 0..n_phi {
            let (a, b, cc, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            for (x, y, z) in [(a, b, cc), (a, cc, d)] {
                let t = tri(x, y, z, material);
                if t.area() < 1e-12 * r * r {
                    continue;
                }
                let outward = t.geometric_normal().dot((x + y + z) / 3.0 - c) >= 0.0;
                out.push(if outward { t } else { tri(x, z, y, material) });
            }
        }
    }
    out
}

/// A square of half-side `r` centred at `c`, its front face towards
/// `-axis` (`axis` a unit vector, not +-X).
fn quad(c: Vec3, axis: Vec3, r: f32, material: u32) -> [Triangle; 2] {
    let u = Vec3::X * r;
    let v = axis.cross(Vec3::X).normalize() * r;
    let corners = [c - u - v, c + u - v, c + u + v, c - u + v];
    let [a, b, cc, d] = corners;
    let facing = |t: Triangle| {
        if t.geometric_normal().dot(axis) < 0.0 {
            t
        } else {
            tri(t.p0.into(), t.p2.into(), t.p1.into(), material)
        }
    };
    [
        facing(tri(a, b, cc, material)),
        facing(tri(a, cc, d, material)),
    ]
}

/// The environment map of a sun of angular radius `r` about `dir`: the
/// texels whose centres lie within `r` of it, their radiance
/// [`SUN_POWER`] over their total solid angle.
pub fn sun_envmap(dir: Vec3, r: f32) -> EnvMap {
    let (w, h) = ENVMAP_SIZE;
    let cos_r = r.cos();
    let mut inside = vec![false; (w * h) as usize];
    let mut omega = 0.0f64;
    for y in 0..h {
        let v = (y as f32 + 0.5) / h as f32;
        let texel = (2.0 * PI / w as f32) * (PI / h as f32) * (PI * v).sin();
        for x in 0..w {
            let u = (x as f32 + 0.5) / w as f32;
            if uv_to_map_direction(Vec2::new(u, v)).dot(dir) >= cos_r {
                inside[(y * w + x) as usize] = true;
                omega += texel as f64;
            }
        }
    }
    let l = (SUN_POWER as f64 / omega.max(1e-12)) as f32;
    let rgb: Vec<[f32; 3]> = inside
        .iter()
        .map(|&i| if i { [l; 3] } else { [0.0; 3] })
        .collect();
    // No rotation: the map's directions are the world's.
    EnvMap::new(w, h, &rgb, 1.0, 0.0)
}

/// The cell's scene (module documentation).
pub fn scene(cell: &Cell) -> Scene {
    let eye = Vec3::new(0.0, 2.0, 2.0);
    let mirror = Vec3::new(0.0, 1.0, -1.0).normalize();
    let light_at = mirror * 2.5;
    let s = 3.0;
    let mut triangles = vec![
        tri(
            Vec3::new(-s, 0.0, s),
            Vec3::new(s, 0.0, s),
            Vec3::new(s, 0.0, -s),
            0,
        ),
        tri(
            Vec3::new(-s, 0.0, s),
            Vec3::new(s, 0.0, -s),
            Vec3::new(-s, 0.0, -s),
            0,
        ),
    ];
    let mut envmap = None;
    let radiance = match cell.family {
        Family::Sphere => {
            triangles.extend(sphere(light_at, cell.radius, 32, 16, 1));
            light_radiance(cell.radius)
        }
        Family::Quad => {
            triangles.extend(quad(light_at, mirror, cell.radius, 1));
            quad_radiance(cell.radius)
        }
        Family::Envmap => {
            envmap = Some(std::sync::Arc::new(sun_envmap(mirror, cell.radius)));
            0.0
        }
    };
    let plate = Material {
        name: cell.model.name().into(),
        bsdf: cell.model.bsdf(cell.alpha),
        emission: Vec3::ZERO,
        double_sided: false,
        absorption: Vec3::ZERO,
    };
    let light = Material {
        name: "light".into(),
        bsdf: Bsdf::Diffuse {
            reflectance: Vec3::ZERO,
        },
        emission: Vec3::splat(radiance),
        double_sided: false,
        absorption: Vec3::ZERO,
    };
    let camera = Camera {
        name: None,
        node_name: None,
        to_world: Mat4::look_at_rh(eye, Vec3::ZERO, Vec3::Y).inverse(),
        yfov: 40f32.to_radians(),
        aspect_ratio: None,
    };
    let mut scene = Scene {
        triangles,
        materials: vec![plate, light],
        cameras: vec![camera],
        envmap,
        ..Scene::default()
    };
    scene.build_bvh();
    scene
}

/// A render: the film and its render seconds.
pub type Render<'a> = dyn Fn(&Scene, &RenderOptions) -> Result<(Film, f64), String> + 'a;

/// One measurement.
#[derive(Clone, Debug)]
pub struct Row {
    pub backend: String,
    pub cell: Cell,
    pub technique: Technique,
    /// How light samples picked points on emissive triangles: the default
    /// in every row but the quad family's before/after ones.
    pub sampling: LightSampling,
    pub seconds: f64,
    pub spp: u32,
    pub relmse: f64,
}

/// relMSE of `film` against `reference`.
pub fn relmse(film: &Film, reference: &Film) -> Result<f64, String> {
    let pixels = |f: &Film| (0..f.sum.len()).map(|i| f.mean(i)).collect::<Vec<_>>();
    let (a, b) = (pixels(film), pixels(reference));
    let ia = ImageRef::new(film.width, film.height, &a).map_err(|e| e.to_string())?;
    let ib = ImageRef::new(reference.width, reference.height, &b).map_err(|e| e.to_string())?;
    metrics::relmse(&ia, &ib).map_err(|e| e.to_string())
}

/// The techniques rendered a second time by area in the quad family (the
/// solid-angle sampling's before and after).
pub const AREA_TECHNIQUES: [Technique; 2] = [Technique::Light, Technique::MisPower];

/// Every cell and technique on one backend: each technique rendered for
/// `sweep.seconds` (`--time-limit`), against a reference of
/// `sweep.reference_spp` (power heuristic, another seed); in the quad
/// family, [`AREA_TECHNIQUES`] again under `--light-sampling area`.
pub fn run(sweep: &Sweep, backend: &str, render: &Render<'_>) -> Result<Vec<Row>, String> {
    let mut rows = Vec::new();
    for cell in sweep.cells() {
        let s = scene(&cell);
        let reference = RenderOptions {
            spp: sweep.reference_spp,
            ..sweep.options(0x5eed_0001)
        };
        let (reference, _) = render(&s, &reference)?;
        let mut power_spp = sweep.max_spp;
        let mut runs: Vec<(Technique, LightSampling)> = Technique::ALL
            .iter()
            .map(|&t| (t, LightSampling::SolidAngle))
            .collect();
        if cell.family == Family::Quad {
            runs.extend(AREA_TECHNIQUES.iter().map(|&t| (t, LightSampling::Area)));
        }
        for (technique, sampling) in runs {
            let base = RenderOptions {
                light_sampling: sampling,
                ..technique.options(&sweep.options(7))
            };
            let o = match technique {
                // No time limit: the samples the power heuristic reached.
                Technique::Adaptive => RenderOptions {
                    spp: power_spp.max(1),
                    ..base
                },
                _ => RenderOptions {
                    spp: sweep.max_spp,
                    time_limit: Some(sweep.seconds),
                    ..base
                },
            };
            let (film, seconds) = render(&s, &o)?;
            if technique == Technique::MisPower && sampling == LightSampling::SolidAngle {
                power_spp = film.spp;
            }
            rows.push(Row {
                backend: backend.to_string(),
                cell,
                technique,
                sampling,
                seconds,
                spp: film.spp,
                relmse: relmse(&film, &reference)?,
            });
        }
    }
    Ok(rows)
}

/// The relMSE a row would reach in `seconds`: relMSE falls as 1 / time, so
/// a render that overshot its budget is not credited for it.
pub fn at_time(r: &Row, seconds: f64) -> f64 {
    r.relmse * r.seconds / seconds
}

impl Row {
    /// The CSV columns that name the row: backend, model, alpha,
    /// light_radius, technique.
    fn key_columns(&self) -> String {
        format!(
            "{},{},{},{},{}",
            self.backend,
            self.cell.model.name(),
            self.cell.alpha,
            self.cell.radius,
            self.technique.name()
        )
    }
}

/// The contract's CSV of one family's rows (default light sampling).
pub fn csv(rows: &[Row], family: Family) -> String {
    let mut s = String::from("backend,model,alpha,light_radius,technique,seconds,relmse\n");
    for r in rows
        .iter()
        .filter(|r| r.cell.family == family && r.sampling == LightSampling::default())
    {
        s.push_str(&format!(
            "{},{:.6},{:.6e}\n",
            r.key_columns(),
            r.seconds,
            r.relmse
        ));
    }
    s
}

/// The quad family's before/after: [`AREA_TECHNIQUES`] by solid angle and
/// by area, `light_sampling` the option's value.
pub fn light_sampling_csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "backend,model,alpha,light_radius,technique,light_sampling,seconds,spp,relmse\n",
    );
    for r in rows
        .iter()
        .filter(|r| r.cell.family == Family::Quad && AREA_TECHNIQUES.contains(&r.technique))
    {
        s.push_str(&format!(
            "{},{},{:.6},{},{:.6e}\n",
            r.key_columns(),
            r.sampling.name(),
            r.seconds,
            r.spp,
            r.relmse
        ));
    }
    s
}

/// The rows of one (backend, family, model) by cell, in `sweep`'s order.
fn group<'r>(rows: &'r [Row], backend: &str, family: Family, model: Model) -> Vec<&'r Row> {
    rows.iter()
        .filter(|r| r.backend == backend && r.cell.family == family && r.cell.model == model)
        .collect()
}

fn find<'r>(
    g: &[&'r Row],
    alpha: f32,
    radius: f32,
    t: Technique,
    sampling: LightSampling,
) -> Option<&'r Row> {
    g.iter().copied().find(|r| {
        r.cell.alpha == alpha
            && r.cell.radius == radius
            && r.technique == t
            && r.sampling == sampling
    })
}

/// The best technique of a cell at equal time, and each technique's relMSE
/// at equal time over the best's (default light sampling).
pub fn ratios(g: &[&Row], alpha: f32, radius: f32, seconds: f64) -> Vec<(Technique, f64)> {
    let v: Vec<(Technique, f64)> = Technique::ALL
        .iter()
        .filter_map(|&t| {
            find(g, alpha, radius, t, LightSampling::default()).map(|r| (t, at_time(r, seconds)))
        })
        .collect();
    let best = v.iter().map(|x| x.1).fold(f64::INFINITY, f64::min);
    v.into_iter().map(|(t, e)| (t, e / best)).collect()
}

pub fn markdown(rows: &[Row], sweep: &Sweep, devices: &[(String, String)]) -> String {
    let mut s = String::from("# glint stability --methods: where sampling methods fail\n\n");
    s.push_str(&format!(
        "Veach's sweep (thesis figure 9.2): a plate of each model at GGX alpha (rows) lit by a \
         light of size r (columns) at equal power, {0}x{0} pixels, direct lighting, in three \
         families: Veach's sphere light (`methods.csv`), a close square light of two large \
         triangles (`methods-quad.csv`) and a sun in an environment map \
         (`methods-envmap.csv`). Each technique renders for {1} s per cell (`--time-limit`) \
         against a {2}-spp reference (MIS, power heuristic, another seed); relMSE is scaled to \
         exactly {1} s (relMSE x seconds / {1}). `adaptive` (the power heuristic with \
         `--adaptive {3}`) cannot take a time limit: its cap is the samples per pixel the \
         power heuristic reached in the cell's time, and its relMSE is scaled the same way. \
         `src/methods.rs` builds the scenes.\n\n",
        sweep.size, sweep.seconds, sweep.reference_spp, ADAPTIVE_THRESHOLD
    ));
    for (backend, device) in devices {
        s.push_str(&format!("Backend `{backend}`: {device}.\n\n"));
    }
    for (backend, _) in devices {
        for family in Family::ALL {
            for model in Model::ALL {
                let g = group(rows, backend, family, model);
                if !g.is_empty() {
                    family_tables(&mut s, &g, sweep, backend, family, model);
                }
            }
        }
    }
    for (backend, _) in devices {
        for model in Model::ALL {
            let g = group(rows, backend, Family::Quad, model);
            if !g.is_empty() {
                before_after(&mut s, &g, sweep, backend, model);
            }
        }
    }
    s
}

/// A family's heading: Veach's sphere keeps the plain one.
fn heading(backend: &str, family: Family, model: Model) -> String {
    match family {
        Family::Sphere => format!("{backend}, {}", model.name()),
        _ => format!("{backend}, {}, {}", model.name(), family.name()),
    }
}

fn family_tables(
    s: &mut String,
    g: &[&Row],
    sweep: &Sweep,
    backend: &str,
    family: Family,
    model: Model,
) {
    let radii = sweep.radii(family);
    s.push_str(&format!(
        "## {}\n\nColumns: {}. Best technique per cell at equal time (the others' relMSE over \
         the best's in brackets):\n\n",
        heading(backend, family, model),
        family.radius_meaning()
    ));
    header(s, radii);
    for &alpha in &sweep.alphas {
        s.push_str(&format!("| {alpha} |"));
        for &radius in radii {
            let mut r = ratios(g, alpha, radius, sweep.seconds);
            r.sort_by(|a, b| a.1.total_cmp(&b.1));
            let rest: Vec<String> = r[1..]
                .iter()
                .map(|(t, x)| format!("{} {x:.2}", t.name()))
                .collect();
            s.push_str(&format!(" **{}** ({}) |", r[0].0.name(), rest.join(", ")));
        }
        s.push('\n');
    }
    s.push('\n');
    for t in Technique::ALL {
        s.push_str(&format!(
            "relMSE at {} s, `{}`:\n\n",
            sweep.seconds,
            t.name()
        ));
        header(s, radii);
        for &alpha in &sweep.alphas {
            s.push_str(&format!("| {alpha} |"));
            for &radius in radii {
                match find(g, alpha, radius, t, LightSampling::default()) {
                    Some(r) => s.push_str(&format!(
                        " {:.3e} ({} spp) |",
                        at_time(r, sweep.seconds),
                        r.spp
                    )),
                    None => s.push_str(" - |"),
                }
            }
            s.push('\n');
        }
        s.push('\n');
    }
}

/// The quad family's before/after table: relMSE at equal time by area
/// over relMSE by solid angle (above 1: solid angle wins), per technique.
fn before_after(s: &mut String, g: &[&Row], sweep: &Sweep, backend: &str, model: Model) {
    let radii = sweep.radii(Family::Quad);
    s.push_str(&format!(
        "## {backend}, {}, quad: light sampling by area (before) and by solid angle (after)\n\n\
         Each cell: relMSE at {} s by area over relMSE by solid angle (`--light-sampling area` \
         against the default; above 1, solid angle wins), for `light` and `mis-power`; \
         `light-sampling.csv` holds both relMSEs.\n\n",
        model.name(),
        sweep.seconds
    ));
    header(s, radii);
    for &alpha in &sweep.alphas {
        s.push_str(&format!("| {alpha} |"));
        for &radius in radii {
            let cell: Vec<String> = AREA_TECHNIQUES
                .iter()
                .filter_map(|&t| {
                    let a = find(g, alpha, radius, t, LightSampling::Area)?;
                    let b = find(g, alpha, radius, t, LightSampling::SolidAngle)?;
                    let x = at_time(a, sweep.seconds) / at_time(b, sweep.seconds);
                    Some(format!("{} {x:.2}", t.name()))
                })
                .collect();
            s.push_str(&format!(" {} |", cell.join(", ")));
        }
        s.push('\n');
    }
    s.push('\n');
}

fn header(s: &mut String, radii: &[f32]) {
    s.push_str("| alpha \\ r |");
    for r in radii {
        s.push_str(&format!(" {r} |"));
    }
    s.push_str("\n|---|");
    for _ in radii {
        s.push_str("---|");
    }
    s.push('\n');
}

/// One map per (backend, model, technique) of `family`: green where the
/// technique is within 1.25x of the cell's best relMSE at equal time,
/// amber within 2x, red beyond.
pub fn heatmaps(
    rows: &[Row],
    sweep: &Sweep,
    backends: &[String],
    family: Family,
) -> Vec<crate::chart::Heatmap> {
    let mut maps = Vec::new();
    let radii = sweep.radii(family);
    for backend in backends {
        for model in Model::ALL {
            let g = group(rows, backend, family, model);
            if g.is_empty() {
                continue;
            }
            for t in Technique::ALL {
                let mut cells = Vec::new();
                for (i, &alpha) in sweep.alphas.iter().enumerate() {
                    for (j, &radius) in radii.iter().enumerate() {
                        let Some(&(_, x)) = ratios(&g, alpha, radius, sweep.seconds)
                            .iter()
                            .find(|(u, _)| *u == t)
                        else {
                            continue;
                        };
                        let status = if x <= 1.25 {
                            0
                        } else if x <= 2.0 {
                            1
                        } else {
                            2
                        };
                        // Paler green the closer to the best.
                        cells.push((i, j, status, 1e-6 * 10f64.powf(4.0 * (x - 1.0) / 0.25)));
                    }
                }
                maps.push(crate::chart::Heatmap {
                    title: format!("{backend} {} {}", model.name(), t.name()),
                    rows: sweep.alphas.iter().map(|a| format!("alpha {a}")).collect(),
                    cols: radii.len(),
                    cells,
                });
            }
        }
    }
    maps
}
