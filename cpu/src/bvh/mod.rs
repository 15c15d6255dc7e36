//! Bounding volume hierarchy over world-space triangles.
//!
//! - [`build`](Bvh::build): binned SAH (Wald 2007, "On fast construction of
//!   SAH-based bounding volume hierarchies"), flattened into tinybvh's 32-byte
//!   node layout with sibling pairs adjacent; depth is capped so the GPU's
//!   fixed traversal stack of [`STACK_SIZE`] entries can never overflow.
//! - traversal: a robust slab test (Ize 2013, "Robust BVH ray traversal") and
//!   the watertight ray/triangle test (Woop, Benthin, Wald 2013, JCGT 2(1)).
//!
//! `shaders/bvh.glsl` mirrors this module function for function with the same
//! names (`prepare_ray`, `intersect_aabb`, `intersect_triangle`,
//! `bvh_intersect`, `bvh_occluded`), so a CPU/GPU mismatch can be pinned to one
//! of them.

mod build;
mod traverse;

use std::mem::size_of;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::scene::Triangle;

pub use traverse::{PreparedRay, intersect_aabb, intersect_triangle};

/// Entries of the traversal stack (CPU and GPU). The builder guarantees every
/// leaf is at depth `<= MAX_DEPTH < STACK_SIZE`, and front-to-back traversal
/// pushes at most one node per level, so the stack never overflows.
pub const STACK_SIZE: usize = 64;
/// Deepest node the builder creates (root at depth 0).
pub const MAX_DEPTH: usize = 48;
/// The builder never makes leaves larger than this.
pub const MAX_LEAF_SIZE: usize = 4;

/// tinybvh's 32-byte node, read unchanged by the GPU as two `vec4`s (the
/// integers in `.w` through `floatBitsToUint`). Leaf when `tri_count > 0`:
/// triangles `[left_or_first, left_or_first + tri_count)` of the (reordered)
/// triangle array. Interior: children `left_or_first` and `left_or_first + 1`.
/// Node 0 is the root.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    pub aabb_min: [f32; 3],
    pub left_or_first: u32,
    pub aabb_max: [f32; 3],
    pub tri_count: u32,
}
const _: () = assert!(size_of::<BvhNode>() == 32);

impl BvhNode {
    pub fn is_leaf(&self) -> bool {
        self.tri_count > 0
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub o: Vec3,
    pub d: Vec3,
    /// Hits are accepted in (0, tmax): callers offset origins themselves.
    pub tmax: f32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    /// Index into the (reordered) triangle array.
    pub tri: u32,
    /// Barycentrics: p = (1 - u - v) p0 + u p1 + v p2.
    pub u: f32,
    pub v: f32,
}

#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
}

impl Bvh {
    /// Binned-SAH build. Returns the BVH and the triangle order it expects:
    /// `order[i]` is the input index of the triangle at position i.
    /// Deterministic: the same input gives the same nodes and order.
    /// Empty input gives no nodes, and every query on it misses.
    pub fn build(tris: &[Triangle]) -> (Bvh, Vec<u32>) {
        let (nodes, order) = build::build(tris);
        (Bvh { nodes }, order)
    }

    /// Closest hit in (0, ray.tmax), watertight (Woop, Benthin, Wald 2013).
    /// `tris` must be in the order [`Bvh::build`] returned.
    pub fn intersect(&self, tris: &[Triangle], ray: &Ray) -> Option<Hit> {
        traverse::intersect(&self.nodes, tris, ray, |_, _, _| true)
    }

    /// Any hit in (0, ray.tmax).
    pub fn occluded(&self, tris: &[Triangle], ray: &Ray) -> bool {
        traverse::occluded(&self.nodes, tris, ray, |_, _, _| true)
    }

    /// [`Bvh::intersect`] skipping hits where `present(tri, u, v)` is false
    /// (alpha masks).
    pub fn intersect_masked(
        &self,
        tris: &[Triangle],
        ray: &Ray,
        present: impl Fn(u32, f32, f32) -> bool,
    ) -> Option<Hit> {
        traverse::intersect(&self.nodes, tris, ray, present)
    }

    /// [`Bvh::occluded`] skipping hits where `present(tri, u, v)` is false.
    pub fn occluded_masked(
        &self,
        tris: &[Triangle],
        ray: &Ray,
        present: impl Fn(u32, f32, f32) -> bool,
    ) -> bool {
        traverse::occluded(&self.nodes, tris, ray, present)
    }

    /// Depth of the deepest node (root = 0); 0 for an empty hierarchy.
    pub fn depth(&self) -> usize {
        if self.nodes.is_empty() {
            return 0;
        }
        let mut deepest = 0;
        let mut stack = vec![(0usize, 0usize)];
        while let Some((i, d)) = stack.pop() {
            deepest = deepest.max(d);
            let n = &self.nodes[i];
            if !n.is_leaf() {
                let l = n.left_or_first as usize;
                stack.push((l, d + 1));
                stack.push((l + 1, d + 1));
            }
        }
        deepest
    }
}
