//! Ray queries: robust slab test, watertight triangle test, stack traversal.
//! `shaders/bvh.glsl` mirrors every function here under the same name.

use glam::{BVec3, Vec3, Vec3A};

use crate::scene::Triangle;

/// Ize 2013's conservative slab padding ([`crate::abi::BVH_SLAB_PAD`]).
pub const SLAB_PAD: f32 = crate::abi::BVH_SLAB_PAD;

/// Per-ray constants of the slab and watertight triangle tests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PreparedRay {
    pub o: Vec3,
    pub d: Vec3,
    /// 1 / d, with zero (and tiny) components replaced by +-1e30: finite, so
    /// the slab test never forms 0 * inf = NaN (tinybvh's `safercp`); exactly
    /// zero components are then settled by `zero_d` in [`intersect_aabb`].
    pub inv_d: Vec3,
    /// Which components of d are exactly zero (either sign).
    pub zero_d: BVec3,
    /// Woop et al. 2013, fig. 1: kz is the dominant axis of d; kx, ky follow
    /// it cyclically, swapped when d[kz] < 0 to keep the winding.
    pub kx: usize,
    pub ky: usize,
    pub kz: usize,
    /// Shear constants (Sx, Sy, Sz) = (d[kx] / d[kz], d[ky] / d[kz], 1 / d[kz]).
    pub shear: Vec3,
}

#[cfg(test)]
fn safe_rcp(x: f32) -> f32 {
    if x.abs() >= 1e-30 {
        1.0 / x
    } else {
        1e30f32.copysign(x)
    }
}

/// The watertight triangle test's axis order for direction `d` (Woop et
/// al. 2013, fig. 1) as a code, 2 kz + whether kx and ky swap: kz is the
/// dominant axis, kx and ky follow it cyclically, swapped when d[kz] < 0
/// to keep the winding. One byte, so packets compare their rays' codes.
#[inline(always)]
pub(super) fn permutation(d: [f32; 3]) -> u8 {
    let a = d.map(f32::abs);
    let kz = if a[0] >= a[1] && a[0] >= a[2] {
        0
    } else if a[1] >= a[2] {
        1
    } else {
        2
    };
    2 * kz as u8 + (d[kz] < 0.0) as u8
}

/// (kx, ky, kz) of a [`permutation`] code.
#[inline(always)]
pub(super) fn axes(code: u8) -> [usize; 3] {
    const NEXT: [(usize, usize); 3] = [(1, 2), (2, 0), (0, 1)];
    let kz = (code / 2) as usize;
    let (kx, ky) = NEXT[kz];
    if code & 1 != 0 {
        [ky, kx, kz]
    } else {
        [kx, ky, kz]
    }
}

/// 1 / d per lane, with zero, tiny (|d| < 1e-30) and NaN components
/// replaced by +-1e30 (d's sign): finite, so the slab test never forms
/// 0 * inf = NaN (tinybvh's `safercp`).
#[inline(always)]
pub(super) fn safe_inv(d: Vec3A) -> Vec3A {
    Vec3A::select(
        d.abs().cmpge(Vec3A::splat(1e-30)),
        Vec3A::ONE / d,
        Vec3A::splat(1e30).copysign(d),
    )
}

/// The shear constants (d[kx] / d[kz], d[ky] / d[kz], 1 / d[kz]) for the
/// axis order `k`: one division of three lanes.
#[inline(always)]
pub(super) fn shear(d: [f32; 3], k: [usize; 3]) -> Vec3A {
    Vec3A::new(d[k[0]], d[k[1]], 1.0) / Vec3A::splat(d[k[2]])
}

impl PreparedRay {
    /// `prepare_ray` in GLSL. The six divisions are two vector divisions
    /// (the same IEEE quotient per lane, so the same bits as one at a time).
    #[inline]
    pub fn new(o: Vec3, d: Vec3) -> PreparedRay {
        // The axis order as `permutation` and `axes` pick it, written out:
        // through them LLVM compiled the callers of this function larger
        // (the bunny's camera packets 5% more instructions). The x86 unit
        // test `ray8_and_leaf8_are_the_prepared_ray` holds the two to the
        // same order.
        let a = d.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        // (kx, ky) follow kz cyclically, swapped when d[kz] < 0.
        const NEXT: [(usize, usize); 3] = [(1, 2), (2, 0), (0, 1)];
        let (mut kx, mut ky) = NEXT[kz];
        let dv = d.to_array();
        if dv[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        PreparedRay {
            o,
            d,
            inv_d: safe_inv(Vec3A::from(d)).into(),
            zero_d: d.cmpeq(Vec3::ZERO),
            kx,
            ky,
            kz,
            shear: shear(dv, [kx, ky, kz]).into(),
        }
    }
}

/// Entry distance of the ray into the box, clamped to >= 0, or +inf when the
/// ray misses it within [0, tmax].
// Forced: LLVM kept it a call in `occluded`, 10% more instructions there.
#[inline(always)]
pub fn intersect_aabb(r: &PreparedRay, bmin: Vec3, bmax: Vec3, tmax: f32) -> f32 {
    let t1 = (bmin - r.o) * r.inv_d;
    let t2 = (bmax - r.o) * r.inv_d;
    // Along an axis where d is exactly zero the slab holds the whole line when
    // the origin is within it, faces included, and none of it otherwise. The
    // +-1e30 inverse gives that, except with the origin exactly on a face,
    // where 0 * 1e30 = 0 would end the slab at t = 0 and lose hits on that
    // face's triangles (rays along grid lines); so set those axes outright.
    // Most rays have no zero component: they skip the selects.
    let (mut tlo, mut thi) = (t1.min(t2), t1.max(t2));
    if r.zero_d.any() {
        let inside = r.o.cmpge(bmin) & r.o.cmple(bmax);
        let (inf, ninf) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        tlo = Vec3::select(r.zero_d, Vec3::select(inside, ninf, inf), tlo);
        thi = Vec3::select(r.zero_d, Vec3::select(inside, inf, ninf), thi);
    }
    let tnear = tlo.max_element().max(0.0);
    // The pad also widens tmax (the best hit so far): a triangle's computed
    // t and its box's computed entry distance round independently, and a box
    // entered a few ulps "after" the current best may still hold a hit a few
    // ulps before it (rays through shared vertices). Too wide only costs a
    // triangle test; too narrow would lose the closest hit.
    let tfar = thi.min_element().min(tmax) * SLAB_PAD;
    if tnear <= tfar { tnear } else { f32::INFINITY }
}

/// Veltkamp's split of `x` into a high half of 12 significant bits and the
/// exact rest (`hi + lo == x`).
#[inline]
fn split(x: f32) -> (f32, f32) {
    let t = crate::abi::VELTKAMP_SPLIT * x;
    let hi = t - (t - x);
    (hi, x - hi)
}

/// Dekker's exact product: `p = fl(a b)` and its rounding error `e`, with
/// `p + e == a b` exactly (no FMA, so the GPU computes the same bits where
/// its `fma` differs: lavapipe's did not match the CPU's fused one).
#[inline]
fn two_product(a: f32, b: f32) -> (f32, f32) {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    (p, ((ah * bh - p) + ah * bl + al * bh) + al * bl)
}

/// `a b - c d` from the two exact products: to about an ulp, and exactly
/// negated when the operands swap (the property the watertight test needs).
#[inline]
pub fn difference_of_products(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let (p1, e1) = two_product(a, b);
    let (p2, e2) = two_product(c, d);
    (p1 - p2) + (e1 - e2)
}

/// The edge function `e = a b - c d` as the triangle test computed it, or,
/// where it rounded to exactly 0, recomputed by [`difference_of_products`].
#[inline]
pub fn refine_edge(e: f32, a: f32, b: f32, c: f32, d: f32) -> f32 {
    if e == 0.0 {
        difference_of_products(a, b, c, d)
    } else {
        e
    }
}

/// Watertight ray/triangle intersection (Woop, Benthin, Wald 2013, JCGT 2(1),
/// section 3 and appendix A). Returns (t, u, v) for a hit with 0 < t < tmax,
/// p = (1 - u - v) p0 + u p1 + v p2; both faces hit.
///
/// Why it is watertight: the vertices are translated to the ray origin and
/// sheared so the ray is the +z axis; each vertex's 2D coordinates depend on
/// the vertex alone, and an edge's 2D edge function is computed from its two
/// vertices only, so the two triangles sharing an edge get exactly negated
/// values (IEEE products commute and a - b = -(b - a)). Zero counts as inside
/// for both, so a ray through an edge hits at least one of its triangles. The
/// paper's double-precision recomputation when an edge function is exactly 0
/// is done in f32 instead, so the GPU (no fp64 required) computes the same
/// thing: an edge function that rounds to exactly 0 is recomputed from
/// Dekker's exact products ([`refine_edge`]). Besides deciding which
/// of two triangles sharing an edge is hit, this keeps a degenerate
/// (collinear) triangle from reporting a hit where two of its edge
/// functions round to 0 and the third does not (a false hit 0.42 away from
/// such a triangle was found by `cpu/tests/bvh.rs`'s random soups). Only
/// the zero ones are recomputed, so a shared edge is still computed the
/// same way by both triangles (both see the same zero), exactly negated.
#[inline]
pub fn intersect_triangle(r: &PreparedRay, tri: &Triangle, tmax: f32) -> Option<(f32, f32, f32)> {
    let a = Vec3::from(tri.p0) - r.o;
    let b = Vec3::from(tri.p1) - r.o;
    let c = Vec3::from(tri.p2) - r.o;
    let (kx, ky, kz) = (r.kx, r.ky, r.kz);
    let (sx, sy, sz) = (r.shear.x, r.shear.y, r.shear.z);
    let ax = a[kx] - sx * a[kz];
    let ay = a[ky] - sy * a[kz];
    let bx = b[kx] - sx * b[kz];
    let by = b[ky] - sy * b[kz];
    let cx = c[kx] - sx * c[kz];
    let cy = c[ky] - sy * c[kz];
    // Scaled barycentrics: the 2D edge functions opposite A, B and C.
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    if u == 0.0 || v == 0.0 || w == 0.0 {
        u = refine_edge(u, cx, by, cy, bx);
        v = refine_edge(v, ax, cy, ay, cx);
        w = refine_edge(w, bx, ay, by, ax);
    }
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    let az = sz * a[kz];
    let bz = sz * b[kz];
    let cz = sz * c[kz];
    let t = (u * az + v * bz + w * cz) / det;
    // Written so that NaN (from non-finite input) is rejected too; a hit
    // within the t's own error bound of the origin is not reported.
    if t > 0.0 && t < tmax && t > t_error([ax, bx, cx], [ay, by, cy], [az, bz, cz], [u, v, w], det)
    {
        Some((t, v / det, w / det))
    } else {
        None
    }
}

/// pbrt-v4's conservative bound on the error of the triangle test's t
/// (Pharr et al. 4th ed. sec. 6.8.4, `Triangle::Intersect`'s deltaT): from
/// the sheared vertex coordinates `x`, `y`, `z` (z scaled), the edge
/// functions `e` and their sum `det`. A hit with t <= it may be the ray's
/// own origin surface seen through rounding; rejecting it is what keeps a
/// steep ray far from the origin from re-hitting the triangle it leaves.
/// Computed only for a hit, so it costs the misses nothing. `t_error4` (SSE)
/// and `t_error` in bvh.glsl do the same operations in the same order.
#[inline]
pub fn t_error(x: [f32; 3], y: [f32; 3], z: [f32; 3], e: [f32; 3], det: f32) -> f32 {
    use crate::abi::{TRI_GAMMA2, TRI_GAMMA3, TRI_GAMMA5};
    let max3 = |v: [f32; 3]| v[0].abs().max(v[1].abs()).max(v[2].abs());
    let (max_x, max_y, max_z, max_e) = (max3(x), max3(y), max3(z), max3(e));
    let delta_x = TRI_GAMMA5 * (max_x + max_z);
    let delta_y = TRI_GAMMA5 * (max_y + max_z);
    let delta_e = 2.0 * (TRI_GAMMA2 * max_x * max_y + delta_y * max_x + delta_x * max_y);
    3.0 * (TRI_GAMMA3 * max_e * max_z + delta_e * max_z + delta_x * max_e) / det.abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// shaders/bvh.glsl spells the pad as raw bits: keep them in step.
    #[test]
    fn slab_pad_matches_glsl_bits() {
        assert_eq!(SLAB_PAD.to_bits(), 0x3f80_0003);
    }

    /// The scalar form [`PreparedRay::new`] replaced: six divisions.
    fn prepared_scalar(o: Vec3, d: Vec3) -> PreparedRay {
        let a = d.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        PreparedRay {
            o,
            d,
            inv_d: Vec3::new(safe_rcp(d.x), safe_rcp(d.y), safe_rcp(d.z)),
            zero_d: d.cmpeq(Vec3::ZERO),
            kx,
            ky,
            kz,
            shear: Vec3::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]),
        }
    }

    #[test]
    fn prepared_ray_is_the_scalar_one_bit_for_bit() {
        let mut rng = crate::sampling::Pcg32::new(5, 5);
        let special = [
            0.0,
            -0.0,
            1e-31,
            -1e-31,
            1e-30,
            f32::NAN,
            f32::INFINITY,
            1e30,
            -3.0,
        ];
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        for i in 0..20_000 {
            let mut d = rng.dir() * rng.range(1e-3, 1e3);
            if i % 3 == 0 {
                d[i % 3] = special[(i / 3) % special.len()];
            }
            let (a, b) = (
                PreparedRay::new(Vec3::ONE, d),
                prepared_scalar(Vec3::ONE, d),
            );
            assert_eq!(
                (a.kx, a.ky, a.kz, a.zero_d),
                (b.kx, b.ky, b.kz, b.zero_d),
                "{d}"
            );
            assert_eq!(bits(a.inv_d), bits(b.inv_d), "{d}");
            assert_eq!(bits(a.shear), bits(b.shear), "{d}");
        }
    }

    #[test]
    fn safe_rcp_is_finite_and_signed() {
        assert_eq!(safe_rcp(0.0), 1e30);
        assert_eq!(safe_rcp(-0.0), -1e30);
        assert_eq!(safe_rcp(2.0), 0.5);
        assert!(safe_rcp(-1e-38).is_finite() && safe_rcp(-1e-38) < 0.0);
    }
}
