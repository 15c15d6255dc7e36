//! Lanes: the BSDF and sampling math written once over a lane type, so that
//! one source runs one path per call (`f32`, the scalar reference the GPU
//! matches) or eight side by side ([`F32x8`]), as Mitsuba 3 writes its
//! plugins once over Dr.Jit's types.
//!
//! - [`Lane`] is the arithmetic the shared code may use: the four
//!   operations, comparisons giving a [`Lane::Mask`], `select` in place of
//!   a branch, `sqrt`, `abs`, `min`/`max`/`clamp` with `f32`'s NaN rules,
//!   and `sin_cos`. A branch of the scalar code becomes a select of both
//!   sides; a lane whose inputs make NaN or infinity on the side not taken
//!   is harmless, since the select drops it.
//! - `f32` implements it with the plain scalar operations (its mask is a
//!   `bool`; `sin_cos` is the polynomial below, not libm's), so the
//!   one-lane instantiation is the scalar code (the BSDF tests and the GPU
//!   twins pin it).
//! - [`F32x8`] is eight `f32` in an array, every operation a loop over the
//!   lanes that LLVM turns into SIMD instructions of the function it is
//!   compiled in: callers run the wide code in a function compiled for
//!   AVX2 (and FMA-free, so the lanes round as the scalar code does) where
//!   [`SimdLevel::detect`] finds it, and in a baseline SSE2 function
//!   elsewhere ([`simd_at!`](crate::simd_at) makes both copies). The operations are exact per lane
//!   (IEEE add, sub, mul, div, sqrt), and `sin_cos` is one formula for
//!   both lane types (a Cody-Waite reduction and Cephes' minimax
//!   polynomials, within 2e-7 of libm on the angles the samplers use,
//!   |x| <= 2 pi), so the eight lanes compute what eight calls of the
//!   one-lane instantiation compute, bit for bit.
//! - [`V3`] is a 3-vector of lanes with glam's formulas (`dot` summed in
//!   x, y, z order, `normalize` as v * (1 / |v|)), so that `V3<f32>`
//!   rounds as `glam::Vec3` does.

use std::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

use glam::{Vec2, Vec3};

/// The lanes of `live` (bit k: lane k), lowest first: one step per set
/// bit, not a test of all eight.
#[inline(always)]
pub fn live_lanes(live: u8) -> impl Iterator<Item = usize> {
    let mut rest = live;
    std::iter::from_fn(move || {
        (rest != 0).then(|| {
            let k = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            k
        })
    })
}

/// The arithmetic the lane-generic code uses (see the module notes).
pub trait Lane:
    Copy
    + std::fmt::Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// One boolean per lane.
    type Mask: Copy
        + std::fmt::Debug
        + BitAnd<Output = Self::Mask>
        + BitOr<Output = Self::Mask>
        + Not<Output = Self::Mask>;
    /// Lanes side by side.
    const LANES: usize;
    fn splat(v: f32) -> Self;
    fn lt(self, o: Self) -> Self::Mask;
    fn le(self, o: Self) -> Self::Mask;
    fn gt(self, o: Self) -> Self::Mask;
    fn ge(self, o: Self) -> Self::Mask;
    fn eq(self, o: Self) -> Self::Mask;
    /// `t` in the lanes where `m` holds, else `f`.
    fn select(m: Self::Mask, t: Self, f: Self) -> Self;
    fn sqrt(self) -> Self;
    fn abs(self) -> Self;
    /// `f32::min` per lane (a NaN operand gives the other).
    fn min(self, o: Self) -> Self;
    /// `f32::max` per lane.
    fn max(self, o: Self) -> Self;
    /// `f32::clamp` per lane (NaN stays NaN).
    fn clamp(self, lo: f32, hi: f32) -> Self;
    /// `(sin, cos)` by one polynomial in every lane ([`sin_cos_poly`]), so
    /// that one lane and eight compute the same bits.
    fn sin_cos(self) -> (Self, Self);
    /// Lane `i` (i < LANES).
    fn lane(self, i: usize) -> f32;
    /// `f(i)` in lane i: what a table lookup per lane gathers.
    fn from_fn(f: impl FnMut(usize) -> f32) -> Self;
    /// Lane `i` of a mask.
    fn mask_lane(m: Self::Mask, i: usize) -> bool;
    /// Whether `m` holds in every lane.
    fn all(m: Self::Mask) -> bool;
    /// Whether `m` holds in no lane.
    fn none(m: Self::Mask) -> bool;
    /// The lanes of `m` as bits (bit k: lane k), the form [`live_lanes`]
    /// walks.
    #[inline(always)]
    fn bits(m: Self::Mask) -> u8 {
        (0..Self::LANES).fold(0, |b, i| b | u8::from(Self::mask_lane(m, i)) << i)
    }
    /// `(v as i32) as f32` per lane: the integer part of a value inside
    /// i32's range (0 for NaN), as a truncating conversion gives it, so it
    /// rounds as the scalar code's `y as usize` does.
    fn trunc_i32(self) -> Self;
    /// `f32::copysign` per lane: the magnitude of `self`, the sign bit of
    /// `sign` (-0.0 and NaN's sign bit included).
    fn copysign(self, sign: Self) -> Self;
    /// The next float toward +inf per lane ([`next_float_up`]).
    fn next_up(self) -> Self;
    /// The next float toward -inf per lane ([`next_float_down`]).
    fn next_down(self) -> Self;
    /// `t` in the lanes where `m` holds, else `f`, for masks.
    #[inline(always)]
    fn select_mask(m: Self::Mask, t: Self::Mask, f: Self::Mask) -> Self::Mask {
        (m & t) | (!m & f)
    }
    #[inline(always)]
    fn zero() -> Self {
        Self::splat(0.0)
    }
    #[inline(always)]
    fn one() -> Self {
        Self::splat(1.0)
    }
}

impl Lane for f32 {
    type Mask = bool;
    const LANES: usize = 1;
    #[inline(always)]
    fn splat(v: f32) -> Self {
        v
    }
    #[inline(always)]
    fn lt(self, o: Self) -> bool {
        self < o
    }
    #[inline(always)]
    fn le(self, o: Self) -> bool {
        self <= o
    }
    #[inline(always)]
    fn gt(self, o: Self) -> bool {
        self > o
    }
    #[inline(always)]
    fn ge(self, o: Self) -> bool {
        self >= o
    }
    #[inline(always)]
    fn eq(self, o: Self) -> bool {
        self == o
    }
    #[inline(always)]
    fn select(m: bool, t: Self, f: Self) -> Self {
        if m { t } else { f }
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        f32::min(self, o)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        f32::max(self, o)
    }
    #[inline(always)]
    fn clamp(self, lo: f32, hi: f32) -> Self {
        f32::clamp(self, lo, hi)
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        sin_cos_poly(self)
    }
    #[inline(always)]
    fn lane(self, _: usize) -> f32 {
        self
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
        f(0)
    }
    #[inline(always)]
    fn mask_lane(m: bool, _: usize) -> bool {
        m
    }
    #[inline(always)]
    fn all(m: bool) -> bool {
        m
    }
    #[inline(always)]
    fn none(m: bool) -> bool {
        !m
    }
    #[inline(always)]
    fn trunc_i32(self) -> Self {
        self as i32 as f32
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        f32::copysign(self, sign)
    }
    #[inline(always)]
    fn next_up(self) -> Self {
        next_float_up(self)
    }
    #[inline(always)]
    fn next_down(self) -> Self {
        next_float_down(self)
    }
}

/// The next float toward +inf (pbrt-v4's `NextFloatUp`; -0 steps from +0;
/// +inf stays).
#[inline]
pub fn next_float_up(v: f32) -> f32 {
    if v.is_infinite() && v > 0.0 {
        return v;
    }
    let mut b = v.to_bits();
    if b == 0x8000_0000 {
        b = 0;
    }
    b = if v >= 0.0 || b == 0 { b + 1 } else { b - 1 };
    f32::from_bits(b)
}

/// The next float toward -inf (pbrt-v4's `NextFloatDown`; +0 steps from
/// -0; -inf stays).
#[inline]
pub fn next_float_down(v: f32) -> f32 {
    if v.is_infinite() && v < 0.0 {
        return v;
    }
    let mut b = v.to_bits();
    if b == 0 {
        b = 0x8000_0000;
    }
    b = if v > 0.0 { b - 1 } else { b + 1 };
    f32::from_bits(b)
}

/// Eight `f32` lanes (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct F32x8(pub [f32; 8]);

/// Eight lane booleans, all bits set where true (a blend mask).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C, align(32))]
pub struct Mask8(pub [u32; 8]);

/// `[f(0), f(1), ..., f(7)]`, written out: `array::map` and
/// `array::from_fn` go through closures and a drop guard that LLVM leaves
/// out of line in a large function (measured: `try_from_fn` calls, compiled
/// without AVX2, from the wave's AVX2 copy), which the eight calls here
/// never are.
#[inline(always)]
pub fn build8<T>(mut f: impl FnMut(usize) -> T) -> [T; 8] {
    [f(0), f(1), f(2), f(3), f(4), f(5), f(6), f(7)]
}

// Lane by lane, by index ([`build8`]).
macro_rules! lanewise {
    ($f:expr; $($a:expr),+) => {
        build8(|i| $f($($a.0[i]),+))
    };
}

/// `$ymm` (with `core::arch`'s AVX intrinsics in scope and the lanes
/// loaded by [`ymm::ld`]) in a build that enables AVX2 for every
/// function (`-C target-cpu=native`, scripts/build.sh), else `$arr`, the
/// loop over the lanes: LLVM vectorises the loops of a small function, but
/// in a large one (a wave's vertex) it left two to four instructions per
/// lane operation (128-bit halves, shuffles, spills); the intrinsics are
/// one each. Both round as the scalar code does (IEEE add, sub, mul, div,
/// sqrt; ordered comparisons).
macro_rules! ymm_or {
    ($ymm:expr, $arr:expr) => {{
        #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
        #[allow(unused_unsafe)]
        // SAFETY: the build enables AVX2 (the cfg), and `ymm` only
        // reinterprets 32-byte arrays.
        let r = unsafe {
            #[allow(unused_imports)]
            use std::arch::x86_64::*;
            #[allow(unused_imports)]
            use ymm::*;
            $ymm
        };
        #[cfg(not(all(target_arch = "x86_64", target_feature = "avx2")))]
        let r = $arr;
        r
    }};
}

/// Lanes as AVX registers and back ([`ymm_or!`]).
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
mod ymm {
    use std::arch::x86_64::__m256;

    use super::{F32x8, Mask8};

    #[inline(always)]
    pub fn ld(a: F32x8) -> __m256 {
        // SAFETY: 32 bytes to 32 bytes.
        unsafe { std::mem::transmute::<[f32; 8], __m256>(a.0) }
    }
    #[inline(always)]
    pub fn st(v: __m256) -> F32x8 {
        // SAFETY: 32 bytes to 32 bytes, any bits a float.
        F32x8(unsafe { std::mem::transmute::<__m256, [f32; 8]>(v) })
    }
    #[inline(always)]
    pub fn ldm(m: Mask8) -> __m256 {
        // SAFETY: 32 bytes to 32 bytes.
        unsafe { std::mem::transmute::<[u32; 8], __m256>(m.0) }
    }
    #[inline(always)]
    pub fn stm(v: __m256) -> Mask8 {
        // SAFETY: 32 bytes to 32 bytes.
        Mask8(unsafe { std::mem::transmute::<__m256, [u32; 8]>(v) })
    }
}

impl Mask8 {
    /// The lanes `0..n` (n <= 8).
    pub fn first(n: usize) -> Self {
        Self(build8(|i| if i < n { !0 } else { 0 }))
    }

    #[inline(always)]
    pub fn test(self, i: usize) -> bool {
        self.0[i] != 0
    }

    /// The lanes whose bit is set in `bits` (bit k: lane k).
    #[inline(always)]
    pub fn from_bits(bits: u8) -> Self {
        ymm_or!(
            {
                // Lane k's bit, 1 << k, compared with itself.
                let bit = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
                let set = _mm256_and_si256(_mm256_set1_epi32(i32::from(bits)), bit);
                stm(_mm256_castsi256_ps(_mm256_cmpeq_epi32(set, bit)))
            },
            Self(build8(|i| mask_of(bits >> i & 1 != 0)))
        )
    }
}

macro_rules! f32x8_op {
    ($tr:ident, $m:ident, $op:tt, $ymm:ident) => {
        impl $tr for F32x8 {
            type Output = Self;
            #[inline(always)]
            fn $m(self, o: Self) -> Self {
                ymm_or!(
                    st($ymm(ld(self), ld(o))),
                    Self(lanewise!(|a: f32, b: f32| a $op b; self, o))
                )
            }
        }
    };
}
f32x8_op!(Add, add, +, _mm256_add_ps);
f32x8_op!(Sub, sub, -, _mm256_sub_ps);
f32x8_op!(Mul, mul, *, _mm256_mul_ps);
f32x8_op!(Div, div, /, _mm256_div_ps);

impl Neg for F32x8 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        ymm_or!(
            st(_mm256_xor_ps(ld(self), _mm256_set1_ps(-0.0))),
            Self(lanewise!(|a: f32| -a; self))
        )
    }
}

macro_rules! mask8_op {
    ($tr:ident, $m:ident, $op:tt, $ymm:ident) => {
        impl $tr for Mask8 {
            type Output = Self;
            #[inline(always)]
            fn $m(self, o: Self) -> Self {
                ymm_or!(
                    stm($ymm(ldm(self), ldm(o))),
                    Self(lanewise!(|a: u32, b: u32| a $op b; self, o))
                )
            }
        }
    };
}
mask8_op!(BitAnd, bitand, &, _mm256_and_ps);
mask8_op!(BitOr, bitor, |, _mm256_or_ps);

impl Not for Mask8 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        ymm_or!(
            stm(_mm256_xor_ps(
                ldm(self),
                _mm256_castsi256_ps(_mm256_set1_epi32(-1))
            )),
            Self(lanewise!(|a: u32| !a; self))
        )
    }
}

// (Only the lanes as arrays call it.)
#[cfg_attr(all(target_arch = "x86_64", target_feature = "avx2"), allow(dead_code))]
#[inline(always)]
fn mask_of(b: bool) -> u32 {
    if b { !0 } else { 0 }
}

// Cody-Waite split of pi/2 (Cephes' DP1..DP3 doubled) and Cephes' sinf /
// cosf minimax coefficients on [-pi/4, pi/4].
const PIO2_1: f32 = 1.570_312_5;
const PIO2_2: f32 = 4.837_513e-4;
const PIO2_3: f32 = 7.549_79e-8;
const SIN_C: [f32; 3] = [-1.666_665_5e-1, 8.332_161e-3, -1.951_529_6e-4];
const COS_C: [f32; 3] = [4.166_664_6e-2, -1.388_731_6e-3, 2.443_315_7e-5];

/// `(sin x, cos x)` of one lane by the polynomial (what `f32`'s and every
/// lane of [`F32x8`]'s `sin_cos` compute; scalar and branch-free so the
/// loop over the lanes vectorises: SSE2 has no rounding instruction, so
/// the quadrant rounds half away from zero through a truncating
/// conversion).
#[inline(always)]
fn sin_cos_poly(x: f32) -> (f32, f32) {
    let t = x * std::f32::consts::FRAC_2_PI;
    let k = (t + if t < 0.0 { -0.5 } else { 0.5 }) as i32;
    let q = k as f32;
    let r = ((x - q * PIO2_1) - q * PIO2_2) - q * PIO2_3;
    let r2 = r * r;
    let s = r + r * r2 * (SIN_C[0] + r2 * (SIN_C[1] + r2 * SIN_C[2]));
    let c = 1.0 - 0.5 * r2 + r2 * r2 * (COS_C[0] + r2 * (COS_C[1] + r2 * COS_C[2]));
    // Quadrant k mod 4: (s, c), (c, -s), (-s, -c), (-c, s).
    let (a, b) = if k & 1 == 0 { (s, c) } else { (c, s) };
    let sin = if k & 2 != 0 { -a } else { a };
    // (Wrapping: a lane of garbage past 2^31 quadrants saturates k.)
    let cos = if k.wrapping_add(1) & 2 != 0 { -b } else { b };
    (sin, cos)
}

/// [`sin_cos_poly`] in AVX2 registers: the same operations in the same
/// order, so the same bits, for every lane whose quadrant fits an i32
/// (|x| < 3e9; the truncating conversion gives i32::MIN past that where
/// `as i32` saturates, a difference only lanes of garbage see).
#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
#[inline(always)]
fn sin_cos_ymm(x: F32x8) -> (F32x8, F32x8) {
    use std::arch::x86_64::*;
    use ymm::{ld, st};
    // SAFETY: the build enables AVX2 (the cfg).
    #[allow(unused_unsafe)]
    unsafe {
        let x = ld(x);
        let s1 = _mm256_set1_ps;
        let t = _mm256_mul_ps(x, s1(std::f32::consts::FRAC_2_PI));
        let neg = _mm256_cmp_ps::<_CMP_LT_OQ>(t, _mm256_setzero_ps());
        let half = _mm256_blendv_ps(s1(0.5), s1(-0.5), neg);
        let k = _mm256_cvttps_epi32(_mm256_add_ps(t, half));
        let q = _mm256_cvtepi32_ps(k);
        let r = _mm256_sub_ps(
            _mm256_sub_ps(
                _mm256_sub_ps(x, _mm256_mul_ps(q, s1(PIO2_1))),
                _mm256_mul_ps(q, s1(PIO2_2)),
            ),
            _mm256_mul_ps(q, s1(PIO2_3)),
        );
        let r2 = _mm256_mul_ps(r, r);
        // r + r * r2 * (S0 + r2 * (S1 + r2 * S2))
        let ps = _mm256_add_ps(
            s1(SIN_C[0]),
            _mm256_mul_ps(
                r2,
                _mm256_add_ps(s1(SIN_C[1]), _mm256_mul_ps(r2, s1(SIN_C[2]))),
            ),
        );
        let s = _mm256_add_ps(r, _mm256_mul_ps(_mm256_mul_ps(r, r2), ps));
        // 1 - 0.5 r2 + r2 * r2 * (C0 + r2 * (C1 + r2 * C2))
        let pc = _mm256_add_ps(
            s1(COS_C[0]),
            _mm256_mul_ps(
                r2,
                _mm256_add_ps(s1(COS_C[1]), _mm256_mul_ps(r2, s1(COS_C[2]))),
            ),
        );
        let c = _mm256_add_ps(
            _mm256_sub_ps(s1(1.0), _mm256_mul_ps(s1(0.5), r2)),
            _mm256_mul_ps(_mm256_mul_ps(r2, r2), pc),
        );
        let bit = |v: __m256i, b: i32| {
            let set = _mm256_set1_epi32(b);
            _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(v, set), set))
        };
        let odd = bit(k, 1);
        let a = _mm256_blendv_ps(s, c, odd);
        let b = _mm256_blendv_ps(c, s, odd);
        let sign = s1(-0.0);
        let sin = _mm256_blendv_ps(a, _mm256_xor_ps(a, sign), bit(k, 2));
        let k1 = _mm256_add_epi32(k, _mm256_set1_epi32(1));
        let cos = _mm256_blendv_ps(b, _mm256_xor_ps(b, sign), bit(k1, 2));
        (st(sin), st(cos))
    }
}

impl Lane for F32x8 {
    type Mask = Mask8;
    const LANES: usize = 8;
    #[inline(always)]
    fn splat(v: f32) -> Self {
        Self([v; 8])
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Mask8 {
        ymm_or!(
            stm(_mm256_cmp_ps::<_CMP_LT_OQ>(ld(self), ld(o))),
            Mask8(lanewise!(|a: f32, b: f32| mask_of(a < b); self, o))
        )
    }
    #[inline(always)]
    fn le(self, o: Self) -> Mask8 {
        ymm_or!(
            stm(_mm256_cmp_ps::<_CMP_LE_OQ>(ld(self), ld(o))),
            Mask8(lanewise!(|a: f32, b: f32| mask_of(a <= b); self, o))
        )
    }
    #[inline(always)]
    fn gt(self, o: Self) -> Mask8 {
        ymm_or!(
            stm(_mm256_cmp_ps::<_CMP_GT_OQ>(ld(self), ld(o))),
            Mask8(lanewise!(|a: f32, b: f32| mask_of(a > b); self, o))
        )
    }
    #[inline(always)]
    fn ge(self, o: Self) -> Mask8 {
        ymm_or!(
            stm(_mm256_cmp_ps::<_CMP_GE_OQ>(ld(self), ld(o))),
            Mask8(lanewise!(|a: f32, b: f32| mask_of(a >= b); self, o))
        )
    }
    #[inline(always)]
    fn eq(self, o: Self) -> Mask8 {
        ymm_or!(
            stm(_mm256_cmp_ps::<_CMP_EQ_OQ>(ld(self), ld(o))),
            Mask8(lanewise!(|a: f32, b: f32| mask_of(a == b); self, o))
        )
    }
    #[inline(always)]
    fn select(m: Mask8, t: Self, f: Self) -> Self {
        ymm_or!(
            st(_mm256_blendv_ps(ld(f), ld(t), ldm(m))),
            Self(build8(|i| {
                f32::from_bits((t.0[i].to_bits() & m.0[i]) | (f.0[i].to_bits() & !m.0[i]))
            }))
        )
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        ymm_or!(
            st(_mm256_sqrt_ps(ld(self))),
            Self(lanewise!(f32::sqrt; self))
        )
    }
    #[inline(always)]
    fn abs(self) -> Self {
        ymm_or!(
            st(_mm256_andnot_ps(_mm256_set1_ps(-0.0), ld(self))),
            Self(lanewise!(f32::abs; self))
        )
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Self(lanewise!(f32::min; self, o))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Self(lanewise!(f32::max; self, o))
    }
    #[inline(always)]
    fn clamp(self, lo: f32, hi: f32) -> Self {
        Self(lanewise!(|a: f32| a.clamp(lo, hi); self))
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        ymm_or!(sin_cos_ymm(self), {
            let sc: [(f32, f32); 8] = lanewise!(sin_cos_poly; self);
            (Self(build8(|i| sc[i].0)), Self(build8(|i| sc[i].1)))
        })
    }
    #[inline(always)]
    fn lane(self, i: usize) -> f32 {
        self.0[i]
    }
    #[inline(always)]
    fn from_fn(f: impl FnMut(usize) -> f32) -> Self {
        Self(build8(f))
    }
    #[inline(always)]
    fn mask_lane(m: Mask8, i: usize) -> bool {
        m.test(i)
    }
    #[inline(always)]
    fn all(m: Mask8) -> bool {
        ymm_or!(
            _mm256_movemask_ps(ldm(m)) == 0xff,
            m.0.iter().fold(!0, |a, &b| a & b) != 0
        )
    }
    #[inline(always)]
    fn none(m: Mask8) -> bool {
        ymm_or!(
            _mm256_movemask_ps(ldm(m)) == 0,
            m.0.iter().fold(0, |a, &b| a | b) == 0
        )
    }
    #[inline(always)]
    fn bits(m: Mask8) -> u8 {
        ymm_or!(
            _mm256_movemask_ps(ldm(m)) as u8,
            (0..8).fold(0, |b, i| b | u8::from(m.test(i)) << i)
        )
    }
    #[inline(always)]
    fn trunc_i32(self) -> Self {
        Self(lanewise!(|a: f32| a as i32 as f32; self))
    }
    #[inline(always)]
    fn next_up(self) -> Self {
        ymm_or!(
            {
                let v = ld(self);
                let b = _mm256_castps_si256(v);
                let i = _mm256_set1_epi32;
                // -0 steps from +0.
                let b = _mm256_andnot_si256(_mm256_cmpeq_epi32(b, i(i32::MIN)), b);
                let up = _mm256_or_ps(
                    _mm256_cmp_ps::<_CMP_GE_OQ>(v, _mm256_setzero_ps()),
                    _mm256_castsi256_ps(_mm256_cmpeq_epi32(b, _mm256_setzero_si256())),
                );
                let r = _mm256_blendv_ps(
                    _mm256_castsi256_ps(_mm256_sub_epi32(b, i(1))),
                    _mm256_castsi256_ps(_mm256_add_epi32(b, i(1))),
                    up,
                );
                let inf = _mm256_cmp_ps::<_CMP_EQ_OQ>(v, _mm256_set1_ps(f32::INFINITY));
                st(_mm256_blendv_ps(r, v, inf))
            },
            Self(lanewise!(next_float_up; self))
        )
    }
    #[inline(always)]
    fn next_down(self) -> Self {
        ymm_or!(
            {
                let v = ld(self);
                let b = _mm256_castps_si256(v);
                let i = _mm256_set1_epi32;
                // +0 steps from -0.
                let zero = _mm256_cmpeq_epi32(b, _mm256_setzero_si256());
                let b = _mm256_or_si256(b, _mm256_and_si256(zero, i(i32::MIN)));
                let r = _mm256_blendv_ps(
                    _mm256_castsi256_ps(_mm256_add_epi32(b, i(1))),
                    _mm256_castsi256_ps(_mm256_sub_epi32(b, i(1))),
                    _mm256_cmp_ps::<_CMP_GT_OQ>(v, _mm256_setzero_ps()),
                );
                let inf = _mm256_cmp_ps::<_CMP_EQ_OQ>(v, _mm256_set1_ps(f32::NEG_INFINITY));
                st(_mm256_blendv_ps(r, v, inf))
            },
            Self(lanewise!(next_float_down; self))
        )
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        ymm_or!(
            {
                let bit = _mm256_set1_ps(-0.0);
                st(_mm256_or_ps(
                    _mm256_andnot_ps(bit, ld(self)),
                    _mm256_and_ps(bit, ld(sign)),
                ))
            },
            Self(lanewise!(f32::copysign; self, sign))
        )
    }
}

/// The integer arithmetic of the hash-based samplers (`sampling::pcg4d`,
/// the Owen-scrambled Sobol pairs) over `u32` or eight lanes of it,
/// wrapping as the scalar code's `wrapping_*` calls do.
pub trait ULane: Copy + std::fmt::Debug {
    /// The float lanes of the same width.
    type F: Lane;
    fn splat(v: u32) -> Self;
    fn add(self, o: Self) -> Self;
    fn mul(self, o: Self) -> Self;
    fn xor(self, o: Self) -> Self;
    fn and(self, o: Self) -> Self;
    fn or(self, o: Self) -> Self;
    fn shr(self, n: u32) -> Self;
    fn reverse_bits(self) -> Self;
    /// `f32::from_bits` per lane.
    fn bits_to_f32(self) -> Self::F;
}

impl ULane for u32 {
    type F = f32;
    #[inline(always)]
    fn splat(v: u32) -> Self {
        v
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self.wrapping_add(o)
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self.wrapping_mul(o)
    }
    #[inline(always)]
    fn xor(self, o: Self) -> Self {
        self ^ o
    }
    #[inline(always)]
    fn and(self, o: Self) -> Self {
        self & o
    }
    #[inline(always)]
    fn or(self, o: Self) -> Self {
        self | o
    }
    #[inline(always)]
    fn shr(self, n: u32) -> Self {
        self >> n
    }
    #[inline(always)]
    fn reverse_bits(self) -> Self {
        u32::reverse_bits(self)
    }
    #[inline(always)]
    fn bits_to_f32(self) -> f32 {
        f32::from_bits(self)
    }
}

/// Eight `u32` lanes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C, align(32))]
pub struct U32x8(pub [u32; 8]);

impl ULane for U32x8 {
    type F = F32x8;
    #[inline(always)]
    fn splat(v: u32) -> Self {
        Self([v; 8])
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self(lanewise!(u32::wrapping_add; self, o))
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Self(lanewise!(u32::wrapping_mul; self, o))
    }
    #[inline(always)]
    fn xor(self, o: Self) -> Self {
        Self(lanewise!(|a: u32, b: u32| a ^ b; self, o))
    }
    #[inline(always)]
    fn and(self, o: Self) -> Self {
        Self(lanewise!(|a: u32, b: u32| a & b; self, o))
    }
    #[inline(always)]
    fn or(self, o: Self) -> Self {
        Self(lanewise!(|a: u32, b: u32| a | b; self, o))
    }
    #[inline(always)]
    fn shr(self, n: u32) -> Self {
        Self(lanewise!(|a: u32| a >> n; self))
    }
    #[inline(always)]
    fn reverse_bits(self) -> Self {
        Self(lanewise!(u32::reverse_bits; self))
    }
    #[inline(always)]
    fn bits_to_f32(self) -> F32x8 {
        F32x8(lanewise!(f32::from_bits; self))
    }
}

/// A 3-vector of lanes, with glam's formulas.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<L> {
    pub x: L,
    pub y: L,
    pub z: L,
}

/// A 2-vector of lanes (the samplers' random pairs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V2<L> {
    pub x: L,
    pub y: L,
}

impl<L: Lane> V3<L> {
    #[inline(always)]
    pub fn new(x: L, y: L, z: L) -> Self {
        Self { x, y, z }
    }
    #[inline(always)]
    pub fn splat(v: Vec3) -> Self {
        Self::new(L::splat(v.x), L::splat(v.y), L::splat(v.z))
    }
    #[inline(always)]
    pub fn dot(self, o: Self) -> L {
        (self.x * o.x) + (self.y * o.y) + (self.z * o.z)
    }
    #[inline(always)]
    pub fn length_squared(self) -> L {
        self.dot(self)
    }
    /// `self * s` componentwise.
    #[inline(always)]
    pub fn scale(self, s: L) -> Self {
        Self::new(self.x * s, self.y * s, self.z * s)
    }
    #[inline(always)]
    pub fn length(self) -> L {
        self.length_squared().sqrt()
    }
    /// glam's `normalize`: v * (1 / |v|).
    #[inline(always)]
    pub fn normalize(self) -> Self {
        self.scale(L::one() / self.length_squared().sqrt())
    }
    /// glam's `normalize_or_zero`: v * (1 / |v|) where that reciprocal is
    /// finite and positive, else zero.
    #[inline(always)]
    pub fn normalize_or_zero(self) -> Self {
        let rcp = L::one() / self.length();
        let ok = rcp.abs().lt(L::splat(f32::INFINITY)) & rcp.gt(L::zero());
        Self::select(ok, self.scale(rcp), Self::splat(Vec3::ZERO))
    }
    /// glam's `cross`.
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y * o.z - o.y * self.z,
            self.z * o.x - o.z * self.x,
            self.x * o.y - o.x * self.y,
        )
    }
    #[inline(always)]
    pub fn select(m: L::Mask, t: Self, f: Self) -> Self {
        Self::new(
            L::select(m, t.x, f.x),
            L::select(m, t.y, f.y),
            L::select(m, t.z, f.z),
        )
    }
    /// glam's `abs`.
    #[inline(always)]
    pub fn abs(self) -> Self {
        Self::new(self.x.abs(), self.y.abs(), self.z.abs())
    }
    /// glam's `max_element`: max(x, max(y, z)) with max(a, b) = a where
    /// a > b, else b (so a NaN in z or y wins over smaller components,
    /// unlike `f32::max`).
    #[inline(always)]
    pub fn max_element(self) -> L {
        let max = |a: L, b: L| L::select(a.gt(b), a, b);
        max(self.x, max(self.y, self.z))
    }
    /// Lane `i` as a glam vector.
    #[inline(always)]
    pub fn lane(self, i: usize) -> Vec3 {
        Vec3::new(self.x.lane(i), self.y.lane(i), self.z.lane(i))
    }
}

impl<L: Lane> Add for V3<L> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl<L: Lane> Sub for V3<L> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

/// Componentwise product.
impl<L: Lane> Mul for V3<L> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Self::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
}

/// Each component divided by `s`.
impl<L: Lane> Div<L> for V3<L> {
    type Output = Self;
    #[inline(always)]
    fn div(self, s: L) -> Self {
        Self::new(self.x / s, self.y / s, self.z / s)
    }
}

impl<L: Lane> Neg for V3<L> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}

impl From<Vec3> for V3<f32> {
    #[inline(always)]
    fn from(v: Vec3) -> Self {
        Self::new(v.x, v.y, v.z)
    }
}

impl From<V3<f32>> for Vec3 {
    #[inline(always)]
    fn from(v: V3<f32>) -> Self {
        Vec3::new(v.x, v.y, v.z)
    }
}

impl From<Vec2> for V2<f32> {
    #[inline(always)]
    fn from(v: Vec2) -> Self {
        Self { x: v.x, y: v.y }
    }
}

impl From<[Vec3; 8]> for V3<F32x8> {
    fn from(v: [Vec3; 8]) -> Self {
        Self::new(
            F32x8(build8(|i| v[i].x)),
            F32x8(build8(|i| v[i].y)),
            F32x8(build8(|i| v[i].z)),
        )
    }
}

impl From<[Vec2; 8]> for V2<F32x8> {
    fn from(v: [Vec2; 8]) -> Self {
        Self {
            x: F32x8(build8(|i| v[i].x)),
            y: F32x8(build8(|i| v[i].y)),
        }
    }
}

/// The widest instruction set the wide lanes run on here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimdLevel {
    /// x86-64's baseline (two 4-wide halves per 8 lanes), or plain loops
    /// off x86.
    Sse2,
    /// 8 lanes per instruction.
    Avx2,
}

impl SimdLevel {
    /// What this CPU has (cached by std).
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            return Self::Avx2;
        }
        Self::Sse2
    }

    /// How many single-path calls eight lanes cost, rounded up: the least
    /// number of live lanes for which wide code pays (the Sobol bounce
    /// measured 5.3x per lane on AVX2, 1.5x on SSE2, which has no 32-bit
    /// lane multiply; `cpu/tests/lanes_throughput.rs`).
    pub fn break_even(self) -> u8 {
        match self {
            Self::Avx2 => 2,
            Self::Sse2 => 6,
        }
    }

    /// Every level this CPU runs, baseline first (the tests run each).
    pub fn available() -> Vec<Self> {
        let mut v = vec![Self::Sse2];
        if Self::detect() == Self::Avx2 {
            v.push(Self::Avx2);
        }
        v
    }
}

/// `simd_at!(level, fn(args: T, ...) -> R { body } (values, ...))`, or
/// `fn<M: Bound>(...)` over the caller's type parameter `M`: the
/// function literal instantiated twice, once compiled for AVX2 and once for
/// the baseline, and called for `level` (the baseline where the CPU lacks
/// AVX2). The lane-generic code must be `#[inline(always)]` all the way
/// down for the AVX2 copy to hold it; a closure would not do, since it is
/// compiled once, without the feature, and called. The body sees no local
/// variables, only its arguments.
#[macro_export]
macro_rules! simd_at {
    // Generic over one type parameter `$g`, the caller's own (by name).
    ($level:expr, fn<$g:ident: $bound:path>($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty $body:block ($($val:expr),* $(,)?)) => {
        $crate::simd_at!(@at $level, [$g: $bound], [$g], ($($arg: $ty),*) -> $ret $body ($($val),*))
    };
    ($level:expr, fn($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty $body:block ($($val:expr),* $(,)?)) => {
        $crate::simd_at!(@at $level, [], [], ($($arg: $ty),*) -> $ret $body ($($val),*))
    };
    (@at $level:expr, [$($gen:tt)*], [$($inst:tt)*], ($($arg:ident: $ty:ty),*) -> $ret:ty $body:block ($($val:expr),*)) => {{
        #[inline(always)]
        fn body<$($gen)*>($($arg: $ty),*) -> $ret $body
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        unsafe fn avx2<$($gen)*>($($arg: $ty),*) -> $ret {
            body::<$($inst)*>($($arg),*)
        }
        // The arguments first, outside the unsafe block.
        $(let $arg: $ty = $val;)*
        match $level {
            #[cfg(target_arch = "x86_64")]
            $crate::lanes::SimdLevel::Avx2
                if $crate::lanes::SimdLevel::detect() == $crate::lanes::SimdLevel::Avx2 =>
            {
                // SAFETY: the CPU has AVX2 (checked just above).
                unsafe { avx2::<$($inst)*>($($arg),*) }
            }
            _ => body::<$($inst)*>($($arg),*),
        }
    }};
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_cos_polynomial_is_libm_within_2e_7() {
        let mut worst = 0.0f32;
        for i in -20_000..=20_000 {
            let x = i as f32 * (std::f32::consts::TAU / 20_000.0);
            let (s, c) = sin_cos_poly(x);
            let (rs, rc) = x.sin_cos();
            worst = worst.max((s - rs).abs()).max((c - rc).abs());
        }
        assert!(worst <= 2e-7, "worst {worst:e}");
    }

    #[test]
    fn masks_from_and_to_bits_round_trip() {
        for b in 0..=255u8 {
            let m = Mask8::from_bits(b);
            assert_eq!(F32x8::bits(m), b);
            for i in 0..8 {
                assert_eq!(
                    m.0[i],
                    if b >> i & 1 != 0 { !0 } else { 0 },
                    "{b:#x} lane {i}"
                );
            }
        }
    }

    #[test]
    fn select_keeps_the_masked_lanes_bits() {
        let t = F32x8([f32::NAN, 1.0, f32::INFINITY, -0.0, 2.0, 3.0, 4.0, 5.0]);
        let f = F32x8::splat(7.0);
        let m = Mask8::first(2);
        let r = F32x8::select(m, t, f);
        assert!(r.0[0].is_nan());
        assert_eq!(&r.0[1..], &[1.0, 7.0, 7.0, 7.0, 7.0, 7.0, 7.0]);
    }
}
