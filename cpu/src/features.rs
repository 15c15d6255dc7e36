//! What a scene uses, so that a kernel can be built for no more than that
//! ("model no more than a scene needs"), and the simplifications at load
//! that make the set smaller without changing the image.
//!
//! [`Features`] is a bit set. The GPU path tracer receives it as a Vulkan
//! specialization constant (`shaders/features.glsl`): each `HAS(F_...)`
//! test folds to a constant when the pipeline is created and the driver
//! drops the code behind a false one. The generic kernel is the same SPIR-V
//! with every bit set.

use crate::abi;
use crate::bsdf::{Bsdf, Roughness, SMOOTH_ALPHA_THRESHOLD, Shadowing};
use crate::film::RenderOptions;
use crate::scene::{PunctualLight, Scene};

/// A set of kernel features. The bit values are the device ABI's `F_*`
/// (`crate::abi`, from which the GLSL `#define`s are generated).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Features(pub u32);

impl Features {
    /// Lambertian materials (and the diffuse lobe of glTF metallic < 1).
    pub const DIFFUSE: u32 = abi::F_DIFFUSE;
    /// Conductors (smooth or rough).
    pub const CONDUCTOR: u32 = abi::F_CONDUCTOR;
    /// Dielectrics (smooth or rough).
    pub const DIELECTRIC: u32 = abi::F_DIELECTRIC;
    /// glTF metallic-roughness blends (0 < metallic < 1).
    pub const METALLIC: u32 = abi::F_METALLIC;
    /// Any rough (GGX) lobe.
    pub const ROUGH: u32 = abi::F_ROUGH;
    /// A rough lobe with alpha_u != alpha_v.
    pub const ANISOTROPIC: u32 = abi::F_ANISOTROPIC;
    /// Height-correlated Smith G2.
    pub const SMITH_CORRELATED: u32 = abi::F_SMITH_CORRELATED;
    /// Separable Smith G1 G1.
    pub const SMITH_SEPARABLE: u32 = abi::F_SMITH_SEPARABLE;
    /// Emissive triangles (area lights).
    pub const AREA_LIGHTS: u32 = abi::F_AREA_LIGHTS;
    /// Point and spot lights.
    pub const POINT_SPOT: u32 = abi::F_POINT_SPOT;
    /// Directional lights.
    pub const DIRECTIONAL: u32 = abi::F_DIRECTIONAL;
    /// A background that is not black: constant, or an environment map.
    pub const BACKGROUND: u32 = abi::F_BACKGROUND;
    /// Paths continue past the first hit (max depth other than 1).
    pub const BOUNCES: u32 = abi::F_BOUNCES;
    /// Next-event estimation with something to sample.
    pub const NEE: u32 = abi::F_NEE;
    /// The glTF non-metal (a coat over a Lambertian base); the metallic
    /// blend's non-metal part comes with [`Features::METALLIC`].
    pub const COATED: u32 = abi::F_COATED;
    /// Mitsuba's `plastic` and `roughplastic`.
    pub const PLASTIC: u32 = abi::F_PLASTIC;
    /// Mitsuba's `thindielectric`.
    pub const THIN_DIELECTRIC: u32 = abi::F_THIN_DIELECTRIC;
    /// A normal-mapped material: where its BSDF has no transmission, it
    /// folds at the geometric surface ([`crate::bsdf::fold`]).
    pub const NORMAL_MAP: u32 = abi::F_NORMAL_MAP;
    /// Textures (the kernel's `Params.textured`): the material is
    /// recomputed per hit, emission scaled by its texture.
    pub const TEXTURES: u32 = abi::F_TEXTURES;
    /// Alpha-masked or blended materials (`Params.masked`): traversal runs
    /// the alpha test.
    pub const ALPHA_MASKS: u32 = abi::F_ALPHA_MASKS;
    /// A texture in a KHR extension's slot (transmission, clear coat, its
    /// roughness and normal, specular, specular colour): rare in real
    /// files, and each slot's lookup is compiled apart.
    pub const EXTENSION_TEXTURES: u32 = abi::F_EXTENSION_TEXTURES;

    /// Every feature: the generic kernel.
    pub const ALL: Features = Features(abi::F_ALL);

    const NAMES: [(u32, &'static str); 21] = [
        (Self::DIFFUSE, "diffuse"),
        (Self::CONDUCTOR, "conductor"),
        (Self::DIELECTRIC, "dielectric"),
        (Self::METALLIC, "metallic"),
        (Self::ROUGH, "rough"),
        (Self::ANISOTROPIC, "anisotropic"),
        (Self::SMITH_CORRELATED, "smith-correlated"),
        (Self::SMITH_SEPARABLE, "smith-separable"),
        (Self::AREA_LIGHTS, "area-lights"),
        (Self::POINT_SPOT, "point-spot-lights"),
        (Self::DIRECTIONAL, "directional-lights"),
        (Self::BACKGROUND, "background"),
        (Self::BOUNCES, "bounces"),
        (Self::NEE, "nee"),
        (Self::COATED, "coated"),
        (Self::PLASTIC, "plastic"),
        (Self::THIN_DIELECTRIC, "thindielectric"),
        (Self::NORMAL_MAP, "normal-map"),
        (Self::TEXTURES, "textures"),
        (Self::ALPHA_MASKS, "alpha-masks"),
        (Self::EXTENSION_TEXTURES, "extension-textures"),
    ];

    pub fn has(self, bit: u32) -> bool {
        self.0 & bit != 0
    }

    /// The names of the features present, in bit order.
    pub fn names(self) -> Vec<&'static str> {
        Self::NAMES
            .iter()
            .filter(|(b, _)| self.has(*b))
            .map(|(_, n)| *n)
            .collect()
    }

    /// The bits a rough model needs (none when it is rendered smooth).
    fn rough(r: &Roughness) -> u32 {
        if r.is_smooth() {
            return 0;
        }
        let mut f = Self::ROUGH;
        if r.alpha_u != r.alpha_v {
            f |= Self::ANISOTROPIC;
        }
        f | match r.shadowing {
            Shadowing::Correlated => Self::SMITH_CORRELATED,
            Shadowing::Separable => Self::SMITH_SEPARABLE,
        }
    }

    /// A rough clear coat needs the rough code whatever the material under
    /// it is (its GGX lobe is `cc_smooth` without it). Textures only scale
    /// its roughness factor down, so the factor decides.
    fn clearcoat_rough(c: &crate::bsdf::coated::CoatParams) -> u32 {
        if c.clearcoat > 0.0 && c.clearcoat_alpha >= crate::bsdf::SMOOTH_ALPHA_THRESHOLD {
            Self::ROUGH | Self::SMITH_CORRELATED
        } else {
            0
        }
    }

    /// What a material's textures need: the per-hit metallic blend, the
    /// normal map's fold, the KHR extensions' slots.
    fn texture_bits(bsdf: &Bsdf, textures: Option<&crate::texture::MaterialTextures>) -> u32 {
        let Some(t) = textures else {
            return 0;
        };
        let mut f = 0;
        // A textured glTF material is recomputed per hit as the metallic
        // blend, whatever its factors map to.
        if t.mode == crate::texture::MAP_GLTF && !matches!(bsdf, Bsdf::Dielectric { .. }) {
            f |= Self::METALLIC;
        }
        // Whether the fold applies is decided per hit (a texture may take
        // the transmission away).
        if t.normal.is_some() {
            f |= Self::NORMAL_MAP;
        }
        if t.has_coat_textures() || t.clearcoat_normal.is_some() {
            f |= Self::EXTENSION_TEXTURES;
        }
        f
    }

    /// What rendering `scene` with `opts` needs.
    pub fn of(scene: &Scene, opts: &RenderOptions) -> Features {
        let mut f = 0u32;
        let mut used = vec![false; scene.materials.len()];
        for t in &scene.triangles {
            if let Some(u) = used.get_mut(t.material as usize) {
                *u = true;
            }
        }
        for (i, (m, _)) in scene
            .materials
            .iter()
            .zip(&used)
            .enumerate()
            .filter(|(_, (_, u))| **u)
        {
            let textures = scene.textures.material(i as u32);
            f |= Self::texture_bits(&m.bsdf, textures);
            match &m.bsdf {
                Bsdf::Diffuse { .. } => f |= Self::DIFFUSE,
                Bsdf::Plastic(_) => f |= Self::PLASTIC,
                Bsdf::RoughPlastic(p) => {
                    f |= Self::PLASTIC;
                    f |= Self::rough(&p.roughness);
                }
                Bsdf::ThinDielectric { .. } => f |= Self::THIN_DIELECTRIC,
                Bsdf::Coated {
                    roughness, coat, ..
                } => {
                    f |= Self::COATED;
                    f |= Self::rough(roughness);
                    f |= Self::clearcoat_rough(coat);
                }
                Bsdf::Conductor(c) => {
                    f |= Self::CONDUCTOR;
                    f |= Self::rough(&c.roughness);
                }
                Bsdf::Dielectric { eta, roughness, .. } => {
                    f |= Self::DIELECTRIC;
                    // A rough dielectric with eta = 1 is rendered smooth.
                    if *eta != 1.0 {
                        f |= Self::rough(roughness);
                    }
                }
                Bsdf::Metallic {
                    conductor, coat, ..
                } => {
                    f |= Self::METALLIC;
                    f |= Self::rough(&conductor.roughness);
                    f |= Self::clearcoat_rough(coat);
                }
            }
        }
        if scene
            .triangles
            .iter()
            .any(|t| t.light != crate::scene::NO_LIGHT)
        {
            f |= Self::AREA_LIGHTS;
        }
        for l in &scene.lights {
            f |= match l {
                PunctualLight::Directional { .. } => Self::DIRECTIONAL,
                _ => Self::POINT_SPOT,
            };
        }
        if scene.background.max_element() > 0.0 || scene.envmap.is_some() {
            f |= Self::BACKGROUND;
        }
        // The kernel's Params.textured and Params.masked, as
        // `gpu_scene_data` sets them.
        if !scene.textures.is_empty() {
            f |= Self::TEXTURES;
        }
        if scene.textures.has_masks() {
            f |= Self::ALPHA_MASKS;
        }
        if opts.max_depth != 1 {
            f |= Self::BOUNCES;
            let lights =
                Self::AREA_LIGHTS | Self::POINT_SPOT | Self::DIRECTIONAL | Self::BACKGROUND;
            if opts.nee && f & lights != 0 {
                f |= Self::NEE;
            }
        }
        Features(f)
    }
}

/// Simplifications made at load, each exact (the image does not change in
/// expectation), returned as notes for `glint info`:
/// - a rough model whose alphas are under the smooth threshold becomes its
///   smooth counterpart (it is rendered as one already: this makes it
///   visible to [`Features::of`]);
/// - a rough dielectric with eta exactly 1 becomes smooth: it refracts
///   nothing and reflects nothing (F = 0), so it is a pass-through either way;
/// - punctual lights that emit nothing (black colour or zero intensity) are
///   dropped: they add zero, and would only take light-selection odds;
/// - materials identical in every parameter (names aside) are merged, in
///   scenes without textures.
pub fn simplify(scene: &mut Scene) -> Vec<String> {
    let mut notes = Vec::new();
    let mut snapped = 0;
    let snap = |r: &mut Roughness, n: &mut usize| {
        if (r.alpha_u > 0.0 || r.alpha_v > 0.0) && r.alpha_u.max(r.alpha_v) < SMOOTH_ALPHA_THRESHOLD
        {
            r.alpha_u = 0.0;
            r.alpha_v = 0.0;
            *n += 1;
        }
    };
    for m in &mut scene.materials {
        // roughplastic under the threshold is Mitsuba's smooth plastic.
        if let Bsdf::RoughPlastic(p) = m.bsdf
            && p.roughness.is_smooth()
        {
            m.bsdf = Bsdf::Plastic(p.plastic);
            snapped += 1;
        }
        match &mut m.bsdf {
            Bsdf::Conductor(c) => snap(&mut c.roughness, &mut snapped),
            Bsdf::Metallic { conductor, .. } => snap(&mut conductor.roughness, &mut snapped),
            Bsdf::Coated { roughness, .. } => snap(roughness, &mut snapped),
            Bsdf::Dielectric { eta, roughness, .. } => {
                if *eta == 1.0 && !(roughness.alpha_u == 0.0 && roughness.alpha_v == 0.0) {
                    roughness.alpha_u = 0.0;
                    roughness.alpha_v = 0.0;
                    snapped += 1;
                } else {
                    snap(roughness, &mut snapped);
                }
            }
            Bsdf::RoughPlastic(p) => snap(&mut p.roughness, &mut snapped),
            Bsdf::Diffuse { .. } | Bsdf::Plastic(_) | Bsdf::ThinDielectric { .. } => {}
        }
    }
    if snapped > 0 {
        notes.push(format!(
            "{snapped} rough material(s) under the smooth threshold (alpha < {SMOOTH_ALPHA_THRESHOLD}) or with eta = 1 rendered smooth"
        ));
    }

    let before = scene.lights.len();
    scene.lights.retain(|l| {
        let power = match l {
            PunctualLight::Point { intensity, .. } | PunctualLight::Spot { intensity, .. } => {
                *intensity
            }
            PunctualLight::Directional { irradiance, .. } => *irradiance,
        };
        power.max_element() > 0.0
    });
    if scene.lights.len() < before {
        notes.push(format!(
            "{} punctual light(s) that emit nothing dropped",
            before - scene.lights.len()
        ));
    }

    // Merge identical materials: the first of each kind stays. Not with
    // textures: their tables are indexed by material, and two materials
    // with equal factors may still differ in their textures.
    if !scene.textures.materials.is_empty() {
        return notes;
    }
    let n = scene.materials.len();
    let mut remap: Vec<u32> = (0..n as u32).collect();
    let mut keep: Vec<usize> = Vec::new();
    for i in 0..n {
        let same = keep.iter().copied().find(|&k| {
            let (a, b) = (&scene.materials[k], &scene.materials[i]);
            a.bsdf == b.bsdf && a.emission == b.emission && a.double_sided == b.double_sided
        });
        match same {
            Some(k) => remap[i] = remap[k],
            None => {
                remap[i] = keep.len() as u32;
                keep.push(i);
            }
        }
    }
    if keep.len() < n {
        for t in &mut scene.triangles {
            if let Some(&r) = remap.get(t.material as usize) {
                t.material = r;
            }
        }
        let old = std::mem::take(&mut scene.materials);
        scene.materials = keep.iter().map(|&k| old[k].clone()).collect();
        notes.push(format!(
            "{} identical material(s) merged into {}",
            n,
            scene.materials.len()
        ));
    }
    notes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::ConductorParams;
    use crate::scene::{Material, NO_LIGHT, Triangle};
    use glam::Vec3;

    fn material(bsdf: Bsdf) -> Material {
        Material {
            name: "m".into(),
            bsdf,
            emission: Vec3::ZERO,
            double_sided: false,
            absorption: glam::Vec3::ZERO,
        }
    }

    fn rough(a: f32, b: f32, shadowing: Shadowing) -> Roughness {
        Roughness {
            alpha_u: a,
            alpha_v: b,
            shadowing,
            multiscatter: false,
        }
    }

    fn conductor(r: Roughness) -> Bsdf {
        Bsdf::Conductor(ConductorParams {
            eta: Vec3::ONE,
            k: Vec3::splat(2.0),
            specular_reflectance: Vec3::ONE,
            roughness: r,
        })
    }

    /// One triangle per material, the first one emissive if `emit`.
    fn scene(materials: Vec<Material>, lights: Vec<PunctualLight>, background: Vec3) -> Scene {
        let triangles = (0..materials.len() as u32)
            .map(|i| Triangle {
                p0: [0.0, 0.0, i as f32],
                material: i,
                p1: [1.0, 0.0, i as f32],
                light: NO_LIGHT,
                p2: [0.0, 1.0, i as f32],
                flags: 0,
            })
            .collect::<Vec<_>>();
        let mut s = Scene {
            triangles,
            shading: Vec::new(),
            materials,
            lights,
            cameras: vec![],
            background,
            ..Default::default()
        };
        s.build_bvh();
        s
    }

    fn opts() -> RenderOptions {
        RenderOptions::new(4, 4)
    }

    #[test]
    fn each_feature_present_and_absent() {
        let diffuse = material(Bsdf::Diffuse {
            reflectance: Vec3::ONE,
        });
        let s = scene(vec![diffuse.clone()], vec![], Vec3::ZERO);
        let f = Features::of(&s, &opts());
        assert_eq!(
            f.0,
            Features::DIFFUSE | Features::BOUNCES,
            "{:?}",
            f.names()
        );

        let s = scene(vec![diffuse.clone()], vec![], Vec3::splat(0.5));
        let f = Features::of(&s, &opts());
        assert!(f.has(Features::BACKGROUND) && f.has(Features::NEE));
        // NEE off, or no bounces: no light sampling in the kernel.
        let mut o = opts();
        o.nee = false;
        assert!(!Features::of(&s, &o).has(Features::NEE));
        o.max_depth = 1;
        let f = Features::of(&s, &o);
        assert!(!f.has(Features::BOUNCES) && !f.has(Features::NEE));

        let aniso = conductor(rough(0.3, 0.05, Shadowing::Separable));
        let s = scene(vec![material(aniso)], vec![], Vec3::ZERO);
        let f = Features::of(&s, &opts());
        for b in [
            Features::CONDUCTOR,
            Features::ROUGH,
            Features::ANISOTROPIC,
            Features::SMITH_SEPARABLE,
        ] {
            assert!(f.has(b), "{:?}", f.names());
        }
        assert!(!f.has(Features::SMITH_CORRELATED) && !f.has(Features::DIFFUSE));

        let glass = material(Bsdf::Dielectric {
            eta: 1.5,
            roughness: rough(0.2, 0.2, Shadowing::Correlated),
            tint: crate::bsdf::Tint::NONE,
        });
        let f = Features::of(&scene(vec![glass], vec![], Vec3::ZERO), &opts());
        assert!(
            f.has(Features::DIELECTRIC)
                && f.has(Features::ROUGH)
                && f.has(Features::SMITH_CORRELATED)
        );
        assert!(!f.has(Features::ANISOTROPIC));
    }

    #[test]
    fn each_light_kind_present_and_absent() {
        let diffuse = material(Bsdf::Diffuse {
            reflectance: Vec3::ONE,
        });
        let point = PunctualLight::Point {
            position: Vec3::Y,
            intensity: Vec3::ONE,
        };
        let sun = PunctualLight::Directional {
            direction: -Vec3::Y,
            irradiance: Vec3::ONE,
        };
        let f = Features::of(
            &scene(vec![diffuse.clone()], vec![point], Vec3::ZERO),
            &opts(),
        );
        assert!(f.has(Features::POINT_SPOT) && !f.has(Features::DIRECTIONAL));
        let f = Features::of(
            &scene(vec![diffuse.clone()], vec![sun], Vec3::ZERO),
            &opts(),
        );
        assert!(!f.has(Features::POINT_SPOT) && f.has(Features::DIRECTIONAL));

        let mut lamp = diffuse.clone();
        lamp.emission = Vec3::ONE;
        let f = Features::of(&scene(vec![lamp], vec![], Vec3::ZERO), &opts());
        assert!(f.has(Features::AREA_LIGHTS) && f.has(Features::NEE));
    }

    #[test]
    fn a_rough_clear_coat_needs_the_rough_code_and_unused_materials_nothing() {
        // A rough clear coat over a smooth non-metal: the rough code, for
        // the coat's lobe.
        let coat = crate::bsdf::coated::CoatParams {
            clearcoat: 0.8,
            clearcoat_alpha: 0.25,
            ..crate::bsdf::coated::CoatParams::GLTF_DEFAULT
        };
        let plastic = material(Bsdf::Coated {
            base: Vec3::ZERO,
            coat,
            roughness: Roughness::SMOOTH,
        });
        let f = Features::of(&scene(vec![plastic], vec![], Vec3::ZERO), &opts());
        assert!(
            f.has(Features::COATED) && f.has(Features::ROUGH),
            "{:?}",
            f.names()
        );
        let smooth_coat = material(Bsdf::Coated {
            base: Vec3::ZERO,
            coat: crate::bsdf::coated::CoatParams {
                clearcoat_alpha: 0.0,
                ..coat
            },
            roughness: Roughness::SMOOTH,
        });
        let f = Features::of(&scene(vec![smooth_coat], vec![], Vec3::ZERO), &opts());
        assert!(!f.has(Features::ROUGH), "{:?}", f.names());

        // A material no triangle uses adds nothing.
        let diffuse = material(Bsdf::Diffuse {
            reflectance: Vec3::ONE,
        });
        let mut s = scene(vec![diffuse], vec![], Vec3::ZERO);
        s.materials.push(material(conductor(Roughness::SMOOTH)));
        assert!(!Features::of(&s, &opts()).has(Features::CONDUCTOR));
        assert_eq!(Features(Features::DIFFUSE).names(), ["diffuse"]);
    }

    #[test]
    fn simplifications_shrink_the_set() {
        // alpha 1e-4 renders smooth: no rough model in the set.
        let m = material(conductor(rough(1e-4, 1e-4, Shadowing::Correlated)));
        let mut s = scene(vec![m], vec![], Vec3::ZERO);
        assert!(!Features::of(&s, &opts()).has(Features::ROUGH));
        let notes = simplify(&mut s);
        assert_eq!(notes.len(), 1, "{notes:?}");
        let Bsdf::Conductor(c) = s.materials[0].bsdf else {
            panic!()
        };
        assert_eq!((c.roughness.alpha_u, c.roughness.alpha_v), (0.0, 0.0));
        // alpha 0.01 stays rough.
        let mut s = scene(
            vec![material(conductor(rough(
                0.01,
                0.01,
                Shadowing::Correlated,
            )))],
            vec![],
            Vec3::ZERO,
        );
        assert!(simplify(&mut s).is_empty());
        assert!(Features::of(&s, &opts()).has(Features::ROUGH));

        // eta = 1 rough glass: smooth pass-through.
        let pass = material(Bsdf::Dielectric {
            eta: 1.0,
            roughness: rough(0.3, 0.3, Shadowing::Correlated),
            tint: crate::bsdf::Tint::NONE,
        });
        let mut s = scene(vec![pass], vec![], Vec3::ZERO);
        assert!(!Features::of(&s, &opts()).has(Features::ROUGH));
        simplify(&mut s);
        assert!(
            matches!(s.materials[0].bsdf, Bsdf::Dielectric { roughness, .. } if roughness.is_smooth())
        );

        // A black background is no background; a black light is dropped.
        let diffuse = material(Bsdf::Diffuse {
            reflectance: Vec3::ONE,
        });
        let dark = PunctualLight::Point {
            position: Vec3::Y,
            intensity: Vec3::ZERO,
        };
        let mut s = scene(vec![diffuse.clone()], vec![dark], Vec3::ZERO);
        assert!(!Features::of(&s, &opts()).has(Features::BACKGROUND));
        simplify(&mut s);
        assert!(s.lights.is_empty());
        assert!(!Features::of(&s, &opts()).has(Features::POINT_SPOT));

        // Identical materials merge; triangles follow.
        let mut other = diffuse.clone();
        other.name = "copy".into();
        let red = material(Bsdf::Diffuse {
            reflectance: Vec3::X,
        });
        let mut s = scene(vec![diffuse, other, red], vec![], Vec3::ZERO);
        simplify(&mut s);
        assert_eq!(s.materials.len(), 2);
        let mut used: Vec<u32> = s.triangles.iter().map(|t| t.material).collect();
        used.sort();
        assert_eq!(used, [0, 0, 1]);
    }
}
