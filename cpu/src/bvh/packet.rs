//! Closest hits of up to eight coherent rays on the 8-wide tree, in one
//! traversal (a packet): each node's eight boxes are tested once for the
//! whole packet, by interval arithmetic over the rays' origins and inverse
//! directions (Boulos et al. 2006, "Geometric and arithmetic culling
//! methods for entire ray packets"; Embree's and Mitsuba's packets of
//! coherent camera rays), and a leaf's triangles once per ray with the
//! single-ray test.
//!
//! The interval test is conservative: it accepts every box that any ray of
//! the packet accepts ([`super::intersect_aabb`] with the ray's own best
//! hit), since each of its bounds is the same IEEE operations on the
//! packet's extreme origin and inverse direction, and rounding is monotone.
//! So every ray tests every triangle the single-ray traversal could find
//! closest, with the same test: each ray's closest distance is the
//! single-ray traversal's, bit for bit (an exact tie between two triangles
//! may pick the other, as between the binary and the wide trees).
//!
//! It pays where the rays are alike: a pixel's camera rays share their
//! origin and differ in direction by less than a pixel, so the packet
//! visits nearly the nodes one of them visits, once instead of eight
//! times. Rays whose directions differ in sign on an axis, or have a zero
//! component, have no such bound; [`super::Bvh4::intersect_packet`] traces
//! them one at a time.

use super::wide_traverse::Avx2;
use super::wide8::{Bvh8Node, LeafBlock};
use super::{Hit, Ray};

/// Rays per packet.
pub const PACKET: usize = 8;

/// The packet's closest hits, written into `hits` (which starts all
/// None); false where the rays have no interval bound or the CPU no AVX2
/// (`avx2`, the tree's token: then the caller traces them one at a time).
/// Lanes outside `live` (bit k: ray k) are not traced and stay None.
/// (Written in place: a returned `Option` of the array was copied.)
pub(super) fn intersect_packet8(
    avx2: Option<Avx2>,
    nodes: &[Bvh8Node],
    blocks: &[LeafBlock],
    rays: &[Ray; PACKET],
    live: u8,
    hits: &mut [Option<Hit>; PACKET],
) -> bool {
    if nodes.is_empty() || live == 0 {
        return true;
    }
    if avx2.is_none() {
        return false;
    }
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: the token says the CPU has AVX2.
        unsafe { x86::intersect_packet_avx2(nodes, blocks, rays, live, hits) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = (blocks, rays, hits);
        unreachable!("no AVX2 token is made off x86_64")
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use std::arch::x86_64::*;
    use std::mem::MaybeUninit;

    use super::super::traverse::{SLAB_PAD, axes};
    use super::super::wide::{is_leaf_ref, leaf_range};
    use super::super::wide_traverse::order_hits;
    use super::super::wide_traverse::x86::{
        LeafRay, PLANES8, block_closest, hits8, leaf_ray_parts, slab_end8, triangles_sheared,
    };
    use super::super::wide8::{Bvh8Node, LeafBlock, WIDE8_STACK_SIZE};
    use super::{Hit, PACKET, Ray};

    /// The packet: its rays one per lane (what `PreparedRay::new`
    /// computes for each: the origin, the inverse direction, the shear,
    /// the axis order), and per axis the bounds of the interval test with
    /// the byte offsets in a [`Bvh8Node`] of the near and far coordinate
    /// arrays.
    struct Packet8 {
        o8: [__m256; 3],
        inv8: [__m256; 3],
        shear8: [__m256; 3],
        /// The triangle test's axis permutation, the same for every ray.
        k: [usize; 3],
        near: [usize; 3],
        far: [usize; 3],
        /// The origin bound that gives the entry distances' lower bound
        /// (the largest origin where the rays travel toward +axis, else
        /// the smallest) and the one that gives the exits' upper bound.
        o_near: [__m256; 3],
        o_far: [__m256; 3],
        /// The smallest and largest inverse direction (one sign).
        inv_lo: [__m256; 3],
        inv_hi: [__m256; 3],
    }

    /// Lane `j` of `v`.
    #[inline(always)]
    fn lane(v: &__m256, j: usize) -> f32 {
        // SAFETY: an `__m256` is eight `f32`s.
        unsafe { (*(v as *const __m256).cast::<[f32; PACKET]>())[j] }
    }

    /// The smallest and largest of the lanes of `v` that `live` (all ones
    /// in a live lane) selects, NaN lanes left out, as `f32::min` and
    /// `f32::max` folded over them would find them, in every lane. (Equal
    /// values of opposite zero signs may come out either way: the bounds'
    /// zeros compare equal, so the interval test is the same.)
    #[inline(always)]
    fn extremes(v: __m256, live: __m256) -> (__m256, __m256) {
        // SAFETY: called only from the AVX2 entry point below.
        #[allow(unused_unsafe)]
        unsafe {
            let keep = _mm256_and_ps(live, _mm256_cmp_ps::<_CMP_ORD_Q>(v, v));
            let lo = _mm256_blendv_ps(_mm256_set1_ps(f32::INFINITY), v, keep);
            let hi = _mm256_blendv_ps(_mm256_set1_ps(f32::NEG_INFINITY), v, keep);
            let lo = _mm256_min_ps(lo, _mm256_permute2f128_ps::<1>(lo, lo));
            let hi = _mm256_max_ps(hi, _mm256_permute2f128_ps::<1>(hi, hi));
            let lo = _mm256_min_ps(lo, _mm256_permute_ps::<0b0100_1110>(lo));
            let hi = _mm256_max_ps(hi, _mm256_permute_ps::<0b0100_1110>(hi));
            let lo = _mm256_min_ps(lo, _mm256_permute_ps::<0b1011_0001>(lo));
            let hi = _mm256_max_ps(hi, _mm256_permute_ps::<0b1011_0001>(hi));
            (lo, hi)
        }
    }

    /// The rays' component `$c` of `$f` (o or d) as lanes.
    macro_rules! lanes_of {
        ($rays:ident, $f:ident, $c:ident) => {
            _mm256_setr_ps(
                $rays[0].$f.$c,
                $rays[1].$f.$c,
                $rays[2].$f.$c,
                $rays[3].$f.$c,
                $rays[4].$f.$c,
                $rays[5].$f.$c,
                $rays[6].$f.$c,
                $rays[7].$f.$c,
            )
        };
    }

    /// The packet of `rays`, written into `out`; false (and `out` left
    /// as it was) where two live rays' directions differ in sign on an
    /// axis or in the triangle test's permutation, or one has a zero
    /// component. Made in lanes: the rays' axis orders
    /// ([`super::super::traverse::permutation`]) compared by their masks, the interval bounds by reductions across the lanes.
    /// (Written in place: an `Option<Packet8>` returned was copied, a
    /// kilobyte per packet; and the rays staged in arrays a float at a time
    /// were read back eight at a time, each such load waiting for its
    /// eight stores.)
    #[inline(always)]
    fn packet8(rays: &[Ray; PACKET], live: u8, out: &mut MaybeUninit<Packet8>) -> bool {
        // SAFETY: called only from the AVX2 entry point below.
        #[allow(unused_unsafe)]
        unsafe {
            let o8 = [
                lanes_of!(rays, o, x),
                lanes_of!(rays, o, y),
                lanes_of!(rays, o, z),
            ];
            let d8 = [
                lanes_of!(rays, d, x),
                lanes_of!(rays, d, y),
                lanes_of!(rays, d, z),
            ];
            let bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
            let live8 = _mm256_castsi256_ps(_mm256_cmpeq_epi32(
                _mm256_and_si256(_mm256_set1_epi32(i32::from(live)), bits),
                bits,
            ));
            let mask = |m: __m256| _mm256_movemask_ps(m) as u8 & live;
            let uniform = |m: u8| m == 0 || m == live;
            let sign = _mm256_set1_ps(-0.0);
            let zero = _mm256_setzero_ps();
            let Some(k) = common_axes(&d8, live) else {
                return false;
            };
            let mut inv8 = [zero; 3];
            let mut negative = [false; 3];
            for a in 0..3 {
                let da = d8[a];
                // PreparedRay::new's safe reciprocal, lane by lane: the
                // same quotient, and +-1e30 (d's sign) where |d| < 1e-30.
                let big =
                    _mm256_cmp_ps::<_CMP_GE_OQ>(_mm256_andnot_ps(sign, da), _mm256_set1_ps(1e-30));
                let inv = _mm256_blendv_ps(
                    _mm256_or_ps(_mm256_and_ps(da, sign), _mm256_set1_ps(1e30)),
                    _mm256_div_ps(_mm256_set1_ps(1.0), da),
                    big,
                );
                let neg = mask(_mm256_cmp_ps::<_CMP_LT_OQ>(inv, zero));
                if mask(_mm256_cmp_ps::<_CMP_EQ_OQ>(da, zero)) != 0 || !uniform(neg) {
                    return false;
                }
                negative[a] = neg != 0;
                inv8[a] = inv;
            }
            let dz = d8[k[2]];
            let shear8 = [
                _mm256_div_ps(d8[k[0]], dz),
                _mm256_div_ps(d8[k[1]], dz),
                _mm256_div_ps(_mm256_set1_ps(1.0), dz),
            ];
            let p = out.write(Packet8 {
                o8,
                inv8,
                shear8,
                k,
                near: [0; 3],
                far: [0; 3],
                o_near: [zero; 3],
                o_far: [zero; 3],
                inv_lo: [zero; 3],
                inv_hi: [zero; 3],
            });
            for a in 0..3 {
                let (o_lo, o_hi) = extremes(o8[a], live8);
                let (i_lo, i_hi) = extremes(inv8[a], live8);
                // Toward +axis the entry (lo - o) inv is smallest at the
                // largest origin and the exit (hi - o) inv largest at the
                // smallest; toward -axis the other way round.
                let (near, far, o_near, o_far) = if negative[a] {
                    (PLANES8[a].1, PLANES8[a].0, o_lo, o_hi)
                } else {
                    (PLANES8[a].0, PLANES8[a].1, o_hi, o_lo)
                };
                p.near[a] = near;
                p.far[a] = far;
                p.o_near[a] = o_near;
                p.o_far[a] = o_far;
                p.inv_lo[a] = i_lo;
                p.inv_hi[a] = i_hi;
            }
            true
        }
    }

    /// The live rays' common axis order for the triangle test
    /// ([`super::super::traverse::permutation`]'s rule, lane by lane: the
    /// dominant axis, the first of equals, then whether d is negative
    /// along it), or None where two of them differ.
    #[inline(always)]
    fn common_axes(d8: &[__m256; 3], live: u8) -> Option<[usize; 3]> {
        // SAFETY: called only from the AVX2 entry point below.
        #[allow(unused_unsafe)]
        unsafe {
            let mask = |m: __m256| _mm256_movemask_ps(m) as u8 & live;
            let uniform = |m: u8| m == 0 || m == live;
            let sign = _mm256_set1_ps(-0.0);
            let a8 = [
                _mm256_andnot_ps(sign, d8[0]),
                _mm256_andnot_ps(sign, d8[1]),
                _mm256_andnot_ps(sign, d8[2]),
            ];
            let kz0 = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GE_OQ>(a8[0], a8[1]),
                _mm256_cmp_ps::<_CMP_GE_OQ>(a8[0], a8[2]),
            );
            let kz1 = _mm256_andnot_ps(kz0, _mm256_cmp_ps::<_CMP_GE_OQ>(a8[1], a8[2]));
            let (m0, m1) = (mask(kz0), mask(kz1));
            if !uniform(m0) || !uniform(m1) {
                return None;
            }
            let kz = if m0 != 0 {
                0
            } else if m1 != 0 {
                1
            } else {
                2
            };
            let backward = mask(_mm256_cmp_ps::<_CMP_LT_OQ>(d8[kz], _mm256_setzero_ps()));
            uniform(backward).then(|| axes(2 * kz as u8 + u8::from(backward != 0)))
        }
    }

    impl Packet8 {
        /// Ray `j`'s leaf constants, as the single-ray traversal makes them
        /// from its prepared ray.
        #[inline(always)]
        fn leaf(&self, j: usize) -> LeafRay {
            let v = |a: &[__m256; 3]| [lane(&a[0], j), lane(&a[1], j), lane(&a[2], j)];
            leaf_ray_parts(v(&self.o8), self.k, v(&self.shear8))
        }
    }

    /// The rays `rays` of the packet against leaf block `block`, eight
    /// rays per instruction, the block's triangles in order: lane k tests
    /// triangle j with ray k's constants and the operations of the
    /// single-ray test ([`triangles_sheared`]), and takes it where it is
    /// nearer than ray k's best so far, as [`block_closest`] takes the
    /// block's lanes in order. So each ray's best hit is the one it finds
    /// alone, bit for bit.
    #[inline(always)]
    fn block_closest8(
        p: &Packet8,
        block: &LeafBlock,
        rays: u8,
        best: &mut [Hit; PACKET],
        best_t: &mut [f32; PACKET],
    ) {
        // SAFETY: called only from the AVX2 entry point below.
        #[allow(unused_unsafe)]
        unsafe {
            // (No `array::map` here: its closures stay out of line, where
            // the AVX intrinsics they call are calls too.)
            let k = p.k;
            let o = [p.o8[k[0]], p.o8[k[1]], p.o8[k[2]]];
            // Vertex `n` of triangle j minus each ray's origin, in the
            // rays' (common) axis order. (A function, not a closure, so
            // that it is inlined.)
            #[inline(always)]
            fn vertex(
                block: &LeafBlock,
                n: usize,
                j: usize,
                k: [usize; 3],
                o: &[__m256; 3],
            ) -> [__m256; 3] {
                // SAFETY: called only from the AVX2 entry point below.
                #[allow(unused_unsafe)]
                unsafe {
                    let at = |i: usize| _mm256_set1_ps(block.v[n][k[i]][j]);
                    [
                        _mm256_sub_ps(at(0), o[0]),
                        _mm256_sub_ps(at(1), o[1]),
                        _mm256_sub_ps(at(2), o[2]),
                    ]
                }
            }
            for j in 0..block.count as usize {
                let vertex = |n: usize| vertex(block, n, j, k, &o);
                let tmax = _mm256_loadu_ps(best_t.as_ptr());
                let (mut hit, [t, u, v]) = triangles_sheared(
                    &p.shear8,
                    vertex(0),
                    vertex(1),
                    vertex(2),
                    u32::from(rays),
                    tmax,
                );
                while hit != 0 {
                    let l = hit.trailing_zeros() as usize;
                    hit &= hit - 1;
                    best[l] = Hit {
                        t: t[l],
                        tri: block.tri[j],
                        u: u[l],
                        v: v[l],
                    };
                    best_t[l] = t[l];
                }
            }
        }
    }

    /// The eight boxes against the packet: per box, a lower bound of every
    /// ray's entry distance (+inf where no ray of the packet can hit it
    /// before `tmax`, the largest of the rays' own limits), and the mask
    /// of boxes some ray may hit. Per axis the entry's bound is the smaller
    /// of (near plane - o_near) x each inverse direction bound, the exit's
    /// the larger of (far plane - o_far) x each: the extremes of a product
    /// monotone in each factor (see the module notes).
    #[inline(always)]
    fn intersect_aabb8_packet(p: &Packet8, n: &Bvh8Node, tmax: f32) -> (u32, [f32; 8]) {
        // SAFETY: called only from the AVX2 entry point below; the loads
        // read 32-byte aligned `[f32; 8]` fields of an align(64) node at
        // offsets `packet8` took from its layout.
        #[allow(unused_unsafe)]
        unsafe {
            let base = (n as *const Bvh8Node).cast::<u8>();
            let plane = |off: usize| _mm256_load_ps(base.add(off).cast::<f32>());
            let mut tlo = [_mm256_setzero_ps(); 3];
            let mut thi = [_mm256_setzero_ps(); 3];
            for a in 0..3 {
                let dn = _mm256_sub_ps(plane(p.near[a]), p.o_near[a]);
                let df = _mm256_sub_ps(plane(p.far[a]), p.o_far[a]);
                tlo[a] = _mm256_min_ps(
                    _mm256_mul_ps(dn, p.inv_lo[a]),
                    _mm256_mul_ps(dn, p.inv_hi[a]),
                );
                thi[a] = _mm256_max_ps(
                    _mm256_mul_ps(df, p.inv_lo[a]),
                    _mm256_mul_ps(df, p.inv_hi[a]),
                );
            }
            let (tnear, hit) = slab_end8(tlo, thi, _mm256_set1_ps(tmax));
            hits8(tnear, hit)
        }
    }

    /// Which rays hit child `slot`'s box before their best hit `best`:
    /// lane k computes what the single-ray box test computes for ray k
    /// (the same near/far planes, as the packet's rays agree in sign, and
    /// the same operations), so a ray tests a leaf exactly where its own
    /// traversal would.
    #[inline(always)]
    fn rays_in_box(p: &Packet8, n: &Bvh8Node, slot: usize, best: &[f32; PACKET]) -> u8 {
        // SAFETY: called only from the AVX2 entry point below; the loads
        // read `f32`s inside an align(64) node at offsets `packet8` took
        // from its layout, plus the slot.
        #[allow(unused_unsafe)]
        unsafe {
            let base = (n as *const Bvh8Node).cast::<u8>();
            let plane = |off: usize| _mm256_broadcast_ss(&*base.add(off).cast::<f32>().add(slot));
            let mut tlo = [_mm256_setzero_ps(); 3];
            let mut thi = [_mm256_setzero_ps(); 3];
            for a in 0..3 {
                tlo[a] = _mm256_mul_ps(_mm256_sub_ps(plane(p.near[a]), p.o8[a]), p.inv8[a]);
                thi[a] = _mm256_mul_ps(_mm256_sub_ps(plane(p.far[a]), p.o8[a]), p.inv8[a]);
            }
            let (_, hit) = slab_end8(tlo, thi, _mm256_loadu_ps(best.as_ptr()));
            _mm256_movemask_ps(hit) as u8
        }
    }

    /// The packet's traversal: nodes nearest first by the packet's entry
    /// bound, a waiting node dropped when the farthest of the rays' best
    /// hits has moved in front of it; a leaf is tested by the rays that
    /// hit its box (by their own box test when its node was visited).
    /// The hits go into `hits` (its live lanes None on entry); false
    /// where the rays make no packet ([`packet8`]).
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[target_feature(enable = "avx2")]
    pub(super) unsafe fn intersect_packet_avx2(
        nodes: &[Bvh8Node],
        blocks: &[LeafBlock],
        rays: &[Ray; PACKET],
        live: u8,
        hits: &mut [Option<Hit>; PACKET],
    ) -> bool {
        let mut packet = MaybeUninit::uninit();
        if !packet8(rays, live, &mut packet) {
            return false;
        }
        // SAFETY: packet8 wrote it (it returned true).
        let p = unsafe { packet.assume_init_ref() };
        let mut best: [Hit; PACKET] = std::array::from_fn(|k| Hit {
            t: rays[k].tmax,
            tri: u32::MAX,
            u: 0.0,
            v: 0.0,
        });
        // The rays' best distances, lanes outside `live` at -inf (so they
        // hit no box and never hold the packet's limit up).
        let mut best_t: [f32; PACKET] = std::array::from_fn(|k| {
            if live & (1 << k) != 0 {
                rays[k].tmax
            } else {
                f32::NEG_INFINITY
            }
        });
        let farthest = |t: &[f32; PACKET]| t.iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b));
        let mut far = farthest(&best_t);
        // (node, the packet's entry bound, the rays that test it if a leaf)
        let mut stack = [MaybeUninit::<(u32, f32, u8)>::uninit(); WIDE8_STACK_SIZE];
        let mut sp = 0;
        let (mut cur, mut cur_rays) = (0u32, live);
        loop {
            if is_leaf_ref(cur) {
                let block = &blocks[leaf_range(cur).0];
                // More rays than triangles: the rays side by side, a
                // triangle at a time (a test per triangle); else each ray's
                // own test of the block's triangles (a test per ray).
                if cur_rays.count_ones() > block.count {
                    block_closest8(p, block, cur_rays, &mut best, &mut best_t);
                } else {
                    for k in crate::lanes::live_lanes(cur_rays) {
                        block_closest(&p.leaf(k), block, &mut best[k], &|_, _, _| true);
                        best_t[k] = best[k].t;
                    }
                }
                far = farthest(&best_t);
            } else {
                let node = &nodes[cur as usize];
                let (mask, dist) = intersect_aabb8_packet(p, node, far);
                if mask != 0 {
                    let (order, n) = order_hits(mask, &dist);
                    let rays_of = |s: usize| {
                        if is_leaf_ref(node.child[s]) {
                            rays_in_box(p, node, s, &best_t)
                        } else {
                            live
                        }
                    };
                    for &s in order[1..n].iter().rev() {
                        let s = s as usize;
                        let m = rays_of(s);
                        if m != 0 {
                            stack[sp] = MaybeUninit::new((node.child[s], dist[s], m));
                            sp += 1;
                        }
                    }
                    let s = order[0] as usize;
                    cur_rays = rays_of(s);
                    cur = node.child[s];
                    if cur_rays != 0 {
                        continue;
                    }
                }
            }
            loop {
                if sp == 0 {
                    for (k, hit) in hits.iter_mut().enumerate() {
                        if live & (1 << k) != 0 && best[k].tri != u32::MAX {
                            *hit = Some(best[k]);
                        }
                    }
                    return true;
                }
                sp -= 1;
                // SAFETY: every entry below the stack pointer was pushed.
                let (c, d, m) = unsafe { stack[sp].assume_init() };
                if d <= far * SLAB_PAD {
                    (cur, cur_rays) = (c, m);
                    break;
                }
            }
        }
    }
}
