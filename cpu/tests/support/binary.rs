//! The binary BVH's traversal: the reference the 4-wide traversals (CPU and
//! GPU) are tested against ray for ray. No render uses it, so it lives with
//! the tests (`#[path]`-included by `cpu/tests` and the root `tests`); the
//! box and triangle tests it calls are the library's own, which the wide
//! traversals share. `shaders/bvh.glsl`'s `BVH_BINARY` half is its GLSL
//! twin, compiled only into the test kernel `shaders/tests/bvh2_test.comp`.

#![allow(dead_code)]

use glam::Vec3;
use glint_cpu::bvh::{
    Bvh, BvhNode, Hit, PreparedRay, Ray, STACK_SIZE, intersect_aabb, intersect_triangle,
};
use glint_cpu::scene::Triangle;

/// Queries on the binary tree (`tris` in the order `Bvh::build` returned).
pub trait BinaryTraversal {
    /// Closest hit in (0, ray.tmax), watertight (Woop, Benthin, Wald 2013).
    fn intersect(&self, tris: &[Triangle], ray: &Ray) -> Option<Hit>;
    /// Any hit in (0, ray.tmax).
    fn occluded(&self, tris: &[Triangle], ray: &Ray) -> bool;
    /// `intersect` skipping hits where `present(tri, u, v)` is false
    /// (alpha masks).
    fn intersect_masked(
        &self,
        tris: &[Triangle],
        ray: &Ray,
        present: impl Fn(u32, f32, f32) -> bool,
    ) -> Option<Hit>;
    /// `occluded` skipping hits where `present(tri, u, v)` is false.
    fn occluded_masked(
        &self,
        tris: &[Triangle],
        ray: &Ray,
        present: impl Fn(u32, f32, f32) -> bool,
    ) -> bool;
}

impl BinaryTraversal for Bvh {
    fn intersect(&self, tris: &[Triangle], ray: &Ray) -> Option<Hit> {
        intersect(&self.nodes, tris, ray, |_, _, _| true)
    }
    fn occluded(&self, tris: &[Triangle], ray: &Ray) -> bool {
        occluded(&self.nodes, tris, ray, |_, _, _| true)
    }
    fn intersect_masked(
        &self,
        tris: &[Triangle],
        ray: &Ray,
        present: impl Fn(u32, f32, f32) -> bool,
    ) -> Option<Hit> {
        intersect(&self.nodes, tris, ray, present)
    }
    fn occluded_masked(
        &self,
        tris: &[Triangle],
        ray: &Ray,
        present: impl Fn(u32, f32, f32) -> bool,
    ) -> bool {
        occluded(&self.nodes, tris, ray, present)
    }
}

fn node_box(n: &BvhNode) -> (Vec3, Vec3) {
    (n.aabb_min.into(), n.aabb_max.into())
}

/// Closest hit: front-to-back (nearer child first, the other pushed), the
/// search interval shrinking to the best hit so far (tinybvh's `Intersect`).
/// `present(tri, u, v)` is the alpha-mask hook at the leaf triangle test: a
/// hit where it returns false is not there (`|_, _, _| true` compiles away).
pub fn intersect<F: Fn(u32, f32, f32) -> bool>(
    nodes: &[BvhNode],
    tris: &[Triangle],
    ray: &Ray,
    present: F,
) -> Option<Hit> {
    if nodes.is_empty() {
        return None;
    }
    let r = PreparedRay::new(ray.o, ray.d);
    let (bmin, bmax) = node_box(&nodes[0]);
    if intersect_aabb(&r, bmin, bmax, ray.tmax) == f32::INFINITY {
        return None;
    }
    let mut best = Hit {
        t: ray.tmax,
        tri: u32::MAX,
        u: 0.0,
        v: 0.0,
    };
    let mut stack = [0u32; STACK_SIZE];
    let mut sp = 0;
    let mut node = 0usize;
    loop {
        let n = &nodes[node];
        if n.is_leaf() {
            let first = n.left_or_first as usize;
            let leaf = &tris[first..first + n.tri_count as usize];
            for (i, tri) in (first..).zip(leaf) {
                if let Some((t, u, v)) = intersect_triangle(&r, tri, best.t)
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
            let mut c1 = n.left_or_first as usize;
            let mut c2 = c1 + 1;
            let (min1, max1) = node_box(&nodes[c1]);
            let (min2, max2) = node_box(&nodes[c2]);
            let mut d1 = intersect_aabb(&r, min1, max1, best.t);
            let mut d2 = intersect_aabb(&r, min2, max2, best.t);
            if d1 > d2 {
                std::mem::swap(&mut d1, &mut d2);
                std::mem::swap(&mut c1, &mut c2);
            }
            if d1 != f32::INFINITY {
                if d2 != f32::INFINITY {
                    stack[sp] = c2 as u32;
                    sp += 1;
                }
                node = c1;
                continue;
            }
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        node = stack[sp] as usize;
    }
    (best.tri != u32::MAX).then_some(best)
}

/// Any hit: the first triangle hit in (0, tmax) ends the search. Children
/// are still visited nearer first, as tinybvh's `IsOccluded` does: the near
/// side is the likelier to hold a blocker.
pub fn occluded<F: Fn(u32, f32, f32) -> bool>(
    nodes: &[BvhNode],
    tris: &[Triangle],
    ray: &Ray,
    present: F,
) -> bool {
    if nodes.is_empty() {
        return false;
    }
    let r = PreparedRay::new(ray.o, ray.d);
    let (bmin, bmax) = node_box(&nodes[0]);
    if intersect_aabb(&r, bmin, bmax, ray.tmax) == f32::INFINITY {
        return false;
    }
    let mut stack = [0u32; STACK_SIZE];
    let mut sp = 0;
    let mut node = 0usize;
    loop {
        let n = &nodes[node];
        if n.is_leaf() {
            let first = n.left_or_first as usize;
            let leaf = &tris[first..first + n.tri_count as usize];
            if (first..).zip(leaf).any(|(i, tri)| {
                intersect_triangle(&r, tri, ray.tmax)
                    .is_some_and(|(_, u, v)| present(i as u32, u, v))
            }) {
                return true;
            }
        } else {
            let mut c1 = n.left_or_first as usize;
            let mut c2 = c1 + 1;
            let (min1, max1) = node_box(&nodes[c1]);
            let (min2, max2) = node_box(&nodes[c2]);
            let mut d1 = intersect_aabb(&r, min1, max1, ray.tmax);
            let mut d2 = intersect_aabb(&r, min2, max2, ray.tmax);
            if d1 > d2 {
                std::mem::swap(&mut d1, &mut d2);
                std::mem::swap(&mut c1, &mut c2);
            }
            if d1 != f32::INFINITY {
                if d2 != f32::INFINITY {
                    stack[sp] = c2 as u32;
                    sp += 1;
                }
                node = c1;
                continue;
            }
        }
        if sp == 0 {
            return false;
        }
        sp -= 1;
        node = stack[sp] as usize;
    }
}
