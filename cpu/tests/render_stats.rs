//! Statistical properties of whole renders: determinism, MIS correctness
//! (next-event estimation against BSDF sampling alone), and the image
//! comparison itself (it passes on independent renders and catches a 3%
//! bias).

mod render_common;

use glam::Vec3;
use glint_cpu::Material;
use glint_cpu::bsdf::{Bsdf, ConductorParams, Roughness, Shadowing, named_metal};
use glint_cpu::compare::compare_films;
use render_common::*;

const SIZE: u32 = 32;

#[test]
fn same_seed_is_bit_identical_and_another_seed_differs() {
    let s = lit_room(vec![]);
    let a = render(&s, &opts(SIZE, 4, -1, 11));
    let b = render(&s, &opts(SIZE, 4, -1, 11));
    assert_eq!(a, b);
    let c = render(&s, &opts(SIZE, 4, -1, 12));
    assert_ne!(a.sum, c.sum);
    // Different seeds are still the same picture.
    let r = compare_films(&a, &c).unwrap();
    assert!(r.pass, "{r}");
}

#[test]
fn next_event_estimation_with_mis_agrees_with_bsdf_sampling_alone() {
    // The room has an area light and a background: with NEE each is found
    // by light sampling and by BSDF sampling, weighted by the power
    // heuristic; without NEE only by BSDF sampling (weight 1). Any error in
    // a pdf, a MIS weight or a missing contribution breaks the agreement.
    let s = lit_room(vec![]);
    let with = render(&s, &opts(SIZE, 64, -1, 21));
    let without = render_no_nee(&s, &opts(SIZE, 256, -1, 22));
    let r = compare_films(&with, &without).unwrap();
    assert!(r.pass, "{r}");
    // Direct lighting alone too (max depth 2), where MIS does all the work.
    let with = render(&s, &opts(SIZE, 64, 2, 23));
    let without = render_no_nee(&s, &opts(SIZE, 256, 2, 24));
    let r = compare_films(&with, &without).unwrap();
    assert!(r.pass, "depth 2: {r}");
}

#[test]
fn mis_agrees_on_glossy_and_transmissive_surfaces() {
    // The sphere as a rough conductor (a GGX pdf, not a cosine) and as a
    // rough dielectric (transmission: the background is sampled over the
    // whole sphere there): light sampling + MIS against BSDF sampling alone.
    let (eta, k) = named_metal("Cu").unwrap();
    let rough = Roughness {
        alpha_u: 0.3,
        alpha_v: 0.15,
        shadowing: Shadowing::Correlated,
        multiscatter: false,
    };
    let materials = [
        Bsdf::Conductor(ConductorParams {
            eta,
            k,
            specular_reflectance: Vec3::ONE,
            roughness: rough,
        }),
        Bsdf::Dielectric {
            eta: 1.5,
            roughness: rough,
        },
    ];
    for (i, bsdf) in materials.into_iter().enumerate() {
        let s = lit_room(vec![Material {
            name: "sphere".into(),
            bsdf,
            emission: Vec3::ZERO,
            double_sided: false,
        }]);
        let with = render(&s, &opts(SIZE, 64, -1, 41 + i as u64));
        let without = render_no_nee(&s, &opts(SIZE, 256, -1, 51 + i as u64));
        let r = compare_films(&with, &without).unwrap();
        assert!(r.pass, "{bsdf:?}: {r}");
    }
}

#[test]
fn comparison_passes_independent_renders_and_fails_a_three_percent_bias() {
    let s = lit_room(vec![]);
    let a = render(&s, &opts(SIZE, 64, -1, 31));
    let b = render(&s, &opts(SIZE, 64, -1, 32));
    let r = compare_films(&a, &b).unwrap();
    assert!(r.pass, "independent renders: {r}");
    let mut biased = b.clone();
    for (s, s2) in biased.sum.iter_mut().zip(biased.sum_sq.iter_mut()) {
        *s *= 1.03;
        *s2 *= 1.03 * 1.03;
    }
    let r = compare_films(&a, &biased).unwrap();
    assert!(!r.pass, "a 3% bias must be caught: {r}");
}
