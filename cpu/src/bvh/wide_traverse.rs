//! Ray queries on the 4-wide BVH: one box test for all four children of a
//! node (SSE on x86_64, chosen at run time, else a scalar loop), children
//! visited nearest first, triangles tested with the binary traversal's
//! watertight test. `shaders/bvh.glsl` mirrors this file: `intersect_aabb4`,
//! `sort4` and the `bvh_intersect` / `bvh_occluded` loops.
//!
//! Every kernel computes, for each child, exactly what [`intersect_aabb`]
//! computes for that child's box (the same IEEE operations in the same
//! order), so the SIMD, scalar and binary traversals accept the same boxes
//! and find the same closest triangle.

use std::mem::MaybeUninit;

use super::traverse::{PreparedRay, SLAB_PAD, intersect_aabb, intersect_triangle};
use super::wide::{Bvh4Node, SLOT_EMPTY, WIDE_STACK_SIZE, is_leaf_ref, leaf_range};
use super::wide8::{Bvh8Node, LeafBlock, WIDE8_STACK_SIZE};
use super::{Hit, Ray};
use crate::scene::Triangle;

/// How the four boxes of a node are tested. [`Kernel::best`] picks the
/// fastest the CPU supports; the others exist to be compared with it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// Four calls of the binary traversal's [`intersect_aabb`].
    Scalar,
    /// SSE2 (every x86_64 CPU has it).
    Sse2,
    /// The same SSE code compiled with AVX enabled: VEX three-operand
    /// encodings, no extra width (a 4-wide node fills an SSE register).
    Avx,
    /// The 8-wide tree (`wide8.rs`), eight boxes per AVX instruction (AVX2
    /// for the integer compare of the child slots); leaves as `Avx`.
    Avx2x8,
}

impl Kernel {
    /// The kernels this CPU can run, scalar first.
    pub fn available() -> Vec<Kernel> {
        let mut k = vec![Kernel::Scalar];
        #[cfg(target_arch = "x86_64")]
        {
            k.push(Kernel::Sse2);
            if std::arch::is_x86_feature_detected!("avx") {
                k.push(Kernel::Avx);
            }
            if Self::has_avx2() {
                k.push(Kernel::Avx2x8);
            }
        }
        k
    }

    /// Whether this CPU runs [`Kernel::Avx2x8`] (cached by std).
    #[inline]
    pub fn has_avx2() -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            std::arch::is_x86_feature_detected!("avx2")
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            false
        }
    }

    /// The kernel [`super::Bvh4::intersect`] uses: the 8-wide tree where
    /// the CPU has AVX2, else AVX, else SSE2 on x86_64, else scalar. The
    /// detection is cached by std.
    #[inline]
    pub fn best() -> Kernel {
        #[cfg(target_arch = "x86_64")]
        {
            if Self::has_avx2() {
                Kernel::Avx2x8
            } else if std::arch::is_x86_feature_detected!("avx") {
                Kernel::Avx
            } else {
                Kernel::Sse2
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            Kernel::Scalar
        }
    }
}

/// Entry distances of the ray into the four child boxes: +inf for a missed
/// box or an empty slot, as [`intersect_aabb`] returns for one box; and the
/// mask of hit slots (bit i: slot i).
#[inline(always)]
fn intersect_aabb4_scalar(r: &PreparedRay, n: &Bvh4Node, tmax: f32) -> (u32, [f32; 4]) {
    let mut mask = 0;
    let mut dist = [f32::INFINITY; 4];
    for (i, d) in dist.iter_mut().enumerate() {
        if n.child[i] == SLOT_EMPTY {
            break;
        }
        let (lo, hi) = n.child_box(i);
        *d = intersect_aabb(r, lo, hi, tmax);
        if *d != f32::INFINITY {
            mask |= 1 << i;
        }
    }
    (mask, dist)
}

/// The slots in order of (distance, slot): a sorting network of five
/// compare-exchanges, so the order is the same whatever the kernel (ties,
/// e.g. an origin inside two boxes, both at 0, go to the lower slot) and
/// misses (+inf) come last. `sort4` in GLSL; the CPU loop's
/// [`order_hits`] gives the same order of the hits (a unit test pins it).
#[cfg(test)]
fn sort4(dist: &[f32; 4]) -> [usize; 4] {
    let mut o = [0, 1, 2, 3];
    let mut cx = |i: usize, j: usize| {
        let (a, b) = (o[i], o[j]);
        if dist[b] < dist[a] || (dist[b] == dist[a] && b < a) {
            o.swap(i, j);
        }
    };
    cx(0, 1);
    cx(2, 3);
    cx(0, 2);
    cx(1, 3);
    cx(1, 2);
    o
}

/// A leaf's triangles one at a time, in order, for the closest hit: each
/// test's interval ends at the best hit so far. The reference the SIMD leaf
/// test (`x86::leaf_closest`) reproduces bit for bit.
#[inline(always)]
fn leaf_closest_scalar(
    r: &PreparedRay,
    tris: &[Triangle],
    first: usize,
    count: usize,
    best: &mut Hit,
    present: impl Fn(u32, f32, f32) -> bool,
) {
    for (i, tri) in (first..).zip(&tris[first..first + count]) {
        if let Some((t, u, v)) = intersect_triangle(r, tri, best.t)
            && present(i as u32, u, v)
        {
            *best = Hit {
                t,
                tri: i as u32,
                u,
                v,
            };
        }
    }
}

/// Whether any of a leaf's triangles is hit in (0, tmax).
#[inline(always)]
fn leaf_any_scalar(
    r: &PreparedRay,
    tris: &[Triangle],
    first: usize,
    count: usize,
    tmax: f32,
    present: impl Fn(u32, f32, f32) -> bool,
) -> bool {
    (first..).zip(&tris[first..first + count]).any(|(i, tri)| {
        intersect_triangle(r, tri, tmax).is_some_and(|(_, u, v)| present(i as u32, u, v))
    })
}

/// A wide node as the traversal loop sees it: its child references.
pub(super) trait WideNode {
    fn child(&self, slot: usize) -> u32;
}

impl WideNode for Bvh4Node {
    #[inline(always)]
    fn child(&self, slot: usize) -> u32 {
        self.child[slot]
    }
}

impl WideNode for Bvh8Node {
    #[inline(always)]
    fn child(&self, slot: usize) -> u32 {
        self.child[slot]
    }
}

/// Stack entries of either width's traversal: the 8-wide bound (7 per
/// level), which holds the 4-wide one (3 per level) too.
const STACK: usize = WIDE8_STACK_SIZE;
const _: () = assert!(WIDE_STACK_SIZE <= STACK);

/// The hit slots of a node (`mask`) in order of (distance, slot), nearest
/// first, and how many: an insertion sort of the slots taken in increasing
/// order, so a tie stays behind the lower slot. For four slots it is
/// `sort4`'s order of the hits (GLSL's), which a unit test pins.
#[inline(always)]
pub(super) fn order_hits<const W: usize>(mask: u32, dist: &[f32; W]) -> ([u8; W], usize) {
    let mut order = [0u8; W];
    let mut n = 0;
    let mut m = mask;
    while m != 0 {
        let s = m.trailing_zeros() as u8;
        m &= m - 1;
        let mut k = n;
        while k > 0 && dist[s as usize] < dist[order[k - 1] as usize] {
            order[k] = order[k - 1];
            k -= 1;
        }
        order[k] = s;
        n += 1;
    }
    (order, n)
}

/// Closest hit, generic over the node width and the box and leaf tests.
/// Children are visited nearest first; the others wait on the stack with
/// their entry distance and are dropped when popped if the best hit has
/// since moved in front of them (the box test's own criterion: entry >
/// tmax x SLAB_PAD misses). `leaf(first, count, best)` tests a leaf
/// reference's range.
#[inline(always)]
fn closest<N, const W: usize, F, L>(nodes: &[N], tmax: f32, boxes: F, mut leaf: L) -> Option<Hit>
where
    N: WideNode,
    F: Fn(&N, f32) -> (u32, [f32; W]),
    L: FnMut(usize, usize, &mut Hit),
{
    let mut best = Hit {
        t: tmax,
        tri: u32::MAX,
        u: 0.0,
        v: 0.0,
    };
    // Not zeroed: only entries below `sp`, each written by a push, are read
    // (zeroing the stack per query was 2% of a render, in memset).
    let mut stack = [MaybeUninit::<(u32, f32)>::uninit(); STACK];
    let mut sp = 0;
    let mut cur = 0u32;
    loop {
        if is_leaf_ref(cur) {
            let (first, count) = leaf_range(cur);
            leaf(first, count, &mut best);
        } else {
            let node = &nodes[cur as usize];
            let (mask, dist) = boxes(node, best.t);
            if mask != 0 {
                // One or two hits, told by clearing the lowest set bit
                // (x86-64's baseline has no POPCNT: `count_ones` would be a
                // multiply-and-shift sequence).
                let rest = mask & (mask - 1);
                if rest == 0 {
                    cur = node.child(mask.trailing_zeros() as usize);
                    continue;
                }
                if rest & (rest - 1) == 0 {
                    // The order of two hits, with one comparison.
                    let (near, far) = (
                        mask.trailing_zeros() as usize,
                        31 - mask.leading_zeros() as usize,
                    );
                    let (a, b) = if dist[far] < dist[near] {
                        (far, near)
                    } else {
                        (near, far)
                    };
                    stack[sp] = MaybeUninit::new((node.child(b), dist[b]));
                    sp += 1;
                    cur = node.child(a);
                    continue;
                }
                let (order, n) = order_hits(mask, &dist);
                for &s in order[1..n].iter().rev() {
                    stack[sp] = MaybeUninit::new((node.child(s as usize), dist[s as usize]));
                    sp += 1;
                }
                cur = node.child(order[0] as usize);
                continue;
            }
        }
        loop {
            if sp == 0 {
                return (best.tri != u32::MAX).then_some(best);
            }
            sp -= 1;
            // SAFETY: every entry below the stack pointer was pushed.
            let (c, d) = unsafe { stack[sp].assume_init() };
            if d <= best.t * SLAB_PAD {
                cur = c;
                break;
            }
        }
    }
}

/// Any hit: the first triangle hit in (0, tmax) ends the search. Hit
/// children are taken in slot order, unsorted (Embree's any-hit
/// traversal: ordering costs more than it finds blockers sooner, measured
/// with `bench/embree`).
#[inline(always)]
fn occluded<N, const W: usize, F, L>(nodes: &[N], tmax: f32, boxes: F, mut leaf: L) -> bool
where
    N: WideNode,
    F: Fn(&N, f32) -> (u32, [f32; W]),
    L: FnMut(usize, usize) -> bool,
{
    let mut stack = [MaybeUninit::<u32>::uninit(); STACK];
    let mut sp = 0;
    let mut cur = 0u32;
    loop {
        if is_leaf_ref(cur) {
            let (first, count) = leaf_range(cur);
            if leaf(first, count) {
                return true;
            }
        } else {
            let node = &nodes[cur as usize];
            let (mask, _) = boxes(node, tmax);
            if mask != 0 {
                let mut m = mask & (mask - 1);
                while m != 0 {
                    stack[sp] = MaybeUninit::new(node.child(m.trailing_zeros() as usize));
                    sp += 1;
                    m &= m - 1;
                }
                cur = node.child(mask.trailing_zeros() as usize);
                continue;
            }
        }
        if sp == 0 {
            return false;
        }
        sp -= 1;
        // SAFETY: every entry below the stack pointer was pushed.
        cur = unsafe { stack[sp].assume_init() };
    }
}

/// Proof that this CPU has AVX2, made only by [`Avx2::detect`]: a tree
/// that holds one ([`super::Bvh4`]) traverses its 8-wide nodes with no
/// feature test per ray (three such tests and the calls between them were
/// about 40 instructions of every ray).
#[derive(Clone, Copy, Debug)]
pub(super) struct Avx2(());

impl Avx2 {
    /// `Some` where the CPU has AVX2.
    pub(super) fn detect() -> Option<Avx2> {
        Kernel::has_avx2().then_some(Avx2(()))
    }
}

/// Closest hit on the 8-wide tree (AVX2), skipping hits where
/// `present(tri, u, v)` is false (`|_, _, _| true` compiles away).
#[inline]
pub(super) fn intersect8(
    avx2: Avx2,
    nodes: &[Bvh8Node],
    blocks: &[LeafBlock],
    ray: &Ray,
    present: impl Fn(u32, f32, f32) -> bool,
) -> Option<Hit> {
    if nodes.is_empty() {
        return None;
    }
    let _ = avx2;
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: `avx2` says the CPU has AVX2.
        unsafe { x86::intersect_avx2(nodes, blocks, ray, present) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (blocks, ray, present);
        unreachable!("no AVX2 token is made off x86_64")
    }
}

/// Any hit on the 8-wide tree (AVX2), skipping hits where `present` is
/// false.
#[inline]
pub(super) fn any_hit8(
    avx2: Avx2,
    nodes: &[Bvh8Node],
    blocks: &[LeafBlock],
    ray: &Ray,
    present: impl Fn(u32, f32, f32) -> bool,
) -> bool {
    if nodes.is_empty() {
        return false;
    }
    let _ = avx2;
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: `avx2` says the CPU has AVX2.
        unsafe { x86::occluded_avx2(nodes, blocks, ray, present) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (blocks, ray, present);
        unreachable!("no AVX2 token is made off x86_64")
    }
}

pub(super) fn intersect(
    nodes: &[Bvh4Node],
    tris: &[Triangle],
    ray: &Ray,
    kernel: Kernel,
) -> Option<Hit> {
    if nodes.is_empty() {
        return None;
    }
    let r = PreparedRay::new(ray.o, ray.d);
    match kernel {
        #[cfg(target_arch = "x86_64")]
        Kernel::Avx if std::arch::is_x86_feature_detected!("avx") => {
            // SAFETY: the CPU has AVX (checked just above).
            unsafe { x86::intersect_avx(nodes, tris, &r, ray.tmax) }
        }
        // AVX asked for on a CPU without it: SSE2, which every x86_64 has.
        #[cfg(target_arch = "x86_64")]
        Kernel::Sse2 | Kernel::Avx => x86::intersect_sse2(nodes, tris, &r, ray.tmax),
        _ => closest(
            nodes,
            ray.tmax,
            |n, t| intersect_aabb4_scalar(&r, n, t),
            |first, count, best| leaf_closest_scalar(&r, tris, first, count, best, |_, _, _| true),
        ),
    }
}

/// Closest hit skipping triangles where `present(tri, u, v)` is false (the
/// alpha-mask hook); scalar box tests: masked scenes are the rare case.
pub(super) fn intersect_masked(
    nodes: &[Bvh4Node],
    tris: &[Triangle],
    ray: &Ray,
    present: impl Fn(u32, f32, f32) -> bool,
) -> Option<Hit> {
    if nodes.is_empty() {
        return None;
    }
    let r = PreparedRay::new(ray.o, ray.d);
    closest(
        nodes,
        ray.tmax,
        |n, t| intersect_aabb4_scalar(&r, n, t),
        |first, count, best| leaf_closest_scalar(&r, tris, first, count, best, &present),
    )
}

/// Any hit skipping triangles where `present(tri, u, v)` is false.
pub(super) fn occluded_masked(
    nodes: &[Bvh4Node],
    tris: &[Triangle],
    ray: &Ray,
    present: impl Fn(u32, f32, f32) -> bool,
) -> bool {
    if nodes.is_empty() {
        return false;
    }
    let r = PreparedRay::new(ray.o, ray.d);
    occluded(
        nodes,
        ray.tmax,
        |n, t| intersect_aabb4_scalar(&r, n, t),
        |first, count| leaf_any_scalar(&r, tris, first, count, ray.tmax, &present),
    )
}

pub(super) fn any_hit(nodes: &[Bvh4Node], tris: &[Triangle], ray: &Ray, kernel: Kernel) -> bool {
    if nodes.is_empty() {
        return false;
    }
    let r = PreparedRay::new(ray.o, ray.d);
    match kernel {
        #[cfg(target_arch = "x86_64")]
        Kernel::Avx if std::arch::is_x86_feature_detected!("avx") => {
            // SAFETY: the CPU has AVX (checked just above).
            unsafe { x86::occluded_avx(nodes, tris, &r, ray.tmax) }
        }
        #[cfg(target_arch = "x86_64")]
        Kernel::Sse2 | Kernel::Avx => x86::occluded_sse2(nodes, tris, &r, ray.tmax),
        _ => occluded(
            nodes,
            ray.tmax,
            |n, t| intersect_aabb4_scalar(&r, n, t),
            |first, count| leaf_any_scalar(&r, tris, first, count, ray.tmax, |_, _, _| true),
        ),
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) mod x86 {
    use std::arch::x86_64::*;

    use super::super::traverse::{
        PreparedRay, SLAB_PAD, axes, permutation, refine_edge, safe_inv, shear,
    };
    use super::super::wide::Bvh4Node;
    use super::super::wide8::{Bvh8Node, LeafBlock};
    use super::{Hit, Ray, Triangle, closest, occluded};
    use glam::Vec3A;

    /// The ray's constants broadcast to all four lanes, for the box test
    /// and the triangle test.
    pub(in crate::bvh) struct Ray4 {
        o: [__m128; 3],
        inv_d: [__m128; 3],
        zero_d: [bool; 3],
        /// The triangle test's axis permutation (kx, ky, kz) and shear.
        k: [usize; 3],
        shear: [__m128; 3],
    }

    #[inline(always)]
    pub(in crate::bvh) fn ray4(r: &PreparedRay) -> Ray4 {
        // SAFETY (all intrinsics here): SSE2 is part of the x86_64 baseline.
        #[allow(unused_unsafe)]
        unsafe {
            Ray4 {
                o: [_mm_set1_ps(r.o.x), _mm_set1_ps(r.o.y), _mm_set1_ps(r.o.z)],
                inv_d: [
                    _mm_set1_ps(r.inv_d.x),
                    _mm_set1_ps(r.inv_d.y),
                    _mm_set1_ps(r.inv_d.z),
                ],
                zero_d: [r.zero_d.x, r.zero_d.y, r.zero_d.z],
                k: [r.kx, r.ky, r.kz],
                shear: [
                    _mm_set1_ps(r.shear.x),
                    _mm_set1_ps(r.shear.y),
                    _mm_set1_ps(r.shear.z),
                ],
            }
        }
    }

    /// The triangle test's constants for a leaf block, broadcast to four
    /// lanes: the origin's coordinates in the ray's axis order (kx, ky,
    /// kz), the shear, and the byte offsets of the kx, ky, kz rows in a
    /// block vertex (`LeafBlock::v[k]`), so no array of the ray is indexed
    /// by an axis at run time.
    pub(in crate::bvh) struct LeafRay {
        o: [__m128; 3],
        shear: [__m128; 3],
        rows: [usize; 3],
    }

    /// A row of a block vertex is four `f32`.
    const ROW_BYTES: usize = std::mem::size_of::<[f32; 4]>();

    /// The leaf constants of a ray from what [`PreparedRay::new`] makes of
    /// it: its origin, its axis order (kx, ky, kz) and its shear (a packet
    /// keeps them in lanes).
    #[inline(always)]
    pub(in crate::bvh) fn leaf_ray_parts(o: [f32; 3], k: [usize; 3], shear: [f32; 3]) -> LeafRay {
        // SAFETY: SSE2 is part of the x86_64 baseline.
        #[allow(unused_unsafe)]
        unsafe {
            LeafRay {
                o: k.map(|a| _mm_set1_ps(o[a])),
                shear: [
                    _mm_set1_ps(shear[0]),
                    _mm_set1_ps(shear[1]),
                    _mm_set1_ps(shear[2]),
                ],
                rows: k.map(|a| a * ROW_BYTES),
            }
        }
    }

    /// [`super::intersect_aabb4_scalar`], four boxes per instruction:
    /// the same slab distances, min/max and pad, lane by lane.
    #[inline(always)]
    fn intersect_aabb4(r: &Ray4, n: &Bvh4Node, tmax: f32) -> (u32, [f32; 4]) {
        // SAFETY: SSE2 is part of the x86_64 baseline; the loads read
        // 16-byte aligned `[f32; 4]` / `[u32; 4]` fields of an align(64) node.
        #[allow(unused_unsafe)]
        unsafe {
            let lo = [
                _mm_load_ps(n.lo_x.as_ptr()),
                _mm_load_ps(n.lo_y.as_ptr()),
                _mm_load_ps(n.lo_z.as_ptr()),
            ];
            let hi = [
                _mm_load_ps(n.hi_x.as_ptr()),
                _mm_load_ps(n.hi_y.as_ptr()),
                _mm_load_ps(n.hi_z.as_ptr()),
            ];
            let mut tlo = [_mm_setzero_ps(); 3];
            let mut thi = [_mm_setzero_ps(); 3];
            for a in 0..3 {
                let t1 = _mm_mul_ps(_mm_sub_ps(lo[a], r.o[a]), r.inv_d[a]);
                let t2 = _mm_mul_ps(_mm_sub_ps(hi[a], r.o[a]), r.inv_d[a]);
                tlo[a] = _mm_min_ps(t1, t2);
                thi[a] = _mm_max_ps(t1, t2);
            }
            // Axes where d is exactly zero: the slab holds the whole line
            // when the origin is inside it (faces included), none of it
            // otherwise; see `intersect_aabb`.
            let mut outside = _mm_setzero_ps();
            if r.zero_d[0] | r.zero_d[1] | r.zero_d[2] {
                for a in 0..3 {
                    if r.zero_d[a] {
                        let inside =
                            _mm_and_ps(_mm_cmpge_ps(r.o[a], lo[a]), _mm_cmple_ps(r.o[a], hi[a]));
                        outside = _mm_or_ps(
                            outside,
                            _mm_andnot_ps(inside, _mm_castsi128_ps(_mm_set1_epi32(-1))),
                        );
                        tlo[a] = _mm_set1_ps(f32::NEG_INFINITY);
                        thi[a] = _mm_set1_ps(f32::INFINITY);
                    }
                }
            }
            let tnear = _mm_max_ps(
                _mm_max_ps(_mm_max_ps(tlo[0], tlo[1]), tlo[2]),
                _mm_setzero_ps(),
            );
            let tfar = _mm_mul_ps(
                _mm_min_ps(
                    _mm_min_ps(_mm_min_ps(thi[0], thi[1]), thi[2]),
                    _mm_set1_ps(tmax),
                ),
                _mm_set1_ps(SLAB_PAD),
            );
            // An entry at +inf is a miss, as `intersect_aabb`'s caller reads it.
            let hit = _mm_and_ps(
                _mm_cmple_ps(tnear, tfar),
                _mm_cmplt_ps(tnear, _mm_set1_ps(f32::INFINITY)),
            );
            let empty = _mm_castsi128_ps(_mm_cmpeq_epi32(
                _mm_load_si128(n.child.as_ptr().cast()),
                _mm_set1_epi32(-1),
            ));
            let hit = _mm_andnot_ps(_mm_or_ps(empty, outside), hit);
            let mut dist = [0f32; 4];
            _mm_storeu_ps(
                dist.as_mut_ptr(),
                _mm_or_ps(
                    _mm_and_ps(hit, tnear),
                    _mm_andnot_ps(hit, _mm_set1_ps(f32::INFINITY)),
                ),
            );
            (_mm_movemask_ps(hit) as u32, dist)
        }
    }

    /// Up to four watertight triangle tests at once: lane j computes, with
    /// the same IEEE operations in the same order (no FMA), exactly what
    /// [`intersect_triangle`](super::intersect_triangle) computes for
    /// `tris[j]` against `tmax`, so the hits are the scalar test's bit for
    /// bit. Returns the mask of hit lanes and per lane (t, u, v).
    #[inline(always)]
    fn triangles4(r: &Ray4, tris: &[Triangle], tmax: f32) -> (u32, [[f32; 4]; 3]) {
        debug_assert!((1..=4).contains(&tris.len()));
        let last = tris.len() - 1;
        // SAFETY: SSE2 is part of the x86_64 baseline. Each unaligned load
        // reads 16 bytes inside one 48-byte `Triangle` (#[repr(C)]: p0 at
        // 0, p1 at 16, p2 at 32, each followed by a u32 the tests ignore);
        // lanes past the leaf's end repeat its last triangle and are masked.
        #[allow(unused_unsafe)]
        unsafe {
            let p: [*const f32; 4] =
                std::array::from_fn(|j| (&tris[j.min(last)] as *const Triangle).cast::<f32>());
            // One vertex of the four triangles, as x, y, z rows minus the
            // ray origin.
            let vertex = |off: usize| -> [__m128; 3] {
                let r0 = _mm_loadu_ps(p[0].add(off));
                let r1 = _mm_loadu_ps(p[1].add(off));
                let r2 = _mm_loadu_ps(p[2].add(off));
                let r3 = _mm_loadu_ps(p[3].add(off));
                let t0 = _mm_unpacklo_ps(r0, r1);
                let t1 = _mm_unpacklo_ps(r2, r3);
                let t2 = _mm_unpackhi_ps(r0, r1);
                let t3 = _mm_unpackhi_ps(r2, r3);
                [
                    _mm_sub_ps(_mm_movelh_ps(t0, t1), r.o[0]),
                    _mm_sub_ps(_mm_movehl_ps(t1, t0), r.o[1]),
                    _mm_sub_ps(_mm_movelh_ps(t2, t3), r.o[2]),
                ]
            };
            let (a, b, c) = (vertex(0), vertex(4), vertex(8));
            let [kx, ky, kz] = r.k;
            let permuted = |v: [__m128; 3]| [v[kx], v[ky], v[kz]];
            triangles4_sheared(
                &r.shear,
                permuted(a),
                permuted(b),
                permuted(c),
                tris.len(),
                tmax,
            )
        }
    }

    /// Up to four triangles of one leaf block (`wide8::LeafBlock`, their
    /// coordinates already side by side): [`triangles4`] without the
    /// transposes, each coordinate loaded in the ray's axis order. The same
    /// operations on the same values, so the same hits bit for bit.
    #[inline(always)]
    fn triangles4_block(r: &LeafRay, block: &LeafBlock, tmax: f32) -> (u32, [[f32; 4]; 3]) {
        // SAFETY: SSE2 is part of the x86_64 baseline; the loads read
        // 16-byte aligned `[f32; 4]` rows of an align(16) block, at the
        // offsets of rows 0..3 (`leaf_ray_parts`).
        #[allow(unused_unsafe)]
        unsafe {
            let vertex = |k: usize| -> [__m128; 3] {
                let base = block.v[k].as_ptr().cast::<u8>();
                let row =
                    |i: usize| _mm_sub_ps(_mm_load_ps(base.add(r.rows[i]).cast::<f32>()), r.o[i]);
                [row(0), row(1), row(2)]
            };
            triangles4_sheared(
                &r.shear,
                vertex(0),
                vertex(1),
                vertex(2),
                block.count as usize,
                tmax,
            )
        }
    }

    /// The float vectors the watertight triangle test runs on: four
    /// triangles against one ray (`__m128`), or one triangle against eight
    /// rays (`__m256`, the camera packet's leaves). Each operation is the
    /// same IEEE operation in every lane, so both give a ray and a
    /// triangle the same bits.
    ///
    /// # Safety
    /// The methods use the vector's instructions: SSE2 (the x86_64
    /// baseline) for `__m128`, AVX for `__m256`, which only code the AVX2
    /// entry points reach may call.
    pub(in crate::bvh) trait TriVec: Copy {
        /// The lanes, stored.
        type Array: Copy + Default + AsRef<[f32]> + AsMut<[f32]>;
        unsafe fn splat(x: f32) -> Self;
        unsafe fn add(self, o: Self) -> Self;
        unsafe fn sub(self, o: Self) -> Self;
        unsafe fn mul(self, o: Self) -> Self;
        unsafe fn div(self, o: Self) -> Self;
        unsafe fn max(self, o: Self) -> Self;
        unsafe fn or(self, o: Self) -> Self;
        unsafe fn and(self, o: Self) -> Self;
        /// `!self & o`.
        unsafe fn andnot(self, o: Self) -> Self;
        unsafe fn eq(self, o: Self) -> Self;
        unsafe fn lt(self, o: Self) -> Self;
        unsafe fn gt(self, o: Self) -> Self;
        /// Lane k's sign as bit k.
        unsafe fn mask(self) -> u32;
        unsafe fn store(self) -> Self::Array;
        unsafe fn load(a: &Self::Array) -> Self;
        #[inline(always)]
        unsafe fn abs(self) -> Self {
            unsafe { Self::splat(-0.0).andnot(self) }
        }
    }

    /// [`TriVec`] for vector type `$v` of `$n` lanes, from its intrinsics
    /// (`$cmp` takes the predicate as `_mm256_cmp_ps` does).
    macro_rules! tri_vec {
        ($v:ty, $n:literal, $set1:ident, $add:ident, $sub:ident, $mul:ident, $div:ident,
         $max:ident, $or:ident, $and:ident, $andnot:ident, $cmp:ident, $movemask:ident,
         $storeu:ident, $loadu:ident) => {
            impl TriVec for $v {
                type Array = [f32; $n];
                #[inline(always)]
                unsafe fn splat(x: f32) -> Self {
                    unsafe { $set1(x) }
                }
                #[inline(always)]
                unsafe fn add(self, o: Self) -> Self {
                    unsafe { $add(self, o) }
                }
                #[inline(always)]
                unsafe fn sub(self, o: Self) -> Self {
                    unsafe { $sub(self, o) }
                }
                #[inline(always)]
                unsafe fn mul(self, o: Self) -> Self {
                    unsafe { $mul(self, o) }
                }
                #[inline(always)]
                unsafe fn div(self, o: Self) -> Self {
                    unsafe { $div(self, o) }
                }
                #[inline(always)]
                unsafe fn max(self, o: Self) -> Self {
                    unsafe { $max(self, o) }
                }
                #[inline(always)]
                unsafe fn or(self, o: Self) -> Self {
                    unsafe { $or(self, o) }
                }
                #[inline(always)]
                unsafe fn and(self, o: Self) -> Self {
                    unsafe { $and(self, o) }
                }
                #[inline(always)]
                unsafe fn andnot(self, o: Self) -> Self {
                    unsafe { $andnot(self, o) }
                }
                #[inline(always)]
                unsafe fn eq(self, o: Self) -> Self {
                    unsafe { $cmp::<_CMP_EQ_OQ>(self, o) }
                }
                #[inline(always)]
                unsafe fn lt(self, o: Self) -> Self {
                    unsafe { $cmp::<_CMP_LT_OQ>(self, o) }
                }
                #[inline(always)]
                unsafe fn gt(self, o: Self) -> Self {
                    unsafe { $cmp::<_CMP_GT_OQ>(self, o) }
                }
                #[inline(always)]
                unsafe fn mask(self) -> u32 {
                    unsafe { $movemask(self) as u32 }
                }
                #[inline(always)]
                unsafe fn store(self) -> Self::Array {
                    let mut a = [0f32; $n];
                    unsafe { $storeu(a.as_mut_ptr(), self) };
                    a
                }
                #[inline(always)]
                unsafe fn load(a: &Self::Array) -> Self {
                    unsafe { $loadu(a.as_ptr()) }
                }
            }
        };
    }

    /// SSE's compares by predicate, as AVX's `_mm256_cmp_ps` takes them
    /// (the ordered, quiet forms: what `cmpeq`, `cmplt`, `cmpgt` are).
    #[inline(always)]
    unsafe fn cmp128<const P: i32>(a: __m128, b: __m128) -> __m128 {
        unsafe {
            match P {
                _CMP_EQ_OQ => _mm_cmpeq_ps(a, b),
                _CMP_LT_OQ => _mm_cmplt_ps(a, b),
                _ => _mm_cmpgt_ps(a, b),
            }
        }
    }

    tri_vec!(
        __m128,
        4,
        _mm_set1_ps,
        _mm_add_ps,
        _mm_sub_ps,
        _mm_mul_ps,
        _mm_div_ps,
        _mm_max_ps,
        _mm_or_ps,
        _mm_and_ps,
        _mm_andnot_ps,
        cmp128,
        _mm_movemask_ps,
        _mm_storeu_ps,
        _mm_loadu_ps
    );
    tri_vec!(
        __m256,
        8,
        _mm256_set1_ps,
        _mm256_add_ps,
        _mm256_sub_ps,
        _mm256_mul_ps,
        _mm256_div_ps,
        _mm256_max_ps,
        _mm256_or_ps,
        _mm256_and_ps,
        _mm256_andnot_ps,
        _mm256_cmp_ps,
        _mm256_movemask_ps,
        _mm256_storeu_ps,
        _mm256_loadu_ps
    );

    /// The watertight test of the lanes' (ray, triangle) pairs, whose
    /// vertices are given minus the ray origin, in the ray's axis order
    /// (kx, ky, kz), `shear` the rays' shear: hits with 0 < t < `tmax`
    /// above their own error bound, among the lanes of `lanes`, with their
    /// (t, u, v) (stored where some lane hits).
    ///
    /// # Safety
    /// See [`TriVec`].
    #[inline(always)]
    pub(in crate::bvh) unsafe fn triangles_sheared<V: TriVec>(
        shear: &[V; 3],
        a: [V; 3],
        b: [V; 3],
        c: [V; 3],
        lanes: u32,
        tmax: V,
    ) -> (u32, [V::Array; 3]) {
        unsafe {
            let [sx, sy, sz] = *shear;
            let ax = a[0].sub(sx.mul(a[2]));
            let ay = a[1].sub(sy.mul(a[2]));
            let bx = b[0].sub(sx.mul(b[2]));
            let by = b[1].sub(sy.mul(b[2]));
            let cx = c[0].sub(sx.mul(c[2]));
            let cy = c[1].sub(sy.mul(c[2]));
            let mut u = cx.mul(by).sub(cy.mul(bx));
            let mut v = ax.mul(cy).sub(ay.mul(cx));
            let mut w = bx.mul(ay).sub(by.mul(ax));
            let zero = V::splat(0.0);
            if u.eq(zero).or(v.eq(zero)).or(w.eq(zero)).mask() != 0 {
                // Rare: the scalar test's refinement of edge functions that
                // round to exactly 0, lane by lane.
                // (Written out, not `array::map`: its closures stay out of
                // line, and the AVX intrinsics in them become calls.)
                let (ax, ay, bx, by, cx, cy) = (
                    ax.store(),
                    ay.store(),
                    bx.store(),
                    by.store(),
                    cx.store(),
                    cy.store(),
                );
                let (mut eu, mut ev, mut ew) = (u.store(), v.store(), w.store());
                let (ax, ay, bx, by, cx, cy) = (
                    ax.as_ref(),
                    ay.as_ref(),
                    bx.as_ref(),
                    by.as_ref(),
                    cx.as_ref(),
                    cy.as_ref(),
                );
                for j in 0..ax.len() {
                    eu.as_mut()[j] = refine_edge(eu.as_ref()[j], cx[j], by[j], cy[j], bx[j]);
                    ev.as_mut()[j] = refine_edge(ev.as_ref()[j], ax[j], cy[j], ay[j], cx[j]);
                    ew.as_mut()[j] = refine_edge(ew.as_ref()[j], bx[j], ay[j], by[j], ax[j]);
                }
                u = V::load(&eu);
                v = V::load(&ev);
                w = V::load(&ew);
            }
            let any_neg = u.lt(zero).or(v.lt(zero)).or(w.lt(zero));
            let any_pos = u.gt(zero).or(v.gt(zero)).or(w.gt(zero));
            let det = u.add(v).add(w);
            let az = sz.mul(a[2]);
            let bz = sz.mul(b[2]);
            let cz = sz.mul(c[2]);
            let t = u.mul(az).add(v.mul(bz)).add(w.mul(cz)).div(det);
            // Kept: not both signs, det != 0, 0 < t < tmax (false for NaN).
            let ok = any_neg
                .and(any_pos)
                .or(det.eq(zero))
                .andnot(t.gt(zero).and(t.lt(tmax)));
            let mut mask = ok.mask() & lanes;
            if mask != 0 {
                // Only where some lane hits: t above its own error bound.
                let bound = t_error_lanes([ax, bx, cx], [ay, by, cy], [az, bz, cz], [u, v, w], det);
                mask &= t.gt(bound).mask();
            }
            let mut out = [V::Array::default(); 3];
            if mask != 0 {
                out = [t.store(), v.div(det).store(), w.div(det).store()];
            }
            (mask, out)
        }
    }

    /// [`t_error`](super::super::traverse::t_error) lane by lane, the same
    /// operations in the same order (max of absolute values, no FMA).
    ///
    /// # Safety
    /// See [`TriVec`].
    #[inline(always)]
    unsafe fn t_error_lanes<V: TriVec>(x: [V; 3], y: [V; 3], z: [V; 3], e: [V; 3], det: V) -> V {
        use crate::abi::{TRI_GAMMA2, TRI_GAMMA3, TRI_GAMMA5};
        unsafe {
            let max3 = |v: [V; 3]| v[0].abs().max(v[1].abs()).max(v[2].abs());
            let (max_x, max_y, max_z, max_e) = (max3(x), max3(y), max3(z), max3(e));
            let g = |k: f32| V::splat(k);
            let delta_x = g(TRI_GAMMA5).mul(max_x.add(max_z));
            let delta_y = g(TRI_GAMMA5).mul(max_y.add(max_z));
            let delta_e = g(2.0).mul(
                g(TRI_GAMMA2)
                    .mul(max_x)
                    .mul(max_y)
                    .add(delta_y.mul(max_x))
                    .add(delta_x.mul(max_y)),
            );
            let sum = g(TRI_GAMMA3)
                .mul(max_e)
                .mul(max_z)
                .add(delta_e.mul(max_z))
                .add(delta_x.mul(max_e));
            g(3.0).mul(sum).div(det.abs())
        }
    }

    /// Up to four triangles' test for one ray, `count` of them real.
    #[inline(always)]
    fn triangles4_sheared(
        shear: &[__m128; 3],
        a: [__m128; 3],
        b: [__m128; 3],
        c: [__m128; 3],
        count: usize,
        tmax: f32,
    ) -> (u32, [[f32; 4]; 3]) {
        // SAFETY: SSE2 is part of the x86_64 baseline.
        unsafe { triangles_sheared(shear, a, b, c, (1u32 << count) - 1, __m128::splat(tmax)) }
    }

    /// `leaf_closest_scalar` four triangles per test: the lanes a group
    /// hits are then taken in order, each only if nearer than the best so
    /// far, which is what the one-by-one loop accepts.
    #[inline(always)]
    pub(super) fn leaf_closest(
        r: &Ray4,
        tris: &[Triangle],
        first: usize,
        count: usize,
        best: &mut Hit,
    ) {
        for (g, group) in tris[first..first + count].chunks(4).enumerate() {
            let (mut mask, [t, u, v]) = triangles4(r, group, best.t);
            while mask != 0 {
                let j = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if t[j] < best.t {
                    *best = Hit {
                        t: t[j],
                        tri: (first + 4 * g + j) as u32,
                        u: u[j],
                        v: v[j],
                    };
                }
            }
        }
    }

    /// [`leaf_closest`] on a leaf block of the 8-wide tree, skipping hits
    /// where `present(tri, u, v)` is false (the alpha-mask hook; `|_, _, _|
    /// true` compiles away). Lanes are taken in order, each only if nearer
    /// than the best so far and present: what the one-by-one scalar loop
    /// with the hook accepts.
    #[inline(always)]
    pub(in crate::bvh) fn block_closest(
        r: &LeafRay,
        block: &LeafBlock,
        best: &mut Hit,
        present: &impl Fn(u32, f32, f32) -> bool,
    ) {
        let (mut mask, [t, u, v]) = triangles4_block(r, block, best.t);
        while mask != 0 {
            let j = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            if t[j] < best.t && present(block.tri[j], u[j], v[j]) {
                *best = Hit {
                    t: t[j],
                    tri: block.tri[j],
                    u: u[j],
                    v: v[j],
                };
            }
        }
    }

    #[inline(always)]
    pub(super) fn leaf_any(
        r: &Ray4,
        tris: &[Triangle],
        first: usize,
        count: usize,
        tmax: f32,
    ) -> bool {
        tris[first..first + count]
            .chunks(4)
            .any(|group| triangles4(r, group, tmax).0 != 0)
    }

    #[inline(always)]
    fn intersect_impl(
        nodes: &[Bvh4Node],
        tris: &[Triangle],
        r: &PreparedRay,
        tmax: f32,
    ) -> Option<Hit> {
        let r4 = ray4(r);
        closest(
            nodes,
            tmax,
            |n, t| intersect_aabb4(&r4, n, t),
            |first, count, best| leaf_closest(&r4, tris, first, count, best),
        )
    }

    #[inline(always)]
    fn occluded_impl(nodes: &[Bvh4Node], tris: &[Triangle], r: &PreparedRay, tmax: f32) -> bool {
        let r4 = ray4(r);
        occluded(
            nodes,
            tmax,
            |n, t| intersect_aabb4(&r4, n, t),
            |first, count| leaf_any(&r4, tris, first, count, tmax),
        )
    }

    pub(super) fn intersect_sse2(
        nodes: &[Bvh4Node],
        tris: &[Triangle],
        r: &PreparedRay,
        tmax: f32,
    ) -> Option<Hit> {
        intersect_impl(nodes, tris, r, tmax)
    }

    pub(super) fn occluded_sse2(
        nodes: &[Bvh4Node],
        tris: &[Triangle],
        r: &PreparedRay,
        tmax: f32,
    ) -> bool {
        occluded_impl(nodes, tris, r, tmax)
    }

    /// # Safety
    /// The CPU must support AVX.
    #[target_feature(enable = "avx")]
    pub(super) unsafe fn intersect_avx(
        nodes: &[Bvh4Node],
        tris: &[Triangle],
        r: &PreparedRay,
        tmax: f32,
    ) -> Option<Hit> {
        intersect_impl(nodes, tris, r, tmax)
    }

    /// Per axis, the byte offsets in a [`Bvh8Node`] of its lo and hi
    /// coordinate arrays.
    pub(in crate::bvh) const PLANES8: [(usize, usize); 3] = [
        (
            std::mem::offset_of!(Bvh8Node, lo_x),
            std::mem::offset_of!(Bvh8Node, hi_x),
        ),
        (
            std::mem::offset_of!(Bvh8Node, lo_y),
            std::mem::offset_of!(Bvh8Node, hi_y),
        ),
        (
            std::mem::offset_of!(Bvh8Node, lo_z),
            std::mem::offset_of!(Bvh8Node, hi_z),
        ),
    ];

    /// The end of a slab test of eight boxes (or of one box against eight
    /// rays) from each axis's entry (`tlo`) and exit (`thi`) distances:
    /// the entry max(tlo..., 0), the exit min(thi..., limit) x
    /// [`SLAB_PAD`], and the lanes hit (entry <= exit, entry finite), as
    /// [`intersect_aabb`] ends for one box.
    #[inline(always)]
    pub(in crate::bvh) fn slab_end8(
        tlo: [__m256; 3],
        thi: [__m256; 3],
        limit: __m256,
    ) -> (__m256, __m256) {
        // SAFETY: called only from AVX2 code.
        #[allow(unused_unsafe)]
        unsafe {
            let tnear = _mm256_max_ps(
                _mm256_max_ps(_mm256_max_ps(tlo[0], tlo[1]), tlo[2]),
                _mm256_setzero_ps(),
            );
            let tfar = _mm256_mul_ps(
                _mm256_min_ps(_mm256_min_ps(_mm256_min_ps(thi[0], thi[1]), thi[2]), limit),
                _mm256_set1_ps(SLAB_PAD),
            );
            let hit = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_LE_OQ>(tnear, tfar),
                _mm256_cmp_ps::<_CMP_LT_OQ>(tnear, _mm256_set1_ps(f32::INFINITY)),
            );
            (tnear, hit)
        }
    }

    /// The hit lanes as a mask, and the entry distances with +inf where
    /// missed.
    #[inline(always)]
    pub(in crate::bvh) fn hits8(tnear: __m256, hit: __m256) -> (u32, [f32; 8]) {
        // SAFETY: called only from AVX2 code.
        #[allow(unused_unsafe)]
        unsafe {
            let mut dist = [0f32; 8];
            _mm256_storeu_ps(
                dist.as_mut_ptr(),
                _mm256_blendv_ps(_mm256_set1_ps(f32::INFINITY), tnear, hit),
            );
            (_mm256_movemask_ps(hit) as u32, dist)
        }
    }

    /// The ray's box-test constants broadcast to eight lanes, and per axis
    /// which of a node's planes the ray meets first: the byte offsets in a
    /// [`Bvh8Node`] of the near (`lo_*` where the direction is positive,
    /// else `hi_*`) and far coordinate arrays (Embree's near/far plane
    /// selection: each axis then takes one slab distance for the entry and
    /// one for the exit, with no min/max).
    struct Ray8 {
        o: [__m256; 3],
        inv_d: [__m256; 3],
        /// Bit a: d's component a is exactly zero (either sign).
        zero_d: u32,
        near: [usize; 3],
        far: [usize; 3],
    }

    /// The box test's constants: the inverse direction by one division of
    /// four lanes, the near and far planes from its signs. With [`leaf8`],
    /// what [`PreparedRay::new`] then `Ray8`'s and [`leaf_ray_parts`]' broadcasts
    /// give, bit for bit, made in registers straight from the ray (a
    /// prepared ray built first and then read into both sets of constants
    /// took 175 instructions before the first node, most of them stores and
    /// reloads).
    #[inline(always)]
    fn ray8(ray: &Ray) -> Ray8 {
        let dv = Vec3A::from(ray.d);
        let arrays = PLANES8;
        // SAFETY: called only from the AVX2 entry points below.
        #[allow(unused_unsafe)]
        unsafe {
            let inv: __m128 = safe_inv(dv).into();
            let zero = _mm_setzero_ps();
            let zero_d = _mm_movemask_ps(_mm_cmpeq_ps(dv.into(), zero)) as u32 & 7;
            let positive = _mm_movemask_ps(_mm_cmpge_ps(inv, zero)) as u32;
            let near = std::array::from_fn(|a| {
                if positive & (1 << a) != 0 {
                    arrays[a].0
                } else {
                    arrays[a].1
                }
            });
            let far = std::array::from_fn(|a| {
                if positive & (1 << a) != 0 {
                    arrays[a].1
                } else {
                    arrays[a].0
                }
            });
            Ray8 {
                o: ray.o.to_array().map(|x| _mm256_set1_ps(x)),
                inv_d: [0, 1, 2].map(|i| _mm256_broadcastss_ps(lane(inv, i))),
                zero_d,
                near,
                far,
            }
        }
    }

    /// The triangle test's constants: the axis order, the permuted origin
    /// read from the ray's own fields, the shear by one division. The
    /// queries make them at their first leaf, which rays that escape the
    /// scene and most shadow rays never reach.
    #[inline(always)]
    fn leaf8(ray: &Ray) -> LeafRay {
        // Built here, not through `leaf_ray_parts`: that route (the shear
        // through an array, not broadcast from its register) left the
        // traversal's instructions as they were but shifted LLVM's
        // inlining in the render loop, 1.5-3% slower with the shipped
        // profile-guided build (docs/benchmarks.md, tenth session).
        let (o, d) = (ray.o.to_array(), ray.d.to_array());
        let k = axes(permutation(d));
        let shear: __m128 = shear(d, k).into();
        // SAFETY: SSE is part of the x86_64 baseline.
        #[allow(unused_unsafe)]
        unsafe {
            LeafRay {
                o: k.map(|a| _mm_set1_ps(o[a])),
                shear: [0, 1, 2].map(|i| lane(shear, i)),
                rows: k.map(|a| a * ROW_BYTES),
            }
        }
    }

    /// Lane `i` (0..3) of `v` in every lane.
    #[inline(always)]
    fn lane(v: __m128, i: usize) -> __m128 {
        // SAFETY: SSE is part of the x86_64 baseline.
        #[allow(unused_unsafe)]
        unsafe {
            match i {
                0 => _mm_shuffle_ps::<0x00>(v, v),
                1 => _mm_shuffle_ps::<0x55>(v, v),
                _ => _mm_shuffle_ps::<0xaa>(v, v),
            }
        }
    }

    /// [`intersect_aabb4`] for the eight boxes of an 8-wide node, lane by
    /// lane the same entry and exit distances: along an axis with a
    /// positive (negative) inverse direction, (lo - o) inv is the smaller
    /// (larger) of the two slab distances for every box with lo <= hi,
    /// rounding being monotone, so taking the near plane's is taking the
    /// min. An empty slot (lo = +inf, hi = -inf) then enters at +inf on
    /// every axis, a miss without a test of its reference.
    #[inline(always)]
    fn intersect_aabb8(r: &Ray8, n: &Bvh8Node, tmax: f32) -> (u32, [f32; 8]) {
        // SAFETY: called only from the AVX2 entry points below; the loads
        // read 32-byte aligned `[f32; 8]` fields of an align(64) node at
        // offsets `ray8` took from its layout.
        #[allow(unused_unsafe)]
        unsafe {
            let base = (n as *const Bvh8Node).cast::<u8>();
            let plane = |off: usize| _mm256_load_ps(base.add(off).cast::<f32>());
            let mut tlo = [_mm256_setzero_ps(); 3];
            let mut thi = [_mm256_setzero_ps(); 3];
            for a in 0..3 {
                tlo[a] = _mm256_mul_ps(_mm256_sub_ps(plane(r.near[a]), r.o[a]), r.inv_d[a]);
                thi[a] = _mm256_mul_ps(_mm256_sub_ps(plane(r.far[a]), r.o[a]), r.inv_d[a]);
            }
            // Axes where d is exactly zero: the slab holds the whole line
            // when the origin is inside it (faces included), none of it
            // otherwise; see `intersect_aabb`.
            let mut outside = _mm256_setzero_ps();
            if r.zero_d != 0 {
                for a in 0..3 {
                    if r.zero_d & (1 << a) != 0 {
                        // Each axis's lo array precedes its hi array.
                        let (lo, hi) = (
                            plane(r.near[a].min(r.far[a])),
                            plane(r.near[a].max(r.far[a])),
                        );
                        let inside = _mm256_and_ps(
                            _mm256_cmp_ps::<_CMP_GE_OQ>(r.o[a], lo),
                            _mm256_cmp_ps::<_CMP_LE_OQ>(r.o[a], hi),
                        );
                        outside = _mm256_or_ps(
                            outside,
                            _mm256_andnot_ps(inside, _mm256_castsi256_ps(_mm256_set1_epi32(-1))),
                        );
                        tlo[a] = _mm256_set1_ps(f32::NEG_INFINITY);
                        thi[a] = _mm256_set1_ps(f32::INFINITY);
                    }
                }
                // An empty slot's planes are +inf and -inf, so the test
                // above already calls it outside.
            }
            let (tnear, hit) = slab_end8(tlo, thi, _mm256_set1_ps(tmax));
            hits8(tnear, _mm256_andnot_ps(outside, hit))
        }
    }

    /// # Safety
    /// The CPU must support AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn intersect_avx2(
        nodes: &[Bvh8Node],
        blocks: &[LeafBlock],
        ray: &Ray,
        present: impl Fn(u32, f32, f32) -> bool,
    ) -> Option<Hit> {
        // Prepared here, not by the caller: its fields then stay in
        // registers (a prepared ray passed by reference was read back in
        // pieces other than those written, a store-forwarding stall). The
        // leaf test's constants wait for the first leaf.
        let (r8, tmax) = (ray8(ray), ray.tmax);
        let mut leaf = None;
        closest(
            nodes,
            tmax,
            |n, t| intersect_aabb8(&r8, n, t),
            |block, _, best| {
                let leaf = leaf.get_or_insert_with(|| leaf8(ray));
                block_closest(leaf, &blocks[block], best, &present)
            },
        )
    }

    /// # Safety
    /// The CPU must support AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn occluded_avx2(
        nodes: &[Bvh8Node],
        blocks: &[LeafBlock],
        ray: &Ray,
        present: impl Fn(u32, f32, f32) -> bool,
    ) -> bool {
        // Prepared here: see `intersect_avx2`.
        let (r8, tmax) = (ray8(ray), ray.tmax);
        let mut leaf = None;
        occluded(
            nodes,
            tmax,
            |n, t| intersect_aabb8(&r8, n, t),
            |block, _| {
                let b = &blocks[block];
                let leaf = leaf.get_or_insert_with(|| leaf8(ray));
                let (mut mask, [_, u, v]) = triangles4_block(leaf, b, tmax);
                while mask != 0 {
                    let j = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if present(b.tri[j], u[j], v[j]) {
                        return true;
                    }
                }
                false
            },
        )
    }

    /// # Safety
    /// The CPU must support AVX.
    #[target_feature(enable = "avx")]
    pub(super) unsafe fn occluded_avx(
        nodes: &[Bvh4Node],
        tris: &[Triangle],
        r: &PreparedRay,
        tmax: f32,
    ) -> bool {
        occluded_impl(nodes, tris, r, tmax)
    }

    #[cfg(test)]
    mod tests {
        use super::*;
        use glam::Vec3;

        /// `ray8` and `leaf8` give what `PreparedRay::new` then the
        /// broadcasts give, bit for bit, on rays of every axis order and sign, with
        /// zero (either sign), tiny, huge and NaN components.
        #[test]
        fn ray8_and_leaf8_are_the_prepared_ray() {
            if !std::arch::is_x86_feature_detected!("avx2") {
                return;
            }
            let values = [
                0.7f32,
                -0.7,
                0.0,
                -0.0,
                0.3,
                -0.3,
                1e-31,
                -1e-31,
                2.0,
                -5.0,
                1e30,
                f32::NAN,
            ];
            let bits4 = |v: __m128| {
                let mut a = [0f32; 4];
                // SAFETY: SSE2 is part of the x86_64 baseline.
                unsafe { _mm_storeu_ps(a.as_mut_ptr(), v) };
                a.map(f32::to_bits)
            };
            let bits8 = |v: __m256| {
                let mut a = [0f32; 8];
                // SAFETY: AVX2 was detected above.
                unsafe { _mm256_storeu_ps(a.as_mut_ptr(), v) };
                a.map(f32::to_bits)
            };
            let mut checked = 0;
            for &x in &values {
                for &y in &values {
                    for &z in &values {
                        let d = Vec3::new(x, y, z);
                        let o = Vec3::new(0.25 - z, 1.5 + x, -3.0 * y);
                        let ray = Ray { o, d, tmax: 1.0 };
                        let p = PreparedRay::new(o, d);
                        let (r8, leaf) = (ray8(&ray), leaf8(&ray));
                        let k = [p.kx, p.ky, p.kz];
                        let (inv, ov, shear) =
                            (p.inv_d.to_array(), o.to_array(), p.shear.to_array());
                        for a in 0..3 {
                            assert_eq!(bits8(r8.o[a]), [ov[a].to_bits(); 8], "{d}");
                            assert_eq!(bits8(r8.inv_d[a]), [inv[a].to_bits(); 8], "{d}");
                            let (lo, hi) = PLANES8[a];
                            let (near, far) = if inv[a] >= 0.0 { (lo, hi) } else { (hi, lo) };
                            assert_eq!((r8.near[a], r8.far[a]), (near, far), "{d}");
                            assert_eq!(bits4(leaf.o[a]), [ov[k[a]].to_bits(); 4], "{d}");
                            assert_eq!(bits4(leaf.shear[a]), [shear[a].to_bits(); 4], "{d}");
                            assert_eq!(leaf.rows[a], k[a] * ROW_BYTES, "{d}");
                        }
                        let zero = p.zero_d;
                        let zero_bits =
                            u32::from(zero.x) | u32::from(zero.y) << 1 | u32::from(zero.z) << 2;
                        assert_eq!(r8.zero_d, zero_bits, "{d}");
                        checked += 1;
                    }
                }
            }
            assert_eq!(checked, values.len().pow(3));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The SIMD leaf tests against the one-by-one scalar loop, on leaves of
    /// 1..16 triangles: random ones, ones sharing the ray's vertices and
    /// edges (ties and the watertight edge rule), degenerate and non-finite
    /// ones, every ray direction kind (zero components included). Same hit,
    /// bit for bit, and the same any-hit answer.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn simd_leaf_test_is_the_scalar_one() {
        use glam::Vec3;
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        let tri = |a: Vec3, b: Vec3, c: Vec3, i: u32| Triangle {
            p0: a.into(),
            material: i,
            p1: b.into(),
            light: u32::MAX,
            p2: c.into(),
            flags: 0,
        };
        let mut checked = 0;
        for case in 0..4000 {
            let o = Vec3::new(rnd(), rnd(), rnd()) * 2.0;
            let mut d = Vec3::new(rnd(), rnd(), rnd());
            if case % 5 == 0 {
                d.x = 0.0;
            }
            if case % 7 == 0 {
                d.y = -0.0;
            }
            if d == Vec3::ZERO {
                d = Vec3::Z;
            }
            let n = 1 + case % 16;
            let mut tris: Vec<Triangle> = (0..n)
                .map(|i| {
                    let c = o + d * (1.0 + 3.0 * rnd().abs());
                    let e = 0.5 + rnd().abs();
                    let v = |r: f32, s: f32, t: f32| c + Vec3::new(r, s, t) * e;
                    tri(
                        v(rnd(), rnd(), rnd()),
                        v(rnd(), rnd(), rnd()),
                        v(rnd(), rnd(), rnd()),
                        i as u32,
                    )
                })
                .collect();
            match case % 6 {
                // Two triangles sharing an edge the ray passes through.
                1 if n >= 2 => {
                    let p = o + d * 2.0;
                    let q = Vec3::new(rnd(), rnd(), rnd());
                    tris[0] = tri(p - q, p + q, p + Vec3::new(q.y, -q.x, q.z), 0);
                    tris[1] = tri(p + q, p - q, p - Vec3::new(q.y, -q.x, q.z), 1);
                }
                // The same triangle twice: a tie goes to the first.
                2 if n >= 2 => tris[n - 1] = tris[0],
                // Degenerate and non-finite triangles.
                3 => {
                    tris[0].p1 = tris[0].p0;
                    if n >= 2 {
                        tris[1].p2 = [f32::NAN, 0.0, f32::INFINITY];
                    }
                }
                _ => {}
            }
            let r = PreparedRay::new(o, d);
            let rt = x86::ray4(&r);
            for tmax in [f32::INFINITY, 3.0, 1.5] {
                let empty = Hit {
                    t: tmax,
                    tri: u32::MAX,
                    u: 0.0,
                    v: 0.0,
                };
                let (mut want, mut got) = (empty, empty);
                leaf_closest_scalar(&r, &tris, 0, n, &mut want, |_, _, _| true);
                x86::leaf_closest(&rt, &tris, 0, n, &mut got);
                assert_eq!(
                    (got.t.to_bits(), got.tri, got.u.to_bits(), got.v.to_bits()),
                    (
                        want.t.to_bits(),
                        want.tri,
                        want.u.to_bits(),
                        want.v.to_bits()
                    ),
                    "case {case}, tmax {tmax}"
                );
                assert_eq!(
                    x86::leaf_any(&rt, &tris, 0, n, tmax),
                    leaf_any_scalar(&r, &tris, 0, n, tmax, |_, _, _| true),
                    "case {case}, tmax {tmax}"
                );
                checked += usize::from(want.tri != u32::MAX);
            }
        }
        // The cases hit often enough to test something.
        assert!(checked > 2000, "{checked} hits");
    }

    /// The CPU's order of a node's hits is GLSL's `sort4` order of them,
    /// ties included.
    #[test]
    fn order_hits_is_sort4_on_the_hits() {
        let mut rng = crate::sampling::Pcg32::new(4, 4);
        let values = [0.0, 0.5, 0.5, 1.0, 2.0, f32::INFINITY];
        for _ in 0..20_000 {
            let dist: [f32; 4] = std::array::from_fn(|_| values[rng.below(values.len())]);
            let mask = (0..4)
                .filter(|&i| dist[i] != f32::INFINITY)
                .fold(0, |m, i| m | 1 << i);
            let (order, n) = order_hits(mask, &dist);
            let want: Vec<usize> = sort4(&dist)
                .into_iter()
                .filter(|&i| mask & 1 << i != 0)
                .collect();
            let got: Vec<usize> = order[..n].iter().map(|&s| s as usize).collect();
            assert_eq!(got, want, "{dist:?}");
        }
        let inf = f32::INFINITY;
        let dist = [3.0, inf, 1.0, 1.0, 0.5, inf, 2.0, 0.5];
        let (order, n) = order_hits(0b1101_1101, &dist);
        assert_eq!(&order[..n], &[4, 7, 2, 3, 6, 0]);
    }

    #[test]
    fn sort4_orders_by_distance_then_slot() {
        let inf = f32::INFINITY;
        assert_eq!(sort4(&[3.0, 1.0, inf, 2.0]), [1, 3, 0, 2]);
        assert_eq!(sort4(&[0.0, 0.0, inf, 0.0]), [0, 1, 3, 2]);
        assert_eq!(sort4(&[inf, inf, 5.0, inf]), [2, 0, 1, 3]);
        // Every permutation of distinct keys sorts.
        let vals = [0.5f32, 1.5, 2.5, 3.5];
        for p in 0..24 {
            let mut idx = vec![0, 1, 2, 3];
            let mut perm = [0usize; 4];
            let mut k = p;
            for (j, slot) in perm.iter_mut().enumerate() {
                *slot = idx.remove(k % (4 - j));
                k /= 4 - j;
            }
            let d = perm.map(|i| vals[i]);
            let o = sort4(&d);
            assert!(o.windows(2).all(|w| d[w[0]] < d[w[1]]), "{d:?} -> {o:?}");
        }
    }
}
