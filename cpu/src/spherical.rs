//! Spherical triangles: the solid angle a triangle subtends from a point,
//! and directions sampled uniformly within it (Arvo, "Stratified Sampling
//! of Spherical Triangles", SIGGRAPH 1995, as pbrt-v4 writes it in
//! `SampleSphericalTriangle`). Twin of `shaders/integrator/spherical.glsl`
//! (same names, same operations).
//!
//! Light sampling uses it for emissive triangles that subtend a large
//! solid angle from the shading point (see [`crate::lights`]): sampling by
//! area there weights each sample by d^2 / cos theta_light, which varies
//! without bound over a triangle that is close or seen at a grazing angle;
//! sampling by solid angle makes the weight constant over the triangle.

use glam::{Vec2, Vec3};

use crate::lanes::V3;

/// atan(y / x) for y >= 0, in [0, pi], with the same operations on both
/// backends: Cephes' `atanf` (range reduction to |t| <= tan(pi / 8) and
/// a degree-9 odd polynomial, 2e-7 relative), because GLSL's `atan` is
/// only held to 4096 ulp by Vulkan (lavapipe's differs from Rust's in the
/// fourth digit).
#[inline]
pub fn atan2_nonneg(y: f32, x: f32) -> f32 {
    lanes::atan2_nonneg(y, x)
}

/// The solid angle triangle `v` subtends from `p` (van Oosterom and
/// Strackee 1983: tan(omega / 2) = |a . (b x c)| / (1 + a.b + b.c + c.a)
/// for the unit vectors toward the vertices), in [0, 2 pi]. Zero for a
/// degenerate triangle or one whose plane holds `p`.
#[inline]
pub fn triangle_solid_angle(v: [Vec3; 3], p: Vec3) -> f32 {
    spherical_triangle_shape(v, p).0
}

/// The solid angle (as [`triangle_solid_angle`]) and the shape of the
/// spherical triangle: its solid angle over the square of its longest
/// chord, about 0.43 for a small equilateral one and near 0 for a sliver
/// (a triangle seen edge-on from afar, or a thin one). [`sample_spherical_triangle`]
/// loses its accuracy in f32 on slivers (its construction divides by
/// differences of nearly equal angles): measured in `cpu/tests/light_sampling.rs`.
#[inline]
pub fn spherical_triangle_shape(v: [Vec3; 3], p: Vec3) -> (f32, f32) {
    lanes::spherical_triangle_shape(v.map(V3::from), p.into())
}

/// A direction sampled uniformly in the solid angle triangle `v` subtends
/// from `p`, as the barycentrics (b1, b2) of the point it hits (weights of
/// `v[1]` and `v[2]`), clamped into the triangle. `None` when the triangle
/// is degenerate as seen from `p` (two vertices in one direction).
/// `omega` is [`triangle_solid_angle`]`(v, p)`, the density's reciprocal.
pub fn sample_spherical_triangle(v: [Vec3; 3], p: Vec3, omega: f32, u: Vec2) -> Option<Vec2> {
    let (valid, b) = lanes::sample_spherical_triangle(v.map(V3::from), p.into(), omega, u.into());
    valid.then(|| Vec2::new(b.x, b.y))
}

/// The spherical triangle's functions over any [`crate::lanes::Lane`]
/// type: one source with the scalar forms above (their one-lane
/// instantiation, bit for bit), each branch a select and each early
/// return a lane left invalid. Eight lanes compute what eight one-lane
/// calls compute, bit for bit (both lane types take one polynomial sine).
pub mod lanes {
    use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

    use crate::abi::{ATAN_P3, ATAN_P5, ATAN_P7, ATAN_P9, ATAN_TAN_3PI_8, ATAN_TAN_PI_8};
    use crate::lanes::{Lane, V2, V3};

    /// [`super::atan2_nonneg`].
    #[inline(always)]
    pub fn atan2_nonneg<L: Lane>(y: L, x: L) -> L {
        let flip = x.lt(L::zero());
        let ax = L::select(flip, -x, x);
        // t = y / ax >= 0, reduced without forming it where it overflows.
        let big = y.gt(L::splat(ATAN_TAN_3PI_8) * ax);
        let mid = y.gt(L::splat(ATAN_TAN_PI_8) * ax);
        let base = L::select(
            big,
            L::splat(FRAC_PI_2),
            L::select(mid, L::splat(FRAC_PI_4), L::zero()),
        );
        // One division of the picked numerator and denominator.
        let num = L::select(big, -ax, L::select(mid, y - ax, y));
        let den = L::select(big, y, L::select(mid, y + ax, ax));
        let t = num / den;
        let z = t * t;
        let r = base
            + (((L::splat(ATAN_P9) * z + L::splat(ATAN_P7)) * z + L::splat(ATAN_P5)) * z
                + L::splat(ATAN_P3))
                * z
                * t
            + t;
        let r = L::select(flip, L::splat(PI) - r, r);
        L::select(big | mid | ax.gt(L::zero()), r, L::zero())
    }

    /// [`super::spherical_triangle_shape`]: (omega, shape).
    #[inline(always)]
    pub fn spherical_triangle_shape<L: Lane>(v: [V3<L>; 3], p: V3<L>) -> (L, L) {
        let a = (v[0] - p).normalize_or_zero();
        let b = (v[1] - p).normalize_or_zero();
        let c = (v[2] - p).normalize_or_zero();
        let num = a.dot(b.cross(c)).abs();
        let den = L::one() + a.dot(b) + b.dot(c) + c.dot(a);
        let omega = L::splat(2.0) * atan2_nonneg(num, den);
        let finite = omega.abs().lt(L::splat(f32::INFINITY));
        let chord2 = (a - b)
            .length_squared()
            .max((b - c).length_squared())
            .max((c - a).length_squared());
        let shape = L::select(chord2.gt(L::zero()), omega / chord2, L::zero());
        (
            L::select(finite, omega, L::zero()),
            L::select(finite, shape, L::zero()),
        )
    }

    /// [`super::sample_spherical_triangle`]: where the sample exists, and
    /// its barycentrics.
    #[inline(always)]
    pub fn sample_spherical_triangle<L: Lane>(
        v: [V3<L>; 3],
        p: V3<L>,
        omega: L,
        u: V2<L>,
    ) -> (L::Mask, V2<L>) {
        let a = (v[0] - p).normalize_or_zero();
        let b = (v[1] - p).normalize_or_zero();
        let c = (v[2] - p).normalize_or_zero();
        // The great circles' normals through a and its neighbours: the
        // spherical triangle's angle alpha at a, as its cosine and sine (no
        // inverse trigonometry).
        let n_ab = a.cross(b);
        let n_ca = c.cross(a);
        let zero = L::zero();
        let degenerate = n_ab.length_squared().eq(zero)
            | n_ca.length_squared().eq(zero)
            | b.cross(c).length_squared().eq(zero);
        let (n_ab, n_ca) = (n_ab.normalize(), n_ca.normalize());
        let cos_alpha = -n_ab.dot(n_ca);
        let sin_alpha = n_ab.cross(n_ca).length();
        // The sub-triangle (a, b, c') whose area is u.x of the whole: its
        // angles sum to pi + u.x omega, and Arvo's construction needs the
        // sine and cosine of that sum less alpha.
        let (sin_u, cos_u) = (u.x * omega).sin_cos();
        let (sin_ap, cos_ap) = (-sin_u, -cos_u);
        let sin_phi = sin_ap * cos_alpha - cos_ap * sin_alpha;
        let cos_phi = cos_ap * cos_alpha + sin_ap * sin_alpha;
        let k1 = cos_phi + cos_alpha;
        let k2 = sin_phi - sin_alpha * a.dot(b);
        let cos_bp = (k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha)
            / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha);
        // NaN only where the triangle covers (nearly) a hemisphere, which
        // the caller's solid-angle bound keeps out.
        let nan = !cos_bp.eq(cos_bp);
        let cos_bp = cos_bp.clamp(-1.0, 1.0);
        // c' on the arc from a to c, then the direction on the arc from b
        // to c' at the fraction u.y of the arc's (1 - cos) measure.
        let sin_bp = (L::one() - cos_bp * cos_bp).max(zero).sqrt();
        let cp = a.scale(cos_bp) + (c - a.scale(c.dot(a))).normalize_or_zero().scale(sin_bp);
        // 1 - cos theta as |c' - b|^2 / 2 and sin theta from it: no
        // cancellation when the arc is short.
        let one_minus_cos = u.y * L::splat(0.5) * (cp - b).length_squared();
        let cos_theta = L::one() - one_minus_cos;
        let sin_theta = (one_minus_cos * (L::splat(2.0) - one_minus_cos))
            .max(zero)
            .sqrt();
        let w = b.scale(cos_theta)
            + (cp - b.scale(cp.dot(b)))
                .normalize_or_zero()
                .scale(sin_theta);
        // Where w meets the triangle (Moller-Trumbore with the ray p + t w).
        let e1 = v[1] - v[0];
        let e2 = v[2] - v[0];
        let s1 = w.cross(e2);
        let divisor = s1.dot(e1);
        let no_hit = divisor.eq(zero) | !divisor.abs().lt(L::splat(f32::INFINITY));
        let inv = L::one() / divisor;
        let s = p - v[0];
        let b1 = (s.dot(s1) * inv).clamp(0.0, 1.0);
        let b2 = (w.dot(s.cross(e1)) * inv).clamp(0.0, 1.0);
        let sum = b1 + b2;
        let over = sum.gt(L::one());
        let bary = V2 {
            x: L::select(over, b1 / sum, b1),
            y: L::select(over, b2 / sum, b2),
        };
        (!(degenerate | nan | no_hit), bary)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    #[test]
    fn atan2_nonneg_matches_the_library() {
        let mut worst = 0.0f32;
        for i in 0..=2000 {
            let th = PI * i as f32 / 2000.0;
            for r in [1e-6f32, 0.3, 1.0, 7.0, 1e5] {
                let (y, x) = (r * th.sin().max(0.0), r * th.cos());
                let got = atan2_nonneg(y, x);
                let want = (y as f64).atan2(x as f64) as f32;
                worst = worst.max((got - want).abs() / want.abs().max(1e-30));
            }
        }
        assert!(worst < 4e-7, "{worst}");
        assert_eq!(atan2_nonneg(0.0, 0.0), 0.0);
        assert_eq!(atan2_nonneg(0.0, -1.0), PI);
    }

    #[test]
    fn an_octant_subtends_half_pi() {
        let v = [Vec3::X, Vec3::Y, Vec3::Z];
        let omega = triangle_solid_angle(v, Vec3::ZERO);
        assert!((omega - PI / 2.0).abs() < 1e-6, "{omega}");
        // Scaled and seen from the same point: the same solid angle.
        let omega = triangle_solid_angle(v.map(|x| 7.0 * x), Vec3::ZERO);
        assert!((omega - PI / 2.0).abs() < 1e-6, "{omega}");
    }

    #[test]
    fn a_far_triangle_subtends_area_cos_over_d2() {
        let d = 100.0;
        let v = [
            Vec3::new(0.0, 0.0, d),
            Vec3::new(1.0, 0.0, d),
            Vec3::new(0.0, 1.0, d),
        ];
        let omega = triangle_solid_angle(v, Vec3::ZERO);
        let approx = 0.5 / (d * d);
        assert!((omega / approx - 1.0).abs() < 1e-3, "{omega} {approx}");
        // In its own plane: nothing.
        assert_eq!(triangle_solid_angle(v, Vec3::new(5.0, 5.0, d)), 0.0);
    }

    #[test]
    fn sampled_points_lie_on_the_triangle_and_corners_map_to_vertices() {
        let v = [Vec3::X, Vec3::Y, Vec3::Z];
        let b = sample_spherical_triangle(v, Vec3::ZERO, PI / 2.0, Vec2::new(0.0, 0.0)).unwrap();
        // u = (0, 0): the direction of b (pbrt-v4's parameterisation).
        assert!((b - Vec2::new(1.0, 0.0)).length() < 1e-5, "{b}");
        for i in 0..64 {
            let u = Vec2::new((i % 8) as f32 / 8.0 + 0.05, (i / 8) as f32 / 8.0 + 0.05);
            let b = sample_spherical_triangle(v, Vec3::ZERO, PI / 2.0, u).unwrap();
            assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6, "{b}");
        }
        assert!(
            sample_spherical_triangle([Vec3::X, Vec3::X, Vec3::Z], Vec3::ZERO, 0.0, Vec2::ZERO)
                .is_none()
        );
    }
}
