// A reflecting BSDF about a normal-mapped shading normal, folded at the
// geometric surface so that it loses no energy: twin of
// cpu/src/bsdf/fold.rs (the derivation is there). `n` is the geometric
// normal in the shading frame on wo's side (fold_normal); a direction
// below the geometric surface leaves as its mirror image above it.
#ifndef GLINT_BSDF_FOLD_GLSL
#define GLINT_BSDF_FOLD_GLSL

#include "bsdf/bsdf.glsl"

// Fold::new: the unit geometric normal `ng` turned to wo's side.
vec3 fold_normal(vec3 ng, vec3 wo) {
    return dot(wo, ng) < 0.0 ? -ng : ng;
}

// Fold::mirror: `w` mirrored at the geometric tangent plane.
vec3 fold_mirror(vec3 n, vec3 w) {
    return w - 2.0 * dot(w, n) * n;
}

// Fold::sample after bsdf_sample, in place: a sample below the geometric
// surface leaves mirrored above it; a non-delta one is weighed by the
// folded f and pdf, the pair's other member evaluated here (the sampled
// one's f |cos| is its weight times its pdf). False where the folded pdf
// vanishes. The folded evaluation at a light sample is the integrator's
// (pathtrace.comp sums over wi and its mirror image in one loop, so the
// kernel holds one copy of bsdf_eval and bsdf_pdf there).
bool fold_sample(Material m, vec3 n, vec3 wo, inout BsdfSample s) {
    vec3 a = s.wi;
    if (!s.delta) {
        vec3 r = fold_mirror(n, a);
        float pdf = s.pdf + bsdf_pdf(m, wo, r);
        if (!(pdf > 0.0)) {
            return false;
        }
        s.weight = (s.weight * s.pdf + bsdf_eval(m, wo, r) * abs(r.z)) / pdf;
        s.pdf = pdf;
    }
    if (!(dot(a, n) > 0.0)) {
        s.wi = fold_mirror(n, a);
    }
    return true;
}

#endif
