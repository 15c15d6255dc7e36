//! Binned SAH construction (Wald 2007, "On fast construction of SAH-based
//! bounding volume hierarchies"), flattened into tinybvh's node layout.

use glam::Vec3A;
use rayon::prelude::*;

use super::{BvhNode, MAX_DEPTH, MAX_LEAF_SIZE};
use crate::scene::Triangle;

/// Bins per axis over the centroid bounds. Wald reports 8-16 bins lose next to
/// nothing against a full sweep; 16 costs little at our sizes.
const BINS: usize = 16;
/// SAH constants as tinybvh uses them: one traversal step costs as much as one
/// triangle test.
const C_TRAV: f32 = 1.0;
const C_ISECT: f32 = 1.0;

/// The SAH's prices: what a leaf of n triangles costs to test, and a
/// traversal step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum LeafCost {
    /// n triangle tests, and a step as dear as one (tinybvh's constants):
    /// the GPU's loop over a leaf's triangles, and the binary reference.
    Triangles,
    /// One test per block of up to [`MAX_LEAF_SIZE`] triangles side by
    /// side, both for leaves and for the two sides of a split: the CPU's
    /// SIMD leaf test (`wide8::LeafBlock`) costs the same for one triangle
    /// as for four (Embree's SAH for its four-triangle leaves). A binary
    /// step costs [`C_TRAV_BLOCKS`] of a block test, since the 8-wide
    /// collapse tests about three binary levels per node test. Measured
    /// against the alternatives in docs/benchmarks.md.
    Blocks,
}

/// A binary traversal step's cost in block tests, for [`LeafCost::Blocks`].
const C_TRAV_BLOCKS: f32 = 0.25;

impl LeafCost {
    /// The SAH's count of `n` triangles: tests for `Triangles`, blocks for
    /// `Blocks`.
    fn units(self, n: usize) -> f32 {
        match self {
            LeafCost::Triangles => n as f32,
            LeafCost::Blocks => n.div_ceil(MAX_LEAF_SIZE) as f32,
        }
    }

    fn traversal(self) -> f32 {
        match self {
            LeafCost::Triangles => C_TRAV,
            LeafCost::Blocks => C_TRAV_BLOCKS,
        }
    }
}

/// In 16-byte vectors: a box grows by one `minps` and one `maxps` (the
/// binning's chain from one triangle to the next in the same bin).
#[derive(Clone, Copy, Debug)]
struct Aabb {
    min: Vec3A,
    max: Vec3A,
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    #[inline(always)]
    fn grow(&mut self, b: &Aabb) {
        self.min = self.min.min(b.min);
        self.max = self.max.max(b.max);
    }

    #[inline(always)]
    fn grow_point(&mut self, p: Vec3A) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The centre, where Wald bins a triangle.
    #[inline(always)]
    fn centroid(&self) -> Vec3A {
        0.5 * (self.min + self.max)
    }

    /// Half the surface area: the SAH only needs ratios. 0 for an empty box.
    fn half_area(&self) -> f32 {
        let e = self.max - self.min;
        if e.x < 0.0 || e.y < 0.0 || e.z < 0.0 {
            return 0.0;
        }
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

/// Per-triangle data the builder reads: bounds (binned by their centroid,
/// as Wald bins them), and the triangle's index. The records themselves
/// are partitioned, so each node's passes read its triangles' records in a
/// row.
struct Prim {
    bounds: Aabb,
    index: u32,
}

impl Prim {
    fn of(t: &Triangle, index: u32) -> Prim {
        let mut bounds = Aabb::EMPTY;
        for p in t.vertices() {
            bounds.grow_point(p.into());
        }
        // The loader rejects non-finite positions; should one get here,
        // it is binned as a point at the origin so it cannot poison the
        // bounds of its neighbours (the triangle test never hits it).
        if !(bounds.min.is_finite() && bounds.max.is_finite()) {
            bounds = Aabb {
                min: Vec3A::ZERO,
                max: Vec3A::ZERO,
            };
        }
        Prim { bounds, index }
    }
}

pub(super) fn build(tris: &[Triangle], cost: LeafCost) -> (Vec<BvhNode>, Vec<u32>) {
    build_capped(tris, MAX_DEPTH, cost)
}

/// Subtrees of at least this many triangles split their two halves across
/// threads (rayon); smaller ones are built on the thread that reaches them.
const PAR_MIN: usize = 4096;

/// Every leaf ends at depth <= max(max_depth, ceil(log2 n)).
///
/// The node layout is depth first, left child first, a node's two children
/// side by side (allocated when the node is split), so a subtree's nodes
/// stay close in memory. It is the same whatever the number of threads:
/// subtrees built in parallel are placed afterwards, in that order.
fn build_capped(tris: &[Triangle], max_depth: usize, cost: LeafCost) -> (Vec<BvhNode>, Vec<u32>) {
    if tris.is_empty() {
        return (Vec::new(), Vec::new());
    }
    let mut prims: Vec<Prim> = (0..tris.len())
        .into_par_iter()
        .map(|i| Prim::of(&tris[i], i as u32))
        .collect();
    // One pass for the root; every other node's extent comes from its
    // parent's partition.
    let mut root = Extent::EMPTY;
    for p in &prims {
        root.grow(p);
    }
    let ctx = Ctx { max_depth, cost };
    let tree = grow_parallel(&mut prims, 0, root, 0, ctx);
    // A binary tree with at least one triangle per leaf has at most 2n - 1 nodes.
    let mut nodes = Vec::with_capacity(2 * tris.len() - 1);
    nodes.push(BvhNode::default());
    tree.place(&mut nodes, 0);
    (nodes, prims.iter().map(|p| p.index).collect())
}

/// What every node of one build shares.
#[derive(Clone, Copy)]
struct Ctx {
    max_depth: usize,
    cost: LeafCost,
}

/// A node's triangles' bounds and the bounds of their centroids (what the
/// binning spans).
#[derive(Clone, Copy)]
struct Extent {
    bounds: Aabb,
    centroids: Aabb,
}

impl Extent {
    const EMPTY: Extent = Extent {
        bounds: Aabb::EMPTY,
        centroids: Aabb::EMPTY,
    };

    #[inline(always)]
    fn grow(&mut self, p: &Prim) {
        self.bounds.grow(&p.bounds);
        self.centroids.grow_point(p.bounds.centroid());
    }

    /// The node of these triangles, its children or triangles not set.
    fn node(&self) -> BvhNode {
        BvhNode {
            aabb_min: self.bounds.min.into(),
            aabb_max: self.bounds.max.into(),
            ..BvhNode::default()
        }
    }
}

/// Splits a node's triangles (`prims`, of depth `depth`) in place: the left
/// side's count and both sides' extents, or `None` for a leaf.
fn split_node(
    prims: &mut [Prim],
    ext: &Extent,
    depth: usize,
    ctx: Ctx,
) -> Option<(usize, [Extent; 2])> {
    let split = choose_split(
        prims,
        &ext.bounds,
        &ext.centroids,
        depth,
        ctx.max_depth,
        ctx.cost,
    )?;
    let (left_count, sides) = match split {
        Split::Sah { axis, plane } => partition(prims, axis, plane, &ext.centroids),
        Split::Median { axis } => {
            median(prims, axis);
            let mid = prims.len() / 2;
            let mut sides = [Extent::EMPTY; 2];
            for (side, half) in sides.iter_mut().zip([&prims[..mid], &prims[mid..]]) {
                for p in half {
                    side.grow(p);
                }
            }
            (mid, sides)
        }
    };
    debug_assert!(left_count > 0 && left_count < prims.len());
    Some((left_count, sides))
}

/// Builds the subtree of `prims` (the triangles from `first` on) into
/// `out`, its root at `slot`.
fn grow_serial(
    prims: &mut [Prim],
    first: usize,
    ext: Extent,
    depth: usize,
    ctx: Ctx,
    out: &mut Vec<BvhNode>,
    slot: usize,
) {
    let mut node = ext.node();
    match split_node(prims, &ext, depth, ctx) {
        None => {
            node.left_or_first = first as u32;
            node.tri_count = prims.len() as u32;
            out[slot] = node;
        }
        Some((left_count, [left, right])) => {
            let children = out.len();
            node.left_or_first = children as u32;
            out[slot] = node;
            out.push(BvhNode::default());
            out.push(BvhNode::default());
            let (lp, rp) = prims.split_at_mut(left_count);
            grow_serial(lp, first, left, depth + 1, ctx, out, children);
            grow_serial(
                rp,
                first + left_count,
                right,
                depth + 1,
                ctx,
                out,
                children + 1,
            );
        }
    }
}

/// A subtree built apart from the tree it belongs to.
enum Subtree {
    /// Its nodes in the build's layout, the subtree's root first: child
    /// references count from that root (the root's children at 1 and 2).
    Flat(Vec<BvhNode>),
    /// A node whose two subtrees were built on their own.
    Split(BvhNode, Box<[Subtree; 2]>),
}

impl Subtree {
    /// Writes the subtree into `out`, its root at `slot` and its other
    /// nodes appended, child references rebased.
    fn place(self, out: &mut Vec<BvhNode>, slot: usize) {
        match self {
            Subtree::Flat(nodes) => {
                // Local index i >= 1 lands at base + i - 1.
                let base = out.len() as u32 - 1;
                let at = out.len();
                out.extend_from_slice(&nodes[1..]);
                out[slot] = nodes[0];
                for i in std::iter::once(slot).chain(at..out.len()) {
                    if out[i].tri_count == 0 {
                        out[i].left_or_first += base;
                    }
                }
            }
            Subtree::Split(mut node, children) => {
                let at = out.len();
                node.left_or_first = at as u32;
                out[slot] = node;
                out.push(BvhNode::default());
                out.push(BvhNode::default());
                let [left, right] = *children;
                left.place(out, at);
                right.place(out, at + 1);
            }
        }
    }
}

/// [`grow_serial`], the two sides of a large node built side by side.
fn grow_parallel(prims: &mut [Prim], first: usize, ext: Extent, depth: usize, ctx: Ctx) -> Subtree {
    if prims.len() < PAR_MIN {
        let mut nodes = vec![BvhNode::default()];
        grow_serial(prims, first, ext, depth, ctx, &mut nodes, 0);
        return Subtree::Flat(nodes);
    }
    let mut node = ext.node();
    match split_node(prims, &ext, depth, ctx) {
        Some((left_count, [left, right])) => {
            let (lp, rp) = prims.split_at_mut(left_count);
            let (l, r) = rayon::join(
                || grow_parallel(lp, first, left, depth + 1, ctx),
                || grow_parallel(rp, first + left_count, right, depth + 1, ctx),
            );
            Subtree::Split(node, Box::new([l, r]))
        }
        // (Not reached: the leaf-size cap splits a node this large.)
        None => {
            node.left_or_first = first as u32;
            node.tri_count = prims.len() as u32;
            Subtree::Flat(vec![node])
        }
    }
}

enum Split {
    /// Left: triangles whose centroid falls in bins `0..=plane` along `axis`.
    Sah { axis: usize, plane: usize },
    /// Left: the `count / 2` triangles with the smallest centroids along `axis`.
    Median { axis: usize },
}

fn ceil_log2(n: usize) -> usize {
    (usize::BITS - (n.max(1) - 1).leading_zeros()) as usize
}

/// The cheapest plane between the bins of one axis (the first of equal
/// costs) and its unnormalised SAH cost A_L N_L + A_R N_R (N in `leaf`'s units); `None` where
/// every plane leaves one side empty.
fn best_plane(
    bin_bounds: &[Aabb; BINS],
    bin_count: &[usize; BINS],
    count: usize,
    leaf: LeafCost,
) -> Option<(f32, usize)> {
    // Sweep from the right: cost of the right side of plane i (bins > i).
    let mut right_cost = [0.0f32; BINS];
    let mut acc = Aabb::EMPTY;
    let mut n = 0;
    for plane in (0..BINS - 1).rev() {
        acc.grow(&bin_bounds[plane + 1]);
        n += bin_count[plane + 1];
        right_cost[plane] = if n > 0 {
            acc.half_area() * leaf.units(n)
        } else {
            f32::NAN
        };
    }
    let mut best: Option<(f32, usize)> = None;
    let mut acc = Aabb::EMPTY;
    let mut n = 0;
    for plane in 0..BINS - 1 {
        acc.grow(&bin_bounds[plane]);
        n += bin_count[plane];
        if n == 0 || n == count {
            continue;
        }
        let cost = acc.half_area() * leaf.units(n) + right_cost[plane];
        if best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, plane));
        }
    }
    best
}

/// `None` makes a leaf.
fn choose_split(
    prims: &[Prim],
    bounds: &Aabb,
    centroids: &Aabb,
    depth: usize,
    max_depth: usize,
    leaf: LeafCost,
) -> Option<Split> {
    let count = prims.len();
    if count <= 1 {
        return None;
    }
    let extent = centroids.max - centroids.min;
    let widest = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    // Depth guard: a median split halves the count, so from here every leaf
    // ends at depth <= depth + ceil(log2 count). SAH splits are allowed only
    // while that sum stays below MAX_DEPTH; each SAH split raises the depth by
    // one and never raises ceil(log2 count), so the sum never exceeds
    // max_depth anywhere in the tree.
    if depth + ceil_log2(count) >= max_depth {
        return (count > MAX_LEAF_SIZE).then_some(Split::Median { axis: widest });
    }

    // Flat (and non-finite) centroid extents are skipped: nothing to bin.
    let binned = [0, 1, 2].map(|a| extent[a] > 0.0 && extent[a].is_finite());
    let scale = Vec3A::splat(BINS as f32) / extent;
    // All three axes binned in one pass over the triangles (the build's
    // hot loop: one read of each triangle's bounds instead of three).
    let mut all_bounds = [[Aabb::EMPTY; BINS]; 3];
    let mut all_counts = [[0usize; BINS]; 3];
    for p in prims {
        // The three axes' bin coordinates in one vector (lane by lane what
        // `bin_of` computes).
        let at = (p.bounds.centroid() - centroids.min) * scale;
        for axis in 0..3 {
            if binned[axis] {
                let b = bin_index(at[axis]);
                all_bounds[axis][b].grow(&p.bounds);
                all_counts[axis][b] += 1;
            }
        }
    }
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if !binned[axis] {
            continue;
        }
        if let Some((cost, plane)) = best_plane(&all_bounds[axis], &all_counts[axis], count, leaf)
            && best.is_none_or(|(c, _, _)| cost < c)
        {
            best = Some((cost, axis, plane));
        }
    }

    match best {
        Some((cost, axis, plane)) => {
            // SAH (Wald 2007, eq. 1): C = C_trav + C_isect (A_L N_L + A_R N_R) / A.
            let parent = bounds.half_area();
            let split_cost = if parent > 0.0 {
                leaf.traversal() + C_ISECT * cost / parent
            } else {
                f32::INFINITY
            };
            let leaf_cost = C_ISECT * leaf.units(count);
            if split_cost < leaf_cost || count > MAX_LEAF_SIZE {
                Some(Split::Sah { axis, plane })
            } else {
                None
            }
        }
        // All centroids coincide (or are not finite): SAH cannot separate
        // them, so only the leaf-size cap forces a split, by count.
        None => (count > MAX_LEAF_SIZE).then_some(Split::Median { axis: widest }),
    }
}

/// The bin of a centroid coordinate. Float-to-int casts saturate (NaN -> 0),
/// so this is in range whatever the input.
fn bin_of(c: f32, lo: f32, scale: f32) -> usize {
    bin_index((c - lo) * scale)
}

/// The bin of a bin coordinate x: its integer part clamped to the bins (0
/// for NaN), as a saturating `x as usize` then `min` give it, with one
/// truncation where x is in range (the saturating conversion's checks were
/// a quarter of the build's time).
#[inline(always)]
fn bin_index(x: f32) -> usize {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cvttss_si32, _mm_set_ss};
        // SAFETY: SSE is part of the x86_64 baseline. Out of i32's range
        // and NaN give i32::MIN, sorted out below.
        let i = unsafe { _mm_cvttss_si32(_mm_set_ss(x)) };
        if (0..BINS as i32).contains(&i) {
            i as usize
        } else if x >= BINS as f32 {
            BINS - 1
        } else {
            0
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        (x as usize).min(BINS - 1)
    }
}

/// Moves the triangles left of the plane to the front; returns how many,
/// and the extents of the two sides (gathered on the way, so a child needs
/// no pass of its own for them).
fn partition(
    prims: &mut [Prim],
    axis: usize,
    plane: usize,
    centroids: &Aabb,
) -> (usize, [Extent; 2]) {
    let lo = centroids.min[axis];
    let scale = BINS as f32 / (centroids.max[axis] - lo);
    let is_left = |p: &Prim| bin_of(p.bounds.centroid()[axis], lo, scale) <= plane;
    let (mut left, mut right) = (Extent::EMPTY, Extent::EMPTY);
    let mut l = 0;
    let mut r = prims.len();
    while l < r {
        if is_left(&prims[l]) {
            left.grow(&prims[l]);
            l += 1;
        } else {
            r -= 1;
            right.grow(&prims[l]);
            prims.swap(l, r);
        }
    }
    (l, [left, right])
}

/// Puts the `len / 2` smallest centroids along `axis` first. Ties are broken
/// by triangle index, so even all-equal centroids split in a defined way.
fn median(prims: &mut [Prim], axis: usize) {
    let mid = prims.len() / 2;
    prims.select_nth_unstable_by(mid, |a, b| {
        let (ca, cb) = (a.bounds.centroid()[axis], b.bounds.centroid()[axis]);
        ca.total_cmp(&cb).then(a.index.cmp(&b.index))
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ceil_log2_values() {
        assert_eq!([1, 2, 3, 4, 5, 8, 9].map(ceil_log2), [0, 1, 2, 2, 3, 3, 4]);
    }

    fn depth(nodes: &[BvhNode], i: usize) -> usize {
        let n = &nodes[i];
        if n.tri_count > 0 {
            0
        } else {
            let l = n.left_or_first as usize;
            1 + depth(nodes, l).max(depth(nodes, l + 1))
        }
    }

    /// A chain SAH builds 19 deep: a cap of 12 must hold it to 12, and
    /// still put every triangle in a leaf of at most MAX_LEAF_SIZE.
    #[test]
    fn depth_guard_caps_depth() {
        let tris: Vec<Triangle> = (0..400)
            .map(|i| {
                let x = 1.1f32.powi(i);
                Triangle {
                    p0: [x, 0.0, 0.0],
                    p1: [x, 1.0, 0.0],
                    p2: [x, 0.0, 1.0],
                    ..Default::default()
                }
            })
            .collect();
        for cost in [LeafCost::Triangles, LeafCost::Blocks] {
            let (free, _) = build_capped(&tris, MAX_DEPTH, cost);
            assert!(
                depth(&free, 0) > 12,
                "the chain is not deep enough to test the guard"
            );
            let (capped, order) = build_capped(&tris, 12, cost);
            assert!(depth(&capped, 0) <= 12);
            let mut seen = vec![0; tris.len()];
            for n in capped.iter().filter(|n| n.tri_count > 0) {
                assert!(n.tri_count as usize <= MAX_LEAF_SIZE);
                for k in n.left_or_first..n.left_or_first + n.tri_count {
                    seen[order[k as usize] as usize] += 1;
                }
            }
            assert!(seen.iter().all(|&s| s == 1));
        }
    }

    /// Triangles scattered by a small LCG: clusters and gaps, so the SAH
    /// and the size cap both split.
    fn scattered(n: usize) -> Vec<Triangle> {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n)
            .map(|i| {
                let c = [next() * 10.0, next() * (1 + i % 7) as f32, next()];
                let mut v = |k: usize| {
                    [
                        c[0] + next() * 0.1,
                        c[1] + next() * 0.1 * k as f32,
                        c[2] + next() * 0.1,
                    ]
                };
                Triangle {
                    p0: v(0),
                    p1: v(1),
                    p2: v(2),
                    ..Default::default()
                }
            })
            .collect()
    }

    /// The parallel build gives the one-thread layout node for node, on
    /// any number of threads: subtrees built apart are placed where the
    /// depth-first allocation puts them.
    #[test]
    fn parallel_build_is_the_serial_layout() {
        let tris = scattered(5 * PAR_MIN + 123);
        for cost in [LeafCost::Triangles, LeafCost::Blocks] {
            // The whole tree on one thread, without `grow_parallel`.
            let mut prims: Vec<Prim> = tris
                .iter()
                .zip(0u32..)
                .map(|(t, i)| Prim::of(t, i))
                .collect();
            let mut root = Extent::EMPTY;
            for p in &prims {
                root.grow(p);
            }
            let ctx = Ctx {
                max_depth: MAX_DEPTH,
                cost,
            };
            let mut serial = vec![BvhNode::default()];
            grow_serial(&mut prims, 0, root, 0, ctx, &mut serial, 0);
            let serial_order: Vec<u32> = prims.iter().map(|p| p.index).collect();
            assert!(serial.len() > 2 * tris.len() / MAX_LEAF_SIZE);
            for threads in [1, 2, 5] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let (nodes, order) = pool.install(|| build(&tris, cost));
                assert_eq!(order, serial_order, "{cost:?}, {threads} threads");
                assert!(
                    nodes == serial,
                    "{cost:?}, {threads} threads: the nodes differ"
                );
            }
        }
    }

    /// `bin_index` is the saturating conversion's answer everywhere: at
    /// the edges and on every 997th bit pattern.
    #[test]
    fn bin_index_is_the_saturating_cast() {
        let check = |x: f32| assert_eq!(bin_index(x), (x as usize).min(BINS - 1), "{x:e}");
        for x in [
            0.0f32,
            -0.0,
            -0.5,
            -1.0,
            0.999,
            15.0,
            15.999,
            16.0,
            17.5,
            2.147_483_6e9,
            3e9,
            -3e9,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ] {
            check(x);
        }
        for bits in (0..=u32::MAX).step_by(997) {
            check(f32::from_bits(bits));
        }
    }

    #[test]
    fn bin_of_stays_in_range() {
        assert_eq!(bin_of(f32::NAN, 0.0, 1.0), 0);
        assert_eq!(bin_of(-5.0, 0.0, 1.0), 0);
        assert_eq!(bin_of(1.0, 0.0, BINS as f32), BINS - 1);
        assert_eq!(bin_of(f32::INFINITY, 0.0, 1.0), BINS - 1);
    }
}
