//! The 8-wide BVH of CPUs with AVX2: a binary tree collapsed eight
//! children to a node ([`super::wide::collapse_slots`], the same rule as the
//! 4-wide tree, so its leaves and child boxes are that binary tree's bit for
//! bit), one coordinate of the eight boxes per 256-bit register, so one AVX
//! instruction tests a coordinate of all eight (Embree's BVH8 layout). CPU
//! only: the GPU reads the 4-wide tree. The renders' 8-wide tree is
//! collapsed from a binary tree of its own, built for its leaf blocks
//! ([`super::Bvh4::build`]); [`super::Bvh4::collapse`] makes one from the
//! GPU's binary tree, which the tests compare leaf for leaf.
//!
//! Why a second width: `bench/embree` measured glint's 4-wide traversal at
//! 0.46-0.67 of Embree's (which traverses 8-wide nodes on AVX2 CPUs), and
//! node visits dominate the render profile; an 8-wide node roughly halves
//! the interior nodes a ray visits for the same cost per node test.
//!
//! Every box test computes, per child, exactly what
//! [`super::intersect_aabb`] computes for that child's box (the same IEEE
//! operations in the same order), and the leaves use the 4-wide traversal's
//! triangle tests, so the 8-wide traversal finds the binary traversal's
//! closest distance (an exact tie between two triangles may pick the other).

use super::wide::{MAX_WIDE_DEPTH, SLOT_EMPTY, collapse_slots, is_leaf_ref, leaf_range, leaf_ref};
use super::{BvhNode, MAX_LEAF_SIZE};
use crate::scene::Triangle;

/// Children per node.
pub const WIDTH8: usize = 8;
/// Entries of the 8-wide traversal stack: a node visited pushes at most
/// seven children (the nearest is visited at once), and at most
/// `MAX_WIDE_DEPTH + 1` nodes lie on the path to the current one (the
/// collapse rule puts interior children at least two binary levels down,
/// whatever the width).
pub const WIDE8_STACK_SIZE: usize = (WIDTH8 - 1) * (MAX_WIDE_DEPTH + 1);

/// Eight child boxes, one coordinate per `[f32; 8]` (32-byte aligned for
/// AVX loads), and their references as in [`super::Bvh4Node`] (a wide
/// node's index, a leaf reference, or [`SLOT_EMPTY`], empty slots last).
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bvh8Node {
    pub lo_x: [f32; 8],
    pub hi_x: [f32; 8],
    pub lo_y: [f32; 8],
    pub hi_y: [f32; 8],
    pub lo_z: [f32; 8],
    pub hi_z: [f32; 8],
    pub child: [u32; 8],
}

impl Bvh8Node {
    /// No children.
    pub const EMPTY: Bvh8Node = Bvh8Node {
        lo_x: [f32::INFINITY; 8],
        hi_x: [f32::NEG_INFINITY; 8],
        lo_y: [f32::INFINITY; 8],
        hi_y: [f32::NEG_INFINITY; 8],
        lo_z: [f32::INFINITY; 8],
        hi_z: [f32::NEG_INFINITY; 8],
        child: [SLOT_EMPTY; 8],
    };

    fn set_child(&mut self, i: usize, n: &BvhNode, child: u32) {
        [self.lo_x[i], self.lo_y[i], self.lo_z[i]] = n.aabb_min;
        [self.hi_x[i], self.hi_y[i], self.hi_z[i]] = n.aabb_max;
        self.child[i] = child;
    }

    /// Number of used slots (they come first).
    pub fn child_count(&self) -> usize {
        self.child.iter().take_while(|&&c| c != SLOT_EMPTY).count()
    }
}

/// One leaf's triangles (at most [`MAX_LEAF_SIZE`] = 4) with their
/// coordinates side by side, `v[vertex][axis][lane]`, so the SIMD triangle
/// test loads each row without transposing (Embree's `Triangle4v`), and
/// each lane's index in the scene's triangle array; lanes past `count`
/// repeat the last triangle. The 8-wide tree's leaf references name a
/// block, not a triangle range: its leaves need not be ranges of the
/// scene's order (the tree [`super::Bvh4::build`] makes for the CPU is
/// built apart from the GPU's).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeafBlock {
    pub v: [[[f32; 4]; 3]; 3],
    /// Each lane's triangle: its index in the scene's triangle array.
    pub tri: [u32; 4],
    /// Triangles in the block, 1..=4.
    pub count: u32,
    _pad: [u32; 3],
}

const _: () = assert!(MAX_LEAF_SIZE <= 4);

impl LeafBlock {
    /// The block of `tris[first..first + count]`, lane j's index in the
    /// scene's array `id(first + j)`.
    fn new(tris: &[Triangle], first: usize, count: usize, id: &impl Fn(usize) -> u32) -> LeafBlock {
        let mut v = [[[0f32; 4]; 3]; 3];
        let mut tri = [0u32; 4];
        for lane in 0..4 {
            let i = first + lane.min(count - 1);
            let t = &tris[i];
            tri[lane] = id(i);
            for (k, p) in [t.p0, t.p1, t.p2].into_iter().enumerate() {
                for axis in 0..3 {
                    v[k][axis][lane] = p[axis];
                }
            }
        }
        LeafBlock {
            v,
            tri,
            count: count as u32,
            _pad: [0; 3],
        }
    }
}

/// The binary tree `bin` collapsed into 8-wide nodes, with a block per
/// leaf of `tris` (in the order the build returned); `id(i)` is the index
/// in the scene's triangle array of `tris[i]`.
pub(super) fn collapse8(
    bin: &[BvhNode],
    tris: &[Triangle],
    id: impl Fn(usize) -> u32,
) -> (Vec<Bvh8Node>, Vec<LeafBlock>) {
    let mut blocks = Vec::new();
    let nodes = collapse_slots(bin, WIDTH8)
        .iter()
        .map(|slots| {
            let mut node = Bvh8Node::EMPTY;
            for (s, &(i, child)) in slots.iter().enumerate() {
                let child = if is_leaf_ref(child) {
                    let (first, count) = leaf_range(child);
                    blocks.push(LeafBlock::new(tris, first, count, &id));
                    leaf_ref((blocks.len() - 1) as u32, count as u32)
                } else {
                    child
                };
                node.set_child(s, &bin[i], child);
            }
            node
        })
        .collect();
    (nodes, blocks)
}

/// Depth of the deepest node (root = 0); 0 for an empty hierarchy.
pub(super) fn depth8(nodes: &[Bvh8Node]) -> usize {
    if nodes.is_empty() {
        return 0;
    }
    let mut deepest = 0;
    let mut stack = vec![(0usize, 0usize)];
    while let Some((i, d)) = stack.pop() {
        deepest = deepest.max(d);
        for &c in &nodes[i].child {
            if c != SLOT_EMPTY && !is_leaf_ref(c) {
                stack.push((c as usize, d + 1));
            }
        }
    }
    deepest
}
