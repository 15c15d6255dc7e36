//! Geometry for the BVH tests, shared by `cpu/tests/bvh*.rs` and the GPU
//! agreement test `tests/gpu_bvh.rs` (included with `#[path]`), so the CPU
//! and GPU differential tests draw the same kinds of rays from the same code.
#![allow(dead_code)]

use std::path::Path;

use glam::Vec3;
use glint_cpu::{Hit, Ray, Triangle};

pub use glint_cpu::sampling::Pcg32;

pub fn tri(p0: Vec3, p1: Vec3, p2: Vec3) -> Triangle {
    Triangle {
        p0: p0.into(),
        p1: p1.into(),
        p2: p2.into(),
        ..Default::default()
    }
}

pub fn bounds_of(tris: &[Triangle]) -> (Vec3, Vec3) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for t in tris {
        for p in t.vertices() {
            if p.is_finite() {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
    }
    (lo, hi)
}

/// Random rays in the style of tinybvh's test: origins inside and around the
/// bounds, most aimed at a random point of a random triangle (so they hit),
/// some with one or two zero direction components, some unnormalised, some
/// with a tmax short of the aimed point.
pub fn random_rays(tris: &[Triangle], count: usize, rng: &mut Pcg32) -> Vec<Ray> {
    let (lo, hi) = bounds_of(tris);
    let size = hi - lo;
    (0..count)
        .map(|_| {
            let o = if rng.f32() < 0.5 {
                rng.vec_in(lo, hi)
            } else {
                rng.vec_in(lo - size, hi + size)
            };
            let aimed = rng.f32() < 0.7;
            let mut d = if aimed {
                let t = &tris[rng.below(tris.len())];
                let [a, b, c] = t.vertices();
                let (mut u, mut v) = (rng.f32(), rng.f32());
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                (a + u * (b - a) + v * (c - a)) - o
            } else {
                rng.dir()
            };
            let zeros = rng.f32();
            if zeros < 0.1 {
                d[rng.below(3)] = 0.0;
            } else if zeros < 0.15 {
                let keep = rng.below(3);
                for k in 0..3 {
                    if k != keep {
                        d[k] = 0.0;
                    }
                }
            }
            if d == Vec3::ZERO || !d.is_finite() {
                d = Vec3::X;
            }
            // Unnormalised directions change the units of t: still exact.
            d = if rng.f32() < 0.3 {
                d * rng.range(0.1, 10.0)
            } else {
                d.normalize()
            };
            let tmax = match rng.below(4) {
                0 => rng.range(0.0, 1.5) * (size.length() / d.length()),
                _ => f32::INFINITY,
            };
            Ray { o, d, tmax }
        })
        .collect()
}

/// Rays leaving the surface, as a path's bounces do but without the
/// integrator's offset: origins at random points of random triangles (so
/// within rounding of the triangle's plane, on either side), directions
/// uniform on the sphere, a tenth with one zero component, a quarter with a
/// short tmax. The origin's own triangle may be hit at a tiny t or missed,
/// depending on rounding: every traversal that shares the triangle test must
/// decide it the same way.
pub fn rays_from_surfaces(tris: &[Triangle], count: usize, rng: &mut Pcg32) -> Vec<Ray> {
    let (lo, hi) = bounds_of(tris);
    let size = (hi - lo).length();
    (0..count)
        .map(|_| {
            let t = &tris[rng.below(tris.len())];
            let [a, b, c] = t.vertices();
            let (mut u, mut v) = (rng.f32(), rng.f32());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let o = a + u * (b - a) + v * (c - a);
            let mut d = rng.dir();
            if rng.f32() < 0.1 {
                d[rng.below(3)] = 0.0;
            }
            if d == Vec3::ZERO || !d.is_finite() || !o.is_finite() {
                return Ray {
                    o: lo,
                    d: Vec3::X,
                    tmax: f32::INFINITY,
                };
            }
            let tmax = if rng.f32() < 0.25 {
                rng.range(0.0, 0.2) * size
            } else {
                f32::INFINITY
            };
            Ray { o, d, tmax }
        })
        .collect()
}

/// Triangles of random shape and orientation, centres uniform in the unit cube.
pub fn random_soup(rng: &mut Pcg32, n: usize, size: f32) -> Vec<Triangle> {
    (0..n)
        .map(|_| {
            let c = rng.vec_in(Vec3::ZERO, Vec3::ONE);
            tri(
                c + size * rng.dir(),
                c + size * rng.dir(),
                c + size * rng.dir(),
            )
        })
        .collect()
}

/// A soup of the awkward cases: exact duplicates, zero-area triangles
/// (repeated and collinear vertices), axis-aligned triangles sharing planes.
pub fn nasty_soup(rng: &mut Pcg32) -> Vec<Triangle> {
    let mut tris = random_soup(rng, 400, 0.05);
    for i in 0..100 {
        let t = tris[i];
        tris.push(t);
    }
    for _ in 0..100 {
        let a = rng.vec_in(Vec3::ZERO, Vec3::ONE);
        let b = rng.vec_in(Vec3::ZERO, Vec3::ONE);
        tris.push(tri(a, a, b));
        tris.push(tri(a, 0.5 * (a + b), b));
        tris.push(tri(a, a, a));
    }
    for i in 0..8 {
        for j in 0..8 {
            let (x, y) = (i as f32 / 8.0, j as f32 / 8.0);
            let s = 1.0 / 8.0;
            let z = 0.5;
            tris.push(tri(
                Vec3::new(x, y, z),
                Vec3::new(x + s, y, z),
                Vec3::new(x, y + s, z),
            ));
            tris.push(tri(
                Vec3::new(x + s, y, 0.25),
                Vec3::new(x + s, y + s, 0.25),
                Vec3::new(x, y + s, 0.25),
            ));
        }
    }
    tris
}

/// A pinhole camera framing the bounds from +z: the rays a render's first
/// bounce traces.
pub fn primary_rays(lo: Vec3, hi: Vec3, w: usize, h: usize) -> Vec<Ray> {
    let c = 0.5 * (lo + hi);
    let r = 0.5 * (hi - lo).length();
    let eye = c + Vec3::new(0.3, 0.2, 1.0).normalize() * 2.5 * r;
    let fwd = (c - eye).normalize();
    let right = fwd.cross(Vec3::Y).normalize();
    let up = right.cross(fwd);
    let tan = (0.5f32 * 40f32.to_radians()).tan();
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            let sx = (2.0 * x / w as f32 - 1.0) * tan;
            let sy = (1.0 - 2.0 * y / h as f32) * tan;
            Ray {
                o: eye,
                d: (fwd + sx * right + sy * up).normalize(),
                tmax: f32::INFINITY,
            }
        })
        .collect()
}

/// A cosine-distributed bounce off every primary hit, on the side the ray
/// came from, its origin offset along the normal as the integrator does.
pub fn diffuse_rays(
    tris: &[Triangle],
    primary: &[Ray],
    hits: &[Option<Hit>],
    rng: &mut Pcg32,
) -> Vec<Ray> {
    primary
        .iter()
        .zip(hits)
        .filter_map(|(r, h)| {
            let h = (*h)?;
            let [a, b, c] = tris[h.tri as usize].vertices();
            let mut n = (b - a).cross(c - a).normalize();
            if n.dot(r.d) > 0.0 {
                n = -n;
            }
            let p = r.o + h.t * r.d;
            let eps = 1e-4 * p.abs().max_element().max(1.0);
            // Cosine-weighted hemisphere (Malley's method) about n.
            let (u1, u2) = (rng.f32(), rng.f32());
            let (rad, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
            let (s, t) = n.any_orthonormal_pair();
            let d = rad * phi.cos() * s + rad * phi.sin() * t + (1.0 - u1).max(0.0).sqrt() * n;
            Some(Ray {
                o: p + eps * n,
                d,
                tmax: f32::INFINITY,
            })
        })
        .collect()
}

/// The bunny's triangles in file order, positions only (repository copy,
/// read by the loader without building its BVH).
pub fn bunny() -> Vec<Triangle> {
    asset_triangles("bunny.glb")
}

/// The triangles of a bundled scene (`assets/NAME`), as bare geometry.
pub fn asset_triangles(name: &str) -> Vec<Triangle> {
    // The root package and the cpu/ crate both include this file.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = [
        root.join("assets").join(name),
        root.join("../assets").join(name),
    ]
    .into_iter()
    .find(|p| p.is_file())
    .unwrap_or_else(|| panic!("assets/{name}"));
    file_triangles(&path)
}

/// The triangles of `../shared/assets/NAME` (the workplace's scanned
/// meshes, beside the repository), or None, with a line saying so, where
/// that file is missing (a clean clone on CI).
pub fn shared_asset_triangles(name: &str) -> Option<Vec<Triangle>> {
    // The root package and the cpu/ crate both include this file.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let paths = [
        root.join("../shared/assets").join(name),
        root.join("../../shared/assets").join(name),
    ];
    match paths.iter().find(|p| p.is_file()) {
        Some(p) => Some(file_triangles(p)),
        None => {
            eprintln!("shared/assets/{name} not found: skipped");
            None
        }
    }
}

/// The triangles of a glTF file, as bare geometry.
pub fn file_triangles(path: &Path) -> Vec<Triangle> {
    let scene =
        glint_cpu::loader::parse(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    scene
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.vertices();
            tri(a, b, c)
        })
        .collect()
}

/// The surface of [-1, 1]^3 as an n x n grid per face, every grid coordinate
/// computed by one expression so shared vertices are bit-identical.
pub fn grid_cube(n: usize) -> Vec<Triangle> {
    let coord = |i: usize| -1.0 + 2.0 * i as f32 / n as f32;
    let mut tris = Vec::new();
    for axis in 0..3 {
        for side in [-1.0f32, 1.0] {
            let p = |i: usize, j: usize| {
                let mut v = [0.0f32; 3];
                v[axis] = side;
                v[(axis + 1) % 3] = coord(i);
                v[(axis + 2) % 3] = coord(j);
                Vec3::from(v)
            };
            for i in 0..n {
                for j in 0..n {
                    tris.push(tri(p(i, j), p(i + 1, j), p(i + 1, j + 1)));
                    tris.push(tri(p(i, j), p(i + 1, j + 1), p(i, j + 1)));
                }
            }
        }
    }
    tris
}
