// Energy-compensated GGX (`multiscatter`): cpu/src/bsdf/multiscatter.rs
// function by function (read its header for Kulla & Conty 2017 and Turquin
// 2019). The albedo tables live in a storage buffer, not in constant
// arrays (lavapipe's compiler stalled on 6000-element constant arrays):
// the including kernel defines MS_TABLE(i) to read element i of
// glint_cpu::bsdf::multiscatter::gpu_tables() (layout: MS_OFF_* below).
// Without MS_TABLE the tables read as "no compensation" (albedo 1).
#ifndef GLINT_BSDF_MULTISCATTER_GLSL
#define GLINT_BSDF_MULTISCATTER_GLSL

#include "glint_abi.glsl" // generated from cpu/src/abi.rs
// The tables' sizes and offsets (MS_N, MS_T_N, MS_OFF_*, COAT_*, RP_*) and
// the dielectric table's eta' range (MS_T_ETA_MIN, MS_T_ETA_MAX):
// glint_abi.glsl, from glint_cpu::abi's TABLE_CONSTANTS.

#ifdef MS_TABLE
#define MS_AT(i) MS_TABLE(i)
#else
#define MS_AT(i) 1.0
#endif

// Bilinear lookup of table[alpha][mu] (multiscatter.rs lerp2).
float ms_lerp2(uint base, float mu, float alpha) {
    uint n = MS_N;
    float x = clamp(mu, 0.0, 1.0) * float(n - 1u);
    float y = clamp(alpha, 0.0, 1.0) * float(n - 1u);
    uint x0 = min(uint(x), n - 2u);
    uint y0 = min(uint(y), n - 2u);
    float fx = x - float(x0);
    float fy = y - float(y0);
    float a00 = MS_AT(base + y0 * n + x0);
    float a10 = MS_AT(base + y0 * n + x0 + 1u);
    float a01 = MS_AT(base + (y0 + 1u) * n + x0);
    float a11 = MS_AT(base + (y0 + 1u) * n + x0 + 1u);
    float a = a00 + (a10 - a00) * fx;
    float b = a01 + (a11 - a01) * fx;
    return a + (b - a) * fy;
}

float ms_lerp1(uint base, float alpha) {
    uint n = MS_N;
    float y = clamp(alpha, 0.0, 1.0) * float(n - 1u);
    uint y0 = min(uint(y), n - 2u);
    float f = y - float(y0);
    float a = MS_AT(base + y0);
    return a + (MS_AT(base + y0 + 1u) - a) * f;
}

// Directional albedo E(mu) of the F = 1 single-scattering GGX lobe.
float ms_albedo(float mu, float alpha, bool separable) {
    return ms_lerp2(MS_OFF_E + (separable ? MS_N * MS_N : 0u), mu, alpha);
}

float ms_albedo_avg(float alpha, bool separable) {
    return ms_lerp1(MS_OFF_E_AVG + (separable ? MS_N : 0u), alpha);
}

// The multiple-scattering lobe f_ms for wo, wi both above the surface.
vec3 conductor_ms_eval(float mu_o, float mu_i, float alpha, bool separable, vec3 f_avg) {
    float e_avg = ms_albedo_avg(alpha, separable);
    if (!(e_avg < 1.0)) {
        return vec3(0.0);
    }
    float eo = ms_albedo(mu_o, alpha, separable);
    float ei = ms_albedo(mu_i, alpha, separable);
    vec3 f_ms = f_avg * f_avg * e_avg / (vec3(1.0) - f_avg * (1.0 - e_avg));
    return f_ms * (max(1.0 - eo, 0.0) * max(1.0 - ei, 0.0) / (GLINT_PI * (1.0 - e_avg)));
}

// Probability of sampling the multiple-scattering lobe (conductor.rs
// conductor_ms_prob).
float conductor_ms_prob(float mu_o, float alpha, bool separable) {
    return clamp(1.0 - ms_albedo(mu_o, alpha, separable), 0.0, 1.0);
}

// Flux albedo E(mu, alpha, eta') of the single-scattering rough
// dielectric, trilinear in mu, alpha, ln eta'.
float dielectric_ms_albedo(float mu, float alpha, float eta, bool separable) {
    uint n = MS_T_N;
    uint base = MS_OFF_T + (separable ? n * n * n : 0u);
    float x = clamp(mu, 0.0, 1.0) * float(n - 1u);
    float y = clamp(alpha, 0.0, 1.0) * float(n - 1u);
    float lo = log(MS_T_ETA_MIN);
    float hi = log(MS_T_ETA_MAX);
    float z = clamp((log(max(eta, 1e-6)) - lo) / (hi - lo), 0.0, 1.0) * float(n - 1u);
    uint x0 = min(uint(x), n - 2u);
    uint y0 = min(uint(y), n - 2u);
    uint z0 = min(uint(z), n - 2u);
    float fx = x - float(x0);
    float fy = y - float(y0);
    float fz = z - float(z0);
    float p[2];
    for (uint dz = 0u; dz < 2u; dz++) {
        uint k = z0 + dz;
        float a00 = MS_AT(base + (k * n + y0) * n + x0);
        float a10 = MS_AT(base + (k * n + y0) * n + x0 + 1u);
        float a01 = MS_AT(base + (k * n + y0 + 1u) * n + x0);
        float a11 = MS_AT(base + (k * n + y0 + 1u) * n + x0 + 1u);
        float a = a00 + (a10 - a00) * fx;
        float b = a01 + (a11 - a01) * fx;
        p[dz] = a + (b - a) * fy;
    }
    return p[0] + (p[1] - p[0]) * fz;
}

#endif
