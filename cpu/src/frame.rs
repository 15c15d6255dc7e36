//! Orthonormal shading frames: local coordinates have the normal on +z, so
//! `cos theta = w.z` (pbrt-v4's convention).

use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
}

impl Frame {
    /// A frame around unit normal `n`, tangent chosen by Duff et al. 2017
    /// ("Building an Orthonormal Basis, Revisited"): continuous except at
    /// n.z = -1 exactly, branch-free, and written identically in GLSL.
    #[inline]
    pub fn from_normal(n: Vec3) -> Self {
        let f = lanes::Frame::<f32>::from_normal(n.into());
        Self {
            s: f.s.into(),
            t: f.t.into(),
            n,
        }
    }

    /// A frame around unit normal `n` whose `s` axis follows `tangent`
    /// projected onto the tangent plane (Gram-Schmidt); falls back to
    /// [`Frame::from_normal`] when the tangent is degenerate or parallel to n.
    pub fn from_normal_tangent(n: Vec3, tangent: Vec3) -> Self {
        let (ok, s, t) = lanes::tangent_axes::<f32>(n.into(), tangent.into());
        if !ok {
            return Self::from_normal(n);
        }
        Self {
            s: s.into(),
            t: t.into(),
            n,
        }
    }

    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// The frames over any [`crate::lanes::Lane`] type (one source with the
/// scalar [`Frame::from_normal`] and [`Frame::from_normal_tangent`], and
/// the same formulas as its `to_local` and `to_world`).
pub mod lanes {
    use crate::lanes::{Lane, V3};

    #[derive(Clone, Copy, Debug)]
    pub struct Frame<L> {
        pub s: V3<L>,
        pub t: V3<L>,
        pub n: V3<L>,
    }

    /// The axes s and t of the frame around unit normal `n` whose s
    /// follows `tangent` projected onto the tangent plane (Gram-Schmidt),
    /// valid where the projection's squared length is in [1e-12, f32::MAX]
    /// (not where the tangent is degenerate, parallel to n or NaN).
    #[inline(always)]
    pub fn tangent_axes<L: Lane>(n: V3<L>, tangent: V3<L>) -> (L::Mask, V3<L>, V3<L>) {
        let s = tangent - n.scale(n.dot(tangent));
        let len2 = s.length_squared();
        let ok = len2.ge(L::splat(1e-12)) & len2.le(L::splat(f32::MAX));
        let s = s / len2.sqrt();
        (ok, s, n.cross(s))
    }

    impl<L: Lane> Frame<L> {
        /// [`super::Frame::from_normal`] in every lane.
        #[inline(always)]
        pub fn from_normal(n: V3<L>) -> Self {
            let sign = L::one().copysign(n.z);
            let a = -L::one() / (sign + n.z);
            let b = n.x * n.y * a;
            let s = V3::new(L::one() + sign * n.x * n.x * a, sign * b, -sign * n.x);
            let t = V3::new(b, sign + n.y * n.y * a, -n.y);
            Self { s, t, n }
        }

        /// [`super::Frame::from_normal_tangent`] in every lane.
        #[inline(always)]
        pub fn from_normal_tangent(n: V3<L>, tangent: V3<L>) -> Self {
            let (ok, s, t) = tangent_axes(n, tangent);
            let f = Self::from_normal(n);
            Self {
                s: V3::select(ok, s, f.s),
                t: V3::select(ok, t, f.t),
                n,
            }
        }

        #[inline(always)]
        pub fn to_local(&self, v: V3<L>) -> V3<L> {
            V3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
        }

        #[inline(always)]
        pub fn to_world(&self, v: V3<L>) -> V3<L> {
            self.s.scale(v.x) + self.t.scale(v.y) + self.n.scale(v.z)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_orthonormal_and_invert() {
        let normals = [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.5, 0.8).normalize(),
            Vec3::new(1e-7, 0.0, -1.0).normalize(),
        ];
        for n in normals {
            for f in [
                Frame::from_normal(n),
                Frame::from_normal_tangent(n, Vec3::new(1.0, 2.0, 3.0).normalize()),
            ] {
                assert!((f.s.length() - 1.0).abs() < 1e-5);
                assert!((f.t.length() - 1.0).abs() < 1e-5);
                assert!(
                    f.s.dot(f.t).abs() < 1e-5
                        && f.s.dot(f.n).abs() < 1e-5
                        && f.t.dot(f.n).abs() < 1e-5
                );
                // Right-handed: s x t = n.
                assert!((f.s.cross(f.t) - f.n).length() < 1e-4, "{f:?}");
                let v = Vec3::new(0.2, -0.7, 0.4);
                assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
            }
        }
    }

    /// The tangent frames in lanes are the scalar frames bit for bit in
    /// every lane, degenerate tangents (zero, parallel to n, NaN, huge)
    /// falling back to the normal-only frame as one lane does.
    #[test]
    fn tangent_frames_in_lanes_are_the_scalar_ones() {
        use crate::lanes::{F32x8, V3};
        let n = [
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(0.3, -0.5, 0.8).normalize(),
            Vec3::X,
            Vec3::new(1e-7, 0.0, -1.0).normalize(),
            Vec3::new(-0.6, 0.0, 0.8),
            Vec3::Y,
            Vec3::new(0.0, 0.6, -0.8),
        ];
        let t = [
            Vec3::new(1.0, 2.0, 3.0).normalize(),
            Vec3::ZERO,
            Vec3::new(0.3, -0.5, 0.8).normalize(),
            Vec3::new(f32::NAN, 0.0, 1.0),
            Vec3::new(1e-7, 0.0, 0.0),
            Vec3::new(3e19, -1e19, 2e19),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 1e-3, 0.0),
        ];
        let lanes3 = |v: [Vec3; 8]| {
            V3::new(
                F32x8(v.map(|v| v.x)),
                F32x8(v.map(|v| v.y)),
                F32x8(v.map(|v| v.z)),
            )
        };
        let f = lanes::Frame::<F32x8>::from_normal_tangent(lanes3(n), lanes3(t));
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        for l in 0..8 {
            let one = Frame::from_normal_tangent(n[l], t[l]);
            assert_eq!(bits(f.s.lane(l)), bits(one.s), "lane {l} s");
            assert_eq!(bits(f.t.lane(l)), bits(one.t), "lane {l} t");
        }
    }
}
