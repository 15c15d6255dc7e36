// The BSDFs in the local shading frame (n = +z, wo toward the viewer, wi
// toward the light): line-for-line twin of cpu/src/bsdf/{mod,diffuse,
// conductor,dielectric,coated,metallic}.rs, same function names and math, so a
// CPU/GPU mismatch can be pinned to one function (tests/gpu_bsdf.rs).
//
// API: bsdf_eval, bsdf_pdf, bsdf_sample, bsdf_is_delta on a Material
// (material.glsl). Radiance transport: transmission carries 1/eta_rel^2.
#ifndef GLINT_BSDF_BSDF_GLSL
#define GLINT_BSDF_BSDF_GLSL

#include "features.glsl"
#include "bsdf/material.glsl"
#include "bsdf/fresnel.glsl"
#include "bsdf/microfacet.glsl"
#include "bsdf/warp.glsl"
#include "bsdf/multiscatter.glsl"
#include "integrator/frame.glsl"

// GLINT_INV_PI, SMOOTH_ALPHA_THRESHOLD (GGX alphas below it are rendered
// as the smooth counterpart), ETA_SMOOTH_THRESHOLD (a rough dielectric with
// |eta - 1| below it is rendered smooth), ONE_MINUS_EPS and CLEARCOAT_IOR:
// glint_abi.glsl.

struct BsdfSample {
    vec3 wi;      // sampled incident direction (local frame)
    float pdf;    // solid-angle pdf; for delta lobes the lobe's probability
    vec3 weight;  // f |cos wi| / pdf; for delta lobes the lobe's throughput
    float eta;    // eta_t / eta_i crossed by a transmission, else 1
    bool delta;   // sampled a Dirac lobe
};

// A kernel built without rough lobes (features.glsl) knows every lobe is
// smooth, and drops the microfacet code.
bool roughness_is_smooth(float alpha_u, float alpha_v) {
    return !HAS(F_ROUGH) || max(alpha_u, alpha_v) < SMOOTH_ALPHA_THRESHOLD;
}

vec2 rough_alphas(Material m) {
    return vec2(max(m.alpha_u, MIN_ALPHA), max(m.alpha_v, MIN_ALPHA));
}

// Material.shadowing: bit 0 separable; bit 1 multiscatter
// (bsdf/multiscatter.glsl).
bool material_multiscatter(Material m) {
    return (m.shadowing & SHADOWING_MULTISCATTER) != 0u;
}

bool material_separable(Material m) {
    if (!HAS(F_SMITH_CORRELATED)) {
        return true;
    }
    return HAS(F_SMITH_SEPARABLE) && (m.shadowing & SHADOWING_SEPARABLE) != 0u;
}

// Mirror both directions to the upper hemisphere when wo is below it.
void two_sided(inout vec3 wo, inout vec3 wi) {
    if (wo.z < 0.0) {
        wo.z = -wo.z;
        wi.z = -wi.z;
    }
}

// ------------------------------------------------------------------ diffuse

vec3 diffuse_eval(vec3 rho, vec3 wo, vec3 wi) {
    if (wo.z * wi.z <= 0.0) {
        return vec3(0.0);
    }
    return rho * GLINT_INV_PI;
}

float diffuse_pdf(vec3 wo, vec3 wi) {
    if (wo.z * wi.z <= 0.0) {
        return 0.0;
    }
    return abs(wi.z) * GLINT_INV_PI;
}

bool diffuse_sample(vec3 rho, vec3 wo, vec2 u, out BsdfSample s) {
    s = BsdfSample(vec3(0.0), 0.0, vec3(0.0), 1.0, false);
    if (wo.z == 0.0) {
        return false;
    }
    vec3 wi = square_to_cosine_hemisphere(u);
    if (wi.z <= 0.0) {
        return false;
    }
    if (wo.z < 0.0) {
        wi.z = -wi.z;
    }
    s = BsdfSample(wi, abs(wi.z) * GLINT_INV_PI, rho, 1.0, false);
    return true;
}

// ---------------------------------------------------------------- conductor

// F_avg x specular_reflectance of the Kulla-Conty lobe: GpuMaterial
// carries F_avg (glint_cpu::bsdf::multiscatter::fresnel_conductor_avg) in
// the .w of eta, k and specular.
vec3 conductor_f_avg(Material m) {
    return vec3(m.eta.w, m.k.w, m.specular.w) * m.specular.xyz;
}

// conductor.rs conductor_sample_ms: u.x picks the lobe (multiple
// scattering with probability 1 - E(mu_o)), rescaled for its own warp.
bool conductor_sample_ms(Material m, vec3 wo, bool flip, vec2 u, vec2 a, out BsdfSample s) {
    s = BsdfSample(vec3(0.0), 0.0, vec3(0.0), 1.0, false);
    float am = sqrt(a.x * a.y);
    bool separable = material_separable(m);
    float p_ms = conductor_ms_prob(wo.z, am, separable);
    vec3 wi;
    vec3 wm;
    if (u.x < p_ms) {
        wi = square_to_cosine_hemisphere(vec2(min(u.x / p_ms, ONE_MINUS_EPS), u.y));
        if (wi.z <= 0.0) {
            return false;
        }
        wm = normalize(wo + wi);
    } else {
        wm = ggx_sample_visible(wo, a.x, a.y, vec2(min((u.x - p_ms) / (1.0 - p_ms), ONE_MINUS_EPS), u.y));
        wi = reflect_dir(wo, wm);
        if (wi.z <= 0.0) {
            return false;
        }
    }
    float d = dot(wo, wm);
    if (d <= 0.0) {
        return false;
    }
    float pdf_ss = ggx_pdf_visible(wo, wm, a.x, a.y) / (4.0 * d);
    vec3 f_ss = fresnel_conductor(d, m.eta.xyz, m.k.xyz) * m.specular.xyz
        * (ggx_d(wm, a.x, a.y) * ggx_visibility(wo, wi, a.x, a.y, separable));
    float pdf = (1.0 - p_ms) * pdf_ss + p_ms * wi.z * GLINT_INV_PI;
    if (!(pdf > 0.0) || isinf(pdf)) {
        return false;
    }
    vec3 f = f_ss + conductor_ms_eval(wo.z, wi.z, am, separable, conductor_f_avg(m));
    vec3 weight = f * (wi.z / pdf);
    if (flip) {
        wi.z = -wi.z;
    }
    s = BsdfSample(wi, pdf, weight, 1.0, false);
    return true;
}

vec3 conductor_eval(Material m, vec3 wo, vec3 wi) {
    if (roughness_is_smooth(m.alpha_u, m.alpha_v)) {
        return vec3(0.0);
    }
    two_sided(wo, wi);
    if (wo.z <= 0.0 || wi.z <= 0.0) {
        return vec3(0.0);
    }
    vec2 a = rough_alphas(m);
    vec3 wm = normalize(wo + wi);
    vec3 f = fresnel_conductor(dot(wo, wm), m.eta.xyz, m.k.xyz) * m.specular.xyz;
    vec3 f_ss = f * (ggx_d(wm, a.x, a.y) * ggx_visibility(wo, wi, a.x, a.y, material_separable(m)));
    if (material_multiscatter(m)) {
        f_ss += conductor_ms_eval(wo.z, wi.z, sqrt(a.x * a.y), material_separable(m), conductor_f_avg(m));
    }
    return f_ss;
}

float conductor_pdf(Material m, vec3 wo, vec3 wi) {
    if (roughness_is_smooth(m.alpha_u, m.alpha_v)) {
        return 0.0;
    }
    two_sided(wo, wi);
    if (wo.z <= 0.0 || wi.z <= 0.0) {
        return 0.0;
    }
    vec2 a = rough_alphas(m);
    vec3 wm = normalize(wo + wi);
    float d = dot(wo, wm);
    if (d <= 0.0) {
        return 0.0;
    }
    float pdf_ss = ggx_pdf_visible(wo, wm, a.x, a.y) / (4.0 * d);
    if (material_multiscatter(m)) {
        float p = conductor_ms_prob(wo.z, sqrt(a.x * a.y), material_separable(m));
        return (1.0 - p) * pdf_ss + p * wi.z * GLINT_INV_PI;
    }
    return pdf_ss;
}

bool conductor_sample(Material m, vec3 wo, vec2 u, out BsdfSample s) {
    s = BsdfSample(vec3(0.0), 0.0, vec3(0.0), 1.0, false);
    if (wo.z == 0.0) {
        return false;
    }
    bool flip = wo.z < 0.0;
    vec3 wo_up = vec3(wo.x, wo.y, abs(wo.z));
    if (roughness_is_smooth(m.alpha_u, m.alpha_v)) {
        vec3 f = fresnel_conductor(wo_up.z, m.eta.xyz, m.k.xyz) * m.specular.xyz;
        s = BsdfSample(vec3(-wo.x, -wo.y, wo.z), 1.0, f, 1.0, true);
        return true;
    }
    vec2 a = rough_alphas(m);
    if (material_multiscatter(m)) {
        return conductor_sample_ms(m, wo_up, flip, u, a, s);
    }
    vec3 wm = ggx_sample_visible(wo_up, a.x, a.y, u);
    float d = dot(wo_up, wm);
    vec3 wi = reflect_dir(wo_up, wm);
    if (wi.z <= 0.0 || d <= 0.0) {
        return false;
    }
    // pdf and weight from the sampled normal (see conductor.rs).
    float pdf = ggx_pdf_visible(wo_up, wm, a.x, a.y) / (4.0 * d);
    float g1 = ggx_g1(wo_up, a.x, a.y);
    if (!(pdf > 0.0) || isinf(pdf) || !(g1 > 0.0)) {
        return false;
    }
    vec3 f = fresnel_conductor(d, m.eta.xyz, m.k.xyz) * m.specular.xyz;
    vec3 weight = f * (ggx_g2(wo_up, wi, a.x, a.y, material_separable(m)) / g1);
    if (flip) {
        wi.z = -wi.z;
    }
    s = BsdfSample(wi, pdf, weight, 1.0, false);
    return true;
}

// --------------------------------------------------------------- dielectric

bool dielectric_is_smooth(float eta, Material m) {
    return roughness_is_smooth(m.alpha_u, m.alpha_v) || abs(eta - 1.0) < ETA_SMOOTH_THRESHOLD;
}

// dielectric.rs dielectric_ms_scale: 1 / E(mu_o) of the single-scattering
// lobe seen from wo's side with `multiscatter` (Turquin 2019), else 1.
float dielectric_ms_scale(float eta, Material m, vec3 wo) {
    if (!material_multiscatter(m)) {
        return 1.0;
    }
    vec2 a = rough_alphas(m);
    float side_eta = wo.z >= 0.0 ? eta : 1.0 / eta;
    float e = dielectric_ms_albedo(abs(wo.z), sqrt(a.x * a.y), side_eta, material_separable(m));
    return e > 0.0 ? 1.0 / e : 1.0;
}

// Generalised half vector (Walter 2007 eq. 16), face-forwarded to +z;
// false when degenerate or back-facing.
bool dielectric_half_vector(float eta, vec3 wo, vec3 wi, out vec3 wm, out float etap,
                            out bool is_reflection) {
    float co = wo.z;
    float ci = wi.z;
    wm = vec3(0.0, 0.0, 1.0);
    etap = 1.0;
    is_reflection = co * ci > 0.0;
    if (co == 0.0 || ci == 0.0) {
        return false;
    }
    etap = is_reflection ? 1.0 : (co > 0.0 ? eta : 1.0 / eta);
    vec3 h = wi * etap + wo;
    float len2 = dot(h, h);
    if (!(len2 > 1e-12)) {
        return false;
    }
    wm = h / sqrt(len2);
    if (wm.z < 0.0) {
        wm = -wm;
    }
    if (dot(wm, wi) * ci <= 0.0 || dot(wm, wo) * co <= 0.0) {
        return false;
    }
    return true;
}

vec3 dielectric_eval(float eta, Material m, vec3 wo, vec3 wi) {
    if (dielectric_is_smooth(eta, m)) {
        return vec3(0.0);
    }
    vec3 wm;
    float etap;
    bool is_reflection;
    if (!dielectric_half_vector(eta, wo, wi, wm, etap, is_reflection)) {
        return vec3(0.0);
    }
    vec2 a = rough_alphas(m);
    float d = ggx_d(wm, a.x, a.y);
    float v = ggx_visibility(wo, wi, a.x, a.y, material_separable(m));
    float f = fresnel_dielectric(dot(wo, wm), eta);
    float scale = dielectric_ms_scale(eta, m, wo);
    if (is_reflection) {
        return vec3(d * f * v * scale);
    }
    float dot_i = dot(wi, wm);
    float dot_o = dot(wo, wm);
    float denom = (dot_i + dot_o / etap) * (dot_i + dot_o / etap);
    if (!(denom > 0.0)) {
        return vec3(0.0);
    }
    float ft = d * (1.0 - f) * 4.0 * v * abs(dot_i * dot_o) / denom;
    return vec3(ft / (etap * etap) * scale);
}

float dielectric_pdf(float eta, Material m, vec3 wo, vec3 wi) {
    if (dielectric_is_smooth(eta, m)) {
        return 0.0;
    }
    vec3 wm;
    float etap;
    bool is_reflection;
    if (!dielectric_half_vector(eta, wo, wi, wm, etap, is_reflection)) {
        return 0.0;
    }
    vec2 a = rough_alphas(m);
    float dot_o = dot(wo, wm);
    float dot_i = dot(wi, wm);
    float pr = fresnel_dielectric(dot_o, eta);
    float pt = 1.0 - pr;
    float pdf_wm = ggx_pdf_visible(wo, wm, a.x, a.y);
    if (is_reflection) {
        return pdf_wm / (4.0 * abs(dot_o)) * pr;
    }
    float denom = (dot_i + dot_o / etap) * (dot_i + dot_o / etap);
    if (!(denom > 0.0)) {
        return 0.0;
    }
    return pdf_wm * (abs(dot_i) / denom) * pt;
}

bool dielectric_sample(float eta, Material m, vec3 wo, float uc, vec2 u, out BsdfSample s) {
    s = BsdfSample(vec3(0.0), 0.0, vec3(0.0), 1.0, false);
    if (wo.z == 0.0) {
        return false;
    }
    if (dielectric_is_smooth(eta, m)) {
        float pr = fresnel_dielectric(wo.z, eta);
        if (uc < pr) {
            s = BsdfSample(vec3(-wo.x, -wo.y, wo.z), pr, vec3(1.0), 1.0, true);
            return true;
        }
        vec3 wt;
        float etap;
        if (!refract_dir(wo, vec3(0.0, 0.0, 1.0), eta, wt, etap)) {
            return false;
        }
        if (wt.z == 0.0) {
            return false;
        }
        s = BsdfSample(wt, 1.0 - pr, vec3(1.0 / (etap * etap)), etap, true);
        return true;
    }
    vec2 a = rough_alphas(m);
    vec3 wm = ggx_sample_visible(wo, a.x, a.y, u);
    float dot_o = dot(wo, wm);
    float pr = fresnel_dielectric(dot_o, eta);
    float pdf_wm = ggx_pdf_visible(wo, wm, a.x, a.y);
    float g1 = ggx_g1(wo, a.x, a.y);
    if (!(g1 > 0.0)) {
        return false;
    }
    bool separable = material_separable(m);
    vec3 wi;
    float pdf;
    float weight;
    float eta_rel;
    if (uc < pr) {
        wi = reflect_dir(wo, wm);
        if (wi.z * wo.z <= 0.0) {
            return false;
        }
        pdf = pdf_wm / (4.0 * abs(dot_o)) * pr;
        weight = ggx_g2(wo, wi, a.x, a.y, separable) / g1;
        eta_rel = 1.0;
    } else {
        float etap;
        if (!refract_dir(wo, wm, eta, wi, etap)) {
            return false;
        }
        if (wi.z * wo.z >= 0.0) {
            return false;
        }
        float dot_i = dot(wi, wm);
        float denom = (dot_i + dot_o / etap) * (dot_i + dot_o / etap);
        if (!(denom > 0.0)) {
            return false;
        }
        pdf = pdf_wm * (abs(dot_i) / denom) * (1.0 - pr);
        weight = ggx_g2(wo, wi, a.x, a.y, separable) / g1 / (etap * etap);
        eta_rel = etap;
    }
    if (!(pdf > 0.0) || isinf(pdf)) {
        return false;
    }
    vec3 hm;
    float hetap;
    bool hrefl;
    if (!dielectric_half_vector(eta, wo, wi, hm, hetap, hrefl)) {
        return false;
    }
    s = BsdfSample(wi, pdf, vec3(weight * dielectric_ms_scale(eta, m, wo)), eta_rel, false);
    return true;
}

// ------------------------------------------------------------------ coated

#include "bsdf/coated.glsl"
#include "bsdf/plastic.glsl"

// ----------------------------------------------------------------- metallic

// metallic.rs: the conductor with probability w, the coated non-metal of
// base and m.coat with 1 - w (Mitsuba 3's blendbsdf); its f and density are
// gltf_inner_eval's and gltf_inner_pdf's below. A lobe of weight exactly
// zero (metallic 0 or 1) is not evaluated: its term added nothing
// (metallic.rs, `lobes`).
bool metallic_sample(float w, vec3 base, Material m, vec3 wo, float uc, vec2 u,
                     out BsdfSample s) {
    // One call of each lobe's sample (lavapipe's compile time grows with
    // every inlined copy); w = 0 is the non-metal alone, its sample as it is.
    bool metal = uc < w;
    bool ok;
    if (metal) {
        ok = conductor_sample(m, wo, u, s);
    } else {
        float ucn = w == 0.0 ? uc : clamp((uc - w) / (1.0 - w), 0.0, ONE_MINUS_EPS);
        ok = coated_sample(base, m, wo, ucn, u, s);
    }
    if (!ok || w == 0.0) {
        return ok;
    }
    if (s.delta) {
        s.pdf = metal ? w : (1.0 - w) * s.pdf;
        return true;
    }
    vec3 wi = s.wi;
    vec3 f_s = s.weight * (s.pdf / abs(wi.z));
    float pdf_c;
    vec3 f_c;
    float pdf_n;
    vec3 f_n;
    if (metal) {
        pdf_c = s.pdf;
        f_c = f_s;
        pdf_n = 0.0;
        f_n = vec3(0.0);
        if (1.0 - w != 0.0) {
            pdf_n = coated_pdf(base, m, wo, wi);
            f_n = coated_eval(base, m, wo, wi);
        }
    } else {
        pdf_n = s.pdf;
        f_n = f_s;
        pdf_c = conductor_pdf(m, wo, wi);
        f_c = conductor_eval(m, wo, wi);
    }
    float pdf = w * pdf_c + (1.0 - w) * pdf_n;
    if (!(pdf > 0.0) || isinf(pdf)) {
        s = BsdfSample(vec3(0.0), 0.0, vec3(0.0), 1.0, false);
        return false;
    }
    vec3 f = w * f_c + (1.0 - w) * f_n;
    s = BsdfSample(wi, pdf, f * (abs(wi.z) / pdf), 1.0, false);
    return true;
}

// --------------------------------------------------------------- clearcoat
// clearcoat.rs: a GGX coat (IOR 1.5) of weight c = m.extra.y, alpha
// m.extra.z, normal m.extra.w (encode_coat_normal; 0: the shading normal),
// over the coated and metallic kinds:
// f = c f_cc + w(mu_o) w(mu_i) f_inner, w(mu) = 1 - c E_cc(mu), the coat's
// terms about its own normal, its lobe carrying the coat's cosine.

bool cc_smooth(Material m) {
    return !HAS(F_ROUGH) || m.extra.z < SMOOTH_ALPHA_THRESHOLD;
}

// bsdf::clearcoat::decode_coat_normal.
vec2 decode_coat_normal(float e) {
    if (e < 1.0) {
        return vec2(0.0);
    }
    uint k = uint(e) - 1u;
    vec2 q = vec2(float(k / COAT_NORMAL_STRIDE), float(k % COAT_NORMAL_STRIDE));
    return q / float(COAT_NORMAL_STEPS) - 1.0;
}

bool cc_tilted(Material m) {
    return m.extra.w >= 1.0;
}

Frame cc_frame(Material m) {
    vec2 xy = decode_coat_normal(m.extra.w);
    return frame_from_normal(vec3(xy, sqrt(max(1.0 - dot(xy, xy), 0.0))));
}

// Clearcoat::local / world: front-side shading directions in the coat's
// frame and back.
vec3 cc_local(Material m, vec3 w) {
    return cc_tilted(m) ? frame_to_local(cc_frame(m), w) : w;
}

vec3 cc_world(Material m, vec3 w) {
    return cc_tilted(m) ? frame_to_world(cc_frame(m), w) : w;
}

vec3 cc_front(vec3 w, float side) {
    return vec3(w.x, w.y, w.z * side);
}

float cc_side(vec3 wo) {
    return wo.z < 0.0 ? -1.0 : 1.0;
}

// Clearcoat::shading_value.
float cc_shading_value(Material m, float f, vec3 wi_c, float wi_z) {
    if (!cc_tilted(m)) {
        return f;
    }
    return wi_z == 0.0 ? 0.0 : f * (abs(wi_c.z) / abs(wi_z));
}

// w(mu) for `w`, wo on the side `side`.
float cc_through(Material m, vec3 w, float side) {
    float mu = abs(cc_local(m, cc_front(w, side)).z);
    return 1.0 - m.extra.y * coat_albedo(mu, max(m.extra.z, MIN_ALPHA), CLEARCOAT_IOR, cc_smooth(m));
}

float cc_p_coat(Material m, vec3 wo) {
    return clamp(1.0 - cc_through(m, wo, cc_side(wo)), 0.0, 1.0);
}

// The coat's pair (wo, wi) in its frame on the front side, and their half
// vector and cosine; false where the coat's lobe is 0 (smooth, or wi and
// wo on different sides of the coat).
bool cc_pair(Material m, vec3 wo, vec3 wi, out vec3 wo_c, out vec3 wi_c, out vec3 h, out float d) {
    if (cc_smooth(m) || wo.z == 0.0) {
        return false;
    }
    float side = cc_side(wo);
    wo_c = cc_local(m, cc_front(wo, side));
    wi_c = cc_local(m, cc_front(wi, side));
    if (wo_c.z <= 0.0 || wi_c.z <= 0.0) {
        return false;
    }
    h = normalize(wo_c + wi_c);
    d = dot(wo_c, h);
    return d > 0.0;
}

float cc_coat_eval(Material m, vec3 wo, vec3 wi) {
    vec3 wo_c, wi_c, h;
    float d;
    if (!cc_pair(m, wo, wi, wo_c, wi_c, h, d)) {
        return 0.0;
    }
    float a = max(m.extra.z, MIN_ALPHA);
    float f = m.extra.y * fresnel_dielectric(d, CLEARCOAT_IOR) * ggx_d(h, a, a)
        * ggx_visibility(wo_c, wi_c, a, a, false);
    return cc_shading_value(m, f, wi_c, wi.z);
}

float cc_coat_pdf(Material m, vec3 wo, vec3 wi) {
    vec3 wo_c, wi_c, h;
    float d;
    if (!cc_pair(m, wo, wi, wo_c, wi_c, h, d)) {
        return 0.0;
    }
    float a = max(m.extra.z, MIN_ALPHA);
    return ggx_pdf_visible(wo_c, h, a, a) / (4.0 * d);
}

// The glTF material under its clear coat: the coated non-metal, or the
// metallic blend of a conductor and the coated non-metal. Each with one
// call of coated_* (lavapipe's compile time grows with every inlined copy):
// the non-metal is the blend's non-metal part, alone.
bool gltf_is_coated(Material m) {
    return HAS(F_COATED) && (!HAS(F_METALLIC) || m.kind == KIND_COATED);
}

vec3 gltf_inner_eval(Material m, vec3 wo, vec3 wi) {
    float w = gltf_is_coated(m) ? 0.0 : m.reflectance.w;
    vec3 f_c = w != 0.0 ? conductor_eval(m, wo, wi) : vec3(0.0);
    vec3 f_n = 1.0 - w != 0.0 ? coated_eval(m.reflectance.xyz, m, wo, wi) : vec3(0.0);
    return w * f_c + (1.0 - w) * f_n;
}

float gltf_inner_pdf(Material m, vec3 wo, vec3 wi) {
    float w = gltf_is_coated(m) ? 0.0 : m.reflectance.w;
    float pdf_c = w != 0.0 ? conductor_pdf(m, wo, wi) : 0.0;
    float pdf_n = 1.0 - w != 0.0 ? coated_pdf(m.reflectance.xyz, m, wo, wi) : 0.0;
    return w * pdf_c + (1.0 - w) * pdf_n;
}

bool gltf_inner_sample(Material m, vec3 wo, float uc, vec2 u, out BsdfSample s) {
    return metallic_sample(gltf_is_coated(m) ? 0.0 : m.reflectance.w, m.reflectance.xyz, m, wo,
                           uc, u, s);
}

vec3 gltf_eval(Material m, vec3 wo, vec3 wi) {
    vec3 inner = gltf_inner_eval(m, wo, wi);
    if (m.extra.y <= 0.0) {
        return inner;
    }
    float side = cc_side(wo);
    return vec3(cc_coat_eval(m, wo, wi)) + inner * (cc_through(m, wo, side) * cc_through(m, wi, side));
}

float gltf_pdf(Material m, vec3 wo, vec3 wi) {
    float inner = gltf_inner_pdf(m, wo, wi);
    if (m.extra.y <= 0.0) {
        return inner;
    }
    float p = cc_p_coat(m, wo);
    return p * cc_coat_pdf(m, wo, wi) + (1.0 - p) * inner;
}

// The clear coat's own lobe picked (probability p; w_o its transmission
// at wo, on side `side`): its sample, the inner material evaluated there.
bool cc_coat_sample(Material m, vec3 wo, vec2 u, float side, float p, float w_o,
                    inout BsdfSample s) {
    // In the coat's frame, on the front side.
    vec3 up = cc_local(m, cc_front(wo, side));
    if (up.z <= 0.0) {
        return false;
    }
    if (cc_smooth(m)) {
        float f = m.extra.y * fresnel_dielectric(up.z, CLEARCOAT_IOR);
        s = BsdfSample(cc_front(cc_world(m, vec3(-up.x, -up.y, up.z)), side), p, vec3(f / p), 1.0, true);
        return true;
    }
    float a = max(m.extra.z, MIN_ALPHA);
    vec3 wm = ggx_sample_visible(up, a, a, u);
    float d = dot(up, wm);
    vec3 wi_c = reflect_dir(up, wm);
    if (wi_c.z <= 0.0 || d <= 0.0 || !(ggx_g1(up, a, a) > 0.0)) {
        return false;
    }
    float pdf_c = ggx_pdf_visible(up, wm, a, a) / (4.0 * d);
    vec3 wi = cc_front(cc_world(m, wi_c), side);
    float f_c = cc_shading_value(m, m.extra.y * fresnel_dielectric(d, CLEARCOAT_IOR) * ggx_d(wm, a, a)
        * ggx_g2(up, wi_c, a, a, false) / (4.0 * up.z * wi_c.z), wi_c, wi.z);
    float pdf = p * pdf_c + (1.0 - p) * gltf_inner_pdf(m, wo, wi);
    if (!(pdf > 0.0) || isinf(pdf)) {
        return false;
    }
    vec3 f = vec3(f_c) + gltf_inner_eval(m, wo, wi) * (w_o * cc_through(m, wi, side));
    s = BsdfSample(wi, pdf, f * (abs(wi.z) / pdf), 1.0, false);
    return true;
}

bool gltf_sample(Material m, vec3 wo, float uc, vec2 u, out BsdfSample s) {
    // One call of the inner material's sample (lavapipe's compile time
    // grows with every inlined copy): without a clear coat, its sample as
    // it is.
    bool cc = m.extra.y > 0.0;
    float side = 0.0;
    float p = 0.0;
    float w_o = 0.0;
    if (cc) {
        s = BsdfSample(vec3(0.0), 0.0, vec3(0.0), 1.0, false);
        if (wo.z == 0.0) {
            return false;
        }
        side = cc_side(wo);
        p = cc_p_coat(m, wo);
        w_o = cc_through(m, wo, side);
        if (uc < p) {
            return cc_coat_sample(m, wo, u, side, p, w_o, s);
        }
    }
    float uci = cc ? clamp((uc - p) / (1.0 - p), 0.0, ONE_MINUS_EPS) : uc;
    bool ok = gltf_inner_sample(m, wo, uci, u, s);
    if (!ok || !cc) {
        return ok;
    }
    float w_i = cc_through(m, s.wi, side);
    if (s.delta) {
        s.weight *= w_o * w_i / (1.0 - p);
        s.pdf *= 1.0 - p;
        return true;
    }
    vec3 f_in = s.weight * (s.pdf / abs(s.wi.z));
    float pdf = p * cc_coat_pdf(m, wo, s.wi) + (1.0 - p) * s.pdf;
    if (!(pdf > 0.0) || isinf(pdf)) {
        s = BsdfSample(vec3(0.0), 0.0, vec3(0.0), 1.0, false);
        return false;
    }
    vec3 f = vec3(cc_coat_eval(m, wo, s.wi)) + f_in * (w_o * w_i);
    s.weight = f * (abs(s.wi.z) / pdf);
    s.pdf = pdf;
    return true;
}

// ---------------------------------------------------------------- dispatch

// Each dispatcher names every kind and ends in this error value: a kind no
// branch knows (a tag added on the Rust side only) gives NaN, which the
// per-call test (tests/gpu_bsdf.rs) sees, never another BSDF's values.
#define BSDF_UNKNOWN_KIND uintBitsToFloat(0x7fc00000u)

// A dielectric's Mitsuba specular_reflectance (.specular) and
// specular_transmittance (.reflectance) for the pair (wo, wi): bsdf::Tint.
vec3 dielectric_tint(Material m, vec3 wo, vec3 wi) {
    return wo.z * wi.z > 0.0 ? m.specular.xyz : m.reflectance.xyz;
}

// The glTF models, coated non-metal and metal: one branch, so that each
// call site inlines gltf_* once (lavapipe's compile time grows with every
// inlined copy).
#define IS_GLTF(m) ((HAS(F_COATED) && (m).kind == KIND_COATED) || (HAS(F_METALLIC) && (m).kind == KIND_METALLIC))

vec3 bsdf_eval(Material m, vec3 wo, vec3 wi) {
    if (HAS(F_DIFFUSE) && m.kind == KIND_DIFFUSE) {
        return diffuse_eval(m.reflectance.xyz, wo, wi);
    } else if (HAS(F_CONDUCTOR) && m.kind == KIND_CONDUCTOR) {
        return conductor_eval(m, wo, wi);
    } else if (HAS(F_DIELECTRIC) && m.kind == KIND_DIELECTRIC) {
        return dielectric_eval(m.eta.x, m, wo, wi) * dielectric_tint(m, wo, wi);
    } else if (IS_GLTF(m)) {
        return gltf_eval(m, wo, wi);
    } else if (HAS(F_PLASTIC) && m.kind == KIND_PLASTIC) {
        return plastic_eval(m, wo, wi);
    } else if (HAS(F_PLASTIC) && m.kind == KIND_ROUGH_PLASTIC) {
        return roughplastic_eval(m, wo, wi);
    } else if (HAS(F_THIN_DIELECTRIC) && m.kind == KIND_THIN_DIELECTRIC) {
        return vec3(0.0);
    }
    return vec3(BSDF_UNKNOWN_KIND);
}

float bsdf_pdf(Material m, vec3 wo, vec3 wi) {
    if (HAS(F_DIFFUSE) && m.kind == KIND_DIFFUSE) {
        return diffuse_pdf(wo, wi);
    } else if (HAS(F_CONDUCTOR) && m.kind == KIND_CONDUCTOR) {
        return conductor_pdf(m, wo, wi);
    } else if (HAS(F_DIELECTRIC) && m.kind == KIND_DIELECTRIC) {
        return dielectric_pdf(m.eta.x, m, wo, wi);
    } else if (IS_GLTF(m)) {
        return gltf_pdf(m, wo, wi);
    } else if (HAS(F_PLASTIC) && m.kind == KIND_PLASTIC) {
        return plastic_pdf(m, wo, wi);
    } else if (HAS(F_PLASTIC) && m.kind == KIND_ROUGH_PLASTIC) {
        return roughplastic_pdf(m, wo, wi);
    } else if (HAS(F_THIN_DIELECTRIC) && m.kind == KIND_THIN_DIELECTRIC) {
        return 0.0;
    }
    return BSDF_UNKNOWN_KIND;
}

bool bsdf_sample(Material m, vec3 wo, float uc, vec2 u, out BsdfSample s) {
    if (HAS(F_DIFFUSE) && m.kind == KIND_DIFFUSE) {
        return diffuse_sample(m.reflectance.xyz, wo, u, s);
    } else if (HAS(F_CONDUCTOR) && m.kind == KIND_CONDUCTOR) {
        return conductor_sample(m, wo, u, s);
    } else if (HAS(F_DIELECTRIC) && m.kind == KIND_DIELECTRIC) {
        bool ok = dielectric_sample(m.eta.x, m, wo, uc, u, s);
        s.weight *= dielectric_tint(m, wo, s.wi);
        return ok;
    } else if (IS_GLTF(m)) {
        return gltf_sample(m, wo, uc, u, s);
    } else if (HAS(F_PLASTIC) && m.kind == KIND_PLASTIC) {
        return plastic_sample(m, wo, uc, u, s);
    } else if (HAS(F_PLASTIC) && m.kind == KIND_ROUGH_PLASTIC) {
        return roughplastic_sample(m, wo, uc, u, s);
    } else if (HAS(F_THIN_DIELECTRIC) && m.kind == KIND_THIN_DIELECTRIC) {
        return thin_sample(m, wo, uc, s);
    }
    s.wi = vec3(0.0, 0.0, 1.0);
    s.weight = vec3(BSDF_UNKNOWN_KIND);
    s.pdf = BSDF_UNKNOWN_KIND;
    s.eta = 1.0;
    s.delta = false;
    return true;
}

bool bsdf_is_delta(Material m) {
    if (HAS(F_DIFFUSE) && m.kind == KIND_DIFFUSE) {
        return false;
    } else if (HAS(F_CONDUCTOR) && m.kind == KIND_CONDUCTOR) {
        return roughness_is_smooth(m.alpha_u, m.alpha_v);
    } else if (HAS(F_DIELECTRIC) && m.kind == KIND_DIELECTRIC) {
        return dielectric_is_smooth(m.eta.x, m);
    } else if (HAS(F_COATED) && m.kind == KIND_COATED) {
        return m.extra.x >= 1.0 && roughness_is_smooth(m.alpha_u, m.alpha_v)
            && (m.extra.y <= 0.0 || cc_smooth(m));
    } else if (HAS(F_PLASTIC) && (m.kind == KIND_PLASTIC || m.kind == KIND_ROUGH_PLASTIC)) {
        return false;
    } else if (HAS(F_THIN_DIELECTRIC) && m.kind == KIND_THIN_DIELECTRIC) {
        return true;
    }
    return HAS(F_METALLIC) && m.kind == KIND_METALLIC && (m.reflectance.w >= 1.0 || m.extra.x >= 1.0)
        && roughness_is_smooth(m.alpha_u, m.alpha_v) && (m.extra.y <= 0.0 || cc_smooth(m));
}

bool bsdf_has_transmission(Material m) {
    return (HAS(F_DIELECTRIC) && m.kind == KIND_DIELECTRIC)
        || (HAS(F_THIN_DIELECTRIC) && m.kind == KIND_THIN_DIELECTRIC)
        || ((m.kind == KIND_COATED || m.kind == KIND_METALLIC) && m.extra.x > 0.0);
}

#endif
