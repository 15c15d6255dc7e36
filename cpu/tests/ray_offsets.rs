//! Ray offsets from the hit point's floating-point error bound
//! (`integrator::offset_origin`, pbrt-v4's `OffsetRayOrigin`): a scene
//! renders the same moved 10 km from the origin or scaled by 1e-4 .. 1e5,
//! and a huge ground plane does not change a small lit object (each
//! compared statistically with `glint_cpu::compare`); where f32 truly runs
//! out, a warning says so.

mod render_common;

use glam::{Quat, Vec3};
use glint_cpu::compare::compare_films;
use glint_cpu::integrator::{
    hit_error, next_float_down, next_float_up, offset_origin, precision_warning,
};
use glint_cpu::{PunctualLight, Scene};
use render_common::*;

/// The scene mapped by p -> s p + t (camera and lights too).
fn moved(base: &Scene, s: f32, t: Vec3, eye: Vec3, target: Vec3, yfov: f32) -> Scene {
    let f = |p: Vec3| p * s + t;
    let tris = base
        .triangles
        .iter()
        .map(|tr| {
            let [a, b, c] = tr.vertices();
            let mut n = tri(f(a), f(b), f(c), tr.material);
            n.flags = tr.flags;
            n
        })
        .collect();
    let lights = base
        .lights
        .iter()
        .map(|l| match *l {
            PunctualLight::Point {
                position,
                intensity,
            } => PunctualLight::Point {
                position: f(position),
                // Same irradiance at the scaled distances.
                intensity: intensity * s * s,
            },
            other => other,
        })
        .collect();
    scene(
        tris,
        base.materials.clone(),
        lights,
        look_at(f(eye), f(target), Vec3::Y, yfov),
        base.background,
    )
}

fn room_view() -> (Vec3, Vec3) {
    (Vec3::new(0.0, 0.0, 3.2), Vec3::new(0.0, -0.1, 0.0))
}

#[test]
fn room_renders_the_same_far_away_and_at_any_scale() {
    let base = lit_room(vec![]);
    let (eye, target) = room_view();
    let o = opts(32, 64, -1, 3);
    let reference = render(&base, &o);
    let mut failures = Vec::new();
    for (s, t) in [
        (1.0, Vec3::new(1e4, 2e3, -3e3)),
        (1e-4, Vec3::ZERO),
        (1e-2, Vec3::ZERO),
        (1e2, Vec3::ZERO),
        (1e5, Vec3::ZERO),
    ] {
        let sc = moved(&base, s, t, eye, target, 45.0);
        assert!(precision_warning(&sc).is_none(), "scale {s} at {t}");
        let film = render(&sc, &opts(32, 64, -1, 4));
        let r = compare_films(&reference, &film).unwrap();
        eprintln!("scale {s} moved {t}: {r}");
        if !r.pass {
            failures.push(format!("scale {s} moved {t}: {r}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A 20 cm box on a ground lit by a point light, direct lighting only
/// (so the ground's extent cannot matter physically), seen from above so
/// that the small ground fills the view.
fn box_on_ground(ground_half_size: f32) -> Scene {
    let mut t = floor(0.37, ground_half_size, 0);
    t.extend(box_mesh(
        Vec3::new(0.0, 0.47, 0.0),
        Vec3::splat(0.1),
        Quat::from_rotation_y(0.5),
        1,
    ));
    scene(
        t,
        vec![diffuse("ground", 0.6), diffuse("box", 0.8)],
        vec![PunctualLight::Point {
            position: Vec3::new(0.4, 1.3, 0.2),
            intensity: Vec3::splat(2.0),
        }],
        look_at(
            Vec3::new(0.0, 1.9, 1.0),
            Vec3::new(0.0, 0.37, 0.0),
            Vec3::Y,
            30.0,
        ),
        Vec3::ZERO,
    )
}

#[test]
fn huge_ground_plane_does_not_change_a_small_object() {
    let o = opts(32, 32, 2, 5);
    let small = render(&box_on_ground(3.0), &o);
    // A single 2 km triangle pair: offsets of ~8 mm on the ground (its own
    // triangle test's rounding), the box's unchanged.
    for half in [30.0, 1e3] {
        let huge = render(&box_on_ground(half), &opts(32, 32, 2, 6));
        let r = compare_films(&small, &huge).unwrap();
        assert!(r.pass, "ground half-size {half}: {r}");
    }
}

#[test]
fn precision_warning_only_where_f32_runs_out() {
    let base = lit_room(vec![]);
    let (eye, target) = room_view();
    assert!(precision_warning(&base).is_none());
    // 10 km: offsets of 4 mm against 18 cm triangles, fine.
    let near = moved(&base, 1.0, Vec3::new(1e4, 0.0, 0.0), eye, target, 45.0);
    assert!(precision_warning(&near).is_none());
    // 1e7: offsets of 4 m against 18 cm triangles.
    let far = moved(&base, 1.0, Vec3::new(1e7, 0.0, 0.0), eye, target, 45.0);
    let w = precision_warning(&far).expect("a warning");
    assert!(w.contains("float precision"), "{w}");
}

/// The offset origin lies strictly on the requested side of the triangle's
/// plane, and a ray from it never hits its own triangle, for triangles
/// from 1e-4 to 1e5 in size and up to 1e6 away from the origin.
#[test]
fn offset_origins_never_self_intersect() {
    use glint_cpu::bvh::{PreparedRay, intersect_triangle};
    // PCG32's stream found a steep ray (d.y = 0.47) leaving a 1e5-sized
    // triangle 1e6 from the origin that re-hit it at t = 0.49, beyond the
    // fixed RAY_ERR_TRI margin; the triangle test's own t error bound
    // (pbrt-v4's deltaT, `bvh::traverse::t_error`) now rejects it.
    struct R(glint_cpu::sampling::Pcg32);
    impl R {
        fn f(&mut self) -> f32 {
            self.0.f32()
        }
        fn v(&mut self) -> Vec3 {
            Vec3::new(self.f() - 0.5, self.f() - 0.5, self.f() - 0.5)
        }
    }
    // 16 streams of 40,000 rays (0.1 s in the test profile).
    let mut hits = 0;
    let mut n = 0;
    for stream in 0..16 {
        let mut rng = R(glint_cpu::sampling::Pcg32::new(12345, stream));
        for size_exp in [-4, -2, 0, 2, 5] {
            for far_exp in [0, 2, 4, 6] {
                let size = 10f32.powi(size_exp);
                let far = 10f32.powi(far_exp);
                for _ in 0..2000 {
                    let c = rng.v() * far;
                    let (p0, mut p1, mut p2) =
                        (c + rng.v() * size, c + rng.v() * size, c + rng.v() * size);
                    // A third of the triangles lie in an axis-aligned plane.
                    if rng.f() < 0.33 {
                        p1.y = p0.y;
                        p2.y = p0.y;
                    }
                    let ng = (p1 - p0).cross(p2 - p0).normalize();
                    if !ng.is_finite() {
                        continue;
                    }
                    let tr = tri(p0, p1, p2, 0);
                    let (u, w) = (rng.f(), rng.f());
                    let (u, w) = if u + w > 1.0 {
                        (1.0 - u, 1.0 - w)
                    } else {
                        (u, w)
                    };
                    let p = (1.0 - u - w) * p0 + u * p1 + w * p2;
                    let err = hit_error(p0, p1, p2);
                    // Half the rays graze the plane (normal component down to
                    // 1e-6 of the in-plane one), where the triangle test's
                    // rounding matters most.
                    let mut d = (rng.v() * 2.0).normalize();
                    if rng.f() < 0.5 {
                        let inplane = (d - ng * d.dot(ng)).normalize();
                        let k = 10f32.powf(-6.0 * rng.f());
                        d = (inplane + ng * k * (rng.f() - 0.5).signum()).normalize();
                    }
                    if !d.is_finite() {
                        continue;
                    }
                    let o = offset_origin(p, err, ng, d);
                    n += 1;
                    let r = PreparedRay::new(o, d);
                    if intersect_triangle(&r, &tr, f32::MAX).is_some() {
                        hits += 1;
                    }
                }
            }
        }
    }
    assert_eq!(hits, 0, "{hits} self-intersections of {n} rays");
}

#[test]
fn next_float_steps_one_ulp() {
    for v in [0.0f32, -0.0, 1.0, -1.0, 1e-30, -3.5e7, f32::MAX] {
        let up = next_float_up(v);
        let down = next_float_down(v);
        assert!(up > v && down < v, "{v}: {up} {down}");
        if v != 0.0 && v.abs() < f32::MAX {
            assert_eq!(next_float_down(up), v);
        }
    }
    assert_eq!(next_float_up(f32::INFINITY), f32::INFINITY);
}
