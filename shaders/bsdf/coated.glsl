// The glTF non-metal: cpu/src/bsdf/coated.rs function by function (read its
// header for the model: a GGX dielectric coat over a Lambertian base, albedo
// scaled so that a white base reflects 1). Included by bsdf.glsl after the
// diffuse and conductor helpers it uses. The coat tables are read from the
// tables' storage buffer at MS_OFF_COAT (multiscatter.glsl's MS_AT).
#ifndef GLINT_BSDF_COATED_GLSL
#define GLINT_BSDF_COATED_GLSL

float coat_eta_coord(float eta) {
    return sqrt(clamp((eta - 1.0) / (eta + 1.0), 0.0, 1.0));
}

// coated.rs cell: the lower grid index of t on an n-point grid over [0, 1]
// and the fraction towards the next.
uint coat_cell(float t, uint n, out float f) {
    float y = clamp(t, 0.0, 1.0) * float(n - 1u);
    uint i = min(uint(y), n - 2u);
    f = y - float(i);
    return i;
}

float coat_at(uint i, uint j, uint k) {
    return MS_AT(MS_OFF_COAT + (k * COAT_N_ALPHA + j) * COAT_N_MU + i);
}

// E(mu, alpha, eta) of the coat with s = 1; exact Fresnel when is_smooth.
float coat_albedo(float mu, float alpha, float eta, bool is_smooth) {
    if (is_smooth) {
        return fresnel_dielectric(clamp(mu, 0.0, 1.0), eta);
    }
    float fx, fy, fz;
    uint i = coat_cell(sqrt(sqrt(clamp(mu, 0.0, 1.0))), COAT_N_MU, fx);
    uint j = coat_cell(sqrt(clamp(alpha, 0.0, 1.0)), COAT_N_ALPHA, fy);
    uint k = coat_cell(coat_eta_coord(eta), COAT_N_ETA, fz);
    float p[2];
    for (uint d = 0u; d < 2u; d++) {
        uint kk = k + d;
        float a = coat_at(i, j, kk) + (coat_at(i + 1u, j, kk) - coat_at(i, j, kk)) * fx;
        float b = coat_at(i, j + 1u, kk) + (coat_at(i + 1u, j + 1u, kk) - coat_at(i, j + 1u, kk)) * fx;
        p[d] = a + (b - a) * fy;
    }
    return p[0] + (p[1] - p[0]) * fz;
}

float coat_avg_at(uint j, uint k) {
    return MS_AT(MS_OFF_COAT + COAT_E_LEN + k * COAT_N_ALPHA + j);
}

float coat_albedo_avg(float alpha, float eta, bool is_smooth) {
    float fy, fz;
    uint j = coat_cell(sqrt(clamp(is_smooth ? 0.0 : alpha, 0.0, 1.0)), COAT_N_ALPHA, fy);
    uint k = coat_cell(coat_eta_coord(eta), COAT_N_ETA, fz);
    float a = coat_avg_at(j, k) + (coat_avg_at(j + 1u, k) - coat_avg_at(j, k)) * fy;
    float b = coat_avg_at(j, k + 1u) + (coat_avg_at(j + 1u, k + 1u) - coat_avg_at(j, k + 1u)) * fy;
    return a + (b - a) * fz;
}

// coated.rs CoatAtWo.
struct CoatAtWo {
    float alpha;
    bool is_smooth;
    vec3 eo;
    vec3 e_avg;
    float p_coat;
    float p_base;  // 1 - p_coat without the cancellation (coated.rs)
};

float coat_mean(vec3 v) {
    return (v.x + v.y + v.z) * (1.0 / 3.0);
}

CoatAtWo coat_at_wo(vec3 base, Material m, float mu_o) {
    CoatAtWo w;
    w.is_smooth = roughness_is_smooth(m.alpha_u, m.alpha_v);
    vec2 a = rough_alphas(m);
    w.alpha = sqrt(a.x * a.y);
    w.eo = m.coat.xyz * coat_albedo(mu_o, w.alpha, m.coat.w, w.is_smooth);
    w.e_avg = m.coat.xyz * coat_albedo_avg(w.alpha, m.coat.w, w.is_smooth);
    float spec = coat_mean(w.eo);
    float diff = coat_mean(base * (vec3(1.0) - w.eo));
    float total = spec + diff;
    w.p_coat = total > 0.0 ? clamp(spec / total, 0.0, 1.0) : 0.5;
    w.p_base = total > 0.0 ? clamp(diff / total, 0.0, 1.0) : 0.5;
    return w;
}

vec3 coat_base_term(vec3 base, Material m, CoatAtWo w, float mu_i) {
    vec3 ei = m.coat.xyz * coat_albedo(mu_i, w.alpha, m.coat.w, w.is_smooth);
    vec3 denom = vec3(1.0) - w.e_avg;
    if (!(min(denom.x, min(denom.y, denom.z)) > 0.0)) {
        return vec3(0.0);
    }
    return base * max(vec3(1.0) - w.eo, vec3(0.0)) * max(vec3(1.0) - ei, vec3(0.0)) * GLINT_INV_PI
        / denom;
}

vec3 coat_lobe(Material m, vec3 wo, vec3 wi, vec3 wm) {
    vec2 a = rough_alphas(m);
    float f = fresnel_dielectric(dot(wo, wm), m.coat.w);
    return m.coat.xyz * (f * ggx_d(wm, a.x, a.y) * ggx_visibility(wo, wi, a.x, a.y, false));
}

vec3 opaque_eval(vec3 base, Material m, vec3 wo, vec3 wi) {
    two_sided(wo, wi);
    if (wo.z <= 0.0 || wi.z <= 0.0) {
        return vec3(0.0);
    }
    CoatAtWo w = coat_at_wo(base, m, wo.z);
    vec3 f = coat_base_term(base, m, w, wi.z);
    if (!w.is_smooth) {
        f += coat_lobe(m, wo, wi, normalize(wo + wi));
    }
    return f;
}

float coat_pdf_rough(Material m, CoatAtWo w, vec3 wo, vec3 wi) {
    if (w.is_smooth) {
        return 0.0;
    }
    vec2 a = rough_alphas(m);
    vec3 wm = normalize(wo + wi);
    float d = dot(wo, wm);
    if (d <= 0.0) {
        return 0.0;
    }
    return ggx_pdf_visible(wo, wm, a.x, a.y) / (4.0 * d);
}

float opaque_pdf(vec3 base, Material m, vec3 wo, vec3 wi) {
    two_sided(wo, wi);
    if (wo.z <= 0.0 || wi.z <= 0.0) {
        return 0.0;
    }
    CoatAtWo w = coat_at_wo(base, m, wo.z);
    return w.p_base * wi.z * GLINT_INV_PI + w.p_coat * coat_pdf_rough(m, w, wo, wi);
}

bool opaque_sample(vec3 base, Material m, vec3 wo, float uc, vec2 u, out BsdfSample s) {
    s = BsdfSample(vec3(0.0), 0.0, vec3(0.0), 1.0, false);
    if (wo.z == 0.0) {
        return false;
    }
    bool flip = wo.z < 0.0;
    wo.z = abs(wo.z);
    CoatAtWo w = coat_at_wo(base, m, wo.z);
    vec3 wi;
    vec3 f;
    float pdf;
    if (uc < w.p_coat) {
        if (w.is_smooth) {
            vec3 fm = m.coat.xyz * fresnel_dielectric(wo.z, m.coat.w);
            s = BsdfSample(vec3(-wo.x, -wo.y, flip ? -wo.z : wo.z), w.p_coat, fm / w.p_coat, 1.0,
                           true);
            return true;
        }
        vec2 a = rough_alphas(m);
        vec3 wm = ggx_sample_visible(wo, a.x, a.y, u);
        float d = dot(wo, wm);
        wi = reflect_dir(wo, wm);
        if (wi.z <= 0.0 || d <= 0.0) {
            return false;
        }
        float pdf_c = ggx_pdf_visible(wo, wm, a.x, a.y) / (4.0 * d);
        pdf = w.p_coat * pdf_c + w.p_base * wi.z * GLINT_INV_PI;
        f = coat_lobe(m, wo, wi, wm) + coat_base_term(base, m, w, wi.z);
    } else {
        wi = square_to_cosine_hemisphere(u);
        if (wi.z <= 0.0) {
            return false;
        }
        pdf = w.p_coat * coat_pdf_rough(m, w, wo, wi) + w.p_base * wi.z * GLINT_INV_PI;
        f = coat_base_term(base, m, w, wi.z);
        if (!w.is_smooth) {
            f += coat_lobe(m, wo, wi, normalize(wo + wi));
        }
    }
    if (!(pdf > 0.0) || isinf(pdf)) {
        return false;
    }
    vec3 weight = f * (wi.z / pdf);
    if (flip) {
        wi.z = -wi.z;
    }
    s = BsdfSample(wi, pdf, weight, 1.0, false);
    return true;
}

// ---------------------------------------------------- thin-walled transmission
// thinwall.rs: KHR_materials_transmission without a volume.

vec3 slab_r(Material m, float mu) {
    float r = fresnel_dielectric(min(abs(mu), 1.0), m.coat.w);
    return min(m.coat.xyz * (2.0 * r / (1.0 + r)), vec3(1.0));
}

vec3 thinwall_eval(vec3 tint, Material m, vec3 wo, vec3 wi) {
    if (roughness_is_smooth(m.alpha_u, m.alpha_v) || wo.z == 0.0 || wi.z == 0.0) {
        return vec3(0.0);
    }
    bool transmitted = wo.z * wi.z < 0.0;
    wo.z = abs(wo.z);
    wi.z = abs(wi.z);
    vec2 a = rough_alphas(m);
    vec3 h = normalize(wo + wi);
    float d = dot(wo, h);
    if (d <= 0.0) {
        return vec3(0.0);
    }
    vec3 rr = slab_r(m, d);
    float lobe = ggx_d(h, a.x, a.y) * ggx_visibility(wo, wi, a.x, a.y, false);
    return transmitted ? tint * (vec3(1.0) - rr) * lobe : rr * lobe;
}

float thinwall_pdf(Material m, vec3 wo, vec3 wi) {
    if (roughness_is_smooth(m.alpha_u, m.alpha_v) || wo.z == 0.0 || wi.z == 0.0) {
        return 0.0;
    }
    bool transmitted = wo.z * wi.z < 0.0;
    wo.z = abs(wo.z);
    wi.z = abs(wi.z);
    vec2 a = rough_alphas(m);
    vec3 h = normalize(wo + wi);
    float d = dot(wo, h);
    if (d <= 0.0) {
        return 0.0;
    }
    float p_r = coat_mean(slab_r(m, d));
    float p = transmitted ? 1.0 - p_r : p_r;
    return p * ggx_pdf_visible(wo, h, a.x, a.y) / (4.0 * d);
}

bool thinwall_sample(vec3 tint, Material m, vec3 wo, float uc, vec2 u, out BsdfSample s) {
    s = BsdfSample(vec3(0.0), 0.0, vec3(0.0), 1.0, false);
    if (wo.z == 0.0) {
        return false;
    }
    bool flip = wo.z < 0.0;
    vec3 wo_up = vec3(wo.x, wo.y, abs(wo.z));
    if (roughness_is_smooth(m.alpha_u, m.alpha_v)) {
        vec3 rr = slab_r(m, wo_up.z);
        float p_r = coat_mean(rr);
        if (uc < p_r) {
            s = BsdfSample(vec3(-wo.x, -wo.y, wo.z), p_r, rr / p_r, 1.0, true);
        } else {
            s = BsdfSample(-wo, 1.0 - p_r, tint * (vec3(1.0) - rr) / (1.0 - p_r), 1.0, true);
        }
        return true;
    }
    vec2 a = rough_alphas(m);
    vec3 wm = ggx_sample_visible(wo_up, a.x, a.y, u);
    float d = dot(wo_up, wm);
    vec3 wi = reflect_dir(wo_up, wm);
    float g1 = ggx_g1(wo_up, a.x, a.y);
    if (wi.z <= 0.0 || d <= 0.0 || !(g1 > 0.0)) {
        return false;
    }
    vec3 rr = slab_r(m, d);
    float p_r = coat_mean(rr);
    bool transmit = uc >= p_r;
    float p = transmit ? 1.0 - p_r : p_r;
    float pdf = p * ggx_pdf_visible(wo_up, wm, a.x, a.y) / (4.0 * d);
    if (!(pdf > 0.0) || isinf(pdf)) {
        return false;
    }
    float g = ggx_g2(wo_up, wi, a.x, a.y, false) / g1;
    vec3 weight = transmit ? tint * (vec3(1.0) - rr) * (g / p) : rr * (g / p);
    if (flip != transmit) {
        wi.z = -wi.z;
    }
    s = BsdfSample(wi, pdf, weight, 1.0, false);
    return true;
}

// coated.rs: the opaque non-metal with probability 1 - t, the thin-walled
// transmission with t = m.extra.x.
vec3 coated_eval(vec3 base, Material m, vec3 wo, vec3 wi) {
    float t = m.extra.x;
    vec3 f = opaque_eval(base, m, wo, wi);
    if (t <= 0.0) {
        return f;
    }
    return (1.0 - t) * f + t * thinwall_eval(base, m, wo, wi);
}

float coated_pdf(vec3 base, Material m, vec3 wo, vec3 wi) {
    float t = m.extra.x;
    float pdf = opaque_pdf(base, m, wo, wi);
    if (t <= 0.0) {
        return pdf;
    }
    return (1.0 - t) * pdf + t * thinwall_pdf(m, wo, wi);
}

bool coated_sample(vec3 base, Material m, vec3 wo, float uc, vec2 u, out BsdfSample s) {
    float t = m.extra.x;
    bool blend = t > 0.0;
    bool thin = blend && uc < t;
    // One call of each part's sample (lavapipe's compile time grows with
    // every inlined copy): without transmission, the opaque part's sample
    // with uc as it is.
    bool ok;
    if (thin) {
        ok = thinwall_sample(base, m, wo, min(uc / t, ONE_MINUS_EPS), u, s);
    } else {
        float uco = blend ? clamp((uc - t) / (1.0 - t), 0.0, ONE_MINUS_EPS) : uc;
        ok = opaque_sample(base, m, wo, uco, u, s);
    }
    if (!ok || !blend) {
        return ok;
    }
    if (s.delta) {
        s.pdf *= thin ? t : 1.0 - t;
        return true;
    }
    // The sampled part's own pdf and f, the other part evaluated (coated.rs).
    vec3 f_s = s.weight * (s.pdf / abs(s.wi.z));
    float pdf;
    vec3 f;
    if (thin) {
        pdf = t * s.pdf + (1.0 - t) * opaque_pdf(base, m, wo, s.wi);
        f = t * f_s + (1.0 - t) * opaque_eval(base, m, wo, s.wi);
    } else {
        pdf = (1.0 - t) * s.pdf + t * thinwall_pdf(m, wo, s.wi);
        f = (1.0 - t) * f_s + t * thinwall_eval(base, m, wo, s.wi);
    }
    if (!(pdf > 0.0) || isinf(pdf)) {
        s = BsdfSample(vec3(0.0), 0.0, vec3(0.0), 1.0, false);
        return false;
    }
    s.weight = f * (abs(s.wi.z) / pdf);
    s.pdf = pdf;
    return true;
}

#endif
