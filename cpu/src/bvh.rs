//! Bounding volume hierarchy over world-space triangles.
//!
//! INTERFACE FIXED BY THE LEAD; bodies owned by the BVH work (replace the
//! `todo!`s, keep the signatures and the node layout; add what is needed).

use std::mem::size_of;

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::scene::Triangle;

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
    pub fn build(tris: &[Triangle]) -> (Bvh, Vec<u32>) {
        let _ = tris;
        todo!("BVH work")
    }

    /// Closest hit in (0, ray.tmax), watertight (Woop, Benthin, Wald 2013).
    pub fn intersect(&self, tris: &[Triangle], ray: &Ray) -> Option<Hit> {
        let _ = (tris, ray);
        todo!("BVH work")
    }

    /// Any hit in (0, ray.tmax).
    pub fn occluded(&self, tris: &[Triangle], ray: &Ray) -> bool {
        let _ = (tris, ray);
        todo!("BVH work")
    }
}
