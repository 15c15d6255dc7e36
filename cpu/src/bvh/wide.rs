//! The 4-wide BVH: the binary binned-SAH tree collapsed so every node holds
//! the boxes of up to four children side by side, one coordinate per
//! `[f32; 4]`, so one SIMD instruction tests a coordinate of all four boxes
//! (the layout of Embree's BVH4 and of Wald, Benthin, Boulos 2008, "Getting
//! rid of packets"). The GPU reads the same bytes (`Bvh4Node`,
//! declared in [`crate::abi`], which generates its GLSL).
//!
//! Why collapse our own tree instead of taking `obvhs` (PLOC + CWBVH) or
//! `tinybvh-rs`: the collapse keeps the binary tree's leaves, triangle order
//! and child boxes bit for bit, so the wide traversal can be tested against
//! the binary one ray for ray (the same triangle, not merely a hit at a
//! similar distance), and the node is plain `f32`/`u32` words that GLSL reads
//! without decoding. CWBVH's 8-bit quantised boxes pay off on real GPUs,
//! where traversal is memory bound; on lavapipe (the GPU here is LLVM code on
//! the same two cores) and on the CPU the dequantisation is extra ALU work,
//! and the crates would add a second builder whose trees the binary
//! reference could not be compared with node by node.
//!
//! Why 4 wide here: an SSE register and a GLSL `vec4` hold exactly one
//! coordinate of four boxes, and it is the GPU's layout. CPUs with AVX2
//! traverse the same tree collapsed 8 wide (`wide8.rs`), measured faster
//! there (`bench/embree`, docs/benchmarks.md); [`collapse_slots`] serves
//! both widths.

use glam::Vec3;

use super::{BvhNode, MAX_DEPTH, MAX_LEAF_SIZE};

/// Children per node.
pub const WIDTH: usize = 4;
/// A child slot that holds nothing. Empty slots are always the last ones.
pub const SLOT_EMPTY: u32 = crate::abi::BVH4_SLOT_EMPTY;
/// Set in a child reference to a leaf: bits 0..27 are the first triangle,
/// bits 27..31 the triangle count minus 1.
pub const LEAF_BIT: u32 = crate::abi::BVH4_LEAF_BIT;
const LEAF_FIRST_BITS: u32 = 27;
/// Triangles a leaf reference can address.
pub const MAX_LEAF_FIRST: u32 = crate::abi::BVH4_LEAF_FIRST_MASK;
const _: () = assert!(MAX_LEAF_FIRST == (1 << LEAF_FIRST_BITS) - 1);

/// Deepest wide node on any path (root = 0): the collapse puts interior
/// children at least two binary levels below their parent, and the binary
/// builder keeps interior nodes at depth <= MAX_DEPTH - 1, so a path holds
/// wide nodes at binary depths 0, 2, 4, ..., at most MAX_DEPTH - 2.
pub const MAX_WIDE_DEPTH: usize = (MAX_DEPTH - 1) / 2;
/// Entries of the wide traversal stack (CPU and GPU): a node visited pushes
/// at most `WIDTH - 1` children (the nearest is visited at once), and at most
/// `MAX_WIDE_DEPTH + 1` nodes lie on the path to the current one.
pub const WIDE_STACK_SIZE: usize = crate::abi::BVH4_STACK_SIZE;
const _: () = assert!(WIDE_STACK_SIZE == (WIDTH - 1) * (MAX_WIDE_DEPTH + 1));
const _: () = assert!(MAX_LEAF_SIZE <= 1 << (31 - LEAF_FIRST_BITS));

pub use crate::abi::Bvh4Node;

impl Default for Bvh4Node {
    fn default() -> Self {
        Bvh4Node::EMPTY
    }
}

impl Bvh4Node {
    /// No children.
    pub const EMPTY: Bvh4Node = Bvh4Node {
        lo_x: [f32::INFINITY; 4],
        hi_x: [f32::NEG_INFINITY; 4],
        lo_y: [f32::INFINITY; 4],
        hi_y: [f32::NEG_INFINITY; 4],
        lo_z: [f32::INFINITY; 4],
        hi_z: [f32::NEG_INFINITY; 4],
        child: [SLOT_EMPTY; 4],
        _pad: [0; 4],
    };

    /// Slot `i`'s box.
    pub fn child_box(&self, i: usize) -> (Vec3, Vec3) {
        (
            Vec3::new(self.lo_x[i], self.lo_y[i], self.lo_z[i]),
            Vec3::new(self.hi_x[i], self.hi_y[i], self.hi_z[i]),
        )
    }

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

/// The reference to a leaf of `count` (1..=16) triangles from `first`.
pub fn leaf_ref(first: u32, count: u32) -> u32 {
    // Counts up to MAX_LEAF_SIZE (the builder's limit): 16 with the largest
    // `first` would spell SLOT_EMPTY.
    assert!(first <= MAX_LEAF_FIRST && (1..=MAX_LEAF_SIZE as u32).contains(&count));
    LEAF_BIT | (count - 1) << LEAF_FIRST_BITS | first
}

/// Whether a (non-empty) child reference is a leaf.
#[inline(always)]
pub fn is_leaf_ref(child: u32) -> bool {
    child & LEAF_BIT != 0
}

/// (first, count) of a leaf reference.
#[inline(always)]
pub fn leaf_range(child: u32) -> (usize, usize) {
    (
        (child & MAX_LEAF_FIRST) as usize,
        (((child >> LEAF_FIRST_BITS) & 0xf) + 1) as usize,
    )
}

fn half_area(n: &BvhNode) -> f32 {
    let e = Vec3::from(n.aabb_max) - Vec3::from(n.aabb_min);
    e.x * e.y + e.y * e.z + e.z * e.x
}

/// Collapses a binary BVH (as [`super::Bvh::build`] makes it) into 4-wide
/// nodes ([`collapse_slots`] with four slots).
pub(super) fn collapse(bin: &[BvhNode]) -> Vec<Bvh4Node> {
    collapse_slots(bin, WIDTH)
        .iter()
        .map(|slots| {
            let mut node = Bvh4Node::EMPTY;
            for (s, &(i, child)) in slots.iter().enumerate() {
                node.set_child(s, &bin[i], child);
            }
            node
        })
        .collect()
}

/// Collapses a binary BVH into nodes of up to `width` children, top down
/// (Wald et al. 2008, section 3.1): a wide node starts from a binary node's
/// two children and repeatedly opens an interior child into its two
/// children until it has `width`. Children one binary level down are opened
/// first, so every interior child of a wide node lies at least two binary
/// levels below it (the depth bound [`MAX_WIDE_DEPTH`] rests on that); then
/// the child with the largest surface area, the likeliest to be entered
/// (the SAH's argument). Leaves stay the binary tree's leaves, so the
/// triangle order is unchanged. Nodes are numbered depth first. Returns,
/// per wide node, its slots in order: (binary node whose box the slot
/// holds, child reference: a wide node's index or a [`leaf_ref`]).
pub(super) fn collapse_slots(bin: &[BvhNode], width: usize) -> Vec<Vec<(usize, u32)>> {
    let Some(root) = bin.first() else {
        return Vec::new();
    };
    if root.is_leaf() {
        return vec![vec![(0, leaf_ref(root.left_or_first, root.tri_count))]];
    }
    let mut out = vec![Vec::new()];
    // (binary node, wide node to fill from its children)
    let mut tasks = vec![(0usize, 0usize)];
    while let Some((b, w)) = tasks.pop() {
        let l = bin[b].left_or_first as usize;
        // (binary node, levels below b), in the binary tree's left-to-right order.
        let mut slots: Vec<(usize, u32)> = vec![(l, 1), (l + 1, 1)];
        while slots.len() < width {
            let mut pick: Option<(usize, bool, f32)> = None;
            for (k, &(i, d)) in slots.iter().enumerate() {
                if bin[i].is_leaf() {
                    continue;
                }
                let key = (d == 1, half_area(&bin[i]));
                // Strictly better only: ties keep the leftmost (determinism).
                if pick.is_none_or(|(_, p1, pa)| (key.0 && !p1) || (key.0 == p1 && key.1 > pa)) {
                    pick = Some((k, key.0, key.1));
                }
            }
            let Some((k, _, _)) = pick else { break };
            let (i, d) = slots[k];
            let c = bin[i].left_or_first as usize;
            slots[k] = (c, d + 1);
            slots.insert(k + 1, (c + 1, d + 1));
        }
        let mut interior = Vec::new();
        for &(i, _) in &slots {
            let n = &bin[i];
            if n.is_leaf() {
                out[w].push((i, leaf_ref(n.left_or_first, n.tri_count)));
            } else {
                let idx = out.len();
                out.push(Vec::new());
                out[w].push((i, idx as u32));
                interior.push((i, idx));
            }
        }
        // Reversed so the leftmost child's subtree is filled first.
        tasks.extend(interior.into_iter().rev());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leaf_refs_round_trip() {
        for (first, count) in [
            (0, 1),
            (7, 4),
            (MAX_LEAF_FIRST, MAX_LEAF_SIZE as u32),
            (1 << 24, 3),
        ] {
            let r = leaf_ref(first, count);
            assert!(is_leaf_ref(r) && r != SLOT_EMPTY);
            assert_eq!(leaf_range(r), (first as usize, count as usize));
        }
        assert!(!is_leaf_ref(12345));
    }
}
