// Light sampling for next-event estimation, twin of cpu/src/lights.rs
// (same names; read its header for the selection rule). Needs bindings.glsl
// and bsdf/warp.glsl (square_to_cosine_hemisphere, the map
// glint_cpu::bsdf::warp writes once for the CPU's BSDFs and lights).
#ifndef GLINT_INTEGRATOR_LIGHTS_GLSL
#define GLINT_INTEGRATOR_LIGHTS_GLSL

#include "glint_abi.glsl" // generated from cpu/src/abi.rs
#include "integrator/spherical.glsl"
// TRI_DOUBLE_SIDED, NO_LIGHT, MIS_*: glint_abi.glsl.
#define GLINT_FLT_MAX 3.402823466e+38
#define UNIFORM_SPHERE_PDF (1.0 / (4.0 * 3.14159265358979323846))

vec3 square_to_uniform_sphere(vec2 u) {
    float z = 1.0 - 2.0 * u.x;
    float r = sqrt(max(1.0 - z * z, 0.0));
    float phi = 2.0 * 3.14159265358979323846 * u.y;
    return vec3(r * cos(phi), r * sin(phi), z);
}

float cosine_hemisphere_pdf(float cos_theta) {
    return max(cos_theta, 0.0) * 0.31830988618379067154;
}

vec2 square_to_uniform_triangle(vec2 u) {
    float su0 = sqrt(u.x);
    return vec2(1.0 - su0, u.y * su0);
}

// Power heuristic, beta = 2 (Veach 1997, eq. 9.13).
float power_heuristic(float a, float b) {
    float a2 = a * a;
    float b2 = b * b;
    float s = a2 + b2;
    if (s > 0.0 && !isinf(s)) {
        return a2 / s;
    } else if (isinf(a)) {
        return 1.0;
    }
    return 0.0;
}

// Balance heuristic (Veach 1997, eq. 9.10).
float balance_heuristic(float a, float b) {
    float s = a + b;
    if (s > 0.0 && !isinf(s)) {
        return a / s;
    } else if (isinf(a)) {
        return 1.0;
    }
    return 0.0;
}

// glint_cpu::sampling::mis_light: weight of a light sample.
float mis_light(uint mode, float light_pdf, float bsdf_pdf) {
    if (mode == MIS_POWER) {
        return power_heuristic(light_pdf, bsdf_pdf);
    } else if (mode == MIS_BALANCE) {
        return balance_heuristic(light_pdf, bsdf_pdf);
    }
    return 1.0;
}

// glint_cpu::sampling::mis_bsdf: weight of a BSDF sample that found an
// emitter its vertex also sampled lights for.
float mis_bsdf(uint mode, float bsdf_pdf, float light_pdf) {
    if (mode == MIS_POWER) {
        return power_heuristic(bsdf_pdf, light_pdf);
    } else if (mode == MIS_BALANCE) {
        return balance_heuristic(bsdf_pdf, light_pdf);
    }
    return 0.0;
}

// Smallest i with u < emitters[i].cdf (glint_cpu::sampling::sample_cdf).
uint sample_emitter_cdf(uint n, float u) {
    uint lo = 0u;
    uint hi = n > 0u ? n - 1u : 0u;
    while (lo < hi) {
        uint mid = lo + (hi - lo) / 2u;
        if (u < emitters[mid].cdf) {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    return lo;
}

// KHR_lights_punctual's spot attenuation.
float spot_falloff(float cos_angle, float cos_inner, float cos_outer) {
    float scale = 1.0 / max(cos_inner - cos_outer, 0.001);
    float t = clamp((cos_angle - cos_outer) * scale, 0.0, 1.0);
    return t * t;
}

vec3 triangle_normal(Triangle t) {
    return cross(t.p1.xyz - t.p0.xyz, t.p2.xyz - t.p0.xyz);
}

// Radiance an emissive triangle sends along w (away from it); false when
// it sends nothing (not emissive, or its back face without doubleSided).
// Times the emissive texture at barycentrics (u, v) of triangle tri (= t).
bool emitted(Triangle t, uint tri, float u, float v, vec3 w, out vec3 le) {
    uint material = floatBitsToUint(t.p0.w);
    Material m = materials[material];
    le = m.emission.xyz;
    if (!(max(le.x, max(le.y, le.z)) > 0.0)) {
        return false;
    }
    bool front = dot(triangle_normal(t), w) > 0.0;
    if (!(front || (floatBitsToUint(t.p2.w) & TRI_DOUBLE_SIDED) != 0u)) {
        return false;
    }
    if (HAS(F_TEXTURES) && params.textured != 0u) {
        le *= emission_factor(material, tri, u, v);
    }
    return true;
}

struct LightSample {
    vec3 wi;
    float dist;        // meaningless when at_infinity
    vec3 weight;       // radiance (or equivalent) / pdf
    float pdf;         // solid angle, with the category choice; 0 for deltas
    bool delta;
    bool at_infinity;  // directional and background samples
};

// Lights::sampling_angle: the solid angle by which emitter e (triangle t)
// is sampled from p, 0 where by area (always under --light-sampling area).
float lights_sampling_angle(Triangle t, Emitter e, vec3 p) {
    if (params.solid_angle == 0u) {
        return 0.0;
    }
    return spherical_sampling_angle(t.p0.xyz, t.p1.xyz, t.p2.xyz, e.center, e.radius, e.area, p);
}

bool lights_sample(vec3 p, vec3 bg_normal, float u_cat, float u_idx, vec2 u,
                   out LightSample ls) {
    ls.wi = vec3(0.0);
    ls.dist = 0.0;
    ls.weight = vec3(0.0);
    ls.pdf = 0.0;
    ls.delta = false;
    ls.at_infinity = false;
    if (HAS(F_AREA_LIGHTS) && u_cat < params.p_area) {
        uint i = sample_emitter_cdf(params.emitter_count, u_idx);
        Emitter e = emitters[i];
        Triangle t = triangles[e.tri];
        float omega = lights_sampling_angle(t, e, p);
        vec2 b;
        if (omega > 0.0) {
            if (!sample_spherical_triangle(t.p0.xyz, t.p1.xyz, t.p2.xyz, p, omega, u, b)) {
                return false;
            }
        } else {
            b = square_to_uniform_triangle(u);
        }
        vec3 q = (1.0 - b.x - b.y) * t.p0.xyz + b.x * t.p1.xyz + b.y * t.p2.xyz;
        vec3 d = q - p;
        float dist2 = dot(d, d);
        float dist = sqrt(dist2);
        if (!(dist > 0.0)) {
            return false;
        }
        vec3 wi = d / dist;
        vec3 le;
        if (!emitted(t, e.tri, b.x, b.y, -wi, le)) {
            return false;
        }
        float pdf;
        if (omega > 0.0) {
            pdf = params.p_area * e.pmf / omega;
        } else {
            float cos_l = abs(dot(normalize(triangle_normal(t)), -wi));
            pdf = params.p_area * e.pmf / e.area * dist2 / cos_l;
        }
        if (!(pdf > 0.0) || isinf(pdf)) {
            return false;
        }
        ls.wi = wi;
        ls.dist = dist;
        ls.weight = le / pdf;
        ls.pdf = pdf;
        return true;
    } else if ((HAS(F_POINT_SPOT) || HAS(F_DIRECTIONAL)) && u_cat < params.p_area + params.p_punctual) {
        uint n = params.light_count;
        uint i = min(uint(u_idx * float(n)), n - 1u);
        Light l = lights[i];
        float sel = params.p_punctual / float(n);
        vec3 li;
        if (!HAS(F_POINT_SPOT) || (HAS(F_DIRECTIONAL) && l.kind == LIGHT_DIRECTIONAL)) {
            ls.wi = -l.direction;
            ls.at_infinity = true;
            li = l.intensity;
        } else {
            vec3 d = l.position - p;
            float dist2 = dot(d, d);
            float dist = sqrt(dist2);
            if (!(dist > 0.0)) {
                return false;
            }
            ls.wi = d / dist;
            ls.dist = dist;
            li = l.intensity / dist2;
            if (l.kind == LIGHT_SPOT) {
                li *= spot_falloff(dot(l.direction, -ls.wi), l.cos_inner, l.cos_outer);
            } else if (l.kind != LIGHT_POINT) {
                li = vec3(uintBitsToFloat(0x7fc00000u)); // an unknown kind: NaN, no point light
            }
        }
        if (max(li.x, max(li.y, li.z)) <= 0.0) {
            return false;
        }
        ls.weight = li / sel;
        ls.delta = true;
        return true;
    } else if (HAS(F_BACKGROUND) && params.p_background > 0.0) {
        if (params.env_width > 0u) {
            vec3 ewi;
            float epdf;
            vec3 erad;
            if (!env_sample(u, ewi, epdf, erad)) {
                return false;
            }
            float pdf = params.p_background * epdf;
            ls.wi = ewi;
            ls.at_infinity = true;
            ls.weight = erad / pdf;
            ls.pdf = pdf;
            return true;
        }
        vec3 wi;
        float dir_pdf;
        if (all(equal(bg_normal, vec3(0.0)))) {
            wi = square_to_uniform_sphere(u);
            dir_pdf = UNIFORM_SPHERE_PDF;
        } else {
            vec3 local = square_to_cosine_hemisphere(u);
            wi = frame_to_world(frame_from_normal(bg_normal), local);
            dir_pdf = cosine_hemisphere_pdf(local.z);
        }
        float pdf = params.p_background * dir_pdf;
        if (!(pdf > 0.0)) {
            return false;
        }
        ls.wi = wi;
        ls.at_infinity = true;
        ls.weight = params.background.xyz / pdf;
        ls.pdf = pdf;
        return true;
    }
    return false;
}

// Density of lights_sample, called at p, picking the point dist away
// along wi on emitter triangle tri (MIS of a BSDF sample from p that hit it).
float lights_area_pdf(uint tri, vec3 p, vec3 wi, float dist) {
    Triangle t = triangles[tri];
    Emitter e = emitters[floatBitsToUint(t.p1.w)];
    float omega = lights_sampling_angle(t, e, p);
    if (omega > 0.0) {
        return params.p_area * e.pmf / omega;
    }
    float cos_l = abs(dot(normalize(triangle_normal(t)), wi));
    if (!(cos_l > 0.0)) {
        return 0.0;
    }
    return params.p_area * e.pmf / e.area * dist * dist / cos_l;
}

float lights_background_pdf(vec3 bg_normal, vec3 wi) {
    if (params.env_width > 0u) {
        return params.p_background * env_pdf(wi);
    }
    float dir_pdf = all(equal(bg_normal, vec3(0.0))) ? UNIFORM_SPHERE_PDF
                                                       : cosine_hemisphere_pdf(dot(bg_normal, wi));
    return params.p_background * dir_pdf;
}

// Radiance from the background along d: the environment map, else the
// constant background (Lights::background_radiance).
vec3 lights_background_radiance(vec3 d) {
    if (params.env_width > 0u) {
        return env_radiance(d);
    }
    return params.background.xyz;
}

// Axis of the background's cosine lobe, or zero (uniform sphere) for
// transmissive BSDFs (glint_cpu::lights::background_direction_frame).
vec3 background_direction_frame(vec3 ns, vec3 wo, bool transmits) {
    if (transmits) {
        return vec3(0.0);
    }
    return dot(ns, wo) >= 0.0 ? ns : -ns;
}

#endif
