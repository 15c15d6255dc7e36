// Anisotropic GGX: line-for-line twin of cpu/src/bsdf/microfacet.rs (same
// function names; derivations and citations on the Rust side). No term
// ever produces inf: the Smith functions are written without 1/cos.
#ifndef GLINT_BSDF_MICROFACET_GLSL
#define GLINT_BSDF_MICROFACET_GLSL

#include "glint_abi.glsl" // generated from cpu/src/abi.rs
// GLINT_PI; MIN_ALPHA: rough alphas are clamped to at least it.

float ggx_d(vec3 wm, float ax, float ay) {
    float x = wm.x / ax;
    float y = wm.y / ay;
    float t = x * x + y * y + wm.z * wm.z;
    if (t <= 0.0) {
        return 0.0;
    }
    return 1.0 / (GLINT_PI * ax * ay * t * t);
}

float ggx_root(vec3 w, float ax, float ay) {
    float a2 = ax * ax * w.x * w.x + ay * ay * w.y * w.y;
    return sqrt(w.z * w.z + a2);
}

float ggx_g1(vec3 w, float ax, float ay) {
    float cz = abs(w.z);
    float d = cz + ggx_root(w, ax, ay);
    if (d <= 0.0) {
        return 0.0;
    }
    return 2.0 * cz / d;
}

float ggx_g2(vec3 wo, vec3 wi, float ax, float ay, bool separable) {
    if (separable) {
        return ggx_g1(wo, ax, ay) * ggx_g1(wi, ax, ay);
    }
    float co = abs(wo.z);
    float ci = abs(wi.z);
    float d = ci * ggx_root(wo, ax, ay) + co * ggx_root(wi, ax, ay);
    if (d <= 0.0) {
        return 0.0;
    }
    return 2.0 * co * ci / d;
}

// V = G2 / (4 |co| |ci|), finite at grazing angles.
float ggx_visibility(vec3 wo, vec3 wi, float ax, float ay, bool separable) {
    float co = abs(wo.z);
    float ci = abs(wi.z);
    float so = ggx_root(wo, ax, ay);
    float si = ggx_root(wi, ax, ay);
    float d = separable ? (co + so) * (ci + si) : 2.0 * (ci * so + co * si);
    if (d <= 0.0) {
        return 0.0;
    }
    return 1.0 / d;
}

// Density of visible normals D_w(wm) = G1(w) / |cos w| D(wm) |w . wm|.
float ggx_pdf_visible(vec3 w, vec3 wm, float ax, float ay) {
    float d = abs(w.z) + ggx_root(w, ax, ay);
    if (d <= 0.0) {
        return 0.0;
    }
    return 2.0 * ggx_d(wm, ax, ay) * abs(dot(w, wm)) / d;
}

// Visible-normal sample (Dupuy & Benyoub 2023 spherical caps), for w's
// mirror image when w is below the surface.
vec3 ggx_sample_visible(vec3 w, float ax, float ay, vec2 u) {
    vec3 wh = vec3(ax * w.x, ay * w.y, w.z);
    if (wh.z < 0.0) {
        wh = -wh;
    }
    float len2 = dot(wh, wh);
    if (len2 <= 0.0) {
        return vec3(0.0, 0.0, 1.0);
    }
    wh /= sqrt(len2);
    float phi = 2.0 * GLINT_PI * u.x;
    float z = (1.0 - u.y) * (1.0 + wh.z) - wh.z;
    float sin_theta = sqrt(clamp(1.0 - z * z, 0.0, 1.0));
    vec3 c = vec3(sin_theta * cos(phi), sin_theta * sin(phi), z);
    vec3 h = c + wh;
    vec3 wm = vec3(ax * h.x, ay * h.y, max(h.z, 0.0));
    float l2 = dot(wm, wm);
    if (l2 <= 1e-30) {
        return vec3(0.0, 0.0, 1.0);
    }
    return wm / sqrt(l2);
}

vec3 reflect_dir(vec3 w, vec3 n) {
    return -w + 2.0 * dot(w, n) * n;
}

#endif
