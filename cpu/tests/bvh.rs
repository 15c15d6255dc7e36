//! BVH tests: structure invariants, differential closest/any-hit against brute
//! force (tinybvh's test), watertightness on closed meshes and the bunny; each
//! for the binary BVH and for the 4-wide BVH with every box-test kernel the
//! CPU runs (scalar, SSE2, AVX), which must agree with the binary one.

#[path = "support/binary.rs"]
mod binary;
#[path = "support/geometry.rs"]
mod geometry;
use binary::BinaryTraversal;

use std::collections::HashMap;
use std::time::Instant;

use glam::Vec3;
use glint_cpu::bvh::{
    Kernel, MAX_DEPTH, MAX_LEAF_SIZE, MAX_WIDE_DEPTH, PreparedRay, SLOT_EMPTY, STACK_SIZE, WIDTH,
    intersect_triangle, is_leaf_ref, leaf_range,
};
use glint_cpu::{Bvh, Bvh4, Bvh4Node, Hit, Ray, Triangle};
use rayon::prelude::*;

use geometry::{
    Pcg32, bounds_of, bunny, grid_cube, nasty_soup, random_rays, random_soup, rays_from_surfaces,
    tri,
};

/// Builds and applies the order, as `Scene::build_bvh` does.
fn build(input: &[Triangle]) -> (Bvh, Vec<Triangle>, Vec<u32>) {
    let (bvh, order) = Bvh::build(input);
    let tris = order.iter().map(|&i| input[i as usize]).collect();
    (bvh, tris, order)
}

/// The reference: every triangle, lowest index wins exact ties.
fn brute_closest(tris: &[Triangle], ray: &Ray) -> Option<Hit> {
    let r = PreparedRay::new(ray.o, ray.d);
    let mut best: Option<Hit> = None;
    for (i, t) in tris.iter().enumerate() {
        let tmax = best.map_or(ray.tmax, |h| h.t);
        if let Some((t, u, v)) = intersect_triangle(&r, t, tmax) {
            best = Some(Hit {
                t,
                tri: i as u32,
                u,
                v,
            });
        }
    }
    best
}

/// Checks the layout every consumer relies on; returns (leaves, depth).
fn check_structure(bvh: &Bvh, tris: &[Triangle], order: &[u32]) -> (usize, usize) {
    let n = tris.len();
    let mut seen = vec![false; n];
    for &i in order {
        assert!(
            !std::mem::replace(&mut seen[i as usize], true),
            "order is not a permutation"
        );
    }
    assert!(seen.iter().all(|&s| s), "order is not a permutation");
    if n == 0 {
        assert!(bvh.nodes.is_empty());
        return (0, 0);
    }
    let nodes = &bvh.nodes;
    let mut covered = vec![0u32; n];
    let mut visited = vec![false; nodes.len()];
    let mut leaves = 0;
    let mut depth = 0;
    let mut stack = vec![(0usize, 0usize)];
    while let Some((i, d)) = stack.pop() {
        assert!(
            !std::mem::replace(&mut visited[i], true),
            "node {i} reached twice"
        );
        depth = depth.max(d);
        let node = &nodes[i];
        let (lo, hi) = (Vec3::from(node.aabb_min), Vec3::from(node.aabb_max));
        if node.is_leaf() {
            leaves += 1;
            assert!(
                node.tri_count as usize <= MAX_LEAF_SIZE,
                "leaf of {}",
                node.tri_count
            );
            let first = node.left_or_first as usize;
            for t in first..first + node.tri_count as usize {
                covered[t] += 1;
                // Non-finite triangles are binned as a point at the origin.
                let finite = tris[t].vertices().iter().all(|p| p.is_finite());
                for p in tris[t].vertices() {
                    if finite {
                        assert!(
                            p.cmpge(lo).all() && p.cmple(hi).all(),
                            "triangle outside its leaf"
                        );
                    }
                }
            }
        } else {
            let l = node.left_or_first as usize;
            assert!(l > i && l + 1 < nodes.len(), "children of {i} out of range");
            for c in [l, l + 1] {
                let ch = &nodes[c];
                assert!(
                    Vec3::from(ch.aabb_min).cmpge(lo).all()
                        && Vec3::from(ch.aabb_max).cmple(hi).all(),
                    "child {c} outside parent {i}"
                );
                stack.push((c, d + 1));
            }
        }
    }
    assert!(visited.iter().all(|&v| v), "unreachable nodes");
    assert!(
        covered.iter().all(|&c| c == 1),
        "a triangle is not in exactly one leaf"
    );
    assert_eq!(nodes.len(), 2 * leaves - 1);
    assert!(
        depth <= MAX_DEPTH && MAX_DEPTH < STACK_SIZE,
        "depth {depth}"
    );
    assert_eq!(bvh.depth(), depth);
    (leaves, depth)
}

/// The binary BVH and its 4-wide collapse, traversed every way there is.
struct Traversals {
    bin: Bvh,
    wide: Bvh4,
    kernels: Vec<Kernel>,
}

impl Traversals {
    fn new(bin: Bvh, tris: &[Triangle]) -> Self {
        let wide = Bvh4::collapse(&bin, tris);
        Traversals {
            bin,
            wide,
            kernels: Kernel::available(),
        }
    }

    /// (name, closest hit, occluded) of each traversal, the binary first.
    fn each(&self, tris: &[Triangle], ray: &Ray) -> Vec<(String, Option<Hit>, bool)> {
        let mut out = vec![(
            "binary".to_string(),
            self.bin.intersect(tris, ray),
            self.bin.occluded(tris, ray),
        )];
        for &k in &self.kernels {
            out.push((
                format!("wide {k:?}"),
                self.wide.intersect_with(k, tris, ray),
                self.wide.occluded_with(k, tris, ray),
            ));
        }
        out
    }
}

/// The wide BVH's invariants against the binary tree it was collapsed from:
/// exactly the binary leaves (so every triangle in exactly one leaf), child
/// boxes inside the parent's box, full nodes (>= 2 children, empty slots last
/// and empty), the node count between ceil((L - 1) / 3) and L - 1 for L binary
/// leaves (each wide node absorbs 1..=3 binary interior nodes), and the depth
/// within MAX_WIDE_DEPTH and about half the binary depth. Returns the depth.
fn check_wide_structure(wide: &Bvh4, bin: &Bvh, tris: &[Triangle]) -> usize {
    if bin.nodes.is_empty() {
        assert!(wide.nodes.is_empty());
        return 0;
    }
    let nodes = &wide.nodes;
    let mut bin_leaves: Vec<(usize, usize)> = bin
        .nodes
        .iter()
        .filter(|n| n.is_leaf())
        .map(|n| (n.left_or_first as usize, n.tri_count as usize))
        .collect();
    let mut leaves = Vec::new();
    let mut visited = vec![false; nodes.len()];
    let mut depth = 0;
    let (root_lo, root_hi) = (
        Vec3::from(bin.nodes[0].aabb_min),
        Vec3::from(bin.nodes[0].aabb_max),
    );
    let mut stack = vec![(0usize, 0usize, root_lo, root_hi)];
    while let Some((i, d, plo, phi)) = stack.pop() {
        assert!(
            !std::mem::replace(&mut visited[i], true),
            "wide node {i} reached twice"
        );
        depth = depth.max(d);
        let node: &Bvh4Node = &nodes[i];
        assert_eq!(node._pad, [0; 4]);
        let used = node.child_count();
        assert!(
            used >= 2 || (nodes.len() == 1 && used == 1),
            "node {i} has {used} children"
        );
        for s in 0..WIDTH {
            let (lo, hi) = node.child_box(s);
            let c = node.child[s];
            if s >= used {
                assert_eq!(c, SLOT_EMPTY, "node {i}: a used slot after an empty one");
                assert!(lo == Vec3::INFINITY && hi == Vec3::NEG_INFINITY);
                continue;
            }
            assert!(
                lo.cmpge(plo).all() && hi.cmple(phi).all() && lo.cmple(hi).all(),
                "child {s} of wide node {i} outside its parent"
            );
            if is_leaf_ref(c) {
                let (first, count) = leaf_range(c);
                leaves.push((first, count));
                for t in &tris[first..first + count] {
                    if t.vertices().iter().all(|p| p.is_finite()) {
                        for p in t.vertices() {
                            assert!(p.cmpge(lo).all() && p.cmple(hi).all());
                        }
                    }
                }
            } else {
                assert!((c as usize) < nodes.len() && c as usize > i);
                stack.push((c as usize, d + 1, lo, hi));
            }
        }
    }
    assert!(visited.iter().all(|&v| v), "unreachable wide nodes");
    bin_leaves.sort();
    leaves.sort();
    assert_eq!(
        leaves, bin_leaves,
        "the wide leaves are not the binary leaves"
    );
    let l = bin_leaves.len();
    assert!(
        nodes.len() >= (l - 1).div_ceil(3) && nodes.len() <= (l - 1).max(1),
        "{} wide nodes for {l} leaves",
        nodes.len()
    );
    let bin_depth = bin.depth();
    assert!(depth <= MAX_WIDE_DEPTH && depth <= bin_depth.saturating_sub(1) / 2);
    assert_eq!(wide.depth(), depth);
    check_wide8_structure(wide, bin, tris, &bin_leaves);
    depth
}

/// The 8-wide tree of `wide` collapsed from `bin` ([`check_tree8`]'s
/// invariants), its root's boxes inside the binary root's, and its leaves
/// exactly the binary leaves: each block the binary leaf's range of
/// triangles in order.
fn check_wide8_structure(wide: &Bvh4, bin: &Bvh, tris: &[Triangle], bin_leaves: &[(usize, usize)]) {
    let (rlo, rhi) = (
        Vec3::from(bin.nodes[0].aabb_min),
        Vec3::from(bin.nodes[0].aabb_max),
    );
    let root = &wide.nodes8[0];
    for s in 0..root.child_count() {
        let lo = Vec3::new(root.lo_x[s], root.lo_y[s], root.lo_z[s]);
        let hi = Vec3::new(root.hi_x[s], root.hi_y[s], root.hi_z[s]);
        assert!(lo.cmpge(rlo).all() && hi.cmple(rhi).all());
    }
    let mut leaves: Vec<(usize, usize)> = check_tree8(wide, tris)
        .iter()
        .map(|ids| {
            let first = ids[0] as usize;
            for (j, &id) in ids.iter().enumerate() {
                assert_eq!(
                    id as usize,
                    first + j,
                    "a block that is not a binary leaf's range"
                );
            }
            (first, ids.len())
        })
        .collect();
    leaves.sort();
    assert_eq!(
        leaves, bin_leaves,
        "the 8-wide leaves are not the binary leaves"
    );
}

/// Every traversal of `t` against the binary one on `ray`: the same closest
/// hit exactly (the wide BVH tests the same boxes and triangles), except
/// another triangle at exactly the same distance (visit order decides exact
/// ties); the same occlusion, except for a hit within rounding of tmax.
fn assert_traversals_agree(name: &str, t: &Traversals, tris: &[Triangle], ray: &Ray) {
    let all = t.each(tris, ray);
    let (_, want, want_occ) = &all[0];
    for (which, got, occ) in &all[1..] {
        match (got, want) {
            (Some(g), Some(w)) if g.tri != w.tri => {
                assert_eq!(g.t, w.t, "{name} {which}: {ray:?}: {g:?} binary {w:?}")
            }
            _ => assert_eq!(got, want, "{name} {which}: {ray:?}"),
        }
        if occ != want_occ {
            let near_tmax = |t: f32| (t - ray.tmax).abs() <= 1e-5 * ray.tmax;
            assert!(
                brute_any_t(tris, ray).is_some_and(near_tmax),
                "{name} {which}: occluded {occ}, binary {want_occ}, {ray:?}"
            );
        }
    }
}

#[derive(Default, Debug)]
struct Diff {
    rays: usize,
    hits: usize,
    /// Different triangle at an equal distance (coplanar or shared edges).
    tie_swaps: usize,
    /// Different triangle, distances within the tolerance but not equal.
    near_swaps: usize,
}

/// BVH vs brute force on every ray: same triangle (or a tie within 2e-5
/// relative), same occlusion, and barycentrics that rebuild the hit point.
fn differential(name: &str, input: &[Triangle], rays: &[Ray]) -> Diff {
    let (bvh, tris, order) = build(input);
    check_structure(&bvh, &tris, &order);
    let all = Traversals::new(bvh.clone(), &tris);
    check_wide_structure(&all.wide, &bvh, &tris);
    let (render, render_order) = Bvh4::build(input);
    assert_eq!(render_order, order, "{name}: the render's triangle order");
    check_tree8(&render, &tris);
    let results: Vec<Diff> = rays
        .par_chunks(256)
        .map(|chunk| {
            let mut diff = Diff::default();
            for ray in chunk {
                diff.rays += 1;
                let got = bvh.intersect(&tris, ray);
                let want = brute_closest(&tris, ray);
                let occluded = bvh.occluded(&tris, ray);
                assert_traversals_agree(name, &all, &tris, ray);
                assert_render_tree_agrees(name, &render, &tris, ray, got, occluded);
                match (got, want) {
                    (None, None) => {}
                    (Some(g), Some(w)) => {
                        diff.hits += 1;
                        if g.tri != w.tri {
                            let rel = (g.t - w.t).abs() / w.t.abs().max(f32::MIN_POSITIVE);
                            assert!(rel <= 2e-5, "{name}: {ray:?}: bvh {g:?} brute {w:?}");
                            if g.t == w.t {
                                diff.tie_swaps += 1;
                            } else {
                                diff.near_swaps += 1;
                            }
                        } else {
                            assert_eq!(g, w, "{name}: {ray:?}");
                        }
                        let [a, b, c] = tris[g.tri as usize].vertices();
                        let p = (1.0 - g.u - g.v) * a + g.u * b + g.v * c;
                        let q = ray.o + g.t * ray.d;
                        let scale = a
                            .abs()
                            .max(b.abs())
                            .max(c.abs())
                            .max(ray.o.abs())
                            .max((g.t * ray.d).abs())
                            .max_element();
                        // Barycentrics of a near-zero-area sliver (the
                        // nasty soup's collinear triangles) are ill-conditioned:
                        // check the well-shaped ones.
                        let edge2 = (b - a).length_squared().max((c - a).length_squared());
                        let well_shaped = (b - a).cross(c - a).length() > 1e-3 * edge2;
                        assert!(
                            !well_shaped || (p - q).abs().max_element() <= 1e-4 * scale.max(1.0),
                            "{name}: barycentrics rebuild {p} but the ray is at {q}"
                        );
                    }
                    _ => panic!("{name}: {ray:?}: bvh {got:?} brute {want:?}"),
                }
                // Any-hit must agree with closest-hit, except a hit within
                // rounding of tmax, where the box test may decide either way.
                if occluded != want.is_some() {
                    let near_tmax = |t: f32| (t - ray.tmax).abs() <= 1e-5 * ray.tmax;
                    let any = brute_any_t(&tris, ray);
                    assert!(
                        any.is_some_and(near_tmax),
                        "{name}: occluded {occluded} but closest {want:?} for {ray:?}"
                    );
                }
            }
            diff
        })
        .collect();
    let mut total = Diff::default();
    for d in results {
        total.rays += d.rays;
        total.hits += d.hits;
        total.tie_swaps += d.tie_swaps;
        total.near_swaps += d.near_swaps;
    }
    eprintln!(
        "{name}: {} triangles, {} nodes, {} wide nodes, {total:?}",
        input.len(),
        bvh.nodes.len(),
        all.wide.nodes.len()
    );
    total
}

/// An 8-wide tree's invariants (the one `Bvh4::build` makes for the CPU
/// from its own binary tree, or `Bvh4::collapse`'s): every triangle in
/// exactly one block lane (lanes past the count repeating the last), each
/// lane's vertices bit for bit those of the scene triangle it names, every
/// child box inside its parent's and holding its block's triangles, full
/// nodes with empty slots last and empty, within the depth bound. Returns
/// each block's triangles.
fn check_tree8(wide: &Bvh4, tris: &[Triangle]) -> Vec<Vec<u32>> {
    use glint_cpu::bvh::WIDTH8;
    let nodes = &wide.nodes8;
    if tris.is_empty() {
        assert!(nodes.is_empty() && wide.blocks.is_empty());
        return Vec::new();
    }
    let mut blocks = Vec::new();
    let mut seen = vec![0u32; tris.len()];
    let mut depth = 0;
    // (node, depth, the box its parent gave it)
    let mut stack = vec![(0usize, 0usize, Vec3::NEG_INFINITY, Vec3::INFINITY)];
    while let Some((i, d, plo, phi)) = stack.pop() {
        depth = depth.max(d);
        let node = &nodes[i];
        let used = node.child_count();
        assert!(
            used >= 2 || (nodes.len() == 1 && used == 1),
            "node {i}: {used} children"
        );
        for s in 0..WIDTH8 {
            let lo = Vec3::new(node.lo_x[s], node.lo_y[s], node.lo_z[s]);
            let hi = Vec3::new(node.hi_x[s], node.hi_y[s], node.hi_z[s]);
            let c = node.child[s];
            if s >= used {
                assert_eq!(c, SLOT_EMPTY);
                assert!(lo == Vec3::INFINITY && hi == Vec3::NEG_INFINITY);
                continue;
            }
            assert!(lo.cmpge(plo).all() && hi.cmple(phi).all() && lo.cmple(hi).all());
            if !is_leaf_ref(c) {
                assert!((c as usize) < nodes.len() && c as usize > i);
                stack.push((c as usize, d + 1, lo, hi));
                continue;
            }
            let (b, count) = leaf_range(c);
            let block = &wide.blocks[b];
            assert_eq!(block.count as usize, count);
            assert!((1..=4).contains(&count));
            blocks.push(block.tri[..count].to_vec());
            for lane in 0..4 {
                let id = block.tri[lane] as usize;
                assert_eq!(id, block.tri[lane.min(count - 1)] as usize);
                if lane < count {
                    seen[id] += 1;
                }
                let t = &tris[id];
                // A triangle with a non-finite vertex is binned as a point
                // at the origin (the builder's rule): its box says nothing.
                let finite = t.vertices().iter().all(|v| v.is_finite());
                for (k, p) in [t.p0, t.p1, t.p2].iter().enumerate() {
                    let p = Vec3::from(*p);
                    if finite {
                        assert!(
                            p.cmpge(lo).all() && p.cmple(hi).all(),
                            "block {b} outside its box"
                        );
                    }
                    for axis in 0..3 {
                        assert_eq!(block.v[k][axis][lane].to_bits(), p[axis].to_bits());
                    }
                }
            }
        }
    }
    assert!(
        seen.iter().all(|&n| n == 1),
        "a triangle in no block or in two"
    );
    assert_eq!(blocks.len(), wide.blocks.len());
    assert!(depth <= MAX_WIDE_DEPTH);
    assert_eq!(wide.depth8(), depth);
    blocks
}

/// The render's tree against the binary traversal's answer (`want`,
/// `want_occ`): the same closest distance (the triangle too, but for an
/// exact tie), the same occlusion but for a hit within rounding of tmax.
fn assert_render_tree_agrees(
    name: &str,
    render: &Bvh4,
    tris: &[Triangle],
    ray: &Ray,
    want: Option<Hit>,
    want_occ: bool,
) {
    let got = render.intersect(tris, ray);
    match (got, want) {
        (Some(g), Some(w)) if g.tri != w.tri => {
            assert_eq!(g.t, w.t, "{name} render tree: {ray:?}: {g:?} binary {w:?}")
        }
        _ => assert_eq!(got, want, "{name} render tree: {ray:?}"),
    }
    if render.occluded(tris, ray) != want_occ {
        let near_tmax = |t: f32| (t - ray.tmax).abs() <= 1e-5 * ray.tmax;
        assert!(
            brute_any_t(tris, ray).is_some_and(near_tmax),
            "{name} render tree: occlusion differs, {ray:?}"
        );
    }
}

fn brute_any_t(tris: &[Triangle], ray: &Ray) -> Option<f32> {
    let r = PreparedRay::new(ray.o, ray.d);
    tris.iter()
        .find_map(|t| intersect_triangle(&r, t, ray.tmax).map(|h| h.0))
}

#[test]
fn empty_scene_misses() {
    let (bvh, order) = Bvh::build(&[]);
    assert!(bvh.nodes.is_empty() && order.is_empty());
    assert_eq!(bvh.depth(), 0);
    let ray = Ray {
        o: Vec3::ZERO,
        d: Vec3::X,
        tmax: f32::INFINITY,
    };
    assert_eq!(bvh.intersect(&[], &ray), None);
    assert!(!bvh.occluded(&[], &ray));
    let all = Traversals::new(bvh, &[]);
    assert!(all.wide.nodes.is_empty() && all.wide.depth() == 0);
    for (which, hit, occ) in all.each(&[], &ray) {
        assert!(hit.is_none() && !occ, "{which}");
    }
}

#[test]
fn single_triangle() {
    let t = tri(
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(0.0, 1.0, 1.0),
    );
    let (bvh, tris, order) = build(&[t]);
    assert_eq!(order, vec![0]);
    assert_eq!(bvh.nodes.len(), 1);
    check_structure(&bvh, &tris, &order);
    let all = Traversals::new(bvh.clone(), &tris);
    // A lone leaf root becomes a wide root with one child.
    assert_eq!(all.wide.nodes.len(), 1);
    check_wide_structure(&all.wide, &bvh, &tris);
    let ray = |o: Vec3, d: Vec3, tmax: f32| Ray { o, d, tmax };
    let h = bvh
        .intersect(
            &tris,
            &ray(Vec3::new(0.25, 0.5, 0.0), Vec3::Z, f32::INFINITY),
        )
        .unwrap();
    assert_eq!((h.t, h.tri), (1.0, 0));
    assert!(
        (h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6,
        "{h:?}"
    );
    // From behind, both faces are hit.
    let h = bvh
        .intersect(
            &tris,
            &ray(Vec3::new(0.25, 0.25, 3.0), -Vec3::Z, f32::INFINITY),
        )
        .unwrap();
    assert_eq!(h.t, 2.0);
    // (0, tmax) is open at both ends.
    assert!(
        bvh.intersect(&tris, &ray(Vec3::new(0.25, 0.25, 0.0), Vec3::Z, 1.0))
            .is_none()
    );
    assert!(!bvh.occluded(&tris, &ray(Vec3::new(0.25, 0.25, 0.0), Vec3::Z, 1.0)));
    assert!(bvh.occluded(&tris, &ray(Vec3::new(0.25, 0.25, 0.0), Vec3::Z, 1.0001)));
    assert!(
        bvh.intersect(&tris, &ray(Vec3::new(0.25, 0.25, 1.0), Vec3::Z, 5.0))
            .is_none()
    );
    // Outside the triangle, and pointing away.
    assert!(
        bvh.intersect(&tris, &ray(Vec3::new(0.75, 0.75, 0.0), Vec3::Z, 5.0))
            .is_none()
    );
    assert!(
        bvh.intersect(&tris, &ray(Vec3::new(0.25, 0.25, 0.0), -Vec3::Z, 5.0))
            .is_none()
    );
    // In the triangle's plane: no hit (det = 0).
    assert!(
        bvh.intersect(&tris, &ray(Vec3::new(-1.0, 0.25, 1.0), Vec3::X, 5.0))
            .is_none()
    );
    // Axis-aligned rays whose origin lies exactly on the box's faces (zero
    // direction components: the slab test must not form 0 * inf = NaN),
    // through the triangle's edges and a vertex, which count as inside.
    for (o, d, t) in [
        (Vec3::new(0.0, 0.25, 0.0), Vec3::Z, 1.0),
        (Vec3::new(0.25, 0.0, 0.0), Vec3::Z, 1.0),
        (Vec3::new(0.0, 0.0, 0.0), Vec3::Z, 1.0),
        (Vec3::new(0.0, 1.0, 2.0), -Vec3::Z, 1.0),
        (Vec3::new(1.0, 0.0, 3.0), -Vec3::Z, 2.0),
        (Vec3::new(0.5, 0.5, 0.0), Vec3::Z, 1.0),
    ] {
        let r = ray(o, d, f32::INFINITY);
        for (which, hit, occ) in all.each(&tris, &r) {
            assert_eq!(hit.map(|h| h.t), Some(t), "{which} {r:?}");
            assert!(occ, "{which} {r:?}");
        }
    }
    // The other cases above, on the wide traversals too.
    for r in [
        ray(Vec3::new(0.25, 0.25, 0.0), Vec3::Z, 1.0),
        ray(Vec3::new(0.25, 0.25, 0.0), Vec3::Z, 1.0001),
        ray(Vec3::new(0.25, 0.25, 3.0), -Vec3::Z, f32::INFINITY),
        ray(Vec3::new(0.75, 0.75, 0.0), Vec3::Z, 5.0),
        ray(Vec3::new(-1.0, 0.25, 1.0), Vec3::X, 5.0),
    ] {
        assert_traversals_agree("single", &all, &tris, &r);
    }
}

/// A sliver triangle (p1 the rounded midpoint of p0 and p2) and a ray for
/// which two of the three edge functions round to exactly 0: before they
/// were recomputed (`bvh::traverse::refine_edge`) the test reported a hit
/// at t = 0.0121 with barycentrics (0, 1), a point 0.42 away from the ray
/// (found by the random soups on PCG32's stream; the BVH's box rightly
/// culled it). Since the recomputation, a hit would be where the ray meets
/// the sliver, after the box's entry (t = 0.1447) and inside the box (a
/// sliver's barycentrics are ill-conditioned, so the point they give is
/// only near the ray); the test's own t error bound (pbrt-v4's deltaT,
/// `bvh::traverse::t_error`) is larger than that t for a triangle of
/// rounding-error area, so it reports none, as pbrt-v4's does.
#[test]
fn degenerate_triangle_with_zero_edge_functions_is_not_hit() {
    let t = tri(
        Vec3::new(0.050923765, 0.42181003, 0.7977893),
        Vec3::new(0.028740615, 0.37331295, 0.4751265),
        Vec3::new(0.0065574646, 0.32481587, 0.15246373),
    );
    let o = Vec3::new(0.4602896, 0.68930554, 0.097110555);
    let d = Vec3::new(-2.828041, -1.8726577, 4.578493);
    let r = PreparedRay::new(o, d);
    let Some((th, u, v)) = intersect_triangle(&r, &t, f32::INFINITY) else {
        return;
    };
    assert!(th > 0.14, "t {th}");
    let [p0, p1, p2] = t.vertices();
    let hit = o + th * d;
    let (lo, hi) = (p0.min(p1).min(p2) - 1e-5, p0.max(p1).max(p2) + 1e-5);
    assert!(
        hit.cmpge(lo).all() && hit.cmple(hi).all(),
        "{hit} outside {lo}..{hi}"
    );
    assert!(
        (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v),
        "{u} {v}"
    );
}

/// The triangle test alone against a double-precision Moller-Trumbore on
/// well-conditioned cases: t and the barycentric convention.
#[test]
fn triangle_test_matches_f64_reference() {
    let mut rng = Pcg32::from_state(7);
    let mut checked = 0;
    for _ in 0..20_000 {
        let t = random_soup(&mut rng, 1, 0.5)[0];
        let o = rng.vec_in(Vec3::splat(-2.0), Vec3::splat(3.0));
        // Aim near the triangle, a little past its edges, so about half hit.
        let [p0, p1, p2] = t.vertices();
        let (s, r) = (rng.range(-0.2, 1.2), rng.range(-0.2, 1.2));
        let d = (p0 + s * (p1 - p0) + r * (p2 - p0) - o).normalize();
        let [a, b, c] = t.vertices().map(|p| p.as_dvec3());
        let (od, dd) = (o.as_dvec3(), d.as_dvec3());
        let (e1, e2) = (b - a, c - a);
        let pv = dd.cross(e2);
        let det = e1.dot(pv);
        // Skip grazing rays: their t is ill-conditioned in any precision.
        if det.abs() < 0.05 * e1.cross(e2).length() {
            continue;
        }
        let tv = od - a;
        let u = tv.dot(pv) / det;
        let qv = tv.cross(e1);
        let v = dd.dot(qv) / det;
        let tt = e2.dot(qv) / det;
        let inside = u > 1e-4 && v > 1e-4 && u + v < 1.0 - 1e-4 && tt > 1e-4;
        let outside = u < -1e-4 || v < -1e-4 || u + v > 1.0 + 1e-4 || tt < -1e-4;
        let got = intersect_triangle(&PreparedRay::new(o, d), &t, f32::INFINITY);
        if inside {
            let (gt, gu, gv) = got.expect("missed a clear hit");
            assert!(
                (gt as f64 - tt).abs() <= 1e-4 * tt.max(1.0),
                "t {gt} vs {tt}"
            );
            assert!((gu as f64 - u).abs() < 1e-4 && (gv as f64 - v).abs() < 1e-4);
            checked += 1;
        } else if outside {
            assert!(got.is_none(), "hit a clear miss");
        }
    }
    assert!(checked > 1000, "only {checked} hits checked");
}

#[test]
fn differential_random_soups() {
    let mut rng = Pcg32::from_state(1);
    let small = random_soup(&mut rng, 3000, 0.04);
    let slivers = random_soup(&mut rng, 300, 0.6);
    let nasty = nasty_soup(&mut rng);
    let mut total = Diff::default();
    for (name, soup) in [("small", small), ("slivers", slivers), ("nasty", nasty)] {
        let mut rays = random_rays(&soup, 24_000, &mut rng);
        rays.extend(rays_from_surfaces(&soup, 10_000, &mut rng));
        let d = differential(name, &soup, &rays);
        total.rays += d.rays;
        total.hits += d.hits;
        total.near_swaps += d.near_swaps;
    }
    assert!(total.rays >= 100_000);
    // The rays must mostly hit, or the comparison proves little.
    assert!(total.hits * 2 > total.rays, "{total:?}");
    // A different triangle at a different (if close) distance means the BVH
    // culled the closest one: only rounding at box faces may do that.
    assert!(total.near_swaps * 10_000 <= total.rays, "{total:?}");
}

#[test]
fn degenerate_inputs_build_and_traverse() {
    let mut rng = Pcg32::from_state(3);
    // Identical centroids: SAH cannot split; the leaf cap must still be kept.
    let t = tri(Vec3::ZERO, Vec3::X, Vec3::Y);
    let same = vec![t; 5000];
    let (bvh, tris, order) = build(&same);
    check_structure(&bvh, &tris, &order);
    let all = Traversals::new(bvh.clone(), &tris);
    check_wide_structure(&all.wide, &bvh, &tris);
    let ray = Ray {
        o: Vec3::new(0.2, 0.2, -1.0),
        d: Vec3::Z,
        tmax: f32::INFINITY,
    };
    for (which, hit, occ) in all.each(&tris, &ray) {
        assert_eq!(hit.map(|h| h.t), Some(1.0), "{which}");
        assert!(occ, "{which}");
    }

    // Geometrically spaced triangles over 16 decades: SAH peels them off a
    // few at a time (the depth guard itself is tested in bvh::build, with a
    // lower cap, since f32's range cannot make a chain deeper than ~20 here).
    let chain: Vec<Triangle> = (0..400)
        .map(|i| {
            let x = 1.1f32.powi(i);
            tri(
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x, 1.0, 0.0),
                Vec3::new(x, 0.0, 1.0),
            )
        })
        .collect();
    let rays = random_rays(&chain, 2000, &mut rng);
    differential("chain", &chain, &rays);

    // Non-finite positions (the loader rejects them): no panic, never hit,
    // and the finite triangles are still found.
    let mut soup = random_soup(&mut rng, 500, 0.05);
    let finite = soup.clone();
    let rays = random_rays(&finite, 2000, &mut rng);
    for i in 0..50 {
        let mut t = soup[i];
        t.p1[i % 3] = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY][i % 3];
        soup.push(t);
    }
    let (bvh, tris, order) = build(&soup);
    check_structure(&bvh, &tris, &order);
    let all = Traversals::new(bvh.clone(), &tris);
    check_wide_structure(&all.wide, &bvh, &tris);
    let (fb, ftris, _) = build(&finite);
    for ray in &rays {
        let want = fb.intersect(&ftris, ray);
        for (which, got, _) in all.each(&tris, ray) {
            assert_eq!(got.map(|h| h.t), want.map(|h| h.t), "{which} {ray:?}");
            if let Some(h) = got {
                assert!(
                    tris[h.tri as usize]
                        .vertices()
                        .iter()
                        .all(|p| p.is_finite())
                );
            }
        }
    }
}

#[test]
fn build_is_deterministic() {
    let mut rng = Pcg32::from_state(11);
    let soup = random_soup(&mut rng, 5000, 0.03);
    let (a, oa) = Bvh::build(&soup);
    let (b, ob) = Bvh::build(&soup);
    assert_eq!(a.nodes, b.nodes);
    assert_eq!(oa, ob);
    let ta: Vec<_> = oa.iter().map(|&i| soup[i as usize]).collect();
    let (wa, wb) = (Bvh4::collapse(&a, &ta), Bvh4::collapse(&b, &ta));
    assert_eq!(wa.nodes, wb.nodes);
    assert_eq!(wa.nodes8, wb.nodes8);
    assert_eq!(wa.blocks, wb.blocks);
}

/// A closed icosphere: shared vertices are bit-identical between triangles.
fn icosphere(center: Vec3, radius: f32, levels: u32) -> Vec<Triangle> {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut verts: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut faces: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid: HashMap<(usize, usize), usize> = HashMap::new();
        let mut midpoint = |a: usize, b: usize, verts: &mut Vec<Vec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                verts.push((0.5 * (verts[a] + verts[b])).normalize());
                verts.len() - 1
            })
        };
        faces = faces
            .iter()
            .flat_map(|&[a, b, c]| {
                let ab = midpoint(a, b, &mut verts);
                let bc = midpoint(b, c, &mut verts);
                let ca = midpoint(c, a, &mut verts);
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    let world: Vec<Vec3> = verts.iter().map(|&v| center + radius * v).collect();
    faces
        .iter()
        .map(|&[a, b, c]| tri(world[a], world[b], world[c]))
        .collect()
}

/// Unique vertices and edges of a mesh (by exact position).
fn edges_and_vertices(tris: &[Triangle]) -> (Vec<Vec3>, Vec<(Vec3, Vec3)>) {
    let key = |p: Vec3| p.to_array().map(f32::to_bits);
    let mut verts = HashMap::new();
    let mut edges = HashMap::new();
    for t in tris {
        let v = t.vertices();
        for k in 0..3 {
            verts.insert(key(v[k]), v[k]);
            let (a, b) = (v[k], v[(k + 1) % 3]);
            let (a, b) = if key(a) < key(b) { (a, b) } else { (b, a) };
            edges.insert((key(a), key(b)), (a, b));
        }
    }
    let mut verts: Vec<_> = verts.into_iter().collect();
    verts.sort_by_key(|(k, _)| *k);
    let mut edges: Vec<_> = edges.into_iter().collect();
    edges.sort_by_key(|(k, _)| *k);
    (
        verts.into_iter().map(|x| x.1).collect(),
        edges.into_iter().map(|x| x.1).collect(),
    )
}

/// Rays from inside a closed mesh towards its vertices, edge points (ends,
/// midpoints, random points) and, for the cube, axis-aligned rays through
/// grid lines: every one must hit. Returns the number of rays.
fn assert_no_leaks(name: &str, mesh: &[Triangle], origins: &[Vec3], rng: &mut Pcg32) -> usize {
    let (bvh, tris, _) = build(mesh);
    let all = Traversals::new(bvh, &tris);
    let (verts, edges) = edges_and_vertices(mesh);
    let mut targets = verts.clone();
    for &(a, b) in &edges {
        targets.push(0.5 * (a + b));
        targets.push(a.lerp(b, rng.f32()));
    }
    let mut leaks = 0;
    let mut rays = 0;
    for &o in origins {
        for &p in &targets {
            for d in [p - o, (p - o).normalize()] {
                let ray = Ray {
                    o,
                    d,
                    tmax: f32::INFINITY,
                };
                rays += 1;
                let want = brute_closest(&tris, &ray);
                for (which, hit, occ) in all.each(&tris, &ray) {
                    match (hit, want) {
                        (Some(h), Some(w)) if occ => {
                            // Many triangles meet at the aimed point: a near tie.
                            assert!((h.t - w.t).abs() <= 2e-5 * w.t, "{name} {which}: {ray:?}");
                        }
                        _ => leaks += 1,
                    }
                }
            }
        }
    }
    assert_eq!(leaks, 0, "{name}: {leaks} of {rays} rays leaked");
    rays
}

#[test]
fn watertight_closed_meshes() {
    let mut rng = Pcg32::from_state(5);
    // Off-grid centre and radius so coordinates are not round numbers.
    let c = Vec3::new(0.31, -1.73, 2.09);
    let sphere = icosphere(c, 3.3, 3);
    let mut origins = vec![c];
    origins.extend((0..6).map(|_| c + 1.5 * rng.dir()));
    let n = assert_no_leaks("icosphere", &sphere, &origins, &mut rng);

    let cube = grid_cube(8);
    let mut origins = vec![Vec3::ZERO, Vec3::new(0.25, -0.5, 0.125)];
    origins.extend((0..4).map(|_| 0.9 * rng.dir()));
    let m = assert_no_leaks("cube", &cube, &origins, &mut rng);

    // Axis-aligned rays (two zero direction components) exactly along the
    // grid lines, from inside: they cross the faces at edges and vertices of
    // the grid and run inside flat (zero-thickness) boxes.
    let (bvh, tris, _) = build(&cube);
    let all = Traversals::new(bvh, &tris);
    let coord = |i: usize| -1.0 + 2.0 * i as f32 / 8.0;
    let mut leaks = 0;
    let mut axis_rays = 0;
    for axis in 0..3 {
        for i in 0..=8 {
            for j in 0..=8 {
                for k in [1usize, 4, 7] {
                    for sign in [-1.0f32, 1.0] {
                        let mut o = [0.0f32; 3];
                        o[axis] = coord(k) * 0.5;
                        o[(axis + 1) % 3] = coord(i) * if i == 0 || i == 8 { 0.999 } else { 1.0 };
                        o[(axis + 2) % 3] = coord(j) * if j == 0 || j == 8 { 0.999 } else { 1.0 };
                        let mut d = Vec3::ZERO;
                        d[axis] = sign;
                        let ray = Ray {
                            o: Vec3::from(o),
                            d,
                            tmax: f32::INFINITY,
                        };
                        axis_rays += 1;
                        for (which, hit, occ) in all.each(&tris, &ray) {
                            match hit {
                                Some(h) if occ => {
                                    assert!(
                                        (h.t - (1.0 - sign * o[axis])).abs() < 1e-6,
                                        "{which} {ray:?} {h:?}"
                                    );
                                }
                                _ => leaks += 1,
                            }
                        }
                    }
                }
            }
        }
    }
    assert_eq!(
        leaks, 0,
        "cube: {leaks} of {axis_rays} axis-aligned rays leaked"
    );
    eprintln!("watertight: {n} icosphere rays, {m} + {axis_rays} cube rays, no leaks");
}

/// The bunny is not closed, so rays aim from outside at points on its interior
/// edges where the two triangles lie on opposite sides of the edge as seen
/// along the ray: the surface covers that point, so the ray must hit at or
/// before it.
fn bunny_edge_leaks(
    input: &[Triangle],
    all: &Traversals,
    tris: &[Triangle],
    rng: &mut Pcg32,
) -> (usize, usize) {
    let key = |p: Vec3| p.to_array().map(f32::to_bits);
    let mut edge_tris: HashMap<([u32; 3], [u32; 3]), Vec<usize>> = HashMap::new();
    for (i, t) in input.iter().enumerate() {
        let v = t.vertices();
        for k in 0..3 {
            let (a, b) = (key(v[k]), key(v[(k + 1) % 3]));
            edge_tris.entry((a.min(b), a.max(b))).or_default().push(i);
        }
    }
    let mut interior: Vec<_> = edge_tris
        .into_iter()
        .filter(|(_, ts)| ts.len() == 2)
        .map(|(k, ts)| (k, [ts[0], ts[1]]))
        .collect();
    interior.sort();
    let (lo, hi) = bounds_of(input);
    let (center, radius) = (0.5 * (lo + hi), (hi - lo).length());
    let (mut rays, mut leaks) = (0, 0);
    while rays < 20_000 {
        let ((ka, kb), [t1, t2]) = interior[rng.below(interior.len())];
        let a = Vec3::from(ka.map(f32::from_bits));
        let b = Vec3::from(kb.map(f32::from_bits));
        let p = a.lerp(b, rng.range(0.05, 0.95));
        let o = center + radius * rng.dir();
        let d = p - o;
        // The third vertices must lie on opposite sides of the plane through
        // the edge and the ray, with a margin against rounding.
        let side = |t: usize| {
            let third = input[t]
                .vertices()
                .into_iter()
                .find(|&v| key(v) != ka && key(v) != kb)
                .unwrap();
            let n = (b - a).cross(d).normalize();
            n.dot(third - a) / (third - a).length()
        };
        let (s1, s2) = (side(t1), side(t2));
        if !(s1 * s2 < 0.0 && s1.abs() > 0.05 && s2.abs() > 0.05) {
            continue;
        }
        rays += 1;
        let ray = Ray {
            o,
            d,
            tmax: f32::INFINITY,
        };
        for (_, hit, occ) in all.each(tris, &ray) {
            match hit {
                Some(h) if h.t <= 1.0 + 1e-4 && occ => {}
                _ => leaks += 1,
            }
        }
    }
    (rays, leaks)
}

#[test]
fn bunny_build_differential_and_watertight() {
    let input = bunny();
    assert_eq!(input.len(), 69_451);
    let start = Instant::now();
    let (bvh, order) = Bvh::build(&input);
    let build_s = start.elapsed().as_secs_f64();
    let tris: Vec<Triangle> = order.iter().map(|&i| input[i as usize]).collect();
    let (leaves, depth) = check_structure(&bvh, &tris, &order);
    let start = Instant::now();
    let all = Traversals::new(bvh.clone(), &tris);
    let collapse_s = start.elapsed().as_secs_f64();
    let wide_depth = check_wide_structure(&all.wide, &bvh, &tris);
    eprintln!(
        "bunny: build {:.1} ms, {} nodes, {leaves} leaves, depth {depth}; \
         collapse {:.1} ms, {} wide nodes, wide depth {wide_depth}",
        build_s * 1e3,
        bvh.nodes.len(),
        collapse_s * 1e3,
        all.wide.nodes.len(),
    );

    let mut rng = Pcg32::from_state(2);
    let (rays, leaks) = bunny_edge_leaks(&input, &all, &tris, &mut rng);
    assert_eq!(
        leaks, 0,
        "bunny: {leaks} of {rays} edge rays x traversals leaked"
    );

    // Brute force costs 69k triangle tests a ray: 3,000 rays keep this test
    // to a few seconds; the soups above take the 10^5-ray load, and the wide
    // BVH is compared with the binary one on 10^5 bunny rays below.
    let rays = random_rays(&input, 3_000, &mut rng);
    let d = differential("bunny", &input, &rays);
    assert!(d.hits * 2 > d.rays, "{d:?}");
    assert!(d.near_swaps * 10_000 <= d.rays, "{d:?}");
}

/// 10^5 random bunny rays (zero direction components, origins inside and
/// out, short tmax): every wide kernel gives the binary traversal's closest
/// hit and occlusion.
#[test]
fn bunny_wide_matches_binary() {
    let input = bunny();
    let (bvh, tris, _) = build(&input);
    let all = Traversals::new(bvh, &tris);
    let mut rng = Pcg32::from_state(0xb0b);
    let mut rays = random_rays(&tris, 80_000, &mut rng);
    rays.extend(rays_from_surfaces(&tris, 20_000, &mut rng));
    let hits: usize = rays
        .par_chunks(1024)
        .map(|chunk| {
            let mut hits = 0;
            for ray in chunk {
                assert_traversals_agree("bunny", &all, &tris, ray);
                hits += all.bin.intersect(&tris, ray).is_some() as usize;
            }
            hits
        })
        .sum();
    assert!(hits * 2 > rays.len(), "{hits} hits");
}

/// Alpha-masked queries (a triangle is there only where `present(tri, u,
/// v)` says so, as an alpha mask cuts it): every kernel's masked closest
/// and any hit against the binary traversal's on 10^5 bunny rays, with a
/// mask that removes whole triangles and parts of others.
#[test]
fn masked_queries_match_the_binary_traversal_on_every_kernel() {
    let input = bunny();
    let (bvh, tris, _) = build(&input);
    let all = Traversals::new(bvh, &tris);
    let present = |tri: u32, u: f32, v: f32| {
        let h = tri.wrapping_mul(0x9e37_79b9) >> 29;
        h != 0 && !(h == 1 && u + v > 0.5)
    };
    let mut rng = Pcg32::from_state(0xa1fa);
    let mut rays = random_rays(&tris, 80_000, &mut rng);
    rays.extend(rays_from_surfaces(&tris, 20_000, &mut rng));
    let (mut hits, mut masked_away) = (0, 0);
    for ray in &rays {
        let want = all.bin.intersect_masked(&tris, ray, present);
        let want_occ = all.bin.occluded_masked(&tris, ray, present);
        hits += want.is_some() as usize;
        masked_away += (want.is_none() && all.bin.intersect(&tris, ray).is_some()) as usize;
        for &k in &all.kernels {
            let got = all.wide.intersect_masked_with(k, &tris, ray, present);
            // The same distance (an exact tie may pick another triangle).
            assert_eq!(got.map(|h| h.t), want.map(|h| h.t), "{k:?} {ray:?}");
            let occ = all.wide.occluded_masked_with(k, &tris, ray, present);
            let near_tmax = want.is_some_and(|h| (h.t - ray.tmax).abs() <= 1e-5 * ray.tmax);
            assert!(occ == want_occ || near_tmax, "{k:?} occlusion {ray:?}");
        }
    }
    assert!(
        hits > 20_000 && masked_away > 1_000,
        "{hits} hits, {masked_away} masked away"
    );
}

/// Packets of eight alike rays (`Bvh4::intersect_packet`, the interval
/// test over the packet) against each ray traced alone: the same closest
/// distance bit for bit, and the same triangle and barycentrics unless two
/// triangles tie at that distance. Packets are made around the bunny's and
/// the Cornell box's rays with origins and directions spread from not at
/// all (a pinhole camera's pixel) to a third of the scene, random ray
/// limits and random live lanes; packets that differ in a direction's sign
/// or dominant axis, or have a zero component, must give None from the
/// packet alone and still the single-ray answers from `intersect_packet`.
#[test]
fn packets_find_each_ray_s_closest_hit() {
    for (name, input) in [
        ("bunny", bunny()),
        ("cornell", geometry::asset_triangles("cornell.gltf")),
    ] {
        // The render's tree (`Bvh4::build`), in the order it gives.
        let (_, tris, _) = build(&input);
        let (wide, _) = Bvh4::build(&input);
        let (lo, hi) = bounds_of(&tris);
        let size = (hi - lo).length();
        let mut rng = Pcg32::from_state(0x9ac4e7);
        let mut seeds = geometry::primary_rays(lo, hi, 64, 64);
        seeds.extend(random_rays(&tris, 4000, &mut rng));
        seeds.extend(rays_from_surfaces(&tris, 4000, &mut rng));
        let (mut packed, mut hits, mut ties) = (0usize, 0usize, 0usize);
        for (i, seed) in seeds.iter().enumerate() {
            let spread = [0.0, 1e-4, 1e-2, 0.3][i % 4];
            let rays: [Ray; 8] = std::array::from_fn(|k| {
                let jitter =
                    |rng: &mut Pcg32| Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0;
                let (jo, jd) = (jitter(&mut rng), jitter(&mut rng));
                let mut d = (seed.d + spread * jd).normalize_or(seed.d);
                if seed.d.cmpeq(Vec3::ZERO).any() && k % 3 == 0 {
                    d = seed.d;
                }
                let tmax = if rng.f32() < 0.2 {
                    rng.f32() * size
                } else {
                    seed.tmax
                };
                Ray {
                    o: seed.o + spread * size * jo,
                    d,
                    tmax,
                }
            });
            let live = if i % 5 == 0 {
                (rng.next_u32() as u8).max(1)
            } else {
                0xff
            };
            let mut got = [None; 8];
            wide.intersect_packet(&tris, &rays, live, &mut got);
            let only = wide.intersect_packet_only(&rays, live);
            if let Some(only) = only {
                assert_eq!(only, got, "{name}: ray {i}");
                packed += 1;
            }
            for k in 0..8 {
                let want = (live & (1 << k) != 0)
                    .then(|| wide.intersect(&tris, &rays[k]))
                    .flatten();
                let (g, w) = (got[k], want);
                assert_eq!(
                    g.map(|h| h.t.to_bits()),
                    w.map(|h| h.t.to_bits()),
                    "{name}: seed {i} ray {k} {:?}",
                    rays[k]
                );
                if let (Some(g), Some(w)) = (g, w) {
                    hits += 1;
                    if g.tri == w.tri {
                        assert_eq!((g.u, g.v), (w.u, w.v), "{name}: seed {i} ray {k}");
                    } else {
                        ties += 1;
                    }
                }
            }
            if Kernel::has_avx2() && i < 64 * 64 {
                // A pinhole camera's packets: one origin, directions alike.
                assert!(
                    only.is_some() || spread > 0.0 || !packable(&rays),
                    "{name}: ray {i}"
                );
            }
        }
        eprintln!(
            "{name}: {packed} of {} packets traversed as packets, {hits} hits, {ties} ties",
            seeds.len()
        );
        assert!(hits > seeds.len(), "{name}: {hits} hits");
        assert!(ties * 1000 <= hits, "{name}: {ties} ties");
        if Kernel::has_avx2() {
            assert!(packed * 3 > seeds.len(), "{name}: {packed} packets");
        }
    }
}

/// Packets whose rays pass exactly through the vertices and along the
/// edges of a grid of triangles (edge functions that round to exactly 0,
/// the triangle test's refinement, in every lane of the packet's leaf test)
/// and whose eight rays share a leaf (the leaf tested eight rays per
/// instruction): each ray's hit is the single ray's, bit for bit.
#[test]
fn packets_through_vertices_and_edges_match_single_rays() {
    // A 12 x 12 grid of unit squares at z = -5, two triangles each, the
    // diagonals alternating.
    let mut input = Vec::new();
    for i in 0..12 {
        for j in 0..12 {
            let p = |x: i32, y: i32| Vec3::new(x as f32, y as f32, -5.0);
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            if (i + j) % 2 == 0 {
                input.extend([tri(a, b, c), tri(a, c, d)]);
            } else {
                input.extend([tri(a, b, d), tri(b, c, d)]);
            }
        }
    }
    let (_, tris, _) = build(&input);
    let (wide, _) = Bvh4::build(&input);
    let mut packed = 0;
    let mut rng = Pcg32::from_state(0x51d3);
    // A square's corners and the middles of its sides: eight rays into
    // one or two leaves.
    let spots = [
        (0.0, 0.0),
        (1.0, 0.0),
        (1.0, 1.0),
        (0.0, 1.0),
        (0.5, 0.0),
        (1.0, 0.5),
        (0.5, 1.0),
        (0.0, 0.5),
    ];
    for x0 in 1..=9 {
        for y0 in 1..=9 {
            for offset in [Vec3::ZERO, Vec3::new(0.25, 0.25, 0.0)] {
                // From origins on the grid's axis (a pixel's rays share
                // theirs), directions all (+, +, -), z dominant.
                let shared = rng.f32() < 0.5;
                let rays: [Ray; 8] = std::array::from_fn(|k| {
                    let (dx, dy) = spots[k];
                    let target = Vec3::new(x0 as f32 + dx, y0 as f32 + dy, -5.0) + offset;
                    let o = if shared {
                        Vec3::ZERO
                    } else {
                        Vec3::new(0.0, 0.0, -(k as f32) * 0.125)
                    };
                    Ray {
                        o,
                        d: target - o,
                        tmax: f32::MAX,
                    }
                });
                let mut got = [None; 8];
                wide.intersect_packet(&tris, &rays, 0xff, &mut got);
                packed += usize::from(wide.intersect_packet_only(&rays, 0xff).is_some());
                for (k, ray) in rays.iter().enumerate() {
                    // The same distance bit for bit; the same barycentrics
                    // where the same triangle (an exact tie between two may
                    // go either way, as between the two trees).
                    let (g, w) = (got[k].unwrap(), wide.intersect(&tris, ray).unwrap());
                    assert_eq!(g.t.to_bits(), w.t.to_bits(), "ray {k} {ray:?}");
                    if g.tri == w.tri {
                        assert_eq!(
                            (g.u.to_bits(), g.v.to_bits()),
                            (w.u.to_bits(), w.v.to_bits())
                        );
                    }
                }
            }
        }
    }
    if Kernel::has_avx2() {
        assert!(packed > 0, "no packet was traversed as one");
    }
}

/// Whether the rays agree in every direction component's sign and in the
/// dominant axis (the packet traversal's condition).
fn packable(rays: &[Ray; 8]) -> bool {
    let key = |d: Vec3| {
        let p = PreparedRay::new(Vec3::ZERO, d);
        (p.kx, p.ky, p.kz, d.to_array().map(|c| (c < 0.0, c == 0.0)))
    };
    rays.iter().all(|r| key(r.d) == key(rays[0].d)) && !rays[0].d.cmpeq(Vec3::ZERO).any()
}
