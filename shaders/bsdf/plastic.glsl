// Mitsuba 3's smooth plastic and thindielectric: cpu/src/bsdf/{plastic,thin}.rs
// function by function (read their headers). Included by bsdf.glsl.
// Material: plastic reflectance.xyz diffuse, .w nonlinear, specular.xyz,
// eta.x; thindielectric eta.x, specular.xyz reflectance, k.xyz
// transmittance.
#ifndef GLINT_BSDF_PLASTIC_GLSL
#define GLINT_BSDF_PLASTIC_GLSL

float fresnel_diffuse_reflectance(float eta) {
    float inv = 1.0 / eta;
    if (eta < 1.0) {
        return 0.0636 * inv + (eta * (eta * -1.4399 + 0.7099) + 0.6681);
    }
    const float c[6] = float[6](0.919317, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881);
    float acc = c[5];
    for (int k = 4; k >= 0; k--) {
        acc = acc * inv + c[k];
    }
    return acc;
}

float plastic_mean(vec3 v) {
    return (v.x + v.y + v.z) * (1.0 / 3.0);
}

float plastic_sampling_weight(Material m) {
    float s = plastic_mean(m.specular.xyz);
    float d = plastic_mean(m.reflectance.xyz);
    return s + d > 0.0 ? s / (s + d) : 0.5;
}

vec3 plastic_diffuse_scaled(Material m) {
    float fdr = fresnel_diffuse_reflectance(1.0 / m.eta.x);
    vec3 rho = m.reflectance.xyz;
    return m.reflectance.w != 0.0 ? rho / (vec3(1.0) - rho * fdr) : rho / (1.0 - fdr);
}

// (P, 1 - P) of the mirror at mu_o.
vec2 plastic_probabilities(Material m, float mu_o) {
    float f = fresnel_dielectric(mu_o, m.eta.x);
    float w = plastic_sampling_weight(m);
    float s = f * w;
    float d = (1.0 - f) * (1.0 - w);
    return s + d > 0.0 ? vec2(s / (s + d), d / (s + d)) : vec2(0.0, 1.0);
}

vec3 plastic_diffuse_term(Material m, float mu_o, float mu_i) {
    float fo = fresnel_dielectric(mu_o, m.eta.x);
    float fi = fresnel_dielectric(mu_i, m.eta.x);
    return plastic_diffuse_scaled(m) * ((1.0 - fo) * (1.0 - fi) * GLINT_INV_PI / (m.eta.x * m.eta.x));
}

vec3 plastic_eval(Material m, vec3 wo, vec3 wi) {
    two_sided(wo, wi);
    if (wo.z <= 0.0 || wi.z <= 0.0) {
        return vec3(0.0);
    }
    return plastic_diffuse_term(m, wo.z, wi.z);
}

float plastic_pdf(Material m, vec3 wo, vec3 wi) {
    two_sided(wo, wi);
    if (wo.z <= 0.0 || wi.z <= 0.0) {
        return 0.0;
    }
    return plastic_probabilities(m, wo.z).y * wi.z * GLINT_INV_PI;
}

bool plastic_sample(Material m, vec3 wo, float uc, vec2 u, out BsdfSample s) {
    s = BsdfSample(vec3(0.0), 0.0, vec3(0.0), 1.0, false);
    if (wo.z == 0.0) {
        return false;
    }
    bool flip = wo.z < 0.0;
    float mu_o = abs(wo.z);
    vec2 p = plastic_probabilities(m, mu_o);
    if (uc < p.x) {
        vec3 f = m.specular.xyz * fresnel_dielectric(mu_o, m.eta.x);
        s = BsdfSample(vec3(-wo.x, -wo.y, wo.z), p.x, f / p.x, 1.0, true);
        return true;
    }
    vec3 wi = square_to_cosine_hemisphere(u);
    if (wi.z <= 0.0 || !(p.y > 0.0)) {
        return false;
    }
    float pdf = p.y * wi.z * GLINT_INV_PI;
    vec3 weight = plastic_diffuse_term(m, mu_o, wi.z) * (wi.z / pdf);
    if (flip) {
        wi.z = -wi.z;
    }
    s = BsdfSample(wi, pdf, weight, 1.0, false);
    return true;
}

// ------------------------------------------------------------ thindielectric

float thin_reflectance(float mu, float eta) {
    float r = fresnel_dielectric(min(abs(mu), 1.0), eta);
    return 2.0 * r / (1.0 + r);
}

bool thin_sample(Material m, vec3 wo, float uc, out BsdfSample s) {
    s = BsdfSample(vec3(0.0), 0.0, vec3(0.0), 1.0, false);
    if (wo.z == 0.0) {
        return false;
    }
    float r = thin_reflectance(wo.z, m.eta.x);
    if (uc < r) {
        s = BsdfSample(vec3(-wo.x, -wo.y, wo.z), r, m.specular.xyz, 1.0, true);
    } else {
        s = BsdfSample(-wo, 1.0 - r, m.k.xyz, 1.0, true);
    }
    return true;
}

// ------------------------------------------------------------ roughplastic
// cpu/src/bsdf/roughplastic.rs. Material as plastic, plus alpha_u (isotropic)
// and the Smith form bit; the tables come after the coat's (MS_OFF_RP).

float rp_at(uint base, uint i, uint j, uint k) {
    return MS_AT(base + (k * RP_N_ALPHA + j) * RP_N_MU + i);
}

float rp_transmittance(float mu, float alpha, float eta, bool separable) {
    uint base = MS_OFF_RP + (separable ? RP_T_LEN : 0u);
    float fx, fy, fz;
    uint i = coat_cell(mu, RP_N_MU, fx);
    uint j = coat_cell(sqrt(alpha), RP_N_ALPHA, fy);
    uint k = coat_cell(coat_eta_coord(eta), RP_N_ETA, fz);
    float p[2];
    for (uint d = 0u; d < 2u; d++) {
        uint kk = k + d;
        float a = rp_at(base, i, j, kk) + (rp_at(base, i + 1u, j, kk) - rp_at(base, i, j, kk)) * fx;
        float b = rp_at(base, i, j + 1u, kk)
            + (rp_at(base, i + 1u, j + 1u, kk) - rp_at(base, i, j + 1u, kk)) * fx;
        p[d] = a + (b - a) * fy;
    }
    return p[0] + (p[1] - p[0]) * fz;
}

float rp_r_at(uint base, uint j, uint k) {
    return MS_AT(base + k * RP_N_ALPHA + j);
}

float rp_internal_reflectance(float alpha, float eta, bool separable) {
    uint base = MS_OFF_RP + 2u * RP_T_LEN + (separable ? RP_R_LEN : 0u);
    float fy, fz;
    uint j = coat_cell(sqrt(alpha), RP_N_ALPHA, fy);
    uint k = coat_cell(coat_eta_coord(eta), RP_N_ETA, fz);
    float a = rp_r_at(base, j, k) + (rp_r_at(base, j + 1u, k) - rp_r_at(base, j, k)) * fy;
    float b = rp_r_at(base, j, k + 1u) + (rp_r_at(base, j + 1u, k + 1u) - rp_r_at(base, j, k + 1u)) * fy;
    return a + (b - a) * fz;
}

struct RpAtWo {
    float alpha;
    bool separable;
    float to;
    float p_spec;
    float p_diff;
};

RpAtWo rp_at_wo(Material m, float mu_o) {
    RpAtWo w;
    w.alpha = max(m.alpha_u, MIN_ALPHA);
    w.separable = material_separable(m);
    w.to = rp_transmittance(mu_o, w.alpha, m.eta.x, w.separable);
    float ws = plastic_sampling_weight(m);
    float s = (1.0 - w.to) * ws;
    float d = w.to * (1.0 - ws);
    w.p_spec = s + d > 0.0 ? s / (s + d) : 0.0;
    w.p_diff = s + d > 0.0 ? d / (s + d) : 1.0;
    return w;
}

vec3 rp_diffuse_scaled(Material m, RpAtWo w) {
    float r_int = rp_internal_reflectance(w.alpha, m.eta.x, w.separable);
    vec3 rho = m.reflectance.xyz;
    return m.reflectance.w != 0.0 ? rho / (vec3(1.0) - rho * r_int) : rho / (1.0 - r_int);
}

vec3 rp_f(Material m, RpAtWo w, vec3 wo, vec3 wi, vec3 wm) {
    float a = w.alpha;
    float f = fresnel_dielectric(dot(wo, wm), m.eta.x);
    vec3 spec = m.specular.xyz
        * (f * ggx_d(wm, a, a) * ggx_g2(wo, wi, a, a, w.separable) / (4.0 * wo.z * wi.z));
    float ti = rp_transmittance(wi.z, a, m.eta.x, w.separable);
    float eta2 = m.eta.x * m.eta.x;
    return spec + rp_diffuse_scaled(m, w) * (GLINT_INV_PI * w.to * ti / eta2);
}

float rp_pdf_at(RpAtWo w, vec3 wo, vec3 wi, vec3 wm) {
    float d = dot(wo, wm);
    float spec = d > 0.0 ? ggx_pdf_visible(wo, wm, w.alpha, w.alpha) / (4.0 * d) : 0.0;
    return w.p_spec * spec + w.p_diff * wi.z * GLINT_INV_PI;
}

vec3 roughplastic_eval(Material m, vec3 wo, vec3 wi) {
    two_sided(wo, wi);
    if (wo.z <= 0.0 || wi.z <= 0.0) {
        return vec3(0.0);
    }
    RpAtWo w = rp_at_wo(m, wo.z);
    return rp_f(m, w, wo, wi, normalize(wo + wi));
}

float roughplastic_pdf(Material m, vec3 wo, vec3 wi) {
    two_sided(wo, wi);
    if (wo.z <= 0.0 || wi.z <= 0.0) {
        return 0.0;
    }
    RpAtWo w = rp_at_wo(m, wo.z);
    return rp_pdf_at(w, wo, wi, normalize(wo + wi));
}

bool roughplastic_sample(Material m, vec3 wo, float uc, vec2 u, out BsdfSample s) {
    s = BsdfSample(vec3(0.0), 0.0, vec3(0.0), 1.0, false);
    if (wo.z == 0.0) {
        return false;
    }
    bool flip = wo.z < 0.0;
    wo.z = abs(wo.z);
    RpAtWo w = rp_at_wo(m, wo.z);
    vec3 wi;
    vec3 wm;
    if (uc < w.p_spec) {
        wm = ggx_sample_visible(wo, w.alpha, w.alpha, u);
        wi = reflect_dir(wo, wm);
    } else {
        wi = square_to_cosine_hemisphere(u);
        wm = normalize(wo + wi);
    }
    if (wi.z <= 0.0) {
        return false;
    }
    float pdf = rp_pdf_at(w, wo, wi, wm);
    if (!(pdf > 0.0) || isinf(pdf)) {
        return false;
    }
    vec3 weight = rp_f(m, w, wo, wi, wm) * (wi.z / pdf);
    if (flip) {
        wi.z = -wi.z;
    }
    s = BsdfSample(wi, pdf, weight, 1.0, false);
    return true;
}

#endif
