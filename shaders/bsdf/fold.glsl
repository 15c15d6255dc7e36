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

// Fold::reweigh, after bsdf_sample, in place: a sample below the geometric
// surface leaves mirrored above it; a non-delta one is weighed by the
// folded f and pdf, from the sampled direction's f |cos| (its weight times
// its pdf) and its mirror image's, `partner_f` and `partner_pdf` (which
// pathtrace.comp evaluates in its light sample's loop, so that the kernel
// holds one copy of bsdf_eval and bsdf_pdf). False where the folded pdf
// vanishes.
bool fold_reweigh(vec3 n, vec3 partner_f, float partner_pdf, inout BsdfSample s) {
    vec3 a = s.wi;
    if (!s.delta) {
        float pdf = s.pdf + partner_pdf;
        if (!(pdf > 0.0)) {
            return false;
        }
        s.weight = (s.weight * s.pdf + partner_f) / pdf;
        s.pdf = pdf;
    }
    if (!(dot(a, n) > 0.0)) {
        s.wi = fold_mirror(n, a);
    }
    return true;
}

#endif
