//! Bounding volume hierarchy over world-space triangles.
//!
//! - [`build`](Bvh::build): binned SAH (Wald 2007, "On fast construction of
//!   SAH-based bounding volume hierarchies"), flattened into tinybvh's 32-byte
//!   node layout with sibling pairs adjacent; depth is capped so the GPU's
//!   fixed traversal stack of [`STACK_SIZE`] entries can never overflow.
//! - traversal: a robust slab test (Ize 2013, "Robust BVH ray traversal") and
//!   the watertight ray/triangle test (Woop, Benthin, Wald 2013, JCGT 2(1)).
//!
//! - [`Bvh4`]: the binary tree collapsed into 4-wide nodes ([`Bvh4Node`],
//!   `wide.rs`), traversed with one SIMD box test per node (`wide_traverse.rs`),
//!   and the CPU's 8-wide tree (`wide8.rs`, from a second binary build priced
//!   for its leaf blocks; a pixel's camera rays traverse it as one packet,
//!   `packet.rs`). Renders use them; the binary tree stays the reference the
//!   wide ones are tested against (its traversal lives with the tests, in
//!   `cpu/tests/support/binary.rs`: no render uses it).
//!
//! `shaders/bvh.glsl` mirrors this module function for function with the same
//! names (`prepare_ray`, `intersect_aabb`, `intersect_triangle`,
//! `intersect_aabb4`, `sort4`, `bvh_intersect`, `bvh_occluded`), so a CPU/GPU
//! mismatch can be pinned to one of them.

mod build;
mod packet;
mod traverse;
mod wide;
mod wide8;
mod wide_traverse;

use glam::Vec3;

use crate::scene::Triangle;

pub use packet::PACKET;
pub use traverse::{PreparedRay, SLAB_PAD, intersect_aabb, intersect_triangle};
pub use wide::{
    Bvh4Node, LEAF_BIT, MAX_WIDE_DEPTH, SLOT_EMPTY, WIDE_STACK_SIZE, WIDTH, is_leaf_ref, leaf_range,
};
use wide_traverse::Avx2;
pub use wide_traverse::Kernel;
pub use wide8::{Bvh8Node, LeafBlock, WIDE8_STACK_SIZE, WIDTH8};

/// Entries of the traversal stack (CPU and GPU). The builder guarantees every
/// leaf is at depth `<= MAX_DEPTH < STACK_SIZE`, and front-to-back traversal
/// pushes at most one node per level, so the stack never overflows.
pub const STACK_SIZE: usize = crate::abi::BVH_STACK_SIZE;
/// Deepest node the builder creates (root at depth 0).
pub const MAX_DEPTH: usize = 48;
/// The builder never makes leaves larger than this.
pub const MAX_LEAF_SIZE: usize = 4;

pub use crate::abi::BvhNode;

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
        let (nodes, order) = build::build(tris, build::LeafCost::Triangles);
        (Bvh { nodes }, order)
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

/// The trees the renderers traverse: the 4-wide one (see `wide.rs`), a
/// binary tree's leaves and boxes regrouped four to a node, which the GPU
/// and CPUs without AVX2 read; and the 8-wide one. Node 0 is the root;
/// empty for an empty scene.
#[derive(Clone, Debug, Default)]
pub struct Bvh4 {
    pub nodes: Vec<Bvh4Node>,
    /// The 8-wide tree (`wide8.rs`), which CPUs with AVX2 traverse
    /// ([`Kernel::Avx2x8`]): in a render, collapsed from a binary tree of
    /// its own ([`Bvh4::build`]); from `nodes`' binary tree with
    /// [`Bvh4::collapse`].
    pub nodes8: Vec<Bvh8Node>,
    /// The 8-wide tree's leaves: each leaf's triangles side by side.
    pub blocks: Vec<LeafBlock>,
    /// Where the CPU has AVX2 (detected once, when the tree is made): the
    /// default queries then take the 8-wide tree with no test per ray.
    avx2: Option<Avx2>,
}

impl Bvh4 {
    /// The renderers' trees, and the triangle order the scene takes: the
    /// 4-wide one (the GPU's) is [`Bvh::build`]'s binary tree collapsed,
    /// its leaves ranges of that order; the 8-wide one (the CPU's) is
    /// collapsed from a binary tree of its own, built with the SAH cost of
    /// the CPU's leaf test (a block of up to four triangles tests at the
    /// cost of one, `build::LeafCost::Blocks`), its blocks naming their
    /// triangles by their index in that order. The two builds run side by
    /// side (rayon).
    pub fn build(tris: &[Triangle]) -> (Bvh4, Vec<u32>) {
        let ((bvh, order), (bin8, order8)) = rayon::join(
            || Bvh::build(tris),
            || build::build(tris, build::LeafCost::Blocks),
        );
        // Where each input triangle lands in the scene's order.
        let mut scene_index = vec![0u32; tris.len()];
        for (pos, &i) in order.iter().enumerate() {
            scene_index[i as usize] = pos as u32;
        }
        let tris8: Vec<Triangle> = order8.iter().map(|&i| tris[i as usize]).collect();
        let (nodes8, blocks) = wide8::collapse8(&bin8, &tris8, |p| scene_index[order8[p] as usize]);
        let wide = Bvh4 {
            nodes: wide::collapse(&bvh.nodes),
            nodes8,
            blocks,
            avx2: Avx2::detect(),
        };
        (wide, order)
    }

    /// Regroups a binary BVH four children to a node, and eight to a node
    /// with its leaves' triangles (`tris`, in the order the build returned)
    /// side by side; leaves, their triangle ranges and every child box are
    /// kept unchanged: both widths have the binary tree's leaves (what the
    /// tests compare with the binary reference traversal).
    pub fn collapse(bvh: &Bvh, tris: &[Triangle]) -> Bvh4 {
        let (nodes8, blocks) = wide8::collapse8(&bvh.nodes, tris, |i| i as u32);
        Bvh4 {
            nodes: wide::collapse(&bvh.nodes),
            nodes8,
            blocks,
            avx2: Avx2::detect(),
        }
    }

    /// Closest hit in (0, ray.tmax), the binary traversal's answer
    /// ([`Bvh::intersect`]) with the fastest box test this CPU has.
    pub fn intersect(&self, tris: &[Triangle], ray: &Ray) -> Option<Hit> {
        match self.avx2 {
            Some(avx2) => {
                wide_traverse::intersect8(avx2, &self.nodes8, &self.blocks, ray, |_, _, _| true)
            }
            None => self.intersect_with(Kernel::best(), tris, ray),
        }
    }

    /// [`Bvh4::intersect`] of the rays in `live` (bit k: `rays[k]`), into
    /// `hits` (which starts all None; the other lanes stay so): in one
    /// packet traversal (`packet.rs`) where the CPU has AVX2 and the rays'
    /// directions agree in sign on every axis, else one ray at a time.
    /// Each ray's closest distance is [`Bvh4::intersect`]'s (an exact tie
    /// may pick the other triangle).
    #[inline]
    pub fn intersect_packet(
        &self,
        tris: &[Triangle],
        rays: &[Ray; PACKET],
        live: u8,
        hits: &mut [Option<Hit>; PACKET],
    ) {
        let (nodes, blocks) = (&self.nodes8, &self.blocks);
        if !packet::intersect_packet8(self.avx2, nodes, blocks, rays, live, hits) {
            for k in crate::lanes::live_lanes(live) {
                hits[k] = self.intersect(tris, &rays[k]);
            }
        }
    }

    /// The packet traversal of [`Bvh4::intersect_packet`] alone: None
    /// where it does not apply (no AVX2, or rays that differ in a
    /// direction's sign or dominant axis, or have a zero component).
    pub fn intersect_packet_only(
        &self,
        rays: &[Ray; PACKET],
        live: u8,
    ) -> Option<[Option<Hit>; PACKET]> {
        let mut hits = [None; PACKET];
        packet::intersect_packet8(self.avx2, &self.nodes8, &self.blocks, rays, live, &mut hits)
            .then_some(hits)
    }

    /// Any hit in (0, ray.tmax).
    pub fn occluded(&self, tris: &[Triangle], ray: &Ray) -> bool {
        match self.avx2 {
            Some(avx2) => {
                wide_traverse::any_hit8(avx2, &self.nodes8, &self.blocks, ray, |_, _, _| true)
            }
            None => self.occluded_with(Kernel::best(), tris, ray),
        }
    }

    /// [`Bvh4::intersect`] skipping hits where `present(tri, u, v)` is
    /// false (alpha masks).
    pub fn intersect_masked(
        &self,
        tris: &[Triangle],
        ray: &Ray,
        present: impl Fn(u32, f32, f32) -> bool,
    ) -> Option<Hit> {
        match self.avx2 {
            Some(avx2) => wide_traverse::intersect8(avx2, &self.nodes8, &self.blocks, ray, present),
            None => self.intersect_masked_with(Kernel::best(), tris, ray, present),
        }
    }

    /// [`Bvh4::intersect_masked`] with a given kernel: the 8-wide tree
    /// for [`Kernel::Avx2x8`], else the 4-wide one with scalar box tests.
    pub fn intersect_masked_with(
        &self,
        kernel: Kernel,
        tris: &[Triangle],
        ray: &Ray,
        present: impl Fn(u32, f32, f32) -> bool,
    ) -> Option<Hit> {
        match (kernel, Avx2::detect()) {
            (Kernel::Avx2x8, Some(avx2)) => {
                wide_traverse::intersect8(avx2, &self.nodes8, &self.blocks, ray, present)
            }
            _ => wide_traverse::intersect_masked(&self.nodes, tris, ray, present),
        }
    }

    /// [`Bvh4::occluded`] skipping hits where `present(tri, u, v)` is false.
    pub fn occluded_masked(
        &self,
        tris: &[Triangle],
        ray: &Ray,
        present: impl Fn(u32, f32, f32) -> bool,
    ) -> bool {
        match self.avx2 {
            Some(avx2) => wide_traverse::any_hit8(avx2, &self.nodes8, &self.blocks, ray, present),
            None => self.occluded_masked_with(Kernel::best(), tris, ray, present),
        }
    }

    /// [`Bvh4::occluded_masked`] with a given kernel.
    pub fn occluded_masked_with(
        &self,
        kernel: Kernel,
        tris: &[Triangle],
        ray: &Ray,
        present: impl Fn(u32, f32, f32) -> bool,
    ) -> bool {
        match (kernel, Avx2::detect()) {
            (Kernel::Avx2x8, Some(avx2)) => {
                wide_traverse::any_hit8(avx2, &self.nodes8, &self.blocks, ray, present)
            }
            _ => wide_traverse::occluded_masked(&self.nodes, tris, ray, present),
        }
    }

    /// [`Bvh4::intersect`] with a given box-test kernel (for tests and
    /// benchmarks; an unsupported one falls back to one the CPU has).
    pub fn intersect_with(&self, kernel: Kernel, tris: &[Triangle], ray: &Ray) -> Option<Hit> {
        match (kernel, Avx2::detect()) {
            (Kernel::Avx2x8, Some(avx2)) => {
                wide_traverse::intersect8(avx2, &self.nodes8, &self.blocks, ray, |_, _, _| true)
            }
            _ => wide_traverse::intersect(&self.nodes, tris, ray, kernel),
        }
    }

    /// [`Bvh4::occluded`] with a given box-test kernel.
    pub fn occluded_with(&self, kernel: Kernel, tris: &[Triangle], ray: &Ray) -> bool {
        match (kernel, Avx2::detect()) {
            (Kernel::Avx2x8, Some(avx2)) => {
                wide_traverse::any_hit8(avx2, &self.nodes8, &self.blocks, ray, |_, _, _| true)
            }
            _ => wide_traverse::any_hit(&self.nodes, tris, ray, kernel),
        }
    }

    /// Depth of the deepest 8-wide node (root = 0).
    pub fn depth8(&self) -> usize {
        wide8::depth8(&self.nodes8)
    }

    /// Depth of the deepest wide node (root = 0); 0 for an empty hierarchy.
    pub fn depth(&self) -> usize {
        if self.nodes.is_empty() {
            return 0;
        }
        let mut deepest = 0;
        let mut stack = vec![(0usize, 0usize)];
        while let Some((i, d)) = stack.pop() {
            deepest = deepest.max(d);
            for &c in &self.nodes[i].child {
                if c != SLOT_EMPTY && !is_leaf_ref(c) {
                    stack.push((c as usize, d + 1));
                }
            }
        }
        deepest
    }
}
