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

use super::traverse::{PreparedRay, SLAB_PAD, intersect_aabb, intersect_triangle};
use super::wide::{Bvh4Node, SLOT_EMPTY, WIDE_STACK_SIZE, is_leaf_ref, leaf_range};
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
        }
        k
    }

    /// The kernel [`super::Bvh4::intersect`] uses: AVX where the CPU has it,
    /// else SSE2 on x86_64, else scalar. The detection is cached by std.
    #[inline]
    pub fn best() -> Kernel {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx") {
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
/// misses (+inf) come last. `sort4` in GLSL.
#[inline(always)]
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

/// Closest hit, generic over the box test. Children are visited nearest
/// first; the others wait on the stack with their entry distance and are
/// dropped when popped if the best hit has since moved in front of them
/// (the box test's own criterion: entry > tmax x SLAB_PAD misses).
#[inline(always)]
fn closest<F, P>(
    nodes: &[Bvh4Node],
    tris: &[Triangle],
    r: &PreparedRay,
    tmax: f32,
    boxes: F,
    present: P,
) -> Option<Hit>
where
    F: Fn(&Bvh4Node, f32) -> (u32, [f32; 4]),
    P: Fn(u32, f32, f32) -> bool,
{
    let mut best = Hit {
        t: tmax,
        tri: u32::MAX,
        u: 0.0,
        v: 0.0,
    };
    let mut stack = [(0u32, 0f32); WIDE_STACK_SIZE];
    let mut sp = 0;
    let mut cur = 0u32;
    loop {
        if is_leaf_ref(cur) {
            let (first, count) = leaf_range(cur);
            for (i, tri) in (first..).zip(&tris[first..first + count]) {
                if let Some((t, u, v)) = intersect_triangle(r, tri, best.t)
                    && present(i as u32, u, v)
                {
                    best = Hit {
                        t,
                        tri: i as u32,
                        u,
                        v,
                    };
                }
            }
        } else {
            let node = &nodes[cur as usize];
            let (mask, dist) = boxes(node, best.t);
            if mask != 0 {
                if mask.is_power_of_two() {
                    cur = node.child[mask.trailing_zeros() as usize];
                    continue;
                }
                let (near, far) = (
                    mask.trailing_zeros() as usize,
                    31 - mask.leading_zeros() as usize,
                );
                if mask.count_ones() == 2 {
                    // sort4's answer for two hits, with one comparison.
                    let (a, b) = if dist[far] < dist[near] {
                        (far, near)
                    } else {
                        (near, far)
                    };
                    stack[sp] = (node.child[b], dist[b]);
                    sp += 1;
                    cur = node.child[a];
                    continue;
                }
                let order = sort4(&dist);
                for &s in order[1..mask.count_ones() as usize].iter().rev() {
                    stack[sp] = (node.child[s], dist[s]);
                    sp += 1;
                }
                cur = node.child[order[0]];
                continue;
            }
        }
        loop {
            if sp == 0 {
                return (best.tri != u32::MAX).then_some(best);
            }
            sp -= 1;
            let (c, d) = stack[sp];
            if d <= best.t * SLAB_PAD {
                cur = c;
                break;
            }
        }
    }
}

/// Any hit: the first triangle hit in (0, tmax) ends the search; children
/// still nearest first (the likelier blockers).
#[inline(always)]
fn occluded<F, P>(
    nodes: &[Bvh4Node],
    tris: &[Triangle],
    r: &PreparedRay,
    tmax: f32,
    boxes: F,
    present: P,
) -> bool
where
    F: Fn(&Bvh4Node, f32) -> (u32, [f32; 4]),
    P: Fn(u32, f32, f32) -> bool,
{
    let mut stack = [0u32; WIDE_STACK_SIZE];
    let mut sp = 0;
    let mut cur = 0u32;
    loop {
        if is_leaf_ref(cur) {
            let (first, count) = leaf_range(cur);
            if (first..).zip(&tris[first..first + count]).any(|(i, tri)| {
                intersect_triangle(r, tri, tmax).is_some_and(|(_, u, v)| present(i as u32, u, v))
            }) {
                return true;
            }
        } else {
            let node = &nodes[cur as usize];
            let (mask, dist) = boxes(node, tmax);
            if mask != 0 {
                if mask.is_power_of_two() {
                    cur = node.child[mask.trailing_zeros() as usize];
                    continue;
                }
                let (near, far) = (
                    mask.trailing_zeros() as usize,
                    31 - mask.leading_zeros() as usize,
                );
                if mask.count_ones() == 2 {
                    let (a, b) = if dist[far] < dist[near] {
                        (far, near)
                    } else {
                        (near, far)
                    };
                    stack[sp] = node.child[b];
                    sp += 1;
                    cur = node.child[a];
                    continue;
                }
                let order = sort4(&dist);
                for &s in order[1..mask.count_ones() as usize].iter().rev() {
                    stack[sp] = node.child[s];
                    sp += 1;
                }
                cur = node.child[order[0]];
                continue;
            }
        }
        if sp == 0 {
            return false;
        }
        sp -= 1;
        cur = stack[sp];
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
            tris,
            &r,
            ray.tmax,
            |n, t| intersect_aabb4_scalar(&r, n, t),
            |_, _, _| true,
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
        tris,
        &r,
        ray.tmax,
        |n, t| intersect_aabb4_scalar(&r, n, t),
        present,
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
        tris,
        &r,
        ray.tmax,
        |n, t| intersect_aabb4_scalar(&r, n, t),
        present,
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
            tris,
            &r,
            ray.tmax,
            |n, t| intersect_aabb4_scalar(&r, n, t),
            |_, _, _| true,
        ),
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;

    use super::super::traverse::{PreparedRay, SLAB_PAD};
    use super::super::wide::Bvh4Node;
    use super::{Hit, Triangle, closest, occluded};

    /// The ray's constants broadcast to all four lanes.
    struct Ray4 {
        o: [__m128; 3],
        inv_d: [__m128; 3],
        zero_d: [bool; 3],
    }

    #[inline(always)]
    fn ray4(r: &PreparedRay) -> Ray4 {
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
            tris,
            r,
            tmax,
            |n, t| intersect_aabb4(&r4, n, t),
            |_, _, _| true,
        )
    }

    #[inline(always)]
    fn occluded_impl(nodes: &[Bvh4Node], tris: &[Triangle], r: &PreparedRay, tmax: f32) -> bool {
        let r4 = ray4(r);
        occluded(
            nodes,
            tris,
            r,
            tmax,
            |n, t| intersect_aabb4(&r4, n, t),
            |_, _, _| true,
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
}

#[cfg(test)]
mod tests {
    use super::*;

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
