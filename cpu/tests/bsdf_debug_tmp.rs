mod common;
use common::*;
use glam::DVec3;
use glint_cpu::bsdf::{Bsdf, Shadowing};

fn d64(wm: DVec3, a: f64) -> f64 {
    let t = (wm.x / a).powi(2) + (wm.y / a).powi(2) + wm.z * wm.z;
    1.0 / (std::f64::consts::PI * a * a * t * t)
}
fn fr64(c: f64, eta: f64) -> f64 {
    let (c, eta) = if c < 0.0 { (-c, 1.0 / eta) } else { (c, eta) };
    let s2 = (1.0 - c * c) / (eta * eta);
    if s2 >= 1.0 {
        return 1.0;
    }
    let ct = (1.0 - s2).sqrt();
    let rs = (c - eta * ct) / (c + eta * ct);
    let rp = (eta * c - ct) / (eta * c + ct);
    0.5 * (rs * rs + rp * rp)
}
fn pdf64(wo: DVec3, wi: DVec3, a: f64, eta: f64) -> f64 {
    let h = wi * eta + wo;
    let mut wm = h.normalize();
    if wm.z < 0.0 {
        wm = -wm;
    }
    if wm.dot(wi) >= 0.0 || wm.dot(wo) <= 0.0 {
        return 0.0;
    }
    let so = (wo.z * wo.z + a * a * (wo.x * wo.x + wo.y * wo.y)).sqrt();
    let dvis = 2.0 * d64(wm, a) * wo.dot(wm) / (wo.z + so);
    let di = wi.dot(wm);
    let dd = wo.dot(wm);
    dvis * (1.0 - fr64(dd, eta)) * di.abs() / (di + dd / eta).powi(2)
}
#[test]
fn debug() {
    let c = 1e-4f64;
    let wo = DVec3::new(
        (1.0 - c * c).sqrt() * 1.1f64.cos(),
        (1.0 - c * c).sqrt() * 1.1f64.sin(),
        c,
    );
    let b = Bsdf::Dielectric {
        eta: 1.5,
        roughness: rough(1.0, 1.0, Shadowing::Correlated),
    };
    let p0 = 1.1 + std::f64::consts::PI;
    for z in [-1e-3f64, -1e-2] {
        for dp in [-0.3f64, -0.1, -0.03, -0.01, -0.003, 0.0, 0.003, 0.03, 0.3] {
            let r = (1.0 - z * z).sqrt();
            let wi = DVec3::new(r * (p0 + dp).cos(), r * (p0 + dp).sin(), z);
            println!(
                "z {z} dphi {dp}: f32 {:.5} f64 {:.5}",
                b.pdf(wo.as_vec3(), wi.as_vec3()),
                pdf64(wo, wi, 1.0, 1.5)
            );
        }
    }
}
