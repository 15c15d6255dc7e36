//! The small stability sweep (`glint stability --quick`) in CI: every point
//! of every BSDF's sweep finite, energy-conserving, sample-consistent and
//! equal on the GPU (the GLSL BSDFs through shaders/tests/bsdf_test.comp),
//! under the validation layer; and the outputs' shape.

mod common;

use glint::stability::{self, COS, Size, Status};

#[test]
fn quick_sweep_has_no_failing_point() {
    let ctx = common::context();
    let rows = stability::run(Size::Quick, Some(&ctx)).unwrap();
    let messages = ctx.finish();
    assert!(messages.is_empty(), "validation: {messages:?}");
    assert_eq!(rows.len() % COS.len(), 0);
    let fails: Vec<String> = rows
        .iter()
        .filter(|(_, r)| r.status == Status::Fail)
        .map(|(p, r)| {
            format!(
                "{} {} {} cos {}: {}",
                p.family, p.model, p.param, COS[p.cos_index], r.why
            )
        })
        .collect();
    assert!(
        fails.is_empty(),
        "{} failing points:\n{}",
        fails.len(),
        fails.join("\n")
    );
    // Every point was measured on the GPU, and the thresholds' continuity too.
    assert!(rows.iter().all(|(_, r)| r.gpu_mismatch.is_some()));
    assert!(rows.iter().any(|(_, r)| r.continuity.is_some()));
    // The quadrature ran where lobes are wide, and agrees there.
    let quad: Vec<_> = rows
        .iter()
        .filter_map(|(_, r)| r.albedo_quad.map(|q| (q, r)))
        .collect();
    assert!(quad.len() > 100);
    let csv = stability::csv(&rows);
    assert_eq!(csv.lines().count(), rows.len() + 1);
    let md = stability::markdown(&rows, Size::Quick, Some("test"));
    assert!(
        md.contains("pass,") || md.contains(" pass, "),
        "{}",
        &md[..300.min(md.len())]
    );
}

/// The sweep's checks can fail: a BSDF that gains energy, one that returns
/// NaN, and a GPU mismatch are each classified as failing.
#[test]
fn the_checks_catch_broken_bsdfs() {
    use glam::Vec3;
    use glint_cpu::bsdf::Bsdf;
    let pts = stability::points();
    // Energy: a diffuse reflectance of 1.2 has albedo 1.2.
    let mut p = pts[0].clone();
    p.bsdf = Bsdf::Diffuse {
        reflectance: Vec3::splat(1.2),
    };
    let mut r = stability::measure_cpu(&p, Size::Quick, 1);
    assert!(r.albedo > 1.1, "{r:?}");
    assert!(r.lost == 0.0, "{r:?}");
    stability::classify(&mut r);
    assert_eq!(r.status, Status::Fail, "{r:?}");
    // NaN: a NaN reflectance.
    p.bsdf = Bsdf::Diffuse {
        reflectance: Vec3::splat(f32::NAN),
    };
    let mut r = stability::measure_cpu(&p, Size::Quick, 1);
    assert!(!r.finite, "{r:?}");
    stability::classify(&mut r);
    assert_eq!(r.status, Status::Fail, "{r:?}");
    // A GPU mismatch on one query in a hundred degrades, on one in ten fails.
    p.bsdf = Bsdf::Diffuse {
        reflectance: Vec3::splat(0.5),
    };
    let mut r = stability::measure_cpu(&p, Size::Quick, 1);
    stability::classify(&mut r);
    assert_eq!(r.status, Status::Pass, "{r:?}");
    r.gpu_mismatch = Some(0.01);
    stability::classify(&mut r);
    assert_eq!(r.status, Status::Degrade, "{r:?}");
    r.gpu_mismatch = Some(0.1);
    stability::classify(&mut r);
    assert_eq!(r.status, Status::Fail, "{r:?}");
}
